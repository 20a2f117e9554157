//! The page's per-frame cost, natively: the same [`Session::shade`] (set_pose, light, shade)
//! on the same model, frame and lighting as the page at `?t=1.25&freeze=1`, timed the way
//! `web/test/browser-test.mjs` times it in Chromium (the median of 5 runs of 300 frames), so
//! the two divide into the wasm-to-native ratio of `docs/results/web.md`.
//!
//! `cargo run --release -p aprt-wasm --example native_frame [-- web/data]`

use std::time::Instant;

use aprt_wasm::{Session, add_directional};

/// The page's defaults (`web/main.js`): the sky and the light.
const SKY: [(usize, f32); 2] = [(0, 0.5), (2, 0.25)];
const LIGHT: (f32, f32, f32) = (-0.6, 0.8, 2.5);
const SECONDS: f64 = 1.25;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = std::path::PathBuf::from(std::env::args().nth(1).unwrap_or("web/data".into()));
    let manifest: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("manifest.json"))?)?;
    let bin = std::fs::read(dir.join("clip.bin"))?;
    let blob = std::fs::read(dir.join("model.aprt"))?;
    let mut session = Box::new(Session::open(&blob)?);
    let info = *session.info();

    let frames = manifest["frames"].as_u64().ok_or("frames")? as usize;
    let fps = manifest["fps"].as_f64().ok_or("fps")?;
    let frame = (SECONDS * fps + 1e-9).floor() as usize % frames;
    let floats = |name: &str, per_frame: usize| -> Result<Vec<f32>, Box<dyn std::error::Error>> {
        let offset = manifest["arrays"][name]["offset"]
            .as_u64()
            .ok_or(name.to_owned())? as usize;
        let start = offset + frame * per_frame * 4;
        let bytes = bin
            .get(start..start + per_frame * 4)
            .ok_or("clip.bin is short")?;
        Ok(bytes
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes(b.try_into().unwrap()))
            .collect())
    };
    let angles = floats("angles", info.pose_len())?;
    let flat = floats("bone_rotations", info.bones() * 9)?;
    let bones: Vec<[[f32; 3]; 3]> = flat
        .chunks_exact(9)
        .map(|r| [[r[0], r[1], r[2]], [r[3], r[4], r[5]], [r[6], r[7], r[8]]])
        .collect();
    let mut lighting = vec![0.0; info.coeffs()];
    for (c, value) in SKY {
        lighting[c] = value;
    }
    let (azimuth, elevation, strength) = LIGHT;
    let dir = [
        elevation.cos() * azimuth.cos(),
        elevation.cos() * azimuth.sin(),
        elevation.sin(),
    ];
    add_directional(info.order(), dir, strength, &mut lighting)?;

    let mut shading = vec![0.0; info.vertices()];
    let mut runs = Vec::new();
    for _ in 0..5 {
        let start = Instant::now();
        for _ in 0..300 {
            session.shade(&angles, &lighting, &bones, &mut shading)?;
        }
        runs.push(start.elapsed().as_secs_f64() * 1e6 / 300.0);
    }
    runs.sort_by(f64::total_cmp);
    println!(
        "native: frame {frame}, {} vertices, {:.1} µs per frame (median of 5 × 300)",
        info.vertices(),
        runs[2]
    );
    Ok(())
}
