//! The kernels in AVX2 registers, for x86-64 CPUs that have AVX2 and F16C (Intel since 2013,
//! AMD since 2015): the only module of aprt-core with `unsafe` code.
//!
//! Each kernel performs the portable kernel's multiplies and adds in the same order, one
//! eight-lane register per block row, so the two give the same bits (the tests compare them
//! exactly). What the wider registers buy is decoding: an f16 row is one `vcvtph2ps` and an i8
//! row one sign-extending load and `vcvtdq2ps`, where SSE2 spends four to six operations per
//! four lanes; and the stored-basis transfer keeps eight vertices' outputs in registers,
//! vectorised over coefficients, so it needs no transposition.
//!
//! Measured (`cargo bench -p aprt-tests --bench eval`, PCA(8,22), 11,500 vertices, order 6,
//! on an AVX-512 machine): f32 shading 0.82× a memcpy of its bytes and full transfer 10.4×,
//! against 2.04× and 40.4× before these kernels (issue 33). f16 and i8 shading cost 1.07× and
//! 1.05× the f32 time, interleaved: rows that fit in cache are bound by the multiply–adds,
//! which every encoding pays, plus a conversion (see docs/results/performance.md).
#![allow(unsafe_code)]

use core::arch::x86_64::{
    __cpuid, __cpuid_count, __m256, __m256i, __m512, __mmask16, _mm_loadl_epi64, _mm_loadu_ps,
    _mm_loadu_si128, _mm256_add_ps, _mm256_castpd_ps, _mm256_castps_pd, _mm256_cmpgt_epi32,
    _mm256_cvtepi8_epi32, _mm256_cvtepi32_ps, _mm256_cvtph_ps, _mm256_loadu_ps, _mm256_loadu_si256,
    _mm256_maskload_ps, _mm256_maskstore_ps, _mm256_mul_ps, _mm256_set_m128, _mm256_set1_epi32,
    _mm256_set1_ps, _mm256_setr_epi32, _mm256_setr_ps, _mm256_setzero_ps, _mm256_shuffle_ps,
    _mm256_unpackhi_ps, _mm256_unpacklo_ps, _mm512_add_ps, _mm512_castpd_ps,
    _mm512_castpd256_pd512, _mm512_castps_pd, _mm512_castps128_ps512, _mm512_castps512_ps256,
    _mm512_cvtepi8_epi32, _mm512_cvtepi32_ps, _mm512_cvtph_ps, _mm512_extractf64x4_pd,
    _mm512_insertf32x4, _mm512_insertf64x4, _mm512_loadu_ps, _mm512_mask_storeu_ps,
    _mm512_maskz_loadu_ps, _mm512_mul_ps, _mm512_set1_ps, _mm512_setzero_ps, _mm512_shuffle_f32x4,
    _mm512_shuffle_ps, _mm512_unpackhi_ps, _mm512_unpacklo_ps, _xgetbv,
};
use core::sync::atomic::{AtomicU8, Ordering};

mod lanes;

use super::{BlockLayout, IdentityWeights, bone_lanes};
use crate::blob::format::{Encoding, MAX_COEF_DIMS, VERTEX_BLOCK};

/// Proof that this CPU runs AVX2 and F16C with the operating system's support: a value exists
/// only where [`Avx2::get`] found them. `avx512`: it also runs AVX-512F, which shading uses.
#[derive(Clone, Copy)]
pub(crate) struct Avx2 {
    avx512: bool,
}

/// What detection found: `UNKNOWN` until the first call.
static FOUND: AtomicU8 = AtomicU8::new(UNKNOWN);
const UNKNOWN: u8 = 0;
const NEITHER: u8 = 1;
const AVX2: u8 = 2;
const AVX512: u8 = 3;

/// Makes [`Avx2::get`] find nothing (`portable`), or detect again.
pub(crate) fn force_portable(portable: bool) {
    FOUND.store(if portable { NEITHER } else { UNKNOWN }, Ordering::Relaxed);
}

impl Avx2 {
    /// The token, if this CPU has AVX2 and F16C. Detection runs once; afterwards this is one
    /// relaxed load (racing first calls detect twice and store the same answer).
    #[inline(always)]
    pub(crate) fn get() -> Option<Avx2> {
        let found = match FOUND.load(Ordering::Relaxed) {
            UNKNOWN => {
                let found = detect();
                FOUND.store(found, Ordering::Relaxed);
                found
            }
            found => found,
        };
        (found >= AVX2).then_some(Avx2 {
            avx512: found == AVX512,
        })
    }

    /// The same token without AVX-512, so that tests reach the AVX2 shading on any CPU.
    #[cfg(test)]
    pub(crate) fn without_avx512(self) -> Avx2 {
        Avx2 { avx512: false }
    }

