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

use crate::bake::clip::BakedClip;
use crate::model::proxies::{ProxyFit, ProxyOptions, fit_proxies};
use crate::rig::Rig;
use crate::rig::bone_frames::BoneFrames;
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

/// The skinning matrices that pose the proxies of a model of `bones` bones: the first `bones`
/// of a pose's joint matrices. A model's bones end at the highest joint that weights a vertex
/// ([`Skin::joint_count`](crate::rig::skin::Skin::joint_count)); the joints past it, such as
/// the unweighted end joints many exports carry, move nothing the model sees.
pub fn bone_skinning(joints: &[Mat4], bones: usize) -> Result<Vec<Skinning>> {
    let Some(joints) = joints.get(..bones) else {
        bail!(
            "the model has {bones} bones, the character {} joints",
            joints.len()
        );
    };
    Ok(joints.iter().map(skinning_of).collect())
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
    let skinning = bone_skinning(joints, bones.count)?;
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

/// The section of a rig's fitted spheres: each bone's bound over the bind-pose vertices whose
/// bone it is, and the proxies it ignores (its own and its neighbours', which the learnt model
/// carries).
pub fn section_of(bind: &Mesh, bones: &BoneFrames, fit: &ProxyFit, cull: f32) -> ProxySection {
    let mut sum = vec![[0.0f64; 3]; bones.count];
    let mut count = vec![0usize; bones.count];
    for (p, &b) in bind.positions.iter().zip(&bones.vertex_bone) {
        let b = usize::from(b);
        for k in 0..3 {
            sum[b][k] += f64::from(p[k]);
        }
        count[b] += 1;
    }
    let centres: Vec<[f64; 3]> = sum
        .iter()
        .zip(&count)
        .map(|(s, &n)| s.map(|x| x / n.max(1) as f64))
        .collect();
    let mut radius = vec![0.0f64; bones.count];
    for (p, &b) in bind.positions.iter().zip(&bones.vertex_bone) {
        let b = usize::from(b);
        let d = (0..3)
            .map(|k| (f64::from(p[k]) - centres[b][k]).powi(2))
            .sum::<f64>();
        radius[b] = radius[b].max(d.sqrt());
    }
    let spheres: Vec<Sphere> = fit
        .proxies
        .iter()
        .map(|p| Sphere {
            bone: p.bone,
            centre: p.centre.map(|x| x as f32),
            radius: p.radius as f32,
        })
        .collect();
    let bones_out = (0..bones.count)
        .map(|b| {
            let near = |bone: u16| {
                usize::from(bone) == b || fit.neighbours.get(b).is_some_and(|n| n.contains(&bone))
            };
            let ignored = spheres
                .iter()
                .enumerate()
                .filter(|(_, s)| near(s.bone))
                .fold(0u64, |m, (i, _)| m | 1 << i);
            BoneBound {
                centre: centres[b].map(|x| x as f32),
                // Slack for vertices that other bones pull off their bone's rigid motion.
                radius: (radius[b] * 1.1) as f32,
                ignored,
            }
        })
        .collect();
    ProxySection {
        spheres,
        bones: bones_out,
        cull,
    }
}

/// Whether a fit uses occluder proxies (`--proxies`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Occluders {
    /// Fitted with and without them; the lower held-out error wins.
    #[default]
    Auto,
    /// Never: the model alone.
    None,
    /// Always, for bone-frame models of characters.
    On,
}

impl Occluders {
    /// The name of the command line and the reports.
    pub fn name(self) -> &'static str {
        match self {
            Occluders::Auto => "auto",
            Occluders::None => "none",
            Occluders::On => "on",
        }
    }
}

/// The smallest cap a fitted model's proxies keep, in `sin²α`: a sphere stops occluding a
/// vertex `√(1/0.1) ≈ 3.2` radii away, where it blocks 10 % of the cosine lobe's band 0,
/// fading in over the next 10 %; what lies beyond is the learnt model's, which sees it in
/// its targets. Measured on the demo's character in `wave` (`cargo bench -p aprt-tests
/// --bench proxies`, `APRT_CULL` to try others; 55 spheres before the brim had any): 0.02
/// costs 130× the shading, 0.1 16×, 0.2 6.8×; with the 64 that cover the brim, 0.1 costs
/// 18.6×.
pub const DEFAULT_CULL: f32 = 0.1;

/// What the proxies did in a fit's selection.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct OccluderChoice {
    /// Spheres fitted to the character.
    pub spheres: usize,
    /// Their volume error over the parts ([`ProxyFit::volume_error`]).
    pub volume_error: f64,
    /// The held-out error of the best model fitted with them.
    pub held_out_with: f64,
    /// The held-out error of the best model fitted without them (`None` under `--proxies on`).
    pub held_out_without: Option<f64>,
    /// Whether the model keeps them.
    pub used: bool,
}

