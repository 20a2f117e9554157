//! Closed-form checks of the bake: unoccluded lobes against Funk–Hecke, polygon occluders
//! against Lambert's formula, one bounce against an independent quadrature, and the
//! structural guarantees (determinism, agreement between ray structures, degenerate input).

use super::*;
use std::f64::consts::PI;

/// `y_00 = 1/(2√π)`.
const Y00: f64 = 0.282_094_791_773_878_14;

fn settings(order: usize, rays: usize) -> BakeSettings {
    BakeSettings {
        order,
        rays,
        bounces: 0,
        albedo: 0.0,
        shadows: true,
    }
}

/// Positions and triangles of one piece of a test scene.
type Part = (Vec<[f32; 3]>, Vec<[u32; 3]>);

/// A grid of quads with corners at `origin + u·du + v·dv` for every `u` in `us` and `v` in
/// `vs`, wound so that the face normal is `du × dv`.
fn quad_grid(
    origin: DVec3,
    du: DVec3,
    dv: DVec3,
    us: &[f64],
    vs: &[f64],
) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    let mut positions = Vec::new();
    for &v in vs {
        for &u in us {
            positions.push((origin + du * u + dv * v).as_vec3().to_array());
        }
    }
    let w = us.len() as u32;
    let mut triangles = Vec::new();
    for j in 0..vs.len() as u32 - 1 {
        for i in 0..w - 1 {
            let a = j * w + i;
            triangles.push([a, a + 1, a + w + 1]);
            triangles.push([a, a + w + 1, a + w]);
        }
    }
    (positions, triangles)
}

fn steps(from: f64, to: f64, n: usize) -> Vec<f64> {
    (0..=n)
        .map(|i| from + (to - from) * i as f64 / n as f64)
        .collect()
}

/// Concatenates parts into one mesh with area-weighted normals.
fn merge(parts: &[Part]) -> Mesh {
    let (mut positions, mut triangles) = (Vec::new(), Vec::new());
    for (p, t) in parts {
        let base = positions.len() as u32;
        positions.extend_from_slice(p);
        triangles.extend(t.iter().map(|t| t.map(|i| i + base)));
    }
    Mesh::with_area_weighted_normals(positions, triangles)
}

/// `∫_polygon max(n·ω, 0) dω` seen from `p`, by Lambert's formula `½ Σ_e Θ_e (n·Γ_e)`, for a
/// polygon wholly in the hemisphere of `n` (no clipping needed).
fn lambert(p: DVec3, n: DVec3, polygon: &[DVec3]) -> f64 {
    let mut sum = 0.0;
    for (i, a) in polygon.iter().enumerate() {
        let b = polygon[(i + 1) % polygon.len()];
        let (ua, ub) = ((*a - p).normalize(), (b - p).normalize());
        let theta = ua.dot(ub).clamp(-1.0, 1.0).acos();
        sum += theta * n.dot(ua.cross(ub).normalize_or_zero());
    }
    0.5 * sum.abs()
}

fn dc(t: &[f32], n2: usize, j: usize) -> f64 {
    f64::from(t[j * n2])
}

/// QMC error bound for smooth integrands at 4096 cosine-Hammersley directions. The estimator
/// error of `(π/N) Σ f(ω_i)` is bounded by π·V(f)·D*_N (Koksma–Hlawka) with the Hammersley
/// star discrepancy D*_N ≈ log₂N / N ≈ 3·10⁻³ and V(f) of order 1 for `y_lm` up to band 5, so
/// the bound is about 10⁻²; what the pattern achieves in practice is an order of magnitude
/// better, and the assertion sits at 2·10⁻³ absolute (coefficients are up to 1.02 in size).
const LOBE_TOL: f64 = 2e-3;

