//! One sphere's caps seen from the eight vertices of a block, lane-wise and branch-free in
//! any [`Lanes`] (the module above says what a cap is and how it occludes). Every lane runs
//! the same operations whatever its case (out of reach, inside the sphere, above or cut by the
//! horizon): each case's value is computed and the lane's is selected, so a block costs the
//! same whatever its lanes hold and every implementation of the lanes gives the same bits.
//!
//! The horizon-clipped form factor (Snyder's formula) needs `acos` and `atan`; they are
//! polynomials here, so that they run in vector registers with the same bits on every target:
//! - `acos x = √(1 − x) · Σ_{k=0}^{7} a_k x^k` for `0 ≤ x ≤ 1` (Abramowitz and Stegun 4.4.46,
//!   error at most 2e-8 by their table; 2.2e-8 measured in f64 with the printed coefficients),
//!   and `π − acos(−x)` below 0;
//! - `atan x = x Σ_{k=0}^{8} b_k x^{2k}` for `0 ≤ x ≤ 1` (4.4.49, error at most 2e-8), and
//!   `π/2 − atan(1/x)` above 1, through `atan2(y, x) = atan(min/max)`.
//!
//! In f32 the form factor is then within [`FORM_FACTOR_ERROR`] of the exact f64 one for every
//! cap the proxies keep (`the_lane_form_factor_is_within_its_bound_of_the_exact_one`).

use core::f32::consts::{FRAC_PI_2, PI};

use crate::lanes::Lanes;
use crate::sh::MAX_ORDER;

/// Most the lane-wise form factor differs from the exact f64 one, for caps of `sin²α` from
/// 0.01 (the smallest any cull keeps is larger) to a sphere touching the vertex, at every tilt:
/// the polynomials' 2.2e-8 and f32 rounding of terms up to `π` (5.7e-7 measured at worst, the
/// same bits on every target). Against the whole cosine lobe's `π`, a part in three million.
#[cfg(test)]
pub(crate) const FORM_FACTOR_ERROR: f32 = 1e-6;

/// Abramowitz and Stegun 4.4.46: `acos x ≈ √(1 − x) Σ a_k x^k` on `[0, 1]`, as printed there
/// (f32 rounds them; the test bounds include that).
#[allow(clippy::excessive_precision)]
const ACOS: [f32; 8] = [
    1.570_796_305,
    -0.214_598_801_6,
    0.088_978_987_4,
    -0.050_174_304_6,
    0.030_891_881_0,
    -0.017_088_125_6,
    0.006_670_090_1,
    -0.001_262_491_1,
];

/// Abramowitz and Stegun 4.4.49: `atan x ≈ x Σ b_k x^{2k}` on `[0, 1]`, as printed there.
#[allow(clippy::excessive_precision)]
const ATAN: [f32; 9] = [
    1.0,
    -0.333_331_452_8,
    0.199_935_508_5,
    -0.142_088_994_4,
    0.106_562_639_3,
    -0.075_289_640_0,
    0.042_909_613_8,
    -0.016_165_736_7,
    0.002_866_225_7,
];

/// `Σ c_k x^k` by Horner's rule: a multiply and an add per coefficient, never fused.
#[inline(always)]
fn horner<V: Lanes>(x: V, coefficients: &[f32]) -> V {
    let mut p = V::splat(0.0);
    for &c in coefficients.iter().rev() {
        p = p * x + V::splat(c);
    }
    p
}

/// Arc cosine on `[-1, 1]` (see the module doc for the polynomial and its error).
#[inline(always)]
pub(crate) fn acos<V: Lanes>(x: V) -> V {
    let a = x.abs();
    let p = (V::splat(1.0) - a).max(V::splat(0.0)).sqrt() * horner(a, &ACOS);
    V::select(x.lt(V::splat(0.0)), V::splat(PI) - p, p)
}

