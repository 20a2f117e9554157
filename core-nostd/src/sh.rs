//! Real, orthonormal spherical harmonics up to order [`MAX_ORDER`].
//!
//! The convention is stated once, on [`eval_basis`], where the crate's documentation shows it.

use crate::blob::format::VERTEX_BLOCK;
use crate::lanes::{Lanes, Portable};
use crate::math;

/// Highest supported SH order (bands `0..MAX_ORDER`).
pub const MAX_ORDER: usize = 6;
/// Number of coefficients at [`MAX_ORDER`].
pub const MAX_COEFFS: usize = MAX_ORDER * MAX_ORDER;

/// `Â_l = 2π ∫₀¹ t P_l(t) dt`: the clamped cosine `max(cos θ, 0)` as zonal harmonics, in the
/// un-normalised form (π, 2π/3, π/4, 0, −π/24, 0). By Funk–Hecke its coefficient on `y_{l,m}`
/// around a normal `n` is `Â_l · y_{l,m}(n)`.
pub const CLAMPED_COSINE_BANDS: [f32; MAX_ORDER] = [
    core::f32::consts::PI,
    2.0 * core::f32::consts::PI / 3.0,
    core::f32::consts::PI / 4.0,
    0.0,
    -core::f32::consts::PI / 24.0,
    0.0,
];

/// Why an SH routine refused its input.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShError {
    /// The order is 0 or above [`MAX_ORDER`].
    BadOrder,
    /// The output slice is shorter than `order²`.
    OutputTooSmall,
    /// The direction has zero length, or a NaN or infinite component.
    BadDirection,
    /// A light's intensity is negative, NaN or infinite.
    BadIntensity,
}

impl core::fmt::Display for ShError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            ShError::BadOrder => "SH order must be in 1..=6",
            ShError::OutputTooSmall => "output slice shorter than order squared",
            ShError::BadDirection => "direction is zero, NaN or infinite",
            ShError::BadIntensity => "intensity is negative, NaN or infinite",
        })
    }
}

impl core::error::Error for ShError {}

/// Number of coefficients of an order-`order` expansion.
pub const fn coeff_count(order: usize) -> usize {
    order * order
}

/// Coefficient index of band `l`, index `m` (−l..=l).
pub(crate) const fn index(l: usize, m: i32) -> usize {
    ((l * l + l) as isize + m as isize) as usize
}

fn check(order: usize, out_len: usize) -> Result<usize, ShError> {
    if order == 0 || order > MAX_ORDER {
        return Err(ShError::BadOrder);
    }
    let n2 = coeff_count(order);
    if out_len < n2 {
        return Err(ShError::OutputTooSmall);
    }
    Ok(n2)
}

/// The unit vector along `dir`. Any finite non-zero `dir` is accepted: when the squared length
/// would underflow into subnormals (components below ~1e-19, where it loses digits and the
/// result is no longer unit length) or overflow (above ~1e19), the components are first
/// divided by the largest one. The common case pays one extra comparison.
pub(crate) fn normalise(dir: [f32; 3]) -> Result<[f32; 3], ShError> {
    let len2 = dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2];
    if len2.is_normal() {
        let inv = 1.0 / math::sqrt(len2);
        return Ok([dir[0] * inv, dir[1] * inv, dir[2] * inv]);
    }
    if !dir.iter().all(|x| x.is_finite()) {
        return Err(ShError::BadDirection);
    }
    let largest = dir.iter().fold(0.0f32, |m, &x| m.max(math::abs(x)));
    if largest == 0.0 {
        return Err(ShError::BadDirection);
    }
    let d = dir.map(|x| x / largest);
    let inv = 1.0 / math::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    Ok(d.map(|x| x * inv))
}

/// `K_l^m` for `0 ≤ m ≤ l < MAX_ORDER`, from the factorial ratio, in f64.
const fn norm_f64(l: usize, m: usize) -> f64 {
    let mut ratio = 1.0f64; // (l−m)!/(l+m)!
    let mut k = l - m + 1;
    while k <= l + m {
        ratio /= k as f64;
        k += 1;
    }
    math::const_sqrt((2 * l + 1) as f64 / (4.0 * core::f64::consts::PI) * ratio)
}

