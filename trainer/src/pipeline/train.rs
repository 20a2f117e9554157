//! Training a model: fit the linear model to a baked clip in the frame it is learned in, and
//! `aprt train` end to end (bake every pose through a checkpoint, so an interrupted run
//! resumes, fit, write the blob, then remove the checkpoint).

use std::borrow::Cow;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result};
use aprt_core::{
    MAX_BONES, MAX_COEF_DIMS, MAX_LIT, MAX_POSE_DIMS, MAX_POSE_LEN, MAX_VERTICES, Rotation,
};
use nalgebra::DMatrix;

use crate::bake::budget::{BudgetError, Workload};
pub use crate::bake::checkpoint::ShardBaked;
use crate::bake::checkpoint::{Checkpoint, OnExisting, Vertices};
use crate::bake::clip::{BakedClip, pose_all};
use crate::bake::shard::Shard;
use crate::bake::{BakeError, BakeSettings};
use crate::io::atomic::write_atomic;
use crate::io::source::{Poses, clip_names};
use crate::irradiance_rig::RigKind;
use crate::irradiance_rig::fit::{FIT_POSES, fit_irradiance_rig, rig_fitting_surfaces};
use crate::limits::MAX_FRAMES;
use crate::model::export::{ExportError, Precision, check_alpha};
use crate::model::fit::{
    Alpha, Anchor, Choice, CoefDims, Decision, Dims, Fit, FitInput, FitOptions, FitReport,
    HeldOutKind, LOCALITY_RADIUS, Local, Offer, PriorKind, Validation, choose, fit, fit_input,
    rest_distance_sentence,
};
use crate::model::locality::locality;
use crate::model::occluders::{
    DEFAULT_CULL, OccluderChoice, Occluders, rig_section, with_occlusion,
};
use crate::model::precision::{PrecisionChoice, encode_chosen};
use crate::model::runtime::{BlobInfo, describe};
use crate::model::{LinearModel, ModelFrame};
use crate::progress::Reporter;
use crate::rig::bone_frames::BoneFrames;
use crate::rig::bone_frames::{FrameChange, change_frames, dominant_bones};
use crate::rig::mesh::Mesh;
use crate::rig::pose_layout::PoseLayout;
use crate::rig::pose_sampler::{DEFAULT_VALIDATION_POSES, sampled_clip, validation_clip};
use crate::rig::{Clip, Rig};

/// Training poses sampled for the locality's distances (besides the bind pose).
const LOCALITY_POSES: usize = 24;

/// What a rig's model is fitted to: the training frames (one clip or several), the rest pose
/// (baked, one frame: the prior of bone-frame models) and the clips held out whole to choose
/// the model by.
#[derive(Clone, Copy)]
pub struct ClipSet<'a> {
    /// The training frames.
    pub train: &'a BakedClip,
    /// The rest pose, baked.
    pub rest: Option<&'a BakedClip>,
    /// Validation clips: `--validate`'s, then the validation poses (`--validation-poses`).
    pub validation: &'a [BakedClip],
}

/// Fits a model to `clips` in `frame` (each vertex's dominant-bone frame, or world space). The
/// model records the layout's entry names. Bone-frame models are anchored at the rest pose
/// (their prior, when it wins on held-out error, is the rest transfer carried by the skin);
/// world-frame models keep the mean as their prior. Bone-frame models are fitted with and
/// without occluder proxies fitted to the bind mesh (`options.proxies`), each with its own
/// model selection, and keep the one of lower held-out error; the report says what both gave.
pub fn fit_clip(
    rig: &dyn Rig,
    layout: &PoseLayout,
    clips: ClipSet<'_>,
    order: usize,
    options: &FitOptions,
    frame: ModelFrame,
) -> Result<Fit> {
    let bones = (frame == ModelFrame::Bone).then(|| dominant_bones(rig));
    let proxies = match (options.proxies, &bones) {
        (Occluders::None, _) | (_, None) => None,
        (_, Some(b)) => rig_section(rig, b, DEFAULT_CULL)?,
    };
    let fit_with = |section: Option<&[u8]>| {
        let bones = bones.as_ref();
        fit_targets(rig, layout, clips, order, options, bones, section)
    };
    let plain = match (&proxies, options.proxies) {
        (Some(_), Occluders::On) => None,
        _ => Some(fit_with(None)?),
    };
    let Some((section, proxy_fit)) = proxies else {
        return plain.context("a fit without proxies");
    };
    let occluded = fit_with(Some(&section))?;
    let held_out = |f: &Fit| f.report.chosen.held_out_error;
    let without = plain.as_ref().map(held_out);
    // Without the proxies first, the simpler: they win a tie, as they cost nothing a frame.
    fn offer(f: &Fit, complexity: usize) -> Offer<'_> {
        Offer {
            error: f.report.chosen.held_out_error,
            rows: f.report.chosen_rows(),
            complexity,
        }
    }
    let offers: Vec<Offer<'_>> = plain
        .iter()
        .map(|p| offer(p, 0))
        .chain([offer(&occluded, 1)])
        .collect();
    let verdict = choose(&offers).expect("the fit with proxies is offered");
    let used = verdict.chosen == offers.len() - 1;
    let names = ["without proxies", "with proxies"];
    let decision =
        (offers.len() > 1).then(|| Decision::of("proxies", &verdict, |i| names[i].into()));
    let choice = OccluderChoice {
        spheres: proxy_fit.proxies.len(),
        volume_error: proxy_fit.volume_error,
        held_out_with: held_out(&occluded),
        held_out_without: without,
        used,
    };
    let mut fitted = match (used, plain) {
        (false, Some(plain)) => plain,
        _ => Fit {
            model: LinearModel {
                proxies: Some(section),
                ..occluded.model
            },
            report: occluded.report,
        },
    };
    fitted.report.occluders = Some(choice);
    fitted.report.decisions.extend(decision);
    Ok(fitted)
}

