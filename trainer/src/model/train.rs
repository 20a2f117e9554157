//! Training a model: fit the linear model to a baked clip in the frame it is learned in, and
//! `aprt train` end to end (bake every pose through a checkpoint, so an interrupted run
//! resumes, fit, write the blob, then remove the checkpoint).

use std::borrow::Cow;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use nalgebra::DMatrix;

use crate::bake::BakeSettings;
use crate::bake::checkpoint::{Checkpoint, OnExisting};
use crate::bake::clip::{BakedClip, pose_all};
use crate::io::atomic::write_atomic;
use crate::io::source::Poses;
use crate::model::ModelFrame;
use crate::model::export::{Precision, encode_model};
use crate::model::fit::{Fit, FitOptions, fit};
use crate::model::runtime::{BlobInfo, describe};
use crate::progress::Reporter;
use crate::rig::Rig;
use crate::rig::bone_frames::{FrameChange, change_frames, dominant_bones};
use crate::rig::mesh::Mesh;
use crate::rig::pose_layout::PoseLayout;

/// Fits a model to `train` in `frame` (each vertex's dominant-bone frame, or world space). The
/// model records the layout's entry names.
pub fn fit_clip(
    rig: &dyn Rig,
    layout: &PoseLayout,
    train: &BakedClip,
    order: usize,
    options: &FitOptions,
    frame: ModelFrame,
) -> Result<Fit> {
    let bones = (frame == ModelFrame::Bone).then(|| dominant_bones(rig));
    let targets = match &bones {
        Some(b) => Cow::Owned(change_frames(
            &train.transfer,
            &train.rotations,
            b,
            FrameChange::WorldToBone,
        )?),
        None => Cow::Borrowed(&train.transfer),
    };
    let a = layout.names().len();
    let angles = DMatrix::from_fn(train.angles.len(), a, |i, j| train.angles[i][j]);
    let mut fitted = fit(&angles, &targets, order, options)?;
    fitted.model.bones = bones;
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
    /// Precision of the blob's large sections.
    pub precision: Precision,
    /// The frame a rig's clip is learned in. Meshes read from files have no bones and always
    /// learn transfer in world space.
    pub frame: ModelFrame,
    /// The checkpoint directory every baked pose is saved in until the model is written.
    pub checkpoint: PathBuf,
    /// What to do with a checkpoint that is already there.
    pub existing: OnExisting,
}

/// What [`train`] wrote.
#[derive(Debug)]
pub struct Trained {
    /// Poses the model was fitted to.
    pub poses: usize,
    /// The written blob, as `aprt inspect` describes it.
    pub info: BlobInfo,
}

/// Bakes every pose (through the checkpoint), fits the model, writes it to `output`
/// atomically and then removes the checkpoint. Notes (joints left out, bake progress, poses
/// resumed) go to `reporter`.
pub fn train(
    poses: Poses,
    output: &Path,
    settings: &TrainSettings,
    reporter: &dyn Reporter,
) -> Result<Trained> {
    let (fitted, checkpoint, poses) = match poses {
        Poses::Meshes {
            files,
            meshes,
            angles,
        } => {
            let name = |i: usize| files[i].display().to_string();
            let (transfers, checkpoint) = bake_checkpointed(&meshes, name, settings, reporter)?;
            let a = DMatrix::from_fn(angles.len(), angles[0].len(), |i, j| angles[i][j]);
            let fitted = fit(&a, &transfers, settings.bake.order, &settings.fit)?;
            (fitted, checkpoint, angles.len())
        }
        Poses::Rig { rig, clip } => {
            let layout = PoseLayout::from_training(&rig.angle_names(), &clip.frames)
                .with_context(|| format!("clip {}", clip.name))?;
            if !layout.dropped().is_empty() {
                reporter.note(&format!(
                    "joints that never move in {} and are left out of the model: {}",
                    clip.name,
                    layout.dropped().join(", ")
                ));
            }
            let meshes = pose_all(rig.as_ref(), &clip.name, &clip.frames)?;
            let name = |i: usize| format!("clip {} frame {i}", clip.name);
            let (transfer, checkpoint) = bake_checkpointed(&meshes, name, settings, reporter)?;
            let frames = clip.frames.len();
            let baked = BakedClip::new(
                rig.as_ref(),
                &layout,
                &clip.name,
                clip.frames,
                meshes,
                transfer,
            )?;
            let fitted = fit_clip(
                rig.as_ref(),
                &layout,
                &baked,
                settings.bake.order,
                &settings.fit,
                settings.frame,
            )?;
            (fitted, checkpoint, frames)
        }
    };
    let blob = encode_model(&fitted.model, settings.precision)?;
    write_atomic(output, &blob).with_context(|| format!("cannot write {}", output.display()))?;
    checkpoint.remove()?;
    Ok(Trained {
        poses,
        info: describe(&blob)?,
    })
}

/// The transfer of every pose of `meshes`, through the checkpoint of `settings` (opened for
/// these meshes, so a resume with other inputs is refused); `name(i)` names pose `i` in errors.
fn bake_checkpointed(
    meshes: &[Mesh],
    name: impl Fn(usize) -> String,
    settings: &TrainSettings,
    reporter: &dyn Reporter,
) -> Result<(Vec<Vec<f32>>, Checkpoint)> {
    let mut checkpoint = Checkpoint::open(
        &settings.checkpoint,
        settings.existing,
        &settings.bake,
        meshes,
    )?;
    let transfer = checkpoint.bake(meshes, name, reporter)?;
    Ok((transfer, checkpoint))
}
