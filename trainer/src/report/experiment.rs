//! One experiment of the paper (its Tables 1 and 2) on any rig: bake a training clip and novel
//! clips, fit several model shapes, and measure each through aprt-core against three
//! baselines. `aprt demo` runs it on the built-in character, `aprt results` on real assets.

use std::fmt::Write as _;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use aprt_core::{LitWeights, Model, ModelInfo, PoseWeights, ProxyFrame, Rotation, ShRotation};
use glam::Mat4;

use crate::bake::clip::{BakedClip, bake_clip, bake_rest};
use crate::bake::{BakeSettings, bake_poses};
use crate::model::ModelFrame;
use crate::model::export::{ExportError, Precision, encode_model};
use crate::model::fit::{Alpha, CoefDims, Dims, Features, Fit, FitError, FitOptions, Local, Prior};
use crate::model::occluders::{DEFAULT_CULL, Occluders, bone_skinning, occlusion, rig_section};
use crate::model::predict::predict_world;
use crate::pipeline::train::{ClipSet, Selection, fit_clip};
use crate::progress::{Reporter, Silent};
use crate::report::evaluate::{mean_transfer, nearest_pose, relative_error, skinned_transfer};
use crate::rig::Rig;
use crate::rig::bone_frames::dominant_bones;
use crate::rig::mesh::Mesh;
use crate::rig::pose_layout::PoseLayout;
use crate::rig::pose_sampler::{
    SAMPLED_CLIP, SEED, VALIDATION_CLIP, sample_poses, validation_poses,
};

/// One model shape the experiment fits.
#[derive(Clone, Debug)]
pub struct ModelConfig {
    /// Row name in the table.
    pub name: String,
    /// Fit options.
    pub options: FitOptions,
    /// The frame the model learns transfer in.
    pub frame: ModelFrame,
    /// Training poses sampled within the training clip's ranges and added to it, as
    /// `aprt train --sample-poses` does (0: none).
    pub sample_poses: usize,
}

/// The name of the default model's configuration, the first of [`standard_configs`].
pub const DEFAULT_CONFIG: &str = "default: bone frame, bounded, LOSO α, k_a and prior";
/// The default with the rest prior forced.
pub const REST_CONFIG: &str = "default, rest prior";
/// The default without occluder proxies: what the model learns alone.
pub const NO_PROXIES_CONFIG: &str = "default, no occluder proxies";
/// The default with the local model forced (`--local only`).
pub const LOCAL_CONFIG: &str = "default, local model (every entry near each vertex)";
/// The default with the cosine features forced (`--features cosines`).
pub const COSINES_CONFIG: &str = "default, cosine features";
/// The default with the features chosen by held-out error (`--features auto`).
pub const AUTO_FEATURES_CONFIG: &str = "default, angles or cosine features by held-out error";
/// The paper's model in bone frames: every pose dimension, the mean as prior, unbounded.
pub const PAPER_CONFIG: &str = "paper: bone frame, mean prior, unbounded, LOSO α";