/// The proxies of a rig's bind mesh and their section (culled below `cull`), for a
/// bone-frame model of `bones`; `None` when no part is large enough for a sphere.
pub fn rig_section(
    rig: &dyn Rig,
    bones: &BoneFrames,
    cull: f32,
) -> Result<Option<(Vec<u8>, ProxyFit)>> {
    let bind = rig.bind_mesh();
    let fit = fit_proxies(bind, bones, &ProxyOptions::default())
        .context("fitting occluder proxies to the bind mesh")?;
    if fit.proxies.is_empty() {
        return Ok(None);
    }
    let bytes = section_of(bind, bones, &fit, cull).to_bytes()?;
    Ok(Some((bytes, fit)))
}

/// Each frame's world-frame transfer plus what the proxies block in it: the targets of a
/// model with proxies, which the runtime's subtraction turns back into the transfer.
pub fn with_occlusion(
    section: &[u8],
    bones: &BoneFrames,
    clip: &BakedClip,
    order: usize,
) -> Result<Vec<Vec<f32>>> {
    clip.transfer
        .iter()
        .zip(clip.joints.iter().zip(&clip.meshes))
        .enumerate()
        .map(|(f, (t, (joints, mesh)))| {
            let d = occlusion(section, bones, joints, mesh, order)
                .with_context(|| format!("{}, frame {f}", clip.name))?;
            if d.len() != t.len() {
                bail!(
                    "{}, frame {f}: {} transfer values, the proxies give {}",
                    clip.name,
                    t.len(),
                    d.len()
                );
            }
            Ok(t.iter().zip(&d).map(|(t, d)| t + d).collect())
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::proxies::Proxy;

    /// Two bones of four vertices each, far apart, and a third bone touching the first.
    fn parts() -> (Mesh, BoneFrames) {
        let mut positions = Vec::new();
        for x in [0.0f32, 5.0, 1.0] {
            for k in 0..4 {
                positions.push([x + 0.1 * k as f32, 0.0, 0.0]);
            }
        }
        let mesh = Mesh::with_area_weighted_normals(positions, vec![[0, 1, 8]]);
        let bones = BoneFrames {
            count: 3,
            vertex_bone: vec![0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2, 2],
        };
        (mesh, bones)
    }

    #[test]
    fn a_bone_ignores_its_own_and_its_neighbours_spheres_and_bounds_its_vertices() {
        let (mesh, bones) = parts();
        let sphere = |bone: u16, x: f64| Proxy {
            bone,
            centre: [x, 0.0, 0.0],
            radius: 0.2,
        };
        let fit = ProxyFit {
            proxies: vec![sphere(0, 0.15), sphere(1, 5.15), sphere(2, 1.15)],
            neighbours: vec![vec![2], vec![], vec![0]],
            bones: Vec::new(),
            volume_error: 0.0,
            uncovered: 0.0,
            covered: 1.0,
        };
        let section = section_of(&mesh, &bones, &fit, DEFAULT_CULL);
        assert_eq!(section.bones[0].ignored, 0b101);
        assert_eq!(section.bones[1].ignored, 0b010);
        assert_eq!(section.bones[2].ignored, 0b101);
        for (j, p) in mesh.positions.iter().enumerate() {
            let b = &section.bones[usize::from(bones.vertex_bone[j])];
            let d = (0..3)
                .map(|k| (p[k] - b.centre[k]).powi(2))
                .sum::<f32>()
                .sqrt();
            assert!(d <= b.radius, "vertex {j} outside its bone's bound");
        }
        // The bytes read back through aprt-core.
        let bytes = section.to_bytes().unwrap();
        assert!(ProxySet::parse(&bytes, 3).is_ok());
        assert!(ProxySet::parse(&bytes, 2).is_err());
    }

    #[test]
    fn occlusion_of_a_posed_mesh_moves_with_the_joints() {
        let (mesh, bones) = parts();
        let section = ProxySection {
            spheres: vec![Sphere {
                bone: 1,
                centre: [0.15, 0.0, 0.5],
                radius: 0.2,
            }],
            bones: vec![BoneBound::default(); 3],
            cull: DEFAULT_CULL,
        }
        .to_bytes()
        .unwrap();
        let still = vec![Mat4::IDENTITY; 3];
        let d = occlusion(&section, &bones, &still, &mesh, 3).unwrap();
        // Bone 0's vertices lie under the sphere: occluded; bone 1's are 5 m away: not.
        assert!(d[..4 * 9].iter().any(|&x| x != 0.0));
        assert!(d[4 * 9..8 * 9].iter().all(|&x| x == 0.0));
        // Bone 1 lifts its sphere 100 m: nothing left to occlude.
        let mut lifted = still.clone();
        lifted[1] = Mat4::from_translation(glam::Vec3::new(0.0, 0.0, 100.0));
        let d = occlusion(&section, &bones, &lifted, &mesh, 3).unwrap();
        assert!(d.iter().all(|&x| x == 0.0));
    }
}
