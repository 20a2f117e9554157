//! Pictures shared by the demo and the results document: SH lighting for renders, shading
//! from transfer, and ground truth | prediction | 4× error panels.

use std::path::Path;

use anyhow::Result;
use glam::{Quat, Vec3};

use crate::bake::clip::BakedClip;
use crate::report::render::{Colormap, View, render_scalar, save_png_atomic, side_by_side};
use crate::rig::mesh::Mesh;

/// SH lighting of the pictures: a directional light (Hanning-windowed to tame ringing) and a
/// dim uniform sky, so shadowed regions stay readable.
pub fn picture_lighting(order: usize, to_light: Vec3) -> Vec<f32> {
    let mut l = vec![0.0f32; order * order];
    aprt_core::project_directional(order, to_light.normalize().to_array(), 1.0, &mut l)
        .expect("valid order and direction");
    for (c, x) in l.iter_mut().enumerate() {
        let band = aprt_core::band_of(c) as f32;
        *x *= 0.5 * (1.0 + (std::f32::consts::PI * band / order as f32).cos());
    }
    l[0] += 0.15 * (4.0 * std::f32::consts::PI).sqrt() / std::f32::consts::PI;
    l
}

/// Shading `Σ_c L_c t_c` per vertex (shown directly as grey: an albedo of π).
pub fn shade_with(transfer: &[f32], lighting: &[f32]) -> Vec<f32> {
    transfer
        .chunks_exact(lighting.len())
        .map(|t| t.iter().zip(lighting).map(|(a, b)| a * b).sum::<f32>())
        .collect()
}

/// The view of the pictures: three-quarter from the front, slightly from above.
pub const PICTURE_VIEW: View = View {
    yaw: 0.5,
    pitch: 0.15,
};

/// Whether [`save_panels`] adds a panel of the error between the first two shadings.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ErrorPanel {
    /// A last panel shows 4× the absolute difference of the first two (blue 0, red ≥ 0.25).
    Shown,
    /// Only the shadings.
    Omitted,
}

/// Writes `mesh` shaded by each of `shadings` side by side, in grey, and the error panel if
/// `panel` asks for it.
pub fn save_panels(path: &Path, mesh: &Mesh, shadings: &[&[f32]], panel: ErrorPanel) -> Result<()> {
    let (w, h) = (360, 480);
    let mut panels = shadings
        .iter()
        .map(|s| render_scalar(mesh, s, PICTURE_VIEW, w, h, Colormap::Grey))
        .collect::<Result<Vec<_>, _>>()?;
    if panel == ErrorPanel::Shown && shadings.len() >= 2 {
        let error: Vec<f32> = shadings[0]
            .iter()
            .zip(shadings[1])
            .map(|(a, b)| 4.0 * (a - b).abs())
            .collect();
        panels.push(render_scalar(
            mesh,
            &error,
            PICTURE_VIEW,
            w,
            h,
            Colormap::Error { max: 1.0 },
        )?);
    }
    save_png_atomic(path, &side_by_side(&panels))?;
    Ok(())
}

/// The mesh turned so `up` points along +z, the renderer's up.
pub fn upright(mesh: &Mesh, up: Vec3) -> Mesh {
    let q = Quat::from_rotation_arc(up.normalize(), Vec3::Z);
    let turn = |v: &[f32; 3]| (q * Vec3::from(*v)).to_array();
    Mesh {
        positions: mesh.positions.iter().map(turn).collect(),
        normals: mesh.normals.iter().map(turn).collect(),
        triangles: mesh.triangles.clone(),
    }
}

/// Writes ground truth | `blob`'s prediction through aprt-core | 4× error for frame `frame`
/// of `clip` under `lighting`, with the character's `up` turned to the screen's up. Returns
/// the ground-truth shading, for further panels.
pub fn save_model_frame(
    path: &Path,
    blob: &[u8],
    clip: &BakedClip,
    frame: usize,
    lighting: &[f32],
    up: Vec3,
) -> Result<Vec<f32>> {
    let truth = shade_with(&clip.transfer[frame], lighting);
    let model = crate::model::runtime::predict_shading(
        blob,
        &clip.angles[frame],
        &clip.core_rotations(frame),
        lighting,
    )?;
    let mesh = upright(&clip.meshes[frame], up);
    save_panels(path, &mesh, &[&truth, &model], ErrorPanel::Shown)?;
    Ok(truth)
}
