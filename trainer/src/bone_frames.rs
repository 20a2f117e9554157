//! Bone frames: each vertex's transfer expressed in the frame of its most influential bone,
//! so the rigid part of limb motion needs no learning and the model only learns how
//! shadowing changes with the pose.

use anyhow::Result;
use aprt_core::rotate::ShRotation;
use glam::DMat3;

use crate::model::BoneFrames;
use crate::rig::Rig;
use crate::sh_rotate::{nearest_rotation, rotate_each};

/// Every bone's world rotation in a pose: the rotation part of its skinning matrix.
pub fn bone_rotations(rig: &dyn Rig, angles: &[f64]) -> Result<Vec<DMat3>> {
    Ok(rig
        .joint_matrices(angles)?
        .iter()
        .map(|m| nearest_rotation(DMat3::from_mat4(m.as_dmat4())))
        .collect())
}

/// Each vertex's bone: its most influential joint. Its transfer is learned in that frame.
pub fn dominant_bones(rig: &dyn Rig) -> BoneFrames {
    let skin = rig.skin();
    let vertex_bone = (0..skin.vertex_count())
        .map(|j| {
            skin.influences(j)
                .max_by(|a, b| a.1.total_cmp(&b.1))
                .map_or(0, |(b, _)| b as u16)
        })
        .collect();
    BoneFrames {
        count: skin.joint_count(),
        vertex_bone,
    }
}

/// World-frame transfer of each pose re-expressed in each vertex's bone frame: the targets a
/// bone-frame model is fitted to.
pub fn to_bone_frames(
    rig: &dyn Rig,
    poses: &[Vec<f64>],
    world: &[Vec<f32>],
) -> Result<Vec<Vec<f32>>> {
    change_frames(rig, poses, world, true)
}

/// Bone-frame transfer of each pose (as a bone-frame model predicts it) back in world space.
pub fn to_world_frames(
    rig: &dyn Rig,
    poses: &[Vec<f64>],
    local: &[Vec<f32>],
) -> Result<Vec<Vec<f32>>> {
    change_frames(rig, poses, local, false)
}

fn change_frames(
    rig: &dyn Rig,
    poses: &[Vec<f64>],
    transfer: &[Vec<f32>],
    into_bone: bool,
) -> Result<Vec<Vec<f32>>> {
    let bones = dominant_bones(rig);
    let vertices = rig.bind_mesh().vertex_count();
    let order = (transfer.first().map_or(0, |t| t.len() / vertices) as f64).sqrt() as usize;
    let rotation = ShRotation::new(order)?;
    poses
        .iter()
        .zip(transfer)
        .map(|(a, t)| {
            Ok(change_frame(
                &rotation,
                t,
                &bones,
                &bone_rotations(rig, a)?,
                into_bone,
            ))
        })
        .collect()
}

/// Transfer moved between world and bone frames: into the bone frame (`Rᵀ`) or out of it.
pub fn change_frame(
    rotation: &ShRotation,
    transfer: &[f32],
    bones: &BoneFrames,
    rotations: &[DMat3],
    into_bone: bool,
) -> Vec<f32> {
    rotate_each(rotation, transfer, |j| {
        let r = rotations[bones.vertex_bone[j] as usize];
        if into_bone { r.transpose() } else { r }
    })
}
