//! The study's picture per method on one pose, drawn from surface points rather than from the
//! mesh: ground truth ray-traced at every point | the vertices' ray-traced transfer
//! interpolated across each triangle | the light map read bilinearly at each point's UV, and
//! under the two methods their absolute error on one colour scale. A rasterised mesh would
//! draw the vertex method exactly and the truth only at the vertices; drawn from points dense
//! enough to cover the screen, the truth shows the shadows that fall inside large faces, and
//! the vertex panel's error shows what its corners cannot hold.
//!
//! The vertex panel interpolates the per-vertex *truth*, not a fitted model's prediction, so
//! its error is what vertices cannot hold whatever their values: the model's own error only
//! adds to it (the study's tables give both).

use anyhow::{Context, Result};
use glam::Vec3;
use image::RgbImage;

use crate::bake::{BakeSettings, bake_poses};
use crate::lighting::GREY_PER_IRRADIANCE;
use crate::lightmap::bake::BakedMaps;
use crate::lightmap::codec::{CodecSettings, ShlmFile, encode};
use crate::progress::Reporter;
use crate::report::figures::{ErrorKey, PICTURE_VIEW, captioned, shade_with, upright};
use crate::report::render::{BACKGROUND, Colormap, render_splats, save_png_atomic};
use crate::rig::Rig;
use crate::rig::mesh::Mesh;
use crate::surface::SurfacePoints;
use crate::surface::error::Accuracy;

use super::surface::{Probe, bake_surface};

/// Points of the picture: about six a pixel of a 360×480 panel's character, so every pixel
/// of the surface holds a point of its own and an edge inside a face shows at the panel's
/// resolution (at the study's 16k a point covers several pixels).
pub const PICTURE_POINTS: usize = 200_000;

/// Panel size, as the previews'.
const PANEL: (u32, u32) = (360, 480);

/// How much larger than its share of the area a point's disc is drawn: the points lie on a
/// low-discrepancy pattern, not a grid, so discs of exactly their share leave gaps.
const SPLAT_SCALE: f32 = 1.5;

/// One pose shaded three ways at the picture's points (irradiance under the preview lights'
/// luminance), and the two methods' errors as the study measures them.
struct Shadings {
    truth: Vec<f32>,
    vertex: Vec<f32>,
    map: Vec<f32>,
    vertex_error: Accuracy,
    map_error: Accuracy,
}

/// Shades `posed` (the pose `baked`'s one frame was baked on) at `points`: the truth baked
/// there, the per-vertex truth interpolated, and the compressed light map read bilinearly.
fn shadings(
    rig: &dyn Rig,
    posed: &Mesh,
    baked: &BakedMaps,
    (points, lighting): (&SurfacePoints, &[f32]),
    bake: &BakeSettings,
    reporter: &dyn Reporter,
) -> Result<Shadings> {
    let seq = &baked.sequence;
    let n2 = seq.order * seq.order;
    let meshes = std::slice::from_ref(posed);
    let truth = bake_surface(meshes, points, bake, reporter)?;
    let vertices = bake_poses(meshes, bake, reporter).context("baking the picture's pose")?;
    let bytes = encode(seq, &CodecSettings::default())?;
    let map = ShlmFile::parse(&bytes)?.decode_all()?;
    let bind = rig.bind_mesh();
    let probe = Probe::new(points, &baked.layout, &bind.triangles, lighting);
    let vertex = probe.of_vertices(&vertices, n2);
    let map = probe.of_maps(&map[..1], seq.resolution, n2);
    Ok(Shadings {
        vertex_error: probe.error(&vertex, n2, &truth),
        map_error: probe.error(&map, n2, &truth),
        truth: shade_with(&truth[0], lighting),
        vertex: shade_with(&vertex[0], lighting),
        map: shade_with(&map[0], lighting),
    })
}

/// Each point's disc radius on `mesh`: a disc of the posed surface's area shared evenly among
/// the points, [`SPLAT_SCALE`] larger. One radius for all, as the points are spread at one
/// density: a sliver triangle's lone point, given a disc of its own triangle's area, would
/// leave the sliver's length uncovered, and a pixel there would show the surface behind.
fn radii(points: &SurfacePoints, mesh: &Mesh) -> Vec<f32> {
    let area: f32 = (mesh.triangles.iter())
        .map(|t| {
            let [a, b, c] = t.map(|v| Vec3::from(mesh.positions[v as usize]));
            0.5 * (b - a).cross(c - a).length()
        })
        .filter(|a| a.is_finite())
        .sum();
    let share = area / points.len().max(1) as f32;
    vec![SPLAT_SCALE * (share / std::f32::consts::PI).sqrt(); points.len()]
}

/// A round upper end for the error scale: the 99.9th percentile of `errors` (grey levels)
/// rounded up to 1, 2 or 5 times a power of ten, so a few saturated points do not wash the
/// rest out and the bar reads as a plain number. Not lower: every point's truth carries the
/// Monte Carlo noise of its rays, a few grey levels, which a scale near the bulk of the
/// errors paints over the whole surface, hiding the shadows a method misses.
fn error_scale(errors: &[f32]) -> f32 {
    let mut sorted: Vec<f32> = errors.iter().copied().filter(|e| e.is_finite()).collect();
    sorted.sort_by(f32::total_cmp);
    let high = sorted
        .get(sorted.len() * 999 / 1000)
        .copied()
        .unwrap_or(1.0)
        .max(1.0);
    let power = 10f32.powf(high.log10().floor());
    [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|m| m * power)
        .find(|&s| s >= high)
        .unwrap_or(10.0 * power)
}