/// `NORMS[l][m] = K_l^m` as f32, computed at compile time: [`eval_basis`] runs once per ray in
/// the bake (millions of calls per pose) and recomputing factorial ratios and square roots
/// there cost about a quarter of the bake's time.
const NORMS: [[f32; MAX_ORDER]; MAX_ORDER] = {
    let mut table = [[0.0f32; MAX_ORDER]; MAX_ORDER];
    let mut l = 0;
    while l < MAX_ORDER {
        let mut m = 0;
        while m <= l {
            table[l][m] = norm_f64(l, m) as f32;
            m += 1;
        }
        l += 1;
    }
    table
};

/// `RECURRENCE[l][m] = [(2l − 1)/(l − m), (l + m − 1)/(l − m)]` for `l ≥ m + 2`: the three-term
/// recurrence's weights, so that [`eval_basis`] multiplies where it would divide (ten divisions
/// at order 4 were half its time in the occluder proxies' per-vertex loop).
const RECURRENCE: [[[f32; 2]; MAX_ORDER]; MAX_ORDER] = {
    let mut table = [[[0.0f32; 2]; MAX_ORDER]; MAX_ORDER];
    let mut l = 2;
    while l < MAX_ORDER {
        let mut m = 0;
        while m + 2 <= l {
            let k = (l - m) as f64;
            table[l][m] = [
                ((2 * l - 1) as f64 / k) as f32,
                ((l + m - 1) as f64 / k) as f32,
            ];
            m += 1;
        }
        l += 1;
    }
    table
};

/// Evaluates all `order²` basis functions in direction `dir` (normalised here) into `out`.
///
/// # The SH convention (the one place it is stated)
/// - Order `n` means bands `l = 0..n`, so `n²` coefficients; coefficient index `c = l² + l + m`.
/// - Directions are unit vectors `(x, y, z)` with `z = cos θ` and `φ = atan2(y, x)`.
/// - No Condon–Shortley phase: `y_{1,-1} = k·y`, `y_{1,0} = k·z`, `y_{1,1} = k·x` with
///   `k = √(3/4π)`. For `m > 0`: `y_{l,m} = √2 K_l^m P_l^m(cos θ) cos(mφ)` and
///   `y_{l,-m} = √2 K_l^m P_l^m(cos θ) sin(mφ)`, `K_l^m = √((2l+1)/4π · (l−m)!/(l+m)!)`.
/// - Lighting `L` and transfer `t` are projected with the same basis; the shading integral is
///   the dot product `Σ_c L_c t_c` (orthonormality), and the renderer applies albedo / π.
///
/// Uses the Cartesian recurrences (no trigonometry): `P_l^m / sin^m θ` by the three-term
/// recurrence in `z`, and `sin^m θ (cos mφ, sin mφ)` as the real and imaginary parts of
/// `(x + iy)^m`, so it is exact at the poles where `φ` is undefined.
///
/// ```
/// let mut y = [0.0; 4];
/// aprt_core::eval_basis(2, [0.0, 0.0, 2.0], &mut y)?; // any length: normalised here
/// let k = (3.0 / (4.0 * core::f32::consts::PI)).sqrt();
/// assert!((y[2] - k).abs() < 1e-6 && y[1] == 0.0 && y[3] == 0.0); // y_10 = k z
/// # Ok::<(), aprt_core::ShError>(())
/// ```
pub fn eval_basis(order: usize, dir: [f32; 3], out: &mut [f32]) -> Result<(), ShError> {
    check(order, out.len())?;
    let unit = normalise(dir)?;
    match order {
        1 => basis_of::<1>(unit, out),
        2 => basis_of::<2>(unit, out),
        3 => basis_of::<3>(unit, out),
        4 => basis_of::<4>(unit, out),
        5 => basis_of::<5>(unit, out),
        _ => basis_of::<6>(unit, out),
    }
    Ok(())
}

