//! The C and C++ examples (`examples/shade.c`, `examples/shade.cpp`), built with the system
//! `cc` and `c++` against the staticlib (and the C one against the cdylib) and run on the
//! golden blobs (one with occluder proxies) and a model with an irradiance rig, print exactly
//! what the same frame computed through `aprt_core` in Rust prints: every float's bits, so C,
//! C++ and Rust agree to the last bit.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;

use crate::common::{have, repo, staticlib};

use aprt_core::{
    DirectionalLight, Light, LightMap, LitWeights, Model, Placement, PointLight, PoseWeights,
    ProxyFrame, RigLitWeights, Rotation, Skinning, SphereLight, StreamedModel, project_directional,
};

// The inputs of shade.c and shade.cpp, literally.
const ANGLES: [f32; 8] = [0.1, -0.2, 0.3, 0.05, -0.15, 0.25, 0.0, 0.4];
const POSITIONS: [[f32; 3]; 8] = [
    [0.0, 0.0, 0.0],
    [0.5, 0.1, 0.2],
    [-0.3, 0.4, 0.1],
    [0.2, -0.5, 0.6],
    [0.1, 0.3, -0.4],
    [-0.6, 0.2, 0.3],
    [0.4, 0.4, 0.4],
    [0.0, -0.2, 0.8],
];
const SKY_DIR: [f32; 3] = [0.5, -0.8, 0.9];
const TURN: Rotation = [[0.8, -0.6, 0.0], [0.6, 0.8, 0.0], [0.0, 0.0, 1.0]];
const IDENTITY: Rotation = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
/// The translation of every bone's skinning matrix (its rotation is the bone's, above).
const SHIFT: [f32; 3] = [0.05, -0.1, 0.2];
/// The vertices' normals, cycled like `POSITIONS` (the last one zero: it sees no proxy).
const NORMALS: [[f32; 3]; 8] = [
    [0.0, 0.0, 1.0],
    [0.6, 0.0, 0.8],
    [0.0, 0.6, 0.8],
    [-0.6, 0.0, 0.8],
    [0.0, -0.6, 0.8],
    [0.0, 0.0, -1.0],
    [0.8, 0.0, 0.6],
    [0.0, 0.0, 0.0],
];
const WEIGHTS: [f32; 3] = [1.0, 0.5, 1.0];
const PLACE: Placement = Placement {
    rotation: [[0.8, 0.0, -0.6], [0.0, 1.0, 0.0], [0.6, 0.0, 0.8]],
    translation: [0.1, 0.0, -0.2],
};

fn lights() -> [Light; 3] {
    [
        Light::Sphere(SphereLight {
            position: [0.5, 1.0, 2.0],
            radius: 0.3,
            radiance: [2.0, 1.5, 1.0],
        }),
        Light::Point(PointLight {
            position: [-1.0, 0.5, 1.0],
            intensity: [1.0, 1.0, 1.0],
        }),
        Light::Directional(DirectionalLight {
            direction: [0.3, -0.2, 0.9],
            irradiance: [0.5, 0.6, 0.7],
        }),
    ]
}

fn line(out: &mut String, name: &str, values: &[f32]) {
    write!(out, "{name} {}", values.len()).unwrap();
    for v in values {
        write!(out, " {:08x}", v.to_bits()).unwrap();
    }
    out.push('\n');
}

