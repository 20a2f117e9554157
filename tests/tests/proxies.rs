//! Occluder proxies against closed forms and an independent quadrature: a sphere's cap seen
//! from a point on a plane, proxies following their bones, culling, the combination of
//! overlapping caps, linearity in the lighting, and hostile sections.

use std::f64::consts::PI;

use aprt_core::{
    Error, LitWeights, MAX_COEFFS, Model, PoseWeights, ProxyFrame, ProxySet, Skinning,
    StreamedModel, clamped_cosine, coeff_count, eval_basis,
};
use aprt_tests::quadrature::gauss_legendre;
use aprt_tests::{Streamed, random_model};
use aprt_trainer::model::occluders::{BoneBound, ProxySection, Sphere};
use aprt_trainer::{BoneFrames, Precision, encode_model};

const Y00: f64 = 0.282_094_791_773_878_14;
const IDENTITY: Skinning = [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0];

/// One sphere on bone 0, a vertex on bone 1, neither ignoring the other.
fn one_sphere(centre: [f32; 3], radius: f32, cull: f32) -> Vec<u8> {
    ProxySection {
        spheres: vec![Sphere {
            bone: 0,
            centre,
            radius,
        }],
        bones: vec![BoneBound::default(); 2],
        cull,
    }
    .to_bytes()
    .unwrap()
}

/// The occlusion of a vertex of bone 1 at `position` with `normal`, the proxies posed by
/// `skinning`.
fn occlusion(
    section: &[u8],
    skinning: &[Skinning],
    order: usize,
    vertex: ([f32; 3], [f32; 3]),
) -> (bool, Vec<f64>) {
    let set = ProxySet::parse(section, skinning.len()).unwrap();
    let mut frame = ProxyFrame::new();
    set.pose(skinning, &mut frame).unwrap();
    let mut d = [0.0f32; MAX_COEFFS];
    let hit = frame.occlusion(order, 1, vertex, None, &mut d).unwrap();
    (
        hit,
        d[..coeff_count(order)]
            .iter()
            .map(|&x| f64::from(x))
            .collect(),
    )
}

/// `∫_cap max(n·ω, 0) y_c(ω) dω` by quadrature in the cap's own frame: Gauss–Legendre in
/// `cos θ` over `[cos α, 1]`, uniform in φ.
fn cap_projection(order: usize, axis: [f64; 3], sin_alpha: f64, normal: [f64; 3]) -> Vec<f64> {
    let (nt, np) = (96, 512);
    let (mut nodes, mut weights) = (vec![0.0; nt], vec![0.0; nt]);
    gauss_legendre(nt, &mut nodes, &mut weights);
    let cos_alpha = (1.0 - sin_alpha * sin_alpha).sqrt();
    // An orthonormal frame around the axis.
    let helper = if axis[2].abs() < 0.9 {
        [0.0, 0.0, 1.0]
    } else {
        [1.0, 0.0, 0.0]
    };
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let norm = |a: [f64; 3]| {
        let l = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
        a.map(|x| x / l)
    };
    let u = norm(cross(axis, helper));
    let w = cross(axis, u);
    let n2 = coeff_count(order);
    let mut out = vec![0.0; n2];
    let mut y = [0.0f32; MAX_COEFFS];
    for (t, wt) in nodes.iter().zip(&weights) {
        // Map [−1, 1] onto [cos α, 1].
        let ct = cos_alpha + (t + 1.0) * 0.5 * (1.0 - cos_alpha);
        let st = (1.0 - ct * ct).max(0.0).sqrt();
        let wct = wt * 0.5 * (1.0 - cos_alpha);
        for k in 0..np {
            let phi = 2.0 * PI * (k as f64 + 0.5) / np as f64;
            let dir = [0, 1, 2].map(|i| ct * axis[i] + st * (phi.cos() * u[i] + phi.sin() * w[i]));
            let cosine = (dir[0] * normal[0] + dir[1] * normal[1] + dir[2] * normal[2]).max(0.0);
            if cosine == 0.0 {
                continue;
            }
            eval_basis(order, dir.map(|x| x as f32), &mut y).unwrap();
            let dw = wct * 2.0 * PI / np as f64 * cosine;
            for c in 0..n2 {
                out[c] += dw * f64::from(y[c]);
            }
        }
    }
    out
}

