//! Per-vertex ("analytic") lights through the pose model's transfer (`shade_lights`,
//! *Irradiance Rigs*): the definition against an independent path that rotates the light's SH
//! vector rather than its direction, the closed form of a sphere light on an unoccluded
//! vertex, linearity in the weights, the lights and the vertex range, and hostile inputs.

use aprt_core::{
    CLAMPED_COSINE_BANDS, DirectionalLight, Error, Input, Light, LightError, Model, PointLight,
    PoseWeights, Rotation, ShRotation, SphereLight, StreamedModel, coeff_count, irradiance_sh,
    sphere_light_bands,
};
use aprt_tests::{axis_angle, noise, random_model};
use aprt_trainer::model::runtime::static_model;
use aprt_trainer::{BoneFrames, LinearModel, Precision, encode_model};

const ROTATIONS: [([f32; 3], f32); 3] = [
    ([1.0, 2.0, 0.5], 0.7),
    ([0.0, 0.0, 1.0], -1.2),
    ([-1.0, 0.3, 0.2], 2.5),
];

/// A random model, in its bones' frames when `bones` is given (vertices split evenly).
fn model_with_bones(
    order: usize,
    vertices: usize,
    coef_dims: Option<usize>,
    bones: Option<usize>,
) -> LinearModel {
    let mut model = random_model(order, vertices, 4, 2, coef_dims);
    model.bones = bones.map(|count| BoneFrames {
        count,
        vertex_bone: (0..vertices)
            .map(|j| (j * count / vertices) as u16)
            .collect(),
    });
    model
}

fn triples(seed: u64, n: usize, scale: f32) -> Vec<[f32; 3]> {
    noise(seed, 3 * n)
        .chunks_exact(3)
        .map(|p| {
            [
                p[0] as f32 * scale,
                p[1] as f32 * scale,
                p[2] as f32 * scale,
            ]
        })
        .collect()
}

/// `count` random lights cycling through sphere, point and directional, near the unit cube.
fn random_lights(seed: u64, count: usize) -> Vec<Light> {
    let u = noise(seed, 8 * count);
    (0..count)
        .map(|i| {
            let x = &u[8 * i..8 * i + 8];
            let position = [3.0 * x[0] as f32, 3.0 * x[1] as f32, 3.0 * x[2] as f32];
            let colour = [x[3], x[4], x[5]].map(|c| 0.2 + c.abs() as f32);
            match i % 3 {
                0 => Light::Sphere(SphereLight {
                    position,
                    radius: 0.2 + 0.8 * x[6].abs() as f32,
                    radiance: colour,
                }),
                1 => Light::Point(PointLight {
                    position,
                    intensity: colour,
                }),
                _ => Light::Directional(DirectionalLight {
                    direction: position,
                    irradiance: colour,
                }),
            }
        })
        .collect()
}

/// The reference of one vertex: `Σ_i w_i t · (R_bᵀ applied to l_i(p))`, rotating the light's
/// world SH vector with `ShRotation`, and the magnitude `Σ |w_i t_c l_c|` for the tolerance.
fn reference(
    order: usize,
    t: &[f32],
    rotation: Option<&Rotation>,
    lights: &[Light],
    weights: &[f32],
    p: [f32; 3],
) -> ([f64; 3], f64) {
    let n2 = coeff_count(order);
    let (mut sum, mut magnitude) = ([0.0f64; 3], 0.0f64);
    for (light, &w) in lights.iter().zip(weights) {
        let mut sh = vec![[0.0f32; 3]; n2];
        light.add_radiance_sh(order, p, &mut sh).unwrap();
        for ch in 0..3 {
            let mut channel: Vec<f32> = sh.iter().map(|c| c[ch]).collect();
            if let Some(r) = rotation {
                let rt = std::array::from_fn(|i| std::array::from_fn(|j| f64::from(r[j][i])));
                ShRotation::new(order)
                    .unwrap()
                    .apply(&rt, &mut channel)
                    .unwrap();
            }
            for (tc, lc) in t.iter().zip(&channel) {
                let x = f64::from(w) * f64::from(*tc) * f64::from(*lc);
                sum[ch] += x;
                magnitude += x.abs();
            }
        }
    }
    (sum, magnitude)
}

