//! The occluder proxies' correction of a frame's shading or transfer (see `proxies/`): each
//! vertex loses what the spheres of other parts block, `D_j`, computed from the vertex's
//! posed position and normal (the caller's skinned mesh, as for `shade_rig`).

use super::first_non_finite;
use super::rig::check_positions;
use crate::blob::{Error, Input, ModelInfo, Reader};
use crate::proxies::{ProxyFrame, unit, vertex_occlusion};
use crate::rotation::Rotation;
use crate::sh::MAX_COEFFS;

impl ModelInfo {
    /// Checks the per-vertex inputs of an occlusion call over `count` vertices from `first`.
    fn check_occlusion_inputs(
        &self,
        frame: &ProxyFrame,
        positions: &[[f32; 3]],
        normals: &[[f32; 3]],
        first: usize,
        count: usize,
    ) -> Result<(), Error> {
        self.check_proxy_frame(frame)?;
        check_positions(positions, count)?;
        if normals.len() != count {
            return Err(Error::WrongLength {
                what: Input::Normals,
                expected: count,
                found: normals.len(),
            });
        }
        if let Some(index) = normals.iter().position(|n| first_non_finite(n).is_some()) {
            return Err(Error::NonFiniteNormal { index });
        }
        self.check_range(first, count)
    }

    /// Visits every vertex of `first .. first + count` that some proxy may reach, with its
    /// index in the range and the mask of those proxies (its bone's, cut to its block's).
    fn each_reached_vertex<R: Reader>(
        &self,
        r: &mut R,
        frame: &ProxyFrame,
        (first, count): (usize, usize),
        positions: &[[f32; 3]],
        mut visit: impl FnMut(usize, usize, u64),
    ) -> Result<(), Error> {
        let end = first + count;
        self.each_block(r, first, count, |v0, bones, _| {
            let (lo, hi) = (v0.max(first), (v0 + bones.len()).min(end));
            let lanes = &bones[lo - v0..hi - v0];
            let block = frame.block_mask(lanes, &positions[lo - first..hi - first]);
            if block == 0 {
                return;
            }
            for j in lo..hi {
                let bone = bones[j - v0];
                let mask = frame.candidates.get(bone).copied().unwrap_or(0) & block;
                if mask != 0 {
                    visit(j - first, bone, mask);
                }
            }
        })
    }

    #[allow(clippy::too_many_arguments)]
    pub(crate) fn occlude<R: Reader>(
        &self,
        r: &mut R,
        frame: &ProxyFrame,
        lighting: &[f32],
        positions: &[[f32; 3]],
        normals: &[[f32; 3]],
        first: usize,
        out: &mut [f32],
    ) -> Result<(), Error> {
        let n2 = self.coeffs();
        if lighting.len() != n2 {
            return Err(Error::WrongLength {
                what: Input::Lighting,
                expected: n2,
                found: lighting.len(),
            });
        }
        if let Some(index) = first_non_finite(lighting) {
            return Err(Error::NonFiniteLighting { index });
        }
        self.check_occlusion_inputs(frame, positions, normals, first, out.len())?;
        let mut d = [0.0f32; MAX_COEFFS];
        let range = (first, out.len());
        self.each_reached_vertex(r, frame, range, positions, |i, _, mask| {
            let Some(normal) = unit(normals[i]) else {
                return;
            };
            let vertex = (positions[i], normal);
            if vertex_occlusion(frame, self.order, mask, vertex, None, &mut d) {
                out[i] -= d[..n2]
                    .iter()
                    .zip(lighting)
                    .map(|(d, l)| d * l)
                    .sum::<f32>();
            }
        })
    }

    #[allow(clippy::too_many_arguments)]
    pub(crate) fn occlude_transfer<R: Reader>(
        &self,
        r: &mut R,
        frame: &ProxyFrame,
        bones: &[Rotation],
        positions: &[[f32; 3]],
        normals: &[[f32; 3]],
        first: usize,
        out: &mut [f32],
    ) -> Result<(), Error> {
        let n2 = self.coeffs();
        if bones.len() != self.bones() {
            return Err(Error::WrongLength {
                what: Input::BoneRotations,
                expected: self.bones(),
                found: bones.len(),
            });
        }
        self.check_rotations(bones)?;
        if !out.len().is_multiple_of(n2) {
            return Err(Error::WrongLength {
                what: Input::Transfer,
                expected: out.len() / n2 * n2,
                found: out.len(),
            });
        }
        let count = out.len() / n2;
        self.check_occlusion_inputs(frame, positions, normals, first, count)?;
        let mut d = [0.0f32; MAX_COEFFS];
        self.each_reached_vertex(r, frame, (first, count), positions, |i, bone, mask| {
            let Some(normal) = unit(normals[i]) else {
                return;
            };
            let vertex = (positions[i], normal);
            if vertex_occlusion(frame, self.order, mask, vertex, bones.get(bone), &mut d) {
                for (t, d) in out[i * n2..(i + 1) * n2].iter_mut().zip(&d) {
                    *t -= d;
                }
            }
        })
    }
}
