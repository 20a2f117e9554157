//! Per-frame evaluation: pose vector → pose projection → per-coefficient weights → per-vertex
//! shading (lighting pushed through the basis) or per-vertex transfer.
//!
//! A frame is three steps, each with caller-owned state:
//! 1. `set_pose`: `z = P(φ(b(a)) − μ)` with the pose bound `b` and the pose features `φ`,
//!    then `w^c = W^c z'` with `z' = [1, z]` (O(n² k_a k_v), reads only the small sections).
//! 2. `light`: push an SH lighting vector `L` through the weights, `s_k = Σ_c L_c w^c_k`
//!    (O(n² k_v), no blob access), rotated into each bone's frame first for bone-frame models.
//! 3. `shade` streams the vertex rows: `shade_j = Σ_k s_k U_jk` (O(k_v) per vertex); or
//!    `transfer` gives the n² transfer values per vertex for a GPU (O(n² k_v)).
//!
//! With the identity basis (the full linear model) the rows are the per-vertex weights and the
//! same steps cost O(n² k_a) per vertex, as in the paper. The steps are written once here,
//! over [`Reader`], for the resident and the streamed model alike.
//!
//! Beside them, `rig.rs` shades under an irradiance rig's lighting at each vertex's position,
//! and `analytic.rs` under lights evaluated per vertex (*Irradiance Rigs*), both through the
//! same transfer.

mod analytic;
mod bounds;
mod device;
mod features;
pub(crate) mod kernels;
pub use device::{ProxyView, VertexRows};
pub use kernels::use_portable_kernels;
mod occlude;
mod rig;
mod weights;

#[cfg(target_arch = "x86_64")]
pub(crate) use kernels::Avx2;
use kernels::{
    BlockLayout, IdentityWeights, RowRef, bone_lanes, dot, shade_blocks, transfer_identity,
    transfer_stored,
};
pub(crate) use rig::check_positions;
use weights::check_capacity;
pub use weights::{LitWeights, MAX_POSE_WEIGHTS, PoseWeights};
pub(crate) use weights::{Stamp, check_stamp};

use crate::blob::format::{Basis, Encoding, Frame, MAX_COEF_DIMS, MAX_POSE_LEN, VERTEX_BLOCK};
use crate::blob::{Error, Input, ModelInfo, Reader, Span};
use crate::rotation::{Rotation, ShRotation, is_rotation};
use crate::sh::MAX_COEFFS;

/// The index of the first NaN or infinite value, if any.
pub(crate) fn first_non_finite(xs: &[f32]) -> Option<usize> {
    match all_finite(xs) {
        true => None,
        false => xs.iter().position(|x| !x.is_finite()),
    }
}

/// `Ok` when every value of a call's output is finite; else the output is zeroed (nothing
/// non-finite reaches the caller) and [`Error::Overflow`] says why: a blob may hold values,
/// and a caller may pass inputs, whose sums exceed f32 however each was checked.
pub(crate) fn finite_output(out: &mut [f32]) -> Result<(), Error> {
    if all_finite(out) {
        return Ok(());
    }
    out.fill(0.0);
    Err(Error::Overflow)
}

/// Whether every value is finite: no value has every exponent bit set, found with integer
/// masks, adds and ors over eight independent lanes (a full exponent carries into the sign
/// bit), which vectorise on every target, SSE2 included; a search stopping at the first
/// non-finite value runs one value at a time (per-vertex inputs are scanned every frame).
pub(crate) fn all_finite(xs: &[f32]) -> bool {
    const EXPONENT: u32 = 0x7f80_0000;
    let carry = |x: &f32| (x.to_bits() & EXPONENT) + 0x0080_0000;
    let (chunks, tail) = xs.as_chunks::<8>();
    let mut seen = [0u32; 8];
    for chunk in chunks {
        for (s, x) in seen.iter_mut().zip(chunk) {
            *s |= carry(x);
        }
    }
    let tail = tail.iter().fold(0, |all, x| all | carry(x));
    seen.iter().fold(tail, |all, s| all | s) & 0x8000_0000 == 0
}