    /// [`super::shade_bytes`] in AVX2, for eight lanes of one bone, whose weights are `q`.
    #[inline(always)]
    pub(crate) fn shade_one_bone(self, encoding: Encoding, bytes: &[u8], q: &[f32]) -> [f32; 8] {
        // SAFETY: `self` exists only on a CPU with AVX2 and F16C.
        unsafe {
            match encoding {
                Encoding::F32 => shade_one_bone(bytes.as_chunks::<4>().0, q),
                Encoding::F16 => shade_one_bone(bytes.as_chunks::<2>().0, q),
                Encoding::I8 => shade_one_bone(bytes, q),
            }
        }
    }

    /// [`super::shade_bytes`] in AVX2, for lanes of several bones.
    #[inline(always)]
    pub(crate) fn shade_mixed(
        self,
        encoding: Encoding,
        bytes: &[u8],
        q: &[f32],
        width: usize,
        bones: [usize; VERTEX_BLOCK],
    ) -> [f32; VERTEX_BLOCK] {
        // SAFETY: `self` exists only on a CPU with AVX2 and F16C.
        unsafe {
            match encoding {
                Encoding::F32 => shade_mixed(bytes.as_chunks::<4>().0, q, width, bones),
                Encoding::F16 => shade_mixed(bytes.as_chunks::<2>().0, q, width, bones),
                Encoding::I8 => shade_mixed(bytes, q, width, bones),
            }
        }
    }

    /// [`super::shade_blocks`] in AVX2.
    #[inline(always)]
    pub(crate) fn shade_blocks(
        self,
        encoding: Encoding,
        blocks: &[u8],
        layout: BlockLayout,
        q: &[f32],
        width: usize,
        visit: impl FnMut(usize, [f32; VERTEX_BLOCK]),
    ) {
        let run = Run {
            blocks,
            layout,
            q,
            width,
        };
        // SAFETY: `self` exists only on a CPU with AVX2 and F16C, and says whether it also
        // has AVX-512F.
        unsafe {
            match (encoding, self.avx512) {
                (Encoding::F32, false) => shade_run::<[u8; 4]>(run, visit),
                (Encoding::F16, false) => shade_run::<[u8; 2]>(run, visit),
                (Encoding::I8, false) => shade_run::<u8>(run, visit),
                (Encoding::F32, true) => shade_run_512::<[u8; 4]>(run, visit),
                (Encoding::F16, true) => shade_run_512::<[u8; 2]>(run, visit),
                (Encoding::I8, true) => shade_run_512::<u8>(run, visit),
            }
        }
    }

    /// [`super::transfer_stored`] in AVX2.
    #[inline(always)]
    pub(crate) fn transfer_stored(
        self,
        encoding: Encoding,
        bytes: &[u8],
        w: &[f32],
        t: &mut [f32],
    ) {
        // SAFETY: `self` exists only on a CPU with AVX2 and F16C, and says whether it also
        // has AVX-512F.
        unsafe {
            match (encoding, self.avx512) {
                (Encoding::F32, false) => transfer_stored(bytes.as_chunks::<4>().0, w, t),
                (Encoding::F16, false) => transfer_stored(bytes.as_chunks::<2>().0, w, t),
                (Encoding::I8, false) => transfer_stored(bytes, w, t),
                (Encoding::F32, true) => transfer_stored_512(bytes.as_chunks::<4>().0, w, t),
                (Encoding::F16, true) => transfer_stored_512(bytes.as_chunks::<2>().0, w, t),
                (Encoding::I8, true) => transfer_stored_512(bytes, w, t),
            }
        }
    }

    /// [`super::transfer_identity`] in AVX2.
    #[inline(always)]
    pub(crate) fn transfer_identity(
        self,
        encoding: Encoding,
        bytes: &[u8],
        z: IdentityWeights<'_>,
        t: &mut [f32],
    ) {
        // SAFETY: `self` exists only on a CPU with AVX2 and F16C.
        unsafe {
            match encoding {
                Encoding::F32 => transfer_identity(bytes.as_chunks::<4>().0, z, t),
                Encoding::F16 => transfer_identity(bytes.as_chunks::<2>().0, z, t),
                Encoding::I8 => transfer_identity(bytes, z, t),
            }
        }
    }

    /// [`super::compose`] in AVX2, or sixteen texels at a time in AVX-512.
    #[inline(always)]
    pub(crate) fn compose<const N2: usize>(
        self,
        maps: &[f32],
        l: &[[f32; 3]; N2],
        out: &mut [[f32; 3]],
    ) {
        // SAFETY: `self` exists only on a CPU with AVX2 and F16C, and says whether it also
        // has AVX-512F.
        unsafe {
            match self.avx512 {
                false => compose(maps, l, out),
                true => compose_512(maps, l, out),
            }
        }
    }
}