/// [`eval_basis`] at a unit direction for a known order: with `N` a constant the loops unroll
/// and every index folds, about three times as fast as the loops over a run-time order (the
/// bake calls it once per ray, the occluder proxies once per cap).
#[inline(always)]
fn basis_of<const N: usize>([x, y, z]: [f32; 3], out: &mut [f32]) {
    let out = &mut out[..N * N];
    let (mut cm, mut sm) = (1.0f32, 0.0f32); // Re, Im of (x + iy)^m
    let mut pmm = 1.0f32; // (2m−1)!!, P_m^m / sin^m θ without Condon–Shortley phase
    for m in 0..N {
        // p_prev2, p_prev: P̃_{l−2}^m, P̃_{l−1}^m
        let mut p_prev2 = 0.0f32;
        let mut p_prev = pmm;
        for l in m..N {
            let p = if l == m {
                pmm
            } else if l == m + 1 {
                (2 * m + 1) as f32 * z * pmm
            } else {
                let [a, b] = RECURRENCE[l][m];
                a * z * p_prev - b * p_prev2
            };
            if l > m {
                p_prev2 = p_prev;
                p_prev = p;
            }
            let k = NORMS[l][m];
            if m == 0 {
                out[index(l, 0)] = k * p;
            } else {
                let k2 = core::f32::consts::SQRT_2 * k * p;
                out[index(l, m as i32)] = k2 * cm;
                out[index(l, -(m as i32))] = k2 * sm;
            }
        }
        let (ncm, nsm) = (cm * x - sm * y, cm * y + sm * x);
        cm = ncm;
        sm = nsm;
        pmm *= (2 * m + 1) as f32;
    }
}

/// Eight lanes of [`VERTEX_BLOCK`] unit directions (`[axis][lane]`).
pub(crate) type DirectionLanes = [[f32; VERTEX_BLOCK]; 3];

/// [`eval_basis`] of eight unit directions at once, `out[c][lane]`: each lane goes through
/// exactly the operations of the one-direction basis (so it gets the same bits), eight at a
/// time, which the compiler vectorises. Per-vertex lights evaluate one basis per vertex and
/// light; this is their inner loop.
pub(crate) fn eval_basis_lanes(
    order: usize,
    dirs: DirectionLanes,
    out: &mut [[f32; VERTEX_BLOCK]; MAX_COEFFS],
) {
    let dirs = dirs.map(Portable);
    let mut y = BasisArray([Portable::splat(0.0); MAX_COEFFS]);
    match order {
        1 => basis_lanes::<Portable, 1>(dirs, &mut y),
        2 => basis_lanes::<Portable, 2>(dirs, &mut y),
        3 => basis_lanes::<Portable, 3>(dirs, &mut y),
        4 => basis_lanes::<Portable, 4>(dirs, &mut y),
        5 => basis_lanes::<Portable, 5>(dirs, &mut y),
        _ => basis_lanes::<Portable, 6>(dirs, &mut y),
    }
    for (o, y) in out.iter_mut().zip(&y.0).take(order * order) {
        *o = y.0;
    }
}

/// Where [`basis_lanes`] puts each value: `put(l, c, y_c)`, in its own order (by `m`, then
/// `l`), so that a kernel can use a value as it is made instead of storing all `n²`.
pub(crate) trait BasisSink<V> {
    fn put(&mut self, l: usize, c: usize, y: V);
}

/// The basis stored whole, `[c]`.
struct BasisArray<V>([V; MAX_COEFFS]);

impl<V> BasisSink<V> for BasisArray<V> {
    #[inline(always)]
    fn put(&mut self, _: usize, c: usize, y: V) {
        self.0[c] = y;
    }
}

/// `(2m − 1)!!`, `P_m^m / sin^m θ` without the Condon–Shortley phase: exact in f32.
const DOUBLE_FACTORIAL: [f32; MAX_ORDER] = [1.0, 1.0, 3.0, 15.0, 105.0, 945.0];