fn relative(a: &[f64], b: &[f64]) -> f64 {
    let diff: f64 = a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum();
    let norm: f64 = b.iter().map(|y| y * y).sum();
    (diff / norm).sqrt()
}

#[test]
fn a_sphere_over_a_plane_occludes_its_closed_form_cap() {
    let radius = 0.3f32;
    for height in [0.45f32, 0.6, 1.0, 2.0, 4.0] {
        for tilt_deg in [0.0f32, 20.0, 40.0, 60.0] {
            let tilt = tilt_deg.to_radians();
            let centre = [height * tilt.sin(), 0.0, height * tilt.cos()];
            let section = one_sphere(centre, radius, 0.0);
            let (hit, d) = occlusion(&section, &[IDENTITY; 2], 4, ([0.0; 3], [0.0, 0.0, 1.0]));
            assert!(hit);
            // Above the horizon the cosine-weighted cap is π sin²α cos β, exactly.
            let sin2 = f64::from(radius / height).powi(2);
            let closed = PI * sin2 * f64::from(tilt.cos());
            let above = (f64::from(tilt) + sin2.sqrt().asin()) < PI / 2.0;
            let axis = [tilt.sin(), 0.0, tilt.cos()].map(f64::from);
            let quad = cap_projection(4, axis, sin2.sqrt(), [0.0, 0.0, 1.0]);
            if above {
                assert!(
                    (d[0] - Y00 * closed).abs() < 1e-5 * closed.max(1e-3),
                    "h {height} tilt {tilt_deg}: D00 {} against {}",
                    d[0],
                    Y00 * closed
                );
            }
            // Band 0 is exact in every case, and every band for a cap about the normal; a
            // tilted cap's higher bands are off by the second order of its tilt's shift (6 %
            // of the vector for a cap of 42° tilted 40°, 0.2 % at 17°).
            assert!(
                (d[0] - quad[0]).abs() < 2e-4 * quad[0],
                "h {height} tilt {tilt_deg}: D00 {} against quadrature {}",
                d[0],
                quad[0]
            );
            let err = relative(&d, &quad);
            // The tilt's shift of the bands is first-order: the rest grows with the cap.
            let bound = if above { 0.15 * sin2 } else { 0.35 * sin2 };
            assert!(
                err < bound,
                "h {height} tilt {tilt_deg}: relative error {err}"
            );
        }
    }
}

#[test]
fn a_cap_cut_by_the_horizon_keeps_its_exact_form_factor() {
    // A sphere low over the plane, half of it below the vertex's horizon.
    for (tilt_deg, height) in [(75.0f32, 1.0f32), (85.0, 0.8), (95.0, 1.2)] {
        let tilt = tilt_deg.to_radians();
        let radius = 0.3f32;
        let centre = [height * tilt.sin(), 0.0, height * tilt.cos()];
        let section = one_sphere(centre, radius, 0.0);
        let (_, d) = occlusion(&section, &[IDENTITY; 2], 3, ([0.0; 3], [0.0, 0.0, 1.0]));
        let axis = [tilt.sin(), 0.0, tilt.cos()].map(f64::from);
        let quad = cap_projection(3, axis, f64::from(radius / height), [0.0, 0.0, 1.0]);
        assert!(
            (d[0] - quad[0]).abs() < 1e-3 * quad[0].abs() + 1e-7,
            "tilt {tilt_deg}: D00 {} against quadrature {}",
            d[0],
            quad[0]
        );
    }
    // Wholly below the horizon: nothing.
    let section = one_sphere([0.0, 0.0, -2.0], 0.3, 0.0);
    let (hit, d) = occlusion(&section, &[IDENTITY; 2], 3, ([0.0; 3], [0.0, 0.0, 1.0]));
    assert!(!hit && d.iter().all(|&x| x == 0.0));
}

#[test]
fn a_vertex_inside_a_sphere_loses_its_whole_lobe() {
    let section = one_sphere([0.1, 0.0, 0.0], 0.5, 0.0);
    let normal = [0.0f32, 0.6, 0.8];
    let (hit, d) = occlusion(&section, &[IDENTITY; 2], 4, ([0.0; 3], normal));
    let mut lobe = [0.0f32; 16];
    clamped_cosine(4, normal, &mut lobe).unwrap();
    assert!(hit);
    for (a, b) in d.iter().zip(lobe) {
        assert!(
            (a - f64::from(b)).abs() < 1e-5,
            "{a} against the lobe's {b}"
        );
    }
}