#[test]
fn unoccluded_transfer_is_the_clamped_cosine_lobe() {
    let normals = [
        DVec3::Z,
        -DVec3::Z,
        DVec3::X,
        -DVec3::X,
        DVec3::Y,
        -DVec3::Y,
        DVec3::new(1.0, 1.0, 1.0).normalize(),
        DVec3::new(0.3, -0.5, -0.8).normalize(),
        DVec3::new(1e-7, 0.0, -1.0).normalize(),
    ];
    let mut worst = 0.0f64;
    for n in normals {
        // One triangle in the tangent plane of n, so nothing but itself is in the scene.
        let (t, b) = directions::tangent_frame(n);
        let positions = [DVec3::ZERO, t, b]
            .map(|p| (p + DVec3::splat(0.5)).as_vec3().to_array())
            .to_vec();
        let mesh = Mesh::with_area_weighted_normals(positions, vec![[0, 1, 2]]);
        for order in 1..=aprt_core::MAX_ORDER {
            let n2 = order * order;
            let baked = bake_pose(&mesh, &settings(order, 4096)).unwrap();
            let mut expect = [0.0f32; aprt_core::MAX_COEFFS];
            aprt_core::clamped_cosine(order, n.as_vec3().to_array(), &mut expect).unwrap();
            for j in 0..3 {
                assert!((DVec3::from(mesh.normals[j].map(f64::from)) - n).length() < 1e-6);
                for c in 0..n2 {
                    let err = (f64::from(baked[j * n2 + c]) - f64::from(expect[c])).abs();
                    worst = worst.max(err);
                    assert!(
                        err < LOBE_TOL,
                        "n={n:?} order={order} vertex {j} c={c}: {} vs {}",
                        baked[j * n2 + c],
                        expect[c]
                    );
                }
                // The DC term is exact for cosine-weighted sampling (up to f32 rounding).
                assert!((dc(&baked, n2, j) - PI * Y00).abs() < 1e-6);
            }
        }
    }
    eprintln!("worst unoccluded coefficient error at 4096 rays: {worst:.2e}");
}

/// The rotation convention of the bake: summing the local table over a subset of the pattern
/// and rotating by the vertex frame equals summing the basis at the placed world directions.
/// Expected: agreement to f32 rounding of the order-6 rotation, 1e-5 of the vector's size.
#[test]
fn rotated_local_sum_equals_the_world_sum() {
    let order = aprt_core::MAX_ORDER;
    let n2 = order * order;
    let pattern = directions::cosine_hammersley(500);
    let table = local_basis(order, &pattern).unwrap();
    let mut worst = 0.0f64;
    for k in 0..50u64 {
        // Deterministic pseudo-random normals, angles and visibility masks.
        let h = |i: u64| directions::vertex_rotation((k * 7 + i) as usize) / std::f64::consts::TAU;
        let n = DVec3::new(2.0 * h(0) - 1.0, 2.0 * h(1) - 1.0, 2.0 * h(2) - 1.0).normalize();
        let frame = directions::vertex_frame(n, directions::vertex_rotation(k as usize));
        let mut dirs = Vec::new();
        directions::place_pattern(&pattern, &frame, &mut dirs);
        let (mut local, mut world) = ([0.0f64; 36], [0.0f64; 36]);
        let mut y = [0.0f32; 36];
        for (i, d) in dirs.iter().enumerate() {
            if directions::vertex_rotation(i + 1000 * k as usize) < 4.0 {
                continue;
            }
            for (acc, &b) in local.iter_mut().zip(&table[i * n2..][..n2]) {
                *acc += b;
            }
            aprt_core::eval_basis(order, d.as_vec3().to_array(), &mut y).unwrap();
            for (acc, &b) in world.iter_mut().zip(&y) {
                *acc += f64::from(b);
            }
        }
        let mut rotated = local.map(|x| x as f32);
        ShRotation::new(order)
            .unwrap()
            .apply(&directions::frame_matrix(&frame), &mut rotated)
            .unwrap();
        let size = world.iter().map(|x| x * x).sum::<f64>().sqrt();
        for c in 0..n2 {
            worst = worst.max((f64::from(rotated[c]) - world[c]).abs() / size);
        }
    }
    eprintln!("worst rotated-vs-world coefficient error: {worst:.2e} of the vector's size");
    assert!(worst < 1e-5, "{worst}");
}

/// A floor of small triangles around each receiver point (normal +z) under a square
/// occluder of half-width `half` at height `h`, centred above the origin.
fn floor_under_square(receivers: &[DVec3], half: f64, h: f64) -> (Mesh, Vec<DVec3>) {
    let mut parts = Vec::new();
    for &p in receivers {
        let d = 0.01;
        parts.push(quad_grid(
            p,
            DVec3::X * d,
            DVec3::Y * d,
            &[0.0, 1.0],
            &[0.0, 1.0],
        ));
    }
    let corner = DVec3::new(-half, -half, h);
    parts.push(quad_grid(
        corner,
        DVec3::X * 2.0 * half,
        DVec3::Y * 2.0 * half,
        &[0.0, 1.0],
        &[0.0, 1.0],
    ));
    let square = vec![
        DVec3::new(-half, -half, h),
        DVec3::new(half, -half, h),
        DVec3::new(half, half, h),
        DVec3::new(-half, half, h),
    ];
    (merge(&parts), square)
}

/// Visibility is discontinuous, so the QMC error is larger than for the smooth lobe:
/// discrepancy over the square's (curved) boundary, about 1/√N per unit boundary length in the
/// worst case. 5·10⁻³ relative to the unoccluded DC `π·y_00`.
const SQUARE_TOL: f64 = 5e-3 * PI * Y00;

