//! The ground truth of a clip: a rig posed at every frame and baked, with what fitting and
//! measuring a model need beside the transfer (the model's pose vector of each frame and every
//! bone's rotation). The demo, the results document and `aprt train` all bake clips this way.

use std::time::Instant;

use anyhow::{Context, Result};
use glam::{DMat3, Mat4};

use crate::bake::{BakeSettings, bake_poses};
use crate::progress::Reporter;
use crate::rig::Rig;
use crate::rig::bone_frames::all_rotations;
use crate::rig::mesh::Mesh;
use crate::rig::pose_layout::PoseLayout;
use crate::rig::transfer_rotation::row_major;

/// Ground truth of one clip: its poses, meshes and baked transfer.
#[derive(Clone)]
pub struct BakedClip {
    /// Clip name.
    pub name: String,
    /// The rig's full pose vector of each frame.
    pub poses: Vec<Vec<f64>>,
    /// The model's pose vector of each frame (the layout's entries).
    pub angles: Vec<Vec<f64>>,
    /// The posed meshes.
    pub meshes: Vec<Mesh>,
    /// World-frame transfer of each frame, `v × n²` vertex-major.
    pub transfer: Vec<Vec<f32>>,
    /// Per frame, every bone's world rotation.
    pub rotations: Vec<Vec<DMat3>>,
    /// Per frame, every joint's skinning matrix (bind pose to posed): what moves a model's
    /// occluder proxies.
    pub joints: Vec<Vec<Mat4>>,
    /// The clips the frames come from, in order, with their frame counts (one for a single
    /// clip): held-out segments of the fit never straddle two of them.
    pub parts: Vec<(String, usize)>,
}

/// Each frame's joint matrices and posed mesh: what a model's occluder proxies need besides
/// its pose vector (see [`crate::model::occluders`]).
#[derive(Clone, Copy, Debug)]
pub struct Geometry<'a> {
    /// Per frame, every joint's skinning matrix.
    pub joints: &'a [Vec<Mat4>],
    /// Per frame, the posed mesh.
    pub meshes: &'a [Mesh],
}

/// Poses and bakes `poses` of `rig`; returns the clip and the bake's seconds per frame. The
/// bake's progress and its speed go to `reporter`.
pub fn bake_clip(
    rig: &dyn Rig,
    layout: &PoseLayout,
    name: &str,
    poses: Vec<Vec<f64>>,
    settings: &BakeSettings,
    reporter: &dyn Reporter,
) -> Result<(BakedClip, f64)> {
    let meshes = pose_all(rig, name, &poses)?;
    let start = Instant::now();
    let transfer =
        bake_poses(&meshes, settings, reporter).with_context(|| format!("baking clip {name}"))?;
    let per_frame = start.elapsed().as_secs_f64() / poses.len().max(1) as f64;
    reporter.note(&format!(
        "  {name}: {} frames, {per_frame:.2} s/frame",
        poses.len()
    ));
    Ok((
        BakedClip::new(rig, layout, name, poses, meshes, transfer)?,
        per_frame,
    ))
}

/// The rig's rest pose ([`Rig::rest_pose`]), baked as a one-frame clip: the anchor and prior
/// of bone-frame models.
pub fn bake_rest(
    rig: &dyn Rig,
    layout: &PoseLayout,
    settings: &BakeSettings,
    reporter: &dyn Reporter,
) -> Result<BakedClip> {
    Ok(bake_clip(
        rig,
        layout,
        "rest pose",
        vec![rig.rest_pose()],
        settings,
        reporter,
    )?
    .0)
}

/// Every pose of a clip skinned.
pub fn pose_all(rig: &dyn Rig, name: &str, poses: &[Vec<f64>]) -> Result<Vec<Mesh>> {
    poses
        .iter()
        .map(|p| rig.pose(p))
        .collect::<Result<Vec<_>, _>>()
        .with_context(|| format!("posing clip {name}"))
}

impl BakedClip {
    /// A clip whose meshes were baked elsewhere (for example through a checkpoint).
    pub fn new(
        rig: &dyn Rig,
        layout: &PoseLayout,
        name: &str,
        poses: Vec<Vec<f64>>,
        meshes: Vec<Mesh>,
        transfer: Vec<Vec<f32>>,
    ) -> Result<BakedClip> {
        let rotations = all_rotations(rig, &poses)?;
        let joints = poses
            .iter()
            .map(|p| rig.joint_matrices(p))
            .collect::<Result<_, _>>()?;
        Ok(BakedClip {
            name: name.to_owned(),
            parts: vec![(name.to_owned(), poses.len())],
            angles: poses.iter().map(|p| layout.reduce(p)).collect(),
            poses,
            meshes,
            transfer,
            rotations,
            joints,
        })
    }

    /// This clip with every vertex's transfer cut to SH order `order` (a bake of a higher
    /// order holds the lower one exactly: the coefficients are independent projections).
    pub fn truncated(&self, order: usize) -> BakedClip {
        let m2 = order * order;
        let v = self.meshes.first().map_or(0, Mesh::vertex_count).max(1);
        BakedClip {
            name: self.name.clone(),
            poses: self.poses.clone(),
            angles: self.angles.clone(),
            meshes: self.meshes.clone(),
            transfer: self
                .transfer
                .iter()
                .map(|t| {
                    let n2 = t.len() / v;
                    t.chunks_exact(n2.max(1))
                        .flat_map(|c| &c[..m2.min(c.len())])
                        .copied()
                        .collect()
                })
                .collect(),
            rotations: self.rotations.clone(),
            joints: self.joints.clone(),
            parts: self.parts.clone(),
        }
    }

    /// The clips one after the other, as one training set named by their names joined with
    /// `+`, their parts kept.
    pub fn concat(clips: Vec<BakedClip>) -> BakedClip {
        let name = clips
            .iter()
            .map(|c| c.name.as_str())
            .collect::<Vec<_>>()
            .join(" + ");
        let mut all = BakedClip {
            name,
            poses: Vec::new(),
            angles: Vec::new(),
            meshes: Vec::new(),
            transfer: Vec::new(),
            rotations: Vec::new(),
            joints: Vec::new(),
            parts: Vec::new(),
        };
        for c in clips {
            all.poses.extend(c.poses);
            all.angles.extend(c.angles);
            all.meshes.extend(c.meshes);
            all.transfer.extend(c.transfer);
            all.rotations.extend(c.rotations);
            all.joints.extend(c.joints);
            all.parts.extend(c.parts);
        }
        all
    }

    /// The posed geometry of every frame, for models with occluder proxies.
    pub fn geometry(&self) -> Geometry<'_> {
        Geometry {
            joints: &self.joints,
            meshes: &self.meshes,
        }
    }

    /// Frame `f`'s bone rotations as aprt-core takes them (row-major f32).
    pub fn core_rotations(&self, f: usize) -> Vec<[[f32; 3]; 3]> {
        self.rotations[f].iter().map(|r| row_major(*r)).collect()
    }
}
