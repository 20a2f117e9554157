//! The occluder proxies' correction of a frame's shading or transfer (see `proxies/`): each
//! vertex loses what the spheres of other parts block, `D_j`, computed from the vertex's
//! posed position and normal (the caller's skinned mesh, as for `shade_rig`).

use super::rig::check_positions;
use super::{finite_output, first_non_finite};
use crate::blob::format::VERTEX_BLOCK;
use crate::blob::{Error, Input, ModelInfo, Reader};
use crate::proxies::{Block, Output, ProxyFrame, block_occlusion};
use crate::rotation::{IDENTITY, Rotation};
use crate::sh::MAX_COEFFS;

impl ModelInfo {
    /// One proper rotation per bone, whatever the frame (the occlusion's transfer is in the
    /// vertices' bone frames).
    pub(super) fn check_bone_rotations(&self, bones: &[Rotation]) -> Result<(), Error> {
        if bones.len() != self.bones() {
            return Err(Error::WrongLength {
                what: Input::BoneRotations,
                expected: self.bones(),
                found: bones.len(),
            });
        }
        self.check_rotations(bones)
    }

    /// Checks the per-vertex inputs of an occlusion call over `count` vertices from `first`.
    pub(super) fn check_occlusion_inputs(
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
        if let Some(i) = first_non_finite(normals.as_flattened()) {
            return Err(Error::NonFiniteNormal { index: i / 3 });
        }
        self.check_range(first, count)
    }

    /// Hands `visit` every block of `first .. first + count` that a proxy may reach, with its
    /// first vertex `v0` (lane `l` is vertex `v0 + l`; lanes outside the range take no proxy,
    /// so no proxy reaches them). A lane takes the proxies of its bone's mask, and in the
    /// bone's frame when `rotations` are given.
    fn each_receiving_block<'a, R: Reader>(
        &self,
        r: &mut R,
        frame: &ProxyFrame,
        (first, count): (usize, usize),
        (positions, normals): (&'a [[f32; 3]], &'a [[f32; 3]]),
        rotations: Option<&'a [Rotation]>,
        mut visit: impl FnMut(usize, &Block),
    ) -> Result<(), Error> {
        let end = first + count;
        self.each_block(r, first, count, |v0, bones, _| {
            let lanes = v0.max(first) - v0..(v0 + VERTEX_BLOCK).min(end) - v0;
            // The lanes' proxies first: most blocks of a frame have none within reach of
            // their bones, and are done before their vertices are read.
            let mut masks = [0u64; VERTEX_BLOCK];
            for l in lanes.clone() {
                masks[l] = frame.candidates.get(bones[l]).copied().unwrap_or(0);
            }
            if masks.iter().all(|&m| m == 0) {
                return;
            }
            // Lanes outside the range have no proxies; their rotation is never read.
            let rotations = rotations.map(|r| bones.map(|b| r.get(b).unwrap_or(&IDENTITY)));
            // A whole block is read in place; one the range cuts is copied, zero-padded.
            let (mut p, mut n) = ([[0.0f32; 3]; VERTEX_BLOCK], [[0.0f32; 3]; VERTEX_BLOCK]);
            let whole = |xs: &'a [[f32; 3]]| xs.get(v0.checked_sub(first)?..)?.first_chunk();
            let (positions, normals) = match (whole(positions), whole(normals)) {
                (Some(p), Some(n)) => (p, n),
                _ => {
                    for l in lanes {
                        let i = v0 + l - first;
                        (p[l], n[l]) = (positions[i], normals[i]);
                    }
                    (&p, &n)
                }
            };
            let block = Block {
                masks,
                positions,
                normals,
                rotations,
            };
            visit(v0, &block);
        })
    }

    /// Visits every vertex of `first .. first + count` that some proxy reaches with its
    /// index in the range and its occlusion `D` (n² values; in its bone's frame when
    /// `rotations` are given). A vertex of zero normal sees no proxy.
    fn each_occlusion<R: Reader>(
        &self,
        r: &mut R,
        frame: &ProxyFrame,
        (first, count): (usize, usize),
        vertices: (&[[f32; 3]], &[[f32; 3]]),
        rotations: Option<&[Rotation]>,
        mut visit: impl FnMut(usize, &[f32]),
    ) -> Result<(), Error> {
        let n2 = self.coeffs();
        let mut d = [[0.0f32; MAX_COEFFS]; VERTEX_BLOCK];
        let range = (first, count);
        self.each_receiving_block(r, frame, range, vertices, rotations, |v0, block| {
            let reached = block_occlusion(frame, self.order, block, Output::Transfer(&mut d));
            for (l, d) in d
                .iter()
                .enumerate()
                .filter(|&(l, _)| reached & (1 << l) != 0)
            {
                visit(v0 + l - first, &d[..n2]);
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
        let mut shading = [0.0f32; VERTEX_BLOCK];
        self.each_receiving_block(r, frame, range, (positions, normals), None, |v0, block| {
            let output = Output::Shading {
                lighting,
                out: &mut shading,
            };
            let reached = block_occlusion(frame, self.order, block, output);
            for (l, s) in shading
                .iter()
                .enumerate()
                .filter(|&(l, _)| reached & (1 << l) != 0)
            {
                out[v0 + l - first] -= s;
            }
        })?;
        finite_output(out)
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
        self.check_bone_rotations(bones)?;
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
        )?;
        finite_output(&mut out[..count * n2])
    }
}