/// The widest set this CPU and its operating system run: [`AVX512`] (AVX-512F, with AVX2 and
/// F16C), [`AVX2`] (AVX2 and F16C) or [`NEITHER`]. Intel SDM vol. 1, 14.3 and 15.2: CPUID for
/// the instructions, XCR0 for the operating system saving their registers (bits 1–2 for YMM,
/// 5–7 for the mask registers and ZMM).
fn detect() -> u8 {
    let (max_leaf, leaf1) = (__cpuid(0).eax, __cpuid(1));
    let has = |bits: u64, mask: u64| bits & mask == mask;
    const OSXSAVE_AVX_F16C: u64 = (1 << 27) | (1 << 28) | (1 << 29);
    if max_leaf < 7 || !has(leaf1.ecx.into(), OSXSAVE_AVX_F16C) {
        return NEITHER;
    }
    // SAFETY: OSXSAVE set means `xgetbv` is enabled.
    let xcr0 = unsafe { xcr0() };
    let leaf7 = u64::from(__cpuid_count(7, 0).ebx);
    match (
        has(xcr0, 0b110) && has(leaf7, 1 << 5),
        has(xcr0, 0b1110_0110) && has(leaf7, 1 << 16),
    ) {
        (false, _) => NEITHER,
        (true, false) => AVX2,
        (true, true) => AVX512,
    }
}

#[target_feature(enable = "xsave")]
fn xcr0() -> u64 {
    // SAFETY: called only where CPUID reports OSXSAVE.
    unsafe { _xgetbv(0) }
}

/// Stored values of one encoding, eight at a time.
trait Lanes: Copy + 'static {
    /// The encoding these values are.
    const ENCODING: Encoding;

    /// Bytes of this encoding as values (a trailing partial value dropped).
    fn view(bytes: &[u8]) -> &[Self];

    /// One block row as eight f32 lanes.
    ///
    /// # Safety
    /// The CPU has AVX2 and F16C.
    unsafe fn lanes(row: &[Self; VERTEX_BLOCK]) -> __m256;

    /// Two consecutive block rows as sixteen f32 lanes, the first row in lanes 0–7.
    ///
    /// # Safety
    /// The CPU has AVX-512F.
    unsafe fn pair(rows: &[[Self; VERTEX_BLOCK]; 2]) -> __m512;
}

/// Lanes 8–15 of a register.
#[inline]
#[target_feature(enable = "avx512f,avx2,f16c")]
fn high_half(x: __m512) -> __m256 {
    _mm256_castpd_ps(_mm512_extractf64x4_pd::<1>(_mm512_castps_pd(x)))
}

impl Lanes for [u8; 4] {
    const ENCODING: Encoding = Encoding::F32;

    fn view(bytes: &[u8]) -> &[Self] {
        bytes.as_chunks().0
    }

    #[inline(always)]
    unsafe fn lanes(row: &[Self; VERTEX_BLOCK]) -> __m256 {
        // SAFETY: the row is 32 bytes; the caller guarantees AVX.
        unsafe { _mm256_loadu_ps(row.as_ptr().cast()) }
    }

    #[inline(always)]
    unsafe fn pair(rows: &[[Self; VERTEX_BLOCK]; 2]) -> __m512 {
        // SAFETY: the rows are 64 bytes; the caller guarantees AVX-512F.
        unsafe { _mm512_loadu_ps(rows.as_ptr().cast()) }
    }
}

impl Lanes for [u8; 2] {
    const ENCODING: Encoding = Encoding::F16;

    fn view(bytes: &[u8]) -> &[Self] {
        bytes.as_chunks().0
    }

    #[inline(always)]
    unsafe fn lanes(row: &[Self; VERTEX_BLOCK]) -> __m256 {
        // SAFETY: the row is 16 bytes; the caller guarantees F16C. The conversion is exact.
        unsafe { _mm256_cvtph_ps(_mm_loadu_si128(row.as_ptr().cast())) }
    }

    #[inline(always)]
    unsafe fn pair(rows: &[[Self; VERTEX_BLOCK]; 2]) -> __m512 {
        // SAFETY: the rows are 32 bytes; the caller guarantees AVX-512F. Exact, as above.
        unsafe { _mm512_cvtph_ps(_mm256_loadu_si256(rows.as_ptr().cast())) }
    }
}

impl Lanes for u8 {
    const ENCODING: Encoding = Encoding::I8;

    fn view(bytes: &[u8]) -> &[Self] {
        bytes
    }

    #[inline(always)]
    unsafe fn lanes(row: &[Self; VERTEX_BLOCK]) -> __m256 {
        // SAFETY: the row is 8 bytes; the caller guarantees AVX2.
        unsafe { _mm256_cvtepi32_ps(_mm256_cvtepi8_epi32(_mm_loadl_epi64(row.as_ptr().cast()))) }
    }

    #[inline(always)]
    unsafe fn pair(rows: &[[Self; VERTEX_BLOCK]; 2]) -> __m512 {
        // SAFETY: the rows are 16 bytes; the caller guarantees AVX-512F.
        unsafe { _mm512_cvtepi32_ps(_mm512_cvtepi8_epi32(_mm_loadu_si128(rows.as_ptr().cast()))) }
    }
}

