//! Bone frames: each vertex's transfer expressed in the frame of its most influential bone,
//! so the rigid part of limb motion needs no learning and the model only learns how
//! shadowing changes with the pose.

use anyhow::{Result, bail};
use aprt_core::ShRotation;
use glam::DMat3;

use crate::rig::Rig;
use crate::rig::transfer_rotation::{nearest_rotation, rotate_each};

/// For bone-frame models: which bone's frame each vertex's transfer is expressed in.
#[derive(Clone, Debug, PartialEq)]
pub struct BoneFrames {
    /// Number of bones.
    pub count: usize,
    /// The bone of each vertex.
    pub vertex_bone: Vec<u16>,
}

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

/// [`bone_rotations`] of every pose.
pub fn all_rotations(rig: &dyn Rig, poses: &[Vec<f64>]) -> Result<Vec<Vec<DMat3>>> {
    poses.iter().map(|a| bone_rotations(rig, a)).collect()
}

/// Which way transfer moves between world space and each vertex's bone frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameChange {
    /// World-frame transfer re-expressed in each vertex's bone frame (by `Rᵀ`): the targets a
    /// bone-frame model is fitted to.
    WorldToBone,
    /// Bone-frame transfer (as a bone-frame model predicts it) back in world space (by `R`).
    BoneToWorld,
}

/// Transfer of each of `poses` of `rig` moved between world space and each vertex's bone
/// frame: [`change_frames`] with the rig's bone rotations in each pose, and its bones.
pub fn change_rig_frames(
    rig: &dyn Rig,
    poses: &[Vec<f64>],
    transfer: &[Vec<f32>],
    change: FrameChange,
) -> Result<Vec<Vec<f32>>> {
    change_frames(
        transfer,
        &all_rotations(rig, poses)?,
        &dominant_bones(rig),
        change,
    )
}

/// Transfer of every frame moved into (or out of) each vertex's bone frame; `rotations` are
/// each frame's bone rotations.
pub fn change_frames(
    transfer: &[Vec<f32>],
    rotations: &[Vec<DMat3>],
    bones: &BoneFrames,
    change: FrameChange,
) -> Result<Vec<Vec<f32>>> {
    if rotations.len() != transfer.len() {
        bail!(
            "moving transfer between world and bone frames needs every frame's bone rotations \
             ({} frames, rotations for {})",
            transfer.len(),
            rotations.len()
        );
    }
    let vertices = bones.vertex_bone.len();
    let order = (transfer.first().map_or(0, |t| t.len() / vertices.max(1)) as f64).sqrt() as usize;
    let rotation = ShRotation::new(order)?;
    Ok(transfer
        .iter()
        .zip(rotations)
        .map(|(t, r)| change_frame(&rotation, t, bones, r, change))
        .collect())
}

/// One frame's transfer moved between world and bone frames, as `change` says.
pub fn change_frame(
    rotation: &ShRotation,
    transfer: &[f32],
    bones: &BoneFrames,
    rotations: &[DMat3],
    change: FrameChange,
) -> Vec<f32> {
    rotate_each(rotation, transfer, |j| {
        let r = rotations[bones.vertex_bone[j] as usize];
        match change {
            FrameChange::WorldToBone => r.transpose(),
            FrameChange::BoneToWorld => r,
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bone_frame_transfer_without_every_frames_rotations_is_refused() {
        let bones = BoneFrames {
            count: 1,
            vertex_bone: vec![0],
        };
        let transfer = vec![vec![1.0f32; 4]; 2];
        let err = change_frames(
            &transfer,
            &[vec![DMat3::IDENTITY]],
            &bones,
            FrameChange::BoneToWorld,
        )
        .unwrap_err();
        assert!(
            err.to_string().contains("(2 frames, rotations for 1)"),
            "{err}"
        );
        let moved = change_frames(
            &transfer,
            &vec![vec![DMat3::IDENTITY]; 2],
            &bones,
            FrameChange::BoneToWorld,
        )
        .unwrap();
        for (m, t) in moved.iter().flatten().zip(transfer.iter().flatten()) {
            assert!(
                (m - t).abs() < 1e-6,
                "the identity moved transfer: {moved:?}"
            );
        }
    }
}