/// Test 1: The definition, for world- and bone-frame models, stored and identity bases, f32 and
/// f16, all three kinds of light: resident and streamed, over a range not starting on a block.
#[test]
fn shading_is_transfer_dot_light_at_each_vertex() {
    let (order, vertices) = (4, 29);
    let rotations: Vec<Rotation> = ROTATIONS.iter().map(|&(a, t)| axis_angle(a, t)).collect();
    let lights = random_lights(7, 9);
    let weights: Vec<f32> = noise(8, 9).iter().map(|w| 0.1 + w.abs() as f32).collect();
    let positions = triples(9, vertices, 1.0);
    for bones in [None, Some(3)] {
        for coef_dims in [Some(5), None] {
            for precision in [Precision::F32, Precision::F16] {
                let blob = encode_model(
                    &model_with_bones(order, vertices, coef_dims, bones),
                    precision,
                )
                .unwrap();
                let core = Model::parse(&blob).unwrap();
                let rotations = &rotations[..bones.unwrap_or(0)];
                let mut pose = PoseWeights::new();
                core.set_pose(&[0.3, -0.1, 0.2, 0.5], &mut pose).unwrap();
                let n2 = core.info().coeffs();
                let mut transfer = vec![0.0f32; vertices * n2];
                core.transfer(&pose, 0, &mut transfer).unwrap();
                let mut vertex_bones = vec![0u16; vertices];
                core.vertex_bones(0, &mut vertex_bones).unwrap();

                let mut shaded = vec![[0.0f32; 3]; vertices];
                core.shade_lights(
                    &pose,
                    rotations,
                    &lights,
                    &weights,
                    &positions,
                    0,
                    &mut shaded,
                )
                .unwrap();
                for j in 0..vertices {
                    let r = bones.map(|_| &rotations[vertex_bones[j] as usize]);
                    let t = &transfer[j * n2..(j + 1) * n2];
                    let (want, magnitude) = reference(order, t, r, &lights, &weights, positions[j]);
                    for ch in 0..3 {
                        let got = f64::from(shaded[j][ch]);
                        assert!(
                            (got - want[ch]).abs() <= 2e-5 * (1.0 + magnitude),
                            "bones {bones:?}, basis {coef_dims:?}, {precision:?}, vertex {j}, \
                             channel {ch}: {got} vs {}",
                            want[ch]
                        );
                    }
                }

                let mut scratch = vec![0u8; core.info().scratch_bytes()];
                let mut streamed = StreamedModel::open(&blob[..], &mut scratch).unwrap();
                let mut part = vec![[0.0f32; 3]; 17];
                streamed
                    .shade_lights(
                        &pose,
                        rotations,
                        &lights,
                        &weights,
                        &positions[5..22],
                        5,
                        &mut part,
                    )
                    .unwrap();
                assert_eq!(
                    part,
                    shaded[5..22],
                    "streamed, partial range: the same bits"
                );
            }
        }
    }
}

/// `Â_l` of the clamped cosine for any `l` (f64): 2π/3 at `l = 1`, 0 at other odd `l`, and
/// `2π (−1)^{l/2−1} / ((l+2)(l−1)) · l! / (2^l ((l/2)!)²)` at even `l`.
fn clamped_cosine_band(l: usize) -> f64 {
    use std::f64::consts::PI;
    match l {
        0 => PI,
        1 => 2.0 * PI / 3.0,
        _ if l % 2 == 1 => 0.0,
        _ => {
            // l! / (2^l ((l/2)!)²) = C(l, l/2) / 2^l, as a running product.
            let central =
                (1..=l / 2).fold(1.0f64, |c, k| c * (l / 2 + k) as f64 / (4.0 * k as f64));
            let sign = if (l / 2) % 2 == 1 { 1.0 } else { -1.0 };
            2.0 * PI * sign / (((l + 2) * (l - 1)) as f64) * central
        }
    }
}

