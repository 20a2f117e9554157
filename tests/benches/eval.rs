//! Per-frame cost of the core evaluator against a plain memory copy of the same bytes (the
//! model's per-vertex rows), on a model the size of the paper's Master Pai PCA(8,22): 11.5k
//! vertices, 54 angles, order 6, at each storage precision. The memcpy and every step run in
//! interleaved batches (`interleaved_seconds`), and each ratio is the median of per-round
//! ratios, so the machine's drift cancels. A last table times each precision's shading against
//! the f32 shading of the same model, interleaved the same way: what the precision knob buys.
//! One core. `cargo bench -p aprt-tests --bench eval`.

use std::hint::black_box;
use std::time::Duration;

use aprt_core::format::read_header;
use aprt_core::{LitWeights, Model, PoseWeights, SectionKind, StreamedModel};
use aprt_tests::{Streamed, interleaved_seconds, median_ratio, noise, random_model, with_cosines};
use aprt_trainer::{BoneFrames, LinearModel, Precision, encode_model};

const VERTICES: usize = 11_500;
const JOINTS: usize = 54;
const ORDER: usize = 6;
const ROUNDS: usize = 15;

/// One benchmarked model: its name, k_a, k_v (`None`: identity), precision, bone count, and
/// whether every angle's cosine is a feature.
type Case = (&'static str, usize, Option<usize>, Precision, usize, bool);

const CASES: [Case; 9] = [
    ("PCA(8,22) f32", 8, Some(22), Precision::F32, 0, false),
    ("PCA(8,22) f16", 8, Some(22), Precision::F16, 0, false),
    ("PCA(8,22) i8", 8, Some(22), Precision::I8, 0, false),
    (
        "PCA(8,22) f32, cosines",
        8,
        Some(22),
        Precision::F32,
        0,
        true,
    ),
    (
        "PCA(8,22) f32, 30 bones",
        8,
        Some(22),
        Precision::F32,
        30,
        false,
    ),
    (
        "PCA(8,22) i8, 30 bones",
        8,
        Some(22),
        Precision::I8,
        30,
        false,
    ),
    ("full linear (k_a 8) f32", 8, None, Precision::F32, 0, false),
    ("full linear (k_a 8) f16", 8, None, Precision::F16, 0, false),
    ("full linear (k_a 8) i8", 8, None, Precision::I8, 0, false),
];

fn model(&(_, ka, kv, _, bones, cosines): &Case) -> LinearModel {
    let mut m = random_model(ORDER, VERTICES, JOINTS, ka, kv);
    // Values in [-0.5, 0.5): realistic magnitudes, safely inside f16's range.
    m.weights.iter_mut().for_each(|x| *x *= 0.5);
    if cosines {
        // Every angle's cosine beside it: 108 pose features.
        m = with_cosines(m, &[true; JOINTS]);
    }
    if bones > 0 {
        // Contiguous runs of vertices per bone, as body parts are in real meshes.
        let vertex_bone = (0..VERTICES)
            .map(|j| (j * bones / VERTICES) as u16)
            .collect();
        m.bones = Some(BoneFrames {
            count: bones,
            vertex_bone,
        });
    }
    m
}

/// The per-vertex rows of a blob: what a frame streams.
fn rows(blob: &[u8]) -> &[u8] {
    read_header(blob)
        .unwrap()
        .sections
        .iter()
        .find(|e| {
            let kind = SectionKind::from_tag(e.kind);
            kind == SectionKind::VertexBasis || kind == SectionKind::VertexWeights
        })
        .map(|e| &blob[e.offset as usize..(e.offset + e.len) as usize])
        .unwrap()
}

fn main() {
    let budget = Duration::from_millis(4000);
    let angles: Vec<f32> = noise(7, JOINTS).iter().map(|&x| x as f32).collect();
    let light: Vec<f32> = noise(8, ORDER * ORDER).iter().map(|&x| x as f32).collect();
    println!(
        "aprt-core evaluator, one core; {VERTICES} vertices, {JOINTS} angles, order {ORDER}; \
         medians of {ROUNDS} interleaved rounds"
    );
    println!(
        "{:<42} {:>10} {:>11} {:>10} {:>11}",
        "model / step", "row bytes", "µs/frame", "frames/s", "× memcpy"
    );
    for case in &CASES {
        let rotations = bone_rotations(case.4);
        let blob = encode_model(&model(case), case.3).unwrap();
        let m = Model::parse(&blob).unwrap();
        let rows = rows(&blob);
        let mut copy = vec![0u8; rows.len()];
        let mut pose = Box::new(PoseWeights::new());
        let mut lit = Box::new(LitWeights::new());
        let mut shading = vec![0.0f32; VERTICES];
        let mut transfer = vec![0.0f32; VERTICES * ORDER * ORDER];
        let mut scratch = vec![0u8; 16 * 1024];
        let mut streamed = StreamedModel::open(Streamed::new(&blob), &mut scratch).unwrap();
        // Each step its own state, as the closures are alive together.
        let (mut pose2, mut lit2) = (Box::new(PoseWeights::new()), Box::new(LitWeights::new()));
        let mut pose3 = Box::new(PoseWeights::new());
        let mut shading2 = vec![0.0f32; VERTICES];
        let mut memcpy = || {
            copy.copy_from_slice(black_box(rows));
            black_box(&copy);
        };
        let mut shade = || {
            m.set_pose(black_box(&angles), &mut pose).unwrap();
            m.light(&pose, black_box(&light), &rotations, &mut lit)
                .unwrap();
            m.shade(&lit, 0, &mut shading).unwrap();
            black_box(&shading);
        };
        let mut shade_streamed = || {
            streamed.set_pose(black_box(&angles), &mut pose2).unwrap();
            streamed
                .light(&pose2, black_box(&light), &rotations, &mut lit2)
                .unwrap();
            streamed.shade(&lit2, 0, &mut shading2).unwrap();
            black_box(&shading2);
        };
        let mut full_transfer = || {
            m.set_pose(black_box(&angles), &mut pose3).unwrap();
            m.transfer(&pose3, 0, &mut transfer).unwrap();
            black_box(&transfer);
        };
        let times = interleaved_seconds(
            budget,
            ROUNDS,
            &mut [
                &mut memcpy,
                &mut shade,
                &mut shade_streamed,
                &mut full_transfer,
            ],
        );
        let steps = [
            "memcpy of the vertex rows",
            "shade, resident",
            "shade, streamed via 16 KiB",
            "transfer (n² per vertex)",
        ];
        for (step, t) in steps.iter().zip(&times) {
            let secs = median_ratio(t, &[1.0; ROUNDS]);
            println!(
                "{:<42} {:>10} {:>11.1} {:>10.0} {:>10.2}x",
                format!("{}: {step}", case.0),
                rows.len(),
                secs * 1e6,
                1.0 / secs,
                median_ratio(t, &times[0])
            );
        }
    }
    println!(
        "\n{:<42} {:>11} {:>11}",
        "shade against f32's", "µs/frame", "× f32"
    );
    // (f32, f16, i8) in the world frame; (f32, i8) in 30 bone frames; (f32, f16, i8) unreduced.
    for group in [&CASES[0..3], &CASES[4..6], &CASES[6..9]] {
        precisions(group, budget, &angles, &light);
    }
}

/// Shading of `cases` (one model in several precisions, f32 first) interleaved in one run,
/// each against the first.
fn precisions(cases: &[Case], budget: Duration, angles: &[f32], light: &[f32]) {
    let blobs: Vec<Vec<u8>> = cases
        .iter()
        .map(|c| encode_model(&model(c), c.3).unwrap())
        .collect();
    let rotations = bone_rotations(cases[0].4);
    let mut steps: Vec<Box<dyn FnMut() + '_>> = blobs
        .iter()
        .map(|blob| {
            let m = Model::parse(blob).unwrap();
            let (mut pose, mut lit) = (Box::new(PoseWeights::new()), Box::new(LitWeights::new()));
            let mut shading = vec![0.0f32; VERTICES];
            let rotations = &rotations;
            Box::new(move || {
                m.set_pose(black_box(angles), &mut pose).unwrap();
                m.light(&pose, black_box(light), rotations, &mut lit)
                    .unwrap();
                m.shade(&lit, 0, &mut shading).unwrap();
                black_box(&shading);
            }) as Box<dyn FnMut()>
        })
        .collect();
    let mut refs: Vec<&mut dyn FnMut()> = steps.iter_mut().map(|s| &mut **s as _).collect();
    let times = interleaved_seconds(budget, ROUNDS, &mut refs);
    for (case, t) in cases.iter().zip(&times) {
        println!(
            "{:<42} {:>11.1} {:>10.2}x",
            case.0,
            median_ratio(t, &[1e-6; ROUNDS]),
            median_ratio(t, &times[0])
        );
    }
}

/// `bones` rotations about z, a tenth of a radian apart.
fn bone_rotations(bones: usize) -> Vec<[[f32; 3]; 3]> {
    (0..bones)
        .map(|b| {
            let (s, c) = (0.1 * b as f32).sin_cos();
            [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
        })
        .collect()
}
