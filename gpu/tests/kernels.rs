//! The kernels on the device against aprt-core on the CPU: shading and transfer of every
//! golden blob and of the built-in character's model (bone frames, occluder proxies, 13,022
//! vertices) in f32, f16 and i8 rows, within [`aprt_gpu::TOLERANCE`] of each frame's peak.

mod common;

use std::path::Path;

use aprt_core::{
    DirectionalLight, Error, IrradianceRig, Light, LitWeights, Model, Placement, PointLight,
    PoseWeights, ProxyFrame, RigLitWeights, Rotation, SphereLight,
};
use aprt_gpu::{FrameError, Gpu, GpuModel, TOLERANCE};
use common::{builtin_models, gpu_or_skip, rotations, skinning, trainer, vertices_near_proxies};

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
    let mut on_gpu = GpuModel::upload(gpu, &model).unwrap();
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
        if let Some(rig) = model.irradiance_rig() {
            let what = format!("{what}, frame {frame}");
            check_rig(gpu, (&model, &mut on_gpu), (&pose, &bones), &rig, &what);
        }
        check_lights(
            gpu,
            (&model, &mut on_gpu),
            (&pose, &bones),
            &format!("{what}, frame {frame}"),
        );
        if info.has_proxies() {
            let what = format!("{what}, frame {frame}");
            check_proxies(
                gpu,
                (&model, &on_gpu),
                (&pose, &lit),
                (&lighting, &bones),
                &what,
            );
        }
    }
}

/// Shading under the model's irradiance rig, placed turned and moved, at vertices spread over
/// and beyond its box (a lattice clamps them to its faces).
fn check_rig(
    gpu: &Gpu,
    (model, on_gpu): (&Model<'_>, &mut GpuModel),
    (pose, bones): (&PoseWeights, &[Rotation]),
    rig: &IrradianceRig<'_>,
    what: &str,
) {
    let info = model.info();
    let n2 = info.coeffs();
    let vectors: Vec<[f32; 3]> = (0..rig.vectors() * n2)
        .map(|i| {
            let t = i as f32;
            [
                0.5 + 0.4 * t.sin(),
                0.4 + 0.3 * (1.7 * t).cos(),
                0.3 / (1.0 + t),
            ]
        })
        .collect();
    let mut buffer = vec![0.0; info.rig_lit_weights_len(rig.vectors())];
    let mut lit = RigLitWeights::new(&mut buffer);
    let unset = on_gpu.shade_rig(gpu, (&lit, rig, &Placement::IDENTITY), &[]);
    assert!(
        matches!(unset, Err(FrameError::Core(Error::WeightsNotSet))),
        "{what}: {unset:?}"
    );
    model.light_rig(pose, &vectors, bones, &mut lit).unwrap();
    let (s, c) = 0.4f32.sin_cos();
    let placement = Placement {
        rotation: [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]],
        translation: [0.2, -0.1, 0.05],
    };
    let centre = rig.centre();
    let half = rig.half();
    let positions: Vec<[f32; 3]> = (0..info.vertices())
        .map(|j| {
            let t = j as f32;
            let root =
                [0, 1, 2].map(|k| centre[k] + 1.3 * half[k] * (t * (0.7 + 0.4 * k as f32)).sin());
            placement.to_world(root)
        })
        .collect();
    let mut cpu = vec![[0.0; 3]; info.vertices()];
    model
        .shade_rig(&lit, rig, &placement, &positions, 0, &mut cpu)
        .unwrap();
    on_gpu
        .shade_rig(gpu, (&lit, rig, &placement), &positions)
        .unwrap();
    let rgb = on_gpu.read_rig(gpu).unwrap();
    assert_close(
        &format!("{what}, irradiance rig"),
        rgb.as_flattened(),
        cpu.as_flattened(),
    );
}