#[test]
fn square_occluder_matches_lambert() {
    let receivers = [
        DVec3::ZERO,
        DVec3::new(0.3, 0.1, 0.0),
        DVec3::new(0.9, -0.6, 0.0),
        DVec3::new(1.7, 1.2, 0.0),
    ];
    let (mesh, square) = floor_under_square(&receivers, 1.0, 1.0);
    let n2 = 36;
    let baked = bake_pose(&mesh, &settings(6, 4096)).unwrap();
    let mut worst = 0.0f64;
    for (k, &p) in receivers.iter().enumerate() {
        let j = 4 * k; // first vertex of the receiver's quad is the receiver point itself
        assert_eq!(
            DVec3::from(mesh.positions[j].map(f64::from)),
            p.as_vec3().as_dvec3()
        );
        let expect = Y00 * (PI - lambert(p, DVec3::Z, &square));
        let err = (dc(&baked, n2, j) - expect).abs();
        worst = worst.max(err);
        assert!(
            err < SQUARE_TOL,
            "receiver {p:?}: {} vs {expect}",
            dc(&baked, n2, j)
        );
    }
    // The centred receiver is well shadowed: a meaningful test, not a near-unoccluded one.
    assert!(dc(&baked, n2, 0) < 0.6 * PI * Y00);
    eprintln!("worst square-occluder DC error at 4096 rays: {worst:.2e}");
}

#[test]
fn huge_occluder_blocks_everything() {
    let (mesh, square) = floor_under_square(&[DVec3::ZERO], 100.0, 1.0);
    let baked = bake_pose(&mesh, &settings(6, 4096)).unwrap();
    let expect = Y00 * (PI - lambert(DVec3::ZERO, DVec3::Z, &square));
    assert!(
        expect < 1e-3 * PI * Y00,
        "the occluder leaves {expect} of sky"
    );
    assert!((dc(&baked, 36, 0) - expect).abs() < SQUARE_TOL);
    for (c, t) in baked[..36].iter().enumerate() {
        assert!(t.abs() < 1e-3, "c={c}: {t}");
    }
}

/// A floor (z = 0, x ∈ [−9, 1], y ∈ [−10, 10]) meeting a wall (x = 1, facing −x, y ∈ [−10, 10],
/// z from −0.05 to 10.05). The wall's first row of vertices lies just below the floor so that
/// no wall vertex sits exactly on the floor plane (where half its rays would start inside the
/// floor); by mirror symmetry the transfer at z = ±0.05 is the same, so the straddling strip
/// interpolates correctly.
fn floor_and_wall() -> Mesh {
    let floor = quad_grid(
        DVec3::new(-9.0, -10.0, 0.0),
        DVec3::X,
        DVec3::Y,
        &steps(0.0, 10.0, 10),
        &steps(0.0, 20.0, 20),
    );
    let mut zs = vec![-0.05];
    zs.extend(steps(0.05, 10.05, 20));
    let wall = quad_grid(
        DVec3::new(1.0, -10.0, 0.0),
        DVec3::Z,
        DVec3::Y,
        &zs,
        &steps(0.0, 20.0, 40),
    );
    merge(&[floor, wall])
}

/// Composite Simpson over `[a, b]` with `n` (even) intervals.
fn simpson(a: f64, b: f64, n: usize, f: impl Fn(f64) -> f64) -> f64 {
    let h = (b - a) / n as f64;
    let inner: f64 = (1..n)
        .map(|i| f(a + h * i as f64) * if i % 2 == 1 { 4.0 } else { 2.0 })
        .sum();
    (f(a) + f(b) + inner) * h / 3.0
}

