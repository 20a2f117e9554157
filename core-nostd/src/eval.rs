//! Per-frame evaluation: joint angles → pose projection → per-coefficient weights → per-vertex
//! shading (lighting pushed through the basis) or per-vertex transfer.
//!
//! A frame is three steps, each with caller-owned state:
//! 1. [`Model::set_pose`]: `z = P(a − μ)`, then `w^c = W^c z'` with `z' = [1, z]`
//!    (O(n² k_a k_v), reads only the small sections).
//! 2. [`Model::light`]: push an SH lighting vector `L` through the weights:
//!    `s_k = Σ_c L_c w^c_k` (O(n² k_v), no blob access).
//! 3. [`Model::shade`] streams the vertex rows: `shade_j = Σ_k s_k U_jk` (O(k_v) per vertex);
//!    or [`Model::transfer`] gives the n² transfer values per vertex for a GPU (O(n² k_v)).
//!
//! With the identity basis (the full linear model) the rows are the per-vertex weights and the
//! same steps cost O(n² k_a) per vertex, as in the paper.

use crate::blob::for_each_chunk;
use crate::blob::{
    Basis, BlobSource, Encoding, Error, Frame, MAX_COEF_DIMS, MAX_JOINTS, MAX_LIT, MAX_POSE_DIMS,
    Model, Section, VERTEX_BLOCK,
};
use crate::euler::EulerRotation;
use crate::rotate::is_rotation;
use crate::sh::{MAX_COEFFS, coeff_count};

/// Longest per-vertex row: k_v (stored basis) or n²(1 + k_a) (identity basis).
pub const MAX_ROW: usize = {
    let identity = MAX_COEFFS * (MAX_POSE_DIMS + 1);
    if identity > MAX_COEF_DIMS {
        identity
    } else {
        MAX_COEF_DIMS
    }
};

/// The model shape that pose and lighting weights were computed for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Shape {
    order: usize,
    pose_dims: usize,
    coef_dims: usize,
    basis: Basis,
    /// Bone count matters too: lighting weights hold one vector per bone.
    frame: Frame,
}

impl Shape {
    fn of(m: &Model) -> Shape {
        Shape {
            order: m.order,
            pose_dims: m.pose_dims,
            coef_dims: m.coef_dims,
            basis: m.basis,
            frame: m.frame,
        }
    }
}

/// Pose state of one frame (about 14 KiB): the projected pose and the per-coefficient weights.
#[derive(Clone, Debug)]
pub struct PoseWeights {
    shape: Option<Shape>,
    /// `z' = [1, z]`.
    z: [f32; MAX_POSE_DIMS + 1],
    /// Stored basis: `w[k * n² + c]`, coefficient-contiguous so transfer is a sum of vectors.
    w: [f32; MAX_COEFFS * MAX_COEF_DIMS],
}

impl Default for PoseWeights {
    fn default() -> Self {
        PoseWeights {
            shape: None,
            z: [0.0; MAX_POSE_DIMS + 1],
            w: [0.0; MAX_COEFFS * MAX_COEF_DIMS],
        }
    }
}

impl PoseWeights {
    /// The projected pose `z` (k_a values) of the last [`Model::set_pose`].
    pub fn projected(&self) -> &[f32] {
        let ka = self.shape.map_or(0, |s| s.pose_dims);
        &self.z[1..1 + ka]
    }
}

/// Lighting pushed through the pose weights (64 KiB): one weight per row value, per bone for
/// bone-frame models.
#[derive(Clone, Debug)]
pub struct LitWeights {
    shape: Option<Shape>,
    q: [f32; MAX_LIT],
}

impl Default for LitWeights {
    fn default() -> Self {
        LitWeights {
            shape: None,
            q: [0.0; MAX_LIT],
        }
    }
}

/// Little-endian element encodings, decoded in the hot loops.
trait Decode: Copy {
    fn value(self) -> f32;
}

impl Decode for [u8; 4] {
    #[inline(always)]
    fn value(self) -> f32 {
        f32::from_le_bytes(self)
    }
}

impl Decode for [u8; 2] {
    #[inline(always)]
    fn value(self) -> f32 {
        f16_to_f32(u16::from_le_bytes(self))
    }
}

impl Decode for f32 {
    #[inline(always)]
    fn value(self) -> f32 {
        self
    }
}

