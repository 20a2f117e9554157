//! Which method `aprt train --scene` writes: the scene's `[effects] method` when it fixes one
//! (and, for a light map, its resolution and precision), otherwise the kind `aprt report`
//! recommends for the scene. The choice runs the report's own sweep ([`crate::report::sweep`],
//! every setting of both methods on the scene's test clips, at the report's default stride and
//! surface points), so the two commands agree on the kind by construction: there is one
//! measure of what a method costs and what it shows over the surface, not two.

use anyhow::{Context, Result, bail};

use crate::model::export::Precision;
use crate::progress::Reporter;
use crate::report::sweep::{self, Point, ReportSettings, SceneClips};
use crate::rig::pose_sampler::DEFAULT_VALIDATION_POSES;
use crate::scene::file::{Choice, Method, Scene};
use crate::scene::lighting::SceneLighting;
use crate::surface::DEFAULT_SURFACE_POINTS;

/// Frames of each clip the choice's sweep uses: one in three, `aprt report`'s default.
pub const CHOICE_STRIDE: usize = 3;

/// The method a scene's model is written with, and why.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
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
/// of them is left to `auto` and the sweep must choose ([`swept_method`]).
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

/// The method the report's sweep of `scene` on `clips` under `lighting` recommends
/// ([`decision_from`]). Progress and notes go to `reporter`.
pub fn swept_method(
    scene: &Scene,
    lighting: &SceneLighting,
    clips: &SceneClips<'_>,
    reporter: &dyn Reporter,
) -> Result<MethodDecision> {
    let started = std::time::Instant::now();
    reporter.note("choosing the method by `aprt report`'s sweep of both (1 frame in 3)");
    let settings = ReportSettings {
        budget_us: None,
        budget_bytes: None,
        stride: CHOICE_STRIDE,
        validation_poses: DEFAULT_VALIDATION_POSES,
        surface_points: DEFAULT_SURFACE_POINTS as usize,
    };
    sweep::check_stride(clips.train, CHOICE_STRIDE)?;
    let report = sweep::run(scene, lighting.clone(), clips, &settings, reporter)
        .context("choosing the method by the report's sweep")?;
    let mut decision = decision_from(&report.points, report.recommended)?;
    decision.seconds = started.elapsed().as_secs_f64();
    Ok(decision)
}

/// The method of a sweep's recommended point (`recommended`, an index into `points`), or of
/// its most accurate setting when none fits the budget, with the sentence that says why.
pub fn decision_from(points: &[Point], recommended: Option<usize>) -> Result<MethodDecision> {
    let most_accurate = points.iter().min_by(|a, b| a.error.total_cmp(&b.error));
    let (chosen, why) = match (recommended, most_accurate) {
        (Some(i), _) => (&points[i], "recommended within the scene's budget"),
        (None, Some(p)) => (p, "the most accurate: no setting fits the scene's budget"),
        (None, None) => bail!("the report's sweep measured no setting to choose the method by"),
    };
    let method = match chosen.setting.method {
        "lightmap" => Method::LightMap,
        _ => Method::Vertex,
    };
    let precision = [Precision::F32, Precision::F16, Precision::I8]
        .into_iter()
        .find(|p| p.name() == chosen.setting.precision);
    Ok(MethodDecision {
        method,
        resolution: chosen.setting.resolution,
        precision: (method == Method::LightMap).then_some(precision).flatten(),
        reason: format!(
            "method {}: `aprt report`'s sweep ({} settings, error over the surface on the test clips) has {} {why}, {:.2} grey levels at {:.1} µs a frame and {} bytes",
            method.name(),
            points.len(),
            chosen.setting.label,
            chosen.error,
            chosen.us_per_frame,
            chosen.bytes
        ),
        seconds: 0.0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::sweep::Setting;
    use crate::report::sweep::measure::Measured;

    fn point(method: &'static str, precision: &'static str, error: f64) -> Point {
        Point {
            setting: Setting {
                label: format!("{method} {precision}"),
                method,
                resolution: (method == "lightmap").then_some(128),
                order: 3,
                pose_dims: "auto".into(),
                coef_dims: "auto".into(),
                fitted: (4, 15),
                precision,
                rays: 128,
                bounces: 0,
                proxies: ("none", false),
            },
            error,
            us_per_frame: 100.0,
            bytes: 1000,
            pareto: false,
            pareto_bytes: false,
            measured: Measured::default(),
            bake_s_per_frame: 0.0,
            fit_s: 0.0,
            blob: Vec::new(),
        }
    }

    /// The recommendation's kind is written, a light map with its resolution and precision;
    /// with no recommendation (nothing fits the budget) the most accurate setting's kind, and
    /// the reason says which.
    #[test]
    fn the_kind_is_the_recommendations_or_the_most_accurate() {
        let points = vec![point("vertex", "f32", 5.0), point("lightmap", "i8", 4.0)];
        let chosen = decision_from(&points, Some(0)).unwrap();
        assert_eq!(
            (chosen.method, chosen.resolution, chosen.precision),
            (Method::Vertex, None, None)
        );
        assert!(
            chosen.reason.contains("recommended within"),
            "{}",
            chosen.reason
        );
        let fallback = decision_from(&points, None).unwrap();
        assert_eq!(fallback.method, Method::LightMap);
        assert_eq!(
            (fallback.resolution, fallback.precision),
            (Some(128), Some(Precision::I8))
        );
        assert!(
            fallback.reason.contains("no setting fits"),
            "{}",
            fallback.reason
        );
        assert!(decision_from(&[], None).is_err());
    }
}
