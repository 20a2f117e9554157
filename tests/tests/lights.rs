//! The core's lights (`aprt_core::Light`) against references derived here, never against its
//! own output: the ZH bands (eq. 2 of *Irradiance Rigs*) and their derivative (eq. 3) against
//! Gauss–Legendre quadrature of `2π ∫ P_l` in f64, the rotated projection against quadrature
//! of `y_c` over the light's cap, the gradient against differences of the projection at
//! displaced points, the horizon-clipped sphere's closed form against a quadrature of
//! `∫_cap max(cos, 0)`, and the SH path against the Funk–Hecke series.

// Indexed loops over channels and coefficients read like the formulas they check.
#![allow(clippy::needless_range_loop)]

use aprt_core::{
    DirectionalLight, Light, LightError, MAX_ORDER, PointLight, Rgb, SphereLight, Window,
    apply_window, eval_basis, irradiance_sh, sphere_light_bands, sphere_light_derivative_bands,
};
use aprt_tests::quadrature::gauss_legendre;

const PI: f64 = std::f64::consts::PI;

/// `P_l(t)` by the three-term recurrence.
fn legendre(l: usize, t: f64) -> f64 {
    let (mut p0, mut p1) = (1.0, t);
    if l == 0 {
        return 1.0;
    }
    for k in 2..=l {
        let p2 = ((2 * k - 1) as f64 * t * p1 - (k - 1) as f64 * p0) / k as f64;
        (p0, p1) = (p1, p2);
    }
    p1
}

/// `∫_a^b f` by `panels` panels of a 16-point Gauss–Legendre rule.
fn integrate(a: f64, b: f64, panels: usize, f: impl Fn(f64) -> f64) -> f64 {
    let (mut t, mut w) = ([0.0f64; 16], [0.0f64; 16]);
    gauss_legendre(16, &mut t, &mut w);
    let h = (b - a) / panels as f64;
    let mut acc = 0.0;
    for p in 0..panels {
        let lo = a + p as f64 * h;
        for i in 0..16 {
            acc += w[i] * 0.5 * h * f(lo + 0.5 * h * (t[i] + 1.0));
        }
    }
    acc
}

/// Reference ZH band `2π ∫_{cos α}^1 P_l(t) dt` of a sphere of radius `r` at distance `d`, in
/// f64 (16 Gauss nodes integrate these degree-≤5 polynomials exactly).
fn zh_reference(l: usize, r: f64, d: f64) -> f64 {
    if d < r {
        return if l == 0 { 4.0 * PI } else { 0.0 };
    }
    let c = (1.0 - (r / d).powi(2)).max(0.0).sqrt();
    2.0 * PI * integrate(c, 1.0, 1, |t| legendre(l, t))
}

/// `Â_l = 2π ∫₀¹ t P_l(t) dt`.
fn clamped_cosine_reference(l: usize) -> f64 {
    2.0 * PI * integrate(0.0, 1.0, 1, |t| t * legendre(l, t))
}

fn sphere(position: [f32; 3], radius: f32, radiance: Rgb) -> Light {
    Light::Sphere(SphereLight {
        position,
        radius,
        radiance,
    })
}

/// Eq. 2 at every band against quadrature, from tiny lights to the surface. The bands scale
/// like `π sin²α`; the f32 closed form agrees to 4e-6 of that scale (tens of ulps).
#[test]
fn zh_bands_match_quadrature() {
    for ratio in [
        1e-4f32, 1e-2, 0.1, 0.5, 0.9, 0.99, 0.999, 0.99999, 0.9999999, 1.0,
    ] {
        let (r, d) = (ratio, 1.0f32);
        let got = sphere_light_bands(r, d).unwrap();
        let scale = PI * (r as f64 / d as f64).powi(2);
        for (l, &g) in got.iter().enumerate() {
            let want = zh_reference(l, r as f64, d as f64);
            assert!(
                (g as f64 - want).abs() <= 4e-6 * scale,
                "r/d {ratio} band {l}: {g} vs {want}"
            );
        }
    }
    // Scale invariance: only r/d matters.
    let (a, b) = (
        sphere_light_bands(0.3, 1.0).unwrap(),
        sphere_light_bands(3e-20, 1e-19).unwrap(),
    );
    for (x, y) in a.iter().zip(b) {
        assert!((x - y).abs() < 1e-6, "{a:?} {b:?}");
    }
    assert_eq!(
        sphere_light_bands(2.0, 1.0).unwrap(),
        [4.0 * std::f32::consts::PI, 0.0, 0.0, 0.0, 0.0, 0.0]
    );
}