/// What the examples print for `blob`, computed through `aprt_core` alone.
fn expected(blob: &[u8]) -> String {
    let model = Model::parse(blob).unwrap();
    let info = *model.info();
    let rig = model.irradiance_rig();
    let (n, n2, k) = (
        info.vertices(),
        info.coeffs(),
        rig.map_or(0, |r| r.vectors()),
    );
    let mut out = String::new();
    let atlas = i32::from(model.texel_atlas().is_some());
    writeln!(
        out,
        "model order {} coeffs {n2} vertices {n} pose_len {} bones {} rig {k} atlas {atlas} \
         proxies {}",
        info.order(),
        info.pose_len(),
        info.bones(),
        i32::from(info.has_proxies())
    )
    .unwrap();
    let angles: Vec<f32> = (0..info.pose_len()).map(|i| ANGLES[i % 8]).collect();
    let bones: Vec<Rotation> = (0..info.bones())
        .map(|b| if b % 2 == 1 { TURN } else { IDENTITY })
        .collect();
    let mut sky = [0.0f32; 36];
    project_directional(info.order(), SKY_DIR, 3.0, &mut sky).unwrap();
    let sky = &sky[..n2];
    let (mut pose, mut lit) = (Box::new(PoseWeights::new()), Box::new(LitWeights::new()));
    model.set_pose(&angles, &mut pose).unwrap();
    model.light(&pose, sky, &bones, &mut lit).unwrap();
    let mut shading = vec![0.0; n];
    model.shade(&lit, 0, &mut shading).unwrap();
    line(&mut out, "shade", &shading);
    let mut transfer = vec![0.0; n * n2];
    model.transfer(&pose, 0, &mut transfer).unwrap();
    line(&mut out, "transfer", &transfer);

    let positions: Vec<[f32; 3]> = (0..n).map(|j| POSITIONS[j % 8]).collect();
    let mut rgb = vec![[0.0f32; 3]; n];
    let lights = lights();
    model
        .shade_lights(&pose, &bones, &lights, &WEIGHTS, &positions, 0, &mut rgb)
        .unwrap();
    line(&mut out, "lights", rgb.as_flattened());

    // The occluder proxies, posed by each bone's rotation with SHIFT as its translation.
    let skinning: Vec<Skinning> = bones
        .iter()
        .map(|r| {
            let row = |i: usize| [r[i][0], r[i][1], r[i][2], SHIFT[i]];
            [row(0), row(1), row(2)].concat().try_into().unwrap()
        })
        .collect();
    let normals: Vec<[f32; 3]> = (0..n).map(|j| NORMALS[j % 8]).collect();
    if info.has_proxies() {
        let mut proxies = Box::new(ProxyFrame::new());
        model.pose_proxies(&skinning, &mut proxies).unwrap();
        let mut occluded = shading.clone();
        model
            .occlude(&proxies, sky, &positions, &normals, 0, &mut occluded)
            .unwrap();
        // The inputs reach some vertices and miss others, so the lines test something.
        let changed = occluded
            .iter()
            .zip(&shading)
            .filter(|(a, b)| a != b)
            .count();
        assert!(
            0 < changed && changed < n,
            "{changed} of {n} vertices occluded"
        );
        line(&mut out, "occluded", &occluded);
        let mut occluded = transfer.clone();
        model
            .occlude_transfer(&proxies, &bones, &positions, &normals, 0, &mut occluded)
            .unwrap();
        assert_ne!(occluded, transfer);
        line(&mut out, "occluded_transfer", &occluded);
    }

    let mut vectors = vec![[0.0f32; 3]; k * n2];
    if let Some(rig) = rig {
        line(
            &mut out,
            "share",
            &[rig.share_of(&lights[0], &PLACE, 1.0, 0.25)],
        );
        rig.vectors_from_lights(info.order(), &PLACE, &lights, &[], &mut vectors)
            .unwrap();
        line(&mut out, "vectors", vectors.as_flattened());
        let mut buffer = vec![0.0; info.rig_lit_weights_len(k)];
        let mut rig_lit = RigLitWeights::new(&mut buffer);
        model
            .light_rig(&pose, &vectors, &bones, &mut rig_lit)
            .unwrap();
        model
            .shade_rig(&rig_lit, &rig, &PLACE, &positions, 0, &mut rgb)
            .unwrap();
        line(&mut out, "rig", rgb.as_flattened());
    }

    let env: Vec<[f32; 3]> = sky.iter().map(|&c| [c; 3]).collect();
    let map = LightMap::new(info.order()).unwrap();
    map.compose(&transfer, &env, &mut rgb).unwrap();
    line(&mut out, "lightmap", rgb.as_flattened());
    map.compose_lights(&transfer, &positions, &lights, &env, &mut rgb)
        .unwrap();
    line(&mut out, "lightmap_lights", rgb.as_flattened());
    if let Some(rig) = rig {
        map.compose_rig(&transfer, &rig, &vectors, &PLACE, &positions, &mut rgb)
            .unwrap();
        line(&mut out, "lightmap_rig", rgb.as_flattened());
    }

    let mut scratch = vec![0u8; info.scratch_bytes()];
    let mut streamed = StreamedModel::open(blob, &mut scratch).unwrap();
    let (mut pose, mut lit) = (Box::new(PoseWeights::new()), Box::new(LitWeights::new()));
    streamed.set_pose(&angles, &mut pose).unwrap();
    streamed.light(&pose, sky, &bones, &mut lit).unwrap();
    streamed.shade(&lit, 0, &mut shading).unwrap();
    line(&mut out, "streamed", &shading);
    if info.has_proxies() {
        let mut proxies = Box::new(ProxyFrame::new());
        streamed.pose_proxies(&skinning, &mut proxies).unwrap();
        streamed
            .occlude(&proxies, sky, &positions, &normals, 0, &mut shading)
            .unwrap();
        line(&mut out, "streamed_occluded", &shading);
        streamed.transfer(&pose, 0, &mut transfer).unwrap();
        streamed
            .occlude_transfer(&proxies, &bones, &positions, &normals, 0, &mut transfer)
            .unwrap();
        line(&mut out, "streamed_occluded_transfer", &transfer);
    }
    out
}