#[test]
fn one_bounce_off_a_wall_matches_quadrature() {
    let mesh = floor_and_wall();
    let x = 9; // floor vertex at the origin: row 10 of 21, column 9 of 11
    assert_eq!(mesh.positions[10 * 11 + x], [0.0, 0.0, 0.0]);
    let x = 10 * 11 + x;
    let rho = 0.8;
    let direct = bake_pose(&mesh, &settings(1, 4096)).unwrap();
    let bounced = bake_pose(
        &mesh,
        &BakeSettings {
            order: 1,
            rays: 4096,
            bounces: 1,
            albedo: rho,
            shadows: true,
        },
    )
    .unwrap();
    let bounce = f64::from(bounced[x]) - f64::from(direct[x]);

    // Independent computation. The wall's direct DC transfer at (1, y, z), normal −x, is
    // y_00 (π − Lambert(floor)); the floor point at the origin receives from the wall
    // (ρ/π) ∫_wall t⁰(y) cos θ_x cos θ_y / r² dA, with cos θ_x = z/r, cos θ_y = 1/r.
    let floor = [
        DVec3::new(-9.0, -10.0, 0.0),
        DVec3::new(1.0, -10.0, 0.0),
        DVec3::new(1.0, 10.0, 0.0),
        DVec3::new(-9.0, 10.0, 0.0),
    ];
    let wall_t0 = |y: f64, z: f64| Y00 * (PI - lambert(DVec3::new(1.0, y, z), -DVec3::X, &floor));
    let integrand = |y: f64, z: f64| {
        if z == 0.0 {
            return 0.0; // zero weight; also the Lambert point would sit on the floor's edge
        }
        let r2 = 1.0 + y * y + z * z;
        wall_t0(y, z) * z / (r2 * r2)
    };
    let expect = f64::from(rho) / PI
        * simpson(0.0, 10.05, 400, |z| {
            simpson(-10.0, 10.0, 800, |y| integrand(y, z))
        });
    // Direct part at the same point, also by Lambert (the wall seen from the origin).
    let wall = [
        DVec3::new(1.0, -10.0, 0.0),
        DVec3::new(1.0, 10.0, 0.0),
        DVec3::new(1.0, 10.0, 10.05),
        DVec3::new(1.0, -10.0, 10.05),
    ];
    let expect_direct = Y00 * (PI - lambert(DVec3::ZERO, DVec3::Z, &wall));
    eprintln!(
        "bounce {bounce:.6} vs quadrature {expect:.6}; direct {} vs {expect_direct:.6}",
        direct[x]
    );
    assert!((f64::from(direct[x]) - expect_direct).abs() < SQUARE_TOL);
    // The bounce is a QMC sum of QMC-estimated, linearly interpolated values: 1% relative.
    assert!(
        (bounce - expect).abs() < 0.01 * expect,
        "bounce {bounce} vs {expect}"
    );
    assert!(
        expect > 0.1 * PI * Y00 * f64::from(rho) / 2.0,
        "the test must exercise a sizeable bounce"
    );
}

#[test]
fn zero_bounces_are_bit_identical_to_direct_transfer() {
    let mesh = floor_and_wall();
    let direct = bake_pose(&mesh, &settings(3, 64)).unwrap();
    let other_albedo = bake_pose(
        &mesh,
        &BakeSettings {
            albedo: 0.9,
            shadows: true,
            ..settings(3, 64)
        },
    )
    .unwrap();
    let dark_bounce = bake_pose(
        &mesh,
        &BakeSettings {
            bounces: 1,
            albedo: 0.0,
            shadows: true,
            ..settings(3, 64)
        },
    )
    .unwrap();
    let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&direct), bits(&other_albedo));
    // Closest-hit visibility (bounce path) equals any-hit visibility (shadow path).
    assert_eq!(bits(&direct), bits(&dark_bounce));
    let lit = bake_pose(
        &mesh,
        &BakeSettings {
            bounces: 2,
            albedo: 0.5,
            shadows: true,
            ..settings(3, 64)
        },
    )
    .unwrap();
    assert_ne!(bits(&direct), bits(&lit));
}

#[test]
fn result_is_bit_identical_for_any_thread_count() {
    let mesh = floor_and_wall();
    let s = BakeSettings {
        order: 4,
        rays: 100,
        bounces: 2,
        albedo: 0.7,
        shadows: true,
    };
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let t = pool.install(|| bake_pose(&mesh, &s)).unwrap();
        t.iter().map(|x| x.to_bits()).collect::<Vec<_>>()
    };
    let one = run(1);
    assert_eq!(one, run(2));
    assert_eq!(one, run(3));
}

#[test]
fn ray_structures_agree_bit_for_bit() {
    let (mesh, _) = floor_under_square(&[DVec3::ZERO, DVec3::new(0.8, 0.9, 0.0)], 1.0, 0.5);
    let mesh = merge(&[(mesh.positions, mesh.triangles), {
        let wall = floor_and_wall();
        (wall.positions, wall.triangles)
    }]);
    let s = settings(3, 128);
    let bvh = bake_pose_with(&mesh, &s, Accel::Bvh4).unwrap();
    assert_eq!(bvh, bake_pose_with(&mesh, &s, Accel::Bvh4Packet).unwrap());
    assert_eq!(bvh, bake_pose_with(&mesh, &s, Accel::CwBvh).unwrap());
    assert_eq!(bvh, bake_pose_with(&mesh, &s, Accel::Bvh2).unwrap());
    assert_eq!(bvh, bake_pose_with(&mesh, &s, Accel::BruteForce).unwrap());
    // A vertex range is the same slice of the whole bake.
    let part = bake_vertices(&mesh, &s, Accel::BruteForce, 5..40).unwrap();
    assert_eq!(part, bvh[5 * 9..40 * 9]);
}