/// The model shapes of the paper's tables and the choices behind the default: the default
/// itself first, the same shape with LOO α and in the world frame, the full linear model with
/// and without regularisation, and two PCA settings.
pub fn standard_configs() -> Vec<ModelConfig> {
    let default = FitOptions::default();
    let config = |name: &str, options: FitOptions, frame: ModelFrame| ModelConfig {
        name: name.into(),
        options,
        frame,
        sample_poses: 0,
    };
    let full = FitOptions {
        pose_dims: Dims::All,
        coef_dims: CoefDims::Full,
        ..default
    };
    vec![
        config(DEFAULT_CONFIG, default, ModelFrame::Bone),
        config(PAPER_CONFIG, FitOptions::paper(), ModelFrame::Bone),
        config(
            NO_PROXIES_CONFIG,
            FitOptions {
                proxies: Occluders::None,
                ..default
            },
            ModelFrame::Bone,
        ),
        config(
            REST_CONFIG,
            FitOptions {
                prior: Prior::Rest,
                ..default
            },
            ModelFrame::Bone,
        ),
        config(
            "default, mean prior",
            FitOptions {
                prior: Prior::Mean,
                ..default
            },
            ModelFrame::Bone,
        ),
        config(
            "default, bound reaching the prior 2 widths out",
            FitOptions {
                bound: Some(2.0),
                ..default
            },
            ModelFrame::Bone,
        ),
        config(
            "default, bound clamping only (falloff ∞)",
            FitOptions {
                bound: Some(f64::INFINITY),
                ..default
            },
            ModelFrame::Bone,
        ),
        config(
            LOCAL_CONFIG,
            FitOptions {
                local: Local::Only,
                ..default
            },
            ModelFrame::Bone,
        ),
        config(
            AUTO_FEATURES_CONFIG,
            FitOptions {
                features: Features::Auto,
                ..default
            },
            ModelFrame::Bone,
        ),
        config(
            COSINES_CONFIG,
            FitOptions {
                features: Features::Cosines,
                ..default
            },
            ModelFrame::Bone,
        ),
        config(
            "default shape, LOO α",
            FitOptions {
                alpha: Alpha::Loo,
                ..default
            },
            ModelFrame::Bone,
        ),
        config("default shape, world frame", default, ModelFrame::World),
        config("full linear", full, ModelFrame::Bone),
        config(
            "full linear, least squares (α = 0)",
            FitOptions {
                alpha: Alpha::Fixed(0.0),
                ..full
            },
            ModelFrame::Bone,
        ),
        config(
            "PCA(8, 22)",
            FitOptions {
                pose_dims: Dims::Count(8),
                coef_dims: CoefDims::Count(22),
                ..default
            },
            ModelFrame::Bone,
        ),
        config(
            "PCA(4, 12)",
            FitOptions {
                pose_dims: Dims::Count(4),
                coef_dims: CoefDims::Count(12),
                ..default
            },
            ModelFrame::Bone,
        ),
    ]
}

/// The default trained with `n` sampled poses added to its training clip, exactly as `aprt
/// train --sample-poses n` adds them (same sampler, seed and joint limits): named
/// `default, --sample-poses n`.
pub fn sampled_config(n: usize) -> ModelConfig {
    ModelConfig {
        name: format!("default, --sample-poses {n}"),
        options: FitOptions::default(),
        frame: ModelFrame::Bone,
        sample_poses: n,
    }
}

/// What a `default, --sample-poses N` row is, for the documents that print one.
pub const SAMPLED_LEGEND: &str = "`default, --sample-poses N` is the default trained as `aprt train --sample-poses N` trains it: N poses, each a random training frame with 1 to 3 random joints re-drawn uniformly within the range each entry takes over the training clip (and the built-in characters' joint limits), baked and added to the training clip as a part of their own; its train err is on the training clip alone, and its fit s leaves out baking the N poses.";

/// `train` with `n` poses sampled from its frames and baked appended as the part
/// [`SAMPLED_CLIP`], the very poses `aprt train --sample-poses n` adds to the same frames.
fn with_sampled(
    rig: &dyn Rig,
    layout: &PoseLayout,
    train: &BakedClip,
    n: usize,
    settings: &BakeSettings,
    reporter: &dyn Reporter,
) -> Result<BakedClip> {
    let limits = rig.joint_limits();
    let poses = sample_poses(
        &rig.angle_names(),
        &train.poses,
        limits.as_deref(),
        n,
        SEED,
        0.0,
    );
    reporter.note(&format!("baking {n} sampled training poses"));
    let (sampled, _) = bake_clip(rig, layout, SAMPLED_CLIP, poses, settings, reporter)?;
    Ok(BakedClip::concat(vec![train.clone(), sampled]))
}

