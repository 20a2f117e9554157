//! The fuzz harness of the trainer's readers of characters: arbitrary bytes into the glTF
//! loader (`.gltf` JSON or `.glb`) and the BVH parser with the mannequin built from it. Each
//! gives a rig or an error, never a panic, and never takes time or memory out of proportion
//! to the input. The `gltf` and `bvh` targets in `fuzz/` call these; `tests/tests/loaders.rs`
//! runs them on mutations of the valid fixtures under stable `cargo test`.
//!
//! What is checked beyond "no panic":
//! - an error names the file it was given (`fuzz.gltf`, `fuzz.bvh`) and every message of its
//!   chain is one line, so the CLI prints exactly one `aprt:` line;
//! - a loaded rig poses: the rest pose and the first frame of every clip of up to [`FRAMES`]
//!   frames (the BVH motion's first [`FRAMES`]) give a mesh with one position per bind-mesh
//!   vertex, and every clip frame has one value per pose entry.

use std::error::Error;
use std::path::Path;

use aprt_trainer::{GltfRig, Mocap, MocapOptions, MocapRig, Rig};

/// The name the glTF harness gives its bytes.
pub const GLTF_NAME: &str = "fuzz.gltf";
/// The name the BVH harness gives its bytes.
pub const BVH_NAME: &str = "fuzz.bvh";
/// Longer clips are not sampled, to keep an input cheap.
pub const FRAMES: usize = 64;

/// Loads `bytes` as a glTF document (sampled at 2 fps) and poses it; returns the load error's
/// message if it is refused.
pub fn gltf(bytes: &[u8]) -> Result<(), String> {
    let rig = GltfRig::from_slice(bytes, Path::new(GLTF_NAME), 2.0).map_err(|e| refused(&e))?;
    exercise(&rig, |name| {
        // `animated_joint_matrices` says how long a clip is without sampling all of it; a
        // clip too long to sample at all is refused for its first frame too.
        let first = rig.animated_joint_matrices(name, 0);
        first.is_ok() && rig.animated_joint_matrices(name, FRAMES).is_err()
    });
    Ok(())
}

/// Parses `bytes` as BVH (invalid UTF-8 replaced) and builds its mannequin; returns the error
/// message if either is refused.
pub fn bvh(bytes: &[u8]) -> Result<(), String> {
    let text = String::from_utf8_lossy(bytes);
    let mocap = Mocap::parse(&text, Path::new(BVH_NAME)).map_err(|e| refused(&e))?;
    let frames = mocap.frame_count();
    // Named after the file, as the mannequin's errors name the clip (the file stem).
    let rig =
        MocapRig::from_mocap(mocap, BVH_NAME, &MocapOptions::default()).map_err(|e| refused(&e))?;
    if frames > 0 {
        let clip = rig.clip_range(0..frames.min(FRAMES));
        check_frames(&rig, &clip.expect("the file's own frames sample"));
    }
    exercise(&rig, |_| false);
    Ok(())
}

/// The message chain of a refusal, checked: it names the input, one line per message.
fn refused(error: &dyn Error) -> String {
    let mut chain = error.to_string();
    let mut source = error.source();
    while let Some(e) = source {
        chain.push_str(": ");
        chain.push_str(&e.to_string());
        source = e.source();
    }
    assert!(
        chain.contains(GLTF_NAME) || chain.contains(BVH_NAME),
        "the message does not name the file: {chain}"
    );
    assert!(!chain.contains('\n'), "a message spans lines: {chain:?}");
    chain
}

/// Poses the rest pose, and samples every clip `sample_all` allows.
fn exercise(rig: &dyn Rig, sample_all: impl Fn(&str) -> bool) {
    let entries = rig.angle_names().len();
    let rest = rig.pose(&vec![0.0; entries]).expect("the rest pose poses");
    assert_eq!(rest.positions.len(), rig.bind_mesh().positions.len());
    for name in rig.clip_names() {
        if !sample_all(&name) {
            continue;
        }
        let clip = rig.clip(&name).expect("a listed clip samples");
        check_frames(rig, &clip);
    }
}

/// Every frame of `clip` has one value per pose entry; the first one poses the mesh.
fn check_frames(rig: &dyn Rig, clip: &aprt_trainer::Clip) {
    let entries = rig.angle_names().len();
    assert!(!clip.frames.is_empty(), "clip {} has no frames", clip.name);
    assert!(clip.frames.iter().all(|f| f.len() == entries));
    let posed = rig.pose(&clip.frames[0]).expect("a clip frame poses");
    assert_eq!(posed.positions.len(), rig.bind_mesh().positions.len());
}