/// Eq. 3 against central differences (in f64, of the quadrature reference) of `−d/dd` eq. 2,
/// with a step below a thousandth of the gap `d − r`; agreement to 1e-5 of `2π r²/(d³ cos α)`, the
/// derivative's scale.
#[test]
fn zh_derivative_matches_differences() {
    for ratio in [1e-3f32, 0.1, 0.5, 0.9, 0.99, 0.999] {
        let (r, d) = (ratio as f64, 1.0f64);
        let got = sphere_light_derivative_bands(ratio, 1.0).unwrap();
        let h = (1e-5 * d).min((d - r) / 1000.0);
        let c = (1.0 - r * r / (d * d)).sqrt();
        let scale = 2.0 * PI * r * r / (d * d * d * c);
        for (l, &g) in got.iter().enumerate() {
            let want = -(zh_reference(l, r, d + h) - zh_reference(l, r, d - h)) / (2.0 * h);
            assert!(
                (g as f64 - want).abs() <= 1e-5 * scale,
                "r/d {ratio} band {l}: {g} vs {want}"
            );
        }
    }
}

/// An orthonormal pair perpendicular to the unit `w`, by cross products.
fn frame(w: [f64; 3]) -> ([f64; 3], [f64; 3]) {
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let helper = if w[0].abs() < 0.6 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    let e1 = cross(w, helper);
    let n = (e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]).sqrt();
    let e1 = e1.map(|x| x / n);
    (e1, cross(w, e1))
}

/// `∫_cap y_c` over the cap of half-angle α around `w`: Gauss–Legendre in `t = cos` (from the
/// cap's axis), uniform in the azimuth. Every `y_c` of order ≤ 6 is a polynomial of degree ≤ 5
/// on the sphere, which 8 × 12 nodes integrate exactly.
fn cap_projection(order: usize, w: [f64; 3], cos_alpha: f64) -> [f64; 36] {
    let (e1, e2) = frame(w);
    let (mut t, mut wt) = ([0.0f64; 8], [0.0f64; 8]);
    gauss_legendre(8, &mut t, &mut wt);
    let mut out = [0.0f64; 36];
    let mut y = [0.0f32; 36];
    for i in 0..8 {
        let ti = cos_alpha + (1.0 - cos_alpha) * 0.5 * (t[i] + 1.0);
        let st = (1.0 - ti * ti).max(0.0).sqrt();
        for j in 0..12 {
            let phi = 2.0 * PI * j as f64 / 12.0;
            let dir: [f64; 3] =
                std::array::from_fn(|a| ti * w[a] + st * (phi.cos() * e1[a] + phi.sin() * e2[a]));
            eval_basis(order, dir.map(|x| x as f32), &mut y).unwrap();
            let weight = wt[i] * 0.5 * (1.0 - cos_alpha) * 2.0 * PI / 12.0;
            for c in 0..order * order {
                out[c] += weight * y[c] as f64;
            }
        }
    }
    out
}