#[test]
fn poses_helper_matches_single_pose_bakes() {
    let a = floor_and_wall();
    let (b, _) = floor_under_square(&[DVec3::ZERO], 1.0, 1.0);
    let s = settings(2, 32);
    let all = bake_poses(
        &[a.clone(), b.clone(), Mesh::default()],
        &s,
        &crate::progress::Silent,
    )
    .unwrap();
    assert_eq!(
        all,
        vec![
            bake_pose(&a, &s).unwrap(),
            bake_pose(&b, &s).unwrap(),
            Vec::new()
        ]
    );
}

#[test]
fn degenerate_geometry_bakes_without_panicking() {
    assert_eq!(
        bake_pose(&Mesh::default(), &settings(6, 16)).unwrap(),
        Vec::<f32>::new()
    );
    // Zero-area triangles, a repeated index, an isolated vertex, zero and NaN normals.
    let mesh = Mesh {
        positions: vec![
            [0.0; 3],
            [0.0; 3],
            [0.0; 3],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [4.0, 4.0, 4.0],
        ],
        normals: vec![
            [0.0; 3],
            [f32::NAN, 0.0, 0.0],
            [0.0, 0.0, -3.0],
            [0.0; 3],
            [0.0, 0.0, 1.0],
            [0.0; 3],
        ],
        triangles: vec![[0, 1, 2], [0, 3, 3], [0, 3, 4]],
    };
    for bounces in [0, 2] {
        let t = bake_pose(
            &mesh,
            &BakeSettings {
                order: 2,
                rays: 64,
                bounces,
                albedo: 0.5,
                shadows: true,
            },
        )
        .unwrap();
        assert_eq!(t.len(), 6 * 4);
        assert!(t.iter().all(|x| x.is_finite()));
        // Nothing occludes anything, so every vertex gets the exact unoccluded DC term, and
        // the −3z normal is normalised: its band-1 z coefficient is −(2π/3)·√(3/4π).
        for j in 0..6 {
            assert!((dc(&t, 4, j) - PI * Y00).abs() < 1e-6);
        }
        assert!(
            (f64::from(t[2 * 4 + 2]) + 2.0 * PI / 3.0 * (3.0 / (4.0 * PI)).sqrt()).abs() < 0.05
        );
    }
}

#[test]
fn invalid_input_gives_typed_errors() {
    let good = floor_under_square(&[DVec3::ZERO], 1.0, 1.0).0;
    let s = settings(2, 16);
    for (bad, err) in [
        (settings(0, 16), BakeError::BadOrder(0)),
        (settings(7, 16), BakeError::BadOrder(7)),
        (settings(2, 0), BakeError::BadRayCount(0)),
        (
            settings(2, MAX_RAYS + 1),
            BakeError::BadRayCount(MAX_RAYS + 1),
        ),
        (
            BakeSettings {
                bounces: 1,
                albedo: 1.5,
                shadows: true,
                ..s
            },
            BakeError::BadAlbedo(1.5),
        ),
    ] {
        assert_eq!(bake_pose(&good, &bad), Err(err));
    }
    assert!(matches!(
        bake_pose(
            &good,
            &BakeSettings {
                bounces: 1,
                albedo: f32::NAN,
                shadows: true,
                ..s
            }
        ),
        Err(BakeError::BadAlbedo(_))
    ));
    let mut nan = good.clone();
    nan.positions[3][1] = f32::NAN;
    assert!(matches!(
        bake_pose(&nan, &s),
        Err(BakeError::NonFinitePosition { vertex: 3, .. })
    ));
    let mut inf = good.clone();
    inf.positions[5][0] = f32::INFINITY;
    assert!(matches!(
        bake_pose(&inf, &s),
        Err(BakeError::NonFinitePosition { vertex: 5, .. })
    ));
    let mut far = good.clone();
    far.positions[0] = [2e12, 0.0, 0.0];
    assert!(matches!(
        bake_pose(&far, &s),
        Err(BakeError::ExtentTooLarge { .. })
    ));
    let mut short = good.clone();
    short.normals.pop();
    assert!(matches!(
        bake_pose(&short, &s),
        Err(BakeError::NormalCountMismatch { .. })
    ));
    let mut oob = good.clone();
    oob.triangles[1][2] = 99;
    assert_eq!(
        bake_pose(&oob, &s),
        Err(BakeError::IndexOutOfRange {
            triangle: 1,
            index: 99,
            vertices: 8
        })
    );
    assert_eq!(
        bake_vertices(&good, &s, Accel::CwBvh, 3..9),
        Err(BakeError::BadVertexRange {
            start: 3,
            end: 9,
            vertices: 8
        })
    );
    assert_eq!(
        bake_vertices(&good, &BakeSettings { bounces: 1, ..s }, Accel::CwBvh, 0..1),
        Err(BakeError::BouncesNeedWholeMesh)
    );
}

