//! `aprt export-web`: what the web page (`web/`) needs to play a clip of a model's character
//! through aprt-core in the browser: the mesh and its skin (the page skins it every frame,
//! bit for bit as `rig/skin.rs` does), and per frame the skinning matrices, the model's pose
//! vector and the bones' rotations, computed by the same code as `aprt eval` so the page's
//! shading can be checked against it. A model with occluder proxies needs nothing more: its
//! bones' skinning matrices, which pose the proxies, are the first joints', and the posed
//! mesh they occlude is the page's own skinning.
//!
//! The files: `manifest.json` (dimensions, and each array's dtype, shape and byte offset in
//! `clip.bin`), `clip.bin` (little-endian arrays, each 4-byte aligned) and `model.aprt` (the
//! blob, unchanged).

use std::path::Path;

use anyhow::{Context, Result, bail};
use serde::Serialize;

use crate::io::atomic::write_atomic;
use crate::model::runtime::BlobInfo;
use crate::rig::bone_frames::bone_rotations;
use crate::rig::pose_layout::PoseLayout;
use crate::rig::transfer_rotation::row_major;
use crate::rig::{Clip, Rig};

/// The files [`write_web_export`] writes into its directory.
pub const WEB_FILES: [&str; 3] = ["manifest.json", "clip.bin", "model.aprt"];

/// What the format of `manifest.json` and `clip.bin` is called; the page refuses others.
pub const WEB_FORMAT: &str = "aprt-web 1";

/// One array of `clip.bin`.
#[derive(Debug, Serialize)]
pub struct WebArray {
    /// `f32`, `u32` or `u16`.
    pub dtype: &'static str,
    /// Its shape, row-major.
    pub shape: Vec<usize>,
    /// Its first byte in `clip.bin`.
    pub offset: usize,
}

/// `manifest.json`.
#[derive(Debug, Serialize)]
pub struct WebManifest {
    /// [`WEB_FORMAT`].
    pub format: &'static str,
    /// The clip's name.
    pub clip: String,
    /// Its frames per second.
    pub fps: f64,
    /// Its frames.
    pub frames: usize,
    /// Mesh vertices (the model's).
    pub vertices: usize,
    /// Skin joints (the model's bones for a bone-frame model).
    pub joints: usize,
    /// Influences per vertex in `skin_joints` and `skin_weights` (unused ones weigh 0).
    pub influences: usize,
    /// The model's pose-vector length.
    pub pose_len: usize,
    /// The model's SH order.
    pub order: usize,
    /// The character's up axis in its mesh's frame.
    pub up: [f32; 3],
    /// The model blob's file.
    pub model: &'static str,
    /// The arrays of `clip.bin`, by name: `positions` and `normals` (bind pose, vertices × 3),
    /// `indices` (triangles × 3), `skin_joints` and `skin_weights` (vertices × influences),
    /// `joint_matrices` (frames × joints × 12, the 3 × 4 skinning matrices row-major, what
    /// `Model::pose_proxies` takes),
    /// `angles` (frames × pose_len, the model's pose vector) and `bone_rotations`
    /// (frames × bones × 9, row-major, what `Model::light` takes).
    pub arrays: std::collections::BTreeMap<&'static str, WebArray>,
}

/// `clip.bin` as it is built, with the manifest's entry of every array.
#[derive(Default)]
struct Bin {
    bytes: Vec<u8>,
    arrays: std::collections::BTreeMap<&'static str, WebArray>,
}

impl Bin {
    fn push(&mut self, name: &'static str, dtype: &'static str, shape: &[usize], data: &[u8]) {
        while !self.bytes.len().is_multiple_of(4) {
            self.bytes.push(0);
        }
        let entry = WebArray {
            dtype,
            shape: shape.to_vec(),
            offset: self.bytes.len(),
        };
        self.arrays.insert(name, entry);
        self.bytes.extend_from_slice(data);
    }

    fn f32s(&mut self, name: &'static str, shape: &[usize], data: impl Iterator<Item = f32>) {
        let bytes: Vec<u8> = data.flat_map(f32::to_le_bytes).collect();
        self.push(name, "f32", shape, &bytes);
    }
}