/// A register's eight lanes.
#[inline(always)]
fn array(v: __m256) -> [f32; VERTEX_BLOCK] {
    // SAFETY: both are 32 bytes of plain data.
    unsafe { core::mem::transmute::<__m256, [f32; VERTEX_BLOCK]>(v) }
}

/// `acc + a b`, as two roundings (the portable kernel's `acc += a * b`, never a fused
/// multiply–add).
#[inline]
#[target_feature(enable = "avx2,f16c")]
fn add_product(acc: __m256, a: __m256, b: __m256) -> __m256 {
    _mm256_add_ps(acc, _mm256_mul_ps(a, b))
}

/// A block of one bone: the rows weighted by its `q`.
#[target_feature(enable = "avx2,f16c")]
fn shade_one_bone<E: Lanes>(block: &[E], q: &[f32]) -> [f32; VERTEX_BLOCK] {
    array(weighted_rows(block.as_chunks::<VERTEX_BLOCK>().0, q))
}

/// A run of whole blocks to shade with lighting weights `q` of `width` per bone.
#[derive(Clone, Copy)]
struct Run<'a> {
    blocks: &'a [u8],
    layout: BlockLayout,
    q: &'a [f32],
    width: usize,
}

impl<'a> Run<'a> {
    /// Block `i`'s rows, and the lighting weights of its bone when its lanes share one.
    #[inline(always)]
    fn block<E: Lanes>(self, i: usize) -> (Option<&'a [f32]>, &'a [[E; VERTEX_BLOCK]]) {
        let block = &self.blocks[i * self.layout.bytes..][..self.layout.bytes];
        let (lead, rows) = block.split_at(self.layout.lead);
        // Equal stored bytes are equal bones (the decode is a function of them); comparing
        // them spares decoding eight lanes to find out.
        let rows = E::view(rows).as_chunks().0;
        if lead.is_empty() {
            return (Some(&self.q[..self.width]), rows);
        }
        // Compared as fixed-size values: slices of a run-time length compile to `memcmp`
        // calls, a third of a frame of a bone-frame model with short rows.
        let shared = match E::ENCODING {
            Encoding::F32 => all_equal(lead.as_chunks::<4>().0),
            Encoding::F16 => all_equal(lead.as_chunks::<2>().0),
            Encoding::I8 => all_equal(lead.as_chunks::<1>().0),
        };
        let q = shared.then(|| {
            let first = &lead[..E::ENCODING.size()];
            let bone = bone_lanes(E::ENCODING, first, self.layout.last_bone)[0];
            &self.q[bone * self.width..][..self.width]
        });
        (q, rows)
    }

    /// The lanes of block `i`, whose bones differ.
    #[inline(always)]
    fn mixed<E: Lanes>(self, i: usize) -> [f32; VERTEX_BLOCK] {
        let block = &self.blocks[i * self.layout.bytes..][..self.layout.bytes];
        let (lead, rows) = block.split_at(self.layout.lead);
        let bones = bone_lanes(E::ENCODING, lead, self.layout.last_bone);
        // SAFETY: reached only from `shade_run`, which runs with AVX2 and F16C.
        unsafe { shade_mixed(E::view(rows), self.q, self.width, bones) }
    }
}

/// Whether every lane's stored bytes equal the first lane's.
#[inline(always)]
fn all_equal<const N: usize>(lanes: &[[u8; N]]) -> bool {
    lanes.iter().all(|x| *x == lanes[0])
}

/// Blocks shaded together: their even and odd sums make `2 RUN_BLOCKS` independent chains of
/// adds, where one block's two chains leave the adder waiting on its latency.
const RUN_BLOCKS: usize = 4;

/// [`super::shade_blocks`] in AVX2.
#[target_feature(enable = "avx2,f16c")]
fn shade_run<E: Lanes>(run: Run<'_>, visit: impl FnMut(usize, [f32; VERTEX_BLOCK])) {
    shade_run_with(run, visit, |rows, q| {
        weighted_runs::<E, RUN_BLOCKS>(rows, q)
    });
}

/// [`super::shade_blocks`] in AVX-512: two rows of a block per register.
#[target_feature(enable = "avx512f,avx2,f16c")]
fn shade_run_512<E: Lanes>(run: Run<'_>, visit: impl FnMut(usize, [f32; VERTEX_BLOCK])) {
    shade_run_with(run, visit, |rows, q| {
        weighted_runs_512::<E, RUN_BLOCKS>(rows, q)
    });
}