/// `atan2(y, x)` for `y, x ≥ 0` (0 for both 0), in `[0, π/2]`.
#[inline(always)]
pub(crate) fn atan2_positive<V: Lanes>(y: V, x: V) -> V {
    let (lo, hi) = (y.min(x), y.max(x));
    let zero = V::splat(0.0);
    let t = V::select(zero.lt(hi), lo / hi, zero);
    let p = t * horner(t * t, &ATAN);
    V::select(x.lt(y), V::splat(FRAC_PI_2) - p, p)
}

/// The irradiance of a sphere of unit radiance whose cap has `sin²α = s2` and cotangent
/// `cot_alpha`, seen at `cos β` from its centre: `π sin²α cos β` while the cap is above the
/// horizon (`cos²β > sin²α`), else Snyder's horizon-clipped form,
/// `(cos β acos y − cot α sin β √(1 − y²)) sin²α + atan(sin β √(1 − y²) / cot α)` with
/// `y = −cot α cos β / sin β`. `horizon` says whether any lane needs the clipped form; where
/// none does it is skipped (the selection would discard it).
#[inline(always)]
pub(crate) fn form_factor<V: Lanes>(s2: V, cot_alpha: V, cos_beta: V, horizon: bool) -> V {
    let (zero, one) = (V::splat(0.0), V::splat(1.0));
    let above = V::splat(PI) * s2 * cos_beta.max(zero);
    if !horizon {
        return above;
    }
    let sin_beta = (one - cos_beta * cos_beta).max(zero).sqrt();
    // `sin β = 0` only where the cap is above or below the horizon: discarded below.
    let y = (zero - cot_alpha * cos_beta / sin_beta)
        .max(V::splat(-1.0))
        .min(one);
    let w = sin_beta * (one - y * y).max(zero).sqrt();
    let clipped = (cos_beta * acos(y) - cot_alpha * w) * s2 + atan2_positive(w, cot_alpha);
    V::select(s2.lt(cos_beta * cos_beta), above, clipped.max(zero))
}

/// The zonal bands of the cosine-weighted cap, `2π ∫_{cos α}^1 t P_l(t) dt`, relative to band
/// 0 (`π sin²α`), from `c = cos α`: `[1, 2(1 + c + c²)/(3(1 + c)), (3c² + 1)/4, c³,
/// (35c⁴ − 10c² − 1)/24, c³(9c² − 5)/4]`, factored so that no band cancels for small caps
/// (all tend to 1), exact for a cap about the normal. At `c = 0` they are the clamped cosine lobe's `[1, 2/3, 1/4, 0, −1/24, 0]`
/// (relative to π): a vertex inside a sphere is a cap of `α = 90°` about its normal.
#[inline(always)]
pub(crate) fn band_ratios<V: Lanes>(c: V) -> [V; MAX_ORDER] {
    let one = V::splat(1.0);
    let (c2, c3) = (c * c, c * c * c);
    [
        one,
        (one + c + c2) * V::splat(2.0 / 3.0) / (one + c),
        (V::splat(3.0) * c2 + one) * V::splat(0.25),
        c3,
        (V::splat(35.0) * c2 * c2 - V::splat(10.0) * c2 - one) * V::splat(1.0 / 24.0),
        c3 * (V::splat(9.0) * c2 - V::splat(5.0)) * V::splat(0.25),
    ]
}

/// One sphere: posed centre, radius, and reach (beyond it its caps are culled).
#[derive(Clone, Copy)]
pub(crate) struct Sphere {
    pub(crate) centre: [f32; 3],
    pub(crate) radius: f32,
    pub(crate) reach: f32,
}

/// The fade of caps near the cull: 0 below `sin²α = cull`, 1 from twice it, a smoothstep
/// between, so that a sphere entering a vertex's reach never pops.
#[derive(Clone, Copy)]
pub(crate) struct Fade {
    cull: f32,
    /// `1 / cull`, infinite when nothing is culled (every cap then weighs 1).
    inverse: f32,
}

