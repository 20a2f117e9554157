//! The study's measurements: every rig fitted over the creature's bind and training poses (and
//! over its bind pose alone), each normalised light evaluated with every light in the rig
//! against the exact irradiance, aggregated over directions, and the core's cost per frame.

use aprt_core::{IrradianceRig, Light};
use rayon::prelude::*;
use serde::Serialize;

use super::setup::{DISTANCES, Direction, LASH_FRAME, NOVEL_FRAMES, RigChoice, normalised_light};
use crate::irradiance_rig::fit::fitting_meshes;
use crate::irradiance_rig::{FittedRig, GreyError, RigSettings, evaluate_rig, fit_rig, rig_errors};
use crate::model::runtime::rig_frame_cost;
use crate::rig::creature::Creature;
use crate::rig::mesh::Mesh;
use crate::rig::{Rig, RigError};

/// What to run: the full study, or a reduced one for tests.
#[derive(Clone, Debug)]
pub struct StudySettings {
    /// SH order of the lighting.
    pub order: usize,
    /// The rigs.
    pub rigs: Vec<RigChoice>,
    /// The light directions.
    pub directions: Vec<Direction>,
    /// Distances of the sweep, in radii; must include the table's [`DISTANCES`].
    pub sweep: Vec<f64>,
    /// Evaluate every k-th vertex (1 = all).
    pub vertex_step: usize,
    /// Measure the novel-pose table (rigs fitted over the bind pose alone).
    pub novel: bool,
    /// Time each rig on the core's per-frame path.
    pub timed: bool,
}

/// One light placement's errors over directions (and frames), by two measures.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Cell {
    /// Every light in the rig against the exact irradiance (`error_grey_all_rig`).
    pub exact: Agg,
    /// Every light in the rig against every light per vertex through SH: what the rig adds.
    pub added: Agg,
}

/// Errors over a set of light directions (and frames).
#[derive(Clone, Debug, Default, Serialize)]
pub struct Agg {
    /// Mean over directions of the mean over vertices and channels, grey levels.
    pub mean: f64,
    /// Worst over directions of the largest over vertices and channels, grey levels.
    pub max: f64,
    /// Each direction's (or direction × frame's) mean and largest, in order.
    pub each: Vec<GreyError>,
}

impl Agg {
    fn of(each: Vec<GreyError>) -> Agg {
        let n = each.len().max(1) as f64;
        Agg {
            mean: each.iter().map(|e| e.mean).sum::<f64>() / n,
            max: each.iter().map(|e| e.max).fold(0.0, f64::max),
            each,
        }
    }
}

/// One rig's results.
#[derive(Clone, Debug, Serialize)]
pub struct RigResult {
    /// The rig.
    pub choice: RigChoice,
    /// SH vectors per frame.
    pub sh_vectors: usize,
    /// Surface samples the lights are projected at per frame.
    pub samples: usize,
    /// aprt-core µs per frame (rig vectors + shading every vertex) for one light in the rig,
    /// median; `null` when not timed.
    pub us_per_frame: Option<f64>,
    /// `FittedRig::table` on the bind mesh: (distance / R, worst grey levels per unit
    /// strength against per-vertex SH).
    pub table: Vec<[f64; 2]>,
    /// On the `lash` frame, one cell per sweep distance.
    pub lash: Vec<Cell>,
    /// On the bind pose, one cell per table distance.
    pub bind: Vec<Cell>,
    /// Fitted over the bind pose alone, then over bind + training: mid distance, every
    /// direction and novel frame, on `lash` then `prowl`.
    pub novel: Option<NovelRow>,
}

/// The novel-pose row of one rig.
#[derive(Clone, Debug, Serialize)]
pub struct NovelRow {
    /// `[lash, prowl]`, fitted over the bind pose alone.
    pub bind_only: [Cell; 2],
    /// `[lash, prowl]`, fitted over the bind and training poses.
    pub bind_training: [Cell; 2],
}