/// [`basis_of`], lane by lane, in any [`Lanes`], into `sink`: the same operations on each
/// lane, so the same bits. Written one column `m` at a time with the order a constant, so that
/// every loop unrolls and the values stay in registers.
#[inline(always)]
pub(crate) fn basis_lanes<V: Lanes, const N: usize>(
    [x, y, z]: [V; 3],
    sink: &mut impl BasisSink<V>,
) {
    // Re and Im of (x + iy)^m.
    let (mut cm, mut sm) = (V::splat(1.0), V::splat(0.0));
    basis_column::<V, N, 0>(z, (cm, sm), sink);
    macro_rules! columns {
        ($($m:literal)*) => {$(
            if $m < N {
                (cm, sm) = (cm * x - sm * y, cm * y + sm * x);
                basis_column::<V, N, $m>(z, (cm, sm), sink);
            }
        )*};
    }
    columns!(1 2 3 4 5);
}

/// Column `M` of the basis, `y_lm` and `y_l,−m` for `l = M .. N`, from `z` and `(x + iy)^M`.
#[inline(always)]
fn basis_column<V: Lanes, const N: usize, const M: usize>(
    z: V,
    (cm, sm): (V, V),
    sink: &mut impl BasisSink<V>,
) {
    let pmm = DOUBLE_FACTORIAL[M];
    let (mut p_prev2, mut p_prev) = (V::splat(0.0), V::splat(pmm));
    for l in M..N {
        let p = if l == M {
            V::splat(pmm)
        } else if l == M + 1 {
            V::splat((2 * M + 1) as f32) * z * V::splat(pmm)
        } else {
            let [a, b] = RECURRENCE[l][M];
            V::splat(a) * z * p_prev - V::splat(b) * p_prev2
        };
        if l > M {
            p_prev2 = p_prev;
            p_prev = p;
        }
        let k = NORMS[l][M];
        if M == 0 {
            sink.put(l, index(l, 0), V::splat(k) * p);
        } else {
            let k2 = V::splat(core::f32::consts::SQRT_2 * k) * p;
            sink.put(l, index(l, M as i32), k2 * cm);
            sink.put(l, index(l, -(M as i32)), k2 * sm);
        }
    }
}

/// Projects a directional light of `intensity` arriving from `dir` (pointing toward the light):
/// a delta function, so `L_c = intensity · y_c(dir)`. The intensity is finite and at least 0
/// (a light adds radiance); every `|y_c|` is below 1 up to order 6 (the addition theorem
/// bounds it by `√((2l + 1) / 4π)`), so the projection stays finite.
///
/// ```
/// let mut sun = [0.0; 9];
/// aprt_core::project_directional(3, [0.5, -0.8, 0.9], 3.0, &mut sun)?;
/// let dc = 3.0 * 0.5 / core::f32::consts::PI.sqrt(); // 3 · y_00
/// assert!((sun[0] - dc).abs() < 1e-6);
/// # Ok::<(), aprt_core::ShError>(())
/// ```
pub fn project_directional(
    order: usize,
    dir: [f32; 3],
    intensity: f32,
    out: &mut [f32],
) -> Result<(), ShError> {
    let n2 = check(order, out.len())?;
    if !(intensity >= 0.0 && intensity.is_finite()) {
        return Err(ShError::BadIntensity);
    }
    eval_basis(order, dir, out)?;
    for c in &mut out[..n2] {
        *c *= intensity;
    }
    Ok(())
}

/// Rotates a function that is symmetric about +z, given by its un-normalised zonal bands
/// `bands[l]` (as in [`CLAMPED_COSINE_BANDS`]), to be symmetric about `dir`:
/// `out_{l,m} = bands[l] · y_{l,m}(dir)`.
pub fn rotate_zonal(
    order: usize,
    bands: &[f32],
    dir: [f32; 3],
    out: &mut [f32],
) -> Result<(), ShError> {
    let n2 = check(order, out.len())?;
    if bands.len() < order {
        return Err(ShError::OutputTooSmall);
    }
    eval_basis(order, dir, out)?;
    for (c, v) in out[..n2].iter_mut().enumerate() {
        *v *= bands[band_of(c)];
    }
    Ok(())
}

