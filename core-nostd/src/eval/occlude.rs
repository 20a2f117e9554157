//! The occluder proxies' correction of a frame's shading or transfer (see `proxies/`): each
//! vertex loses what the spheres of other parts block, `D_j`, computed from the vertex's
//! posed position and normal (the caller's skinned mesh, as for `shade_rig`).

use super::first_non_finite;
use super::rig::check_positions;
use crate::blob::format::VERTEX_BLOCK;
use crate::blob::{Error, Input, ModelInfo, Reader};
use crate::proxies::{ProxyFrame, block_occlusion};
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

    /// Visits every vertex of `first .. first + count` that some proxy reaches with its
    /// index in the range and its occlusion `D` (n² values; in its bone's frame when
    /// `rotations` are given). Proxies are first cut to the vertex's bone's and to its
    /// block's reach; a vertex of zero normal sees none.
    fn each_occlusion<R: Reader>(
        &self,
        r: &mut R,
        frame: &ProxyFrame,
        (first, count): (usize, usize),
        (positions, normals): (&[[f32; 3]], &[[f32; 3]]),
        rotations: Option<&[Rotation]>,
        mut visit: impl FnMut(usize, &[f32]),
    ) -> Result<(), Error> {
        let (end, n2) = (first + count, self.coeffs());
        let mut d = [[0.0f32; MAX_COEFFS]; VERTEX_BLOCK];
        self.each_block(r, first, count, |v0, bones, _| {
            let (lo, hi) = (v0.max(first), (v0 + bones.len()).min(end));
            let block =
                frame.block_mask(&bones[lo - v0..hi - v0], &positions[lo - first..hi - first]);
            if block == 0 {
                return;
            }
            // Lanes outside the range keep an empty mask.
            let (mut masks, mut vertices) = (
                [0u64; VERTEX_BLOCK],
                [([0.0f32; 3], [0.0f32; 3]); VERTEX_BLOCK],
            );
            let mut lane_rotations = [None; VERTEX_BLOCK];
            for j in lo..hi {
                let (l, i, bone) = (j - v0, j - first, bones[j - v0]);
                masks[l] = frame.candidates.get(bone).copied().unwrap_or(0) & block;
                vertices[l] = (positions[i], normals[i]);
                lane_rotations[l] = rotations.and_then(|r| r.get(bone));
            }
            if masks == [0; VERTEX_BLOCK] {
                return;
            }
            let reached =
                block_occlusion(frame, self.order, masks, vertices, lane_rotations, &mut d);
            for j in lo..hi {
                let l = j - v0;
                if reached & (1 << l) != 0 {
                    visit(j - first, &d[l][..n2]);
                }
            }
        })
    }

    /// Visits each vertex of `first .. first + positions.len()` some proxy reaches with its
    /// index in the range and its world-frame occlusion `D` (n² values): for lighting that
    /// varies per vertex (an irradiance rig, per-vertex lights), which the caller dots with `D`.
    pub(crate) fn occlusions<R: Reader>(
        &self,
        r: &mut R,
        frame: &ProxyFrame,
        (positions, normals): (&[[f32; 3]], &[[f32; 3]]),
        first: usize,
        visit: impl FnMut(usize, &[f32]),
    ) -> Result<(), Error> {
        let count = positions.len();
        self.check_occlusion_inputs(frame, positions, normals, first, count)?;
        self.each_occlusion(r, frame, (first, count), (positions, normals), None, visit)
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
        self.check_sh_lighting(lighting)?;
        self.check_occlusion_inputs(frame, positions, normals, first, out.len())?;
        let range = (first, out.len());
        self.each_occlusion(r, frame, range, (positions, normals), None, |i, d| {
            out[i] -= d.iter().zip(lighting).map(|(d, l)| d * l).sum::<f32>();
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
        let count = self.transfer_vertices(out.len())?;
        self.check_occlusion_inputs(frame, positions, normals, first, count)?;
        let range = (first, count);
        self.each_occlusion(
            r,
            frame,
            range,
            (positions, normals),
            Some(bones),
            |i, d| {
                for (t, d) in out[i * n2..(i + 1) * n2].iter_mut().zip(d) {
                    *t -= d;
                }
            },
        )
    }
}
