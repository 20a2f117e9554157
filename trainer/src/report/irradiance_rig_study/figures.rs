//! The study's pictures: error against normalised distance per rig (the paper's Figure 5),
//! and a contact sheet of the `lash` frame under each rig beside the exact lighting, with the
//! error as a heat map.

use std::path::Path;

use anyhow::{Result, anyhow};
use aprt_core::{IrradianceRig, Light, MAX_COEFFS, Placement, irradiance_sh};
use image::RgbImage;
use plotters::prelude::*;

use super::measure::{Agg, Measured};
use crate::irradiance_rig::{FittedRig, rig_vectors};
use crate::lighting::GREY_PER_IRRADIANCE;
use crate::report::plots::{Axes, Series, line_plot, register_font};
use crate::report::render::{
    BACKGROUND, Colormap, GUTTER, View, render_scalar, save_png_atomic, side_by_side,
};
use crate::rig::mesh::Mesh;

/// Grey levels drawn fully red in the renders' heat maps.
pub const HEAT_MAX: f32 = 8.0;
/// The renders' view: the creature's left side (+x), head to the left, slightly from above.
const SIDE: View = View {
    yaw: std::f32::consts::FRAC_PI_2,
    pitch: 0.12,
};
const PANEL: (u32, u32) = (360, 128);
const LABEL: u32 = 20;

/// One plot of error against distance on `lash`.
struct Plot {
    file: &'static str,
    title: &'static str,
    /// Against exact (with the SH floor's curve), or against per-vertex SH.
    exact: bool,
    /// The worst over directions of the largest vertex error, or the mean of the means.
    worst: bool,
}

const PLOTS: [Plot; 2] = [
    Plot {
        file: "added_vs_distance_max.png",
        title: "rig vs per-vertex SH: worst vertex, worst direction",
        exact: false,
        worst: true,
    },
    Plot {
        file: "exact_vs_distance_max.png",
        title: "rig vs exact: worst vertex, worst direction",
        exact: true,
        worst: true,
    },
];

/// Writes the plots of error against distance on `lash` (the paper's Figure 5).
pub fn distance_plots(out: &Path, m: &Measured) -> Result<()> {
    for plot in &PLOTS {
        let value = |a: &Agg| if plot.worst { a.max } else { a.mean };
        let curve = |name: String, aggs: Vec<&Agg>| Series {
            name,
            points: m
                .sweep
                .iter()
                .zip(aggs)
                .map(|(&d, a)| (d, value(a)))
                .collect(),
            markers: true,
            line: true,
        };
        let mut series: Vec<Series> = m
            .rigs
            .iter()
            .map(|r| {
                let aggs = r
                    .lash
                    .iter()
                    .map(|c| if plot.exact { &c.exact } else { &c.added });
                curve(
                    format!("{} ({})", r.choice.kind, r.sh_vectors),
                    aggs.collect(),
                )
            })
            .collect();
        if plot.exact {
            series.push(curve(
                "per vertex (SH floor)".into(),
                m.floor_lash.iter().collect(),
            ));
        }
        let (lo, hi) = (m.sweep[0], m.sweep[m.sweep.len() - 1]);
        series.push(Series {
            name: "1 grey level".into(),
            points: vec![(lo, 1.0), (hi, 1.0)],
            markers: false,
            line: true,
        });
        let axes = Axes {
            title: plot.title,
            x: "light distance from the rig centre / R",
            y: "8-bit grey levels",
            log_x: true,
            log_y: true,
        };
        line_plot(&out.join(plot.file), &axes, &series)?;
    }
    Ok(())
}

/// Per-vertex reflected radiance (E / π, white = 1) from `lights` exactly, and through the
/// rig with every light in it; channel 0 (the lights are white).
fn shadings(fitted: &FittedRig, mesh: &Mesh, lights: &[Light], order: usize) -> [Vec<f32>; 3] {
    let bytes = fitted.bytes();
    let rig = IrradianceRig::parse(&bytes).expect("a fitted rig's bytes are valid");
    let vectors = rig_vectors(&rig, lights, order, &Placement::IDENTITY)
        .expect("the study's lights are valid");
    let pi = std::f32::consts::PI;
    let (mut exact, mut through_rig, mut per_vertex) = (Vec::new(), Vec::new(), Vec::new());
    let mut here = [[0.0f32; 3]; MAX_COEFFS];
    for (p, n) in mesh.positions.iter().zip(&mesh.normals) {
        let here = &mut here[..order * order];
        let e: f32 = lights
            .iter()
            .filter_map(|l| l.irradiance(*p, *n).ok())
            .map(|e| e[0])
            .sum();
        exact.push(e / pi);
        rig.lighting_at(&vectors, &Placement::IDENTITY, *p, here);
        through_rig.push(irradiance_sh(order, here, *n).map_or(0.0, |e| e[0]) / pi);
        here.fill([0.0; 3]);
        for l in lights {
            let _ = l.add_radiance_sh(order, *p, here);
        }
        per_vertex.push(irradiance_sh(order, here, *n).map_or(0.0, |e| e[0]) / pi);
    }
    [exact, through_rig, per_vertex]
}