/// A closed cube `[-h, h]³` centred at `c`, each face a 3 × 3 vertex grid wound outward
/// (faces do not share vertices, but their edges coincide exactly).
fn cube(c: DVec3, h: f64) -> Vec<Part> {
    let s = [0.0, 0.5, 1.0];
    let w = 2.0 * h;
    let lo = c - DVec3::splat(h);
    let (x, y, z) = (DVec3::X * w, DVec3::Y * w, DVec3::Z * w);
    [
        (lo + z, x, y),
        (lo, y, x),
        (lo + x, y, z),
        (lo, z, y),
        (lo + y, z, x),
        (lo, x, z),
    ]
    .into_iter()
    .map(|(o, du, dv)| quad_grid(o, du, dv, &s, &s))
    .collect()
}

/// A vertex inside closed geometry. Expected: every ray hits the cube, so every coefficient
/// is exactly 0.0 (not merely small), with every ray structure and with bounces too (the
/// inside of an outward-wound cube is back-facing, and back faces reflect nothing).
#[test]
fn vertex_inside_a_closed_cube_has_exactly_zero_transfer() {
    let mut mesh = merge(&cube(DVec3::ZERO, 1.0));
    let inside = mesh.vertex_count();
    mesh.positions.push([0.1, -0.2, 0.3]);
    mesh.normals.push([0.3, 0.4, 0.5]);
    for accel in [
        Accel::Bvh4Packet,
        Accel::CwBvh,
        Accel::Bvh2,
        Accel::BruteForce,
    ] {
        for bounces in [0, 2] {
            let s = BakeSettings {
                bounces,
                albedo: 0.9,
                shadows: true,
                ..settings(6, 512)
            };
            let t = bake_pose_with(&mesh, &s, accel).unwrap();
            assert!(
                t[inside * 36..].iter().all(|&x| x == 0.0),
                "{accel:?} {bounces}: {:?}",
                &t[inside * 36..inside * 36 + 4]
            );
        }
    }
}

/// The first vertices of [`cube_over_floor`]: the cube's top face, open to the sky.
const TOP_FACE: usize = 9;

/// A cube above a floor: real occlusion (the floor under the cube, the cube's sides and
/// bottom) and convex vertices that must see no self-hit (the top face).
fn cube_over_floor(scale: f64, shift: f64) -> Mesh {
    let d = DVec3::splat(shift);
    let mut parts = cube(DVec3::new(0.0, 0.0, 1.5) + d, 1.0);
    let floor = steps(-3.0, 3.0, 6);
    parts.push(quad_grid(d, DVec3::X, DVec3::Y, &floor, &floor));
    let mut mesh = merge(&parts);
    for p in &mut mesh.positions {
        *p = p.map(|x| (f64::from(x) * scale) as f32);
    }
    mesh.normals = crate::rig::mesh::area_weighted_normals(&mesh.positions, &mesh.triangles);
    mesh
}

/// Transfer is scale invariant. Expected: scaling by a power of two changes no rounding
/// anywhere (positions, normals, the bbox-relative self-hit offset and t_min, every
/// intersection product scale exactly), so the bake is bit-identical from 2⁻¹⁰ to 2¹³;
/// decimal scales from 1e-3 to 1e4 round the positions differently, which can flip rays that
/// graze an edge, so they agree to within one or two rays' weight (π/N per ray, |y_c| ≤ 1).
/// The 9 vertices of the cube's top face (corners, edges, centre) see nothing but sky and must
/// see no self-hit at any scale: their DC term is exactly the unoccluded π·y₀₀, which shows
/// the offset grows with the model.
#[test]
fn the_same_mesh_at_any_scale_bakes_to_the_same_transfer() {
    let s = settings(3, 256);
    let reference = bake_pose(&cube_over_floor(1.0, 0.0), &s).unwrap();
    for k in [-10, -3, 5, 13] {
        let scaled = bake_pose(&cube_over_floor(2f64.powi(k), 0.0), &s).unwrap();
        assert!(scaled == reference, "2^{k}");
    }
    let ray = PI / 256.0;
    for scale in [1e-3, 1e-2, 0.1, 10.0, 1e2, 1e3, 1e4] {
        let t = bake_pose(&cube_over_floor(scale, 0.0), &s).unwrap();
        let worst = t
            .iter()
            .zip(&reference)
            .map(|(a, b)| f64::from((a - b).abs()))
            .fold(0.0, f64::max);
        let self_hit = (0..TOP_FACE)
            .filter(|&j| (dc(&t, 9, j) - PI * Y00).abs() > 1e-6)
            .count();
        eprintln!(
            "scale {scale:e}: max |Δt| {worst:.2e} = {:.2} rays, {self_hit} top-face vertices self-shadowed",
            worst / ray
        );
        assert!(worst <= 2.0 * ray, "scale {scale}: {worst}");
        assert_eq!(self_hit, 0, "scale {scale}");
    }
}