/// The manifest and `clip.bin` of `clip` of `rig` for the model `info` describes. Errors
/// when the model does not fit the character (names, vertex or bone count).
pub fn web_export(rig: &dyn Rig, clip: &Clip, info: &BlobInfo) -> Result<(WebManifest, Vec<u8>)> {
    let layout = PoseLayout::from_names(&rig.angle_names(), &info.angle_names)
        .context("the model does not fit this character")?;
    let mesh = rig.bind_mesh();
    let Some(first) = clip.frames.first() else {
        bail!("clip {} has no frames", clip.name);
    };
    // Skin joints index the skinning matrices; a bone-frame model's bones are their first ones.
    let (vertices, joints) = (mesh.vertex_count(), rig.joint_matrices(first)?.len());
    if vertices != info.vertices || info.bones > joints {
        bail!(
            "the model has {} vertices and {} bones, the character {vertices} and {joints} joints",
            info.vertices,
            info.bones
        );
    }
    let frames = clip.frames.len();
    let mut bin = Bin::default();
    let flat = |v: &[[f32; 3]]| v.iter().flatten().copied().collect::<Vec<_>>();
    bin.f32s(
        "positions",
        &[vertices, 3],
        flat(&mesh.positions).into_iter(),
    );
    bin.f32s("normals", &[vertices, 3], flat(&mesh.normals).into_iter());
    let indices: Vec<u8> = mesh
        .triangles
        .iter()
        .flatten()
        .flat_map(|i| i.to_le_bytes())
        .collect();
    bin.push("indices", "u32", &[mesh.triangles.len(), 3], &indices);
    let influences = push_skin(&mut bin, rig);

    let mut matrices = Vec::with_capacity(frames * joints * 12);
    let mut rotations = Vec::with_capacity(frames * info.bones * 9);
    for pose in &clip.frames {
        for m in rig.joint_matrices(pose)? {
            matrices.extend((0..3).flat_map(|r| m.row(r).to_array()));
        }
        for r in bone_rotations(rig, pose)?.into_iter().take(info.bones) {
            rotations.extend(row_major(r).into_iter().flatten());
        }
    }
    bin.f32s(
        "joint_matrices",
        &[frames, joints, 12],
        matrices.into_iter(),
    );
    let angles = clip.frames.iter().flat_map(|p| layout.reduce(p));
    bin.f32s("angles", &[frames, info.pose_len], angles.map(|a| a as f32));
    bin.f32s(
        "bone_rotations",
        &[frames, info.bones, 9],
        rotations.into_iter(),
    );

    let manifest = WebManifest {
        format: WEB_FORMAT,
        clip: clip.name.clone(),
        fps: clip.fps,
        frames,
        vertices,
        joints,
        influences,
        pose_len: info.pose_len,
        order: info.order,
        up: rig.up().to_array(),
        model: WEB_FILES[2],
        arrays: std::mem::take(&mut bin.arrays),
    };
    Ok((manifest, bin.bytes))
}

/// Appends `skin_joints` (u16) and `skin_weights` (f32), each vertex's influences padded to
/// the most any vertex has; returns that count.
fn push_skin(bin: &mut Bin, rig: &dyn Rig) -> usize {
    let skin = rig.skin();
    let vertices = skin.vertex_count();
    let most = (0..vertices)
        .map(|j| skin.influences(j).len())
        .max()
        .unwrap_or(0);
    let mut joints = Vec::with_capacity(vertices * most * 2);
    let mut weights = Vec::with_capacity(vertices * most);
    for j in 0..vertices {
        let padding = std::iter::repeat_n((0, 0.0), most - skin.influences(j).len());
        for (joint, weight) in skin.influences(j).chain(padding) {
            joints.extend((joint as u16).to_le_bytes());
            weights.push(weight);
        }
    }
    bin.push("skin_joints", "u16", &[vertices, most], &joints);
    bin.f32s("skin_weights", &[vertices, most], weights.into_iter());
    most
}

/// Writes [`WEB_FILES`] into `dir` (created if missing), each atomically.
pub fn write_web_export(dir: &Path, manifest: &WebManifest, bin: &[u8], blob: &[u8]) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let json = serde_json::to_string_pretty(manifest)? + "\n";
    for (name, bytes) in WEB_FILES.iter().zip([json.as_bytes(), bin, blob]) {
        let path = dir.join(name);
        write_atomic(&path, bytes).with_context(|| format!("cannot write {}", path.display()))?;
    }
    Ok(())
}
