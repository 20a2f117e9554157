//! Occluder proxies in the trainer: the section a model carries (spheres per bone, each bone's
//! bounds and the proxies it ignores), and their occlusion of a posed mesh's transfer,
//! computed by aprt-core's own code ([`aprt_core::ProxySet`]) so that the targets a model is
//! fitted to and what the runtime subtracts are the same numbers.
//!
//! A model with proxies is fitted to `baked + D(pose)`, the transfer the spheres would leave
//! if they were not there, and the runtime subtracts `D(pose)` again; at the training poses
//! the two cancel, and in a pose none of them shows, the spheres cast the shadow the model
//! could not learn (module doc of `aprt_core`'s proxies: the cap maths).

use anyhow::{Context, Result, bail};
use aprt_core::format::{PROXY_BONE_RECORD, PROXY_PRELUDE, PROXY_RECORD, proxies_len};
use aprt_core::{MAX_PROXIES, ProxyFrame, ProxySet, Skinning};
use glam::Mat4;

use crate::model::BoneFrames;
use crate::rig::mesh::Mesh;

/// One sphere of a proxies section.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    /// The bone that carries it.
    pub bone: u16,
    /// Its centre in the bind pose, model space.
    pub centre: [f32; 3],
    /// Its radius (> 0).
    pub radius: f32,
}

/// One bone's record: the sphere bounding its vertices in the bind pose, and the proxies
/// that never occlude them (its own and its neighbours').
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BoneBound {
    /// Centre of the bound, bind pose.
    pub centre: [f32; 3],
    /// Radius of the bound (0 for a bone without vertices).
    pub radius: f32,
    /// Bit i: proxy i does not occlude this bone's vertices.
    pub ignored: u64,
}

/// The proxies section of a model, before it is bytes.
#[derive(Clone, Debug, PartialEq)]
pub struct ProxySection {
    /// At most [`MAX_PROXIES`] spheres.
    pub spheres: Vec<Sphere>,
    /// One record per bone of the model.
    pub bones: Vec<BoneBound>,
    /// The smallest cap kept, in `sin²α` (0: every cap, however small).
    pub cull: f32,
}

impl ProxySection {
    /// The section's bytes, in aprt-core's layout (FORMAT.md, `Proxies`), validated by
    /// aprt-core.
    pub fn to_bytes(&self) -> Result<Vec<u8>> {
        let (p, b) = (self.spheres.len(), self.bones.len());
        if p == 0 || p > MAX_PROXIES {
            bail!("occluder proxies: {p} spheres, a model holds 1 to {MAX_PROXIES}");
        }
        let len = proxies_len(p, b).context("occluder proxies: section length overflows")?;
        let mut out = Vec::with_capacity(len as usize);
        let mut put = |x: &[u8]| out.extend_from_slice(x);
        put(&(p as u32).to_le_bytes());
        put(&(b as u32).to_le_bytes());
        put(&self.cull.to_le_bytes());
        put(&0u32.to_le_bytes());
        for s in &self.spheres {
            put(&u32::from(s.bone).to_le_bytes());
            s.centre.iter().for_each(|x| put(&x.to_le_bytes()));
            put(&s.radius.to_le_bytes());
        }
        for bone in &self.bones {
            bone.centre.iter().for_each(|x| put(&x.to_le_bytes()));
            put(&bone.radius.to_le_bytes());
            put(&bone.ignored.to_le_bytes());
        }
        debug_assert_eq!(
            out.len(),
            PROXY_PRELUDE + p * PROXY_RECORD + b * PROXY_BONE_RECORD
        );
        ProxySet::parse(&out, b).map_err(|e| anyhow::anyhow!("occluder proxies: {e}"))?;
        Ok(out)
    }
}

/// The 3 × 4 row-major skinning matrix aprt-core takes, from a joint matrix.
pub fn skinning_of(m: &Mat4) -> Skinning {
    let c = m.to_cols_array_2d();
    [
        c[0][0], c[1][0], c[2][0], c[3][0], c[0][1], c[1][1], c[2][1], c[3][1], c[0][2], c[1][2],
        c[2][2], c[3][2],
    ]
}

/// The occlusion `D` of every vertex of `posed` (posed by `joints`, the rig's joint
/// matrices), world frame, `v × n²` vertex-major: what the proxies of `section` block.
pub fn occlusion(
    section: &[u8],
    bones: &BoneFrames,
    joints: &[Mat4],
    posed: &Mesh,
    order: usize,
) -> Result<Vec<f32>> {
    let set = ProxySet::parse(section, bones.count)
        .map_err(|e| anyhow::anyhow!("occluder proxies: {e}"))?;
    let skinning: Vec<Skinning> = joints.iter().map(skinning_of).collect();
    let mut frame = ProxyFrame::new();
    set.pose(&skinning, &mut frame)
        .map_err(|e| anyhow::anyhow!("posing the occluder proxies: {e}"))?;
    let n2 = order * order;
    let mut out = vec![0.0f32; posed.vertex_count() * n2];
    for (j, d) in out.chunks_exact_mut(n2).enumerate() {
        let bone = usize::from(bones.vertex_bone[j]);
        let vertex = (posed.positions[j], posed.normals[j]);
        frame
            .occlusion(order, bone, vertex, None, d)
            .map_err(|e| anyhow::anyhow!("vertex {j}: {e}"))?;
    }
    Ok(out)
}