impl Fade {
    pub(crate) fn new(cull: f32) -> Fade {
        let inverse = if cull > 0.0 {
            1.0 / cull
        } else {
            f32::INFINITY
        };
        Fade { cull, inverse }
    }

    #[inline(always)]
    fn weight<V: Lanes>(self, s2: V) -> V {
        // A NaN (`0 · ∞`, nothing culled) takes the upper clamp: weight 1.
        let t = ((s2 - V::splat(self.cull)) * V::splat(self.inverse))
            .max(V::splat(0.0))
            .min(V::splat(1.0));
        t * t * (V::splat(3.0) - V::splat(2.0) * t)
    }
}

/// A block's vertices in lanes: posed positions and unit normals.
#[derive(Clone, Copy)]
pub(crate) struct Receivers<V> {
    pub(crate) positions: [V; 3],
    pub(crate) normals: [V; 3],
}

/// One sphere's caps over a block's lanes: form factor `f` (0 where the sphere adds nothing),
/// the axis its bands are taken about (the cap's centre of weight, world frame, not
/// normalised; `+z` where `f` is 0) and the cap's `cos α`.
pub(crate) struct Caps<V> {
    pub(crate) f: V,
    pub(crate) axis: [V; 3],
    pub(crate) cos_alpha: V,
}

