//! What the device tests and the frame bench (`benches/frame.rs`, which includes this file)
//! share: the device or why there is none, the built-in character's model as the root
//! workspace's `aprt` binary trains it, and a frame's bones and vertices.

use std::path::{Path, PathBuf};
use std::process::Command;

use aprt_core::{Model, ProxyFrame, Rotation, Skinning};
use aprt_gpu::Gpu;

/// The adapter `Gpu::new` finds, or `None` after saying on stderr why `test` is skipped; with
/// `$APRT_REQUIRE_GPU` set (as `.ci/run` does) a missing adapter fails the test instead, so
/// CI cannot pass by skipping. The adapter's name is printed either way, so a run's log says
/// what it ran on.
pub fn gpu_or_skip(test: &str) -> Option<Gpu> {
    // Written to the stream itself, not through `eprintln!`, which the test harness captures
    // and hides for a passing test.
    let say = |line: String| std::io::Write::write_all(&mut std::io::stderr(), line.as_bytes());
    match Gpu::new() {
        Ok(gpu) => {
            say(format!("{test}: on {gpu}\n")).unwrap();
            Some(gpu)
        }
        Err(why) => {
            assert!(
                std::env::var_os("APRT_REQUIRE_GPU").is_none(),
                "{test}: GPU required (APRT_REQUIRE_GPU) but {why}"
            );
            say(format!(
                "skipping {test}: {why}; install mesa-vulkan-drivers for lavapipe\n"
            ))
            .unwrap();
            None
        }
    }
}

/// The `aprt` binary of the root workspace (`cargo build --release -p aprt-trainer` builds
/// it; `.ci/run` has, before this crate's tests), or `None` after saying why the test skips;
/// with `$APRT_REQUIRE_GPU` its absence fails the test.
pub fn trainer(test: &str) -> Option<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let bin = std::env::var_os("APRT_BIN")
        .map(PathBuf::from)
        .unwrap_or_else(|| root.join("target/release/aprt"));
    if bin.exists() {
        return Some(bin);
    }
    assert!(
        std::env::var_os("APRT_REQUIRE_GPU").is_none(),
        "{test}: needs {} (cargo build --release -p aprt-trainer)",
        bin.display()
    );
    eprintln!(
        "skipping {test}: no {} (cargo build --release -p aprt-trainer)",
        bin.display()
    );
    None
}

/// The `aprt` arguments of [`builtin_models`] before the rig and the precision, one string so
/// the bench can print what it ran.
pub const BUILTIN_TRAIN: &str =
    "train --builtin --clip wave --rays 8 --validation-poses 0 --proxies on";

/// Each precision of [`builtin_models`] and the irradiance rig its model carries: between
/// them every kind of rig axis (lattice, gradient, constant) and the gradient rig.
pub const BUILTIN_RIGS: [(&str, &str); 3] = [
    ("f32", "mixed:x=lattice3,y=gradient,z=constant"),
    ("f16", "lattice:4x3x2"),
    ("i8", "gradient"),
];

/// The built-in character's model, as the demo's default is shaped (bone frames, occluder
/// proxies, an irradiance rig, k_v 22, 13,022 vertices) but baked with few rays on one clip,
/// in f32, f16 and i8 rows ([`BUILTIN_RIGS`]), each with its precision's name. Baked once:
/// the later precisions resume from the first one's checkpoint.
pub fn builtin_models(aprt: &Path) -> Vec<(&'static str, Vec<u8>)> {
    let dir = std::env::temp_dir().join(format!("aprt-gpu-{}", std::process::id()));
    let checkpoint = dir.join("checkpoint");
    let models = BUILTIN_RIGS
        .into_iter()
        .enumerate()
        .map(|(i, (precision, rig))| {
            let out = dir.join(format!("builtin-{precision}.aprt"));
            let mut command = Command::new(aprt);
            command
                .args(BUILTIN_TRAIN.split(' '))
                .args(["--rig", rig, "--precision", precision])
                .arg("--checkpoint");
            command.arg(&checkpoint).arg("-o").arg(&out);
            if i > 0 {
                command.arg("--resume");
            }
            let run = command.output().unwrap();
            assert!(
                run.status.success(),
                "{}",
                String::from_utf8_lossy(&run.stderr)
            );
            (precision, std::fs::read(&out).unwrap())
        })
        .collect();
    std::fs::remove_dir_all(&dir).unwrap();
    models
}

/// A proper rotation per bone, each about its own axis by its own angle.
pub fn rotations(bones: usize) -> Vec<Rotation> {
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

/// Each bone's skinning matrix: its rotation and a small translation.
pub fn skinning(rotations: &[Rotation]) -> Vec<Skinning> {
    (0..)
        .zip(rotations)
        .map(|(b, r)| {
            let t = [0.01 * b as f32, -0.02, 0.005 * b as f32];
            [0, 1, 2].map(|i| [r[i][0], r[i][1], r[i][2], t[i]])
        })
        .map(|rows| rows.concat().try_into().unwrap())
        .collect()
}

/// Vertices the proxies reach in every way: each vertex of a bone with proxies sits near one
/// of them, at 0.8 to 3 radii from its centre (inside it, touching, far), its normal turned
/// anywhere from facing the sphere to facing away (the horizon cuts many caps).
pub fn vertices_near_proxies(
    model: &Model<'_>,
    frame: &ProxyFrame,
) -> (Vec<[f32; 3]>, Vec<[f32; 3]>) {
    let info = model.info();
    let v = info.vertices();
    let zeros = vec![[0.0f32; 3]; v];
    let view = info
        .proxy_inputs(frame, (&zeros, &zeros), None, None)
        .unwrap();
    let mut bones = vec![0u16; v];
    model.vertex_bones(0, &mut bones).unwrap();
    let (mut positions, mut normals) = (Vec::new(), Vec::new());
    for (j, &bone) in bones.iter().enumerate() {
        let mask = view.mask(usize::from(bone));
        let t = j as f32;
        let direction = [(1.3 * t).sin(), (0.7 * t).cos(), (2.9 * t).sin()];
        let normal = [(0.5 * t).cos(), (1.1 * t).sin(), 0.3 + (0.2 * t).cos()];
        let position = match mask {
            0 => [t.sin(), t.cos(), 0.1 * t],
            m => {
                let ones: Vec<usize> = (0..64).filter(|i| m >> i & 1 == 1).collect();
                let (centre, radius, _) = view.sphere(ones[j % ones.len()]);
                let length = direction
                    .iter()
                    .map(|x| x * x)
                    .sum::<f32>()
                    .sqrt()
                    .max(1e-3);
                let distance = radius * (0.8 + 2.2 * (0.37 * t).sin().abs()) / length;
                [0, 1, 2].map(|k| centre[k] + distance * direction[k])
            }
        };
        positions.push(position);
        normals.push(normal);
    }
    (positions, normals)
}
