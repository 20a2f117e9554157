//! What a written model predicts, in world space, through `aprt-core`: for rows of its own pose
//! vector, or for any clip of its character, mapped onto the pose entries the model records.

use anyhow::{Context, Result, bail};
use glam::DMat3;

use crate::bake::clip::Geometry;
use crate::model::occluders::occlusion;
use crate::model::runtime::{self, BlobInfo};
use crate::rig::bone_frames::{FrameChange, all_rotations, change_frames};
use crate::rig::pose_layout::PoseLayout;
use crate::rig::{Clip, Rig};

/// World-frame transfer a blob predicts through aprt-core for model pose vectors `angles`;
/// `rotations` (each frame's bone rotations) are used when the model is in bone frames, and
/// `geometry` (each frame's joint matrices and posed mesh) when it has occluder proxies, whose
/// occlusion is subtracted as the runtime does.
pub fn predict_world(
    blob: &[u8],
    angles: &[Vec<f64>],
    rotations: &[Vec<DMat3>],
    geometry: Option<Geometry<'_>>,
) -> Result<Vec<Vec<f32>>> {
    let raw = runtime::predict_transfer(blob, angles)?;
    let frames = runtime::bone_frames(blob)?;
    let mut world = match &frames {
        Some(b) => change_frames(&raw, rotations, b, FrameChange::BoneToWorld)?,
        None => raw,
    };
    let (Some(section), Some(bones)) = (runtime::proxies_section(blob)?, &frames) else {
        return Ok(world);
    };
    let geometry = geometry.context(
        "this model has occluder proxies: evaluating it needs each frame's posed mesh and \
         joint matrices (a clip of its character), not pose vectors alone",
    )?;
    if geometry.meshes.len() != world.len() || geometry.joints.len() != world.len() {
        bail!(
            "{} frames of pose vectors but {} posed meshes and {} frames of joints",
            world.len(),
            geometry.meshes.len(),
            geometry.joints.len()
        );
    }
    let order = aprt_core::Model::parse(blob)?.info().order();
    for (f, t) in world.iter_mut().enumerate() {
        let d = occlusion(
            section,
            bones,
            &geometry.joints[f],
            &geometry.meshes[f],
            order,
        )
        .with_context(|| format!("frame {f}"))?;
        for (t, d) in t.iter_mut().zip(d) {
            *t -= d;
        }
    }
    Ok(world)
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
    let (joints, meshes) = match runtime::proxies_section(blob)? {
        Some(_) => {
            let joints = clip
                .frames
                .iter()
                .map(|p| rig.joint_matrices(p))
                .collect::<Result<Vec<_>, _>>()?;
            let meshes = clip
                .frames
                .iter()
                .map(|p| rig.pose(p))
                .collect::<Result<Vec<_>, _>>()?;
            (joints, meshes)
        }
        None => (Vec::new(), Vec::new()),
    };
    let geometry = Geometry {
        joints: &joints,
        meshes: &meshes,
    };
    predict_world(blob, &angles, &rotations, Some(geometry))
}
