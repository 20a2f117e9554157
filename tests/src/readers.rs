//! The fuzz harness of the trainer's readers of settings and data: the scene file, the lights
//! file, the `.shlm` light-map sequence, the equirectangular environment map (`.hdr`, `.exr`)
//! and the `.npy` array. Each gives a value or an error, never a panic, and never takes time or
//! memory out of proportion to the input. The `scene`, `lights`, `shlm`, `env_map` and `npy`
//! targets in `fuzz/` call these; `tests/tests/readers.rs` runs them on prefixes and mutations
//! of their seeds under stable `cargo test`.
//!
//! What is checked beyond "no panic":
//! - every message of a refusal's chain is one line, so the CLI prints exactly one `aprt:`
//!   line; the scene, lights and environment-map errors name the file they were given (the
//!   `.shlm` and `.npy` readers take bytes, and the CLI names the file around their errors);
//! - what is accepted holds what the reader promises: finite f32 values where the formats say
//!   so, counts within their caps, a decoded size that matches the header.

use std::error::Error;
use std::path::Path;

use aprt_core::{Light, MAX_ORDER};
use aprt_trainer::io::npy::{decode_f32, encode_f32};
use aprt_trainer::lighting::lights_file::{MAX_LIGHTS, parse_lights};
use aprt_trainer::lighting::{EnvironmentImage, decode_equirect};
use aprt_trainer::lightmap::codec::ShlmFile;
use aprt_trainer::limits::MAX_RAYS;
use aprt_trainer::scene::file::{Choice, Environment, SceneSource, parse_scene};

/// The name the scene harness gives its bytes.
pub const SCENE_NAME: &str = "fuzz.toml";
/// The name the lights harness gives its bytes.
pub const LIGHTS_NAME: &str = "fuzz-lights.toml";
/// The names the environment-map harness gives its bytes: OpenEXR when they start with the
/// first byte of its magic (`v`, 0x76), Radiance otherwise.
pub const HDR_NAME: &str = "fuzz.hdr";
/// See [`HDR_NAME`].
pub const EXR_NAME: &str = "fuzz.exr";
/// What a decoded environment map or light-map sequence may hold here, far below the
/// trainer's own budget (`MAX_BYTES`, 4 GB) so that no input reaches libFuzzer's 2 GB limit.
pub const FUZZ_BYTES: u64 = 64 << 20;
/// The SH order environment maps are projected to.
pub const ENV_ORDER: usize = 3;

/// Parses `bytes` as a scene file (invalid UTF-8 replaced) and checks what it holds; returns
/// the error's message if it is refused.
pub fn scene(bytes: &[u8]) -> Result<(), String> {
    let text = String::from_utf8_lossy(bytes);
    let scene = parse_scene(&text, Path::new(SCENE_NAME)).map_err(|e| refused(&e, SCENE_NAME))?;
    let e = &scene.effects;
    assert!(e.bounces <= 8 && (1..=MAX_RAYS).contains(&e.rays));
    assert!((0.0..=1.0).contains(&e.albedo));
    assert!(e.error_target.is_finite() && e.error_target > 0.0);
    if let Choice::Fixed(order) = e.order {
        assert!((1..=MAX_ORDER).contains(&order));
    }
    let b = &scene.budget;
    assert!(b.us_per_frame.is_none_or(|us| us.is_finite() && us > 0.0));
    assert!(b.bytes.is_none_or(|bytes| bytes > 0));
    if let SceneSource::Gltf { fps: Some(fps), .. } = scene.source {
        assert!(fps.is_finite() && fps > 0.0);
    }
    match &scene.environment {
        Some(Environment::Sh(sh)) => {
            assert!(
                (1..=MAX_ORDER).any(|o| o * o == sh.len()),
                "{} SH",
                sh.len()
            );
            assert!(sh.iter().flatten().all(|x| x.is_finite()));
            assert!(sh[0].iter().all(|&x| x >= 0.0), "negative band 0");
        }
        Some(Environment::Map(_)) => {}
        None => assert!(!scene.lights.is_empty(), "nothing lights the scene"),
    }
    check_lights(&scene.lights);
    let obj_seq = matches!(scene.source, SceneSource::ObjSeq { .. });
    assert!(obj_seq || !scene.train.is_empty(), "no training clips");
    assert_eq!(scene.clip_specs("train").len(), scene.train.len());
    assert_eq!(scene.clip_specs("validate").len(), scene.validate.len());
    assert_eq!(scene.clip_specs("test").len(), scene.test.len());
    Ok(())
}

/// Parses `bytes` as a lights file (invalid UTF-8 replaced) and checks the lights; returns the
/// error's message if it is refused.
pub fn lights(bytes: &[u8]) -> Result<(), String> {
    let text = String::from_utf8_lossy(bytes);
    let lights =
        parse_lights(&text, Path::new(LIGHTS_NAME)).map_err(|e| refused(&e, LIGHTS_NAME))?;
    assert!(!lights.is_empty(), "a lights file holds at least one light");
    check_lights(&lights);
    Ok(())
}

/// Parses `bytes` as a `.shlm` file, as they are and with the trailing CRC recomputed (so
/// mutations reach the checks behind it), and decodes what is accepted; returns the first
/// error's message if both are refused.
pub fn shlm(bytes: &[u8]) -> Result<(), String> {
    let as_is = shlm_once(bytes);
    if bytes.len() < 4 {
        return as_is;
    }
    let mut resealed = bytes.to_vec();
    let body = resealed.len() - 4;
    let crc = aprt_core::format::crc32(&resealed[..body]);
    resealed[body..].copy_from_slice(&crc.to_le_bytes());
    as_is.or_else(|_| shlm_once(&resealed))
}

