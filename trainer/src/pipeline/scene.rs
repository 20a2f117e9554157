//! `aprt train --scene`: plan the scene, train what it needs through
//! [`crate::pipeline::train::train`], and measure what the plan saved against the full
//! simulation (shadows, every coefficient the runtime holds, the scene's rays and bounces) on
//! a few of the same poses, in the same run.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result};
use aprt_core::{MAX_ORDER, Rgb};

use super::scene_light_map::train_scene_light_map;
use crate::bake::checkpoint::OnExisting;
use crate::bake::shard::Shard;
use crate::bake::{BakeSettings, bake_poses};
use crate::io::source::Poses;
use crate::model::fit::FitOptions;
use crate::model::precision::PrecisionChoice;
use crate::pipeline::train::{
    Outcome, RunSeconds, ShardBaked, TrainSettings, check_validation_poses, fitting_surfaces, train,
};
use crate::progress::{Reporter, Silent};
use crate::rig::mesh::Mesh;
use crate::rig::pose_sampler::DEFAULT_VALIDATION_POSES;
use crate::scene::file::Method;
use crate::scene::file::{Choice, Scene};
use crate::scene::frame_cost::{self, BudgetCheck};
use crate::scene::irradiance_rig_choice::{CANDIDATES, RigDecision, choose_rig};
use crate::scene::lighting::SceneLighting;
use crate::scene::method::MethodDecision;
use crate::scene::{BakePlan, plan_bake};

/// Poses the full simulation is timed on, at most.
pub const FULL_SIMULATION_POSES: usize = 3;

/// What `aprt train --scene` computed, skipped and spent (`--report FILE.json`).
#[derive(Clone, Debug, serde::Serialize)]
pub struct SceneTrainReport {
    /// The scene file.
    pub scene: PathBuf,
    /// The model written.
    pub model: PathBuf,
    /// Its method (per vertex or a light map) and why.
    pub method: MethodDecision,
    /// Visibility rays cast by the bake.
    pub rays_cast: u64,
    /// Inter-reflection passes after the direct pass.
    pub bounce_passes: usize,
    /// SH order of the model.
    pub sh_order: usize,
    /// Why that order.
    pub sh_order_reason: String,
    /// Worst unshadowed irradiance error of the scene's lighting at orders 1..=6, grey levels.
    pub grey_by_order: Vec<f32>,
    /// The irradiance rig stored and why.
    pub rig: RigDecision,
    /// The precision written.
    pub precision: String,
    /// Why that precision.
    pub precision_reason: String,
    /// What was computed, one sentence each.
    pub computed: Vec<String>,
    /// What was skipped, one sentence each.
    pub skipped: Vec<String>,
    /// Wall-clock seconds of the whole command, planning included.
    pub seconds: f64,
    /// Seconds by stage.
    pub stages: RunSeconds,
    /// Validation poses sampled, baked and used to choose the model (`--validation-poses`).
    pub validation_poses: usize,
    /// Seconds this run spent baking them (part of `stages.bake`); poses read back from a
    /// checkpoint cost 0 here.
    pub validation_bake_s: f64,
    /// The full simulation, timed on a few poses of the same run (not for a light map, whose
    /// bake is per texel).
    pub full_simulation: Option<FullSimulation>,
    /// Model bytes.
    pub bytes: usize,
    /// The written model's median µs a frame through aprt-core, as
    /// [`crate::scene::frame_cost::us_per_frame`] times it: the pose, the scene's lighting
    /// under its rig (or at the centre without one), every vertex shaded, and the lights the
    /// rig leaves to each vertex.
    pub us_per_frame: f64,
    /// Whether that fits the scene's `[budget] us_per_frame` (`null` without one).
    pub within_budget: Option<bool>,
    /// What to say when it does not: by how much, and what to change.
    #[serde(skip)]
    pub over_budget: Option<String>,
}

/// The full simulation's cost, measured on [`FULL_SIMULATION_POSES`] poses and scaled to all.
#[derive(Clone, Debug, serde::Serialize)]
pub struct FullSimulation {
    /// What it simulates.
    pub settings: String,
    /// Poses it was timed on.
    pub poses_timed: usize,
    /// Seconds per pose, measured.
    pub seconds_per_pose: f64,
    /// The same for the scene's bake, measured on the same poses just before.
    pub scene_seconds_per_pose: f64,
    /// Seconds the full simulation would take for every pose the scene baked.
    pub seconds: f64,
    /// Seconds the scene's bake saved over every pose: the two per-pose times' difference
    /// (0 when the scene needs the full simulation).
    pub saved_seconds: f64,
    /// Full simulation over the scene's bake, per pose.
    pub speedup: f64,
}