/// [`fit_clip`]'s fit of one set of targets: the transfer in the model's frame, plus the
/// occlusion of the proxies of `section` when given.
fn fit_targets(
    rig: &dyn Rig,
    layout: &PoseLayout,
    clips: ClipSet<'_>,
    order: usize,
    options: &FitOptions,
    bones: Option<&BoneFrames>,
    section: Option<&[u8]>,
) -> Result<Fit> {
    let in_frame = |clip: &'_ BakedClip| -> Result<Vec<Vec<f32>>> {
        let targets = match (section, bones) {
            (Some(s), Some(b)) => &with_occlusion(s, b, clip, order)?,
            _ => &clip.transfer,
        };
        Ok(match bones {
            Some(b) => change_frames(targets, &clip.rotations, b, FrameChange::WorldToBone)?,
            None => targets.clone(),
        })
    };
    let matrix = |clip: &BakedClip| {
        DMatrix::from_fn(clip.angles.len(), layout.names().len(), |i, j| {
            clip.angles[i][j]
        })
    };
    let train = clips.train;
    let targets = in_frame(train)?;
    let angles = matrix(train);
    let rest = match (clips.rest, bones) {
        (Some(rest), Some(_)) => Some((in_frame(rest)?.remove(0), rest.angles[0].clone())),
        _ => None,
    };
    let held = clips
        .validation
        .iter()
        .map(|v| Ok((v.name.as_str(), matrix(v), in_frame(v)?)))
        .collect::<Result<Vec<_>>>()?;
    // The local model's groups, from the rig's geometry over a sample of the training poses.
    let locality = match (options.local, bones, &rest) {
        (Local::Auto | Local::Only, Some(_), Some(_)) => {
            let stride = train.meshes.len().div_ceil(LOCALITY_POSES).max(1);
            let sample: Vec<&Mesh> = train.meshes.iter().step_by(stride).collect();
            Some(locality(rig, layout, &sample, LOCALITY_RADIUS)?)
        }
        _ => None,
    };
    let input = FitInput {
        angles: &angles,
        transfers: &targets,
        order,
        clips: train.parts.iter().map(|(_, n)| *n).collect(),
        anchor: rest
            .as_ref()
            .map(|(transfer, angles)| Anchor { angles, transfer }),
        validation: held
            .iter()
            .map(|(name, angles, transfers)| Validation {
                name,
                angles,
                transfers,
            })
            .collect(),
        locality: locality.as_ref(),
    };
    let mut fitted = fit_input(&input, options)?;
    fitted.model.bones = bones.cloned();
    fitted.model.angle_names = layout.names().to_vec();
    Ok(fitted)
}

/// What `aprt train` is asked for besides its poses.
#[derive(Clone, Debug)]
pub struct TrainSettings {
    /// How the poses are baked.
    pub bake: BakeSettings,
    /// The model's shape and regularisation.
    pub fit: FitOptions,
    /// Precision of the blob's large sections, or how to choose it.
    pub precision: PrecisionChoice,
    /// The frame a rig's clip is learned in. Meshes read from files have no bones and always
    /// learn transfer in world space.
    pub frame: ModelFrame,
    /// The checkpoint directory every baked pose is saved in until the model is written.
    pub checkpoint: PathBuf,
    /// What to do with a checkpoint that is already there.
    pub existing: OnExisting,
    /// An irradiance rig to fit to the character and store in the blob (its optional
    /// `IrradianceRig` section), so an engine lights the model from a handful of SH vectors.
    pub irradiance_rig: Option<RigKind>,
    /// Bake only this shard's share of the frames into the checkpoint and stop: a bake farm's
    /// machines each bake one shard, and a final run without it fits the model from the
    /// merged checkpoint (`docs/guide/bake-farms.md`). A shard always joins a checkpoint of the same
    /// inputs and settings, whatever `existing` says, since its fellow shards share it.
    pub shard: Option<Shard>,
    /// `--sample-poses`: training poses sampled within the range each pose entry takes over
    /// the training clips ([`crate::rig::pose_sampler`]), baked and fitted as one more training
    /// clip part, `sampled`. 0: none. Characters only.
    pub sample_poses: usize,
    /// `--validation-poses`: poses sampled from the training frames as `--sample-poses`
    /// samples them but with their own seed and reaching [`VALIDATION_MARGIN`] beyond the
    /// training range ([`crate::rig::pose_sampler::validation_clip`]), baked with the same
    /// settings and appended to the validation clips as the clip `validation poses`: never
    /// trained on, only used to choose the model by. None: [`DEFAULT_VALIDATION_POSES`] for a
    /// character, none for meshes read from files (which have no joints to sample); 0: none,
    /// today's selection exactly.
    ///
    /// [`VALIDATION_MARGIN`]: crate::rig::pose_sampler::VALIDATION_MARGIN
    pub validation_poses: Option<usize>,
}

