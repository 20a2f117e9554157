//! The web page (`web/`) against the trainer: the checked-in export is what `aprt export-web`
//! writes today, of a model with occluder proxies, the page's WebGPU kernel is aprt-gpu's
//! WGSL, and, in headless Chromium, the page skins the mesh bit for bit as the trainer does,
//! its per-vertex shading with the proxies equals `aprt eval` of the same frame (≤ 1e-5
//! relative) on both of its paths, the WebAssembly core's and WebGPU's, its render matches
//! `web/test/reference.png`, and WebGPU's render the core's (`web/test/browser-test.mjs`
//! does the browser half).
//!
//! The browser half needs `node`, Chromium (`/usr/bin/chromium`, or `$APRT_CHROMIUM`) and
//! `web/test/node_modules` (`npm ci` there). Without them it prints why it skipped; with
//! `$APRT_REQUIRE_BROWSER` set (as `.ci/run` does) it fails instead, so CI cannot pass by
//! skipping; so does its WebGPU half when that Chromium offers no WebGPU adapter.

use std::path::{Path, PathBuf};
use std::process::Command;

use aprt_trainer::io::npy::encode_f32;
use aprt_trainer::runtime::proxies_section;
use aprt_trainer::{Character, Rig};
use run::refuse;

use crate::run;

fn web() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../web")
}