/// Everything the study measured.
#[derive(Clone, Debug, Serialize)]
pub struct Measured {
    /// SH order.
    pub order: usize,
    /// The rigs' centre (box of the bind and training poses), root frame.
    pub centre: [f64; 3],
    /// The rigs' radius R, metres.
    pub radius: f64,
    /// Vertices of the creature.
    pub vertices: usize,
    /// Training poses the rigs are fitted over, beside the bind pose.
    pub training_poses: usize,
    /// Every k-th vertex evaluated.
    pub vertex_step: usize,
    /// The light directions.
    pub directions: Vec<Direction>,
    /// The sweep's distances, radii.
    pub sweep: Vec<f64>,
    /// Per rig.
    pub rigs: Vec<RigResult>,
    /// Every light per vertex through SH against exact (the floor), on `lash`, per sweep
    /// distance.
    pub floor_lash: Vec<Agg>,
    /// The same on the bind pose, per table distance.
    pub floor_bind: Vec<Agg>,
}

/// The poses of the study, root frame.
pub struct Poses {
    /// The bind and training meshes the rigs are fitted over.
    pub fitting: Vec<Mesh>,
    /// `lash` at [`LASH_FRAME`].
    pub lash: Mesh,
    /// The novel-pose table's frames: `[lash frames, prowl frames]`.
    pub novel: [Vec<Mesh>; 2],
}

/// Poses the creature for the study.
pub fn poses(creature: &Creature) -> Result<Poses, RigError> {
    let fitting = fitting_meshes(creature, &creature.training_clip())?;
    let clip = |name: &str, frames: &[usize]| -> Result<Vec<Mesh>, RigError> {
        let clip = creature.clip(name)?;
        frames
            .iter()
            .map(|&f| creature.pose(&clip.frames[f]))
            .collect()
    };
    let lash = clip("lash", &[LASH_FRAME])?.remove(0);
    let novel = [
        clip(NOVEL_FRAMES[0].0, &NOVEL_FRAMES[0].1)?,
        clip(NOVEL_FRAMES[1].0, &NOVEL_FRAMES[1].1)?,
    ];
    Ok(Poses {
        fitting,
        lash,
        novel,
    })
}

/// The rig's errors (every light in the rig) and the per-vertex floor, for a light at `d`
/// radii in each direction, over `meshes`.
fn cells(
    fitted: &FittedRig,
    frame: (&[f64; 3], f64),
    meshes: &[&Mesh],
    d: f64,
    settings: &StudySettings,
) -> (Cell, Agg) {
    let bytes = fitted.bytes();
    let rig = IrradianceRig::parse(&bytes).expect("a fitted rig's bytes are valid");
    let (mut errors, mut added, mut floors) = (Vec::new(), Vec::new(), Vec::new());
    for dir in &settings.directions {
        let light = normalised_light(*frame.0, frame.1, d, dir.vector);
        for mesh in meshes {
            let which = (0..mesh.vertex_count()).step_by(settings.vertex_step.max(1));
            let e = rig_errors(&rig, mesh, which, &[light], &[1.0], settings.order)
                .expect("the study's lights are valid");
            errors.push(e.all_rig);
            added.push(e.rig_vs_per_vertex);
            floors.push(e.per_vertex);
        }
    }
    let cell = Cell {
        exact: Agg::of(errors),
        added: Agg::of(added),
    };
    (cell, Agg::of(floors))
}

/// Fits every rig over `meshes` (tabulated on the first when `table`).
fn fit_all(settings: &StudySettings, meshes: &[&Mesh], order: Option<usize>) -> Vec<FittedRig> {
    settings
        .rigs
        .iter()
        .map(|choice| {
            let mut fitted = fit_rig(choice.parsed(), meshes, None);
            if let Some(order) = order {
                fitted
                    .tabulate(meshes[0], order)
                    .expect("the core reads the study's rigs");
            }
            fitted
        })
        .collect()
}