impl TrainSettings {
    /// The validation poses asked of `poses` ([`TrainSettings::validation_poses`], the default
    /// resolved): 0 for meshes read from files.
    pub fn validation_pose_count(&self, poses: &Poses) -> usize {
        match poses {
            Poses::Meshes { .. } => 0,
            Poses::Rig { .. } => self.validation_poses.unwrap_or(DEFAULT_VALIDATION_POSES),
        }
    }
}

/// A model option that no bake could make valid.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum OptionError {
    /// More pose dimensions than the runtime holds.
    #[error("{0} pose dimensions asked for, more than the {MAX_POSE_DIMS} aprt-core holds")]
    PoseDims(usize),
    /// A pose-variance fraction outside `(0, 1]`.
    #[error("the fraction of the pose variance to keep must lie in (0, 1], not {0}{hint}", hint = percent_hint(*.0))]
    PoseFraction(f64),
    /// No vertex-basis vectors.
    #[error(
        "a model needs at least 1 vertex-basis vector to predict any transfer (or none at all: the full linear model, without vertex reduction)"
    )]
    NoCoefDims,
    /// More vertex-basis vectors than the runtime holds.
    #[error(
        "{0} vertex-basis vectors asked for, more than the {MAX_COEF_DIMS} aprt-core holds (the full linear model has no vertex reduction and no such limit)"
    )]
    CoefDims(usize),
    /// A transfer-energy fraction outside `(0, 1]`.
    #[error("the fraction of the transfer energy to keep must lie in (0, 1], not {0}{hint}", hint = percent_hint(*.0))]
    CoefFraction(f64),
    /// A fixed α the model header cannot hold.
    #[error(transparent)]
    Alpha(ExportError),
}

/// For a fraction written as a percentage (`95`), the fraction meant.
fn percent_hint(f: f64) -> String {
    if f > 1.0 && f <= 100.0 {
        format!(" (for {f} % write {})", f / 100.0)
    } else {
        String::new()
    }
}

/// Checks the model options alone: what the runtime holds and what a fraction or α can be.
pub fn check_options(options: &FitOptions) -> Result<(), OptionError> {
    let fraction = |f: f64| f > 0.0 && f <= 1.0;
    match options.pose_dims {
        Dims::Count(k) if k > MAX_POSE_DIMS => return Err(OptionError::PoseDims(k)),
        Dims::Variance(f) if !fraction(f) => return Err(OptionError::PoseFraction(f)),
        _ => {}
    }
    match options.coef_dims {
        CoefDims::Count(0) => return Err(OptionError::NoCoefDims),
        CoefDims::Count(k) if k > MAX_COEF_DIMS => return Err(OptionError::CoefDims(k)),
        CoefDims::Variance(f) if !fraction(f) => return Err(OptionError::CoefFraction(f)),
        _ => {}
    }
    if let Alpha::Fixed(alpha) = options.alpha {
        check_alpha(alpha).map_err(OptionError::Alpha)?;
    }
    Ok(())
}

/// Why `aprt train` refused its request before baking anything.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum RequestError {
    /// More sampled poses than one run bakes.
    #[error(
        "--sample-poses {0}: more than the {MAX_FRAMES} frames one run bakes or evaluates; sample fewer poses"
    )]
    SamplePoses(usize),
    /// Sampled poses asked of meshes read from files, which have no joints to sample.
    #[error(
        "--sample-poses samples a character's joints: meshes read from files (--obj-seq) have none; use a character (--builtin, --gltf, --bvh) or leave it out"
    )]
    SamplePosesMeshes,
    /// More validation poses than one run bakes.
    #[error(
        "--validation-poses {0}: more than the {MAX_FRAMES} frames one run bakes or evaluates; sample fewer poses"
    )]
    ValidationPoses(usize),
    /// Validation poses asked of meshes read from files, which have no joints to sample.
    #[error(
        "--validation-poses {0} samples a character's joints: meshes read from files (--obj-seq) have none; use a character (--builtin, --gltf, --bvh), or leave it out (or give 0): an OBJ sequence's model is chosen on held-out runs of its frames"
    )]
    ValidationPosesMeshes(usize),
    /// A bake setting is out of range.
    #[error(transparent)]
    Bake(#[from] BakeError),
    /// A model option is invalid.
    #[error(transparent)]
    Option(#[from] OptionError),
    /// More pose entries than the runtime takes.
    #[error(
        "{what}: the model would take {entries} pose entries ({per}), more than the {MAX_POSE_LEN} aprt-core accepts"
    )]
    PoseEntries {
        /// The clip or files.
        what: String,
        /// Entries the model would take.
        entries: usize,
        /// Where entries come from: `three per moving joint` or `one per column of angles`.
        per: &'static str,
    },
    /// More vertices than a model may have.
    #[error("{what}: {vertices} vertices, more than the {MAX_VERTICES} a model may have")]
    Vertices {
        /// The clip or files.
        what: String,
        /// Vertices of the mesh.
        vertices: usize,
    },
    /// More bones than a bone-frame model may have.
    #[error(
        "{what}: a bone-frame model of this character needs {bones} bones, more than the {MAX_BONES} aprt-core holds; learn the model in world space instead"
    )]
    Bones {
        /// The clip.
        what: String,
        /// Joints of the skin.
        bones: usize,
    },
    /// More lighting weights per frame than the runtime holds.
    #[error(
        "{what}: a bone-frame model of {bones} bones with {width} lighting weights per bone needs {total} per frame, more than the {MAX_LIT} aprt-core holds; {hint}",
        total = bones * width
    )]
    Lighting {
        /// The clip.
        what: String,
        /// Bones of the model.
        bones: usize,
        /// Lighting weights per bone (k_v, or n² for the full linear model).
        width: usize,
        /// What would fit.
        hint: String,
    },
    /// The bake would exceed the budget of one run.
    #[error(transparent)]
    Budget(#[from] BudgetError),
}