/// Branch-free binary16 → binary32 for finite values (the blob reader rejects the others):
/// sign-extending and shifting by 13 puts the sign in bit 31 and the exponent and mantissa
/// in place; the mask clears the copies of the sign between them, and multiplying by 2^112
/// rebiases the exponent and turns f16 subnormals into exact f32 normals. Four vector
/// operations per lane, which the shading loop pays per stored value.
#[inline(always)]
pub fn f16_to_f32(h: u16) -> f32 {
    const REBIAS: f32 = 5.192_297e33; // 2^112
    let bits = ((h as i16 as i32) << 13) as u32 & 0x8FFF_E000;
    f32::from_bits(bits) * REBIAS
}

/// A vertex's bone from its lead-row value, which the reader validated as an exact integer
/// below the bone count. Adding 2²³ moves such an integer into the low mantissa bits: two
/// vector operations, where `as usize` costs a dozen scalar ones per lane. The clamp keeps any
/// other value (bytes a source changed after it was opened) inside the lighting table.
#[inline(always)]
fn bone_lane(x: f32, last: usize) -> usize {
    (((x + 8_388_608.0).to_bits() & 0x7f_ffff) as usize).min(last)
}

/// Dot product with eight independent accumulators, the tail included, so neither the loop
/// nor the remainder forms a long dependency chain (rows are short: k_v is often ~20).
#[inline(always)]
fn dot<E: Decode>(row: &[E], q: &[f32]) -> f32 {
    let (rc, rt) = row.as_chunks::<8>();
    let (qc, qt) = q.as_chunks::<8>();
    let mut acc = [0.0f32; 8];
    for (r, q) in rc.iter().zip(qc) {
        for l in 0..8 {
            acc[l] += q[l] * r[l].value();
        }
    }
    for (a, (r, q)) in acc.iter_mut().zip(rt.iter().zip(qt)) {
        *a += q * r.value();
    }
    ((acc[0] + acc[4]) + (acc[1] + acc[5])) + ((acc[2] + acc[6]) + (acc[3] + acc[7]))
}

/// One decoded-on-demand row of a section.
#[derive(Clone, Copy)]
enum RowRef<'a> {
    F32(&'a [[u8; 4]]),
    F16(&'a [[u8; 2]]),
}

impl RowRef<'_> {
    /// `out_k += s · row_k` over the shorter of the two; the encoding is matched once per row,
    /// not per value.
    fn add_scaled<'o>(self, s: f32, out: impl Iterator<Item = &'o mut f32>) {
        match self {
            RowRef::F32(r) => out.zip(r).for_each(|(o, x)| *o += s * x.value()),
            RowRef::F16(r) => out.zip(r).for_each(|(o, x)| *o += s * x.value()),
        }
    }

    /// `Σ_k row_k (x_k − c_k)` in f64: the difference of two finite f32 values cannot
    /// overflow there (in f32, `f32::MAX − (−f32::MAX)` is infinite and a zero projection row
    /// then gives NaN), and the few multiply–adds of a pose projection cost nothing.
    fn dot_centred(self, x: &[f32], c: &[f32]) -> f64 {
        fn sum<E: Decode>(row: &[E], x: &[f32], c: &[f32]) -> f64 {
            row.iter()
                .zip(x.iter().zip(c))
                .map(|(r, (&x, &c))| f64::from(r.value()) * (f64::from(x) - f64::from(c)))
                .sum()
        }
        match self {
            RowRef::F32(r) => sum(r, x, c),
            RowRef::F16(r) => sum(r, x, c),
        }
    }
}

fn all_finite(xs: &[f32]) -> bool {
    xs.iter().all(|x| x.is_finite())
}

impl Model {
    /// Streams a section as rows of `width` values: `f(row index, row)`.
    fn each_row<S: BlobSource + ?Sized>(
        &self,
        src: &mut S,
        s: Section,
        width: usize,
        scratch: &mut [u8],
        mut f: impl FnMut(usize, RowRef<'_>),
    ) -> Result<(), Error> {
        let size = s.encoding.size();
        let rows = (s.len as usize).checked_div(width * size).unwrap_or(0);
        for_each_chunk(
            src,
            s.offset,
            width * size,
            rows,
            scratch,
            |first, bytes| {
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
                }
                Ok(())
            },
        )
    }