/// Shading of a run: [`RUN_BLOCKS`] blocks at a time by `group` where each is of one bone,
/// else block by block. Inlined into each instruction set's function.
#[inline(always)]
fn shade_run_with<'a, E: Lanes + 'a>(
    run: Run<'a>,
    mut visit: impl FnMut(usize, [f32; VERTEX_BLOCK]),
    group: impl Fn(
        [&'a [[E; VERTEX_BLOCK]]; RUN_BLOCKS],
        [&'a [f32]; RUN_BLOCKS],
    ) -> [[f32; VERTEX_BLOCK]; RUN_BLOCKS],
) {
    let count = run.blocks.len() / run.layout.bytes.max(1);
    // SAFETY (both): reached only from `shade_run*`, which run with AVX2 and F16C.
    let alone = |i: usize| match run.block::<E>(i) {
        (Some(q), rows) => array(unsafe { weighted_rows(rows, q) }),
        (None, _) => run.mixed::<E>(i),
    };
    let mut i = 0;
    while i + RUN_BLOCKS <= count {
        // Filled by loops: `array::from_fn` and `map` were left as calls in this hot path.
        let (mut rows, mut weights) = ([&[][..]; RUN_BLOCKS], [&[][..]; RUN_BLOCKS]);
        let mut one_bone = true;
        for k in 0..RUN_BLOCKS {
            let (q, r) = run.block::<E>(i + k);
            (rows[k], weights[k], one_bone) = (r, q.unwrap_or(&[]), one_bone && q.is_some());
        }
        if one_bone {
            let lanes = group(rows, weights);
            for (k, lanes) in lanes.iter().enumerate() {
                visit(i + k, *lanes);
            }
        } else {
            (i..i + RUN_BLOCKS).for_each(|i| visit(i, alone(i)));
        }
        i += RUN_BLOCKS;
    }
    (i..count).for_each(|i| visit(i, alone(i)));
}

/// [`weighted_rows`] of several blocks at once, each summed in the same order as alone.
#[inline]
#[target_feature(enable = "avx2,f16c")]
fn weighted_runs<E: Lanes, const N: usize>(
    rows: [&[[E; VERTEX_BLOCK]]; N],
    q: [&[f32]; N],
) -> [[f32; VERTEX_BLOCK]; N] {
    let len = rows
        .iter()
        .zip(&q)
        .map(|(r, q)| r.len().min(q.len()))
        .min()
        .unwrap_or(0);
    // Cut to one length, so that indexing below `len` needs no checks.
    let (rows, q) = (rows.map(|r| &r[..len]), q.map(|q| &q[..len]));
    let (mut even, mut odd) = ([_mm256_setzero_ps(); N], [_mm256_setzero_ps(); N]);
    for r in (1..len).step_by(2) {
        for b in 0..N {
            // SAFETY: this function runs only with AVX2 and F16C.
            let (u0, u1) = unsafe { (E::lanes(&rows[b][r - 1]), E::lanes(&rows[b][r])) };
            even[b] = add_product(even[b], _mm256_set1_ps(q[b][r - 1]), u0);
            odd[b] = add_product(odd[b], _mm256_set1_ps(q[b][r]), u1);
        }
    }
    if len % 2 == 1 {
        for b in 0..N {
            // SAFETY: as above.
            let u = unsafe { E::lanes(&rows[b][len - 1]) };
            even[b] = add_product(even[b], _mm256_set1_ps(q[b][len - 1]), u);
        }
    }
    let mut lanes = [[0.0; VERTEX_BLOCK]; N];
    for b in 0..N {
        lanes[b] = array(_mm256_add_ps(even[b], odd[b]));
    }
    lanes
}

/// [`weighted_runs`] with a block's even and odd rows in the two halves of one AVX-512
/// register: the same two sums, half the instructions.
#[inline]
#[target_feature(enable = "avx512f,avx2,f16c")]
fn weighted_runs_512<E: Lanes, const N: usize>(
    rows: [&[[E; VERTEX_BLOCK]]; N],
    q: [&[f32]; N],
) -> [[f32; VERTEX_BLOCK]; N] {
    let len = rows
        .iter()
        .zip(&q)
        .map(|(r, q)| r.len().min(q.len()))
        .min()
        .unwrap_or(0);
    let (mut pairs, mut q_pairs) = ([&[][..]; N], [&[][..]; N]);
    for b in 0..N {
        (pairs[b], q_pairs[b]) = (
            rows[b][..len].as_chunks::<2>().0,
            q[b][..len].as_chunks::<2>().0,
        );
    }
    // Lanes 0–7 the even row's weight, 8–15 the odd row's.
    let weights =
        |[q0, q1]: [f32; 2]| _mm512_shuffle_f32x4::<0>(_mm512_set1_ps(q0), _mm512_set1_ps(q1));
    let mut acc = [_mm512_setzero_ps(); N];
    // Blocks of one bone (every block of a world-frame model) share each pair's weights.
    let shared = q.iter().all(|x| core::ptr::eq(*x, q[0]));
    for p in 0..len / 2 {
        let first = weights(q_pairs[0][p]);
        for b in 0..N {
            let w = if shared {
                first
            } else {
                weights(q_pairs[b][p])
            };
            // SAFETY: this function runs only with AVX-512F, AVX2 and F16C.
            let u = unsafe { E::pair(&pairs[b][p]) };
            acc[b] = _mm512_add_ps(acc[b], _mm512_mul_ps(w, u));
        }
    }
    let mut lanes = [[0.0; VERTEX_BLOCK]; N];
    for b in 0..N {
        let (mut even, odd) = (_mm512_castps512_ps256(acc[b]), high_half(acc[b]));
        if len % 2 == 1 {
            // SAFETY: as above.
            let u = unsafe { E::lanes(&rows[b][len - 1]) };
            even = add_product(even, _mm256_set1_ps(q[b][len - 1]), u);
        }
        lanes[b] = array(_mm256_add_ps(even, odd));
    }
    lanes
}

/// `Σ_r q_r U_r` over eight lanes: even and odd rows in two sums, then their sum.
#[inline]
#[target_feature(enable = "avx2,f16c")]
fn weighted_rows<E: Lanes>(rows: &[[E; VERTEX_BLOCK]], q: &[f32]) -> __m256 {
    let (pairs, rest) = rows.as_chunks::<2>();
    let (q_pairs, q_rest) = q.as_chunks::<2>();
    let (mut even, mut odd) = (_mm256_setzero_ps(), _mm256_setzero_ps());
    for ([r0, r1], [q0, q1]) in pairs.iter().zip(q_pairs) {
        // SAFETY: this function runs only with AVX2 and F16C.
        let (u0, u1) = unsafe { (E::lanes(r0), E::lanes(r1)) };
        even = add_product(even, _mm256_set1_ps(*q0), u0);
        odd = add_product(odd, _mm256_set1_ps(*q1), u1);
    }
    for (r, q) in rest.iter().zip(q_rest) {
        // SAFETY: as above.
        even = add_product(even, _mm256_set1_ps(*q), unsafe { E::lanes(r) });
    }
    _mm256_add_ps(even, odd)
}

/// A block whose lanes straddle bones: each lane's weights from its own bone, gathered per row.
#[target_feature(enable = "avx2,f16c")]
fn shade_mixed<E: Lanes>(
    block: &[E],
    q: &[f32],
    width: usize,
    bones: [usize; VERTEX_BLOCK],
) -> [f32; VERTEX_BLOCK] {
    let rows = block.as_chunks::<VERTEX_BLOCK>().0;
    let qb: [&[f32]; VERTEX_BLOCK] = core::array::from_fn(|l| &q[bones[l] * width..][..width]);
    let mut acc = _mm256_setzero_ps();
    for (r, row) in rows.iter().take(width).enumerate() {
        let [a, b, c, d, e, f, g, h] = qb.map(|q| q[r]);
        let weights = _mm256_setr_ps(a, b, c, d, e, f, g, h);
        // SAFETY: this function runs only with AVX2 and F16C.
        acc = add_product(acc, weights, unsafe { E::lanes(row) });
    }
    array(acc)
}

/// Lanes `0 .. len` of eight enabled (all bits set), the rest off.
#[inline]
#[target_feature(enable = "avx2,f16c")]
fn first_lanes(len: usize) -> __m256i {
    _mm256_cmpgt_epi32(
        _mm256_set1_epi32(len.min(VERTEX_BLOCK) as i32),
        _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7),
    )
}

/// The stored basis: the block's k_v rows decoded once into a tile; then, eight coefficients
/// at a time, eight accumulators (one per vertex, lanes over coefficients) take
/// `w[k n² + c ..] U[k][lane]` for each k, and are stored straight into each vertex's row.
#[target_feature(enable = "avx2,f16c")]
fn transfer_stored<E: Lanes>(block: &[E], w: &[f32], t: &mut [f32]) {
    let n2 = t.len() / VERTEX_BLOCK;
    let mut tile = [[0.0f32; VERTEX_BLOCK]; MAX_COEF_DIMS];
    let tile = decode_tile(block, &mut tile);
    for c in (0..n2).step_by(VERTEX_BLOCK) {
        let mask = first_lanes(n2 - c);
        let mut acc = [_mm256_setzero_ps(); VERTEX_BLOCK];
        for (u, wk) in tile.iter().zip(w.chunks_exact(n2)) {
            // SAFETY: `wk[c..]` holds at least one value per enabled lane (`n2 - c` of them);
            // the masked load reads no other.
            let wc = unsafe { _mm256_maskload_ps(wk[c..].as_ptr(), mask) };
            for (a, &x) in acc.iter_mut().zip(u) {
                *a = add_product(*a, wc, _mm256_set1_ps(x));
            }
        }
        for (tl, a) in t.chunks_exact_mut(n2).zip(acc) {
            // SAFETY: as the load: `tl[c..]` holds `n2 - c` values, the enabled lanes.
            unsafe { _mm256_maskstore_ps(tl[c..].as_mut_ptr(), mask, a) };
        }
    }
}

/// [`transfer_stored`] sixteen coefficients at a time: order 6's 36 in three steps, not five.
#[target_feature(enable = "avx512f,avx2,f16c")]
fn transfer_stored_512<E: Lanes>(block: &[E], w: &[f32], t: &mut [f32]) {
    let n2 = t.len() / VERTEX_BLOCK;
    let mut tile = [[0.0f32; VERTEX_BLOCK]; MAX_COEF_DIMS];
    let tile = decode_tile(block, &mut tile);
    for c in (0..n2).step_by(16) {
        let mask: __mmask16 = u16::MAX >> 16usize.saturating_sub(n2 - c);
        let mut acc = [_mm512_setzero_ps(); VERTEX_BLOCK];
        for (u, wk) in tile.iter().zip(w.chunks_exact(n2)) {
            // SAFETY: as in `transfer_stored`, with the mask register.
            let wc = unsafe { _mm512_maskz_loadu_ps(mask, wk[c..].as_ptr()) };
            for (a, &x) in acc.iter_mut().zip(u) {
                *a = _mm512_add_ps(*a, _mm512_mul_ps(wc, _mm512_set1_ps(x)));
            }
        }
        for (tl, a) in t.chunks_exact_mut(n2).zip(acc) {
            // SAFETY: as in `transfer_stored`.
            unsafe { _mm512_mask_storeu_ps(tl[c..].as_mut_ptr(), mask, a) };
        }
    }
}

/// The block's rows (at most [`MAX_COEF_DIMS`]) decoded into `tile`, which is returned cut
/// to them.
#[inline]
#[target_feature(enable = "avx2,f16c")]
fn decode_tile<'t, E: Lanes>(
    block: &[E],
    tile: &'t mut [[f32; VERTEX_BLOCK]; MAX_COEF_DIMS],
) -> &'t [[f32; VERTEX_BLOCK]] {
    let rows = block.as_chunks::<VERTEX_BLOCK>().0;
    for (d, r) in tile.iter_mut().zip(rows) {
        // SAFETY: this function runs only with AVX2 and F16C.
        *d = array(unsafe { E::lanes(r) });
    }
    &tile[..rows.len().min(MAX_COEF_DIMS)]
}