/// Runs the study's measurements on `poses`.
pub fn measure(poses: &Poses, settings: &StudySettings) -> Measured {
    let fitting: Vec<&Mesh> = poses.fitting.iter().collect();
    let fits = fit_all(settings, &fitting, Some(settings.order));
    let (centre, radius) = (fits[0].centre, fits[0].radius);
    let frame = (&centre, radius);
    let bind = &poses.fitting[0];
    // Every (rig, distance) on lash over the sweep, then on the bind pose at the table's.
    let jobs: Vec<(usize, f64, bool)> = (0..fits.len())
        .flat_map(|r| {
            let sweep = settings.sweep.iter().map(move |&d| (r, d, true));
            sweep.chain(DISTANCES.iter().map(move |&(_, d)| (r, d, false)))
        })
        .collect();
    let done: Vec<(Cell, Agg)> = jobs
        .par_iter()
        .map(|&(r, d, lash)| {
            let mesh = if lash { &poses.lash } else { bind };
            cells(&fits[r], frame, &[mesh], d, settings)
        })
        .collect();
    let per_rig = settings.sweep.len() + DISTANCES.len();
    let novel = settings.novel.then(|| novel_rows(poses, settings, &fits));
    let mut rigs = Vec::new();
    for (r, fitted) in fits.iter().enumerate() {
        let mine = &done[r * per_rig..(r + 1) * per_rig];
        let (lash, bind): (Vec<_>, Vec<_>) = mine
            .iter()
            .map(|c| c.0.clone())
            .enumerate()
            .partition(|(i, _)| *i < settings.sweep.len());
        rigs.push(RigResult {
            choice: settings.rigs[r].clone(),
            sh_vectors: fitted.kind.shape.vectors(),
            samples: fitted.samples.len(),
            us_per_frame: settings.timed.then(|| timed(fitted, poses, settings)),
            table: fitted.table.clone(),
            lash: lash.into_iter().map(|c| c.1).collect(),
            bind: bind.into_iter().map(|c| c.1).collect(),
            novel: novel.as_ref().map(|rows| rows[r].clone()),
        });
    }
    let floor = |range: std::ops::Range<usize>| done[range].iter().map(|c| c.1.clone()).collect();
    Measured {
        order: settings.order,
        training_poses: poses.fitting.len() - 1,
        centre,
        radius,
        vertices: bind.vertex_count(),
        vertex_step: settings.vertex_step,
        directions: settings.directions.clone(),
        sweep: settings.sweep.clone(),
        rigs,
        floor_lash: floor(0..settings.sweep.len()),
        floor_bind: floor(settings.sweep.len()..per_rig),
    }
}

/// The core's µs per frame for `fitted` with the mid light beyond the tail in the rig, on the
/// `lash` frame (serial, after the parallel work).
fn timed(fitted: &FittedRig, poses: &Poses, settings: &StudySettings) -> f64 {
    let light: Light = normalised_light(
        fitted.centre,
        fitted.radius,
        DISTANCES[1].1,
        [0.0, 1.0, 0.0],
    );
    let rig_settings = RigSettings {
        order: settings.order,
        ..RigSettings::default()
    };
    let lights = [light];
    let shares = evaluate_rig(fitted, &poses.lash, &lights, &rig_settings)
        .expect("the study's lights are valid")
        .shares();
    let cost = rig_frame_cost(fitted, &poses.lash, &lights, &shares, settings.order)
        .expect("the core times the study's rigs");
    // The rig's own cost, whatever share of the light the target leaves per vertex.
    cost.rig_vectors + cost.shade
}

/// The novel-pose rows: each rig fitted over the bind pose alone and over bind + training, at
/// the mid distance (lights placed by the bind + training fit), on the novel frames.
fn novel_rows(poses: &Poses, settings: &StudySettings, fits: &[FittedRig]) -> Vec<NovelRow> {
    let bind_only = fit_all(settings, &[&poses.fitting[0]], None);
    let frame = (&fits[0].centre, fits[0].radius);
    let d = DISTANCES[1].1;
    let jobs: Vec<(usize, bool, usize)> = (0..fits.len())
        .flat_map(|r| {
            [false, true]
                .into_iter()
                .flat_map(move |t| [(r, t, 0), (r, t, 1)])
        })
        .collect();
    let done: Vec<Cell> = jobs
        .par_iter()
        .map(|&(r, training, clip)| {
            let fitted = if training { &fits[r] } else { &bind_only[r] };
            let meshes: Vec<&Mesh> = poses.novel[clip].iter().collect();
            cells(fitted, frame, &meshes, d, settings).0
        })
        .collect();
    done.chunks_exact(4)
        .map(|c| NovelRow {
            bind_only: [c[0].clone(), c[1].clone()],
            bind_training: [c[2].clone(), c[3].clone()],
        })
        .collect()
}