#[test]
fn overlapping_caps_combine_by_their_visible_fractions() {
    let sphere = Sphere {
        bone: 0,
        centre: [0.0, 0.0, 1.0],
        radius: 0.5,
    };
    let twice = ProxySection {
        spheres: vec![sphere, sphere],
        bones: vec![BoneBound::default(); 2],
        cull: 0.0,
    }
    .to_bytes()
    .unwrap();
    let (_, d) = occlusion(&twice, &[IDENTITY; 2], 2, ([0.0; 3], [0.0, 0.0, 1.0]));
    let f = PI * 0.25; // π sin²α cos 0
    let union = PI * (1.0 - (1.0 - f / PI).powi(2));
    assert!(
        (d[0] - Y00 * union).abs() < 1e-5,
        "{} against {}",
        d[0],
        Y00 * union
    );
}

#[test]
fn proxies_follow_their_bone_and_far_vertices_see_nothing() {
    // Bone 0 turned by 90° about x: the sphere at (0, 0, 1) goes to (0, −1, 0).
    let turned: Skinning = [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 1.0, 0.0, 0.0];
    let vertex = ([0.0f32, 0.0, 0.0], [0.0f32, -0.6, 0.8]);
    let on_bone = one_sphere([0.0, 0.0, 1.0], 0.4, 0.01);
    let (_, moved) = occlusion(&on_bone, &[turned, IDENTITY], 4, vertex);
    let placed = one_sphere([0.0, -1.0, 0.0], 0.4, 0.01);
    let (_, expected) = occlusion(&placed, &[IDENTITY; 2], 4, vertex);
    let (_, before) = occlusion(&on_bone, &[IDENTITY; 2], 4, vertex);
    assert!(relative(&moved, &expected) < 1e-5);
    assert!(relative(&moved, &before) > 0.5, "the cap did not move");
    // A translated bone carries its sphere away: beyond r/√cull the correction is exactly 0.
    let far: Skinning = [1.0, 0.0, 0.0, 50.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0];
    let (hit, d) = occlusion(&on_bone, &[far, IDENTITY], 4, vertex);
    assert!(!hit && d.iter().all(|&x| x == 0.0));
}

#[test]
fn a_bone_ignores_its_own_and_its_neighbours_proxies() {
    let mut section = ProxySection {
        spheres: vec![Sphere {
            bone: 0,
            centre: [0.0, 0.0, 1.0],
            radius: 0.4,
        }],
        bones: vec![BoneBound::default(); 2],
        cull: 0.0,
    };
    section.bones[1].ignored = 1;
    let (hit, d) = occlusion(
        &section.to_bytes().unwrap(),
        &[IDENTITY; 2],
        4,
        ([0.0; 3], [0.0, 0.0, 1.0]),
    );
    assert!(!hit && d.iter().all(|&x| x == 0.0));
}

/// A bone-frame model of 24 vertices on 3 bones with one proxy on bone 0 over the vertices
/// of bone 2.
fn model_with_proxies() -> Vec<u8> {
    let mut model = random_model(3, 24, 5, 3, Some(4));
    model.bones = Some(BoneFrames {
        count: 3,
        vertex_bone: (0..24).map(|j| (j / 8) as u16).collect(),
    });
    model.proxies = Some(
        ProxySection {
            spheres: vec![Sphere {
                bone: 0,
                centre: [0.0, 0.0, 1.0],
                radius: 0.5,
            }],
            bones: vec![
                BoneBound {
                    ignored: 1,
                    ..BoneBound::default()
                },
                BoneBound::default(),
                BoneBound {
                    centre: [0.0, 0.0, 0.0],
                    radius: 0.5,
                    ignored: 0,
                },
            ],
            cull: 0.02,
        }
        .to_bytes()
        .unwrap(),
    );
    encode_model(&model, Precision::F32).unwrap()
}

