//! The per-frame kernels: decoding stored values, and the inner loops of shading and
//! transfer over one block of [`VERTEX_BLOCK`] vertices, for the three encodings; and the
//! composition of SH light maps ([`compose`]), eight or sixteen texels at a time.
//!
//! Two kernel sets compute the same bits. `portable` is plain Rust that the compiler
//! vectorises for the target's own vectors (SSE2, NEON, `simd128`) and that runs as scalar code
//! where there are none; it is the reference. On x86-64, `x86` runs the same operations in the
//! same order in AVX2 registers (eight lanes, one block row per register), with F16C's
//! conversion for f16 and one sign-extending load for i8, where the CPU has them: found once at
//! run time, as engines ship one x86-64 build for every CPU. Same bits, so a frame is the same
//! on every machine and target, and the tests compare the sets exactly.
//!
//! Transfer, before → after the portable kernels: 83 → 51 µs a frame (median over the Fox's
//! sweep, `aprt report fixtures/scenes/fox.toml --stride 1`, the two builds run alternately,
//! twice).
//!
//! Light-map composition (`LightMap::compose` of a 512 × 512 map, 4096 texels a call, checks
//! included), one texel at a time → these kernels: 2380 → 819 µs at order 3 and 9039 → 3057 µs
//! at order 6 with AVX-512, where a memory copy of the map takes 692 and 2812 µs
//! (`cargo bench -p aprt-tests --bench lightmap`, one run, the steps interleaved). The scan
//! for non-finite values that must precede any write is most of what remains beyond the
//! copy: in another run, without it, the composition took 511 and 2250 µs.

mod portable;
#[cfg(target_arch = "x86_64")]
mod x86;
#[cfg(target_arch = "x86_64")]
pub(crate) use x86::Avx2;

use crate::blob::format::{Encoding, VERTEX_BLOCK};
pub(crate) use portable::texel;

/// Runs the portable kernels from now on (`true`), or lets the run-time dispatch choose the
/// CPU's widest again (`false`, the default). The two compute the same bits; this is for
/// measuring one against the other (`cargo bench -p aprt-tests --bench proxies`) and for an
/// engine that wants one code path on every machine. Process-wide; a no-op off x86-64.
pub fn use_portable_kernels(portable: bool) {
    #[cfg(target_arch = "x86_64")]
    x86::force_portable(portable);
    #[cfg(not(target_arch = "x86_64"))]
    let _ = portable;
}

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

/// Shading of one block of `encoding` bytes: `out_lane = Σ_r q[bone_lane width + r] U[r][lane]`
/// (see [`portable::shade_block`]).
#[inline(always)]
pub(crate) fn shade_bytes(
    encoding: Encoding,
    bytes: &[u8],
    q: &[f32],
    width: usize,
    bones: [usize; VERTEX_BLOCK],
) -> [f32; VERTEX_BLOCK] {
    #[cfg(target_arch = "x86_64")]
    if let Some(avx2) = x86::Avx2::get() {
        // Decided here, where the lanes are in registers: passed by value to the kernel they
        // are stored and reloaded as a vector, which stalled store forwarding on every block.
        return match bones.iter().all(|&b| b == bones[0]) {
            true => avx2.shade_one_bone(encoding, bytes, &q[bones[0] * width..][..width]),
            false => avx2.shade_mixed(encoding, bytes, q, width, bones),
        };
    }
    match encoding {
        Encoding::F32 => portable::shade_block(bytes.as_chunks::<4>().0, q, width, bones),
        Encoding::F16 => portable::shade_block(bytes.as_chunks::<2>().0, q, width, bones),
        Encoding::I8 => portable::shade_block(bytes, q, width, bones),
    }
}

/// Where the parts of each block are, in a run of whole blocks: `bytes` a block, the first
/// `lead` of them its bone lanes, each bone at most `last_bone`.
#[derive(Clone, Copy)]
pub(crate) struct BlockLayout {
    pub(crate) bytes: usize,
    pub(crate) lead: usize,
    pub(crate) last_bone: usize,
}