fn aprt(args: &[&str]) {
    let status = Command::new(env!("CARGO_BIN_EXE_aprt"))
        .args(args)
        .status()
        .expect("aprt runs");
    assert!(status.success(), "aprt {args:?} failed");
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("aprt-browser-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The page's data is the checked-in model exported now: a change to the export, the
/// built-in character or its clip shows here, not as a puzzling browser failure. The model
/// has occluder proxies, so the export takes them and the browser test checks them.
#[test]
fn the_checked_in_web_export_is_current() {
    let data = web().join("data");
    let out = scratch("export");
    let model = data.join("model.aprt");
    let blob = std::fs::read(&model).unwrap();
    assert!(
        proxies_section(&blob).unwrap().is_some(),
        "web/data/model.aprt has no occluder proxies: the browser test would not check them"
    );
    let args = [
        "export-web",
        model.to_str().unwrap(),
        "--builtin",
        "--clip",
        "wave",
    ];
    aprt(&[&args[..], &["--out", out.to_str().unwrap()]].concat());
    for file in ["manifest.json", "clip.bin", "model.aprt"] {
        let (now, checked_in) = (out.join(file), data.join(file));
        assert!(
            std::fs::read(&now).unwrap() == std::fs::read(&checked_in).unwrap(),
            "web/data/{file} is stale: rerun aprt export-web web/data/model.aprt --builtin --clip wave --out web/data"
        );
    }
    std::fs::remove_dir_all(out).unwrap();
}

/// The page's WebGPU path runs aprt-gpu's kernel: `web/build.sh` copies the WGSL into
/// `web/wgsl/` (the page is served from `web/` alone), and a stale copy fails here.
#[test]
fn the_pages_wgsl_is_aprt_gpus() {
    let shaders = Path::new(env!("CARGO_MANIFEST_DIR")).join("../gpu/src/shaders");
    for file in ["rows.wgsl", "shade.wgsl"] {
        assert!(
            std::fs::read(web().join("wgsl").join(file)).unwrap()
                == std::fs::read(shaders.join(file)).unwrap(),
            "web/wgsl/{file} differs from gpu/src/shaders/{file}: rerun web/build.sh"
        );
    }
}

/// `aprt export-web` refuses what the page could not play, with one line saying why, and
/// never writes over its model.
#[test]
fn export_web_refuses_what_the_page_cannot_play() {
    let out = scratch("refuse");
    let (dir, model) = (out.to_str().unwrap(), web().join("data/model.aprt"));
    let model = model.to_str().unwrap();
    refuse(
        &["export-web", model, "--out", dir],
        &["--builtin", "--clip"],
    );
    let golden = Path::new(env!("CARGO_MANIFEST_DIR")).join("../fixtures/golden/v1-bones.aprt");
    let args = [
        "export-web",
        golden.to_str().unwrap(),
        "--builtin",
        "--clip",
        "wave",
    ];
    refuse(&[&args[..], &["--out", dir]].concat(), &["does not fit"]);
    let data = web().join("data");
    let args = ["export-web", model, "--builtin", "--clip", "wave", "--out"];
    refuse(
        &[&args[..], &[data.to_str().unwrap()]].concat(),
        &["model.aprt"],
    );
    std::fs::remove_dir_all(out).unwrap();
}

/// Why the browser half cannot run here, if it cannot.
fn missing_prerequisite() -> Option<String> {
    let chromium = std::env::var_os("APRT_CHROMIUM")
        .map_or_else(|| PathBuf::from("/usr/bin/chromium"), PathBuf::from);
    let node = Command::new("node").arg("--version").output();
    if !node.is_ok_and(|o| o.status.success()) {
        return Some("node is not on PATH".into());
    }
    if !chromium.is_file() {
        return Some(format!(
            "no Chromium at {} (apt-get install chromium, or set APRT_CHROMIUM)",
            chromium.display()
        ));
    }
    if !web().join("test/node_modules/playwright-core").is_dir() {
        return Some("web/test/node_modules is missing (npm ci in web/test)".into());
    }
    for wasm in ["aprt-scalar.wasm", "aprt-simd.wasm"] {
        if !web().join(wasm).is_file() {
            return Some(format!("web/{wasm} is missing (web/build.sh)"));
        }
    }
    None
}

/// Each frame of `wave` as the trainer poses it (`aprt eval` gives the proxies this mesh),
/// `frames × 2 × vertices × 3` (positions, then normals), into `path`.
fn write_posed_mesh(path: &Path) {
    let rig = Character::builtin();
    let clip = rig.clip("wave").unwrap();
    let mut values = Vec::new();
    for pose in &clip.frames {
        let mesh = rig.pose(pose).unwrap();
        values.extend(mesh.positions.iter().chain(&mesh.normals).flatten());
    }
    let shape = [clip.frames.len(), 2, rig.bind_mesh().vertex_count(), 3];
    std::fs::write(path, encode_f32(&shape, &values)).unwrap();
}

#[test]
fn the_page_in_chromium_shades_as_aprt_eval_and_renders_the_reference() {
    if let Some(why) = missing_prerequisite() {
        assert!(
            std::env::var_os("APRT_REQUIRE_BROWSER").is_none(),
            "browser test required (APRT_REQUIRE_BROWSER) but {why}"
        );
        // Written to the stream itself, not through `eprintln!`, which the test harness
        // captures and hides for a passing test: the skip shows in a plain `cargo test`.
        let line = format!("skipped the browser test: {why}\n");
        std::io::Write::write_all(&mut std::io::stderr(), line.as_bytes()).unwrap();
        return;
    }
    let out = scratch("page");
    let npy = out.join("eval.npy");
    let model = web().join("data/model.aprt");
    let eval = [
        "eval",
        model.to_str().unwrap(),
        "--builtin",
        "--clip",
        "wave",
    ];
    aprt(&[&eval[..], &["--npy", npy.to_str().unwrap()]].concat());
    let posed = out.join("posed.npy");
    write_posed_mesh(&posed);
    let output = Command::new("node")
        .arg(web().join("test/browser-test.mjs"))
        .args(["--reference", npy.to_str().unwrap(), "--t", "1.25"])
        .args(["--posed", posed.to_str().unwrap()])
        .args(["--out", out.join("shots").to_str().unwrap()])
        .output()
        .expect("node runs");
    let log = String::from_utf8_lossy(&output.stdout).into_owned()
        + &String::from_utf8_lossy(&output.stderr);
    eprintln!("{log}");
    assert!(
        output.status.success(),
        "the browser test failed (screenshots in {}):\n{log}",
        out.display()
    );
    // Past the harness's capture, as the skip above: a Chromium without WebGPU shows in a plain
    // `cargo test` (with $APRT_REQUIRE_BROWSER the script failed instead).
    if let Some(skip) = log
        .lines()
        .find(|l| l.starts_with("skipped the WebGPU half"))
    {
        std::io::Write::write_all(&mut std::io::stderr(), format!("{skip}\n").as_bytes()).unwrap();
    }
    std::fs::remove_dir_all(out).unwrap();
}