/// The clamped cosine lobe `max(n·ω, 0)` around `normal`: the transfer vector of an
/// unoccluded point (no albedo, no 1/π).
pub fn clamped_cosine(order: usize, normal: [f32; 3], out: &mut [f32]) -> Result<(), ShError> {
    rotate_zonal(order, &CLAMPED_COSINE_BANDS, normal, out)
}

/// Band `l` of coefficient index `c`.
pub const fn band_of(c: usize) -> usize {
    let mut l = 0;
    while (l + 1) * (l + 1) <= c {
        l += 1;
    }
    l
}

#[cfg(test)]
mod tests {
    use super::*;

    const PI: f64 = core::f64::consts::PI;

    #[test]
    fn a_directional_light_needs_a_finite_non_negative_intensity() {
        let mut out = [0.0f32; 36];
        for bad in [f32::NAN, f32::INFINITY, -1.0, -1e-30] {
            assert_eq!(
                project_directional(6, [0.0, 0.0, 1.0], bad, &mut out),
                Err(ShError::BadIntensity),
                "{bad}"
            );
            assert!(out.iter().all(|c| c.is_finite()), "{bad}: {out:?}");
        }
        project_directional(6, [0.0, 0.6, 0.8], 0.0, &mut out).unwrap();
        assert!(out.iter().all(|&c| c == 0.0));
        // Along +z, `y_50 = √(11 / 4π)`, the largest value of the basis.
        project_directional(6, [0.0, 0.0, 1.0], f32::MAX, &mut out).unwrap();
        assert!(out.iter().all(|c| c.is_finite()));
    }

    #[test]
    fn compile_time_norms_match_the_runtime_formula() {
        for (l, row) in NORMS.iter().enumerate() {
            for (m, &table) in row.iter().enumerate().take(l + 1) {
                let mut ratio = 1.0f64;
                for k in (l - m + 1)..=(l + m) {
                    ratio /= k as f64;
                }
                let k = libm::sqrt((2 * l + 1) as f64 / (4.0 * PI) * ratio) as f32;
                assert_eq!(table.to_bits(), k.to_bits(), "l={l} m={m}");
            }
        }
    }

    /// Independent reference: the closed forms of bands 0–2 written out by hand.
    fn low_bands(d: [f64; 3]) -> [f64; 9] {
        let [x, y, z] = d;
        [
            0.5 * (1.0 / PI).sqrt(),
            (3.0 / (4.0 * PI)).sqrt() * y,
            (3.0 / (4.0 * PI)).sqrt() * z,
            (3.0 / (4.0 * PI)).sqrt() * x,
            0.5 * (15.0 / PI).sqrt() * x * y,
            0.5 * (15.0 / PI).sqrt() * y * z,
            0.25 * (5.0 / PI).sqrt() * (3.0 * z * z - 1.0),
            0.5 * (15.0 / PI).sqrt() * x * z,
            0.25 * (15.0 / PI).sqrt() * (x * x - y * y),
        ]
    }

    #[test]
    fn low_bands_match_closed_forms() {
        let dirs = [
            [0.3f32, -0.5, 0.8],
            [0.0, 0.0, 1.0],
            [0.0, 0.0, -1.0],
            [1.0, 0.0, 0.0],
            [-0.2, 0.9, -0.1],
        ];
        for d in dirs {
            let mut out = [0.0f32; 9];
            eval_basis(3, d, &mut out).unwrap();
            let len = ((d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) as f64).sqrt();
            let dn = [d[0] as f64 / len, d[1] as f64 / len, d[2] as f64 / len];
            for (a, b) in out.iter().zip(low_bands(dn)) {
                assert!((*a as f64 - b).abs() < 1e-6, "{d:?}: {a} vs {b}");
            }
        }
    }

