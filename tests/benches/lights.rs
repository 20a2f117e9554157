//! 64 sphere lights on the built-in character, through aprt-core: every light per vertex
//! through the transfer ("all analytic") against the irradiance rig carrying the far lights and
//! only the near ones per vertex (*Irradiance Rigs*; the paper: 449 against 62 frames/s on a
//! GPU). The two are timed alternately, seven rounds, in one run, so a drift in the machine's
//! speed falls on both. `cargo bench -p aprt-tests --bench lights`.

use std::hint::black_box;
use std::time::Duration;

use aprt_core::{Light, Model, Placement, PoseWeights, RigLitWeights, Rotation, SphereLight};
use aprt_tests::{median_seconds, noise, random_model};
use aprt_trainer::irradiance_rig::{RigKind, fit_rig, rig_vectors};
use aprt_trainer::{BoneFrames, Character, LinearModel, Precision, Rig, encode_model_with_rig};

const ORDER: usize = 4;
const BONES: usize = 20;
const LIGHTS: usize = 64;
const NEAR: usize = 4;

/// 64 sphere lights: `NEAR` a hand's breadth from the body, the rest 3 to 15 m away, all of
/// radius 5 cm and a brightness that lights the body to about mid grey.
fn lights(centre: [f32; 3]) -> Vec<Light> {
    let u = noise(11, 4 * LIGHTS);
    (0..LIGHTS)
        .map(|i| {
            let r = &u[4 * i..4 * i + 4];
            let dir = [r[0] as f32, r[1] as f32, 0.5 * r[2] as f32];
            let n = dir.iter().map(|x| x * x).sum::<f32>().sqrt().max(1e-3);
            let d = if i < NEAR {
                0.45
            } else {
                3.0 + 12.0 * (r[3] as f32 + 0.5)
            };
            Light::Sphere(SphereLight {
                position: std::array::from_fn(|k| centre[k] + d * dir[k] / n),
                radius: 0.05,
                // Irradiance ≈ π L r²/d² ≈ 0.5 / 64 per light at its distance.
                radiance: [d * d * 0.05; 3],
            })
        })
        .collect()
}