/// The identity basis: each coefficient's `1 + k_a` rows weighted as in shading, then its
/// eight lanes written to the eight vertices' rows.
#[target_feature(enable = "avx2,f16c")]
fn transfer_identity<E: Lanes>(block: &[E], z: IdentityWeights<'_>, t: &mut [f32]) {
    let n2 = t.len() / VERTEX_BLOCK;
    let rows = block.as_chunks::<VERTEX_BLOCK>().0;
    for (c, xc) in rows.chunks_exact(z.len).take(n2).enumerate() {
        let lanes = array(weighted_rows(xc, z.of(c)));
        for (tl, x) in t.chunks_exact_mut(n2).zip(lanes) {
            tl[c] = x;
        }
    }
}

/// [`super::compose`]: eight texels at a time, each block's coefficients transposed four at a
/// time into registers (four 16-byte loads per half, then the 4 × 4 transposition of SSE's
/// `_MM_TRANSPOSE4_PS` in both halves at once), a leftover coefficient (n² = 9, 25) inserted
/// lane by lane; then per coefficient, in ascending order, `acc += l_c · column` per colour,
/// the lanes being [`super::texel`]'s sums. The remaining texels go through `texel`.
///
/// Loads and transposition measured faster than `_mm256_i32gather_ps` with stride-n² indices
/// (the same kernel otherwise): 2.50× against 2.34× the scalar composition's speed at order 3,
/// 2.78× against 2.33× at order 6, on this machine's Xeon, whose gathers are slow
/// (`cargo bench -p aprt-tests --bench lightmap`, AVX2 forced, one run each).
#[target_feature(enable = "avx2,f16c")]
fn compose<const N2: usize>(maps: &[f32], l: &[[f32; 3]; N2], out: &mut [[f32; 3]]) {
    let texels = maps.as_chunks::<N2>().0;
    let (blocks, tail) = texels.as_chunks::<VERTEX_BLOCK>();
    let (out_blocks, out_tail) = out.as_chunks_mut::<VERTEX_BLOCK>();
    for (block, o) in blocks.iter().zip(out_blocks) {
        let mut acc = [_mm256_setzero_ps(); 3];
        let mut add = |c: usize, column: __m256| {
            for (a, &x) in acc.iter_mut().zip(&l[c]) {
                *a = add_product(*a, _mm256_set1_ps(x), column);
            }
        };
        let row = |t: usize, c: usize| {
            // SAFETY: `c + 4 <= N2`, so the four values are in texel t's row.
            unsafe { _mm_loadu_ps(block[t][c..c + 4].as_ptr()) }
        };
        for c in (0..N2 / 4 * 4).step_by(4) {
            // Lane k of `v[r]` is texel k's coefficient c + r, lane 4 + k texel 4 + k's.
            let v: [__m256; 4] =
                core::array::from_fn(|t| _mm256_set_m128(row(t + 4, c), row(t, c)));
            let (t0, t1) = (
                _mm256_unpacklo_ps(v[0], v[1]),
                _mm256_unpackhi_ps(v[0], v[1]),
            );
            let (t2, t3) = (
                _mm256_unpacklo_ps(v[2], v[3]),
                _mm256_unpackhi_ps(v[2], v[3]),
            );
            add(c, _mm256_shuffle_ps::<0x44>(t0, t2));
            add(c + 1, _mm256_shuffle_ps::<0xee>(t0, t2));
            add(c + 2, _mm256_shuffle_ps::<0x44>(t1, t3));
            add(c + 3, _mm256_shuffle_ps::<0xee>(t1, t3));
        }
        if N2 == 1 {
            // SAFETY: the block is eight values, one per texel.
            add(0, unsafe { _mm256_loadu_ps(block.as_flattened().as_ptr()) });
        } else {
            for c in N2 / 4 * 4..N2 {
                let [x0, x1, x2, x3, x4, x5, x6, x7] = block.map(|t| t[c]);
                add(c, _mm256_setr_ps(x0, x1, x2, x3, x4, x5, x6, x7));
            }
        }
        let [r, g, b] = acc.map(array);
        for (t, o) in o.iter_mut().enumerate() {
            *o = [r[t], g[t], b[t]];
        }
    }
    for (t, o) in tail.iter().zip(out_tail) {
        *o = super::texel(t, l);
    }
}