/// Draws `text` in white at (x, y) of `image`.
fn label(image: &mut RgbImage, x: i32, y: i32, text: &str) -> Result<()> {
    register_font();
    let (w, h) = image.dimensions();
    let buffer: &mut [u8] = image;
    let root = BitMapBackend::with_buffer(buffer, (w, h)).into_drawing_area();
    let style = ("sans-serif", 14).into_font().color(&WHITE);
    root.draw(&Text::new(text.to_owned(), (x, y), style))
        .map_err(|e| anyhow!("drawing a label: {e}"))?;
    root.present().map_err(|e| anyhow!("drawing a label: {e}"))
}

/// The sRGB encoding of a linear value in 0..1, so dim shading stays readable.
fn srgb(x: f32) -> f32 {
    let x = x.clamp(0.0, 1.0);
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// One row of the sheet: a caption strip above the shading and error panels.
fn row(caption: &str, shading: &[f32], error: &[f32], mesh: &Mesh) -> Result<RgbImage> {
    let (w, h) = PANEL;
    let display: Vec<f32> = shading.iter().map(|&x| srgb(x)).collect();
    let panels = side_by_side(&[
        render_scalar(mesh, &display, SIDE, w, h, Colormap::Grey)?,
        render_scalar(mesh, error, SIDE, w, h, Colormap::Error { max: HEAT_MAX })?,
    ]);
    let mut out = RgbImage::from_pixel(panels.width(), h + LABEL, BACKGROUND);
    image::imageops::replace(&mut out, &panels, 0, i64::from(LABEL));
    label(&mut out, 6, 3, caption)?;
    Ok(out)
}

/// The heat map's key: the colour ramp from 0 to [`HEAT_MAX`] grey levels.
fn key(width: u32) -> Result<RgbImage> {
    let mut out = RgbImage::from_pixel(width, 2 * LABEL, BACKGROUND);
    let (x0, bar) = (width / 2 + GUTTER, width / 2 - 2 * GUTTER - 90);
    for x in 0..bar {
        let c = Colormap::Error { max: 1.0 }.color(x as f32 / (bar - 1) as f32);
        for y in 4..16 {
            out.put_pixel(x0 + x, y, c);
        }
    }
    label(
        &mut out,
        6,
        3,
        "left: reflected radiance (white = 1, sRGB-encoded)",
    )?;
    let ends = format!("0 … ≥ {HEAT_MAX} grey levels |rig − exact|");
    label(&mut out, x0 as i32, 19, &ends)?;
    Ok(out)
}

/// Stacks `rows` top to bottom with a gutter.
fn stack(rows: &[RgbImage]) -> RgbImage {
    let width = rows.iter().map(|r| r.width()).max().unwrap_or(0);
    let height = rows.iter().map(|r| r.height() + GUTTER).sum::<u32>();
    let mut out = RgbImage::from_pixel(width, height, BACKGROUND);
    let mut y = 0;
    for r in rows {
        image::imageops::replace(&mut out, r, 0, i64::from(y));
        y += r.height() + GUTTER;
    }
    out
}

/// The contact sheet: exact lighting with the per-vertex SH floor's error, then each rig's
/// lighting (every light in the rig) with its error against exact, on `mesh` under `lights`.
pub fn contact_sheet(
    path: &Path,
    fits: &[FittedRig],
    mesh: &Mesh,
    lights: &[Light],
    order: usize,
    caption: &str,
) -> Result<()> {
    // Radiance 1 is white: 255 grey levels (GREY_PER_IRRADIANCE · π).
    let grey = |a: &[f32], b: &[f32]| -> Vec<f32> {
        let g = (GREY_PER_IRRADIANCE * std::f64::consts::PI) as f32;
        a.iter().zip(b).map(|(x, y)| g * (x - y).abs()).collect()
    };
    let [exact, _, per_vertex] = shadings(&fits[0], mesh, lights, order);
    let mut rows = vec![row(
        &format!("exact ({caption}) | error of per-vertex SH (floor)"),
        &exact,
        &grey(&per_vertex, &exact),
        mesh,
    )?];
    for fitted in fits {
        let [_, through_rig, _] = shadings(fitted, mesh, lights, order);
        let caption = format!(
            "{} ({} SH vectors) | its error",
            fitted.kind,
            fitted.kind.shape.vectors()
        );
        rows.push(row(
            &caption,
            &through_rig,
            &grey(&through_rig, &exact),
            mesh,
        )?);
    }
    let width = rows[0].width();
    rows.push(key(width)?);
    save_png_atomic(path, &stack(&rows))?;
    Ok(())
}