/// The rotated projection equals the quadrature of the cap's indicator times `y_c` (times the
/// radiance), at every coefficient, for lights in several directions and sizes; a point inside
/// the light sees `4π L` in band 0 alone.
#[test]
fn projection_matches_cap_quadrature() {
    let radiance = [1.0f32, 0.5, 2.0];
    let at = [0.3f32, -0.2, 0.1];
    for (position, radius) in [
        ([0.3f32, -0.2, 5.0], 0.4f32),
        ([2.0, 1.0, -1.5], 1.0),
        ([-1.0, 0.1, 0.2], 1.2),
        ([0.3, 3.0, 0.1], 2.9999),
        ([9.0, -7.0, 3.0], 0.01),
    ] {
        let light = sphere(position, radius, radiance);
        let mut sh = [[0.0f32; 3]; 36];
        light.add_radiance_sh(6, at, &mut sh).unwrap();
        let v: [f64; 3] = std::array::from_fn(|a| position[a] as f64 - at[a] as f64);
        let d = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        let cos_alpha = (1.0 - (radius as f64 / d).powi(2)).max(0.0).sqrt();
        let want = cap_projection(6, v.map(|x| x / d), cos_alpha);
        let scale = want.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        for c in 0..36 {
            for k in 0..3 {
                let w = want[c] * radiance[k] as f64;
                assert!(
                    (sh[c][k] as f64 - w).abs() <= 2e-5 * scale * radiance[k] as f64,
                    "light {position:?} r {radius} c {c}: {} vs {w}",
                    sh[c][k]
                );
            }
        }
    }
    let mut sh = [[0.0f32; 3]; 36];
    sphere([0.0; 3], 1.0, radiance)
        .add_radiance_sh(6, [0.2, 0.1, 0.0], &mut sh)
        .unwrap();
    let dc = 4.0 * PI * 0.5 / PI.sqrt();
    for k in 0..3 {
        assert!((sh[0][k] as f64 - dc * radiance[k] as f64).abs() < 1e-5);
    }
    assert!(sh[1..].iter().flatten().all(|&x| x == 0.0));
}

/// The gradient against fourth-order central differences of the projection at `at ± δ e_i`,
/// `±2δ e_i`, for all three axes. With `δ = d/100` the difference's truncation is about
/// `(δ/d)⁴ 5⁵/30 ≈ 1e-6` and its f32 rounding `1.5 ε d/δ ≈ 2e-5` of `max |L| / d`; the
/// gradient's own stencil adds 2e-5: a tolerance of 2e-4 of `max |L| / d` holds with margin.
#[test]
fn gradient_matches_differences_of_the_projection() {
    let at = [0.1f32, 0.2, -0.3];
    let lights = [
        sphere([0.4, -1.5, 2.0], 0.5, [1.0, 2.0, 0.5]),
        sphere([1.0, 0.6, -0.1], 0.6, [3.0, 1.0, 1.0]),
        sphere([-4.0, 3.0, 5.0], 0.2, [1.0; 3]),
        Light::Point(PointLight {
            position: [-0.5, 1.0, 0.8],
            intensity: [2.0, 1.0, 0.5],
        }),
    ];
    for light in lights {
        let (Light::Sphere(SphereLight { position, .. })
        | Light::Point(PointLight { position, .. })) = light
        else {
            unreachable!()
        };
        let d = (0..3)
            .map(|a| ((position[a] - at[a]) as f64).powi(2))
            .sum::<f64>()
            .sqrt();
        let mut g = [[[0.0f32; 3]; 36]; 3];
        let [gx, gy, gz] = &mut g;
        light.add_gradient_sh(6, at, [gx, gy, gz]).unwrap();
        let project = |p: [f32; 3]| {
            let mut sh = [[0.0f32; 3]; 36];
            light.add_radiance_sh(6, p, &mut sh).unwrap();
            sh
        };
        let base = project(at);
        let scale = base.iter().flatten().fold(0.0f32, |m, x| m.max(x.abs())) as f64 / d;
        let delta = (d / 100.0) as f32;
        for axis in 0..3 {
            let shifted = |k: f32| {
                let mut p = at;
                p[axis] += k * delta;
                project(p)
            };
            let (p1, m1, p2, m2) = (shifted(1.0), shifted(-1.0), shifted(2.0), shifted(-2.0));
            for c in 0..36 {
                for k in 0..3 {
                    let fd = (8.0 * (p1[c][k] as f64 - m1[c][k] as f64)
                        - (p2[c][k] as f64 - m2[c][k] as f64))
                        / (12.0 * delta as f64);
                    assert!(
                        (g[axis][c][k] as f64 - fd).abs() <= 2e-4 * scale,
                        "{light:?} axis {axis} c {c}: {} vs {fd}",
                        g[axis][c][k]
                    );
                }
            }
        }
    }
    // Directional lights are the same everywhere.
    let sun = Light::Directional(DirectionalLight {
        direction: [0.3, 0.9, 0.2],
        irradiance: [1.0; 3],
    });
    let mut g = [[[0.0f32; 3]; 9]; 3];
    let [gx, gy, gz] = &mut g;
    sun.add_gradient_sh(3, at, [gx, gy, gz]).unwrap();
    assert_eq!(g, [[[0.0; 3]; 9]; 3]);
}