/// Builds `source` against the staticlib, or with `shared` against the cdylib beside it.
fn compile(tool: &str, std: &str, source: &str, exe: &Path, shared: bool) {
    let lib = staticlib();
    let mut cmd = Command::new(tool);
    cmd.args([
        std,
        "-O2",
        "-Wall",
        "-Wextra",
        "-Werror",
        "-ffp-contract=off",
        "-I",
    ])
    .arg(repo().join("capi/include"))
    .arg(repo().join("capi/examples").join(source));
    match shared {
        true => cmd.arg("-L").arg(lib.parent().unwrap()).arg("-laprt_capi"),
        false => cmd.arg(&lib),
    };
    let status = cmd
        .args(["-lpthread", "-ldl", "-lm", "-o"])
        .arg(exe)
        .status()
        .unwrap();
    assert!(status.success(), "{tool} failed on {source}");
}

fn run(exe: &Path, model: &Path) -> String {
    let lib_dir = staticlib().parent().unwrap().to_path_buf();
    let out = Command::new(exe)
        .arg(model)
        .env("LD_LIBRARY_PATH", lib_dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{} {} failed: {}",
        exe.display(),
        model.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

/// The models: the four golden blobs, and the fuzz seed with an irradiance rig (its 48-byte
/// probe prefix stripped, as `aprt_tests::harness::Probe::split` does).
fn models(dir: &Path) -> Vec<PathBuf> {
    let mut paths: Vec<PathBuf> = ["atlas", "bones", "proxies", "world"]
        .iter()
        .map(|k| repo().join(format!("fixtures/golden/v1-{k}.aprt")))
        .collect();
    let seed = std::fs::read(repo().join("fuzz/corpus/reader/seed-rig-bones-f32")).unwrap();
    let rig = dir.join("rig-bones-f32.aprt");
    std::fs::write(&rig, &seed[48..]).unwrap();
    paths.push(rig);
    paths
}

#[test]
fn c_and_cpp_examples_match_rust_bit_for_bit() {
    if !have("cc") || !have("c++") {
        let required = std::env::var_os("APRT_REQUIRE_CC").is_some();
        assert!(!required, "APRT_REQUIRE_CC is set and cc or c++ is missing");
        // Written to the stream itself: the harness hides a passing test's `println!`.
        let line = "skipped the C and C++ examples: no system cc or c++ to build them with\n";
        std::io::Write::write_all(&mut std::io::stderr(), line.as_bytes()).unwrap();
        return;
    }
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("capi-examples");
    std::fs::create_dir_all(&dir).unwrap();
    let (c, cpp, c_so) = (
        dir.join("shade_c"),
        dir.join("shade_cpp"),
        dir.join("shade_c_so"),
    );
    compile("cc", "-std=c11", "shade.c", &c, false);
    compile("c++", "-std=c++17", "shade.cpp", &cpp, false);
    // The cdylib exports the same functions (on Linux, found through LD_LIBRARY_PATH).
    let shared = cfg!(target_os = "linux");
    if shared {
        compile("cc", "-std=c11", "shade.c", &c_so, true);
    }
    let (mut rigs, mut occluded) = (0, 0);
    for model in models(&dir) {
        let want = expected(&std::fs::read(&model).unwrap());
        rigs += usize::from(want.contains("\nrig "));
        occluded += usize::from(want.contains("\noccluded "));
        let exes = [&c, &cpp, &c_so];
        for exe in &exes[..2 + usize::from(shared)] {
            let got = run(exe, &model);
            if got != want {
                let first = got.lines().zip(want.lines()).find(|(g, w)| g != w);
                panic!(
                    "{} on {}: output differs from Rust's; first differing line:\n{:?}",
                    exe.display(),
                    model.display(),
                    first
                );
            }
        }
    }
    assert_eq!(rigs, 1, "one model exercises the irradiance rig");
    assert_eq!(occluded, 1, "one model exercises the occluder proxies");
}
