//! Pictures shared by the demo and the results document: SH lighting for renders, shading
//! from transfer, and ground truth | prediction | 4× error panels, each titled, with the error
//! map's colour bar under them.

use std::path::Path;

use anyhow::{Result, anyhow};
use glam::{Quat, Vec3};
use image::RgbImage;
use plotters::prelude::*;

use crate::bake::clip::BakedClip;
use crate::report::plots::register_font;
use crate::report::render::{
    BACKGROUND, Colormap, GUTTER, View, render_scalar, save_png_atomic, side_by_side,
};
use crate::rig::mesh::Mesh;

/// Height in pixels of the title strip above the panels of [`captioned`].
pub const TITLE_HEIGHT: u32 = 24;
/// Height in pixels of the colour bar's strip under them.
const KEY_HEIGHT: u32 = 40;

/// What the colours of an error panel stand for: a colour bar of `Colormap::Error` with its
/// two ends labelled, and a label to its left.
#[derive(Clone, Copy, Debug)]
pub struct ErrorKey<'a> {
    /// Left of the bar: what is shown.
    pub label: &'a str,
    /// Under the bar's blue end.
    pub low: &'a str,
    /// Under its red end.
    pub high: &'a str,
}

/// The key of the 4× error panels: `Colormap::Error { max: 1 }` over 4 |a − b| of shadings
/// drawn with 1 as white, so red is a difference of a quarter of the grey panels' white.
pub const FOUR_X_ERROR: ErrorKey<'static> = ErrorKey {
    label: "|difference|, white = 1:",
    low: "0",
    high: "≥ 0.25 (a quarter of white)",
};

/// `panels` side by side (as [`side_by_side`]) under a strip with `titles[i]` centred over
/// panel `i`, and with `key`, a strip under them holding the colour bar of the error map, under
/// the last panel. Titles beyond the panels are ignored; missing ones leave the strip empty.
pub fn captioned(
    panels: &[RgbImage],
    titles: &[&str],
    key: Option<ErrorKey<'_>>,
) -> Result<RgbImage> {
    let row = side_by_side(panels);
    let key_height = if key.is_some() { KEY_HEIGHT } else { 0 };
    let (w, h) = (row.width(), TITLE_HEIGHT + row.height() + key_height);
    let mut out = RgbImage::from_pixel(w, h, BACKGROUND);
    image::imageops::replace(&mut out, &row, 0, i64::from(TITLE_HEIGHT));
    // Each panel's left edge, and the bar's span under the last one.
    let mut lefts = Vec::with_capacity(panels.len());
    let mut x = 0;
    for p in panels {
        lefts.push(x);
        x += p.width() + GUTTER;
    }
    let bar = match (key, panels.last(), lefts.last()) {
        (Some(_), Some(last), Some(&left)) if last.width() > 24 => {
            let (x0, len) = (left + 12, last.width() - 24);
            let y0 = TITLE_HEIGHT + row.height() + 4;
            for i in 0..len {
                let c = Colormap::Error { max: 1.0 }.color(i as f32 / (len - 1).max(1) as f32);
                for y in y0..y0 + 12 {
                    out.put_pixel(x0 + i, y, c);
                }
            }
            Some((x0, len, y0))
        }
        _ => None,
    };
    register_font();
    {
        let buffer: &mut [u8] = &mut out;
        let root = BitMapBackend::with_buffer(buffer, (w, h)).into_drawing_area();
        let fail = |e: DrawingAreaErrorKind<_>| anyhow!("drawing a picture's captions: {e}");
        let title_style = ("sans-serif", 16).into_font().color(&WHITE);
        let key_style = ("sans-serif", 13).into_font().color(&WHITE);
        let width_of = |text: &str, style: &TextStyle<'_>| {
            root.estimate_text_size(text, style)
                .map(|(tw, _)| tw as i32)
        };
        for ((panel, &left), title) in panels.iter().zip(&lefts).zip(titles) {
            let tw = width_of(title, &title_style).map_err(fail)?;
            let x = left as i32 + ((panel.width() as i32 - tw) / 2).max(4);
            root.draw(&Text::new(title.to_string(), (x, 4), title_style.clone()))
                .map_err(fail)?;
        }
        if let (Some(key), Some((x0, len, y0))) = (key, bar) {
            let (x0, len, y0) = (x0 as i32, len as i32, y0 as i32);
            let lw = width_of(key.label, &key_style).map_err(fail)?;
            root.draw(&Text::new(
                key.label.to_owned(),
                ((x0 - lw - 10).max(4), y0),
                key_style.clone(),
            ))
            .map_err(fail)?;
            root.draw(&Text::new(
                key.low.to_owned(),
                (x0, y0 + 16),
                key_style.clone(),
            ))
            .map_err(fail)?;
            let hw = width_of(key.high, &key_style).map_err(fail)?;
            root.draw(&Text::new(
                key.high.to_owned(),
                ((x0 + len - hw).max(x0 + 16), y0 + 16),
                key_style.clone(),
            ))
            .map_err(fail)?;
        }
        root.present().map_err(fail)?;
    }
    Ok(out)
}

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
    /// A last panel, titled "4× error", shows 4× the absolute difference of the first two
    /// (blue 0, red ≥ 0.25), with its colour bar under the panels.
    Shown,
    /// Only the shadings.
    Omitted,
}

/// Writes `mesh` shaded by each of `shadings` side by side, in grey, each under its title in
/// `titles`, and the error panel if `panel` asks for it.
pub fn save_panels(
    path: &Path,
    mesh: &Mesh,
    shadings: &[&[f32]],
    titles: &[&str],
    panel: ErrorPanel,
) -> Result<()> {
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
    let mut titles = titles.to_vec();
    titles.truncate(shadings.len());
    let key = (panels.len() > shadings.len()).then(|| {
        titles.resize(shadings.len(), "");
        titles.push("4× error");
        FOUR_X_ERROR
    });
    save_png_atomic(path, &captioned(&panels, &titles, key)?)?;
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
    save_panels(
        path,
        &mesh,
        &[&truth, &model],
        &["ground truth (ray-traced)", "model (through aprt-core)"],
        ErrorPanel::Shown,
    )?;
    Ok(truth)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn captioned_panels_get_a_title_strip_and_a_key_under_them() {
        let panel = RgbImage::from_pixel(100, 50, image::Rgb([200, 200, 200]));
        let titled = captioned(&[panel.clone(), panel.clone()], &["a", "b"], None).unwrap();
        assert_eq!(titled.dimensions(), (204, TITLE_HEIGHT + 50));
        let keyed = captioned(&[panel.clone(), panel], &["a", "b"], Some(FOUR_X_ERROR)).unwrap();
        assert_eq!(keyed.dimensions(), (204, TITLE_HEIGHT + 50 + KEY_HEIGHT));
        // The bar's ends under the last panel: blue at its left, red at its right.
        let y = TITLE_HEIGHT + 50 + 8;
        assert_eq!(
            *keyed.get_pixel(104 + 12, y),
            Colormap::Error { max: 1.0 }.color(0.0)
        );
        assert_eq!(
            *keyed.get_pixel(204 - 13, y),
            Colormap::Error { max: 1.0 }.color(1.0)
        );
        // The titles are drawn: the strip is no longer all background.
        let strip = (0..204).flat_map(|x| (0..TITLE_HEIGHT).map(move |y| (x, y)));
        assert!(
            strip
                .clone()
                .any(|(x, y)| *titled.get_pixel(x, y) != BACKGROUND)
        );
    }
}