/// Shading of a run of whole blocks of `encoding` bytes: `visit(block index in the run,
/// lanes)` for each, the lanes as [`shade_bytes`] gives them. One call per run lets the AVX2
/// kernel shade several blocks at once (their sums interleaved, each in its own order).
#[inline(always)]
pub(crate) fn shade_blocks(
    encoding: Encoding,
    blocks: &[u8],
    layout: BlockLayout,
    q: &[f32],
    width: usize,
    mut visit: impl FnMut(usize, [f32; VERTEX_BLOCK]),
) {
    #[cfg(target_arch = "x86_64")]
    if let Some(avx2) = x86::Avx2::get() {
        return avx2.shade_blocks(encoding, blocks, layout, q, width, visit);
    }
    for (i, block) in blocks.chunks_exact(layout.bytes).enumerate() {
        let (lead, rows) = block.split_at(layout.lead);
        let bones = bone_lanes(encoding, lead, layout.last_bone);
        visit(i, shade_bytes(encoding, rows, q, width, bones));
    }
}

/// Stored-basis transfer of one block of `encoding` bytes into the vertex-major `t`
/// (`8 n²` values): `t[lane n² + c] = Σ_k w[k n² + c] U[k][lane]` (see
/// [`portable::transfer_stored`]).
#[inline(always)]
pub(crate) fn transfer_stored(encoding: Encoding, bytes: &[u8], w: &[f32], t: &mut [f32]) {
    #[cfg(target_arch = "x86_64")]
    if let Some(avx2) = x86::Avx2::get() {
        return avx2.transfer_stored(encoding, bytes, w, t);
    }
    match encoding {
        Encoding::F32 => portable::transfer_stored(bytes.as_chunks::<4>().0, w, t),
        Encoding::F16 => portable::transfer_stored(bytes.as_chunks::<2>().0, w, t),
        Encoding::I8 => portable::transfer_stored(bytes, w, t),
    }
}

/// Identity-basis transfer of one block of `encoding` bytes into the vertex-major `t`:
/// `t[lane n² + c] = Σ_i z_c,i X[c (1 + k_a) + i][lane]` (see [`portable::transfer_identity`]).
#[inline(always)]
pub(crate) fn transfer_identity(
    encoding: Encoding,
    bytes: &[u8],
    z: IdentityWeights<'_>,
    t: &mut [f32],
) {
    #[cfg(target_arch = "x86_64")]
    if let Some(avx2) = x86::Avx2::get() {
        return avx2.transfer_identity(encoding, bytes, z, t);
    }
    match encoding {
        Encoding::F32 => portable::transfer_identity(bytes.as_chunks::<4>().0, z, t),
        Encoding::F16 => portable::transfer_identity(bytes.as_chunks::<2>().0, z, t),
        Encoding::I8 => portable::transfer_identity(bytes, z, t),
    }
}

/// Texel-major SH light maps composed under one lighting: `out[t] = Σ_c lighting[c] ·
/// maps[t · n² + c]`, n² = `lighting.len()` (an order's n², 1..=36), each texel with the bits
/// of [`texel`] (see [`portable::compose`]). `maps` holds `out.len()` texels.
pub(crate) fn compose(maps: &[f32], lighting: &[[f32; 3]], out: &mut [[f32; 3]]) {
    match lighting.len() {
        1 => compose_n::<1>(maps, lighting, out),
        4 => compose_n::<4>(maps, lighting, out),
        9 => compose_n::<9>(maps, lighting, out),
        16 => compose_n::<16>(maps, lighting, out),
        25 => compose_n::<25>(maps, lighting, out),
        36 => compose_n::<36>(maps, lighting, out),
        n2 => {
            for (t, o) in maps.chunks_exact(n2.max(1)).zip(out) {
                *o = texel(t, lighting);
            }
        }
    }
}

