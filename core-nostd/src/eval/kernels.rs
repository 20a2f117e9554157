//! The per-frame kernels: decoding stored values, and the inner loops of shading and
//! transfer over one block of [`VERTEX_BLOCK`] vertices. Written once for the three encodings.
//!
//! What vectorises (x86-64 SSE2 asm of `Model::shade_rig`, which inlines `shade_block` for
//! all three encodings: `mulps`/`addps` in the eight-lane loops, `cvtdq2ps` after
//! shift-based sign extension for i8, the f16 decode as `pand`/`pslld`/`mulps`): the
//! single-bone shading loop and both transfer kernels; the mixed-bone shading path is
//! per-lane scalar. Portable code only: the core stays `forbid(unsafe_code)`.
//!
//! Transfer, before → after these kernels: 83 → 51 µs a frame (median over the Fox's sweep,
//! `aprt report fixtures/scenes/fox.toml --stride 1`, the two builds run alternately, twice).
//! `cargo bench -p aprt-tests --bench eval` (11.5k vertices, order 6, PCA(8,22); ratios to a
//! memcpy of the same row bytes, medians of 15 interleaved rounds; 2 shared, noisy cores, so
//! absolute times moved up to 5x between runs) gave, in two separate runs, transfer f32 43.0x →
//! 34.3x, f16 124.8x → 84.6x, i8 362x → 157x a memcpy. Shading is the earlier two-set kernel:
//! four sets measured slower (28.5 → 35–40 µs a frame on the same sweep) and were reverted.

use crate::blob::format::{Encoding, MAX_COEF_DIMS, VERTEX_BLOCK};

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
/// share a bone (the common case), one lighting weight multiplies eight vertices at once, with
/// two accumulator sets to halve the dependency chain of the adds (four sets measured slower:
/// 35–40 µs against 28.5 µs a frame on the Fox's sweep, `aprt report fixtures/scenes/fox.toml
/// --stride 1`, the two builds run alternately). A block whose vertices straddle bones sums
/// each lane on its own.
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

/// Coefficients computed together by the transfer kernels: `GROUP × VERTEX_BLOCK` accumulators
/// (eight SSE2 registers) take one broadcast weight times one eight-lane row per step, so the
/// inner loop is register-resident multiply–adds with no load or store of the output.
const GROUP: usize = 4;

/// Stored basis, one block: `t[lane n² + c] = Σ_k w[k n² + c] U[k][lane]` (`w[k n² + c]` the
/// pose weights of basis vector k). The block's k_v rows are decoded once into a tile, since
/// each is used n² times; then [`GROUP`] coefficients at a time accumulate over k.
pub(crate) fn transfer_stored<E: Decode>(block: &[E], w: &[f32], t: &mut [f32]) {
    let n2 = t.len() / VERTEX_BLOCK;
    let mut tile = [[0.0f32; VERTEX_BLOCK]; MAX_COEF_DIMS];
    let rows = block.as_chunks::<VERTEX_BLOCK>().0;
    for (d, r) in tile.iter_mut().zip(rows) {
        *d = r.map(Decode::value);
    }
    let tile = &tile[..rows.len().min(MAX_COEF_DIMS)];
    let mut c = 0;
    while c + GROUP <= n2 {
        let acc = stored_group::<GROUP>(tile, w, n2, c);
        scatter(&acc, c, n2, t);
        c += GROUP;
    }
    for c in c..n2 {
        scatter(&stored_group::<1>(tile, w, n2, c), c, n2, t);
    }
}