/// Checks everything about `poses` and `settings` that needs no bake, before anything is
/// skinned, baked or written: the bake settings and model options, the runtime's limits on the
/// model (pose entries, vertices, bones, lighting weights per frame) and the budget of the bake
/// (frames, memory, rays, checkpoint files; see [`crate::bake::budget`]). [`train`] calls it
/// first, so a refusal leaves no checkpoint behind.
///
/// A vertex-basis count is checked as asked: a bone-frame model of `b` bones holds at most
/// `MAX_LIT / b` vectors. Limits that depend on the fit (the rank, the vectors a variance
/// fraction keeps) are checked when the model is written.
pub fn check(poses: &Poses, settings: &TrainSettings) -> Result<(), RequestError> {
    settings.bake.validate()?;
    check_options(&settings.fit)?;
    if settings.sample_poses > MAX_FRAMES {
        return Err(RequestError::SamplePoses(settings.sample_poses));
    }
    check_validation_poses(poses, settings.validation_poses)?;
    let (what, frames, mesh, entries, bones) = match poses {
        Poses::Meshes {
            files,
            meshes,
            angles,
        } => {
            if settings.sample_poses > 0 {
                return Err(RequestError::SamplePosesMeshes);
            }
            let (Some(file), Some(mesh)) = (files.first(), meshes.first()) else {
                return Ok(()); // nothing to bake; the fit refuses it
            };
            let dir = file.parent().unwrap_or(Path::new("."));
            let entries = angles.first().map(Vec::len);
            (dir.display().to_string(), meshes.len(), mesh, entries, None)
        }
        Poses::Rig {
            rig,
            clips,
            validation,
        } => {
            let entries = PoseLayout::from_training(&rig.angle_names(), &training_frames(clips))
                .map(|layout| layout.names().len())
                .ok();
            let bones = (settings.frame == ModelFrame::Bone).then(|| rig.skin().joint_count());
            let what = format!("clip {}", clip_names(clips));
            let frames = clips
                .iter()
                .chain(validation)
                .map(|c| c.frames.len())
                .sum::<usize>()
                + settings.sample_poses
                + settings.validation_pose_count(poses);
            (what, frames, rig.bind_mesh(), entries, bones)
        }
    };
    if let Some(entries) = entries.filter(|&e| e > MAX_POSE_LEN) {
        let per = match poses {
            Poses::Meshes { .. } => "one per column of angles",
            Poses::Rig { .. } => "three per moving joint",
        };
        return Err(RequestError::PoseEntries { what, entries, per });
    }
    if mesh.vertex_count() > MAX_VERTICES {
        let vertices = mesh.vertex_count();
        return Err(RequestError::Vertices { what, vertices });
    }
    if let Some(bones) = bones {
        if bones > MAX_BONES {
            return Err(RequestError::Bones { what, bones });
        }
        let n2 = settings.bake.order * settings.bake.order;
        let (width, hint) = match settings.fit.coef_dims.at_order(settings.bake.order) {
            CoefDims::Count(k) => (
                k,
                format!("at most {} vertex-basis vectors fit", MAX_LIT / bones),
            ),
            CoefDims::Full => (
                n2,
                "the full linear model does not fit; keep a vertex basis".to_owned(),
            ),
            CoefDims::Variance(_) | CoefDims::FieldsPlus(_) => (0, String::new()),
        };
        if bones * width > MAX_LIT {
            return Err(RequestError::Lighting {
                what,
                bones,
                width,
                hint,
            });
        }
    }
    // The bake's result, its copy in bone frames, and the full model's f64 outputs.
    let copies = 1
        + usize::from(bones.is_some())
        + 2 * usize::from(settings.fit.coef_dims == CoefDims::Full);
    Workload::bake(frames, mesh, &settings.bake, copies)
        .with_checkpoint()
        .check(&what)?;
    Ok(())
}

/// Checks the validation poses asked of `poses` ([`TrainSettings::validation_poses`]): no
/// more than one run bakes, and none asked of meshes read from files. Part of [`check`];
/// `aprt train --scene` runs it before it plans anything.
pub fn check_validation_poses(poses: &Poses, asked: Option<usize>) -> Result<(), RequestError> {
    match (poses, asked) {
        (_, Some(n)) if n > MAX_FRAMES => Err(RequestError::ValidationPoses(n)),
        (Poses::Meshes { .. }, Some(n)) if n > 0 => Err(RequestError::ValidationPosesMeshes(n)),
        _ => Ok(()),
    }
}

/// The model selection of a fit, for reports and report.json: the chosen candidate, what was
/// held out, and every candidate with its held-out error.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Selection {
    /// The chosen prior.
    pub prior: PriorKind,
    /// What the selection held out.
    pub held_out: HeldOutKind,
    /// The candidate the model is.
    pub chosen: Choice,
    /// How far the rest pose lies from the training poses, in standard deviations (see
    /// `fit::rest_distance`).
    pub rest_distance: Option<f64>,
    /// Every (features, prior, k_a or local) candidate with its best α, in the order tried.
    pub choices: Vec<Choice>,
    /// What the occluder proxies did, when they were tried.
    pub occluders: Option<OccluderChoice>,
    /// How each stage chose (candidates, features, proxies), and by how much.
    pub decisions: Vec<Decision>,
    /// The validation sets (empty for held-out runs) and what each alone would choose.
    pub validation_sets: Vec<ValidationSet>,
}