/// `Σ_{l ≥ n} (2l + 1)|Â_l|`: the terms up to `l = 10⁶` summed (the even ones through
/// `C(l+2, l/2+1)/2^{l+2} = C(l, l/2)/2^l · (l+1)/(l+2)`), the rest bounded by
/// `C(l, l/2)/2^l ≤ √(2/(πl))` and `(2l+1)/((l+2)(l−1)) ≤ 2.5/l`, so each even term is at most
/// `c l^{-3/2}` with `c = 5π √(2/π)`, and the even terms past `N` sum to at most `c/√N`.
fn clamped_cosine_tail(n: usize) -> f64 {
    use std::f64::consts::PI;
    const N: usize = 1_000_000;
    let mut sum: f64 = (n..2)
        .map(|l| (2 * l + 1) as f64 * clamped_cosine_band(l))
        .sum();
    let mut central = 0.5f64; // C(2, 1)/2²
    for l in (2..=N).step_by(2) {
        if l >= n {
            let a = 2.0 * PI / (((l + 2) * (l - 1)) as f64) * central;
            sum += (2 * l + 1) as f64 * a;
        }
        central *= (l + 1) as f64 / (l + 2) as f64;
    }
    sum + 5.0 * PI * (2.0 / PI).sqrt() / (N as f64).sqrt()
}

/// Test 2: An unoccluded vertex under a fully visible sphere light: exactly the SH path's
/// irradiance (`irradiance_sh` of `add_radiance_sh`), and within the truncation bound of the
/// exact `π L r²/d² cos θ` (`Light::irradiance`). By the addition theorem the SH irradiance is
/// `L Σ_{l<n} Â_l b_l (2l+1)/(4π) P_l(cos θ)` and the exact one the whole series; with
/// `|b_l| ≤ b_0` and `|P_l| ≤ 1` the truncation is at most `L b_0/(4π) Σ_{l≥n} (2l+1)|Â_l|`.
#[test]
fn sphere_light_on_an_unoccluded_vertex_matches_the_closed_form() {
    // Normals at 0°..70° from +z and various azimuths; the light straight above.
    let normals: Vec<[f32; 3]> = [0.0f32, 20.0, 40.0, 55.0, 70.0, 10.0, 65.0]
        .iter()
        .enumerate()
        .map(|(i, deg)| {
            let (t, phi) = (deg.to_radians(), i as f32 * 1.3);
            [t.sin() * phi.cos(), t.sin() * phi.sin(), t.cos()]
        })
        .collect();
    let v = normals.len();
    let positions = vec![[0.2f32, -0.1, 0.3]; v];
    let mut worst = Vec::new(); // per order, the largest |E_n − E| / (L b_0)
    for order in 1..=6 {
        let mut order_worst = 0.0f64;
        let blob = encode_model(&static_model(&normals, order), Precision::F32).unwrap();
        let core = Model::parse(&blob).unwrap();
        let mut pose = PoseWeights::new();
        core.set_pose(&[0.7], &mut pose).unwrap();
        let tail = clamped_cosine_tail(order);
        // sin α = 0.25 and 0.1: every normal keeps the whole cap above its horizon (cos 70° > 0.25).
        for (d, r) in [(4.0f32, 1.0f32), (3.0, 0.3)] {
            let centre = [positions[0][0], positions[0][1], positions[0][2] + d];
            let light = Light::Sphere(SphereLight {
                position: centre,
                radius: r,
                radiance: [1.0, 0.5, 2.0],
            });
            let mut shaded = vec![[0.0f32; 3]; v];
            core.shade_lights(&pose, &[], &[light], &[1.0], &positions, 0, &mut shaded)
                .unwrap();
            let n2 = coeff_count(order);
            let mut sh = vec![[0.0f32; 3]; n2];
            light.add_radiance_sh(order, positions[0], &mut sh).unwrap();
            let b0 = f64::from(sphere_light_bands(r, d).unwrap()[0]);
            for (j, n) in normals.iter().enumerate() {
                let sh_path = irradiance_sh(order, &sh, *n).unwrap();
                let exact = light.irradiance(positions[j], *n).unwrap();
                for ch in 0..3 {
                    let (got, e) = (f64::from(shaded[j][ch]), f64::from(exact[ch]));
                    let l = f64::from(light.colour()[ch]);
                    assert!(
                        (got - f64::from(sh_path[ch])).abs() <= 1e-5 * l * b0,
                        "order {order}, normal {j}: {got} vs the SH path {}",
                        sh_path[ch]
                    );
                    let bound = l * b0 / (4.0 * std::f64::consts::PI) * tail;
                    assert!(
                        (got - e).abs() <= bound + 1e-5 * e,
                        "order {order}, normal {j}: {got} vs exact {e}, bound {bound}"
                    );
                    order_worst = order_worst.max((got - e).abs() / (l * b0));
                }
            }
        }
        worst.push(order_worst);
    }
    // Converging: the truncation at order 6 is well under that at order 1 (relative to L b_0).
    assert!(worst[5] < 0.2 * worst[0], "{worst:?}");
    assert!(
        clamped_cosine_tail(6) < clamped_cosine_tail(3)
            && clamped_cosine_tail(3) < clamped_cosine_tail(1)
    );
    println!("worst |E_n − E| / (L b_0), orders 1..=6: {:?}", worst);
    println!(
        "bounds: {:?}",
        (1..=6)
            .map(|n| clamped_cosine_tail(n) / (4.0 * std::f64::consts::PI))
            .collect::<Vec<_>>()
    );
    // The core's Â_l agree with the formula the bound uses.
    for (l, a) in CLAMPED_COSINE_BANDS.iter().enumerate() {
        assert!(
            (f64::from(*a) - clamped_cosine_band(l)).abs() < 1e-6,
            "Â_{l}"
        );
    }
}