/// The `n` validation poses of `train`'s frames, sampled as `aprt train --validation-poses n`
/// samples them (same sampler, seed, margin and joint limits; see
/// [`crate::rig::pose_sampler::validation_poses`]) and baked with `settings` as the clip
/// [`VALIDATION_CLIP`], with the seconds the bake took (posing left out); None when `n` is 0.
/// Never trained on: [`run`] takes it among its validation clips.
pub fn baked_validation_poses(
    rig: &dyn Rig,
    layout: &PoseLayout,
    train: &BakedClip,
    n: usize,
    settings: &BakeSettings,
    reporter: &dyn Reporter,
) -> Result<Option<(BakedClip, f64)>> {
    let limits = rig.joint_limits();
    let poses = validation_poses(&rig.angle_names(), &train.poses, limits.as_deref(), n);
    if poses.is_empty() {
        return Ok(None);
    }
    reporter.note(&format!("baking {} validation poses", poses.len()));
    let count = poses.len();
    let (clip, per_frame) = bake_clip(rig, layout, VALIDATION_CLIP, poses, settings, reporter)?;
    Ok(Some((clip, per_frame * count as f64)))
}

/// One row of the table.
#[derive(Debug, serde::Serialize)]
pub struct Row {
    /// Model or baseline name.
    pub name: String,
    /// Bytes the method needs at runtime.
    pub bytes: usize,
    /// `bytes` as a percentage of one frame of f32 PRT.
    pub percent_of_frame: f64,
    /// Relative transfer error on the training frames.
    pub train_error: f64,
    /// Relative transfer error per novel clip, in clip order.
    pub test_errors: Vec<f64>,
    /// Microseconds per frame through aprt-core: pose step, lighting, shading of every vertex.
    pub shade_us: Option<f64>,
    /// Microseconds per frame of the occluder proxies on top (posing them, subtracting their
    /// occlusion from every vertex's shading), for models that have them.
    pub proxies_us: Option<f64>,
    /// Microseconds per frame through aprt-core for the full per-vertex transfer.
    pub transfer_us: Option<f64>,
    /// Multiply-adds per frame to shade every vertex in RGB, in millions.
    pub megaops: Option<f64>,
    /// Seconds to fit (α selection, both PCAs, solve).
    pub fit_s: Option<f64>,
    /// k_a and k_v and α, for models.
    pub shape: Option<(usize, usize, f64)>,
    /// For models: the prior, what was held out and every candidate's held-out error.
    pub selection: Option<Selection>,
}

/// A model the experiment fitted, with its blob.
pub struct Fitted {
    /// Its configuration.
    pub config: ModelConfig,
    /// The fit and its report.
    pub fit: Fit,
    /// The f32 blob.
    pub blob: Vec<u8>,
}

/// Everything an experiment measured.
pub struct Experiment {
    /// The models, in configuration order.
    pub models: Vec<Fitted>,
    /// The table: the models, then the baselines.
    pub rows: Vec<Row>,
    /// Configurations whose model the runtime cannot hold, and why.
    pub skipped: Vec<(String, String)>,
    /// Bytes of one frame of f32 PRT.
    pub frame_bytes: usize,
    /// The rest pose, baked: the anchor of the bone-frame models.
    pub rest: BakedClip,
    /// The skinned bind transfer's prediction of each test clip, the baseline whose worst
    /// vertices the demo measures the default on.
    pub skinned_tests: Vec<Vec<Vec<f32>>>,
}

impl Experiment {
    /// The model of configuration `name`, or why there is none (skipped as too large for the
    /// runtime, or no such configuration).
    pub fn model(&self, name: &str) -> Result<&Fitted> {
        if let Some(m) = self.models.iter().find(|m| m.config.name == name) {
            return Ok(m);
        }
        match self.skipped.iter().find(|(n, _)| n == name) {
            Some((_, reason)) => bail!("the model {name} was skipped: {reason}"),
            None => bail!("no model configuration is called {name}"),
        }
    }
}