    /// Band 3, m = ±3 and m = 0 spot values, from the standard tables (e.g. Sloan 2008).
    #[test]
    fn band_three_closed_forms() {
        let d = [0.48f32, -0.6, 0.64];
        let (x, y, z) = (0.48f64, -0.6f64, 0.64f64);
        let mut out = [0.0f32; 16];
        eval_basis(4, d, &mut out).unwrap();
        let y30 = 0.25 * (7.0 / PI).sqrt() * (5.0 * z * z * z - 3.0 * z);
        let y33 = 0.25 * (35.0 / (2.0 * PI)).sqrt() * (x * x * x - 3.0 * x * y * y);
        let y3m3 = 0.25 * (35.0 / (2.0 * PI)).sqrt() * (3.0 * x * x * y - y * y * y);
        assert!((out[index(3, 0)] as f64 - y30).abs() < 1e-6);
        assert!((out[index(3, 3)] as f64 - y33).abs() < 1e-6);
        assert!((out[index(3, -3)] as f64 - y3m3).abs() < 1e-6);
    }

    #[test]
    fn clamped_cosine_bands_are_funk_hecke_integrals() {
        // Â_l = 2π ∫₀¹ t P_l(t) dt by Simpson's rule on Legendre polynomials.
        for (l, expect) in CLAMPED_COSINE_BANDS.iter().enumerate() {
            let n = 2000;
            let mut acc = 0.0f64;
            for i in 0..=n {
                let t = i as f64 / n as f64;
                let (mut p0, mut p1) = (1.0f64, t);
                let pl = match l {
                    0 => 1.0,
                    _ => {
                        for k in 2..=l {
                            let p2 = ((2 * k - 1) as f64 * t * p1 - (k - 1) as f64 * p0) / k as f64;
                            p0 = p1;
                            p1 = p2;
                        }
                        p1
                    }
                };
                let w = if i == 0 || i == n {
                    1.0
                } else if i % 2 == 1 {
                    4.0
                } else {
                    2.0
                };
                acc += w * t * pl;
            }
            let integral = 2.0 * PI * acc / (3.0 * n as f64);
            assert!(
                (integral - *expect as f64).abs() < 1e-6,
                "band {l}: {integral} vs {expect}"
            );
        }
    }

    #[test]
    fn clamped_cosine_dc_is_pi_times_y00() {
        let mut out = [0.0f32; 36];
        clamped_cosine(6, [0.2, 0.3, -0.9], &mut out).unwrap();
        assert!((out[0] - core::f32::consts::PI * 0.282_094_8).abs() < 1e-6);
        // Against a directional light along the normal, the lobe integrates to cos 0 = 1
        // up to the order-6 truncation of the delta function.
        let mut light = [0.0f32; 36];
        project_directional(6, [0.2, 0.3, -0.9], 1.0, &mut light).unwrap();
        let e: f32 = out.iter().zip(&light).map(|(a, b)| a * b).sum();
        // Σ_l Â_l (2l+1)/4π for l < 6: 0.25 + 0.5 + 0.3125 + 0 − 0.09375 + 0 = 0.96875
        assert!((e - 0.96875).abs() < 1e-5, "{e}");
    }

    #[test]
    fn rejects_bad_input() {
        let mut out = [0.0f32; 36];
        assert_eq!(
            eval_basis(0, [0.0, 0.0, 1.0], &mut out),
            Err(ShError::BadOrder)
        );
        assert_eq!(
            eval_basis(7, [0.0, 0.0, 1.0], &mut out),
            Err(ShError::BadOrder)
        );
        assert_eq!(
            eval_basis(6, [0.0, 0.0, 0.0], &mut out),
            Err(ShError::BadDirection)
        );
        assert_eq!(
            eval_basis(6, [f32::NAN, 0.0, 1.0], &mut out),
            Err(ShError::BadDirection)
        );
        assert_eq!(
            eval_basis(6, [0.0, 0.0, 1.0], &mut out[..35]),
            Err(ShError::OutputTooSmall)
        );
    }