/// One validation set of a selection: a clip (`--validate`) or the validation poses.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ValidationSet {
    /// The clip's name.
    pub name: String,
    /// Its poses.
    pub poses: usize,
    /// Each candidate's mean error on this set alone, as `choices`.
    pub errors: Vec<f64>,
    /// The candidate of lowest error on this set alone.
    pub lowest: String,
}

impl ValidationSet {
    /// Each set of `report` with its candidates' errors on it.
    fn of(report: &FitReport) -> Vec<Self> {
        let per_choice: Vec<Vec<f64>> = (0..report.choices.len())
            .map(|i| report.set_errors(i))
            .collect();
        let mut sets = Vec::new();
        for (s, (name, poses)) in report.validation_sets.iter().enumerate() {
            let errors: Vec<f64> = per_choice.iter().map(|e| e[s]).collect();
            let lowest = (0..errors.len())
                .filter(|&i| errors[i].is_finite())
                .min_by(|&a, &b| errors[a].total_cmp(&errors[b]))
                .map_or_else(String::new, |i| report.choices[i].label());
            sets.push(Self {
                name: name.clone(),
                poses: *poses,
                errors,
                lowest,
            });
        }
        sets
    }
}

impl Selection {
    /// The selection a fit report records.
    pub fn of(report: &FitReport) -> Self {
        Self {
            prior: report.prior,
            held_out: report.held_out,
            chosen: report.chosen,
            rest_distance: report.rest_distance,
            choices: report.choices.clone(),
            occluders: report.occluders,
            decisions: report.decisions.clone(),
            validation_sets: ValidationSet::of(report),
        }
    }

    /// What the selection held out, as its first line names it.
    fn held_out_phrase(&self) -> String {
        match self.held_out {
            HeldOutKind::Segments(n) => format!("held-out runs of {n} poses"),
            HeldOutKind::Clips(_) => {
                let sets: Vec<String> = self
                    .validation_sets
                    .iter()
                    .map(|s| format!("{} ({} poses)", crate::text::quote(&s.name), s.poses))
                    .collect();
                format!("validation on {}", sets.join(" and "))
            }
        }
    }

    /// One line per candidate, the chosen one marked: the held-out curve over k_a and prior.
    pub fn lines(&self) -> Vec<String> {
        let held = self.held_out_phrase();
        let c = &self.chosen;
        let shape = if c.is_prior() {
            c.shape()
        } else {
            let shape = if c.local { "local model" } else { "k_a" };
            format!("{shape} {}, alpha {:.3e}", c.pose_dims, c.alpha)
        };
        let mut lines = vec![format!(
            "model selection ({held}): {}, prior {}, {shape}",
            features_name(c.cosines),
            c.prior.name(),
        )];
        if let Some(d) = self.rest_distance {
            lines.push(format!("  {}", rest_distance_sentence(d)));
        }
        if let Some(o) = &self.occluders {
            let without = o
                .held_out_without
                .map_or(String::new(), |w| format!(", without them {w:.4e}"));
            let verdict = if o.used { "kept" } else { "left out" };
            lines.push(format!(
                "  occluder proxies: {} spheres, volume error {:.0} %; held-out {:.4e} with them{without}: {verdict} (the candidates below are the {} model's)",
                o.spheres,
                100.0 * o.volume_error,
                o.held_out_with,
                if o.used { "proxies'" } else { "plain" },
            ));
        }
        lines.extend(self.decisions.iter().map(|d| format!("  {}", d.sentence())));
        if self.decisions.iter().any(|d| d.poses > 0) {
            lines.push(format!("  (the rule: {})", crate::model::fit::RULE));
        }
        if self.validation_sets.len() > 1 {
            lines.extend(self.validation_sets.iter().map(|s| {
                let name = crate::text::quote(&s.name);
                format!("  {name} alone would choose {}", s.lowest)
            }));
        }
        lines.extend(self.choices.iter().enumerate().map(|(i, c)| {
            let mark = if *c == self.chosen { " <- chosen" } else { "" };
            let alpha = if c.is_prior() {
                String::new()
            } else {
                format!("alpha {:.3e}, ", c.alpha)
            };
            format!(
                "  {:<7} prior {:<4} {}: {alpha}held-out {:.4e}{}, train {:.4e}{mark}",
                features_name(c.cosines),
                c.prior.name(),
                c.shape(),
                c.held_out_error,
                self.per_set(i),
                c.train_error
            )
        }));
        lines
    }

    /// Candidate `i`'s error on each validation set, when there are several.
    fn per_set(&self, i: usize) -> String {
        if self.validation_sets.len() < 2 {
            return String::new();
        }
        let parts: Vec<String> = self
            .validation_sets
            .iter()
            .map(|s| format!("{} {:.4e}", crate::text::quote(&s.name), s.errors[i]))
            .collect();
        format!(" ({})", parts.join(", "))
    }
}

/// The name of a candidate's pose features, as `--features` spells them.
fn features_name(cosines: bool) -> &'static str {
    if cosines { "cosines" } else { "angles" }
}