/// Fits every configuration on `train`, with its [`ModelConfig::sample_poses`] sampled poses
/// baked and appended (skipping, with the reason, any whose model exceeds the runtime's limits), choosing each by `validation` when it is not empty (by segments of
/// `train` otherwise), then measures each model and the baselines on `train` and `tests` (at
/// least one). `lighting` is the SH lighting the timings shade with.
/// Which configuration is being fitted, and which are skipped, goes to `reporter`.
#[allow(clippy::too_many_arguments)]
pub fn run(
    rig: &dyn Rig,
    layout: &PoseLayout,
    train: &BakedClip,
    validation: &[BakedClip],
    tests: &[BakedClip],
    configs: &[ModelConfig],
    settings: &BakeSettings,
    lighting: &[f32],
    reporter: &dyn Reporter,
) -> Result<Experiment> {
    let order = settings.order;
    let vertices = rig.bind_mesh().vertex_count();
    let frame_bytes = vertices * order * order * 4;
    let timing_clip = tests.first().unwrap_or(train);
    let mut models = Vec::new();
    let mut rows = Vec::new();
    let mut skipped = Vec::new();
    let rest = bake_rest(rig, layout, settings, &Silent)?;
    // The training sets with sampled poses, one per count the configurations ask for.
    let mut sampled: Vec<(usize, BakedClip)> = Vec::new();
    for config in configs {
        let n = config.sample_poses;
        if n > 0 && !sampled.iter().any(|(m, _)| *m == n) {
            sampled.push((n, with_sampled(rig, layout, train, n, settings, reporter)?));
        }
    }
    for config in configs {
        reporter.note(&format!("fitting {}", config.name));
        let clips = ClipSet {
            train: sampled
                .iter()
                .find(|(n, _)| *n == config.sample_poses)
                .map_or(train, |(_, clip)| clip),
            rest: Some(&rest),
            validation,
        };
        let fitted = match fit_clip(rig, layout, clips, order, &config.options, config.frame) {
            Ok(fitted) => fitted,
            Err(err) if matches!(err.downcast_ref(), Some(FitError::NoLocalModel(_))) => {
                reporter.note(&format!("skipping {}: {err}", config.name));
                skipped.push((config.name.clone(), err.to_string()));
                continue;
            }
            Err(err) => return Err(err).with_context(|| format!("fitting {}", config.name)),
        };
        let s = &fitted.report.seconds;
        let fit_s =
            s.validate + s.pose_pca + s.vertex_basis + s.projection + s.cross_validation + s.solve;
        let blob = match encode_model(&fitted.model, Precision::F32) {
            Ok(blob) => blob,
            Err(err @ ExportError::TooLarge { .. }) => {
                reporter.note(&format!("skipping {}: {err}", config.name));
                skipped.push((config.name.clone(), err.to_string()));
                continue;
            }
            Err(err) => return Err(err).with_context(|| format!("writing {}", config.name)),
        };
        let model = *Model::parse(&blob)?.info();
        let error = |clip: &BakedClip| -> Result<f64> {
            let predicted =
                predict_world(&blob, &clip.angles, &clip.rotations, Some(clip.geometry()))?;
            Ok(relative_error(&predicted, &clip.transfer))
        };
        let train_error = error(train)?;
        let test_errors = tests.iter().map(error).collect::<Result<Vec<_>>>()?;
        let rotations = if config.frame == ModelFrame::Bone {
            timing_clip.core_rotations(0)
        } else {
            Vec::new()
        };
        let geometry = (&timing_clip.joints[0][..], &timing_clip.meshes[0]);
        let (shade_us, transfer_us, proxies_us) = time_core(
            &blob,
            &timing_clip.angles[0],
            &rotations,
            lighting,
            Some(geometry),
        )?;
        rows.push(Row {
            name: config.name.clone(),
            bytes: blob.len(),
            percent_of_frame: 100.0 * blob.len() as f64 / frame_bytes as f64,
            train_error,
            test_errors,
            shade_us: Some(shade_us),
            proxies_us,
            transfer_us: Some(transfer_us),
            megaops: Some(megaops(&model)),
            fit_s: Some(fit_s),
            // The fit's α: infinite when the model is its prior alone (its blob holds f32::MAX).
            shape: Some((model.pose_dims(), model.coef_dims(), fitted.report.alpha)),
            selection: Some(Selection::of(&fitted.report)),
        });
        models.push(Fitted {
            config: config.clone(),
            fit: fitted,
            blob,
        });
    }
    let (baseline_rows, skinned_tests) = baselines(rig, train, tests, settings, frame_bytes)?;
    rows.extend(baseline_rows);
    Ok(Experiment {
        models,
        rows,
        skipped,
        frame_bytes,
        rest,
        skinned_tests,
    })
}