/// Where `aprt train --scene` writes, and how it fits.
pub struct SceneTrainOptions<'a> {
    /// The model.
    pub output: &'a Path,
    /// The checkpoint directory.
    pub checkpoint: PathBuf,
    /// What to do with an existing checkpoint.
    pub existing: OnExisting,
    /// The model's shape and regularisation.
    pub fit: FitOptions,
    /// Bake only this shard of the poses into the checkpoint and stop (a bake farm).
    pub shard: Option<Shard>,
    /// Validation poses to sample and bake (`--validation-poses`; None: the default, see
    /// [`TrainSettings::validation_poses`]).
    pub validation_poses: Option<usize>,
    /// The method to write, and why: the scene's ([`crate::scene::method::fixed_method`]), or
    /// the kind `aprt report` recommends (the report's `sweep::choice`).
    pub method: MethodDecision,
}

/// What `aprt train --scene` did: trained the model, or baked one shard of it.
pub enum SceneOutcome {
    /// The model was written.
    Trained(Box<SceneTrainReport>),
    /// One shard was baked.
    Shard(ShardBaked),
}

/// Plans `scene` under `lighting` (its lighting, read by the caller so that its errors name
/// the scene file), trains its model from `poses` into `options.output`, and reports what was
/// computed and skipped. A shard bakes its share with the same plan (every decision is
/// deterministic, so every shard and the final run agree) and stops. Notes and progress go to
/// `reporter`.
pub fn train_scene(
    scene: &Scene,
    lighting: &SceneLighting,
    poses: Poses,
    options: SceneTrainOptions<'_>,
    reporter: &dyn Reporter,
) -> Result<SceneOutcome> {
    if options.method.method == Method::LightMap {
        let method = options.method.clone();
        return train_scene_light_map(scene, lighting, poses, (options, method), reporter);
    }
    let started = Instant::now();
    // The method's choice ran before this call; the command's seconds include it.
    let choice_s = options.method.seconds;
    check_validation_poses(&poses, options.validation_poses)?;
    let fitting = fitting_surfaces(&poses)?;
    let bind = &fitting[0];
    let validation_poses = options.validation_poses;
    let baked = baked_pose_count(&poses, scene, validation_poses);
    // The order and the rig are judged light by light at every vertex: many near lights
    // take long enough to deserve a progress display.
    let progress = reporter.step_progress(1 + CANDIDATES.len());
    progress.step(&format!(
        "choosing the SH order: {} lights at {} vertices",
        lighting.lights.len(),
        bind.vertex_count()
    ));
    let plan = plan_bake(scene, lighting, bind, baked)?;
    let order = plan.bake.order;
    let (rig_kind, rig) = choose_rig(
        scene.effects.rig,
        &lighting.lights,
        &fitting,
        order,
        scene.effects.error_target,
        progress.as_ref(),
    )?;
    progress.finish();
    let precision = match scene.effects.precision {
        Choice::Fixed(p) => PrecisionChoice::Fixed(p),
        Choice::Auto => PrecisionChoice::Auto {
            target: scene.effects.error_target,
            lighting: channels(&lighting.sh_at_centre(order, bind)?),
        },
    };
    for line in plan.computed.iter().chain(&plan.skipped) {
        reporter.note(line);
    }
    reporter.note(&format!("rig: {}", rig.reason));
    let full = match options.shard {
        Some(_) => None,
        None => Some(time_full_simulation(&plan, &fitting, baked, reporter)?),
    };
    let settings = TrainSettings {
        bake: plan.bake,
        fit: options.fit,
        precision,
        frame: scene.effects.frame,
        checkpoint: options.checkpoint,
        existing: options.existing,
        irradiance_rig: rig_kind,
        shard: options.shard,

        // CLI-only (`aprt train --sample-poses`); a scene samples none.
        sample_poses: 0,
        validation_poses,
    };
    let (trained, full) = match (train(poses, options.output, &settings, reporter)?, full) {
        (Outcome::Trained(trained), Some(full)) => (trained, full),
        (Outcome::Shard(baked), _) => return Ok(SceneOutcome::Shard(baked)),
        (Outcome::Trained(_), None) => unreachable!("only shards skip the timing"),
    };
    let mut computed = plan.computed.clone();
    let mut skipped = plan.skipped.clone();
    match rig_kind {
        Some(_) => computed.push(format!("irradiance rig: {}", rig.reason)),
        None => skipped.push(format!("irradiance rig: {}", rig.reason)),
    }
    computed.push(format!("precision {}", trained.precision.1));
    let blob = std::fs::read(options.output)
        .with_context(|| format!("cannot read back {}", options.output.display()))?;
    let cost = frame_cost::us_per_frame(&blob, bind, lighting, scene.effects.error_target)
        .with_context(|| format!("timing {}", options.output.display()))?;
    let budget = (scene.budget.us_per_frame).map(|budget| BudgetCheck {
        cost,
        budget,
        precision: trained.precision.0,
    });
    Ok(SceneOutcome::Trained(Box::new(SceneTrainReport {
        scene: scene.path.clone(),
        model: options.output.to_owned(),
        method: options.method,
        rays_cast: plan.bake.rays_cast(bind.vertex_count()) * trained.baked_poses as u64,
        bounce_passes: plan.bake.bounces,
        sh_order: order,
        sh_order_reason: plan.order.reason.clone(),
        grey_by_order: plan.order.grey_by_order.clone(),
        rig,
        precision: trained.precision.0.name().to_owned(),
        precision_reason: trained.precision.1.clone(),
        computed,
        skipped,
        seconds: choice_s + started.elapsed().as_secs_f64(),
        stages: trained.seconds,
        validation_poses: trained.validation_poses,
        validation_bake_s: trained.validation_bake_s,
        full_simulation: Some(full),
        bytes: trained.info.bytes,
        us_per_frame: cost.us,
        within_budget: budget.map(|b| b.within()),
        over_budget: budget.and_then(|b| b.miss_message()),
    })))
}