fn shlm_once(bytes: &[u8]) -> Result<(), String> {
    let file = ShlmFile::parse(bytes).map_err(|e| refused(&e, ""))?;
    let (r, n2, frames) = (file.resolution(), file.order().pow(2), file.frames());
    assert!((1..=MAX_ORDER).contains(&file.order()) && frames >= 1);
    let filled = file.filled();
    let count = filled.iter().filter(|&&f| f).count();
    assert_eq!(filled.len(), r * r);
    assert_eq!(file.positions().len(), count);
    assert!(file.positions().iter().flatten().all(|x| x.is_finite()));
    let _ = file.describe();
    let frame_bytes = (r * r * n2 * 4) as u64;
    if file.raw_bytes() <= FUZZ_BYTES {
        match file.decode_all() {
            Ok(maps) => {
                assert_eq!(maps.len(), frames);
                maps.iter().for_each(|m| check_map(m, &filled, n2));
            }
            Err(e) => drop(refused(&e, "")),
        }
    } else if frame_bytes <= FUZZ_BYTES {
        let mut map = vec![f32::NAN; r * r * n2];
        for k in [0, frames - 1] {
            match file.decode_frame(k, &mut map) {
                Ok(()) => check_map(&map, &filled, n2),
                Err(e) => drop(refused(&e, "")),
            }
        }
    }
    Ok(())
}

/// A decoded frame: finite, and zero where no texel is filled.
fn check_map(map: &[f32], filled: &[bool], n2: usize) {
    assert_eq!(map.len(), filled.len() * n2);
    for (values, &f) in map.chunks_exact(n2).zip(filled) {
        assert!(values.iter().all(|x| x.is_finite()), "non-finite decode");
        assert!(
            f || values.iter().all(|&x| x == 0.0),
            "an empty texel holds values"
        );
    }
}

/// Decodes `bytes` as an equirectangular OpenEXR map when they start with `v` (the first byte
/// of its magic), Radiance HDR otherwise, within [`FUZZ_BYTES`], and projects it to SH order
/// [`ENV_ORDER`]; returns the error's message if either refuses it.
pub fn env_map(bytes: &[u8]) -> Result<(), String> {
    let name = match bytes.first() {
        Some(0x76) => EXR_NAME,
        _ => HDR_NAME,
    };
    let image =
        decode_equirect(Path::new(name), bytes, FUZZ_BYTES).map_err(|e| refused(&e, name))?;
    let EnvironmentImage {
        width,
        height,
        pixels,
        ..
    } = &image;
    assert_eq!(width * height, pixels.len());
    let sh = image.project(ENV_ORDER).map_err(|e| refused(&e, name))?;
    assert_eq!(sh.len(), ENV_ORDER * ENV_ORDER);
    assert!(sh.iter().flatten().all(|x| x.is_finite()));
    // Band 0 integrates radiance, never negative, against a positive constant.
    assert!(
        sh[0].iter().all(|&x| x >= 0.0),
        "negative band 0: {:?}",
        sh[0]
    );
    Ok(())
}

/// Decodes `bytes` as a `.npy` float32 array; an accepted one has one value per element of its
/// shape and, written again, reads back bit for bit. Returns the error's message if refused.
pub fn npy(bytes: &[u8]) -> Result<(), String> {
    let (shape, values) = decode_f32(bytes).map_err(|e| refused(&e, ""))?;
    let elements = shape.iter().try_fold(1usize, |n, &d| n.checked_mul(d));
    assert_eq!(elements, Some(values.len()), "shape {shape:?}");
    // The writer's header is at most 65,535 bytes: a few dimensions always fit.
    if shape.len() <= 32 {
        let again = decode_f32(&encode_f32(&shape, &values)).expect("its own output reads");
        assert_eq!(again.0, shape);
        assert!(
            again
                .1
                .iter()
                .zip(&values)
                .all(|(a, b)| a.to_bits() == b.to_bits())
        );
    }
    Ok(())
}

/// Lights as the readers promise them: at most [`MAX_LIGHTS`], every value a finite f32,
/// colours not negative, radii positive, directions not zero.
fn check_lights(lights: &[Light]) {
    assert!(lights.len() <= MAX_LIGHTS, "{} lights", lights.len());
    let finite = |v: &[f32]| v.iter().all(|x| x.is_finite());
    let colour = |c: &[f32; 3]| finite(c) && c.iter().all(|&x| x >= 0.0);
    for light in lights {
        let ok = match light {
            Light::Sphere(s) => {
                finite(&s.position) && s.radius.is_finite() && s.radius > 0.0 && colour(&s.radiance)
            }
            Light::Point(p) => finite(&p.position) && colour(&p.intensity),
            Light::Directional(d) => {
                finite(&d.direction) && d.direction != [0.0; 3] && colour(&d.irradiance)
            }
        };
        assert!(ok, "accepted {light:?}");
    }
}

/// The message chain of a refusal, checked: every message one line, and the whole naming
/// `name` (unless empty).
fn refused(error: &dyn Error, name: &str) -> String {
    let mut chain = error.to_string();
    let mut source = error.source();
    while let Some(e) = source {
        chain.push_str(": ");
        chain.push_str(&e.to_string());
        source = e.source();
    }
    assert!(!chain.is_empty(), "an empty message");
    assert!(
        chain.contains(name),
        "the message does not name {name}: {chain}"
    );
    assert!(!chain.contains('\n'), "a message spans lines: {chain:?}");
    chain
}
