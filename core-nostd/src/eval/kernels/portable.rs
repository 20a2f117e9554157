//! The portable kernels: plain Rust over eight-lane arrays, which the compiler vectorises
//! wherever the target has vectors (SSE2 on x86-64, NEON on aarch64, `simd128` on wasm32 built
//! with it) and runs as scalar code elsewhere (thumbv7em). Rust never fuses a multiply and an
//! add, so every target computes the same bits; they are the reference every wider kernel
//! (`x86.rs`) reproduces operation for operation.
//!
//! What vectorises (x86-64 SSE2 asm of `Model::shade_rig`, which inlines `shade_block` for
//! all three encodings: `mulps`/`addps` in the eight-lane loops, `cvtdq2ps` after
//! shift-based sign extension for i8, the f16 decode as `pand`/`pslld`/`mulps`): the
//! single-bone shading loop and both transfer kernels; the mixed-bone shading path is
//! per-lane scalar.

use super::{Decode, IdentityWeights};
use crate::blob::format::{MAX_COEF_DIMS, VERTEX_BLOCK};

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
            let terms = rows.iter().zip(qb).map(|(r, q)| q * r[l].value());
            terms.fold(0.0, |s, x| s + x)
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

/// One texel of an SH light map, `Σ_c l_c t_c` in RGB: one accumulator per colour, the
/// coefficients in ascending order, `acc += l_c · t_c`. The reference every composition
/// kernel reproduces bit for bit, and the kernels' tail.
#[inline(always)]
pub(crate) fn texel(t: &[f32], l: &[[f32; 3]]) -> [f32; 3] {
    let mut acc = [0.0f32; 3];
    for (&x, lc) in t.iter().zip(l) {
        for (a, c) in acc.iter_mut().zip(lc) {
            *a += c * x;
        }
    }
    acc
}

/// Texel-major maps of n² = `N2` coefficients composed under one lighting `l`, eight texels
/// at a time: each block's coefficient c, read across its eight texels (a transposition, which
/// the constant stride lets the compiler do in registers), multiplies the broadcast `l_c` in
/// eight lanes, so each lane performs [`texel`]'s multiplies and adds in its order. The
/// remaining `out.len() mod 8` texels go through [`texel`].
///
/// On x86-64 with SSE2 only (`mulps`/`addps`, the transposition in `movss`/`shufps`/
/// `unpcklps`) this composes a 512 × 512 map 1.40× (order 3) and 1.49× (order 6) as fast as
/// one texel at a time, checks included (`cargo bench -p aprt-tests --bench lightmap` with the
/// AVX kernels switched off, one run); the transposition, not the arithmetic, is its cost.
#[inline(always)]
pub(crate) fn compose<const N2: usize>(maps: &[f32], l: &[[f32; 3]; N2], out: &mut [[f32; 3]]) {
    let texels = maps.as_chunks::<N2>().0;
    let (blocks, tail) = texels.as_chunks::<VERTEX_BLOCK>();
    let (out_blocks, out_tail) = out.as_chunks_mut::<VERTEX_BLOCK>();
    for (block, o) in blocks.iter().zip(out_blocks) {
        *o = compose_block(block, l);
    }
    for (t, o) in tail.iter().zip(out_tail) {
        *o = texel(t, l);
    }
}

/// Eight texels: `out[lane] = Σ_c l_c block[lane][c]`, lane-wise as [`texel`].
#[inline(always)]
fn compose_block<const N2: usize>(
    block: &[[f32; N2]; VERTEX_BLOCK],
    l: &[[f32; 3]; N2],
) -> [[f32; 3]; VERTEX_BLOCK] {
    let mut acc = [[0.0f32; VERTEX_BLOCK]; 3];
    for (c, lc) in l.iter().enumerate() {
        let column: [f32; VERTEX_BLOCK] = core::array::from_fn(|lane| block[lane][c]);
        for (a, x) in acc.iter_mut().zip(lc) {
            for lane in 0..VERTEX_BLOCK {
                a[lane] += x * column[lane];
            }
        }
    }
    core::array::from_fn(|lane| [acc[0][lane], acc[1][lane], acc[2][lane]])
}