/// The figure's two rows: the shadings titled over three panels, and under the two methods
/// their errors in grey levels on one scale with its colour bar.
fn figure(
    shown: &Mesh,
    points: &SurfacePoints,
    s: &Shadings,
    titles: [&str; 3],
) -> Result<(RgbImage, f32)> {
    let (positions, _) = points.on(shown);
    let radii = radii(points, shown);
    let draw = |colour: &dyn Fn(usize) -> image::Rgb<u8>| {
        render_splats(&positions, &radii, PICTURE_VIEW, PANEL, colour)
    };
    let grey = |values: &[f32]| draw(&|i| Colormap::Grey.color(values[i]));
    let top = [grey(&s.truth)?, grey(&s.vertex)?, grey(&s.map)?];
    let off = |values: &[f32]| -> Vec<f32> {
        values
            .iter()
            .zip(&s.truth)
            .map(|(v, t)| ((v - t).abs() as f64 * GREY_PER_IRRADIANCE) as f32)
            .collect()
    };
    let (vertex_off, map_off) = (off(&s.vertex), off(&s.map));
    let both: Vec<f32> = vertex_off.iter().chain(&map_off).copied().collect();
    let max = error_scale(&both);
    let error = |values: &[f32]| draw(&|i| Colormap::Error { max }.color(values[i]));
    let blank = RgbImage::from_pixel(PANEL.0, PANEL.1, BACKGROUND);
    let bottom = [blank, error(&vertex_off)?, error(&map_off)?];
    let high = format!("≥ {max} grey levels");
    let key = ErrorKey {
        label: "|error|:",
        low: "0",
        high: &high,
    };
    let top = captioned(&top, &titles, None)?;
    let bottom = captioned(
        &bottom,
        &["", "|vertices − truth|", "|light map − truth|"],
        Some(key),
    )?;
    let mut out = RgbImage::from_pixel(
        top.width().max(bottom.width()),
        top.height() + bottom.height(),
        BACKGROUND,
    );
    image::imageops::replace(&mut out, &top, 0, 0);
    image::imageops::replace(&mut out, &bottom, 0, i64::from(top.height()));
    Ok((out, max))
}

/// What the picture shows: the pose (`posed`, frame `frame` of the clip called `clip`), its
/// one-frame light map, and where to write it.
pub struct PictureOf<'a> {
    /// The character's name, for the caption.
    pub title: &'a str,
    /// The clip's name and the frame.
    pub clip: (&'a str, usize),
    /// The posed mesh.
    pub posed: &'a Mesh,
    /// The pose's light map, baked on the study's generated UVs.
    pub baked: &'a BakedMaps,
    /// Luminance SH of the preview lights.
    pub lighting: &'a [f32],
    /// The file, and its name in the markdown.
    pub path: &'a std::path::Path,
}

/// Writes the picture and returns the markdown that shows it, with a caption stating its
/// figures.
pub fn save_surface_picture(
    rig: &dyn Rig,
    of: &PictureOf<'_>,
    bake: &BakeSettings,
    reporter: &dyn Reporter,
) -> Result<String> {
    let points = SurfacePoints::spread(rig.bind_mesh(), PICTURE_POINTS)?;
    let s = shadings(
        rig,
        of.posed,
        of.baked,
        (&points, of.lighting),
        bake,
        reporter,
    )?;
    let r = of.baked.sequence.resolution;
    let truth_title = format!("ray-traced at {}k points", PICTURE_POINTS / 1000);
    let map_title = format!("light map {r}x{r}, bilinear");
    let titles = [
        truth_title.as_str(),
        "per-vertex ray-traced, interpolated",
        map_title.as_str(),
    ];
    let shown = upright(of.posed, rig.up());
    let (image, max) = figure(&shown, &points, &s, titles)?;
    save_png_atomic(of.path, &image)?;
    let file = of
        .path
        .file_name()
        .map_or_else(String::new, |f| f.to_string_lossy().into_owned());
    let (v, m) = (s.vertex_error, s.map_error);
    Ok(format!(
        "![{title}: truth, vertices and light map at the surface]({file})\n\n*{title}, `{clip}` frame {frame}, drawn from {points} surface points (each a disc of its share of the area): ray-traced at every point | the vertices' ray-traced transfer interpolated across each triangle (what a GPU's varyings give; the pose model's own error comes on top) | the compressed {r}x{r} light map (generated UVs) read bilinearly. Shading is shown as in the previews (irradiance under the preview lights, 1 = white); the errors below are in grey levels of a white surface (255/π per unit of irradiance, as the tables), one scale for both, red at {max} or more. Over the surface, area-weighted: the vertices {vg:.2} grey levels RMS ({vt:.2}% transfer error, largest {vm:.1}), the light map {mg:.2} ({mt:.2}%, largest {mm:.1}).*\n\n",
        title = of.title,
        clip = of.clip.0,
        frame = of.clip.1,
        points = PICTURE_POINTS,
        vg = v.grey_rms,
        vt = 100.0 * v.transfer_error,
        vm = v.grey_max,
        mg = m.grey_rms,
        mt = 100.0 * m.transfer_error,
        mm = m.grey_max,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The scale's end is the 99.9th percentile rounded up to 1, 2 or 5 × 10^k, at least 1.
    #[test]
    fn error_scales_round_up_to_plain_numbers() {
        let ramp = |top: f32| -> Vec<f32> { (0..=1000).map(|i| top * i as f32 / 1000.0).collect() };
        assert_eq!(error_scale(&ramp(30.0)), 50.0);
        assert_eq!(error_scale(&ramp(15.0)), 20.0);
        assert_eq!(error_scale(&ramp(0.1)), 1.0);
        assert_eq!(error_scale(&ramp(180.0)), 200.0);
        assert_eq!(error_scale(&[]), 1.0);
    }
}
