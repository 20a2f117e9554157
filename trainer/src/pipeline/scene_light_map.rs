//! `aprt train --scene` when the scene's method is a light map: the pose-driven light map
//! (`crate::lightmap::model`) baked and fitted at the scene's SH order, rays and bounces on
//! generated light-map UVs, written atomically, and timed as `aprt report` times it
//! ([`frame_cost::light_map_us_per_frame`]).

use std::time::Instant;

use anyhow::{Context, Result, bail};

use super::scene::{SceneOutcome, SceneTrainOptions, SceneTrainReport};
use crate::io::atomic::write_atomic;
use crate::io::source::{Poses, joined};
use crate::lightmap::bake::{CheckpointSettings, bake_light_map_shard};
use crate::lightmap::layout::{AtlasSpec, LightMapUvs};
use crate::lightmap::model::{LightMapFit, LightMapTraining, train_light_maps};
use crate::model::export::Precision;
use crate::pipeline::train::RunSeconds;
use crate::progress::Reporter;
use crate::scene::file::{Choice, LIGHTMAP_RESOLUTIONS, Scene};
use crate::scene::frame_cost::{self, BudgetCheck, FrameCost};
use crate::scene::irradiance_rig_choice::RigDecision;
use crate::scene::lighting::SceneLighting;
use crate::scene::method::MethodDecision;
use crate::scene::{BakePlan, SHADOWS, plan_bake, shadows_sentence};

/// Precision of a light map whose scene leaves it to `auto` and whose choice did not measure
/// one: f16, which the sweeps find within a hundredth of a grey level of f32 at half the bytes.
const DEFAULT_PRECISION: Precision = Precision::F16;

/// Why a light map stores no irradiance rig.
const NO_RIG: &str = "a light map is composed under the scene's lighting at the character's centre";

/// Trains `scene`'s pose-driven light map from `poses` into `options.output` as `decision`
/// chose it (or bakes one shard of it), and reports what was computed and skipped.
pub fn train_scene_light_map(
    scene: &Scene,
    lighting: &SceneLighting,
    poses: Poses,
    (options, decision): (SceneTrainOptions<'_>, MethodDecision),
    reporter: &dyn Reporter,
) -> Result<SceneOutcome> {
    let started = Instant::now();
    let choice_s = decision.seconds;
    let Poses::Rig { rig, clips, .. } = poses else {
        bail!(
            "{}: method = \"lightmap\" needs a character: an OBJ sequence has no bind mesh the light map's texels could ride",
            scene.path.display()
        );
    };
    let rig = rig.as_ref();
    let bind = rig.bind_mesh();
    let clip = joined(clips);
    let plan = plan_bake(scene, lighting, bind, clip.frames.len())?;
    let resolution = decision
        .resolution
        .unwrap_or(match scene.effects.lightmap_resolution {
            Choice::Fixed(r) => r,
            Choice::Auto => LIGHTMAP_RESOLUTIONS[LIGHTMAP_RESOLUTIONS.len() / 2],
        });
    let precision = decision.precision.unwrap_or(match scene.effects.precision {
        Choice::Fixed(p) => p,
        Choice::Auto => DEFAULT_PRECISION,
    });
    let atlas = AtlasSpec {
        resolution,
        uvs: LightMapUvs::DEFAULT_GENERATE,
    };
    let what = format!("{}: the light map", scene.path.display());
    if let Some(shard) = options.shard {
        let place = (options.checkpoint.as_path(), shard);
        let baked = bake_light_map_shard(rig, &what, &clip, atlas, &plan.bake, place, reporter)?;
        return Ok(SceneOutcome::Shard(baked));
    }
    let training = LightMapTraining {
        atlas,
        bake: plan.bake,
        model: LightMapFit {
            options: &options.fit,
            precision,
            frame: scene.effects.frame,
        },
        checkpoint: CheckpointSettings {
            dir: &options.checkpoint,
            existing: options.existing,
        },
        irradiance_rig: None,
    };
    let trained = train_light_maps(rig, &what, vec![clip], &training, reporter)?;
    write_atomic(options.output, &trained.blob)
        .with_context(|| format!("cannot write {}", options.output.display()))?;
    let us = frame_cost::light_map_us_per_frame(&trained.blob, bind, lighting)
        .with_context(|| format!("timing {}", options.output.display()))?;
    let texels = trained.info.vertices;
    let cost = FrameCost {
        us,
        rig: false,
        proxies: false,
        per_vertex_lights: 0,
    };
    let budget = scene.budget.us_per_frame.map(|budget| BudgetCheck {
        cost,
        budget,
        precision,
    });
    let (computed, skipped) = sentences(
        scene,
        &plan,
        (texels, trained.frames),
        (resolution, precision),
        &decision.reason,
    );
    Ok(SceneOutcome::Trained(Box::new(SceneTrainReport {
        scene: scene.path.clone(),
        model: options.output.to_owned(),
        method: decision,
        rays_cast: plan.bake.rays_cast(texels) * trained.frames as u64,
        bounce_passes: plan.bake.bounces,
        sh_order: plan.bake.order,
        sh_order_reason: plan.order.reason.clone(),
        grey_by_order: plan.order.grey_by_order.clone(),
        rig: RigDecision {
            kind: None,
            reason: NO_RIG.into(),
        },
        precision: precision.name().to_owned(),
        precision_reason: match scene.effects.precision {
            Choice::Fixed(_) => "as the scene asks".to_owned(),
            Choice::Auto => {
                "the light map's precision the method's choice measured (f16 when it measured none)"
                    .to_owned()
            }
        },
        computed,
        skipped,
        // The method's choice ran before this call: the command's seconds include it.
        seconds: choice_s + started.elapsed().as_secs_f64(),
        stages: RunSeconds {
            bake: trained.seconds.0,
            fit: trained.seconds.1,
        },
        validation_poses: 0,
        validation_bake_s: 0.0,
        full_simulation: None,
        bytes: trained.blob.len(),
        us_per_frame: us,
        within_budget: budget.map(|b| b.within()),
        over_budget: budget.and_then(|b| b.miss_message()),
    })))
}

/// What the light map's training computed and skipped, one sentence each: the plan's, its
/// shadows counted at the `texels` of each of `frames` poses (the plan counts vertices), the
/// map at `resolution`² and why, and its `precision`.
fn sentences(
    scene: &Scene,
    plan: &BakePlan,
    (texels, frames): (usize, usize),
    (resolution, precision): (usize, Precision),
    reason: &str,
) -> (Vec<String>, Vec<String>) {
    let mut computed: Vec<String> = plan
        .computed
        .iter()
        .filter(|l| !l.starts_with(SHADOWS))
        .cloned()
        .collect();
    if scene.effects.shadows {
        computed.push(shadows_sentence(&plan.bake, (texels, "texel"), frames));
    }
    computed.push(format!(
        "light map {resolution}x{resolution} on generated UVs ({texels} texels as the model's rows): {reason}"
    ));
    computed.push(format!("precision {}", precision.name()));
    let mut skipped = plan.skipped.clone();
    skipped.push(format!("irradiance rig: {NO_RIG}"));
    (computed, skipped)
}
