//! The irradiance rig a scene needs: none when one SH vector at the character's centre meets
//! the error target for every light, else the rig kind that leaves the fewest lights to be
//! evaluated per vertex, the one with fewer SH vectors on a tie (each rig carries the lights
//! it can and leaves the rest per vertex, so every candidate meets the target; they differ in
//! cost, and the per-vertex lights are what costs). The choice is made on counts, not timings,
//! so every run of a scene (and every shard of a bake farm) makes the same one.

use anyhow::{Context, Result};
use aprt_core::Light;

use crate::io::scene::RigChoice;
use crate::lighting::{RigKind, RigSettings, evaluate_rig, fit_rig};
use crate::rig::mesh::Mesh;

/// The kinds tried, cheapest first.
pub const CANDIDATES: [&str; 4] = ["constant", "gradient", "lattice:2x2x2", "lattice:3x3x3"];

/// The rig chosen and why.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct RigDecision {
    /// The kind stored in the model, if any.
    pub kind: Option<String>,
    /// Why, in one sentence.
    pub reason: String,
}

/// Chooses the rig for `lights` on `meshes` (the bind pose first, then training poses, in the
/// rig's root frame) at `order` and `target` grey levels.
pub fn choose_rig(
    choice: RigChoice,
    lights: &[Light],
    meshes: &[Mesh],
    order: usize,
    target: f32,
) -> Result<(Option<RigKind>, RigDecision)> {
    let decision = |kind: Option<RigKind>, reason: String| {
        (
            kind,
            RigDecision {
                kind: kind.map(|k| k.to_string()),
                reason,
            },
        )
    };
    match choice {
        RigChoice::None => return Ok(decision(None, "the scene asks for no rig".into())),
        RigChoice::Kind(kind) => {
            return Ok(decision(
                Some(kind),
                format!("the scene asks for a {kind} rig"),
            ));
        }
        RigChoice::Auto => {}
    }
    if lights.iter().all(|l| matches!(l, Light::Directional(_))) {
        return Ok(decision(
            None,
            "no rig: every light is distant (directional, or the environment), so one SH vector lights the whole character exactly as far as SH can".into(),
        ));
    }
    let refs: Vec<&Mesh> = meshes.iter().collect();
    let settings = RigSettings {
        order,
        target_error: target,
        ..RigSettings::default()
    };
    let mut tried = Vec::new();
    for name in CANDIDATES {
        let kind: RigKind = name.parse()?;
        let mut fitted = fit_rig(kind, &refs, None);
        fitted.tabulate(&meshes[0], order);
        let eval = evaluate_rig(&fitted, &meshes[0], lights, &settings)
            .with_context(|| format!("evaluating a {name} rig"))?;
        let analytic = eval.lights.iter().filter(|l| l.rig_share < 1.0).count();
        if name == "constant" && analytic == 0 {
            return Ok(decision(
                None,
                format!(
                    "no rig: every light is far enough for the constant rig at {target} grey level(s) (worst {:.2} over {} vertices), so the lights projected at the character's centre light it",
                    eval.error_grey.max, eval.vertices
                ),
            ));
        }
        tried.push((kind, eval.us_per_frame.total, analytic, eval.error_grey.max));
    }
    // Candidates are in order of SH vectors, and min_by_key keeps the first of equals.
    let (kind, us, analytic, max) = tried
        .iter()
        .copied()
        .min_by_key(|t| t.2)
        .expect("at least one candidate");
    let others: Vec<String> = tried
        .iter()
        .map(|(k, us, a, _)| format!("{k} {us:.0} µs ({a} per vertex)"))
        .collect();
    Ok(decision(
        Some(kind),
        format!(
            "a {kind} rig: the fewest lights left per vertex ({analytic}) of the rigs tried, with the fewest SH vectors among those ({}; measured µs per frame through aprt-core), worst error {max:.2} grey levels, {us:.0} µs a frame",
            others.join(", ")
        ),
    ))
}