/// Far from the origin. Expected: f32 positions far from the origin are coarse (ulp(10⁴) ≈
/// 10⁻³ is about the self-hit offset of this 9-unit scene), so the origin offset can round
/// away; the bbox-relative `T_MIN` still ignores the ray's own surface, and a scene whose
/// coordinates stay representable bakes exactly as at home, with no self-shadowing.
#[test]
fn a_mesh_far_from_the_origin_bakes_as_at_the_origin() {
    let s = settings(3, 256);
    let reference = bake_pose(&cube_over_floor(1.0, 0.0), &s).unwrap();
    for shift in [1e2, 1e3, 1e4, 1e5] {
        let t = bake_pose(&cube_over_floor(1.0, shift), &s).unwrap();
        let worst = t
            .iter()
            .zip(&reference)
            .map(|(a, b)| f64::from((a - b).abs()))
            .fold(0.0, f64::max);
        let self_hit = (0..TOP_FACE)
            .filter(|&j| (dc(&t, 9, j) - PI * Y00).abs() > 1e-6)
            .count();
        eprintln!(
            "shift {shift:e}: max |Δt| {worst:.2e}, {self_hit} top-face vertices self-shadowed"
        );
        assert_eq!(self_hit, 0, "shift {shift}");
    }
}

/// Nearly coincident vertices and sliver triangles. Expected: a floor whose two triangles use
/// vertices one f32 ulp apart, and a sliver (1 × 1e-6) hanging over it, bake to finite values;
/// the floor sees an occluder of about 1e-6 sr, so its DC term loses at most one of 1024 rays
/// (π·y₀₀/1024 ≈ 8.7e-4); the near-duplicate vertices get the same transfer up to that ray.
#[test]
fn near_duplicate_vertices_and_slivers_bake_to_finite_plausible_transfer() {
    let next = f32::from_bits(1.0f32.to_bits() + 1);
    let mesh = Mesh::with_area_weighted_normals(
        vec![
            [-1.0, -1.0, 0.0],
            [1.0, -1.0, 0.0],
            [1.0, 1.0, 0.0],
            [next, 1.0, 0.0],
            [-1.0, 1.0, 0.0],
            [-1.0, 0.0, 1.0],
            [1.0, 0.0, 1.0],
            [1.0, 1e-6, 1.0],
        ],
        vec![[0, 1, 2], [0, 3, 4], [5, 7, 6]],
    );
    let t = bake_pose(&mesh, &settings(4, 1024)).unwrap();
    assert!(t.iter().all(|x| x.is_finite()));
    let full = PI * Y00;
    for j in 0..5 {
        assert!(
            dc(&t, 16, j) >= full * (1.0 - 1.0 / 1024.0) - 1e-6,
            "vertex {j}"
        );
    }
    let (a, b) = (&t[2 * 16..3 * 16], &t[3 * 16..4 * 16]);
    let diff = a
        .iter()
        .zip(b)
        .map(|(x, y)| f64::from((x - y).abs()))
        .fold(0.0, f64::max);
    assert!(diff <= PI / 1024.0, "{diff}");
    // The sliver's own vertices face down onto the floor (wound clockwise from above).
    for j in 5..8 {
        assert!(dc(&t, 16, j).is_finite());
    }
}

/// A light map's texels are baked by the vertex bake's own code: points placed at the vertices
/// with the vertices' normals give the vertices' transfer bit for bit without bounces, and to
/// rounding with them (the texel path sums the bounces as one gather of the (B − 1)-bounce
/// total).
#[test]
fn points_at_the_vertices_bake_the_vertices_transfer() {
    let mesh = floor_and_wall();
    let direct = settings(3, 64);
    let at_vertices = |s: &BakeSettings| {
        bake_points(
            &mesh,
            (&mesh.positions, &mesh.normals),
            PatternRotation::PerPoint,
            s,
            &Silent,
        )
        .unwrap()
    };
    let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(
        bits(&at_vertices(&direct)),
        bits(&bake_pose(&mesh, &direct).unwrap())
    );
    let bounced = BakeSettings {
        bounces: 2,
        albedo: 0.7,
        shadows: true,
        ..direct
    };
    let (points, vertices) = (at_vertices(&bounced), bake_pose(&mesh, &bounced).unwrap());
    let scale = vertices.iter().fold(0.0f32, |m, x| m.max(x.abs()));
    for (p, v) in points.iter().zip(&vertices) {
        assert!((p - v).abs() <= 1e-5 * scale, "{p} vs {v}");
    }
    assert_ne!(bits(&points), bits(&at_vertices(&direct)));
}