/// [`compose`] sixteen texels at a time, in AVX-512 registers (lanes 4j + k: texel 4j + k),
/// then at most one block of eight in AVX2. 2.91× the scalar composition's speed at order 3
/// and 2.96× at order 6 in one run of the bench, the AVX2 kernel 2.50× and 2.78× in another:
/// the difference is within the machine's drift, and order 6 runs at the speed of a memory
/// copy either way.
#[target_feature(enable = "avx512f,avx2,f16c")]
fn compose_512<const N2: usize>(maps: &[f32], l: &[[f32; 3]; N2], out: &mut [[f32; 3]]) {
    let texels = maps.as_chunks::<N2>().0;
    let (blocks, _) = texels.as_chunks::<16>();
    let done = 16 * blocks.len().min(out.len() / 16);
    let (out_blocks, _) = out.as_chunks_mut::<16>();
    for (block, o) in blocks.iter().zip(out_blocks) {
        let mut acc = [_mm512_setzero_ps(); 3];
        let mut add = |c: usize, column: __m512| {
            for (a, &x) in acc.iter_mut().zip(&l[c]) {
                *a = _mm512_add_ps(*a, _mm512_mul_ps(_mm512_set1_ps(x), column));
            }
        };
        let row = |t: usize, c: usize| {
            // SAFETY: `c + 4 <= N2`, so the four values are in texel t's row.
            unsafe { _mm_loadu_ps(block[t][c..c + 4].as_ptr()) }
        };
        for c in (0..N2 / 4 * 4).step_by(4) {
            let v: [__m512; 4] = core::array::from_fn(|t| {
                let v = _mm512_castps128_ps512(row(t, c));
                let v = _mm512_insertf32x4::<1>(v, row(t + 4, c));
                let v = _mm512_insertf32x4::<2>(v, row(t + 8, c));
                _mm512_insertf32x4::<3>(v, row(t + 12, c))
            });
            let (t0, t1) = (
                _mm512_unpacklo_ps(v[0], v[1]),
                _mm512_unpackhi_ps(v[0], v[1]),
            );
            let (t2, t3) = (
                _mm512_unpacklo_ps(v[2], v[3]),
                _mm512_unpackhi_ps(v[2], v[3]),
            );
            add(c, _mm512_shuffle_ps::<0x44>(t0, t2));
            add(c + 1, _mm512_shuffle_ps::<0xee>(t0, t2));
            add(c + 2, _mm512_shuffle_ps::<0x44>(t1, t3));
            add(c + 3, _mm512_shuffle_ps::<0xee>(t1, t3));
        }
        if N2 == 1 {
            // SAFETY: the block is sixteen values, one per texel.
            add(0, unsafe { _mm512_loadu_ps(block.as_flattened().as_ptr()) });
        } else {
            (N2 / 4 * 4..N2).for_each(|c| {
                // Two halves of eight inserted lane by lane: sixteen scalar stores and one
                // wide load of them would miss store forwarding.
                let half = |first: usize| {
                    let [x0, x1, x2, x3, x4, x5, x6, x7] =
                        core::array::from_fn(|k| block[first + k][c]);
                    _mm256_castps_pd(_mm256_setr_ps(x0, x1, x2, x3, x4, x5, x6, x7))
                };
                let low = _mm512_castpd256_pd512(half(0));
                add(c, _mm512_castpd_ps(_mm512_insertf64x4::<1>(low, half(8))));
            });
        }
        // SAFETY: both are 64 bytes of plain data.
        let [r, g, b] = acc.map(|v| unsafe { core::mem::transmute::<__m512, [f32; 16]>(v) });
        for (t, o) in o.iter_mut().enumerate() {
            *o = [r[t], g[t], b[t]];
        }
    }
    compose(texels[done..].as_flattened(), l, &mut out[done..]);
}