/// The three baselines: the mean training transfer, the nearest training pose, and the bind
/// pose's transfer carried by the skinning; with the last one's prediction of each test clip.
#[allow(clippy::type_complexity)]
fn baselines(
    rig: &dyn Rig,
    train: &BakedClip,
    tests: &[BakedClip],
    settings: &BakeSettings,
    frame_bytes: usize,
) -> Result<(Vec<Row>, Vec<Vec<Vec<f32>>>)> {
    let mean = mean_transfer(&train.transfer);
    let mean_of =
        |set: &BakedClip| -> Result<Vec<Vec<f32>>> { Ok(vec![mean.clone(); set.transfer.len()]) };
    let nearest_of = |set: &BakedClip| -> Result<Vec<Vec<f32>>> {
        Ok(set
            .angles
            .iter()
            .map(|a| train.transfer[nearest_pose(&train.angles, a)].clone())
            .collect())
    };
    let bind_transfer =
        bake_poses(std::slice::from_ref(rig.bind_mesh()), settings, &Silent)?.remove(0);
    let rotation = ShRotation::new(settings.order)?;
    let skin = rig.skin();
    let skinned_of = |set: &BakedClip| -> Result<Vec<Vec<f32>>> {
        set.poses
            .iter()
            .map(|p| {
                Ok(skinned_transfer(
                    &rotation,
                    &bind_transfer,
                    |j| skin.influences(j).collect(),
                    &rig.joint_matrices(p)?,
                ))
            })
            .collect()
    };
    let row = |name: &str,
               bytes: usize,
               predict: &dyn Fn(&BakedClip) -> Result<Vec<Vec<f32>>>|
     -> Result<Row> {
        Ok(Row {
            name: name.into(),
            bytes,
            percent_of_frame: 100.0 * bytes as f64 / frame_bytes as f64,
            train_error: relative_error(&predict(train)?, &train.transfer),
            test_errors: tests
                .iter()
                .map(|t| Ok(relative_error(&predict(t)?, &t.transfer)))
                .collect::<Result<Vec<_>>>()?,
            shade_us: None,
            proxies_us: None,
            transfer_us: None,
            megaops: None,
            fit_s: None,
            shape: None,
            selection: None,
        })
    };
    let mut rows = vec![
        row("baseline: mean training transfer", frame_bytes, &mean_of)?,
        row(
            "baseline: nearest training pose",
            frame_bytes * train.transfer.len(),
            &nearest_of,
        )?,
        row("baseline: bind transfer, skinned", frame_bytes, &skinned_of)?,
    ];
    if let Some((bytes, corrected_of)) = corrected_bind(rig, &bind_transfer, settings.order)? {
        rows.push(row(
            "baseline: bind transfer, skinned, with occluder proxies",
            frame_bytes + bytes,
            &*corrected_of,
        )?);
    }
    let skinned_tests = tests.iter().map(skinned_of).collect::<Result<Vec<_>>>()?;
    Ok((rows, skinned_tests))
}