/// A bone-frame model with a pose set, and the inputs the linearity and hostile tests share.
struct Scene {
    blob: Vec<u8>,
    rotations: Vec<Rotation>,
    lights: Vec<Light>,
    positions: Vec<[f32; 3]>,
    vertices: usize,
}

fn scene() -> Scene {
    let vertices = 21;
    let blob = encode_model(
        &model_with_bones(3, vertices, Some(4), Some(3)),
        Precision::F32,
    )
    .unwrap();
    Scene {
        blob,
        rotations: ROTATIONS.iter().map(|&(a, t)| axis_angle(a, t)).collect(),
        lights: random_lights(17, 3),
        positions: triples(19, vertices, 1.0),
        vertices,
    }
}

/// Test 3: Linear in each weight and in the set of lights; a range split in two gives the same bits
/// as one call; the output is accumulated; a weight of 0 is no light at all.
#[test]
fn shading_is_linear_and_range_independent() {
    let s = scene();
    let core = Model::parse(&s.blob).unwrap();
    let mut pose = PoseWeights::new();
    core.set_pose(&[0.1, 0.2, -0.3, 0.4], &mut pose).unwrap();
    let v = s.vertices;
    let shade = |lights: &[Light], weights: &[f32], out: &mut [[f32; 3]]| {
        core.shade_lights(&pose, &s.rotations, lights, weights, &s.positions, 0, out)
            .unwrap()
    };
    let close = |a: f32, b: f32| (a - b).abs() <= 2e-6 * (a.abs() + b.abs()) + 1e-30;

    let mut one = vec![[0.0f32; 3]; v];
    shade(&s.lights[..1], &[1.0], &mut one);
    for w in [0.37f32, 2.5, 1e-3] {
        let mut scaled = vec![[0.0f32; 3]; v];
        shade(&s.lights[..1], &[w], &mut scaled);
        for (a, b) in scaled.iter().flatten().zip(one.iter().flatten()) {
            assert!(close(*a, w * b), "weight {w}: {a} vs {}", w * b);
        }
    }

    let weights = [0.8f32, 0.3, 1.0];
    let mut together = vec![[0.0f32; 3]; v];
    shade(&s.lights, &weights, &mut together);
    let mut apart = vec![[0.0f32; 3]; v];
    for i in 0..3 {
        shade(&s.lights[i..=i], &weights[i..=i], &mut apart); // accumulates
    }
    for (a, b) in together.iter().flatten().zip(apart.iter().flatten()) {
        assert!((a - b).abs() <= 1e-5 * (1.0 + a.abs()), "{a} vs {b}");
    }

    // One call, two calls split off a block boundary, and accumulation onto existing values.
    let mut split = vec![[0.0f32; 3]; v];
    let (left, right) = split.split_at_mut(11);
    core.shade_lights(
        &pose,
        &s.rotations,
        &s.lights,
        &weights,
        &s.positions[..11],
        0,
        left,
    )
    .unwrap();
    core.shade_lights(
        &pose,
        &s.rotations,
        &s.lights,
        &weights,
        &s.positions[11..],
        11,
        right,
    )
    .unwrap();
    assert_eq!(split, together);
    let base: Vec<[f32; 3]> = triples(23, v, 5.0);
    let mut onto = base.clone();
    shade(&s.lights, &weights, &mut onto);
    for j in 0..v {
        for ch in 0..3 {
            assert_eq!(
                onto[j][ch].to_bits(),
                (base[j][ch] + together[j][ch]).to_bits()
            );
        }
    }

    // A weight of 0 skips the light, even one no vertex could see finitely.
    let mut on_vertex = s.lights.clone();
    on_vertex.push(Light::Point(PointLight {
        position: s.positions[4],
        intensity: [1.0; 3],
    }));
    let mut skipped = vec![[0.0f32; 3]; v];
    shade(&on_vertex, &[0.8, 0.3, 1.0, 0.0], &mut skipped);
    assert_eq!(skipped, together);
}

