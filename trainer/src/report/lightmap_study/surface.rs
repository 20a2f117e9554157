//! The study's truth on the whole surface ([`crate::surface`]): every frame of a clip baked at
//! points spread over the character by area, and each method read there as an engine shows
//! it — per-vertex transfer interpolated across its triangle, a light map filtered bilinearly
//! at the point's light-map UV — so a shadow inside a large face counts against the vertices
//! that cannot hold it.

use anyhow::{Context, Result};
use aprt_core::Light;

use crate::bake::clip::{BakedClip, bake_clip};
use crate::bake::{BakeSettings, PatternRotation, bake_points};
use crate::lighting::luminance;
use crate::progress::Reporter;
use crate::rig::Clip;
use crate::rig::Rig;
use crate::rig::mesh::Mesh;
use crate::rig::pose_layout::PoseLayout;
use crate::rig::uv::UvLayout;
use crate::surface::SurfacePoints;
use crate::surface::error::{Accuracy, ErrorSum};

/// Ground truth of one clip at the vertices and at the surface points, from one simulator
/// (the same rays, bounces and order).
pub struct ClipTruth {
    /// Per-vertex truth, with the poses and meshes.
    pub vertices: BakedClip,
    /// Seconds per frame of the vertex bake.
    pub vertex_s: f64,
    /// Per frame, every surface point's transfer (`points × n²`, point-major).
    pub surface: Vec<Vec<f32>>,
}

/// Bakes `clip` of `rig` at its vertices and at `points` (spread on the bind mesh, riding the
/// skin), frame by frame with `bake`.
pub fn clip_truth(
    rig: &dyn Rig,
    layout: &PoseLayout,
    clip: &Clip,
    points: &SurfacePoints,
    bake: &BakeSettings,
    reporter: &dyn Reporter,
) -> Result<ClipTruth> {
    let (vertices, vertex_s) =
        bake_clip(rig, layout, &clip.name, clip.frames.clone(), bake, reporter)?;
    let surface = bake_surface(&vertices.meshes, points, bake, reporter)
        .with_context(|| format!("baking clip {} at the surface points", clip.name))?;
    Ok(ClipTruth {
        vertices,
        vertex_s,
        surface,
    })
}

/// Every posed mesh's transfer at `points`, each point with its own turn of the ray pattern
/// as each vertex has in the vertex bake, with one progress display over all of them.
pub fn bake_surface(
    meshes: &[Mesh],
    points: &SurfacePoints,
    bake: &BakeSettings,
    reporter: &dyn Reporter,
) -> Result<Vec<Vec<f32>>> {
    bake.validate()?;
    let progress = reporter.bake_progress(points.len() * meshes.len());
    let mut out = Vec::with_capacity(meshes.len());
    for (p, mesh) in meshes.iter().enumerate() {
        progress.pose(p, meshes.len());
        let (positions, normals) = points.on(mesh);
        out.push(bake_points(
            mesh,
            (&positions, &normals),
            PatternRotation::PerPoint,
            bake,
            progress.as_ref(),
        )?);
    }
    progress.finish();
    Ok(out)
}

/// The luminance of `lights`' SH radiance at the origin, `order²` values: the one lighting of
/// directional lights everywhere, which the surface's grey levels are measured under.
pub fn luminance_sh(lights: &[Light], order: usize) -> Result<Vec<f32>> {
    let mut rgb = vec![[0.0f32; 3]; order * order];
    for light in lights {
        light
            .add_radiance_sh(order, [0.0; 3], &mut rgb)
            .context("projecting a preview light to SH")?;
    }
    Ok(rgb.into_iter().map(luminance).collect())
}

/// Where a case's methods are read at the surface: the points, their UVs in one light-map
/// layout, the bind mesh's triangles (which per-vertex values interpolate across) and the
/// luminance lighting the grey levels are measured under.
pub struct Probe<'a> {
    /// The points.
    pub points: &'a SurfacePoints,
    /// Each point's UV in the light map's layout.
    pub uvs: Vec<[f32; 2]>,
    /// The bind mesh's triangles.
    pub triangles: &'a [[u32; 3]],
    /// Luminance SH lighting, one value per coefficient of the truth.
    pub lighting: &'a [f32],
}

impl<'a> Probe<'a> {
    /// The probe of `points` for maps laid out by `layout`.
    pub fn new(
        points: &'a SurfacePoints,
        layout: &UvLayout,
        triangles: &'a [[u32; 3]],
        lighting: &'a [f32],
    ) -> Self {
        Probe {
            points,
            uvs: points.uvs(layout),
            triangles,
            lighting,
        }
    }