/// Poses the bake covers: training and validation frames, the validation poses
/// (`validation_poses`, as [`TrainSettings::validation_poses`] resolves it) and the rest pose
/// of bone-frame character models.
fn baked_pose_count(poses: &Poses, scene: &Scene, validation_poses: Option<usize>) -> usize {
    match poses {
        Poses::Meshes { meshes, .. } => meshes.len(),
        Poses::Rig {
            clips, validation, ..
        } => {
            let frames: usize = clips.iter().chain(validation).map(|c| c.frames.len()).sum();
            let sampled = validation_poses.unwrap_or(DEFAULT_VALIDATION_POSES);
            frames + sampled + usize::from(scene.effects.frame == crate::model::ModelFrame::Bone)
        }
    }
}

/// Times the scene's bake and the full simulation on the same few of `poses`, and scales
/// both to the `baked` poses of the scene.
fn time_full_simulation(
    plan: &BakePlan,
    poses: &[Mesh],
    baked: usize,
    reporter: &dyn Reporter,
) -> Result<FullSimulation> {
    let full = BakeSettings {
        order: MAX_ORDER,
        shadows: true,
        ..plan.bake
    };
    let sample = &poses[..poses.len().min(FULL_SIMULATION_POSES)];
    let k = sample.len().max(1) as f64;
    let described = format!(
        "shadows, SH order {MAX_ORDER}, {} rays, {} bounces",
        full.rays, full.bounces
    );
    if full == plan.bake {
        reporter.note("the scene needs the full simulation: nothing to save");
        return Ok(FullSimulation {
            settings: described,
            poses_timed: 0,
            seconds_per_pose: 0.0,
            scene_seconds_per_pose: 0.0,
            seconds: 0.0,
            saved_seconds: 0.0,
            speedup: 1.0,
        });
    }
    reporter.note(&format!(
        "timing the full simulation (shadows, order {MAX_ORDER}, {} rays, {} bounces) on {} poses",
        full.rays,
        full.bounces,
        sample.len()
    ));
    // Interleaved pose by pose, so the machine's drift falls on both sides alike.
    let (mut scene_s, mut full_s) = (0.0, 0.0);
    for mesh in sample {
        for (settings, total) in [(&plan.bake, &mut scene_s), (&full, &mut full_s)] {
            let t = Instant::now();
            bake_poses(std::slice::from_ref(mesh), settings, &Silent)?;
            *total += t.elapsed().as_secs_f64() / k;
        }
    }
    Ok(FullSimulation {
        settings: described,
        poses_timed: sample.len(),
        seconds_per_pose: full_s,
        scene_seconds_per_pose: scene_s,
        seconds: full_s * baked as f64,
        saved_seconds: (full_s - scene_s) * baked as f64,
        speedup: full_s / scene_s.max(1e-9),
    })
}

/// Each RGB channel of SH lighting as its own vector.
fn channels(rgb: &[Rgb]) -> [Vec<f32>; 3] {
    std::array::from_fn(|k| rgb.iter().map(|c| c[k]).collect())
}
