//! The kernels on the device against aprt-core on the CPU: shading and transfer of every
//! golden blob and of the built-in character's model (bone frames, occluder proxies, 13,022
//! vertices) in f32, f16 and i8 rows, within [`aprt_gpu::TOLERANCE`] of each frame's peak.

mod common;

use std::path::Path;

use aprt_core::{Error, LitWeights, Model, PoseWeights, Rotation};
use aprt_gpu::{FrameError, Gpu, GpuModel, TOLERANCE};
use common::{builtin_models, gpu_or_skip, trainer};

const GOLDEN: [&str; 5] = [
    "v1-world.aprt",
    "v1-bones.aprt",
    "v1-proxies.aprt",
    "v1-atlas.aprt",
    "v1-atlas-uvs.aprt",
];

fn golden(name: &str) -> Vec<u8> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../fixtures/golden")
        .join(name);
    std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// A proper rotation per bone, each about its own axis by its own angle.
fn rotations(bones: usize) -> Vec<Rotation> {
    (0..bones)
        .map(|b| {
            let (s, c) = (0.3 + 0.7 * b as f32).sin_cos();
            match b % 3 {
                0 => [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]],
                1 => [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]],
                _ => [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]],
            }
        })
        .collect()
}

/// `gpu` against `cpu`, every value within [`TOLERANCE`] of the largest `cpu` magnitude.
fn assert_close(what: &str, gpu: &[f32], cpu: &[f32]) {
    assert_eq!(gpu.len(), cpu.len(), "{what}");
    let peak = cpu.iter().fold(0f32, |m, x| m.max(x.abs()));
    assert!(peak > 0.0, "{what}: an all-zero frame tests nothing");
    let (worst, at) = gpu
        .iter()
        .zip(cpu)
        .map(|(g, c)| (g - c).abs())
        .enumerate()
        .fold(
            (0f32, 0),
            |(m, i), (j, d)| if d > m { (d, j) } else { (m, i) },
        );
    // Written to the stream itself, as `gpu_or_skip` writes, so a passing run's log has it.
    let line = format!("{what}: worst {:.1e} of the peak\n", worst / peak);
    std::io::Write::write_all(&mut std::io::stderr(), line.as_bytes()).unwrap();
    assert!(
        worst <= TOLERANCE * peak,
        "{what}: value {at}: GPU {} against CPU {}, {:.2e} of the peak {peak}",
        gpu[at],
        cpu[at],
        worst / peak
    );
}

/// Shading and transfer of `blob` at two poses, on the device and through aprt-core.
fn check_model(gpu: &Gpu, what: &str, blob: &[u8]) {
    let model = Model::parse(blob).unwrap();
    let info = *model.info();
    let on_gpu = GpuModel::upload(gpu, &model).unwrap();
    let (mut pose, mut lit) = (PoseWeights::new(), LitWeights::new());
    let n2 = info.coeffs();
    let bones = rotations(info.bones());
    for frame in 0..2 {
        let angles: Vec<f32> = (0..info.pose_len())
            .map(|i| 0.4 * ((i + 3 * frame) as f32 * 1.7).sin())
            .collect();
        let lighting: Vec<f32> = (0..n2)
            .map(|c| (1.0 + frame as f32) / (1.0 + c as f32))
            .collect();
        model.set_pose(&angles, &mut pose).unwrap();
        model.light(&pose, &lighting, &bones, &mut lit).unwrap();
        let mut cpu = vec![0.0; info.vertices()];
        model.shade(&lit, 0, &mut cpu).unwrap();
        on_gpu.shade(gpu, &lit).unwrap();
        let shaded = on_gpu.read_shading(gpu).unwrap();
        assert_close(&format!("{what}, frame {frame}, shading"), &shaded, &cpu);
        let mut cpu = vec![0.0; info.vertices() * n2];
        model.transfer(&pose, 0, &mut cpu).unwrap();
        on_gpu.transfer(gpu, &pose).unwrap();
        let transfer = on_gpu.read_transfer(gpu).unwrap();
        assert_close(&format!("{what}, frame {frame}, transfer"), &transfer, &cpu);
    }
}

#[test]
fn every_golden_blob_shades_and_transfers_as_on_the_cpu() {
    let Some(gpu) = gpu_or_skip("every_golden_blob_shades_and_transfers_as_on_the_cpu") else {
        return;
    };
    for name in GOLDEN {
        check_model(&gpu, name, &golden(name));
    }
}

/// Weights computed for another model, or never set, are refused before anything is written:
/// the last frame's output stays as it was.
#[test]
fn weights_of_another_model_are_refused_before_upload() {
    let Some(gpu) = gpu_or_skip("weights_of_another_model_are_refused_before_upload") else {
        return;
    };
    let (world, bones) = (golden("v1-world.aprt"), golden("v1-bones.aprt"));
    let (world, bones) = (Model::parse(&world).unwrap(), Model::parse(&bones).unwrap());
    let on_gpu = GpuModel::upload(&gpu, &world).unwrap();
    let (mut pose, mut lit) = (PoseWeights::new(), LitWeights::new());
    world.set_pose(&[0.1; 4], &mut pose).unwrap();
    world.light(&pose, &[1.0; 9], &[], &mut lit).unwrap();
    on_gpu.shade(&gpu, &lit).unwrap();
    on_gpu.transfer(&gpu, &pose).unwrap();
    let (shading, transfer) = (
        on_gpu.read_shading(&gpu).unwrap(),
        on_gpu.read_transfer(&gpu).unwrap(),
    );

    let (mut other_pose, mut other_lit) = (PoseWeights::new(), LitWeights::new());
    let refused = |r: Result<(), FrameError>, expected: Error| match r {
        Err(FrameError::Core(e)) => assert_eq!(e, expected),
        other => panic!("{other:?}"),
    };
    refused(on_gpu.shade(&gpu, &other_lit), Error::WeightsNotSet);
    refused(on_gpu.transfer(&gpu, &other_pose), Error::WeightsNotSet);
    bones.set_pose(&[0.2; 5], &mut other_pose).unwrap();
    let turns = rotations(bones.info().bones());
    bones
        .light(&other_pose, &[1.0; 9], &turns, &mut other_lit)
        .unwrap();
    refused(on_gpu.shade(&gpu, &other_lit), Error::WeightsForOtherModel);
    refused(
        on_gpu.transfer(&gpu, &other_pose),
        Error::WeightsForOtherModel,
    );
    assert_eq!(on_gpu.read_shading(&gpu).unwrap(), shading);
    assert_eq!(on_gpu.read_transfer(&gpu).unwrap(), transfer);
}

/// The built-in character's model ([`builtin_models`]) in each precision.
#[test]
fn the_builtin_characters_model_agrees_in_every_precision() {
    let test = "the_builtin_characters_model_agrees_in_every_precision";
    let Some(gpu) = gpu_or_skip(test) else {
        return;
    };
    let Some(aprt) = trainer(test) else {
        return;
    };
    for (precision, blob) in builtin_models(&aprt) {
        assert!(Model::parse(&blob).unwrap().info().has_proxies());
        check_model(&gpu, &format!("built-in, {precision}"), &blob);
    }
}