    /// Per-vertex values of every frame (`n2` per vertex) interpolated at the points.
    pub fn of_vertices(&self, frames: &[Vec<f32>], n2: usize) -> Vec<Vec<f32>> {
        frames
            .iter()
            .map(|f| self.points.from_vertices(f, n2, self.triangles))
            .collect()
    }

    /// Every full map (`resolution`² texels × `n2`) read bilinearly at the points' UVs.
    pub fn of_maps(&self, maps: &[Vec<f32>], resolution: usize, n2: usize) -> Vec<Vec<f32>> {
        maps.iter()
            .map(|m| SurfacePoints::from_map(m, resolution, n2, &self.uvs))
            .collect()
    }

    /// The area-weighted error of `pred` (per frame, `pred_n2` values per point) against
    /// `truth` (per frame, the lighting's count per point) over every frame.
    pub fn error(&self, pred: &[Vec<f32>], pred_n2: usize, truth: &[Vec<f32>]) -> Accuracy {
        let weights: Vec<f64> = self.points.points.iter().map(|p| p.weight).collect();
        let mut sum = ErrorSum::new(self.lighting);
        for (p, t) in pred.iter().zip(truth) {
            sum.add(p, pred_n2, t, Some(&weights));
        }
        sum.finish()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit square of two triangles (four vertices) under a field the vertices cannot hold:
    /// band 0 is 0 on the strip x < 1/4 and 1 elsewhere (a shadow's edge through both
    /// triangles' interiors), band 1 is 0. The vertices hold the field at the corners, so
    /// interpolated they give x everywhere; the map holds it at texel centres (UVs are the
    /// positions), so only the one texel column the edge crosses is smeared. Each error
    /// against the field at the points matches its closed form.
    #[test]
    fn a_map_holds_an_edge_inside_a_face_and_the_vertices_do_not() {
        let mesh = Mesh::with_area_weighted_normals(
            vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [0.0, 1.0, 0.0],
            ],
            vec![[0, 1, 2], [0, 2, 3]],
        );
        let field = |x: f32| if x < 0.25 { 0.0f32 } else { 1.0 };
        let points = SurfacePoints::spread(&mesh, 20_000).unwrap();
        let (positions, _) = points.on(&mesh);
        let truth = vec![
            positions
                .iter()
                .flat_map(|p| [field(p[0]), 0.0])
                .collect::<Vec<f32>>(),
        ];
        let layout = UvLayout::from_vertex_uvs(
            &mesh
                .positions
                .iter()
                .map(|p| [p[0], p[1]])
                .collect::<Vec<_>>(),
            &mesh.triangles,
        );
        let lighting = [1.0f32, 0.0];
        let probe = Probe::new(&points, &layout, &mesh.triangles, &lighting);
        // Corner values: the field at each vertex, as a vertex bake gives.
        let corners: Vec<f32> = mesh
            .positions
            .iter()
            .flat_map(|p| [field(p[0]), 0.0])
            .collect();
        let vertex = probe.error(&probe.of_vertices(&[corners], 2), 2, &truth);
        // Interpolated, the corners give x (0 on the left edge, 1 on the right) everywhere:
        // against the step the squared error is ∫₀^¼ x² dx + ∫_¼^1 (1 − x)² dx = 1/192 +
        // 27/192 = 7/48 over a norm of ∫_¼^1 1 dx = 3/4.
        let expected = (7.0f64 / 48.0 / 0.75).sqrt();
        assert!(
            (vertex.transfer_error - expected).abs() < 0.01,
            "{vertex:?} against {expected}"
        );
        let r = 64;
        let map: Vec<f32> = (0..r * r)
            .flat_map(|t| [field(((t % r) as f32 + 0.5) / r as f32), 0.0])
            .collect();
        let lit = probe.error(&probe.of_maps(&[map], r, 2), 2, &truth);
        // The edge lies on a texel boundary; bilinear filtering ramps it from one texel centre
        // to the next, an error rising linearly to 1/2 on each side over half a texel:
        // squared error 2 · (1/2R) · (1/4)/3 = 1/(12R) over the norm 3/4.
        let expected = (1.0 / (12.0 * r as f64) / 0.75).sqrt();
        assert!(
            (lit.transfer_error - expected).abs() < 0.1 * expected,
            "{lit:?} against {expected}"
        );
        assert!(lit.transfer_error < vertex.transfer_error / 4.0);
        // Grey levels follow band 0 alone under this lighting: the same ratio.
        let ratio = vertex.grey_rms / lit.grey_rms;
        let transfer_ratio = vertex.transfer_error / lit.transfer_error;
        assert!(
            (ratio / transfer_ratio - 1.0).abs() < 1e-6,
            "{ratio} {transfer_ratio}"
        );
    }
}
