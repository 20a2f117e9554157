//! Which method a scene's model is written with: the scene's `[effects] method` when it fixes
//! one (and, for a light map, its resolution and precision), or the kind `aprt report`
//! recommends for the scene, which `crate::report::sweep::choice` measures. The decision is
//! here, below the pipeline that acts on it; the sweep that makes it is the report's.

use serde::Serialize;

use crate::model::export::Precision;
use crate::scene::file::{Choice, Method, Scene};

/// The method a scene's model is written with, and why.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MethodDecision {
    /// `vertex` or `lightmap`.
    pub method: Method,
    /// Texels a side of a light map.
    pub resolution: Option<usize>,
    /// The light map's precision, when the choice measured it.
    #[serde(skip)]
    pub precision: Option<Precision>,
    /// One sentence: why.
    pub reason: String,
    /// Wall-clock seconds the choice took (0 when the scene fixes the method).
    pub seconds: f64,
}

/// Whether choosing `scene`'s method needs the sweep: its method is `auto`, or a light map
/// whose resolution or precision is `auto`.
pub fn needs_sweep(scene: &Scene) -> bool {
    let e = &scene.effects;
    match e.method {
        Choice::Auto => true,
        Choice::Fixed(Method::Vertex) => false,
        Choice::Fixed(Method::LightMap) => {
            e.lightmap_resolution == Choice::Auto || e.precision == Choice::Auto
        }
    }
}

/// The method `scene` fixes, with its light map's resolution and precision; `None` when any
/// of them is left to `auto` and the sweep must choose (`crate::report::sweep::choice::swept_method`).
pub fn fixed_method(scene: &Scene) -> Option<MethodDecision> {
    let e = &scene.effects;
    if needs_sweep(scene) {
        return None;
    }
    let Choice::Fixed(method) = e.method else {
        return None;
    };
    let (resolution, precision) = match (method, e.lightmap_resolution, e.precision) {
        (Method::LightMap, Choice::Fixed(r), Choice::Fixed(p)) => (Some(r), Some(p)),
        _ => (None, None),
    };
    Some(MethodDecision {
        method,
        resolution,
        precision,
        reason: format!("method {}, as the scene asks", method.name()),
        seconds: 0.0,
    })
}