/// `∫_cap max(n·x, 0)` for a cap of half-angle α whose axis is at `cos θ` from the normal: the
/// azimuth integral in closed form (`∫₀^{2π} max(a + b cos φ, 0) dφ`), Gauss–Legendre in the
/// polar cosine `t` split at `t = sin θ`, where the cap meets the horizon.
fn clipped_cap_reference(cos_alpha: f64, cos_theta: f64) -> f64 {
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    let ring = |t: f64| {
        let (a, b) = (t * cos_theta, (1.0 - t * t).max(0.0).sqrt() * sin_theta);
        if a >= b {
            2.0 * PI * a
        } else if a <= -b {
            0.0
        } else {
            2.0 * (a * (-a / b).clamp(-1.0, 1.0).acos() + (b * b - a * a).max(0.0).sqrt())
        }
    };
    if sin_theta > cos_alpha && sin_theta < 1.0 {
        integrate(cos_alpha, sin_theta, 64, ring) + integrate(sin_theta, 1.0, 64, ring)
    } else {
        integrate(cos_alpha, 1.0, 64, ring)
    }
}

/// Horizon-clipped sphere lights: Snyder's closed form against the quadrature, at several
/// angles from fully visible through grazing to fully below the horizon, for small, large and
/// nearly touching lights; to 2e-6 of the normal-incidence irradiance `π L sin²α`.
#[test]
fn clipped_sphere_matches_quadrature() {
    for ratio in [0.05f32, 0.3, 0.7, 0.95, 0.999, 0.999999, 1.0] {
        let s = ratio as f64;
        let cos_alpha = (1.0 - s * s).max(0.0).sqrt();
        let light = sphere([0.0, 0.0, 1.0], ratio, [1.0, 2.0, 3.0]);
        for cos_theta in [
            1.0,
            0.9,
            s * 1.001,
            s,
            s * 0.999,
            0.5 * s,
            0.01,
            0.0,
            -0.01,
            -0.5 * s,
            -0.999 * s,
            -s,
            -1.0,
        ] {
            let ct = (cos_theta as f32).clamp(-1.0, 1.0);
            let st = (1.0 - ct * ct).max(0.0).sqrt();
            let got = light.irradiance([0.0; 3], [st, 0.0, ct]).unwrap();
            let want = clipped_cap_reference(cos_alpha, ct as f64);
            for k in 0..3 {
                let w = want * (k + 1) as f64;
                assert!(
                    got[k].is_finite()
                        && (got[k] as f64 - w).abs() <= 2e-6 * PI * s * s * (k + 1) as f64,
                    "r/d {ratio} cos θ {ct}: {} vs {w}",
                    got[k]
                );
            }
        }
    }
}

/// Σ_{l<order} Â_l zh_l (2l+1)/4π P_l(cos θ): by Funk–Hecke, what the SH path must give for a
/// zonal light whose axis is at `cos θ` from the normal.
fn funk_hecke(order: usize, zh: impl Fn(usize) -> f64, cos_theta: f64) -> f64 {
    (0..order)
        .map(|l| {
            clamped_cosine_reference(l) * zh(l) * (2 * l + 1) as f64 / (4.0 * PI)
                * legendre(l, cos_theta)
        })
        .sum()
}