/// Per-vertex lights of every kind at vertices spread around them: inside the sphere light,
/// near the point light, one light of weight 0.
fn check_lights(
    gpu: &Gpu,
    (model, on_gpu): (&Model<'_>, &mut GpuModel),
    (pose, bones): (&PoseWeights, &[Rotation]),
    what: &str,
) {
    let info = model.info();
    // Vertex 0 inside the sphere light; the others around the lights.
    let positions: Vec<[f32; 3]> = (0..info.vertices())
        .map(|j| match j {
            0 => [0.3, 0.25, 0.1],
            _ => {
                let t = j as f32;
                [t.sin(), (1.3 * t).cos(), 0.5 * (0.7 * t).sin()]
            }
        })
        .collect();
    let lights = [
        Light::Sphere(SphereLight {
            position: [0.3, 0.2, 0.1],
            radius: 0.4,
            radiance: [1.0, 0.8, 0.6],
        }),
        Light::Point(PointLight {
            position: [1.2, 0.0, 0.2],
            intensity: [0.02, 0.03, 0.04],
        }),
        Light::Directional(DirectionalLight {
            direction: [0.2, -1.0, 0.5],
            irradiance: [0.7, 0.7, 0.9],
        }),
        Light::Point(PointLight {
            position: [0.0, 0.0, 3.0],
            intensity: [5.0; 3],
        }),
    ];
    let weights = [0.8, 1.0, 0.5, 0.0];
    let negative = on_gpu.shade_lights(
        gpu,
        (pose, bones),
        (&lights, &[0.8, -1.0, 0.5, 0.0]),
        &positions,
    );
    assert!(
        matches!(
            negative,
            Err(FrameError::Core(Error::BadLightWeight { index: 1 }))
        ),
        "{what}: {negative:?}"
    );
    let mut cpu = vec![[0.0; 3]; info.vertices()];
    model
        .shade_lights(pose, bones, &lights, &weights, &positions, 0, &mut cpu)
        .unwrap();
    on_gpu
        .shade_lights(gpu, (pose, bones), (&lights, &weights), &positions)
        .unwrap();
    let rgb = on_gpu.read_lights(gpu).unwrap();
    assert_close(
        &format!("{what}, per-vertex lights"),
        rgb.as_flattened(),
        cpu.as_flattened(),
    );
}

/// The proxies' correction of the shading and the transfer, on the device and on the CPU; at
/// least a tenth of the vertices must be reached in each, or the comparison shows little.
fn check_proxies(
    gpu: &Gpu,
    (model, on_gpu): (&Model<'_>, &GpuModel),
    (pose, lit): (&PoseWeights, &LitWeights),
    (lighting, bones): (&[f32], &[Rotation]),
    what: &str,
) {
    let info = model.info();
    let mut frame = ProxyFrame::new();
    model.pose_proxies(&skinning(bones), &mut frame).unwrap();
    let (positions, normals) = vertices_near_proxies(model, &frame);
    let vertices = (&positions[..], &normals[..]);

    let mut shaded = vec![0.0; info.vertices()];
    model.shade(lit, 0, &mut shaded).unwrap();
    let mut cpu = shaded.clone();
    model
        .occlude(&frame, lighting, &positions, &normals, 0, &mut cpu)
        .unwrap();
    let reached = cpu.iter().zip(&shaded).filter(|(a, b)| a != b).count();
    assert!(10 * reached >= info.vertices(), "{what}: {reached} reached");
    on_gpu.shade(gpu, lit).unwrap();
    on_gpu.occlude(gpu, (&frame, lighting), vertices).unwrap();
    let occluded = on_gpu.read_shading(gpu).unwrap();
    assert_close(&format!("{what}, occluded shading"), &occluded, &cpu);

    let mut transfer = vec![0.0; info.vertices() * info.coeffs()];
    model.transfer(pose, 0, &mut transfer).unwrap();
    let mut cpu = transfer.clone();
    model
        .occlude_transfer(&frame, bones, &positions, &normals, 0, &mut cpu)
        .unwrap();
    let reached = cpu
        .chunks(info.coeffs())
        .zip(transfer.chunks(info.coeffs()));
    let reached = reached.filter(|(a, b)| a != b).count();
    assert!(10 * reached >= info.vertices(), "{what}: {reached} reached");
    on_gpu.transfer(gpu, pose).unwrap();
    on_gpu
        .occlude_transfer(gpu, (&frame, bones), vertices)
        .unwrap();
    let occluded = on_gpu.read_transfer(gpu).unwrap();
    assert_close(&format!("{what}, occluded transfer"), &occluded, &cpu);
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

/// An engine's own device and queue serve as well as the crate's.
#[test]
fn an_engines_device_runs_the_kernels() {
    let Some(own) = gpu_or_skip("an_engines_device_runs_the_kernels") else {
        return;
    };
    let engine = (
        own.device().clone(),
        own.queue().clone(),
        own.info().clone(),
    );
    let gpu = Gpu::from_parts(engine.0, engine.1, engine.2);
    check_model(
        &gpu,
        "v1-bones.aprt on the engine's device",
        &golden("v1-bones.aprt"),
    );
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

/// The proxies' inputs are checked by aprt-core before anything is written: a frame never
/// posed, normals of the wrong count, a position that is not finite, a model without
/// proxies; the last shading stays as it was.
#[test]
fn proxy_inputs_are_refused_before_upload() {
    let Some(gpu) = gpu_or_skip("proxy_inputs_are_refused_before_upload") else {
        return;
    };
    let blob = golden("v1-proxies.aprt");
    let model = Model::parse(&blob).unwrap();
    let info = *model.info();
    let on_gpu = GpuModel::upload(&gpu, &model).unwrap();
    let (mut pose, mut lit) = (PoseWeights::new(), LitWeights::new());
    let bones = rotations(info.bones());
    let lighting = vec![0.5; info.coeffs()];
    model
        .set_pose(&vec![0.1; info.pose_len()], &mut pose)
        .unwrap();
    model.light(&pose, &lighting, &bones, &mut lit).unwrap();
    let mut frame = ProxyFrame::new();
    model.pose_proxies(&skinning(&bones), &mut frame).unwrap();
    let (positions, normals) = vertices_near_proxies(&model, &frame);
    on_gpu.shade(&gpu, &lit).unwrap();
    on_gpu
        .occlude(&gpu, (&frame, &lighting), (&positions, &normals))
        .unwrap();
    let before = on_gpu.read_shading(&gpu).unwrap();

    let refused = |r: Result<(), FrameError>| match r {
        Err(FrameError::Core(e)) => e,
        other => panic!("{other:?}"),
    };
    let unposed = ProxyFrame::new();
    let e = refused(on_gpu.occlude(&gpu, (&unposed, &lighting), (&positions, &normals)));
    assert_eq!(e, Error::WeightsNotSet);
    let short = &normals[1..];
    let e = refused(on_gpu.occlude(&gpu, (&frame, &lighting), (&positions, short)));
    assert!(matches!(e, Error::WrongLength { .. }), "{e:?}");
    let mut nan = positions.clone();
    nan[0][1] = f32::NAN;
    let e = refused(on_gpu.occlude(&gpu, (&frame, &lighting), (&nan, &normals)));
    assert!(matches!(e, Error::NonFinitePosition { index: 0 }), "{e:?}");
    let e = refused(on_gpu.occlude_transfer(&gpu, (&frame, &bones[1..]), (&positions, &normals)));
    assert!(matches!(e, Error::WrongLength { .. }), "{e:?}");
    assert_eq!(on_gpu.read_shading(&gpu).unwrap(), before);

    let world = golden("v1-world.aprt");
    let world = GpuModel::upload(&gpu, &Model::parse(&world).unwrap()).unwrap();
    let none = vec![[0.0; 3]; world.info().vertices()];
    let e = refused(world.occlude(&gpu, (&frame, &[1.0; 9]), (&none, &none)));
    assert_eq!(e, Error::NoProxies);
}

/// Any model file, when `$APRT_GPU_MODEL` names one (for example the model `aprt demo`
/// writes), checked as the built-in ones are; skipped, saying so, without it.
#[test]
fn the_model_file_named_agrees() {
    let Some(path) = std::env::var_os("APRT_GPU_MODEL") else {
        eprintln!("skipping the_model_file_named_agrees: $APRT_GPU_MODEL names no model file");
        return;
    };
    let Some(gpu) = gpu_or_skip("the_model_file_named_agrees") else {
        return;
    };
    let blob = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    check_model(&gpu, &path.to_string_lossy(), &blob);
}