    /// Independent reference by the trigonometric definition in f64: `θ` from `acos z`, `φ`
    /// from `atan2(y, x)`, `P_l^m` by the textbook recurrence in `cos θ` and `sin θ`.
    fn trig_reference(order: usize, d: [f64; 3]) -> [f64; 36] {
        let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        let (theta, phi) = ((d[2] / len).clamp(-1.0, 1.0).acos(), d[1].atan2(d[0]));
        let (ct, st) = (theta.cos(), theta.sin());
        let mut out = [0.0f64; 36];
        for m in 0..order {
            let pmm = (1..=m).fold(1.0, |p, k| p * (2 * k - 1) as f64 * st);
            let (mut p2, mut p1) = (0.0, pmm);
            for l in m..order {
                let p = match l - m {
                    0 => pmm,
                    1 => (2 * m + 1) as f64 * ct * pmm,
                    _ => ((2 * l - 1) as f64 * ct * p1 - (l + m - 1) as f64 * p2) / (l - m) as f64,
                };
                if l > m {
                    (p2, p1) = (p1, p);
                }
                let k = norm_f64(l, m);
                if m == 0 {
                    out[index(l, 0)] = k * p;
                } else {
                    let mf = m as f64;
                    out[index(l, m as i32)] = 2f64.sqrt() * k * p * (mf * phi).cos();
                    out[index(l, -(m as i32))] = 2f64.sqrt() * k * p * (mf * phi).sin();
                }
            }
        }
        out
    }

    /// Order 6 at the poles, along every axis, next to the poles and at extreme direction
    /// lengths. Expected: the poles give exactly the zonal closed form `y_l0(±z) =
    /// (±1)^l √((2l+1)/4π)` with every m ≠ 0 term exactly 0 (the Cartesian recurrence never
    /// divides by sin θ nor calls atan2, so there is nothing to go NaN); elsewhere f32 agrees
    /// with the f64 trigonometric definition to 2e-6 (coefficients are at most 0.93 at order
    /// 6, so this is a few f32 ulps); and the length of `dir` never matters, from 1e-30 to
    /// 1e30 (before the rescaling fix 1e-22 gave a vector of length 1.06 and 1e20 was refused).
    #[test]
    fn order_six_at_poles_axes_and_extreme_lengths() {
        let mut out = [0.0f32; 36];
        for sign in [1.0f32, -1.0] {
            eval_basis(6, [0.0, 0.0, sign], &mut out).unwrap();
            for l in 0..6 {
                for m in -(l as i32)..=(l as i32) {
                    let got = out[index(l, m)];
                    if m == 0 {
                        let want =
                            sign.powi(l as i32) * ((2 * l + 1) as f32 / (4.0 * PI as f32)).sqrt();
                        assert!(
                            (got - want).abs() <= 2.0 * f32::EPSILON * want.abs(),
                            "{l} {got} {want}"
                        );
                    } else {
                        assert_eq!(got, 0.0, "pole {sign}, l {l} m {m}");
                    }
                }
            }
        }
        let near = 1e-20f32;
        let axes_and_poles = [
            [1.0f32, 0.0, 0.0],
            [-1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, -1.0, 0.0],
            [near, 0.0, 1.0],
            [0.0, -near, -1.0],
            [1e-4, 1e-4, 1.0],
            [-0.6, 0.0, 0.8],
        ];
        let scaled = [1e-30f32, 1e-22, 1e-19, 1e19, 1e20, 1e30]
            .into_iter()
            .flat_map(|s| [[0.3 * s, -0.5 * s, 0.8 * s], [0.0, 0.0, -s]]);
        for d in axes_and_poles.into_iter().chain(scaled) {
            eval_basis(6, d, &mut out).unwrap();
            let want = trig_reference(6, d.map(f64::from));
            for (c, (&a, b)) in out.iter().zip(want).enumerate() {
                assert!(
                    a.is_finite() && (a as f64 - b).abs() < 2e-6,
                    "{d:?} c {c}: {a} vs {b}"
                );
            }
        }
        assert_eq!(
            eval_basis(6, [f32::INFINITY, 0.0, 0.0], &mut out),
            Err(ShError::BadDirection)
        );
    }

    #[test]
    fn band_of_matches_index() {
        for l in 0..MAX_ORDER {
            for m in -(l as i32)..=(l as i32) {
                assert_eq!(band_of(index(l, m)), l);
            }
        }
    }
}