    /// Least `scratch` for evaluating from a streaming source: one vertex block, or one row of
    /// the small sections.
    pub fn scratch_bytes(&self) -> usize {
        let small = match self.basis {
            Basis::Stored => self.coef_dims * self.weights.map_or(4, |w| w.encoding.size()),
            Basis::Identity => 0,
        };
        self.block_bytes().max(self.joints * 4).max(small)
    }

    /// Computes the pose weights for joint angles `angles` (`joints()` values, radians as at
    /// training). `scratch` may be empty for a resident blob, else at least
    /// [`Model::scratch_bytes`].
    pub fn set_pose<S: BlobSource + ?Sized>(
        &self,
        src: &mut S,
        angles: &[f32],
        scratch: &mut [u8],
        pose: &mut PoseWeights,
    ) -> Result<(), Error> {
        if angles.len() != self.joints {
            return Err(Error::WrongLength {
                expected: self.joints,
                found: angles.len(),
            });
        }
        if !all_finite(angles) {
            return Err(Error::NonFiniteInput);
        }
        pose.shape = None;
        let (a, ka, kv) = (self.joints, self.pose_dims, self.coef_dims);
        let mut mean = [0.0f32; MAX_JOINTS];
        let mean = &mut mean[..a];
        // The mean row decoded (added to zeros), then centred in f64 by `dot_centred`.
        self.each_row(src, self.pose_mean, a, scratch, |_, mu| {
            mu.add_scaled(1.0, mean.iter_mut())
        })?;
        let z = &mut pose.z[..=ka];
        z[0] = 1.0;
        self.each_row(src, self.pose_projection, a, scratch, |i, p| {
            z[1 + i] = p.dot_centred(angles, mean) as f32
        })?;
        if let (Basis::Stored, Some(weights)) = (self.basis, self.weights) {
            let n2 = coeff_count(self.order);
            let w = &mut pose.w[..n2 * kv];
            w.fill(0.0);
            let z = &pose.z;
            // Row (c, i) of W holds W[c][i][0..k_v]; it adds z'_i W[c][i][k] to w[k][c].
            self.each_row(src, weights, kv, scratch, |ci, row| {
                let (c, zi) = (ci / (ka + 1), z[ci % (ka + 1)]);
                row.add_scaled(zi, w[c..].iter_mut().step_by(n2))
            })?;
        }
        pose.shape = Some(Shape::of(self));
        Ok(())
    }

    /// Pushes the world SH lighting vector `lighting` (n² values) through the pose weights,
    /// for world-frame models.
    pub fn light(
        &self,
        pose: &PoseWeights,
        lighting: &[f32],
        lit: &mut LitWeights,
    ) -> Result<(), Error> {
        if self.frame != Frame::World {
            return Err(Error::FrameMismatch);
        }
        self.check_lighting(pose, lighting)?;
        lit.shape = None;
        self.push(pose, lighting, &mut lit.q[..self.row_width()]);
        lit.shape = Some(Shape::of(self));
        Ok(())
    }

    /// For bone-frame models: rotates the world lighting into each bone's frame
    /// (`rotations[b]`, the bone's world rotation, row-major) by ZYZ Euler angles
    /// ([`EulerRotation`]: two quarter turns about x, tables computed at compile time) and
    /// pushes each through the pose weights.
    pub fn light_skinned(
        &self,
        pose: &PoseWeights,
        lighting: &[f32],
        rotations: &[[[f32; 3]; 3]],
        lit: &mut LitWeights,
    ) -> Result<(), Error> {
        let Frame::Bones { count } = self.frame else {
            return Err(Error::FrameMismatch);
        };
        if rotations.len() != count as usize {
            return Err(Error::WrongLength {
                expected: count as usize,
                found: rotations.len(),
            });
        }
        self.check_lighting(pose, lighting)?;
        lit.shape = None;
        let width = self.row_width();
        let mut local = [0.0f32; MAX_COEFFS];
        let euler = EulerRotation::new(self.order).map_err(|_| Error::ShapeMismatch)?;
        for (r, q) in rotations.iter().zip(lit.q.chunks_exact_mut(width)) {
            if !r.iter().flatten().all(|x| x.is_finite()) || !is_rotation(r, 1e-3) {
                return Err(Error::BadRotation);
            }
            // Bone-frame lighting is the world lighting rotated by Rᵀ.
            let rt = core::array::from_fn(|i| core::array::from_fn(|j| f64::from(r[j][i])));
            local[..lighting.len()].copy_from_slice(lighting);
            euler
                .apply(&rt, &mut local)
                .map_err(|_| Error::ShapeMismatch)?;
            self.push(pose, &local[..lighting.len()], q);
        }
        lit.shape = Some(Shape::of(self));
        Ok(())
    }