/// What [`train`] did: fit and write the model, or bake one shard of it.
#[derive(Debug)]
pub enum Outcome {
    /// The model was written (boxed: a shard's outcome is a fraction of its size).
    Trained(Box<Trained>),
    /// One shard was baked into the checkpoint ([`TrainSettings::shard`]); nothing was fitted.
    Shard(ShardBaked),
}

/// What [`train`] wrote.
#[derive(Debug)]
pub struct Trained {
    /// Poses the model was fitted to.
    pub poses: usize,
    /// The model selection: the prior, what was held out, every candidate.
    pub selection: Selection,
    /// The written blob, as `aprt inspect` describes it.
    pub info: BlobInfo,
    /// The precision written, and why.
    pub precision: (Precision, String),
    /// Poses baked (training, validation and the rest pose), resumed ones included.
    pub baked_poses: usize,
    /// Validation poses sampled, baked and used to choose the model
    /// ([`TrainSettings::validation_poses`]); 0 when none.
    pub validation_poses: usize,
    /// Seconds this run spent baking the validation poses (the bake and checkpointing of each,
    /// posing left out). Poses read back from a checkpoint cost 0 here: a resumed or merged
    /// run counts only what it baked itself.
    pub validation_bake_s: f64,
    /// Seconds spent baking (with posing) and fitting (with the rig and encoding).
    pub seconds: RunSeconds,
}

/// Wall-clock seconds of the stages of [`train`].
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct RunSeconds {
    /// Posing and baking every pose, through the checkpoint.
    pub bake: f64,
    /// Fitting the model and the irradiance rig, choosing the precision, writing the blob.
    pub fit: f64,
}

/// Training poses the automatic precision is measured on at most (evenly spaced).
const PRECISION_POSES: usize = 16;

/// Bakes every pose (through the checkpoint), fits the model, writes it to `output`
/// atomically and then removes the checkpoint. Notes (joints left out, bake progress, poses
/// resumed) go to `reporter`. With [`TrainSettings::shard`] it only bakes that shard's share
/// of the poses into the checkpoint, and writes nothing else.
pub fn train(
    poses: Poses,
    output: &Path,
    settings: &TrainSettings,
    reporter: &dyn Reporter,
) -> Result<Outcome> {
    check(&poses, settings)?;
    // Validation poses first, from the user's training frames alone.
    let n = settings.validation_pose_count(&poses);
    let (poses, validation_poses) = with_validation_poses(poses, n);
    let poses = with_sampled_poses(poses, settings.sample_poses);
    if let Some(shard) = settings.shard {
        if !settings.bake.shadows {
            anyhow::bail!(
                "--shard {shard}: a shadowless bake is the closed-form cosine lobe, milliseconds a pose, and keeps no checkpoint to merge: run it in one piece"
            );
        }
        return bake_shard(&poses, shard, settings, reporter).map(Outcome::Shard);
    }
    let started = Instant::now();
    let rig_section = match &settings.irradiance_rig {
        Some(kind) => {
            let meshes = fitting_surfaces(&poses)?;
            Some(fit_irradiance_rig(*kind, &meshes, settings.bake.order)?)
        }
        None => None,
    };
    let outcome = match poses {
        Poses::Meshes {
            files,
            meshes,
            angles,
        } => {
            let name = |i: usize| files[i].display().to_string();
            let baking = Instant::now();
            let (transfers, checkpoint, _) =
                bake_checkpointed(&meshes, name, 0..0, settings, reporter)?;
            let bake_s = baking.elapsed().as_secs_f64();
            let a = DMatrix::from_fn(angles.len(), angles[0].len(), |i, j| angles[i][j]);
            let fitted = fit(&a, &transfers, settings.bake.order, &settings.fit)?;
            let step = angles.len().div_ceil(PRECISION_POSES).max(1);
            FitOutcome {
                fitted,
                checkpoint,
                poses: angles.len(),
                baked: meshes.len(),
                bake_s,
                validation_bake_s: 0.0,
                measure_on: angles
                    .iter()
                    .step_by(step)
                    .map(|a| (a.clone(), Vec::new()))
                    .collect(),
            }
        }
        Poses::Rig {
            rig,
            clips,
            validation,
        } => fit_rig_clips(
            rig.as_ref(),
            &clips,
            &validation,
            validation_poses,
            settings,
            reporter,
        )?,
    };
    let chosen = encode_chosen(
        &outcome.fitted.model,
        rig_section.as_deref(),
        &settings.precision,
        &outcome.measure_on,
    )?;
    write_atomic(output, &chosen.blob)
        .with_context(|| format!("cannot write {}", output.display()))?;
    if let Some(checkpoint) = outcome.checkpoint {
        checkpoint.remove()?;
    }
    let total = started.elapsed().as_secs_f64();
    Ok(Outcome::Trained(Box::new(Trained {
        poses: outcome.poses,
        selection: Selection::of(&outcome.fitted.report),
        info: describe(&chosen.blob)?,
        precision: (chosen.precision, chosen.reason),
        baked_poses: outcome.baked,
        validation_poses,
        validation_bake_s: outcome.validation_bake_s,
        seconds: RunSeconds {
            bake: outcome.bake_s,
            fit: total - outcome.bake_s,
        },
    })))
}