/// A random bone-frame model the size of the benchmark's (order 4, k_a 8, k_v 32, contiguous
/// runs of vertices per bone, as body parts are) and one rotation per bone.
fn bone_model(v: usize) -> (LinearModel, Vec<Rotation>) {
    let mut reference = random_model(ORDER, v, 23, 8, Some(32));
    reference.weights.iter_mut().for_each(|x| *x *= 0.5);
    reference.bones = Some(BoneFrames {
        count: BONES,
        vertex_bone: (0..v).map(|j| (j * BONES / v) as u16).collect(),
    });
    let rotations = (0..BONES)
        .map(|b| {
            let (s, c) = (0.1 * b as f32).sin_cos();
            [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
        })
        .collect();
    (reference, rotations)
}

/// Seconds per call of `a` and `b`, timed alternately over seven rounds so a drift in the
/// machine's speed falls on both: the medians of each, and the median and range of `a / b`.
fn alternate(budget: Duration, mut a: impl FnMut(), mut b: impl FnMut()) -> ([f64; 2], [f64; 3]) {
    let (mut sa, mut sb, mut ratios) = (Vec::new(), Vec::new(), Vec::new());
    for _ in 0..7 {
        let (ta, tb) = (
            median_seconds(budget / 2, &mut a),
            median_seconds(budget / 2, &mut b),
        );
        sa.push(ta);
        sb.push(tb);
        ratios.push(ta / tb);
    }
    for xs in [&mut sa, &mut sb, &mut ratios] {
        xs.sort_by(f64::total_cmp);
    }
    ([sa[3], sb[3]], [ratios[3], ratios[0], ratios[6]])
}

fn main() {
    let budget = Duration::from_millis(600);
    let human = Character::builtin();
    let walk = human.clip("walk").unwrap();
    let mesh = human.pose(&walk.frames[10]).unwrap();
    let v = mesh.vertex_count();
    let (reference, rotations) = bone_model(v);
    let angles: Vec<f32> = noise(7, 23).iter().map(|&x| x as f32).collect();
    let target = 1.0;
    println!(
        "built-in human: {v} vertices, {BONES} bone frames, order {ORDER}, k_v 32; {LIGHTS} sphere lights, {NEAR} of them near"
    );
    println!(
        "{:<40} {:>8} {:>10} {:>10} {:>9} {:>9}   all analytic / rig + analytic, alternated",
        "rig", "vectors", "in rig", "per vertex", "us/frame", "frames/s"
    );
    for kind in [
        "constant",
        "gradient",
        "mixed:x=constant,y=gradient,z=lattice3",
        "lattice:2x2x3",
        "lattice:4x2x8",
    ] {
        let kind: RigKind = kind.parse().unwrap();
        let mut fitted = fit_rig(kind, &[human.bind_mesh()], None);
        fitted.tabulate(human.bind_mesh(), ORDER).unwrap();
        let blob =
            encode_model_with_rig(&reference, Precision::F32, Some(&fitted.bytes())).unwrap();
        let model = Model::parse(&blob).unwrap();
        let rig = model.irradiance_rig().unwrap();
        let lights = lights(rig.centre());
        let mut pose = Box::new(PoseWeights::new());
        let mut buffer = vec![0.0f32; model.info().rig_lit_weights_len(rig.vectors())];
        let mut out = vec![[0.0f32; 3]; v];
        let ones = vec![1.0f32; LIGHTS];
        let all_analytic = || {
            model.set_pose(black_box(&angles), &mut pose).unwrap();
            out.fill([0.0; 3]);
            model
                .shade_lights(
                    &pose,
                    &rotations,
                    &lights,
                    &ones,
                    &mesh.positions,
                    0,
                    &mut out,
                )
                .unwrap();
            black_box(&out);
        };
        let mut out2 = vec![[0.0f32; 3]; v];
        let mut counts = (0, 0);
        let mut pose2 = Box::new(PoseWeights::new());
        let split = || {
            let pose = &mut pose2;
            model.set_pose(black_box(&angles), pose).unwrap();
            let place = Placement::IDENTITY;
            let shares: Vec<f32> = lights
                .iter()
                .map(|l| rig.share_of(l, &place, target, aprt_core::DEFAULT_BAND))
                .collect();
            let in_rig: Vec<Light> = lights
                .iter()
                .zip(&shares)
                .map(|(l, &s)| l.scaled(s))
                .collect();
            let vectors = rig_vectors(&rig, &in_rig, ORDER, &place).unwrap();
            let mut lit = RigLitWeights::new(&mut buffer);
            model
                .light_rig(pose, &vectors, &rotations, &mut lit)
                .unwrap();
            model
                .shade_rig(&lit, &rig, &place, &mesh.positions, 0, &mut out2)
                .unwrap();
            let rest: Vec<f32> = shares.iter().map(|s| 1.0 - s).collect();
            model
                .shade_lights(
                    pose,
                    &rotations,
                    &lights,
                    &rest,
                    &mesh.positions,
                    0,
                    &mut out2,
                )
                .unwrap();
            counts = (
                shares.iter().filter(|&&s| s > 0.0).count(),
                shares.iter().filter(|&&s| s < 1.0).count(),
            );
            black_box(&out2);
        };
        let ([analytic_s, split_s], [ratio, low, high]) = alternate(budget, all_analytic, split);
        println!(
            "{:<40} {:>8} {:>10} {:>10} {:>9.0} {:>9.1}   all analytic {:.0} us ({:.1} frames/s): median {:.2}x, range {:.2}x to {:.2}x",
            kind.to_string(),
            rig.vectors(),
            counts.0,
            counts.1,
            split_s * 1e6,
            1.0 / split_s,
            analytic_s * 1e6,
            1.0 / analytic_s,
            ratio,
            low,
            high
        );
    }
}