impl ModelInfo {
    /// Streams a section as rows of `width` values: `f(row index, row)`.
    fn each_row<R: Reader>(
        &self,
        r: &mut R,
        s: Span,
        width: usize,
        mut f: impl FnMut(usize, RowRef<'_>),
    ) -> Result<(), Error> {
        let size = s.encoding.size();
        let rows = (s.len as usize).checked_div(width * size).unwrap_or(0);
        r.chunks(s.offset, width * size, rows, |first, bytes| {
            match s.encoding {
                Encoding::F32 => bytes
                    .as_chunks::<4>()
                    .0
                    .chunks_exact(width)
                    .enumerate()
                    .for_each(|(i, r)| f(first + i, RowRef::F32(r))),
                Encoding::F16 => bytes
                    .as_chunks::<2>()
                    .0
                    .chunks_exact(width)
                    .enumerate()
                    .for_each(|(i, r)| f(first + i, RowRef::F16(r))),
                Encoding::I8 => bytes
                    .chunks_exact(width)
                    .enumerate()
                    .for_each(|(i, r)| f(first + i, RowRef::I8(r))),
            }
            Ok(())
        })
    }

    pub(crate) fn set_pose<R: Reader, const N: usize>(
        &self,
        r: &mut R,
        angles: &[f32],
        pose: &mut PoseWeights<N>,
    ) -> Result<(), Error> {
        pose.stamp = None;
        if angles.len() != self.pose_len {
            return Err(Error::WrongLength {
                what: Input::Angles,
                expected: self.pose_len,
                found: angles.len(),
            });
        }
        if let Some(index) = first_non_finite(angles) {
            return Err(Error::NonFiniteAngle { index });
        }
        check_capacity(self.pose_weights_len(), N)?;
        let (a, f, ka, kv) = (
            self.pose_len,
            self.feature_len,
            self.pose_dims,
            self.coef_dims,
        );
        let mut mean = [0.0f32; MAX_POSE_LEN];
        let mean = &mut mean[..f];
        // The mean row decoded (added to zeros), then centred in f64 by `dot_centred`.
        self.each_row(r, self.pose_mean, f, |_, mu| {
            mu.add_scaled(1.0, mean.iter_mut())
        })?;
        // The bounded angles are the features' first `a` values; the cosines follow them.
        let mut features = [0.0f32; MAX_POSE_LEN];
        let features = &mut features[..f];
        self.bound_pose(r, angles, &mut features[..a])?;
        self.add_cosines(r, features)?;
        let z = &mut pose.z[..=ka];
        z[0] = 1.0;
        self.each_row(r, self.pose_projection, f, |i, p| {
            z[1 + i] = p.dot_centred(features, mean) as f32
        })?;
        if let (Basis::Stored, Some(weights)) = (self.basis, self.weights) {
            let n2 = self.coeffs();
            let w = &mut pose.w[..n2 * kv];
            w.fill(0.0);
            let z = &pose.z;
            // Row (c, i) of W holds W[c][i][0..k_v]. Coefficient c's rows come together, so
            // their sum `Σ_i z'_i W[c][i][k]` builds up contiguous in `sum` (vector adds), and
            // only the finished sums are written to w[k][c], a stride of n² apart.
            let mut sum = [0.0f32; MAX_COEF_DIMS];
            let sum = &mut sum[..kv];
            self.each_row(r, weights, kv, |ci, row| {
                let (c, i) = (ci / (ka + 1), ci % (ka + 1));
                if i == 0 {
                    sum.fill(0.0);
                }
                row.add_scaled(z[i], sum.iter_mut());
                if i == ka {
                    w[c..]
                        .iter_mut()
                        .step_by(n2)
                        .zip(&*sum)
                        .for_each(|(w, s)| *w = *s);
                }
            })?;
        }
        self.fold_row_scales(r, pose)?;
        finite_output(&mut pose.z[..=ka])?;
        finite_output(&mut pose.w[..self.pose_weights_len()])?;
        pose.pose_dims = ka;
        pose.stamp = Some(self.id);
        Ok(())
    }

    /// Folds the scales of scaled-byte rows into the pose weights: row r's stored values are
    /// `scale_r · q`, so the weight that multiplies row r takes the scale once per frame and
    /// the per-vertex loops read the bytes as they are. A stored basis scales `w_k^c` (shading
    /// and transfer both go through it); an identity basis writes `z'_i scale_r` per row.
    fn fold_row_scales<R: Reader, const N: usize>(
        &self,
        r: &mut R,
        pose: &mut PoseWeights<N>,
    ) -> Result<(), Error> {
        let Some(scales) = self.row_scales else {
            return Ok(());
        };
        let (n2, basis) = (self.coeffs(), self.basis);
        let (z, w) = (&pose.z[..=self.pose_dims], &mut pose.w);
        r.chunks(scales.offset, 4, self.row_width(), |first, bytes| {
            for (row, s) in (first..).zip(bytes.as_chunks::<4>().0) {
                let s = f32::from_le_bytes(*s);
                match basis {
                    Basis::Stored => w[row * n2..][..n2].iter_mut().for_each(|x| *x *= s),
                    Basis::Identity => w[row] = z[row % z.len()] * s,
                }
            }
            Ok(())
        })
    }

    /// The weights of an identity basis's rows for this pose (see [`IdentityWeights`]).
    fn identity_weights<'p, const P: usize>(
        &self,
        pose: &'p PoseWeights<P>,
    ) -> IdentityWeights<'p> {
        let len = 1 + self.pose_dims;
        match self.row_scales {
            Some(_) => IdentityWeights {
                values: &pose.w[..self.row_width()],
                stride: len,
                len,
            },
            None => IdentityWeights {
                values: &pose.z[..len],
                stride: 0,
                len,
            },
        }
    }

    pub(crate) fn light<const P: usize, const L: usize>(
        &self,
        pose: &PoseWeights<P>,
        lighting: &[f32],
        bones: &[Rotation],
        lit: &mut LitWeights<L>,
    ) -> Result<(), Error> {
        lit.stamp = None;
        self.check_lighting_inputs(pose, bones)?;
        self.check_sh_lighting(lighting)?;
        check_capacity(self.lit_weights_len(), L)?;
        self.check_rotations(bones)?;
        let q = &mut lit.q[..self.lit_weights_len()];
        self.light_checked(pose, lighting, bones, q);
        finite_output(q)?;
        lit.stamp = Some(self.id);
        Ok(())
    }

    /// Vertices a transfer output of `len` values holds: a whole number of n² rows.
    pub(crate) fn transfer_vertices(&self, len: usize) -> Result<usize, Error> {
        let n2 = self.coeffs();
        if !len.is_multiple_of(n2) {
            return Err(Error::WrongLength {
                what: Input::Transfer,
                expected: len / n2 * n2,
                found: len,
            });
        }
        Ok(len / n2)
    }

    /// SH lighting of this model: n² finite coefficients.
    pub(crate) fn check_sh_lighting(&self, lighting: &[f32]) -> Result<(), Error> {
        let n2 = self.coeffs();
        if lighting.len() != n2 {
            return Err(Error::WrongLength {
                what: Input::Lighting,
                expected: n2,
                found: lighting.len(),
            });
        }
        match first_non_finite(lighting) {
            Some(index) => Err(Error::NonFiniteLighting { index }),
            None => Ok(()),
        }
    }

    /// What every lighting call checks first: pose weights of this model, and one rotation
    /// per bone for a bone-frame model (checked by [`ModelInfo::check_rotations`]).
    fn check_lighting_inputs<const P: usize>(
        &self,
        pose: &PoseWeights<P>,
        bones: &[Rotation],
    ) -> Result<(), Error> {
        check_stamp(pose.stamp, self)?;
        if self.frame == Frame::World {
            return Ok(());
        }
        if bones.len() != self.bones() {
            return Err(Error::WrongLength {
                what: Input::BoneRotations,
                expected: self.bones(),
                found: bones.len(),
            });
        }
        Ok(())
    }

    /// Every bone rotation finite and a proper rotation (orthonormal within 10⁻³, not
    /// mirrored); a world-frame model ignores them.
    fn check_rotations(&self, bones: &[Rotation]) -> Result<(), Error> {
        if self.frame == Frame::World {
            return Ok(());
        }
        match bones
            .iter()
            .position(|r| !r.iter().flatten().all(|x| x.is_finite()) || !is_rotation(r, 1e-3))
        {
            Some(bone) => Err(Error::BadRotation { bone }),
            None => Ok(()),
        }
    }

    /// The lighting weights `q` ([`ModelInfo::lit_weights_len`] values) of world lighting
    /// `lighting` (n², finite), rotated into each bone's frame for bone-frame models; the
    /// inputs passed [`ModelInfo::check_lighting_inputs`].
    fn light_checked<const P: usize>(
        &self,
        pose: &PoseWeights<P>,
        lighting: &[f32],
        bones: &[Rotation],
        q: &mut [f32],
    ) {
        let (width, n2) = (self.row_width(), self.coeffs());
        if self.frame == Frame::World {
            self.push(pose, lighting, &mut q[..width]);
            return;
        }
        let rotation = ShRotation::of_order(self.order);
        let mut local = [0.0f32; MAX_COEFFS];
        for (r, q) in bones.iter().zip(q.chunks_exact_mut(width)) {
            // Bone-frame lighting is the world lighting rotated by Rᵀ.
            let rt = core::array::from_fn(|i| core::array::from_fn(|j| f64::from(r[j][i])));
            local[..n2].copy_from_slice(lighting);
            rotation.rotate(&rt, &mut local);
            self.push(pose, &local[..n2], q);
        }
    }

    /// `q` = the lighting pushed through the pose weights: `s_k = Σ_c L_c w^c_k` (stored
    /// basis) or `L_c z'_i` (identity basis, times the row's scale for scaled bytes).
    fn push<const P: usize>(&self, pose: &PoseWeights<P>, lighting: &[f32], q: &mut [f32]) {
        match self.basis {
            Basis::Stored => {
                for (qk, wk) in q.iter_mut().zip(pose.w.chunks_exact(lighting.len())) {
                    *qk = dot(wk, lighting);
                }
            }
            Basis::Identity => {
                let z = self.identity_weights(pose);
                for (c, (l, qc)) in lighting.iter().zip(q.chunks_exact_mut(z.len)).enumerate() {
                    for (qi, zi) in qc.iter_mut().zip(z.of(c)) {
                        *qi = l * zi;
                    }
                }
            }
        }
    }

    fn check_range(&self, first: usize, count: usize) -> Result<(), Error> {
        match first.checked_add(count) {
            Some(end) if end <= self.vertices => Ok(()),
            _ => Err(Error::VertexRange { first, count }),
        }
    }

    /// Where a block's bone lanes and rows are.
    fn block_layout(&self) -> BlockLayout {
        BlockLayout {
            bytes: self.block_bytes(),
            lead: self.lead_rows() * VERTEX_BLOCK * self.rows.encoding.size(),
            last_bone: self.bones().max(1) - 1,
        }
    }

    /// Streams the blocks holding vertices `first .. first + count` as runs of whole blocks:
    /// `visit(first vertex of the run, its bytes)`.
    fn each_run<R: Reader>(
        &self,
        r: &mut R,
        first: usize,
        count: usize,
        mut visit: impl FnMut(usize, &[u8]),
    ) -> Result<(), Error> {
        let block_bytes = self.block_bytes();
        let (b0, b1) = (first / VERTEX_BLOCK, (first + count).div_ceil(VERTEX_BLOCK));
        let offset = self.rows.offset + (b0 as u64) * block_bytes as u64;
        r.chunks(offset, block_bytes, b1 - b0, |i0, bytes| {
            visit((b0 + i0) * VERTEX_BLOCK, bytes);
            Ok(())
        })
    }

    /// Streams the blocks holding vertices `first .. first + count` to
    /// `visit(first vertex of the block, bone lanes, row bytes)`; the bone lanes are all 0 for
    /// world-frame models.
    fn each_block<R: Reader>(
        &self,
        r: &mut R,
        first: usize,
        count: usize,
        mut visit: impl FnMut(usize, [usize; VERTEX_BLOCK], &[u8]),
    ) -> Result<(), Error> {
        let layout = self.block_layout();
        let encoding = self.rows.encoding;
        self.each_run(r, first, count, |v0, bytes| {
            for (i, block) in bytes.chunks_exact(layout.bytes).enumerate() {
                let (lead, rows) = block.split_at(layout.lead);
                let bones = bone_lanes(encoding, lead, layout.last_bone);
                visit(v0 + i * VERTEX_BLOCK, bones, rows);
            }
        })
    }

    pub(crate) fn vertex_bones<R: Reader>(
        &self,
        r: &mut R,
        first: usize,
        out: &mut [u16],
    ) -> Result<(), Error> {
        self.check_range(first, out.len())?;
        let end = first + out.len();
        self.each_block(r, first, out.len(), |v0, bones, _| {
            for j in v0.max(first)..(v0 + VERTEX_BLOCK).min(end) {
                out[j - first] = bones[j - v0] as u16;
            }
        })
    }

    pub(crate) fn shade<R: Reader, const L: usize>(
        &self,
        r: &mut R,
        lit: &LitWeights<L>,
        first: usize,
        out: &mut [f32],
    ) -> Result<(), Error> {
        check_stamp(lit.stamp, self)?;
        self.check_range(first, out.len())?;
        let width = self.row_width();
        let q = &lit.q[..self.lit_weights_len()];
        let encoding = self.rows.encoding;
        let (end, layout) = (first + out.len(), self.block_layout());
        self.each_run(r, first, out.len(), |v0, bytes| {
            shade_blocks(encoding, bytes, layout, q, width, |i, lanes| {
                let v0 = v0 + i * VERTEX_BLOCK;
                let (lo, hi) = (v0.max(first), (v0 + VERTEX_BLOCK).min(end));
                let dst = &mut out[lo - first..hi - first];
                if let Ok(whole) = <&mut [f32; VERTEX_BLOCK]>::try_from(&mut *dst) {
                    *whole = lanes;
                } else {
                    dst.copy_from_slice(&lanes[lo - v0..hi - v0]);
                }
            })
        })?;
        finite_output(out)
    }

    /// The transfer of one streamed block's eight vertices into `t` (`8 n²` values,
    /// vertex-major), from the pose weights: what `transfer` and `shade_lights` both need.
    pub(crate) fn block_transfer<const P: usize>(
        &self,
        pose: &PoseWeights<P>,
        bytes: &[u8],
        t: &mut [f32],
    ) {
        let encoding = self.rows.encoding;
        match self.basis {
            Basis::Stored => {
                transfer_stored(encoding, bytes, &pose.w[..self.pose_weights_len()], t)
            }
            Basis::Identity => transfer_identity(encoding, bytes, self.identity_weights(pose), t),
        }
    }

    pub(crate) fn transfer<R: Reader, const P: usize>(
        &self,
        r: &mut R,
        pose: &PoseWeights<P>,
        first: usize,
        out: &mut [f32],
    ) -> Result<(), Error> {
        check_stamp(pose.stamp, self)?;
        let n2 = self.coeffs();
        let count = self.transfer_vertices(out.len())?;
        self.check_range(first, count)?;
        let end = first + count;
        let mut lanes = [0.0f32; VERTEX_BLOCK * MAX_COEFFS];
        self.each_block(r, first, count, |v0, _, bytes| {
            let t = &mut lanes[..VERTEX_BLOCK * n2];
            self.block_transfer(pose, bytes, t);
            let (lo, hi) = (v0.max(first), (v0 + VERTEX_BLOCK).min(end));
            out[(lo - first) * n2..(hi - first) * n2]
                .copy_from_slice(&t[(lo - v0) * n2..(hi - v0) * n2]);
        })?;
        finite_output(out)
    }
}