    fn check_lighting(&self, pose: &PoseWeights, lighting: &[f32]) -> Result<(), Error> {
        if pose.shape != Some(Shape::of(self)) {
            return Err(Error::ShapeMismatch);
        }
        let n2 = coeff_count(self.order);
        if lighting.len() != n2 {
            return Err(Error::WrongLength {
                expected: n2,
                found: lighting.len(),
            });
        }
        if !all_finite(lighting) {
            return Err(Error::NonFiniteInput);
        }
        Ok(())
    }

    /// `q` = the lighting pushed through the pose weights: `s_k = Σ_c L_c w^c_k` (stored
    /// basis) or `L_c z'_i` (identity basis).
    fn push(&self, pose: &PoseWeights, lighting: &[f32], q: &mut [f32]) {
        match self.basis {
            Basis::Stored => {
                for (qk, wk) in q.iter_mut().zip(pose.w.chunks_exact(lighting.len())) {
                    *qk = dot(wk, lighting);
                }
            }
            Basis::Identity => {
                let z = &pose.z[..=self.pose_dims];
                for (l, qc) in lighting.iter().zip(q.chunks_exact_mut(z.len())) {
                    for (qi, zi) in qc.iter_mut().zip(z) {
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

    /// Streams the blocks holding vertices `first .. first + count` to
    /// `visit(first vertex of the block, bone lanes, row bytes)`; the bone lanes are all 0 for
    /// world-frame models.
    fn each_block<S: BlobSource + ?Sized>(
        &self,
        src: &mut S,
        first: usize,
        count: usize,
        scratch: &mut [u8],
        mut visit: impl FnMut(usize, [usize; VERTEX_BLOCK], &[u8]),
    ) -> Result<(), Error> {
        let block_bytes = self.block_bytes();
        let encoding = self.rows.encoding;
        let lead_bytes = self.lead_rows() * VERTEX_BLOCK * encoding.size();
        let last_bone = self.bones() - 1;
        let (b0, b1) = (first / VERTEX_BLOCK, (first + count).div_ceil(VERTEX_BLOCK));
        let offset = self.rows.offset + (b0 as u64) * block_bytes as u64;
        for_each_chunk(src, offset, block_bytes, b1 - b0, scratch, |i0, bytes| {
            for (i, block) in bytes.chunks_exact(block_bytes).enumerate() {
                let (lead, rows) = block.split_at(lead_bytes);
                let mut bones = [0usize; VERTEX_BLOCK];
                match encoding {
                    Encoding::F32 => lead
                        .as_chunks::<4>()
                        .0
                        .iter()
                        .zip(&mut bones)
                        .for_each(|(x, b)| *b = bone_lane(x.value(), last_bone)),
                    Encoding::F16 => lead
                        .as_chunks::<2>()
                        .0
                        .iter()
                        .zip(&mut bones)
                        .for_each(|(x, b)| *b = bone_lane(x.value(), last_bone)),
                }
                visit((b0 + i0 + i) * VERTEX_BLOCK, bones, rows);
            }
            Ok(())
        })
    }

    /// Number of lighting frames: the bone count, or 1 for world-frame models.
    fn bones(&self) -> usize {
        match self.frame {
            Frame::World => 1,
            Frame::Bones { count } => count as usize,
        }
    }

    /// The bone of each vertex `first .. first + out.len()` (all 0 for world-frame models),
    /// for engines that light [`Model::transfer`] output on the GPU.
    pub fn vertex_bones<S: BlobSource + ?Sized>(
        &self,
        src: &mut S,
        first: usize,
        out: &mut [u16],
        scratch: &mut [u8],
    ) -> Result<(), Error> {
        self.check_range(first, out.len())?;
        let end = first + out.len();
        self.each_block(src, first, out.len(), scratch, |v0, bones, _| {
            for j in v0.max(first)..(v0 + VERTEX_BLOCK).min(end) {
                out[j - first] = bones[j - v0] as u16;
            }
        })
    }

    /// Per-vertex shading `Σ_c L_c t_c(j)` for vertices `first .. first + out.len()`, from
    /// lighting weights of [`Model::light`] or [`Model::light_skinned`]. Multiply by albedo / π
    /// for exit radiance.
    /// `scratch` may be empty for a resident blob, else at least [`Model::block_bytes`].
    pub fn shade<S: BlobSource + ?Sized>(
        &self,
        src: &mut S,
        lit: &LitWeights,
        first: usize,
        out: &mut [f32],
        scratch: &mut [u8],
    ) -> Result<(), Error> {
        if lit.shape != Some(Shape::of(self)) {
            return Err(Error::ShapeMismatch);
        }
        self.check_range(first, out.len())?;
        let width = self.row_width();
        let q = &lit.q[..width * self.bones()];
        let encoding = self.rows.encoding;
        let end = first + out.len();
        self.each_block(src, first, out.len(), scratch, |v0, bones, bytes| {
            let lanes = match encoding {
                Encoding::F32 => shade_block(bytes.as_chunks::<4>().0, q, width, bones),
                Encoding::F16 => shade_block(bytes.as_chunks::<2>().0, q, width, bones),
            };
            let (lo, hi) = (v0.max(first), (v0 + VERTEX_BLOCK).min(end));
            let dst = &mut out[lo - first..hi - first];
            if let Ok(whole) = <&mut [f32; VERTEX_BLOCK]>::try_from(&mut *dst) {
                *whole = lanes;
            } else {
                dst.copy_from_slice(&lanes[lo - v0..hi - v0]);
            }
        })
    }

    /// Per-vertex transfer vectors for vertices `first .. first + count`, written to `out`
    /// (`count · n²` values, vertex-major), for upload to a GPU that does the lighting dot
    /// product. Bone-frame models give transfer in each vertex's bone frame (see
    /// [`Model::vertex_bones`]): light it with that bone's rotated lighting.
    /// `scratch` as for [`Model::shade`].
    pub fn transfer<S: BlobSource + ?Sized>(
        &self,
        src: &mut S,
        pose: &PoseWeights,
        first: usize,
        out: &mut [f32],
        scratch: &mut [u8],
    ) -> Result<(), Error> {
        let shape = Shape::of(self);
        if pose.shape != Some(shape) {
            return Err(Error::ShapeMismatch);
        }
        let n2 = coeff_count(self.order);
        if !out.len().is_multiple_of(n2) {
            return Err(Error::WrongLength {
                expected: out.len() / n2 * n2,
                found: out.len(),
            });
        }
        let count = out.len() / n2;
        self.check_range(first, count)?;
        let encoding = self.rows.encoding;
        let (basis, kv, z) = (self.basis, self.coef_dims, &pose.z[..=self.pose_dims]);
        let w = &pose.w[..n2 * kv.min(MAX_COEF_DIMS)];
        let end = first + count;
        let mut lanes = [0.0f32; VERTEX_BLOCK * MAX_COEFFS];
        self.each_block(src, first, count, scratch, |v0, _, bytes| {
            let t = &mut lanes[..VERTEX_BLOCK * n2];
            match (basis, encoding) {
                (Basis::Stored, Encoding::F32) => transfer_stored(bytes.as_chunks::<4>().0, w, t),
                (Basis::Stored, Encoding::F16) => transfer_stored(bytes.as_chunks::<2>().0, w, t),
                (Basis::Identity, Encoding::F32) => {
                    transfer_identity(bytes.as_chunks::<4>().0, z, t)
                }
                (Basis::Identity, Encoding::F16) => {
                    transfer_identity(bytes.as_chunks::<2>().0, z, t)
                }
            }
            let (lo, hi) = (v0.max(first), (v0 + VERTEX_BLOCK).min(end));
            out[(lo - first) * n2..(hi - first) * n2]
                .copy_from_slice(&t[(lo - v0) * n2..(hi - v0) * n2]);
        })
    }
}

/// Shading of one block: `out_lane = Σ_r q[bone_lane][r] U[r][lane]`. When the eight vertices
/// share a bone (the common case), one lighting weight multiplies eight vertices at once,
/// with two accumulator sets to halve the dependency chain of the adds.
#[inline(always)]
fn shade_block<E: Decode>(
    block: &[E],
    q: &[f32],
    width: usize,
    bones: [usize; VERTEX_BLOCK],
) -> [f32; VERTEX_BLOCK] {
    let rows = block.as_chunks::<VERTEX_BLOCK>().0;
    if bones.iter().any(|&b| b != bones[0]) {
        return core::array::from_fn(|l| {
            let qb = &q[bones[l] * width..][..width];
            rows.iter().zip(qb).map(|(r, q)| q * r[l].value()).sum()
        });
    }
    let q = &q[bones[0] * width..][..width];
    let (pairs, rest) = rows.as_chunks::<2>();
    let (q_pairs, q_rest) = q.as_chunks::<2>();
    let (mut even, mut odd) = ([0.0f32; VERTEX_BLOCK], [0.0f32; VERTEX_BLOCK]);
    for ([r0, r1], [q0, q1]) in pairs.iter().zip(q_pairs) {
        for l in 0..VERTEX_BLOCK {
            even[l] += q0 * r0[l].value();
            odd[l] += q1 * r1[l].value();
        }
    }
    for (r, q) in rest.iter().zip(q_rest) {
        for l in 0..VERTEX_BLOCK {
            even[l] += q * r[l].value();
        }
    }
    core::array::from_fn(|l| even[l] + odd[l])
}

/// Stored basis, one block: `t_lane = Σ_k U[k][lane] w_k`, sums of n²-vectors (`w[k n² + c]`).
fn transfer_stored<E: Decode>(block: &[E], w: &[f32], t: &mut [f32]) {
    let n2 = t.len() / VERTEX_BLOCK;
    t.fill(0.0);
    for (u, wk) in block
        .as_chunks::<VERTEX_BLOCK>()
        .0
        .iter()
        .zip(w.chunks_exact(n2))
    {
        for (ul, tl) in u.iter().zip(t.chunks_exact_mut(n2)) {
            let ul = ul.value();
            for (tc, x) in tl.iter_mut().zip(wk) {
                *tc += ul * x;
            }
        }
    }
}

/// Identity basis, one block: `t_lane,c = Σ_i z'_i X[c (1 + k_a) + i][lane]`.
fn transfer_identity<E: Decode>(block: &[E], z: &[f32], t: &mut [f32]) {
    let n2 = t.len() / VERTEX_BLOCK;
    let rows = block.as_chunks::<VERTEX_BLOCK>().0;
    for (c, xc) in rows.chunks_exact(z.len()).enumerate().take(n2) {
        let mut acc = [0.0f32; VERTEX_BLOCK];
        for (x, zi) in xc.iter().zip(z) {
            for l in 0..VERTEX_BLOCK {
                acc[l] += zi * x[l].value();
            }
        }
        for (l, a) in acc.iter().enumerate() {
            t[l * n2 + c] = *a;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::blob::MAX_BONES;

    #[test]
    fn f16_decode_matches_half_for_every_finite_value() {
        for h in 0..=u16::MAX {
            let reference = half::f16::from_bits(h);
            if reference.is_finite() {
                assert_eq!(
                    f16_to_f32(h).to_bits(),
                    reference.to_f32().to_bits(),
                    "bits {h:#06x}"
                );
            }
        }
    }

    #[test]
    fn bone_lanes_decode_exactly() {
        for b in 0..=MAX_BONES {
            assert_eq!(bone_lane(b as f32, MAX_BONES), b);
            assert_eq!(
                bone_lane(
                    f16_to_f32(half::f16::from_f32(b as f32).to_bits()),
                    MAX_BONES
                ),
                b
            );
        }
    }

    #[test]
    fn dot_handles_every_tail_length() {
        for n in 0..40 {
            let a: [f32; 40] = core::array::from_fn(|i| i as f32 * 0.5 - 3.0);
            let b: [f32; 40] = core::array::from_fn(|i| 1.0 / (1.0 + i as f32));
            let expect: f64 = (0..n).map(|i| a[i] as f64 * b[i] as f64).sum();
            assert!(
                (dot(&a[..n], &b[..n]) as f64 - expect).abs() < 1e-5,
                "n = {n}"
            );
        }
    }
}