/// Test 4: Hostile inputs: each refused with its error and nothing written, or shaded finitely.
#[test]
fn hostile_inputs_are_refused_or_finite() {
    let s = scene();
    let core = Model::parse(&s.blob).unwrap();
    let v = s.vertices;
    let (rot, lights, pos) = (&s.rotations[..], &s.lights[..], &s.positions[..]);
    let w = [1.0f32; 3];
    let mut out = vec![[7.0f32; 3]; v];
    let untouched = out.clone();

    let unset = PoseWeights::new();
    assert_eq!(
        core.shade_lights(&unset, rot, lights, &w, pos, 0, &mut out),
        Err(Error::WeightsNotSet)
    );
    let mut pose = PoseWeights::new();
    core.set_pose(&[0.0; 4], &mut pose).unwrap();

    // `count` outputs (the positions' length unless a test needs them to differ).
    let mut refuse = |rot: &[Rotation],
                      lights: &[Light],
                      w: &[f32],
                      pos: &[[f32; 3]],
                      first: usize,
                      count: usize,
                      want: Error| {
        let got = core.shade_lights(&pose, rot, lights, w, pos, first, &mut out[..count]);
        assert_eq!(got, Err(want));
        assert_eq!(out, untouched, "nothing written on {want:?}");
    };
    let mut nan_pos = pos.to_vec();
    nan_pos[6][1] = f32::NAN;
    refuse(
        rot,
        lights,
        &w,
        &nan_pos,
        0,
        v,
        Error::NonFinitePosition { index: 6 },
    );
    let short = Error::WrongLength {
        what: Input::Positions,
        expected: v,
        found: v - 1,
    };
    refuse(rot, lights, &w, &pos[..v - 1], 0, v, short);
    let mut nan_light = lights.to_vec();
    nan_light[1] = Light::Point(PointLight {
        position: [0.0, f32::NAN, 0.0],
        intensity: [1.0; 3],
    });
    let reason = LightError::NotFinite;
    refuse(
        rot,
        &nan_light,
        &w,
        pos,
        0,
        v,
        Error::BadLight { index: 1, reason },
    );
    let mut flat = lights.to_vec();
    flat[2] = Light::Sphere(SphereLight {
        position: [0.0; 3],
        radius: 0.0,
        radiance: [1.0; 3],
    });
    let reason = LightError::BadRadius;
    refuse(
        rot,
        &flat,
        &w,
        pos,
        0,
        v,
        Error::BadLight { index: 2, reason },
    );
    for bad in [-1.0f32, -0.0 - 1e-30, f32::NAN, f32::INFINITY] {
        let want = Error::BadLightWeight { index: 1 };
        refuse(rot, lights, &[1.0, bad, 1.0], pos, 0, v, want);
    }
    let few = Error::WrongLength {
        what: Input::LightWeights,
        expected: 3,
        found: 2,
    };
    refuse(rot, lights, &w[..2], pos, 0, v, few);
    let missing = Error::WrongLength {
        what: Input::BoneRotations,
        expected: 3,
        found: 2,
    };
    refuse(&rot[..2], lights, &w, pos, 0, v, missing);
    let mut skewed = rot.to_vec();
    skewed[2][0][0] *= 1.1;
    refuse(
        &skewed,
        lights,
        &w,
        pos,
        0,
        v,
        Error::BadRotation { bone: 2 },
    );
    let mut nan_rot = rot.to_vec();
    nan_rot[0][1][2] = f32::NAN;
    refuse(
        &nan_rot,
        lights,
        &w,
        pos,
        0,
        v,
        Error::BadRotation { bone: 0 },
    );
    let range = Error::VertexRange {
        first: v - 2,
        count: 4,
    };
    refuse(rot, lights, &w, &pos[..4], v - 2, 4, range);

    // Finite where the light's radiance is singular or changes form.
    let shade = |lights: &[Light], positions: &[[f32; 3]]| {
        let mut out = vec![[0.0f32; 3]; positions.len()];
        let w = vec![1.0f32; lights.len()];
        core.shade_lights(&pose, rot, lights, &w, positions, 0, &mut out)
            .unwrap();
        assert!(out.iter().flatten().all(|x| x.is_finite()), "{out:?}");
        out
    };
    // A vertex on a point light or anywhere inside its sphere (`POINT_LIGHT_RADIUS`) sees the
    // sphere's uniform radiance: the same finite bits at every distance down to 0, where a
    // delta's `I / d²` at 1.2e-7 added -8e12.
    let p = pos[3];
    let lit_at = |at: [f32; 3]| {
        let lamp = Light::Point(PointLight {
            position: at,
            intensity: [1.0; 3],
        });
        shade(&[lamp], pos)[3]
    };
    let on = lit_at(p);
    let half = 0.5 * aprt_core::POINT_LIGHT_RADIUS;
    for at in [
        [p[0], p[1], p[2] + 1e-20],
        [p[0].next_up(), p[1], p[2]],
        [p[0], p[1] + 1.2e-7, p[2]],
        [p[0] + half, p[1], p[2]],
    ] {
        assert_eq!(lit_at(at), on, "lamp at {at:?}");
    }
    // Inside a sphere light: uniform radiance, 4π L y_00 t_0 (the reference, band 0 only).
    let bulb = Light::Sphere(SphereLight {
        position: [p[0] + 0.1, p[1], p[2]],
        radius: 0.5,
        radiance: [1.0, 2.0, 3.0],
    });
    let inside = shade(&[bulb], &pos[..v]);
    let n2 = core.info().coeffs();
    let mut t = vec![0.0f32; v * n2];
    core.transfer(&pose, 0, &mut t).unwrap();
    let y00 = 0.5 / std::f32::consts::PI.sqrt();
    for ch in 0..3 {
        let want = 4.0 * std::f32::consts::PI * [1.0, 2.0, 3.0][ch] * y00 * t[3 * n2];
        assert!((inside[3][ch] - want).abs() <= 1e-5 * (1.0 + want.abs()));
    }
    // d → r from outside, on the surface, and just inside: all finite; the surface value is
    // the limit from outside (the light fills the hemisphere), inside the uniform value.
    let r = 0.5f32;
    let on = |d: f32| {
        let light = Light::Sphere(SphereLight {
            position: [p[0], p[1], p[2] + d],
            radius: r,
            radiance: [1.0; 3],
        });
        shade(&[light], &pos[..v])[3]
    };
    let surface = on(r);
    for eps in [1e-3f32, 1e-5, 1e-7] {
        let outside = on(r * (1.0 + eps));
        for ch in 0..3 {
            let gap = (outside[ch] - surface[ch]).abs();
            assert!(
                gap <= 20.0 * eps.sqrt() * (1.0 + surface[ch].abs()),
                "ε {eps}: {outside:?} vs {surface:?}"
            );
        }
        on(r * (1.0 - eps));
    }
    // Colours and weights near f32's limit: refused as overflowing, the output zeroed, never
    // Inf or NaN.
    let blaze = Light::Point(PointLight {
        position: [p[0] + 1e-3, p[1], p[2]],
        intensity: [3e38; 3],
    });
    let mut out = vec![[0.0f32; 3]; v];
    assert_eq!(
        core.shade_lights(&pose, rot, &[blaze, blaze], &[3e38, 3e38], pos, 0, &mut out),
        Err(Error::Overflow)
    );
    assert!(out.iter().flatten().all(|&x| x == 0.0), "{out:?}");
}