/// Coefficients `c .. c + G` of a stored-basis block: `acc[g][lane] = Σ_k w[k n² + c + g]
/// tile[k][lane]`.
#[inline(always)]
fn stored_group<const G: usize>(
    tile: &[[f32; VERTEX_BLOCK]],
    w: &[f32],
    n2: usize,
    c: usize,
) -> [[f32; VERTEX_BLOCK]; G] {
    let mut acc = [[0.0f32; VERTEX_BLOCK]; G];
    for (u, wk) in tile.iter().zip(w.chunks_exact(n2)) {
        let Some(wc) = wk.get(c..c + G) else { break };
        for (a, x) in acc.iter_mut().zip(wc) {
            for l in 0..VERTEX_BLOCK {
                a[l] += x * u[l];
            }
        }
    }
    acc
}

/// Writes coefficients `c ..` of the eight lanes into the vertex-major `t` (`t[lane n² + c]`).
#[inline(always)]
fn scatter<const G: usize>(acc: &[[f32; VERTEX_BLOCK]; G], c: usize, n2: usize, t: &mut [f32]) {
    for (tl, l) in t.chunks_exact_mut(n2).zip(0..VERTEX_BLOCK) {
        for (x, a) in tl[c..].iter_mut().zip(acc) {
            *x = a[l];
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

/// Identity basis, one block: `t_lane,c = Σ_i z_c,i X[c (1 + k_a) + i][lane]`. Every value is
/// read once, so it is decoded in the loop; [`GROUP`] coefficients at a time keep that many
/// independent chains in flight (one coefficient's sum is only 1 + k_a long).
pub(crate) fn transfer_identity<E: Decode>(block: &[E], z: IdentityWeights<'_>, t: &mut [f32]) {
    let n2 = t.len() / VERTEX_BLOCK;
    let rows = block.as_chunks::<VERTEX_BLOCK>().0;
    let mut sets = rows.chunks_exact(z.len).take(n2);
    let mut c = 0;
    while c + GROUP <= n2 {
        let mut acc = [[0.0f32; VERTEX_BLOCK]; GROUP];
        for (g, a) in acc.iter_mut().enumerate() {
            if let Some(xc) = sets.next() {
                *a = identity_rows(xc, z.of(c + g));
            }
        }
        scatter(&acc, c, n2, t);
        c += GROUP;
    }
    for (c, xc) in (c..n2).zip(sets) {
        scatter(&[identity_rows(xc, z.of(c))], c, n2, t);
    }
}

/// `Σ_i z_i X_i[lane]` over one coefficient's rows, two chains interleaved.
#[inline(always)]
fn identity_rows<E: Decode>(xc: &[[E; VERTEX_BLOCK]], z: &[f32]) -> [f32; VERTEX_BLOCK] {
    let (pairs, rest) = xc.as_chunks::<2>();
    let (z_pairs, z_rest) = z.as_chunks::<2>();
    let (mut even, mut odd) = ([0.0f32; VERTEX_BLOCK], [0.0f32; VERTEX_BLOCK]);
    for ([x0, x1], [z0, z1]) in pairs.iter().zip(z_pairs) {
        for l in 0..VERTEX_BLOCK {
            even[l] += z0 * x0[l].value();
            odd[l] += z1 * x1[l].value();
        }
    }
    for (x, zi) in rest.iter().zip(z_rest) {
        for l in 0..VERTEX_BLOCK {
            even[l] += zi * x[l].value();
        }
    }
    core::array::from_fn(|l| even[l] + odd[l])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::blob::format::MAX_BONES;
    use crate::sh::MAX_COEFFS;

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

    /// Values of every block in the agreement tests: enough for k_v up to [`MAX_COEF_DIMS`]
    /// and identity rows up to 36 × 10.
    const N: usize = MAX_COEFFS * MAX_COEF_DIMS;

    fn sample(i: usize) -> f32 {
        ((i * 7919 % 211) as f32 - 105.0) / 64.0
    }

    /// The same values in each encoding: f32, f16, and scaled bytes (whose integers they are).
    fn encoded() -> ([f32; N], [[u8; 2]; N], [u8; N]) {
        (
            core::array::from_fn(sample),
            core::array::from_fn(|i| half::f16::from_f32(sample(i)).to_le_bytes()),
            core::array::from_fn(|i| (i * 37 % 255) as u8),
        )
    }

    /// Whether `got` is within f32 rounding of the f64 `want`: `tol` of the sum of the
    /// terms' magnitudes.
    fn close(got: f32, want: f64, magnitude: f64) -> bool {
        (f64::from(got) - want).abs() <= 1e-6 * magnitude + 1e-30
    }

    /// Shading checked against the plain scalar sum `Σ_r q[bone_l width + r] U[r][l]` in f64,
    /// for every width 0..=40 (every tail of the four-row loop) and k_v's limit, blocks of one
    /// bone and blocks straddling three.
    fn shade_agrees<E: Decode>(block: &[E]) {
        let q: [f32; 3 * MAX_COEF_DIMS] = core::array::from_fn(|i| sample(i + 5) * 0.5);
        for width in (0..=40).chain([MAX_COEF_DIMS]) {
            for bones in [[1; 8], [0, 0, 1, 1, 1, 2, 2, 2], [2, 0, 1, 0, 2, 1, 0, 2]] {
                let got = shade_block(&block[..8 * width], &q, width, bones);
                for (l, &b) in bones.iter().enumerate() {
                    let terms = (0..width)
                        .map(|r| f64::from(q[b * width + r]) * f64::from(block[r * 8 + l].value()));
                    let (want, magnitude) =
                        terms.fold((0.0, 0.0), |(s, m), x| (s + x, m + x.abs()));
                    assert!(close(got[l], want, magnitude), "width {width} lane {l}");
                }
            }
        }
    }

    /// Both transfer kernels checked against the plain scalar sums, every order's n² (whole
    /// and partial coefficient groups), k_v 1..=40 and its limit, 1 + k_a 1..=10 with and
    /// without per-row weights.
    fn transfer_agrees<E: Decode>(block: &[E]) {
        let w: [f32; N] = core::array::from_fn(|i| sample(i + 11) * 0.25);
        let mut t = [0.0f32; 8 * MAX_COEFFS];
        for n2 in [1, 4, 9, 16, 25, 36] {
            let t = &mut t[..8 * n2];
            for kv in (1..=40).chain([MAX_COEF_DIMS]) {
                transfer_stored(&block[..8 * kv], &w[..kv * n2], t);
                for (i, &got) in t.iter().enumerate() {
                    let (l, c) = (i / n2, i % n2);
                    let terms = (0..kv)
                        .map(|k| f64::from(w[k * n2 + c]) * f64::from(block[k * 8 + l].value()));
                    let (want, magnitude) =
                        terms.fold((0.0, 0.0), |(s, m), x| (s + x, m + x.abs()));
                    assert!(close(got, want, magnitude), "n² {n2} k_v {kv} [{l}][{c}]");
                }
            }
            for len in 1..=10 {
                for stride in [0, len] {
                    let z = IdentityWeights {
                        values: &w[..n2 * len],
                        stride,
                        len,
                    };
                    transfer_identity(&block[..8 * n2 * len], z, t);
                    for (i, &got) in t.iter().enumerate() {
                        let (l, c) = (i / n2, i % n2);
                        let terms = (0..len).map(|r| {
                            f64::from(z.of(c)[r]) * f64::from(block[(c * len + r) * 8 + l].value())
                        });
                        let (want, magnitude) =
                            terms.fold((0.0, 0.0), |(s, m), x| (s + x, m + x.abs()));
                        assert!(close(got, want, magnitude), "n² {n2} 1 + k_a {len}");
                    }
                }
            }
        }
    }

    #[test]
    fn kernels_agree_with_the_scalar_sums_in_every_encoding() {
        let (f32s, f16s, bytes) = encoded();
        shade_agrees(&f32s);
        shade_agrees(&f16s);
        shade_agrees(&bytes);
        transfer_agrees(&f32s);
        transfer_agrees(&f16s);
        transfer_agrees(&bytes);
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
