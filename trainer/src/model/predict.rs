//! What a written model predicts, in world space, through `aprt-core`: for rows of its own pose
//! vector, or for any clip of its character, mapped onto the pose entries the model records.

use anyhow::{Context, Result, bail};
use glam::DMat3;

use crate::model::runtime::BlobInfo;
use crate::rig::bone_frames::{FrameChange, all_rotations, change_frames};
use crate::rig::pose_layout::PoseLayout;
use crate::rig::{Clip, Rig};

/// World-frame transfer a blob predicts through aprt-core for model pose vectors `angles`;
/// `rotations` (each frame's bone rotations) are used when the model is in bone frames.
pub fn predict_world(
    blob: &[u8],
    angles: &[Vec<f64>],
    rotations: &[Vec<DMat3>],
) -> Result<Vec<Vec<f32>>> {
    let raw = crate::model::runtime::predict_transfer(blob, angles)?;
    match crate::model::runtime::bone_frames(blob)? {
        Some(b) => change_frames(&raw, rotations, &b, FrameChange::BoneToWorld),
        None => Ok(raw),
    }
}

/// World-frame transfer of every frame of `clip` of `rig` as the model `blob` (described by
/// `info`, called `model_name` in errors) predicts it: each frame's pose vector is mapped onto
/// the pose entries the model records, by name, and bone-frame models take each frame's bone
/// rotations. Errors name the entries the rig lacks, or a vertex count that differs.
pub fn predict_clip(
    blob: &[u8],
    info: &BlobInfo,
    model_name: &str,
    rig: &dyn Rig,
    clip: &Clip,
) -> Result<Vec<Vec<f32>>> {
    let layout = PoseLayout::from_names(&rig.angle_names(), &info.angle_names)
        .with_context(|| format!("{model_name} does not fit this character"))?;
    if rig.bind_mesh().vertex_count() != info.vertices {
        bail!(
            "{model_name} has {} vertices, the character has {}",
            info.vertices,
            rig.bind_mesh().vertex_count()
        );
    }
    let angles: Vec<Vec<f64>> = clip.frames.iter().map(|p| layout.reduce(p)).collect();
    let rotations = all_rotations(rig, &clip.frames)?;
    predict_world(blob, &angles, &rotations)
}
