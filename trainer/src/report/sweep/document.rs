//! The report's files: report.json, report.md and the Pareto plots (PNG and SVG) of error
//! against µs per frame and against bytes.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::{Context, Result};

use super::pareto::{TIE_FRACTION, TIE_GREY};
use super::{Point, SweepReport};
use crate::io::atomic::write_atomic;
use crate::report::plots::{Axes, Series, line_plot, line_plot_svg};

/// The plots' file stems in the output directory.
pub const TIME_PLOT: &str = "pareto_us";
/// The error-against-bytes plot.
pub const BYTES_PLOT: &str = "pareto_bytes";

/// The files [`write()`] writes into its directory, which `aprt report` checks against its
/// inputs before any work.
pub const FILES: &[&str] = &[
    "report.json",
    "report.md",
    "pareto_us.png",
    "pareto_us.svg",
    "pareto_bytes.png",
    "pareto_bytes.svg",
];

/// Writes report.json, report.md and the plots into `out`; `command` is how to rerun it.
pub fn write(report: &SweepReport, out: &Path, command: &str) -> Result<()> {
    std::fs::create_dir_all(out).with_context(|| format!("cannot create {}", out.display()))?;
    let json = serde_json::to_string_pretty(report)? + "\n";
    write_atomic(&out.join("report.json"), json.as_bytes())
        .with_context(|| format!("cannot write {}", out.join("report.json").display()))?;
    plot(
        report,
        out,
        TIME_PLOT,
        "µs per frame (aprt-core, one core)",
        |p| (p.us_per_frame, p.pareto),
    )?;
    plot(report, out, BYTES_PLOT, "model bytes", |p| {
        (p.bytes as f64, p.pareto_bytes)
    })?;
    write_atomic(&out.join("report.md"), markdown(report, command).as_bytes())
        .with_context(|| format!("cannot write {}", out.join("report.md").display()))
}

/// One Pareto plot: every setting, the front joined, the recommendation ringed.
fn plot(
    report: &SweepReport,
    out: &Path,
    stem: &str,
    x: &str,
    axis: impl Fn(&Point) -> (f64, bool),
) -> Result<()> {
    let of = |method: &str| -> Vec<(f64, f64)> {
        report
            .points
            .iter()
            .filter(|p| p.setting.method == method)
            .map(|p| (axis(p).0, p.error))
            .collect()
    };
    let mut front: Vec<(f64, f64)> = report
        .points
        .iter()
        .filter(|p| axis(p).1)
        .map(|p| (axis(p).0, p.error))
        .collect();
    front.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut series: Vec<Series> = [
        ("vertex", "per-vertex setting"),
        ("lightmap", "light-map setting"),
    ]
    .into_iter()
    .map(|(method, name)| Series {
        name: name.into(),
        points: of(method),
        markers: true,
        line: false,
    })
    .filter(|s| !s.points.is_empty())
    .collect();
    series.extend([Series {
        name: "Pareto front".into(),
        points: front,
        markers: true,
        line: true,
    }]);
    if let Some(i) = report.recommended {
        let p = &report.points[i];
        series.push(Series {
            name: format!("recommended: {}", p.setting.label),
            points: vec![(axis(p).0, p.error)],
            markers: true,
            line: false,
        });
    }
    // A log axis draws its ticks at powers of ten: use it only when the costs span a decade.
    let (lo, hi) = report
        .points
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), p| {
            let x = axis(p).0;
            (lo.min(x), hi.max(x))
        });
    let axes = Axes {
        title: "shading error against cost, on the test clips",
        x,
        y: match report.error_at {
            "surface" => "RMS shading error over the surface (8-bit grey levels)",
            _ => "RMS shading error at the vertices (8-bit grey levels)",
        },
        log_x: hi > 10.0 * lo,
        log_y: false,
    };
    line_plot(&out.join(format!("{stem}.png")), &axes, &series)?;
    line_plot_svg(&out.join(format!("{stem}.svg")), &axes, &series)
}