/// [`compose`] for one n², whose blocks the compiler lays out at build time.
#[inline(always)]
fn compose_n<const N2: usize>(maps: &[f32], lighting: &[[f32; 3]], out: &mut [[f32; 3]]) {
    let Ok(l) = <&[[f32; 3]; N2]>::try_from(lighting) else {
        return;
    };
    #[cfg(target_arch = "x86_64")]
    if let Some(avx2) = x86::Avx2::get() {
        return avx2.compose(maps, l, out);
    }
    portable::compose(maps, l, out)
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::blob::format::{MAX_BONES, MAX_COEF_DIMS};
    use crate::sh::MAX_COEFFS;
    use crate::test_values::weight;

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

    /// The same values in each encoding as stored bytes: f32, f16, and scaled bytes (whose
    /// integers they are).
    fn encoded() -> ([[u8; 4]; N], [[u8; 2]; N], [u8; N]) {
        (
            core::array::from_fn(|i| sample(i).to_le_bytes()),
            core::array::from_fn(|i| half::f16::from_f32(sample(i)).to_le_bytes()),
            core::array::from_fn(|i| (i * 37 % 255) as u8),
        )
    }

    /// Whether `got` is within f32 rounding of the f64 `want`: `tol` of the sum of the
    /// terms' magnitudes.
    fn close(got: f32, want: f64, magnitude: f64) -> bool {
        (f64::from(got) - want).abs() <= 1e-6 * magnitude + 1e-30
    }

    /// Every width 0..=40 (every tail of the paired-row loop) and k_v's limit.
    fn widths() -> impl Iterator<Item = usize> {
        (0..=40).chain([MAX_COEF_DIMS])
    }

    /// Blocks of one bone, and blocks straddling three.
    const BONES: [[usize; 8]; 3] = [[1; 8], [0, 0, 1, 1, 1, 2, 2, 2], [2, 0, 1, 0, 2, 1, 0, 2]];

    /// Shading (whichever kernel set this CPU runs) checked against the plain sum
    /// `Σ_r q[bone_l width + r] U[r][l]` in f64. `block` holds the values of `bytes`.
    fn shade_agrees<E: Decode>(encoding: Encoding, bytes: &[u8], block: &[E]) {
        let q: [f32; 3 * MAX_COEF_DIMS] = core::array::from_fn(weight);
        for width in widths() {
            for bones in BONES {
                let rows = &bytes[..8 * width * encoding.size()];
                let got = shade_bytes(encoding, rows, &q, width, bones);
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

    /// Every order's n² (whole and partial coefficient groups).
    const COEFFS: [usize; 6] = [1, 4, 9, 16, 25, 36];

    /// Both transfer kernels checked against the plain sums, k_v 1..=40 and its limit,
    /// 1 + k_a 1..=10 with and without per-row weights.
    fn transfer_agrees<E: Decode>(encoding: Encoding, bytes: &[u8], block: &[E]) {
        let w: [f32; N] = core::array::from_fn(|i| weight(i + 11));
        let mut t = [0.0f32; 8 * MAX_COEFFS];
        let size = encoding.size();
        for n2 in COEFFS {
            let t = &mut t[..8 * n2];
            for kv in widths().skip(1) {
                transfer_stored(encoding, &bytes[..8 * kv * size], &w[..kv * n2], t);
                for (i, &got) in t.iter().enumerate() {
                    let (l, c) = (i / n2, i % n2);
                    let terms = (0..kv)
                        .map(|k| f64::from(w[k * n2 + c]) * f64::from(block[k * 8 + l].value()));
                    let (want, magnitude) =
                        terms.fold((0.0, 0.0), |(s, m), x| (s + x, m + x.abs()));
                    assert!(close(got, want, magnitude), "n² {n2} k_v {kv} [{l}][{c}]");
                }
            }
            for z in identity_weights(&w, n2) {
                transfer_identity(encoding, &bytes[..8 * n2 * z.len * size], z, t);
                for (i, &got) in t.iter().enumerate() {
                    let (l, c) = (i / n2, i % n2);
                    let terms = (0..z.len).map(|r| {
                        f64::from(z.of(c)[r]) * f64::from(block[(c * z.len + r) * 8 + l].value())
                    });
                    let (want, magnitude) =
                        terms.fold((0.0, 0.0), |(s, m), x| (s + x, m + x.abs()));
                    assert!(close(got, want, magnitude), "n² {n2} 1 + k_a {}", z.len);
                }
            }
        }
    }

    /// Identity weights for 1 + k_a = 1..=10, shared by every coefficient and per row.
    fn identity_weights(w: &[f32], n2: usize) -> impl Iterator<Item = IdentityWeights<'_>> {
        (1..=10).flat_map(move |len| {
            [0, len].map(|stride| IdentityWeights {
                values: &w[..n2 * len],
                stride,
                len,
            })
        })
    }

    #[test]
    fn kernels_agree_with_the_scalar_sums_in_every_encoding() {
        let (f32s, f16s, bytes) = encoded();
        shade_agrees(Encoding::F32, f32s.as_flattened(), &f32s);
        shade_agrees(Encoding::F16, f16s.as_flattened(), &f16s);
        shade_agrees(Encoding::I8, &bytes, &bytes);
        transfer_agrees(Encoding::F32, f32s.as_flattened(), &f32s);
        transfer_agrees(Encoding::F16, f16s.as_flattened(), &f16s);
        transfer_agrees(Encoding::I8, &bytes, &bytes);
    }

    /// The AVX2 and AVX-512 kernels against the portable ones, bit for bit, in every case the
    /// f64 check covers. (Where the CPU lacks AVX2 or F16C there is nothing to compare; the core
    /// has no standard output to say so on, and CI's machines have both.)
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn avx2_kernels_give_the_portable_bits() {
        let Some(avx2) = x86::Avx2::get() else {
            return;
        };
        let (f32s, f16s, bytes) = encoded();
        for set in [avx2, avx2.without_avx512()] {
            same_bits(set, Encoding::F32, f32s.as_flattened(), &f32s);
            same_bits(set, Encoding::F16, f16s.as_flattened(), &f16s);
            same_bits(set, Encoding::I8, &bytes, &bytes);
        }
    }

    #[cfg(target_arch = "x86_64")]
    fn same_bits<E: Decode>(avx2: x86::Avx2, encoding: Encoding, bytes: &[u8], block: &[E]) {
        // Every result fits one block's transfer: its length and bits, compared whole.
        let bits = |x: &[f32]| {
            let mut bits = [0u32; 8 * MAX_COEFFS];
            bits.iter_mut().zip(x).for_each(|(b, x)| *b = x.to_bits());
            (x.len(), bits)
        };
        let q: [f32; 3 * MAX_COEF_DIMS] = core::array::from_fn(weight);
        let size = encoding.size();
        for width in widths() {
            for bones in BONES {
                let (typed, raw) = (&block[..8 * width], &bytes[..8 * width * size]);
                let portable = portable::shade_block(typed, &q, width, bones);
                let wide = match bones == [1; 8] {
                    true => avx2.shade_one_bone(encoding, raw, &q[width..][..width]),
                    false => avx2.shade_mixed(encoding, raw, &q, width, bones),
                };
                assert_eq!(
                    bits(&portable),
                    bits(&wide),
                    "shade, width {width}, {bones:?}"
                );
            }
        }
        let w: [f32; N] = core::array::from_fn(|i| weight(i + 11));
        let (mut t, mut u) = ([0.0f32; 8 * MAX_COEFFS], [0.0f32; 8 * MAX_COEFFS]);
        for n2 in COEFFS {
            let (t, u) = (&mut t[..8 * n2], &mut u[..8 * n2]);
            for kv in widths().skip(1) {
                let (typed, raw) = (&block[..8 * kv], &bytes[..8 * kv * size]);
                portable::transfer_stored(typed, &w[..kv * n2], t);
                avx2.transfer_stored(encoding, raw, &w[..kv * n2], u);
                assert_eq!(bits(t), bits(u), "stored transfer, n² {n2} k_v {kv}");
            }
            for z in identity_weights(&w, n2) {
                let rows = n2 * z.len;
                portable::transfer_identity(&block[..8 * rows], z, t);
                avx2.transfer_identity(encoding, &bytes[..8 * rows * size], z, u);
                assert_eq!(bits(t), bits(u), "identity transfer, n² {n2} {}", z.len);
            }
        }
    }

    /// Runs of blocks, lead rows and all, shade each block exactly as the portable kernel
    /// does alone: runs of 0..=11 blocks (whole groups of the AVX kernels and every
    /// remainder), with one block of mixed bones at each position, in every encoding, through
    /// each kernel set this CPU runs.
    #[test]
    fn runs_shade_each_block_as_alone() {
        let (f32s, f16s, bytes) = encoded();
        for (encoding, values) in [
            (Encoding::F32, f32s.as_flattened()),
            (Encoding::F16, f16s.as_flattened()),
            (Encoding::I8, &bytes[..]),
        ] {
            runs_match(encoding, values, &mut |run, layout, q, width, visit| {
                shade_blocks(encoding, run, layout, q, width, visit)
            });
            #[cfg(target_arch = "x86_64")]
            if let Some(avx2) = x86::Avx2::get() {
                runs_match(encoding, values, &mut |run, layout, q, width, visit| {
                    avx2.without_avx512()
                        .shade_blocks(encoding, run, layout, q, width, visit)
                });
            }
        }
    }

    /// A way to shade a run: [`shade_blocks`] with the encoding fixed.
    type ShadeRun<'a> =
        dyn FnMut(&[u8], BlockLayout, &[f32], usize, &mut dyn FnMut(usize, [f32; 8])) + 'a;

    fn runs_match(encoding: Encoding, values: &[u8], shade_run: &mut ShadeRun<'_>) {
        const WIDTH: usize = 23;
        let q: [f32; 3 * WIDTH] = core::array::from_fn(weight);
        let size = encoding.size();
        let layout = BlockLayout {
            bytes: 8 * (1 + WIDTH) * size,
            lead: 8 * size,
            last_bone: 2,
        };
        let mut run = [0u8; 11 * 8 * (1 + WIDTH) * 4];
        for blocks in 0..=11 {
            for mixed in 0..blocks.max(1) {
                let run = &mut run[..blocks * layout.bytes];
                for (b, block) in run.chunks_exact_mut(layout.bytes).enumerate() {
                    let (lead, rows) = block.split_at_mut(layout.lead);
                    for (l, x) in lead.chunks_exact_mut(size).enumerate() {
                        let bone = if b == mixed { l % 3 } else { b % 3 };
                        x.copy_from_slice(&stored(encoding, bone)[..size]);
                    }
                    rows.copy_from_slice(&values[b * rows.len()..][..rows.len()]);
                }
                let mut visited = 0;
                shade_run(run, layout, &q, WIDTH, &mut |i, lanes| {
                    let block = &run[i * layout.bytes..][..layout.bytes];
                    let (lead, rows) = block.split_at(layout.lead);
                    let bones = bone_lanes(encoding, lead, 2);
                    let alone = match encoding {
                        Encoding::F32 => {
                            portable::shade_block(rows.as_chunks::<4>().0, &q, WIDTH, bones)
                        }
                        Encoding::F16 => {
                            portable::shade_block(rows.as_chunks::<2>().0, &q, WIDTH, bones)
                        }
                        Encoding::I8 => portable::shade_block(rows, &q, WIDTH, bones),
                    };
                    assert_eq!(
                        lanes.map(f32::to_bits),
                        alone.map(f32::to_bits),
                        "block {i}"
                    );
                    visited += 1;
                });
                assert_eq!(visited, blocks);
            }
        }
    }

    /// A bone index as `encoding` stores it in a lead row.
    fn stored(encoding: Encoding, bone: usize) -> [u8; 4] {
        let mut x = [0; 4];
        match encoding {
            Encoding::F32 => x = (bone as f32).to_le_bytes(),
            Encoding::F16 => {
                x[..2].copy_from_slice(&half::f16::from_f32(bone as f32).to_le_bytes())
            }
            Encoding::I8 => x[0] = bone as u8,
        }
        x
    }

    /// FNV-1a, folded over the bytes of values' bits: the digests the targets compare.
    struct Digest(u64);

    impl Digest {
        fn new() -> Digest {
            Digest(0xcbf2_9ce4_8422_2325)
        }

        fn eat(&mut self, xs: &[f32]) {
            for byte in xs.iter().flat_map(|x| x.to_bits().to_le_bytes()) {
                self.0 = (self.0 ^ u64::from(byte)).wrapping_mul(0x0100_0000_01b3);
            }
        }
    }

    /// FNV-1a over the bits of every shading and transfer result of the agreement tests'
    /// cases, from whichever kernels this target runs.
    fn kernel_bits_digest() -> u64 {
        let mut digest = Digest::new();
        let mut eat = |xs: &[f32]| digest.eat(xs);
        let (f32s, f16s, bytes) = encoded();
        let q: [f32; 3 * MAX_COEF_DIMS] = core::array::from_fn(weight);
        let w: [f32; N] = core::array::from_fn(|i| weight(i + 11));
        let mut t = [0.0f32; 8 * MAX_COEFFS];
        for (encoding, values) in [
            (Encoding::F32, f32s.as_flattened()),
            (Encoding::F16, f16s.as_flattened()),
            (Encoding::I8, &bytes[..]),
        ] {
            let size = encoding.size();
            for width in widths() {
                for bones in BONES {
                    eat(&shade_bytes(
                        encoding,
                        &values[..8 * width * size],
                        &q,
                        width,
                        bones,
                    ));
                }
            }
            for n2 in COEFFS {
                let t = &mut t[..8 * n2];
                for kv in widths().skip(1) {
                    transfer_stored(encoding, &values[..8 * kv * size], &w[..kv * n2], t);
                    eat(t);
                }
                for z in identity_weights(&w, n2) {
                    transfer_identity(encoding, &values[..8 * n2 * z.len * size], z, t);
                    eat(t);
                }
            }
        }
        digest.0
    }

    /// Every target computes the same bits: x86-64 in its AVX-512, AVX2 or SSE2 kernels,
    /// aarch64 in NEON (under qemu in CI), wasm32 in `simd128` (under Node in CI) and
    /// thumbv7em in scalar code all give this digest, which x86-64's portable kernels gave
    /// first. The x86-64 sets are also compared with each other directly above.
    #[test]
    fn kernel_bits_are_the_same_on_every_target() {
        assert_eq!(kernel_bits_digest(), 7_121_280_620_998_438_287);
    }

    /// The bitwise comparison can fail: summing the same products in one chain instead of the
    /// kernels' even and odd chains changes the bits of these sums.
    #[test]
    fn the_summation_order_shows_in_the_bits() {
        let (f32s, _, _) = encoded();
        let q: [f32; MAX_COEF_DIMS] = core::array::from_fn(weight);
        let one_chain = |l: usize| {
            (0..40).fold(0.0f32, |s, r| {
                s + q[r] * f32::from_le_bytes(f32s[r * 8 + l])
            })
        };
        let kernel = shade_bytes(
            Encoding::F32,
            &f32s.as_flattened()[..8 * 40 * 4],
            &q,
            40,
            [0; 8],
        );
        assert!((0..8).any(|l| kernel[l].to_bits() != one_chain(l).to_bits()));
    }

    /// A way to compose light maps: the dispatcher, or one kernel set.
    #[derive(Clone, Copy)]
    enum Composer {
        Dispatch,
        Portable,
        #[cfg(target_arch = "x86_64")]
        Wide(x86::Avx2),
    }

    impl Composer {
        fn run(self, maps: &[f32], l: &[[f32; 3]], out: &mut [[f32; 3]]) {
            match l.len() {
                1 => self.run_n::<1>(maps, l, out),
                4 => self.run_n::<4>(maps, l, out),
                9 => self.run_n::<9>(maps, l, out),
                16 => self.run_n::<16>(maps, l, out),
                25 => self.run_n::<25>(maps, l, out),
                36 => self.run_n::<36>(maps, l, out),
                n2 => panic!("no order has {n2} coefficients"),
            }
        }

        fn run_n<const N2: usize>(self, maps: &[f32], l: &[[f32; 3]], out: &mut [[f32; 3]]) {
            let l: &[[f32; 3]; N2] = l.try_into().unwrap();
            match self {
                Composer::Dispatch => compose(maps, l, out),
                Composer::Portable => portable::compose(maps, l, out),
                #[cfg(target_arch = "x86_64")]
                Composer::Wide(avx2) => avx2.compose(maps, l, out),
            }
        }
    }

    /// Texels per map in the composition tests: every tail of the eight- and sixteen-texel
    /// blocks, after zero, one and two sixteen-texel blocks.
    const TEXELS: usize = 40;

    /// A light-map case: its name, maps and lighting.
    type ComposeCase = (
        &'static str,
        [f32; TEXELS * MAX_COEFFS],
        [[f32; 3]; MAX_COEFFS],
    );

    /// Light-map cases, each a name, `TEXELS · 36` map values and 36 RGB lighting coefficients
    /// (every order takes a prefix):
    /// - full 24-bit mantissas of both signs, so every product rounds and any other order of
    ///   the adds gives other bits;
    /// - maps near `f32::MAX` of one sign under lighting around 1–3: products overflow to
    ///   infinity, and sums of finite products overflow too;
    /// - the same with mixed signs, where an infinite sum can meet one of the other sign and
    ///   give NaN (whose payload IEEE leaves open: the tests accept any NaN for a NaN).
    fn compose_cases() -> [ComposeCase; 3] {
        let maps = |f: &dyn Fn(usize) -> f32| core::array::from_fn(f);
        let huge = |i: usize| f32::MAX * (0.25 + 0.7 * weight(i + 3).abs());
        let light = |scale: f32| {
            core::array::from_fn(|c| [0, 1, 2].map(|k| scale * (1.0 + weight(3 * c + k + 5).abs())))
        };
        [
            (
                "full mantissas",
                maps(&|i| weight(i + 101)),
                core::array::from_fn(|c| [0, 1, 2].map(|k| weight(3 * c + k + 7) * 3.0)),
            ),
            ("overflow", maps(&huge), light(1.0)),
            (
                "overflow, mixed signs",
                maps(&|i| if i % 5 == 2 { -huge(i) } else { huge(i) }),
                light(1.0),
            ),
        ]
    }

    /// Same bits, or both NaN.
    fn same_texel(a: [f32; 3], b: [f32; 3]) -> bool {
        a.iter()
            .zip(&b)
            .all(|(x, y)| x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan()))
    }

    /// Every composition kernel this target runs gives [`texel`]'s bits for every texel:
    /// orders 1..=6, 0..=40 texels, every case of [`compose_cases`], through the dispatcher,
    /// the portable kernel, and on x86-64 the AVX-512 and AVX2 kernels (where the CPU has
    /// them).
    #[test]
    fn composition_kernels_give_the_scalar_bits() {
        #[cfg_attr(not(target_arch = "x86_64"), allow(unused_mut))]
        let mut composers = [
            Some(Composer::Dispatch),
            Some(Composer::Portable),
            None,
            None,
        ];
        #[cfg(target_arch = "x86_64")]
        if let Some(avx2) = x86::Avx2::get() {
            composers[2..].copy_from_slice(&[
                Some(Composer::Wide(avx2)),
                Some(Composer::Wide(avx2.without_avx512())),
            ]);
        }
        let mut out = [[0.0f32; 3]; TEXELS];
        for (name, maps, lighting) in compose_cases() {
            let (mut infinite, mut nan) = (0, 0);
            for n2 in COEFFS {
                let l = &lighting[..n2];
                for texels in 0..=TEXELS {
                    let maps = &maps[..texels * n2];
                    for (k, composer) in composers.iter().flatten().enumerate() {
                        let out = &mut out[..texels];
                        out.fill([7.0; 3]);
                        composer.run(maps, l, out);
                        for (t, (&got, m)) in out.iter().zip(maps.chunks_exact(n2)).enumerate() {
                            let want = texel(m, l);
                            assert!(
                                same_texel(got, want),
                                "{name}, n² {n2}, {texels} texels, composer {k}, texel {t}: \
                                 {got:?} against {want:?}"
                            );
                            infinite += want.iter().filter(|x| x.is_infinite()).count();
                            nan += want.iter().filter(|x| x.is_nan()).count();
                        }
                    }
                }
            }
            // The overflow cases do overflow (and the mixed one meets NaN).
            match name {
                "full mantissas" => assert_eq!((infinite, nan), (0, 0)),
                "overflow" => assert!(infinite > 0 && nan == 0, "{infinite} {nan}"),
                _ => assert!(infinite > 0 && nan > 0, "{infinite} {nan}"),
            }
        }
    }

    /// The texel check can fail: summing a texel's products in two chains (even and odd
    /// coefficients), as a kernel vectorised across coefficients would, changes the bits.
    #[test]
    fn the_texel_order_shows_in_the_bits() {
        let [(_, maps, lighting), ..] = compose_cases();
        let l = &lighting[..36];
        let differs = maps.chunks_exact(36).any(|t| {
            let mut halves = [[0.0f32; 3]; 2];
            for (c, (&x, lc)) in t.iter().zip(l).enumerate() {
                for (a, y) in halves[c % 2].iter_mut().zip(lc) {
                    *a += y * x;
                }
            }
            let two_chains: [f32; 3] = core::array::from_fn(|k| halves[0][k] + halves[1][k]);
            !same_texel(two_chains, texel(t, l))
        });
        assert!(differs);
    }

    /// FNV-1a over the bits of every composed texel of the cases without NaN, from the
    /// composition this target dispatches to.
    fn compose_bits_digest() -> u64 {
        let mut digest = Digest::new();
        let mut out = [[0.0f32; 3]; TEXELS];
        for (_, maps, lighting) in compose_cases().iter().take(2) {
            for n2 in COEFFS {
                for texels in 0..=TEXELS {
                    let out = &mut out[..texels];
                    compose(&maps[..texels * n2], &lighting[..n2], out);
                    digest.eat(out.as_flattened());
                }
            }
        }
        digest.0
    }

    /// Light maps compose to the same bits on every target, as the other kernels do (see
    /// `kernel_bits_are_the_same_on_every_target`): x86-64 with AVX-512, AVX2 or SSE2, and
    /// aarch64 (under qemu) gave this digest.
    #[test]
    fn compose_bits_are_the_same_on_every_target() {
        assert_eq!(compose_bits_digest(), 549_187_341_768_619_835);
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