/// A fully visible sphere light: the exact path is `π L r²/d² cos θ`, and the SH path equals
/// the Funk–Hecke series of its truncation (to 1e-5 of `π L sin²α`). Its error against the
/// exact value shrinks with the order (orders 3 = 4 and 5 = 6, since `Â_3 = Â_5 = 0`): the
/// worst of the angles tried, 6.2% of `π L sin²α` at order 3 and 3.0% at order 6 (r/d = 0.1).
#[test]
fn visible_sphere_exact_and_sh_converge() {
    let (r, dist) = (0.1f32, 1.0f32);
    let s2 = (r as f64 / dist as f64).powi(2);
    let light = sphere([0.0, 0.0, dist], r, [2.0, 1.0, 0.5]);
    let mut worst = [0.0f64; 7];
    for cos_theta in [1.0f64, 0.8, 0.5, 0.2, 0.11] {
        let ct = cos_theta as f32;
        let normal = [(1.0 - ct * ct).sqrt(), 0.0, ct];
        let exact = light.irradiance([0.0; 3], normal).unwrap();
        let want_exact = PI * s2 * ct as f64;
        for order in 1..=MAX_ORDER {
            let mut sh = [[0.0f32; 3]; 36];
            light.add_radiance_sh(order, [0.0; 3], &mut sh).unwrap();
            let e = irradiance_sh(order, &sh, normal).unwrap();
            let series = funk_hecke(order, |l| zh_reference(l, r as f64, dist as f64), ct as f64);
            for (k, scale) in [2.0f64, 1.0, 0.5].into_iter().enumerate() {
                assert!((exact[k] as f64 - scale * want_exact).abs() <= 1e-6 * scale * want_exact);
                assert!(
                    (e[k] as f64 - scale * series).abs() <= 1e-5 * scale * PI * s2,
                    "order {order} cos θ {ct}: {} vs {}",
                    e[k],
                    scale * series
                );
            }
            let rel = (e[1] as f64 - want_exact).abs() / (PI * s2);
            worst[order] = worst[order].max(rel);
        }
    }
    println!("visible sphere r/d 0.1, max |sh - exact| / (π L sin²α), orders 1..6: {worst:?}");
    assert!(worst[5] <= worst[3] && worst[6] <= worst[4] && worst[4] <= worst[2]);
    assert!((worst[3] - 0.062).abs() < 0.002, "{worst:?}");
    assert!((worst[6] - 0.031).abs() < 0.002, "{worst:?}");
}

/// Ramamoorthi–Hanrahan: a directional light of irradiance E through bands 0..2 gives
/// `E (1/4 + cos θ/2 + 5/32 (3 cos²θ − 1))`: 1.0625 E facing it, 0.09375 E at the horizon and
/// 0.0625 E facing away; order 6 facing it gives 0.96875 E. A point light is the same with
/// `E = I/d²`.
#[test]
fn directional_and_point_match_ramamoorthi_hanrahan() {
    let e = [1.0f32, 2.0, 4.0];
    let sun = Light::Directional(DirectionalLight {
        direction: [0.0, 0.0, 3.0],
        irradiance: e,
    });
    let lamp = Light::Point(PointLight {
        position: [0.0, 0.0, 2.0],
        intensity: e.map(|x| 4.0 * x),
    });
    for light in [sun, lamp] {
        let mut sh3 = [[0.0f32; 3]; 9];
        light.add_radiance_sh(3, [0.0; 3], &mut sh3).unwrap();
        let mut sh6 = [[0.0f32; 3]; 36];
        light.add_radiance_sh(6, [0.0; 3], &mut sh6).unwrap();
        for (normal, want3, exact) in [
            ([0.0f32, 0.0, 1.0], 1.0625f32, 1.0f32),
            ([1.0, 0.0, 0.0], 0.09375, 0.0),
            ([0.0, 0.0, -1.0], 0.0625, 0.0),
            (
                [0.0, 0.6, 0.8],
                0.25 + 0.4 + 5.0 / 32.0 * (3.0 * 0.64 - 1.0),
                0.8,
            ),
        ] {
            let got = irradiance_sh(3, &sh3, normal).unwrap();
            let ex = light.irradiance([0.0; 3], normal).unwrap();
            for k in 0..3 {
                assert!(
                    (got[k] - want3 * e[k]).abs() < 1e-5 * e[k],
                    "{normal:?} {got:?}"
                );
                // The lamp is a sphere of `POINT_LIGHT_RADIUS` r, 2 away: the part of it
                // above the horizon adds `8/3π · r/d` of `I/d²` there (1.06e-4).
                let tolerance = match light {
                    Light::Point(_) => 1e-6 + aprt_core::POINT_LIGHT_RADIUS / 2.0,
                    _ => 1e-6,
                };
                assert!(
                    (ex[k] - exact * e[k]).abs() < tolerance * e[k],
                    "{normal:?} {ex:?}"
                );
            }
        }
        let up = irradiance_sh(6, &sh6, [0.0, 0.0, 1.0]).unwrap();
        for k in 0..3 {
            assert!((up[k] - 0.96875 * e[k]).abs() < 1e-5 * e[k]);
        }
    }
}