/// The skinned bind transfer with the occluder proxies' correction: what they block in the
/// pose, less what they blocked in the bind pose (whose transfer already holds it). Returns
/// the section's bytes and the prediction of a clip; `None` when no part of the character is
/// large enough for a proxy.
#[allow(clippy::type_complexity)]
fn corrected_bind<'a>(
    rig: &'a dyn Rig,
    bind_transfer: &[f32],
    order: usize,
) -> Result<Option<(usize, Box<dyn Fn(&BakedClip) -> Result<Vec<Vec<f32>>> + 'a>)>> {
    let bones = dominant_bones(rig);
    let Some((section, _)) = rig_section(rig, &bones, DEFAULT_CULL)? else {
        return Ok(None);
    };
    let skin = rig.skin();
    let rotation = ShRotation::new(order)?;
    let identity = vec![Mat4::IDENTITY; skin.joint_count()];
    let bind_occlusion = occlusion(&section, &bones, &identity, rig.bind_mesh(), order)?;
    let corrected: Vec<f32> = bind_transfer
        .iter()
        .zip(&bind_occlusion)
        .map(|(t, d)| t + d)
        .collect();
    let bytes = section.len();
    let predict = move |set: &BakedClip| -> Result<Vec<Vec<f32>>> {
        set.poses
            .iter()
            .zip(set.joints.iter().zip(&set.meshes))
            .map(|(p, (joints, mesh))| {
                let mut t = skinned_transfer(
                    &rotation,
                    &corrected,
                    |j| skin.influences(j).collect(),
                    &rig.joint_matrices(p)?,
                );
                let d = occlusion(&section, &bones, joints, mesh, order)?;
                t.iter_mut().zip(d).for_each(|(t, d)| *t -= d);
                Ok(t)
            })
            .collect()
    };
    Ok(Some((bytes, Box::new(predict))))
}

/// Median seconds of `f` over 31 calls (robust to a busy machine).
fn median_seconds(mut f: impl FnMut()) -> f64 {
    let mut samples: Vec<f64> = (0..31)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64()
        })
        .collect();
    samples.sort_by(f64::total_cmp);
    samples[15]
}

/// Per-frame cost through aprt-core on one pose: (shade µs, transfer µs, and for a model
/// with occluder proxies the µs of posing them and subtracting their occlusion from the
/// shading of every vertex, on `geometry`: the pose's joint matrices and posed mesh).
pub(crate) fn time_core(
    blob: &[u8],
    angles: &[f64],
    rotations: &[Rotation],
    lighting: &[f32],
    geometry: Option<(&[Mat4], &Mesh)>,
) -> Result<(f64, f64, Option<f64>)> {
    let model = Model::parse(blob)?;
    let info = model.info();
    let a: Vec<f32> = angles.iter().map(|&x| x as f32).collect();
    let mut pose = Box::new(PoseWeights::new());
    let mut lit = Box::new(LitWeights::new());
    let mut shading = vec![0.0f32; info.vertices()];
    let mut result = Ok(());
    let shade = median_seconds(|| {
        result = result
            .and(model.set_pose(&a, &mut pose))
            .and(model.light(&pose, lighting, rotations, &mut lit))
            .and(model.shade(&lit, 0, &mut shading));
    });
    let full_us = transfer_us(blob, angles)?;
    let proxies = match geometry.filter(|_| info.has_proxies()) {
        Some((joints, mesh)) => {
            let skinning = bone_skinning(joints, info.bones())?;
            let mut frame = Box::new(ProxyFrame::new());
            let seconds = median_seconds(|| {
                result = result
                    .and(model.pose_proxies(&skinning, &mut frame))
                    .and(model.occlude(
                        &frame,
                        lighting,
                        &mesh.positions,
                        &mesh.normals,
                        0,
                        &mut shading,
                    ));
            });
            Some(seconds * 1e6)
        }
        None => None,
    };
    result?;
    Ok((shade * 1e6, full_us, proxies))
}

