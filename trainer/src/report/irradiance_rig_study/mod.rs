//! `aprt irradiance-rig-study`: the irradiance-rig results study on the built-in creature (*Irradiance
//! Rigs*, Figures 1 and 5): each rig's error against exact evaluation for normalised sphere
//! lights near, mid and far, the paper's claim that a six-vector mixed rig is comparable to a
//! 64-vector lattice, renders, and how a fit over the bind and training poses holds on novel
//! poses. Writes `README.md`, `results.json` and PNGs.

mod document;
mod figures;
pub mod measure;
pub mod setup;

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use serde::Serialize;

use crate::io::atomic::write_atomic;
use crate::irradiance_rig::fit_rig;
use crate::progress::Reporter;
use crate::rig::creature::Creature;
use crate::rig::mesh::Mesh;
pub use measure::{Measured, StudySettings, measure, poses};
use setup::{DISTANCES, LATTICE_64, MIXED_6, normalised_light};

impl StudySettings {
    /// The full study at SH `order`.
    pub fn full(order: usize) -> StudySettings {
        StudySettings {
            order,
            rigs: setup::rigs(),
            directions: setup::directions(),
            sweep: setup::SWEEP.to_vec(),
            vertex_step: 1,
            novel: true,
            timed: true,
        }
    }
}

/// The mixed rig against the 64-vector lattice for one light placement (on `lash`).
#[derive(Clone, Debug, Serialize)]
pub struct ClaimEntry {
    /// `near`, `mid` or `far`.
    pub distance: &'static str,
    /// The direction's name.
    pub direction: String,
    /// The largest vertex error each rig adds to per-vertex SH, `[mixed, lattice]`.
    pub added_max: [f64; 2],
    /// `added_max[0] / added_max[1]`.
    pub ratio: f64,
    /// `ratio ≤` [`COMPARABLE`].
    pub holds: bool,
    /// The largest vertex error against exact, `[mixed, lattice]`.
    pub exact_max: [f64; 2],
    /// `exact_max[0] / exact_max[1]`.
    pub exact_ratio: f64,
}

/// The ratio within which the mixed rig counts as comparable to the lattice.
pub const COMPARABLE: f64 = 1.5;

/// Index of the sweep distance `d` in `m.sweep`.
fn sweep_index(m: &Measured, d: f64) -> Option<usize> {
    m.sweep.iter().position(|&x| (x - d).abs() < 1e-9)
}

/// The claim, placement by placement, when the rigs include the paper's two.
pub fn claim(m: &Measured) -> Vec<ClaimEntry> {
    let (Some(lattice), Some(mixed)) = (m.rigs.get(LATTICE_64), m.rigs.get(MIXED_6)) else {
        return Vec::new();
    };
    let ratio = |a: f64, b: f64| a / b.max(f64::MIN_POSITIVE);
    let mut out = Vec::new();
    for (name, d) in DISTANCES {
        let Some(i) = sweep_index(m, d) else { continue };
        let (a, b) = (&mixed.lash[i], &lattice.lash[i]);
        for (k, dir) in m.directions.iter().enumerate() {
            let added_max = [a.added.each[k].max, b.added.each[k].max];
            let exact_max = [a.exact.each[k].max, b.exact.each[k].max];
            let r = ratio(added_max[0], added_max[1]);
            out.push(ClaimEntry {
                distance: name,
                direction: dir.name.clone(),
                added_max,
                ratio: r,
                holds: r <= COMPARABLE,
                exact_max,
                exact_ratio: ratio(exact_max[0], exact_max[1]),
            });
        }
    }
    out
}

/// The study's settings as `results.json` records them.
#[derive(Serialize)]
struct Recorded<'a> {
    command: &'a str,
    light_radius_over_r: f64,
    nearest_irradiance: f64,
    distances: Vec<(&'static str, f64)>,
    lash_frame: usize,
    novel_frames: Vec<(&'static str, [usize; 3])>,
    heat_max_grey: f32,
}

/// `results.json`: the settings, everything measured and the claim.
pub fn to_json(m: &Measured, command: &str) -> Result<serde_json::Value> {
    let settings = Recorded {
        command,
        light_radius_over_r: setup::LIGHT_RADIUS,
        nearest_irradiance: setup::NEAREST_IRRADIANCE,
        distances: DISTANCES.to_vec(),
        lash_frame: setup::LASH_FRAME,
        novel_frames: setup::NOVEL_FRAMES.to_vec(),
        heat_max_grey: figures::HEAT_MAX,
    };
    Ok(serde_json::json!({
        "settings": serde_json::to_value(settings)?,
        "measured": serde_json::to_value(m)?,
        "claim": serde_json::to_value(claim(m))?,
    }))
}

/// Runs the whole study and writes `out/README.md`, `out/results.json` and the PNGs. Returns
/// the README's path.
pub fn run(out: &Path, order: usize, command: &str, reporter: &dyn Reporter) -> Result<PathBuf> {
    let start = std::time::Instant::now();
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let creature = Creature::builtin();
    reporter.note("posing the creature");
    let poses = poses(&creature).context("posing the creature")?;
    reporter.note("fitting and measuring the rigs");
    let settings = StudySettings::full(order);
    let m = measure(&poses, &settings);
    reporter.note("drawing");
    figures::distance_plots(out, &m)?;
    let fitting: Vec<&Mesh> = poses.fitting.iter().collect();
    let fits: Vec<_> = settings
        .rigs
        .iter()
        .map(|c| fit_rig(c.parsed(), &fitting, None))
        .collect();
    let d = DISTANCES[1].1;
    let light = normalised_light(m.centre, m.radius, d, [0.0, 1.0, 0.0]);
    let caption = format!(
        "lash frame {}, light {d} R beyond the tail",
        setup::LASH_FRAME
    );
    figures::contact_sheet(
        &out.join("renders.png"),
        &fits,
        &poses.lash,
        &[light],
        order,
        &caption,
    )?;
    let json = serde_json::to_string_pretty(&to_json(&m, command)?)?;
    write_atomic(&out.join("results.json"), json.as_bytes())
        .with_context(|| format!("writing {}", out.display()))?;
    let seconds = start.elapsed().as_secs_f64();
    let readme = document::markdown(&m, &claim(&m), command, seconds);
    let path = out.join("README.md");
    write_atomic(&path, readme.as_bytes())
        .with_context(|| format!("writing {}", path.display()))?;
    Ok(path)
}

#[cfg(test)]
mod tests;