/// The deringing window's cost, the figures in `Window`'s documentation: a directional light of
/// irradiance 1 along +z, normals at 3601 polar angles (the irradiance is zonal), the largest
/// error against `max(cos θ, 0)` and the most negative irradiance, per order and window.
#[test]
fn window_cost() {
    let windows = [None, Some(Window::Hann), Some(Window::Lanczos)];
    let documented: [[(f32, f32); 4]; 3] = [
        [
            (0.094, -0.040),
            (0.094, -0.040),
            (0.059, -0.031),
            (0.059, -0.031),
        ],
        [
            (0.297, -0.047),
            (0.172, -0.022),
            (0.144, -0.016),
            (0.124, -0.012),
        ],
        [
            (0.207, -0.034),
            (0.151, -0.019),
            (0.124, -0.013),
            (0.106, -0.011),
        ],
    ];
    let sun = Light::Directional(DirectionalLight {
        direction: [0.0, 0.0, 1.0],
        irradiance: [1.0; 3],
    });
    for (w, window) in windows.into_iter().enumerate() {
        for order in 3..=6 {
            let mut sh = [[0.0f32; 3]; 36];
            sun.add_radiance_sh(order, [0.0; 3], &mut sh).unwrap();
            if let Some(window) = window {
                apply_window(order, window, &mut sh).unwrap();
            }
            let (mut err, mut lowest) = (0.0f32, f32::INFINITY);
            for i in 0..=3600 {
                let theta = std::f32::consts::PI * i as f32 / 3600.0;
                let e = irradiance_sh(order, &sh, [theta.sin(), 0.0, theta.cos()]).unwrap()[0];
                err = err.max((e - theta.cos().max(0.0)).abs());
                lowest = lowest.min(e);
            }
            println!(
                "window {window:?} order {order}: max error {err:.4}, most negative {lowest:.4}"
            );
            let (want_err, want_low) = documented[w][order - 3];
            assert!((err - want_err).abs() < 6e-4, "{window:?} {order}: {err}");
            assert!(
                (lowest - want_low).abs() < 6e-4,
                "{window:?} {order}: {lowest}"
            );
        }
    }
}

/// Errors, not NaN: NaN lights and points, bad radii; a point on a point light is lit finitely.
#[test]
fn bad_inputs_are_refused() {
    let mut sh = [[0.0f32; 3]; 9];
    let p = Light::Point(PointLight {
        position: [0.0; 3],
        intensity: [1.0; 3],
    });
    // On a point light: inside its sphere, uniform and finite.
    let mut on = [[0.0f32; 3]; 9];
    p.add_radiance_sh(3, [0.0; 3], &mut on).unwrap();
    assert!(on[0].iter().all(|c| c.is_finite() && *c > 0.0), "{on:?}");
    assert!(on[1..].iter().flatten().all(|&c| c == 0.0), "{on:?}");
    let s = sphere([f32::NAN, 0.0, 0.0], 1.0, [1.0; 3]);
    assert_eq!(
        s.add_radiance_sh(3, [0.0; 3], &mut sh),
        Err(LightError::NotFinite)
    );
    let s = sphere([0.0; 3], -0.5, [1.0; 3]);
    assert_eq!(s.validate(), Err(LightError::BadRadius));
    assert_eq!(
        irradiance_sh(3, &sh, [0.0; 3]),
        Err(LightError::ZeroDirection)
    );
    assert!(sh.iter().flatten().all(|&x| x == 0.0));
}