/// Median µs through aprt-core of one pose's full per-vertex transfer (what an engine that
/// lights on the GPU asks the core for each frame).
pub(crate) fn transfer_us(blob: &[u8], angles: &[f64]) -> Result<f64> {
    let model = Model::parse(blob)?;
    let info = model.info();
    let a: Vec<f32> = angles.iter().map(|&x| x as f32).collect();
    let mut pose = Box::new(PoseWeights::new());
    let mut transfer = vec![0.0f32; info.vertices() * info.coeffs()];
    let mut result = Ok(());
    let full = median_seconds(|| {
        result = result
            .and(model.set_pose(&a, &mut pose))
            .and(model.transfer(&pose, 0, &mut transfer));
    });
    result?;
    Ok(full * 1e6)
}

/// Multiply-adds per frame for RGB shading of every vertex.
pub(crate) fn megaops(model: &ModelInfo) -> f64 {
    let (n2, ka, kv, v, a) = (
        model.coeffs() as f64,
        model.pose_dims() as f64,
        model.coef_dims() as f64,
        model.vertices() as f64,
        model.pose_len() as f64,
    );
    let ops = match model.basis() {
        aprt_core::Basis::Stored => ka * a + n2 * (ka + 1.0) * kv + 3.0 * (n2 * kv + kv * v),
        aprt_core::Basis::Identity => ka * a + 3.0 * n2 * (ka + 1.0) * (1.0 + v),
    };
    ops / 1e6
}

/// What the table's columns mean, for the documents that print it.
pub const TABLE_LEGEND: &str = "Errors are relative transfer errors ‖pred − truth‖ / ‖truth‖ over all frames, vertices and coefficients. Times are one core through aprt-core; megaops count multiply-adds for RGB shading of every vertex.";

/// The default's model selection (the first row's) under a markdown heading of `level`:
/// every candidate with its held-out error, as `train` prints it.
pub fn selection_markdown(rows: &[Row], level: &str) -> Option<String> {
    let selection = rows.first()?.selection.as_ref()?;
    Some(format!(
        "\n{level} Model selection of the default\n\nHeld-out mean squared error per transfer value of every candidate (pose features, prior and k_a, or the local model on every entry near each vertex), each at its best α:\n\n```\n{}\n```",
        selection.lines().join("\n")
    ))
}