#[test]
fn the_correction_is_linear_in_the_lighting_and_streams_like_it_reads() {
    let blob = model_with_proxies();
    let model = Model::parse(&blob).unwrap();
    let info = *model.info();
    assert!(info.has_proxies());
    let mut frame = ProxyFrame::new();
    model.pose_proxies(&[IDENTITY; 3], &mut frame).unwrap();
    // Bone 1's vertices lie far away, where its bound says.
    let positions: Vec<[f32; 3]> = (0..24)
        .map(|j| {
            [
                0.02 * (j % 8) as f32 + if j / 8 == 1 { 10.0 } else { 0.0 },
                0.0,
                0.0,
            ]
        })
        .collect();
    let normals = vec![[0.0f32, 0.0, 1.0]; 24];
    let shade = |lighting: &[f32]| {
        let mut out = vec![0.0f32; 24];
        model
            .occlude(&frame, lighting, &positions, &normals, 0, &mut out)
            .unwrap();
        out
    };
    let (a, b) = (
        [1.0f32, 0.2, 0.7, -0.1, 0.3, 0.0, 0.1, 0.2, -0.3],
        [0.0f32, 1.0, -0.5, 0.4, 0.0, 0.2, 0.0, 0.0, 0.6],
    );
    let sum: Vec<f32> = a.iter().zip(&b).map(|(x, y)| x + 2.0 * y).collect();
    let (sa, sb, ss) = (shade(&a), shade(&b), shade(&sum));
    for j in 0..24 {
        assert!((ss[j] - (sa[j] + 2.0 * sb[j])).abs() < 1e-5, "vertex {j}");
    }
    // Bones 0 and 1 ignore the sphere or lie beyond its reach; bone 2's vertices see it.
    assert!(sa[..16].iter().all(|&x| x == 0.0));
    assert!(sa[16..].iter().all(|&x| x < 0.0));
    // The transfer path subtracts the same vectors: shading its difference gives `occlude`.
    let identity = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let mut t = vec![0.0f32; 24 * 9];
    model
        .occlude_transfer(&frame, &[identity; 3], &positions, &normals, 0, &mut t)
        .unwrap();
    for j in 0..24 {
        let dot: f32 = t[j * 9..(j + 1) * 9]
            .iter()
            .zip(&a)
            .map(|(d, l)| d * l)
            .sum();
        assert!(
            (dot - sa[j]).abs() < 1e-5,
            "vertex {j}: {dot} against {}",
            sa[j]
        );
    }
    // `occlusions` hands out the same vectors, for lighting that varies per vertex.
    let mut seen = [0.0f32; 24];
    model
        .occlusions(&frame, &positions, &normals, 0, |i, d| {
            seen[i] = -d.iter().zip(&a).map(|(d, l)| d * l).sum::<f32>();
        })
        .unwrap();
    for j in 0..24 {
        assert!((seen[j] - sa[j]).abs() < 1e-6, "vertex {j}");
    }
    // The streamed model agrees to the bit.
    let mut scratch = vec![0u8; 256];
    let mut streamed = StreamedModel::open(Streamed::new(&blob), &mut scratch).unwrap();
    let mut sframe = ProxyFrame::new();
    streamed.pose_proxies(&[IDENTITY; 3], &mut sframe).unwrap();
    let mut out = vec![0.0f32; 24];
    streamed
        .occlude(&sframe, &a, &positions, &normals, 0, &mut out)
        .unwrap();
    assert_eq!(out, sa);
    // A frame posed for one model is refused by another; bad inputs are errors.
    let other = Model::parse(include_bytes!("../../fixtures/golden/v1-bones.aprt")).unwrap();
    let mut lit = vec![0.0f32; 24];
    assert_eq!(
        model.occlude(&ProxyFrame::new(), &a, &positions, &normals, 0, &mut lit),
        Err(Error::WeightsNotSet)
    );
    assert_eq!(
        other.pose_proxies(&[IDENTITY; 3], &mut sframe),
        Err(Error::NoProxies)
    );
    let mut nan = IDENTITY;
    nan[3] = f32::NAN;
    assert_eq!(
        model.pose_proxies(&[IDENTITY, nan, IDENTITY], &mut frame),
        Err(Error::BadSkinning { bone: 1 })
    );
    let _ = (PoseWeights::<8>::sized(), LitWeights::<8>::sized());
}