/// `poses` with `n` sampled training poses appended as the training clip `sampled` (a
/// character's; [`check`] refuses it for meshes read from files). Sampled before
/// anything is baked, so they are checkpointed like every other training frame and a resume
/// samples the very same poses.
fn with_sampled_poses(poses: Poses, n: usize) -> Poses {
    match poses {
        Poses::Rig {
            rig,
            mut clips,
            validation,
        } if n > 0 => {
            let limits = rig.joint_limits();
            let names = rig.angle_names();
            clips.extend(sampled_clip(&names, &clips, limits.as_deref(), n));
            Poses::Rig {
                rig,
                clips,
                validation,
            }
        }
        poses => poses,
    }
}

/// `poses` with `n` validation poses appended to its validation clips as the clip
/// [`crate::rig::pose_sampler::VALIDATION_CLIP`] (a character's; [`check`] refuses them for
/// meshes read from files), and how many were appended. Sampled from the training frames
/// before anything is baked (and before `--sample-poses` adds its own), so they are
/// checkpointed like every other pose and a resume or a shard samples the very same ones.
fn with_validation_poses(poses: Poses, n: usize) -> (Poses, usize) {
    match poses {
        Poses::Rig {
            rig,
            clips,
            mut validation,
        } if n > 0 => {
            let limits = rig.joint_limits();
            let names = rig.angle_names();
            let clip = validation_clip(&names, &clips, limits.as_deref(), n);
            let count = clip.as_ref().map_or(0, |c| c.frames.len());
            validation.extend(clip);
            let poses = Poses::Rig {
                rig,
                clips,
                validation,
            };
            (poses, count)
        }
        poses => (poses, 0),
    }
}

/// A fitted model with what it took.
struct FitOutcome {
    fitted: Fit,
    /// None for closed-form bakes, which keep no checkpoint.
    checkpoint: Option<Checkpoint>,
    /// Training poses.
    poses: usize,
    /// Poses baked.
    baked: usize,
    /// Seconds posing and baking.
    bake_s: f64,
    /// Seconds baking the validation poses in this run ([`Trained::validation_bake_s`]).
    validation_bake_s: f64,
    /// Training poses (angles and bone rotations) to measure the precision on.
    measure_on: Vec<(Vec<f64>, Vec<Rotation>)>,
}

/// Bakes a character's training and validation clips (and, for bone-frame models, the rest
/// pose) through one checkpoint and fits the model. The last `validation_poses` frames of
/// `validation` are the validation poses, whose bake is timed on its own.
fn fit_rig_clips(
    rig: &dyn Rig,
    clips: &[Clip],
    validation: &[Clip],
    validation_poses: usize,
    settings: &TrainSettings,
    reporter: &dyn Reporter,
) -> Result<FitOutcome> {
    let what = clip_names(clips);
    let layout = PoseLayout::from_training(&rig.angle_names(), &training_frames(clips))
        .with_context(|| format!("clip {what}"))?;
    if !layout.dropped().is_empty() {
        reporter.note(&format!(
            "joints that never move in {what} and are left out of the model: {}",
            layout.dropped().join(", ")
        ));
    }
    // Training clips, then validation clips, then (for bone-frame models, which are
    // anchored at it) the rest pose: all baked through one checkpoint.
    let baking = Instant::now();
    let all: Vec<&Clip> = clips.iter().chain(validation).collect();
    let rest_pose = rig.rest_pose();
    let anchored = settings.frame == ModelFrame::Bone;
    let (mut meshes, names) = rig_poses(rig, &all, anchored.then_some(&rest_pose[..]))?;
    let baked = meshes.len();
    let name = |i: usize| names[i].clone();
    let clip_frames: usize = all.iter().map(|c| c.frames.len()).sum();
    let timed = clip_frames - validation_poses..clip_frames;
    let (mut transfer, checkpoint, validation_bake_s) =
        bake_checkpointed(&meshes, name, timed, settings, reporter)?;
    let bake_s = baking.elapsed().as_secs_f64();
    let rest = if anchored {
        let (mesh, t) = (meshes.pop(), transfer.pop());
        Some(BakedClip::new(
            rig,
            &layout,
            "rest pose",
            vec![rest_pose],
            mesh.into_iter().collect(),
            t.into_iter().collect(),
        )?)
    } else {
        None
    };
    let (mut meshes, mut transfer) = (meshes.into_iter(), transfer.into_iter());
    let mut baked_clips = all
        .iter()
        .map(|clip| {
            let n = clip.frames.len();
            BakedClip::new(
                rig,
                &layout,
                &clip.name,
                clip.frames.clone(),
                meshes.by_ref().take(n).collect(),
                transfer.by_ref().take(n).collect(),
            )
        })
        .collect::<Result<Vec<_>>>()?;
    let held = baked_clips.split_off(clips.len());
    let train = BakedClip::concat(baked_clips);
    let set = ClipSet {
        train: &train,
        rest: rest.as_ref(),
        validation: &held,
    };
    let fitted = fit_clip(
        rig,
        &layout,
        set,
        settings.bake.order,
        &settings.fit,
        settings.frame,
    )?;
    let step = train.angles.len().div_ceil(PRECISION_POSES).max(1);
    let measure_on = (0..train.angles.len())
        .step_by(step)
        .map(|f| {
            let rotations = if anchored {
                train.core_rotations(f)
            } else {
                Vec::new()
            };
            (train.angles[f].clone(), rotations)
        })
        .collect();
    Ok(FitOutcome {
        fitted,
        checkpoint,
        poses: train.poses.len(),
        baked,
        bake_s,
        validation_bake_s,
        measure_on,
    })
}