/// The table as markdown: one column per test clip.
pub fn table_markdown(rows: &[Row], test_clips: &[String]) -> String {
    let mut s = String::new();
    let tests: Vec<String> = test_clips.iter().map(|n| format!("test `{n}`")).collect();
    let _ = writeln!(
        s,
        "| method | k_a | k_v | α | bytes | % of frame | train err | {} | shade µs/frame | proxies µs/frame | transfer µs/frame | megaops/frame | fit s |",
        tests.join(" | ")
    );
    let _ = writeln!(s, "|{}", "---|".repeat(12 + tests.len()));
    for r in rows {
        let opt =
            |x: Option<f64>, digits: usize| x.map_or("–".into(), |x| format!("{x:.digits$}"));
        let (ka, kv, alpha) = r
            .shape
            .map_or(("–".into(), "–".into(), "–".into()), |(a, v, al)| {
                (a.to_string(), v.to_string(), format!("{al:.3e}"))
            });
        let _ = writeln!(
            s,
            "| {} | {ka} | {kv} | {alpha} | {} | {:.1} | {:.2}% | {} | {} | {} | {} | {} | {} |",
            r.name,
            r.bytes,
            r.percent_of_frame,
            100.0 * r.train_error,
            r.test_errors
                .iter()
                .map(|e| format!("{:.2}%", 100.0 * e))
                .collect::<Vec<_>>()
                .join(" | "),
            opt(r.shade_us, 0),
            opt(r.proxies_us, 0),
            opt(r.transfer_us, 0),
            opt(r.megaops, 2),
            opt(r.fit_s, 2),
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rig::Clip;
    use crate::rig::character::Character;
    use crate::rig::pose_sampler::sampled_clip;

    /// Every 8th frame of the built-in character's walk, baked at order 2 without shadows.
    struct Walk {
        rig: Character,
        frames: Vec<Vec<f64>>,
        layout: PoseLayout,
        settings: BakeSettings,
        train: BakedClip,
    }

    fn walk() -> Walk {
        let rig = Character::builtin();
        let frames: Vec<Vec<f64>> = rig
            .clip("walk")
            .unwrap()
            .frames
            .into_iter()
            .step_by(8)
            .collect();
        let layout = PoseLayout::from_training(&rig.angle_names(), &frames).unwrap();
        let settings = BakeSettings {
            order: 2,
            shadows: false,
            ..BakeSettings::default()
        };
        let (train, _) =
            bake_clip(&rig, &layout, "walk", frames.clone(), &settings, &Silent).unwrap();
        Walk {
            rig,
            frames,
            layout,
            settings,
            train,
        }
    }

    /// The sampled row trains on the training clip followed by the very poses `aprt train
    /// --sample-poses` adds to the same frames, as a part of their own, baked like the clip.
    #[test]
    fn the_sampled_row_trains_on_the_clip_and_the_poses_aprt_train_samples() {
        let Walk {
            rig,
            frames,
            layout,
            settings,
            train,
        } = walk();
        let all = with_sampled(&rig, &layout, &train, 5, &settings, &Silent).unwrap();
        let clip = Clip {
            name: "walk".into(),
            fps: 30.0,
            frames: frames.clone(),
        };
        let limits = rig.joint_limits();
        let expected = sampled_clip(&rig.angle_names(), &[clip], limits.as_deref(), 5).unwrap();
        assert_eq!(
            all.parts,
            vec![
                ("walk".to_owned(), frames.len()),
                (SAMPLED_CLIP.to_owned(), 5)
            ]
        );
        assert_eq!(all.poses[..frames.len()], frames[..]);
        assert_eq!(all.poses[frames.len()..], expected.frames[..]);
        assert_eq!(all.transfer.len(), frames.len() + 5);
        assert_eq!(all.transfer[..frames.len()], train.transfer[..]);
        assert_eq!(sampled_config(5).name, "default, --sample-poses 5");
    }

    /// The validation poses are the ones `aprt train --validation-poses` adds to the same
    /// frames, baked as a clip of their own; none for 0.
    #[test]
    fn the_validation_poses_are_the_ones_aprt_train_samples() {
        use crate::rig::pose_sampler::validation_clip;
        let Walk {
            rig,
            frames,
            layout,
            settings,
            train,
        } = walk();
        let none = baked_validation_poses(&rig, &layout, &train, 0, &settings, &Silent);
        assert!(none.unwrap().is_none());
        let (clip, seconds) = baked_validation_poses(&rig, &layout, &train, 4, &settings, &Silent)
            .unwrap()
            .unwrap();
        let walk = Clip {
            name: "walk".into(),
            fps: 30.0,
            frames,
        };
        let limits = rig.joint_limits();
        let expected = validation_clip(&rig.angle_names(), &[walk], limits.as_deref(), 4).unwrap();
        assert_eq!(clip.name, VALIDATION_CLIP);
        assert_eq!(clip.poses, expected.frames);
        assert_eq!(clip.transfer.len(), 4);
        assert!(seconds >= 0.0);
    }

    #[test]
    fn a_skipped_or_unknown_model_is_an_error_that_says_why() {
        let result = Experiment {
            models: Vec::new(),
            rows: Vec::new(),
            skipped: vec![(DEFAULT_CONFIG.into(), "2 GiB is too large".into())],
            frame_bytes: 0,
            rest: BakedClip::concat(Vec::new()),
            skinned_tests: Vec::new(),
        };
        let message = |name: &str| result.model(name).err().unwrap().to_string();
        assert_eq!(
            message(DEFAULT_CONFIG),
            format!("the model {DEFAULT_CONFIG} was skipped: 2 GiB is too large")
        );
        assert_eq!(
            message("PCA(8, 22)"),
            "no model configuration is called PCA(8, 22)"
        );
    }
}