/// The report as markdown.
pub fn markdown(report: &SweepReport, command: &str) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# What accuracy costs: {}\n", report.scene.display());
    let _ = writeln!(
        s,
        "Regenerate with `{command}` ({:.0} s). Character: {}. Ground truth: {}. Frames: {}.\n",
        report.seconds,
        report.character,
        report.reference,
        report
            .frames
            .iter()
            .map(|(n, f)| format!("`{n}` {f}"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    if report.validation_poses > 0 {
        let _ = writeln!(
            s,
            "Every setting's model is chosen as `aprt train --scene` chooses it, by its error on the validation clips and on {} validation poses sampled from the training frames (baked in {:.1} s).\n",
            report.validation_poses, report.validation_bake_s
        );
    }
    let _ = writeln!(
        s,
        "The scene's lighting needs SH order {}: {}.\n",
        report.scene_order.0, report.scene_order.1
    );
    let _ = writeln!(
        s,
        "**Error** is the RMS shading error on the test clips in 8-bit grey levels (a white Lambertian surface under the scene's lighting projected at the character's centre, radiance 1 = white), against the ground truth at order 6; the transfer error is the paper's relative error ‖pred − truth‖/‖truth‖ over every coefficient of the truth. **µs** is one frame through aprt-core on one core, median over a tenth of a second, as `aprt train --scene` measures the model it writes: the pose, the scene's lighting through the irradiance rig every setting carries ({}) or projected at the centre without one, every vertex shaded, the lights the rig leaves to each vertex, and the occluder proxies of a model that has them. **Transfer µs** is the full per-vertex transfer instead. A light-map setting's µs is the pose, every texel's transfer and the RGB map composed through aprt-core's `LightMap` under the lighting at the centre (the renderer's filtered fetch is not counted); it carries no irradiance rig.\n",
        report.irradiance_rig.kind.as_deref().unwrap_or("none")
    );
    s.push_str(&surface_paragraph(report));
    s.push('\n');
    let _ = writeln!(s, "Irradiance rig: {}.\n", report.irradiance_rig.reason);
    let _ = writeln!(s, "![error against µs per frame]({}.png)\n", TIME_PLOT);
    let _ = writeln!(s, "![error against bytes]({}.png)\n", BYTES_PLOT);
    let budget = match report.budget {
        (None, None) => "no budget".to_owned(),
        (us, bytes) => [
            us.map(|u| format!("{u} µs per frame")),
            bytes.map(|b| format!("{b} bytes")),
        ]
        .into_iter()
        .flatten()
        .collect::<Vec<_>>()
        .join(" and "),
    };
    match report.recommended {
        Some(i) => {
            let p = &report.points[i];
            let _ = writeln!(
                s,
                "**Recommended** within {budget}: **{}**, {:.2} grey levels RMS, {:.1} µs per frame, {} bytes. Settings within the budget whose error is within max({TIE_GREY} grey levels, {:.0} % of the lowest) of the lowest there tie, and the cheapest of them in µs is recommended.\n",
                p.setting.label,
                p.error,
                p.us_per_frame,
                p.bytes,
                100.0 * TIE_FRACTION
            );
        }
        None => {
            let _ = writeln!(s, "**No setting fits** within {budget}.\n");
        }
    }
    if let Some(presets) = report.presets {
        let _ = writeln!(
            s,
            "| preset | setting | grey RMS ({}) | µs/frame | bytes |\n|---|---|---:|---:|---:|",
            report.error_at
        );
        for (name, i) in [
            ("fastest", presets.fastest),
            ("balanced", presets.balanced),
            ("best", presets.best),
        ] {
            let p = &report.points[i];
            let _ = writeln!(
                s,
                "| `{name}` | {} | {:.2} | {:.1} | {} |",
                p.setting.label, p.error, p.us_per_frame, p.bytes
            );
        }
        s.push('\n');
    }
    let _ = writeln!(
        s,
        "## Every setting\n\n★: on the error-against-time front; ◆: on the error-against-bytes front.\n\n| setting | k_a, k_v | grey RMS | surface grey RMS | grey max | transfer error | surface transfer error | µs/frame | transfer µs | Mops | bytes | bake s/frame | fit s |\n|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
    );
    for p in &report.points {
        let m = &p.measured;
        let _ = writeln!(
            s,
            "| {}{}{} | {}, {} | {:.2} | {:.2} | {:.1} | {:.4} | {:.4} | {:.1} | {:.1} | {:.2} | {} | {:.2} | {:.1} |",
            p.setting.label,
            if p.pareto { " ★" } else { "" },
            if p.pareto_bytes { " ◆" } else { "" },
            p.setting.fitted.0,
            p.setting.fitted.1,
            m.grey_rms,
            m.surface_grey_rms,
            m.grey_max,
            m.transfer_error,
            m.surface_transfer_error,
            p.us_per_frame,
            m.transfer_us,
            m.megaops,
            p.bytes,
            p.bake_s_per_frame,
            p.fit_s
        );
    }
    if !report.not_swept.is_empty() {
        let _ = writeln!(s, "\nNot swept:\n");
        for line in &report.not_swept {
            let _ = writeln!(s, "- {line}");
        }
    }
    s
}

/// What the surface figures are and which error the fronts rank by.
fn surface_paragraph(report: &SweepReport) -> String {
    format!(
        "**Surface** figures are measured at {} points spread over the surface by area (each weighted by the area it stands for) on every test frame, against their own ray-cast transfer at the reference settings: per-vertex transfer interpolated across each triangle as a renderer interpolates it, a light map filtered bilinearly at each point's light-map UV. What a vertex cannot hold (a shadow inside a large triangle) counts there and not at the vertices. The fronts and the recommendation rank by the error {}.\n",
        report.surface_points,
        match report.error_at {
            "surface" =>
                "over the surface: the scene weighs light maps, and only there are texels and vertices judged alike",
            _ => "at the vertices (a vertex scene; the surface error is beside it)",
        }
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The list the output guard checks names the plots [`write`] writes.
    #[test]
    fn the_listed_files_name_the_plots() {
        for stem in [TIME_PLOT, BYTES_PLOT] {
            for ext in ["png", "svg"] {
                assert!(
                    FILES.contains(&format!("{stem}.{ext}").as_str()),
                    "{stem}.{ext}"
                );
            }
        }
    }
}