/// Every pose a rig's model is baked at, in checkpoint order, with its name for errors: the
/// frames of `clips` (the training clips, then the validation clips), then, for bone-frame
/// models (anchored at it), the rest pose `rest`.
fn rig_poses(
    rig: &dyn Rig,
    clips: &[&Clip],
    rest: Option<&[f64]>,
) -> Result<(Vec<Mesh>, Vec<String>)> {
    let mut meshes = Vec::new();
    let mut names = Vec::new();
    for clip in clips {
        meshes.extend(pose_all(rig, &clip.name, &clip.frames)?);
        names.extend((0..clip.frames.len()).map(|f| format!("clip {} frame {f}", clip.name)));
    }
    if let Some(rest) = rest {
        meshes.push(rig.pose(rest)?);
        names.push("the rest pose".to_owned());
    }
    Ok((meshes, names))
}

/// Bakes `shard`'s share of the poses [`train`] would bake into the checkpoint of
/// `settings`, started or joined (the shards share it); fits nothing, and leaves the
/// irradiance rig to the final run.
fn bake_shard(
    poses: &Poses,
    shard: Shard,
    settings: &TrainSettings,
    reporter: &dyn Reporter,
) -> Result<ShardBaked> {
    let (meshes, names) = match poses {
        Poses::Meshes { files, meshes, .. } => {
            let names = files.iter().map(|f| f.display().to_string()).collect();
            (Cow::Borrowed(meshes.as_slice()), names)
        }
        Poses::Rig {
            rig,
            clips,
            validation,
        } => {
            let all: Vec<&Clip> = clips.iter().chain(validation).collect();
            let rest = (settings.frame == ModelFrame::Bone).then(|| rig.rest_pose());
            let (meshes, names) = rig_poses(rig.as_ref(), &all, rest.as_deref())?;
            (Cow::Owned(meshes), names)
        }
    };
    let (ck, bake) = (&settings.checkpoint, &settings.bake);
    let mut checkpoint = Checkpoint::open(ck, OnExisting::Resume, bake, &meshes)?;
    let name = |i: usize| names[i].clone();
    Ok(checkpoint.bake_shard(&meshes, &Vertices, shard, name, reporter)?)
}

/// The surfaces an irradiance rig is fitted over: a character's bind pose and up to
/// [`FIT_POSES`] training poses in its root frame, or up to [`FIT_POSES`] of the meshes read
/// from files (the first first).
pub fn fitting_surfaces(poses: &Poses) -> Result<Vec<Mesh>> {
    Ok(match poses {
        Poses::Meshes { meshes, .. } => {
            let step = meshes.len().div_ceil(FIT_POSES).max(1);
            meshes.iter().step_by(step).cloned().collect()
        }
        Poses::Rig { rig, clips, .. } => rig_fitting_surfaces(rig.as_ref(), clips)?,
    })
}

/// Every frame of the training clips, in order.
fn training_frames(clips: &[Clip]) -> Vec<Vec<f64>> {
    clips
        .iter()
        .flat_map(|c| c.frames.iter().cloned())
        .collect()
}

/// The transfer of every pose of `meshes`, through the checkpoint of `settings` (opened for
/// these meshes, so a resume with other inputs is refused); `name(i)` names pose `i` in errors.
/// A shadowless bake is closed form and keeps no checkpoint. Also the seconds this run spent
/// baking the poses `timed` (those read back from the checkpoint cost 0).
fn bake_checkpointed(
    meshes: &[Mesh],
    name: impl Fn(usize) -> String,
    timed: Range<usize>,
    settings: &TrainSettings,
    reporter: &dyn Reporter,
) -> Result<(Vec<Vec<f32>>, Option<Checkpoint>, f64)> {
    let (transfer, checkpoint, seconds) = if settings.bake.shadows {
        let mut checkpoint = Checkpoint::open(
            &settings.checkpoint,
            settings.existing,
            &settings.bake,
            meshes,
        )?;
        if settings.existing == OnExisting::Resume && checkpoint.is_new() {
            reporter.note(&format!(
                "note: nothing to resume: {} held no checkpoint, so every pose is baked",
                settings.checkpoint.display()
            ));
        }
        let (transfer, seconds) = checkpoint.bake_at_timed(meshes, &Vertices, name, reporter)?;
        (transfer, Some(checkpoint), seconds[timed].iter().sum())
    } else {
        // Closed form, milliseconds a pose: nothing worth saving for a resume. Baked in three
        // runs to time the poses `timed` (each pose's bake is its own, so bit for bit the
        // same as one run).
        let bake = |meshes: &[Mesh]| crate::bake::bake_poses(meshes, &settings.bake, reporter);
        if timed.is_empty() {
            (bake(meshes)?, None, 0.0)
        } else {
            let mut transfer = bake(&meshes[..timed.start])?;
            let started = Instant::now();
            transfer.extend(bake(&meshes[timed.clone()])?);
            let seconds = started.elapsed().as_secs_f64();
            transfer.extend(bake(&meshes[timed.end..])?);
            (transfer, None, seconds)
        }
    };
    // What follows takes time and memory linear in the poses (model/fit/ridge.rs).
    reporter.note(&format!("baked {} poses; fitting the model", meshes.len()));
    Ok((transfer, checkpoint, seconds))
}
