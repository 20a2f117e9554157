//! The irradiance rig a scene needs: none when one SH vector at the character's centre meets
//! the error target for every light, else the rig kind that leaves the fewest lights to be
//! evaluated per vertex, the one with fewer SH vectors on a tie (each rig carries the lights
//! it can and leaves the rest per vertex, so every candidate meets the target; they differ in
//! cost, and the per-vertex lights are what costs). The choice is made on counts, not timings,
//! so every run of a scene (and every shard of a bake farm) makes the same one.

use anyhow::{Context, Result};
use aprt_core::Light;

use crate::irradiance_rig::{RigKind, RigSettings, evaluate_rig, fit_rig};
use crate::model::runtime::rig_frame_cost;
use crate::progress::StepProgress;
use crate::rig::mesh::Mesh;
use crate::scene::file::RigChoice;

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
/// rig's root frame) at `order` and `target` grey levels. Each candidate tried is a step of
/// `progress`: with a thousand near lights, one takes seconds on a small character.
pub fn choose_rig(
    choice: RigChoice,
    lights: &[Light],
    meshes: &[Mesh],
    order: usize,
    target: f32,
    progress: &dyn StepProgress,
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
        progress.step(&format!(
            "trying a {name} rig: {} lights at {} vertices",
            lights.len(),
            meshes[0].vertex_count()
        ));
        let kind: RigKind = name.parse()?;
        let mut fitted = fit_rig(kind, &refs, None);
        fitted
            .tabulate(&meshes[0], order)
            .with_context(|| format!("tabulating a {name} rig"))?;
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
        let cost = rig_frame_cost(&fitted, &meshes[0], lights, &eval.shares(), order)
            .with_context(|| format!("timing a {name} rig"))?;
        tried.push((kind, cost.total, analytic, eval.error_grey.max));
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
            "a {kind} rig: the fewest lights left per vertex ({analytic}) of the rigs tried, with the fewest SH vectors among those ({}; µs a frame through aprt-core on the bind pose's unreduced transfer, not the model's, which is timed once written), worst error {max:.2} grey levels, {us:.0} µs a frame on that transfer",
            others.join(", ")
        ),
    ))
}

#[cfg(test)]
mod tests {
    use std::cell::RefCell;

    use aprt_core::PointLight;

    use super::*;

    /// Records the steps it is told of.
    #[derive(Default)]
    struct Steps(RefCell<Vec<String>>);

    impl StepProgress for Steps {
        fn step(&self, what: &str) {
            self.0.borrow_mut().push(what.to_owned());
        }
        fn finish(&self) {}
    }

    /// A double cone (a ring of vertices facing out and two apexes), and point lights just off
    /// it: no rig carries them all, so every candidate is tried, each one a step of the
    /// progress display.
    #[test]
    fn every_rig_tried_is_a_step_of_the_progress() {
        let mut positions: Vec<[f32; 3]> = (0..24)
            .map(|i| {
                let a = i as f32 * core::f32::consts::TAU / 24.0;
                [a.cos(), a.sin(), 0.0]
            })
            .collect();
        let lights: Vec<Light> = positions
            .iter()
            .step_by(6)
            .map(|p| {
                Light::Point(PointLight {
                    position: p.map(|c| 1.2 * c),
                    intensity: [1.0; 3],
                })
            })
            .collect();
        positions.extend([[0.0, 0.0, 0.5], [0.0, 0.0, -0.5]]);
        let triangles = (0..24u32)
            .flat_map(|i| [[24, i, (i + 1) % 24], [25, (i + 1) % 24, i]])
            .collect();
        let mesh = Mesh {
            normals: positions.clone(),
            positions,
            triangles,
        };
        let steps = Steps::default();
        let (kind, decision) =
            choose_rig(RigChoice::Auto, &lights, &[mesh], 3, 1.0, &steps).unwrap();
        assert!(kind.is_some(), "{}", decision.reason);
        let steps = steps.0.into_inner();
        assert_eq!(steps.len(), CANDIDATES.len(), "{steps:?}");
        for (step, name) in steps.iter().zip(CANDIDATES) {
            assert_eq!(
                step,
                &format!("trying a {name} rig: 4 lights at 26 vertices")
            );
        }
    }
}