/// Points between vertices: the centre of a floor cell sees the upper hemisphere less the
/// wall, whose share is Lambert's closed form; a bad point or a normal count that does not
/// match is refused.
#[test]
fn points_between_vertices_bake_and_bad_points_are_refused() {
    let mesh = floor_and_wall();
    let s = settings(1, 4096);
    let far = [[-4.5f32, 0.5, 0.0]];
    let up = [[0.0f32, 0.0, 1.0]];
    let t = bake_points(&mesh, (&far, &up), PatternRotation::Shared, &s, &Silent).unwrap();
    let wall = [
        DVec3::new(1.0, -10.0, 0.0),
        DVec3::new(1.0, 10.0, 0.0),
        DVec3::new(1.0, 10.0, 10.05),
        DVec3::new(1.0, -10.0, 10.05),
    ];
    let p = DVec3::from(far[0].map(f64::from));
    let expect = Y00 * (PI - lambert(p, DVec3::Z, &wall));
    assert!(
        (f64::from(t[0]) - expect).abs() < SQUARE_TOL,
        "{t:?} vs {expect}"
    );
    assert!(matches!(
        bake_points(
            &mesh,
            (&[[f32::NAN, 0.0, 0.0]], &up),
            PatternRotation::Shared,
            &s,
            &Silent
        ),
        Err(BakeError::NonFinitePosition { vertex: 0, .. })
    ));
    assert!(matches!(
        bake_points(&mesh, (&far, &[]), PatternRotation::Shared, &s, &Silent),
        Err(BakeError::NormalCountMismatch { .. })
    ));
    // A zero normal falls back to +z rather than NaN.
    let zero = bake_points(
        &mesh,
        (&far, &[[0.0; 3]]),
        PatternRotation::Shared,
        &s,
        &Silent,
    )
    .unwrap();
    assert_eq!(zero, t);
}

/// Without shadows nothing is traced: a vertex shut inside a closed cube still sees the whole
/// clamped cosine lobe, whose band norms are the Funk–Hecke constants `Â_l √((2l+1)/4π)`:
/// √π/2, √(π/3), √(5π)/8, 0 and √π/16 for bands 0 to 4 (odd bands above 1 vanish), and the
/// lobe points along the normal (`t_1m ∝ y_1m(n)`).
#[test]
fn shadowless_transfer_is_the_closed_form_cosine_lobe_even_when_enclosed() {
    let mut mesh = merge(&cube(DVec3::ZERO, 1.0));
    let inside = mesh.vertex_count();
    mesh.positions.push([0.1, -0.2, 0.3]);
    let n = DVec3::new(0.3, 0.4, 0.5).normalize();
    mesh.normals.push([0.3, 0.4, 0.5]);
    let s = BakeSettings {
        shadows: false,
        ..settings(6, 512)
    };
    assert_eq!(s.rays_cast(mesh.vertex_count()), 0);
    assert_eq!(settings(6, 512).rays_cast(10), 5120);
    let t = bake_pose(&mesh, &s).unwrap();
    let ours = &t[inside * 36..];
    let norms = [
        PI.sqrt() / 2.0,
        (PI / 3.0).sqrt(),
        (5.0 * PI).sqrt() / 8.0,
        0.0,
        PI.sqrt() / 16.0,
        0.0,
    ];
    for (l, expect) in norms.iter().enumerate() {
        let band = &ours[l * l..(l + 1) * (l + 1)];
        let norm = band
            .iter()
            .map(|&x| f64::from(x).powi(2))
            .sum::<f64>()
            .sqrt();
        assert!((norm - expect).abs() < 2e-6, "band {l}: {norm} vs {expect}");
    }
    // Band 1 is (√(π/3)) (n_y, n_z, n_x) up to the basis' sign convention: parallel to n.
    let b1 = DVec3::new(f64::from(ours[3]), f64::from(ours[1]), f64::from(ours[2]));
    assert!((b1.normalize().dot(n).abs() - 1.0).abs() < 1e-6, "{b1:?}");
    // The same transfer at points, and refusing bounces without occluders.
    let points = bake_points(
        &mesh,
        (&mesh.positions[inside..], &mesh.normals[inside..]),
        PatternRotation::Shared,
        &s,
        &Silent,
    )
    .unwrap();
    assert_eq!(points, ours);
    let bouncing = BakeSettings { bounces: 1, ..s };
    assert_eq!(
        bake_pose(&mesh, &bouncing),
        Err(BakeError::BouncesNeedShadows)
    );
}