/// The offset from each lane's position to the sphere's centre and its squared length.
#[inline(always)]
pub(crate) fn offsets<V: Lanes>(sphere: Sphere, positions: [V; 3]) -> ([V; 3], V) {
    // No closures over lanes in the kernels: a closure is compiled apart from the AVX2
    // function that runs the kernel, so its lane operations would be calls, not instructions.
    let [x, y, z] = sphere.centre;
    let v = [
        V::splat(x) - positions[0],
        V::splat(y) - positions[1],
        V::splat(z) - positions[2],
    ];
    (v, v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
}

/// The caps of `sphere` seen from the lanes of `receivers` that `hit` holds (within the
/// sphere's reach), given their offsets `v` and squared distances `d2` to its centre.
#[inline(always)]
pub(crate) fn caps<V: Lanes>(
    sphere: Sphere,
    fade: Fade,
    receivers: &Receivers<V>,
    (v, d2): ([V; 3], V),
    hit: V::Mask,
) -> Caps<V> {
    let (zero, one) = (V::splat(0.0), V::splat(1.0));
    let n = receivers.normals;
    let r2 = V::splat(sphere.radius * sphere.radius);
    let inside = d2.le(r2);
    let inverse_d = one / d2.sqrt();
    let s2 = r2 * (inverse_d * inverse_d);
    let weight = fade.weight(s2);
    let a = [v[0] * inverse_d, v[1] * inverse_d, v[2] * inverse_d];
    let cos_beta = a[0] * n[0] + a[1] * n[1] + a[2] * n[2];
    // `√(d² − r²)`: `cos α · d` and `cot α · r`, exact as `d → r`.
    let root = (d2 - r2).max(zero).sqrt();
    let cos_alpha = root * inverse_d;
    let cot_alpha = root * V::splat(1.0 / sphere.radius);
    let horizon = V::and(hit, V::le(cos_beta * cos_beta, s2));
    let unweighted = form_factor(s2, cot_alpha, cos_beta, V::bits(horizon) != 0);
    let f = weight * unweighted;
    // The cosine's tilt across the cap, `(n⊥·ω) 1_cap`, is the derivative as the axis turns
    // towards n⊥ of the zonal `max(a·ω − cos α, 0)`, whose band 0 is `π (1 − cos α)²`. To first
    // order it moves the cap's centre of weight towards the normal: the bands are taken about
    // `a + π (1 − cos α)² k / F · n⊥` (`k` the share of the cap the horizon keeps, so the
    // shift vanishes with the cap). Exact in band 0; the other bands are off by the second
    // order of the shift, a few percent for a cap of 40° tilted 40°.
    let inverse_f = one / unweighted;
    let kept = (V::splat(PI) * s2 * cos_beta * inverse_f)
        .max(zero)
        .min(one);
    let gap = one - cos_alpha;
    let shift = kept * V::splat(PI) * gap * gap * inverse_f;
    let valid = V::and(hit, V::or(inside, zero.lt(f)));
    let cap = Caps {
        f,
        axis: [
            a[0] + shift * (n[0] - cos_beta * a[0]),
            a[1] + shift * (n[1] - cos_beta * a[1]),
            a[2] + shift * (n[2] - cos_beta * a[2]),
        ],
        cos_alpha,
    };
    let whole_lobe = Caps {
        f: V::splat(PI),
        axis: n,
        cos_alpha: zero,
    };
    let nothing = Caps {
        f: zero,
        axis: [zero, zero, one],
        cos_alpha: zero,
    };
    Caps::select(valid, Caps::select(inside, whole_lobe, cap), nothing)
}

impl<V: Lanes> Caps<V> {
    /// `a`'s lanes where `mask` holds, `b`'s elsewhere.
    #[inline(always)]
    fn select(mask: V::Mask, a: Caps<V>, b: Caps<V>) -> Caps<V> {
        Caps {
            f: V::select(mask, a.f, b.f),
            axis: [
                V::select(mask, a.axis[0], b.axis[0]),
                V::select(mask, a.axis[1], b.axis[1]),
                V::select(mask, a.axis[2], b.axis[2]),
            ],
            cos_alpha: V::select(mask, a.cos_alpha, b.cos_alpha),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{FORM_FACTOR_ERROR, acos, atan2_positive, band_ratios, form_factor};
    use crate::lanes::{Lanes, Portable};

    #[test]
    fn acos_is_within_its_bound_on_the_whole_interval() {
        let mut worst = 0.0f64;
        for k in 0..=20_000 {
            let x = -1.0 + k as f32 / 10_000.0;
            let got = acos(Portable::splat(x)).0[0];
            worst = worst.max((f64::from(got) - libm::acos(f64::from(x))).abs());
        }
        // The polynomial's 2.2e-8 and f32 rounding: of the Horner chain, of the square root and,
        // below 0, of `π − p` (f32's π is 8.7e-8 short, and half an ulp at π is 1.2e-7).
        assert!(worst < 5e-7, "{worst:e}");
    }

    #[test]
    fn atan2_is_within_its_bound_in_the_first_quadrant() {
        let mut worst = 0.0f64;
        for i in 0..=400 {
            for j in 0..=400 {
                let (y, x) = (i as f32 / 40.0, j as f32 / 40.0);
                let got = atan2_positive(Portable::splat(y), Portable::splat(x)).0[0];
                let want = libm::atan2(f64::from(y), f64::from(x));
                worst = worst.max((f64::from(got) - want).abs());
            }
        }
        assert!(worst < 2e-7, "{worst:e}");
    }

    /// Snyder's irradiance of a unit-radiance sphere of `sin α = s`, `cos β = ct`, in f64.
    fn exact_form_factor(s: f64, ct: f64) -> f64 {
        let s2 = s * s;
        if ct * ct > s2 {
            return core::f64::consts::PI * s2 * ct.max(0.0);
        }
        let st = (1.0 - ct * ct).max(0.0).sqrt();
        let x = (1.0 - s2).max(0.0).sqrt() / s;
        // Straight up or down with the sphere touching the vertex: the half space around ±n.
        let y = match st > 0.0 {
            true => (-x * ct / st).clamp(-1.0, 1.0),
            false => -ct.signum(),
        };
        let w = st * (1.0 - y * y).max(0.0).sqrt();
        ((ct * libm::acos(y) - x * w) * s2 + libm::atan2(w, x)).max(0.0)
    }

    /// The lane-wise form factor against the exact one at heights from a sphere touching the
    /// vertex to `sin²α = 0.01`, and tilts from the normal to straight below, which puts the
    /// horizon through most caps; the bound holds in every lane whatever its neighbours need.
    #[test]
    fn the_lane_form_factor_is_within_its_bound_of_the_exact_one() {
        let (mut worst, mut clipped) = (0.0f64, 0);
        for i in 0..=300 {
            let s2 = 1.0 - 0.99 * (i as f32 / 300.0);
            let (d, r) = (1.0f32, s2.sqrt());
            let root = (d * d - r * r).max(0.0).sqrt();
            for j in (0..=400).step_by(8) {
                let ct: [f32; 8] = core::array::from_fn(|l| -1.0 + (j + l) as f32 / 200.0);
                let ct = ct.map(|c| c.clamp(-1.0, 1.0));
                let got = form_factor(
                    Portable::splat(s2),
                    Portable::splat(root / r),
                    Portable(ct),
                    true,
                );
                for (l, &c) in ct.iter().enumerate() {
                    let want = exact_form_factor(f64::from(r), f64::from(c));
                    worst = worst.max((f64::from(got.0[l]) - want).abs());
                    clipped += usize::from(c * c <= s2);
                }
            }
        }
        assert!(clipped > 10_000, "{clipped}");
        assert!(worst < f64::from(FORM_FACTOR_ERROR), "{worst:e}");
    }

    /// Without the horizon's lanes the form factor is the unclipped one, and with them the two
    /// meet continuously where the horizon starts to cut the cap.
    #[test]
    fn the_form_factor_is_continuous_at_the_horizon() {
        for s2 in [0.02f32, 0.1, 0.5, 0.9] {
            let s = s2.sqrt();
            let root = (1.0 - s2).sqrt();
            let at = |ct: f32| {
                form_factor(
                    Portable::splat(s2),
                    Portable::splat(root / s),
                    Portable::splat(ct),
                    true,
                )
                .0[0]
            };
            let (above, below) = (at(s * (1.0 + 1e-6)), at(s * (1.0 - 1e-6)));
            assert!((above - below).abs() < 1e-5, "{s2}: {above} {below}");
        }
    }

    /// The bands of a cap about the normal against their integrals by the midpoint rule, and
    /// the clamped cosine lobe at `α = 90°`.
    #[test]
    fn band_ratios_are_the_cosine_weighted_caps_bands() {
        let legendre = |l: usize, t: f64| match l {
            0 => 1.0,
            1 => t,
            2 => (3.0 * t * t - 1.0) / 2.0,
            3 => (5.0 * t.powi(3) - 3.0 * t) / 2.0,
            4 => (35.0 * t.powi(4) - 30.0 * t * t + 3.0) / 8.0,
            _ => (63.0 * t.powi(5) - 70.0 * t.powi(3) + 15.0 * t) / 8.0,
        };
        for c in [0.0f32, 0.3, 0.7, 0.95, 0.999] {
            let ratios = band_ratios(Portable::splat(c));
            let band = |l: usize| {
                let steps = 20_000;
                let h = (1.0 - f64::from(c)) / steps as f64;
                (0..steps)
                    .map(|k| {
                        let t = f64::from(c) + (k as f64 + 0.5) * h;
                        t * legendre(l, t) * h
                    })
                    .sum::<f64>()
            };
            for (l, ratio) in ratios.iter().enumerate() {
                let want = band(l) / band(0);
                assert!((f64::from(ratio.0[0]) - want).abs() < 2e-5, "c {c}, l {l}");
            }
        }
        let lobe = band_ratios(Portable::splat(0.0)).map(|r| r.0[0]);
        let want = [1.0, 2.0 / 3.0, 0.25, 0.0, -1.0 / 24.0, 0.0];
        assert!(lobe.iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-7));
    }
}
