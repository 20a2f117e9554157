//! Per-frame cost of the core evaluator against a plain memory copy of the same bytes, on a
//! model the size of the paper's Master Pai PCA(8,22): 11.5k vertices, 54 angles, order 6.
//! One core, one run, ratios side by side. `cargo bench -p aprt-tests --bench eval`.

use std::hint::black_box;
use std::time::Duration;

use aprt_core::format::read_header;
use aprt_core::{LitWeights, Model, PoseWeights, SectionKind, StreamedModel};
use aprt_tests::{Streamed, median_seconds as time, noise, random_model, with_cosines};
use aprt_trainer::{BoneFrames, LinearModel, Precision, encode_model};

const VERTICES: usize = 11_500;
const JOINTS: usize = 54;
const ORDER: usize = 6;

fn model(ka: usize, kv: Option<usize>) -> LinearModel {
    let mut m = random_model(ORDER, VERTICES, JOINTS, ka, kv);
    // Values in [-0.5, 0.5): realistic magnitudes, safely inside f16's range.
    m.weights.iter_mut().for_each(|x| *x *= 0.5);
    m
}

fn main() {
    let budget = Duration::from_millis(1500);
    let angles: Vec<f32> = noise(7, JOINTS).iter().map(|&x| x as f32).collect();
    let light: Vec<f32> = noise(8, ORDER * ORDER).iter().map(|&x| x as f32).collect();
    println!("aprt-core evaluator, one core; {VERTICES} vertices, {JOINTS} angles, order {ORDER}");
    println!(
        "{:<34} {:>10} {:>11} {:>10} {:>9} {:>13}",
        "model / step", "bytes", "µs/frame", "frames/s", "MFLOP", "× memcpy"
    );
    for (name, ka, kv, precision, bones, cosines) in [
        ("PCA(8,22) f32", 8, Some(22), Precision::F32, 0, false),
        (
            "PCA(8,22) f32, cosine features",
            8,
            Some(22),
            Precision::F32,
            0,
            true,
        ),
        ("PCA(8,22) f16", 8, Some(22), Precision::F16, 0, false),
        (
            "PCA(8,22) f32, 30 bone frames",
            8,
            Some(22),
            Precision::F32,
            30,
            false,
        ),
        (
            "full linear (k_a 8, no k_v) f32",
            8,
            None,
            Precision::F32,
            0,
            false,
        ),
    ] {
        let mut reference = model(ka, kv);
        if cosines {
            // Every angle's cosine beside it: 108 pose features.
            reference = with_cosines(reference, &[true; JOINTS]);
        }
        if bones > 0 {
            // Contiguous runs of vertices per bone, as body parts are in real meshes.
            let vertex_bone = (0..VERTICES)
                .map(|j| (j * bones / VERTICES) as u16)
                .collect();
            reference.bones = Some(BoneFrames {
                count: bones,
                vertex_bone,
            });
        }
        let rotations: Vec<[[f32; 3]; 3]> = (0..bones)
            .map(|b| {
                let (s, c) = (0.1 * b as f32).sin_cos();
                [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
            })
            .collect();
        let blob = encode_model(&reference, precision).unwrap();
        let m = Model::parse(&blob).unwrap();
        let rows = read_header(&blob)
            .unwrap()
            .sections
            .iter()
            .find(|e| {
                let kind = SectionKind::from_tag(e.kind);
                kind == SectionKind::VertexBasis || kind == SectionKind::VertexWeights
            })
            .map(|e| &blob[e.offset as usize..(e.offset + e.len) as usize])
            .unwrap();
        let row_bytes = rows.len();
        let mut copy = vec![0u8; row_bytes];
        let memcpy = time(budget, || {
            copy.copy_from_slice(black_box(rows));
            black_box(&copy);
        });
        let mut pose = Box::new(PoseWeights::new());
        let mut lit = Box::new(LitWeights::new());
        let mut shading = vec![0.0f32; VERTICES];
        let mut transfer = vec![0.0f32; VERTICES * ORDER * ORDER];
        let shade = time(budget, || {
            m.set_pose(black_box(&angles), &mut pose).unwrap();
            m.light(&pose, black_box(&light), &rotations, &mut lit)
                .unwrap();
            m.shade(&lit, 0, &mut shading).unwrap();
            black_box(&shading);
        });
        let mut scratch = vec![0u8; 16 * 1024];
        let mut streamed = StreamedModel::open(Streamed::new(&blob), &mut scratch).unwrap();
        let shade_streamed = time(budget, || {
            streamed.set_pose(black_box(&angles), &mut pose).unwrap();
            streamed
                .light(&pose, black_box(&light), &rotations, &mut lit)
                .unwrap();
            streamed.shade(&lit, 0, &mut shading).unwrap();
            black_box(&shading);
        });
        let full_transfer = time(budget, || {
            m.set_pose(black_box(&angles), &mut pose).unwrap();
            m.transfer(&pose, 0, &mut transfer).unwrap();
            black_box(&transfer);
        });
        let n2 = (ORDER * ORDER) as f64;
        let (v, ka, width) = (VERTICES as f64, ka as f64, m.info().row_width() as f64);
        let pose_flops = 2.0 * ka * m.info().feature_len() as f64
            + if kv.is_some() {
                2.0 * n2 * (ka + 1.0) * width
            } else {
                0.0
            };
        let light_flops = 2.0 * n2 * if kv.is_some() { width } else { ka + 1.0 };
        let shade_flops = pose_flops + light_flops + 2.0 * width * v;
        let transfer_flops =
            pose_flops + 2.0 * n2 * if kv.is_some() { width } else { ka + 1.0 } * v;
        for (step, secs, flops) in [
            ("memcpy of the vertex rows", memcpy, 0.0),
            ("shade, resident", shade, shade_flops),
            ("shade, streamed via 16 KiB", shade_streamed, shade_flops),
            ("transfer (n² per vertex)", full_transfer, transfer_flops),
        ] {
            println!(
                "{:<34} {:>10} {:>11.1} {:>10.0} {:>9.2} {:>12.2}x",
                format!("{name}: {step}"),
                if flops == 0.0 {
                    row_bytes.to_string()
                } else {
                    blob.len().to_string()
                },
                secs * 1e6,
                1.0 / secs,
                flops / 1e6,
                secs / memcpy
            );
        }
    }
}
