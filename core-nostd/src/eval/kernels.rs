//! The per-frame kernels: decoding stored values, and the inner loops of shading and
//! transfer over one block of [`VERTEX_BLOCK`] vertices. Written once for both encodings.

use crate::blob::format::{Encoding, VERTEX_BLOCK};

/// Little-endian element encodings, decoded in the hot loops.
pub(crate) trait Decode: Copy {
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

/// A scaled byte ([`Encoding::I8`](crate::Encoding::I8)): the integer, whose scale the caller
/// has folded into the weight that multiplies it.
impl Decode for u8 {
    #[inline(always)]
    fn value(self) -> f32 {
        f32::from(self as i8)
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
pub(crate) fn f16_to_f32(h: u16) -> f32 {
    const REBIAS: f32 = 5.192_297e33; // 2^112
    let bits = ((h as i16 as i32) << 13) as u32 & 0x8FFF_E000;
    f32::from_bits(bits) * REBIAS
}

/// A vertex's bone from its lead-row value, which the reader validated as an exact integer
/// below the bone count. Adding 2²³ moves such an integer into the low mantissa bits: two
/// vector operations, where `as usize` costs a dozen scalar ones per lane. The clamp keeps any
/// other value (bytes a source changed after it was opened) inside the lighting table.
#[inline(always)]
pub(crate) fn bone_lane(x: f32, last: usize) -> usize {
    (((x + 8_388_608.0).to_bits() & 0x7f_ffff) as usize).min(last)
}

/// Dot product with eight independent accumulators, the tail included, so neither the loop
/// nor the remainder forms a long dependency chain (rows are short: k_v is often ~20).
#[inline(always)]
pub(crate) fn dot<E: Decode>(row: &[E], q: &[f32]) -> f32 {
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
pub(crate) enum RowRef<'a> {
    F32(&'a [[u8; 4]]),
    F16(&'a [[u8; 2]]),
    /// Scaled bytes, unscaled: the caller applies the scale.
    I8(&'a [u8]),
}

impl RowRef<'_> {
    /// `out_k += s · row_k` over the shorter of the two; the encoding is matched once per row,
    /// not per value.
    pub(crate) fn add_scaled<'o>(self, s: f32, out: impl Iterator<Item = &'o mut f32>) {
        match self {
            RowRef::F32(r) => out.zip(r).for_each(|(o, x)| *o += s * x.value()),
            RowRef::F16(r) => out.zip(r).for_each(|(o, x)| *o += s * x.value()),
            RowRef::I8(r) => out.zip(r).for_each(|(o, x)| *o += s * x.value()),
        }
    }

    /// `Σ_k row_k (x_k − c_k)` in f64: the difference of two finite f32 values cannot
    /// overflow there (in f32, `f32::MAX − (−f32::MAX)` is infinite and a zero projection row
    /// then gives NaN), and the few multiply–adds of a pose projection cost nothing.
    pub(crate) fn dot_centred(self, x: &[f32], c: &[f32]) -> f64 {
        fn sum<E: Decode>(row: &[E], x: &[f32], c: &[f32]) -> f64 {
            row.iter()
                .zip(x.iter().zip(c))
                .map(|(r, (&x, &c))| f64::from(r.value()) * (f64::from(x) - f64::from(c)))
                .sum()
        }
        match self {
            RowRef::F32(r) => sum(r, x, c),
            RowRef::F16(r) => sum(r, x, c),
            RowRef::I8(r) => sum(r, x, c),
        }
    }
}

/// Shading of one block of `encoding` bytes (see [`shade_block`]).
#[inline(always)]
pub(crate) fn shade_bytes(
    encoding: Encoding,
    bytes: &[u8],
    q: &[f32],
    width: usize,
    bones: [usize; VERTEX_BLOCK],
) -> [f32; VERTEX_BLOCK] {
    match encoding {
        Encoding::F32 => shade_block(bytes.as_chunks::<4>().0, q, width, bones),
        Encoding::F16 => shade_block(bytes.as_chunks::<2>().0, q, width, bones),
        Encoding::I8 => shade_block(bytes, q, width, bones),
    }
}

/// The bone of each lane from a block's lead row of `encoding` bytes, each at most `last`.
#[inline(always)]
pub(crate) fn bone_lanes(encoding: Encoding, lead: &[u8], last: usize) -> [usize; VERTEX_BLOCK] {
    let mut bones = [0usize; VERTEX_BLOCK];
    match encoding {
        Encoding::F32 => lead
            .as_chunks::<4>()
            .0
            .iter()
            .zip(&mut bones)
            .for_each(|(x, b)| *b = bone_lane(x.value(), last)),
        Encoding::F16 => lead
            .as_chunks::<2>()
            .0
            .iter()
            .zip(&mut bones)
            .for_each(|(x, b)| *b = bone_lane(x.value(), last)),
        // Unsigned bytes: bone indices up to 255.
        Encoding::I8 => lead
            .iter()
            .zip(&mut bones)
            .for_each(|(&x, b)| *b = usize::from(x).min(last)),
    }
    bones
}

/// Shading of one block: `out_lane = Σ_r q[bone_lane][r] U[r][lane]`. When the eight vertices
/// share a bone (the common case), one lighting weight multiplies eight vertices at once,
/// with two accumulator sets to halve the dependency chain of the adds.
#[inline(always)]
pub(crate) fn shade_block<E: Decode>(
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
pub(crate) fn transfer_stored<E: Decode>(block: &[E], w: &[f32], t: &mut [f32]) {
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

/// The weights of an identity basis's rows: coefficient c's `1 + k_a` rows
/// `c (1 + k_a) + i` are multiplied by `of(c)[i]`, which is `z'_i` for every c, or `z'_i`
/// times the row's scale for scaled-byte rows.
#[derive(Clone, Copy)]
pub(crate) struct IdentityWeights<'a> {
    /// `z'`, or the `n² (1 + k_a)` scaled copies of it.
    pub(crate) values: &'a [f32],
    /// 0 when every coefficient shares `z'`, else `1 + k_a`.
    pub(crate) stride: usize,
    /// `1 + k_a`.
    pub(crate) len: usize,
}

impl<'a> IdentityWeights<'a> {
    /// The weights of coefficient c's rows.
    #[inline(always)]
    pub(crate) fn of(self, c: usize) -> &'a [f32] {
        &self.values[c * self.stride..][..self.len]
    }
}

/// Identity basis, one block: `t_lane,c = Σ_i z_c,i X[c (1 + k_a) + i][lane]`.
pub(crate) fn transfer_identity<E: Decode>(block: &[E], z: IdentityWeights<'_>, t: &mut [f32]) {
    let n2 = t.len() / VERTEX_BLOCK;
    let rows = block.as_chunks::<VERTEX_BLOCK>().0;
    for (c, xc) in rows.chunks_exact(z.len).enumerate().take(n2) {
        let mut acc = [0.0f32; VERTEX_BLOCK];
        for (x, zi) in xc.iter().zip(z.of(c)) {
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
    use crate::blob::format::MAX_BONES;

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
