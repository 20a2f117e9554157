//! Bone frames: each vertex's transfer expressed in the frame of its most influential bone,
//! so the rigid part of limb motion needs no learning and the model only learns how
//! shadowing changes with the pose. A light-map model's rows are texels: each takes the bone
//! that drives its triangles most ([`dominant_texel_bones`]).

use anyhow::{Result, bail};
use aprt_core::ShRotation;
use glam::DMat3;

use crate::rig::Rig;
use crate::rig::mesh::Mesh;
use crate::rig::skin::Skin;
use crate::rig::transfer_rotation::{nearest_rotation, rotate_each};
use crate::rig::uv::Atlas;

/// For bone-frame models: which bone's frame each vertex's (or light-map texel row's)
/// transfer is expressed in.
#[derive(Clone, Debug, PartialEq)]
pub struct BoneFrames {
    /// Number of bones.
    pub count: usize,
    /// The bone of each vertex (of each row: a light-map model's rows are texels).
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

/// The bone of largest weight among `(bone, weight)` pairs; of equal weights, the last.
fn heaviest(weights: impl Iterator<Item = (u32, f32)>) -> u16 {
    weights
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .map_or(0, |(b, _)| b as u16)
}

/// Each vertex's bone: its most influential joint. Its transfer is learned in that frame.
pub fn dominant_bones(rig: &dyn Rig) -> BoneFrames {
    let skin = rig.skin();
    let vertex_bone = (0..skin.vertex_count())
        .map(|j| heaviest(skin.influences(j)))
        .collect();
    BoneFrames {
        count: skin.joint_count(),
        vertex_bone,
    }
}

/// The bone of every filled texel of `atlas` (on `bind`'s triangles, skinned by `skin`), in
/// texel order as a light-map model's rows are. A texel's weight for a bone is the sum of
/// the three corners' skin weights of each triangle its samples lie on (the triangle, not the
/// sample point: a texel takes the bone that drives its triangles, as a vertex takes its own),
/// averaged over its samples; a gutter texel's is the mean of its neighbours' that the
/// dilation reads ([`Atlas::gather`], exactly as its transfer is filled). Its bone is the one
/// of largest weight; of equal weights, the highest index (the last, as [`dominant_bones`]
/// takes the last of a vertex's equal influences). Holds samples × bones weights while it
/// works.
pub fn dominant_texel_bones(skin: &Skin, bind: &Mesh, atlas: &Atlas) -> BoneFrames {
    let count = skin.joint_count().max(1);
    let mut weights = vec![0.0f32; atlas.samples().len() * count];
    for (w, s) in weights.chunks_exact_mut(count).zip(atlas.samples()) {
        for &v in &bind.triangles[s.triangle as usize] {
            for (b, x) in skin.influences(v as usize) {
                w[b as usize] += x;
            }
        }
    }
    let map = atlas.gather(&weights, count);
    let vertex_bone = atlas
        .filled()
        .iter()
        .zip(map.chunks_exact(count))
        .filter(|(f, _)| **f)
        .map(|(_, w)| heaviest((0..).zip(w.iter().copied())))
        .collect();
    BoneFrames { count, vertex_bone }
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
    if let Some(r) = rotations.iter().find(|r| r.len() < bones.count) {
        bail!(
            "the model's transfer is in the frames of {} bones, the character has {}: give the \
             character the model was trained on",
            bones.count,
            r.len()
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
    use crate::rig::uv::UvLayout;

    /// A quad split on its diagonal (UV `[0, ¼]²` of an 8² atlas: texels x, y < 2) and a
    /// triangle far from it: a texel takes the bone of largest summed corner weight over its
    /// samples' triangles (the diagonal texels sample both, and their sum picks a bone neither
    /// triangle alone does), ties go to the higher bone, and gutter texels take their filled
    /// neighbours' mean weights.
    #[test]
    fn texels_take_the_bone_that_drives_their_triangles() {
        let influences: Vec<Vec<(u32, f32)>> = vec![
            vec![(0, 1.0)],
            vec![(1, 1.0)],
            vec![(0, 0.25), (1, 0.25), (2, 0.5)],
            vec![(2, 1.0)],
            vec![(1, 1.0)],
            vec![(1, 1.0)],
            vec![(1, 1.0)],
        ];
        let skin = Skin::from_influences(&influences).unwrap();
        let uvs = [
            [0.0, 0.0],
            [0.25, 0.0],
            [0.25, 0.25],
            [0.0, 0.25],
            [0.75, 0.75],
            [1.0, 0.75],
            [1.0, 1.0],
        ];
        let triangles = vec![[0, 1, 2], [0, 2, 3], [4, 5, 6]];
        let bind = Mesh {
            positions: vec![[0.0; 3]; 7],
            normals: vec![[0.0, 0.0, 1.0]; 7],
            triangles,
        };
        let layout = UvLayout::from_vertex_uvs(&uvs, &bind.triangles);
        let atlas = Atlas::build(&layout, &bind.triangles, 8).unwrap();
        let bones = dominant_texel_bones(&skin, &bind, &atlas);
        let filled = atlas.filled();
        assert_eq!(bones.count, 3);
        assert_eq!(
            bones.vertex_bone.len(),
            filled.iter().filter(|&&f| f).count()
        );
        let bone_at = |x: usize, y: usize| {
            let t = y * 8 + x;
            assert!(filled[t], "texel ({x}, {y}) is not filled");
            bones.vertex_bone[filled[..t].iter().filter(|&&f| f).count()]
        };
        // Below the diagonal only the first triangle: bones 0 and 1 weigh 1.25 each, the tie
        // goes to 1. Above it only the second: bone 2 (1.5).
        assert_eq!(bone_at(1, 0), 1);
        assert_eq!(bone_at(0, 1), 2);
        // On the diagonal both: 2.5, 1.5 and 2 summed, bone 0.
        assert_eq!(bone_at(0, 0), 0);
        assert_eq!(bone_at(1, 1), 0);
        // Gutters: (2, 0) reads (1, 0) and (1, 1): means 1.25, 1, 0.75; (0, 2) reads (0, 1) and
        // (1, 1): 1.25, 0.5, 1.25, a tie to bone 2; the far triangle's ring is its bone 1.
        assert_eq!(bone_at(2, 0), 0);
        assert_eq!(bone_at(0, 2), 2);
        assert_eq!(bone_at(5, 7), 1);
        assert_eq!(bone_at(7, 4), 1);
    }

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
