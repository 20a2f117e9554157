//! `aprt report`: what accuracy costs in time. Bakes a scene's clips once at the reference
//! settings (the scene's effects at SH order 6), then fits and measures a model for each
//! setting of the accuracy knobs (SH order, k_a, k_v, precision f32/f16/i8, rays, bounces) on the
//! scene's test clips, marks the Pareto-optimal settings, and recommends the cheapest of the
//! most accurate ones inside the budget ([`pareto::recommend`]). Each setting's µs a frame is
//! what `aprt train --scene` quotes for the model it writes
//! ([`crate::scene::frame_cost::us_per_frame`]): the model carries the rig the scene would
//! choose, and is timed under the scene's lighting with the lights that rig leaves to each
//! vertex. A scene whose `method` is `lightmap` or `auto` sweeps pose-driven light maps too
//! ([`lightmaps`]), and every setting is measured over the whole surface as well as at the
//! vertices ([`crate::surface`]); the front then ranks by the surface error, the only one in
//! which a light map's texels and a vertex's interpolation are judged alike.

pub mod choice;
pub mod document;
pub mod lightmaps;
pub mod measure;
pub mod pareto;

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use aprt_core::MAX_ORDER;

use crate::bake::BakeSettings;
use crate::bake::clip::{BakedClip, bake_clip, bake_rest, pose_all};
use crate::irradiance_rig::RigKind;
use crate::irradiance_rig::fit::{fit_irradiance_rig, rig_fitting_surfaces};
use crate::lighting::luminance;
use crate::model::ModelFrame;
use crate::model::export::{Precision, encode_model_with_rig};
use crate::model::fit::{CoefDims, Dims, FitOptions};
use crate::model::occluders::Occluders;
use crate::pipeline::train::{ClipSet, fit_clip};
use crate::progress::{Reporter, Silent};
use crate::report::experiment::baked_validation_poses;
use crate::rig::mesh::Mesh;
use crate::rig::pose_layout::PoseLayout;
use crate::rig::{Clip, Rig};
use crate::scene::file::{Choice, Method, Scene};
use crate::scene::irradiance_rig_choice::{CANDIDATES, RigDecision, choose_rig};
use crate::scene::lighting::SceneLighting;
use crate::scene::{BakePlan, plan_bake};
use crate::surface::{SurfacePoints, bake_surface};
use lightmaps::{LightMapSweep, light_map_candidates, sweep_light_maps};
use measure::{Measured, Truth, measure};
use pareto::{Cost, Presets, front, presets, recommend};

/// What `aprt report` is asked for.
#[derive(Clone, Debug)]
pub struct ReportSettings {
    /// Microseconds per frame the recommendation may cost (the scene's `[budget]` otherwise).
    pub budget_us: Option<f64>,
    /// Bytes the recommendation may take.
    pub budget_bytes: Option<u64>,
    /// Use every `stride`-th frame of every clip.
    pub stride: usize,
    /// Validation poses sampled from the (strided) training frames and baked with every bake
    /// of the sweep, as `aprt train --scene` samples them to choose its model by.
    pub validation_poses: usize,
    /// Points spread over the surface by area, where every test frame's surface error is
    /// measured.
    pub surface_points: usize,
}

/// The clips of a scene's character, loaded.
pub struct SceneClips<'a> {
    /// The character.
    pub rig: &'a dyn Rig,
    /// Training clips.
    pub train: &'a [Clip],
    /// Clips held out to choose the model by.
    pub validation: &'a [Clip],
    /// Clips the report measures on.
    pub tests: &'a [Clip],
}

/// One setting of the knobs.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Setting {
    /// A short name for tables and plots.
    pub label: String,
    /// `"vertex"` (per-vertex transfer) or `"lightmap"` (a pose-driven light map).
    pub method: &'static str,
    /// Texels a side of a light map; `None` for the vertex method.
    pub resolution: Option<usize>,
    /// SH order.
    pub order: usize,
    /// Pose dimensions k_a asked for (`auto`: chosen by held-out error).
    pub pose_dims: String,
    /// Vertex-basis vectors k_v asked for (`auto`: the default energy fraction).
    pub coef_dims: String,
    /// k_a and k_v of the fitted model.
    pub fitted: (usize, usize),
    /// Precision of the large sections.
    pub precision: &'static str,
    /// Rays per vertex of the training bake.
    pub rays: usize,
    /// Bounces of the training bake.
    pub bounces: usize,
    /// Occluder proxies asked for (`auto`: kept where they lower the held-out error), and
    /// whether the model has them.
    pub proxies: (&'static str, bool),
}

/// One measured setting.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Point {
    /// The setting.
    pub setting: Setting,
    /// RMS shading error on the test clips, 8-bit grey levels: over the surface when the
    /// scene weighs light maps (`SweepReport::error_at`), at the vertices otherwise.
    pub error: f64,
    /// µs per frame through aprt-core, one core, as `aprt train --scene` measures the model it
    /// writes: pose, the scene's lighting under its rig, every vertex shaded, the lights the
    /// rig leaves to each vertex.
    pub us_per_frame: f64,
    /// Bytes of the model.
    pub bytes: usize,
    /// On the front of error against µs per frame.
    pub pareto: bool,
    /// On the front of error against bytes.
    pub pareto_bytes: bool,
    /// Everything measured.
    pub measured: Measured,
    /// Bake seconds per training frame (all cores).
    pub bake_s_per_frame: f64,
    /// Fit seconds.
    pub fit_s: f64,
    /// The model, for `--write-model`.
    #[serde(skip)]
    pub blob: Vec<u8>,
}

impl Point {
    /// `setting`, measured as `measured` with model `blob`, its bake's seconds per training
    /// frame and its fit's seconds; off both fronts until they are marked, its error the
    /// vertices' until the sweep says otherwise.
    pub fn new(
        setting: Setting,
        (measured, blob): (Measured, Vec<u8>),
        (bake_s_per_frame, fit_s): (f64, f64),
    ) -> Point {
        Point {
            setting,
            error: measured.grey_rms,
            us_per_frame: measured.us_per_frame,
            bytes: blob.len(),
            pareto: false,
            pareto_bytes: false,
            measured,
            bake_s_per_frame,
            fit_s,
            blob,
        }
    }
}

/// Everything `aprt report` measured.
#[derive(Debug, serde::Serialize)]
pub struct SweepReport {
    /// The scene file.
    pub scene: PathBuf,
    /// The character, its vertex count.
    pub character: String,
    /// The reference the errors are measured against.
    pub reference: String,
    /// Frames: training, validation (the scene's clips, then the validation poses), and each
    /// test clip's.
    pub frames: Vec<(String, usize)>,
    /// Validation poses sampled from the training frames to choose each model by, as
    /// `aprt train --scene` samples them.
    pub validation_poses: usize,
    /// Seconds the reference bake of the validation poses took.
    pub validation_bake_s: f64,
    /// The order the scene's lighting needs, and why.
    pub scene_order: (usize, String),
    /// Surface points every test frame's surface error is measured at.
    pub surface_points: usize,
    /// Where `error` and the fronts measure: `"surface"` when the scene's method is
    /// `lightmap` or `auto`, `"vertices"` for a vertex scene.
    pub error_at: &'static str,
    /// The settings, in sweep order.
    pub points: Vec<Point>,
    /// Index into `points` of the recommended setting: the cheapest of those within the
    /// budget whose error ties the lowest ([`pareto::recommend`]).
    pub recommended: Option<usize>,
    /// The irradiance rig every setting carries and is timed with, as `train --scene`
    /// chooses it for this scene.
    pub irradiance_rig: RigDecision,
    /// The budget the recommendation was chosen within.
    pub budget: (Option<f64>, Option<u64>),
    /// The named presets, indices into `points`.
    pub presets: Option<Presets>,
    /// Knobs left out, and why.
    pub not_swept: Vec<String>,
    /// Wall-clock seconds of the sweep.
    pub seconds: f64,
}

/// A fit to run: its label, the data it learns from and its options.
pub struct Candidate {
    label: String,
    order: usize,
    pose_dims: Dims,
    coef_dims: CoefDims,
    data: Data,
    proxies: Occluders,
}

/// Which bake a candidate learns from.
#[derive(Clone, Copy, PartialEq)]
enum Data {
    /// The reference bake, truncated to the candidate's order.
    Reference,
    /// A bake of the training clips with fewer rays.
    Rays(usize),
    /// A bake of the training clips with fewer bounces.
    Bounces(usize),
}

/// The training, validation and rest clips of one bake.
pub struct Baked {
    /// The training clips, joined.
    pub train: BakedClip,
    /// The scene's validation clips, then the validation poses (when any).
    pub validation: Vec<BakedClip>,
    /// The rest pose.
    pub rest: BakedClip,
    /// Seconds per training frame.
    pub seconds: f64,
    /// Seconds the validation poses' bake took (0 without them).
    pub validation_bake_s: f64,
}

/// The reference bake every setting is measured against, and what the scene planned.
pub struct Reference {
    /// The pose layout of the training frames.
    pub layout: PoseLayout,
    /// Training, validation and rest clips at the reference settings.
    pub base: Baked,
    /// Test clips at the reference settings: the ground truth.
    pub tests: Vec<BakedClip>,
    /// The scene's bake plan (its order, effects and sentences).
    pub plan: BakePlan,
    /// The scene's lighting.
    pub lighting: SceneLighting,
    /// The reference settings: the scene's effects at SH order 6.
    pub settings: BakeSettings,
    /// Every `stride`-th frame of every clip was baked.
    pub stride: usize,
    /// Validation poses asked for in every bake ([`ReportSettings::validation_poses`]).
    pub validation_poses: usize,
    /// The irradiance rig `train --scene` would store for this scene, and why.
    pub irradiance_rig: (Option<RigKind>, RigDecision),
    /// The surfaces that rig is fitted over (the bind pose first).
    pub fitting: Vec<Mesh>,
    /// Points spread over the bind surface, where the surface error is measured.
    pub surface: SurfacePoints,
    /// Transfer at those points in every frame of every test clip, at the reference settings.
    pub surface_tests: Vec<Vec<Vec<f32>>>,
}

/// Refuses a `stride` (`--stride`) that keeps fewer than two frames of the training clips
/// `train`: no model can be fitted to them, and the fit's error blamed the character.
pub fn check_stride(train: &[Clip], stride: usize) -> Result<()> {
    let frames: usize = train.iter().map(|c| c.frames.len()).sum();
    let kept: usize = train.iter().map(|c| c.frames.len().div_ceil(stride)).sum();
    if stride > 1 && kept < 2 {
        bail!(
            "--stride {stride} keeps {kept} of the {frames} training frames; a model needs two at least: give a smaller stride"
        );
    }
    Ok(())
}

/// Bakes `clips` (every `stride`-th frame of `report`) and the validation poses at the
/// scene's effects and SH order 6, under `lighting` (the scene's, read by the caller, whose
/// errors name the scene file).
pub fn bake_reference(
    scene: &Scene,
    lighting: SceneLighting,
    clips: &SceneClips<'_>,
    report: &ReportSettings,
    reporter: &dyn Reporter,
) -> Result<Reference> {
    if clips.tests.is_empty() {
        bail!(
            "{}: [source] test names no clips: the report measures on clips never trained on",
            scene.path.display()
        );
    }
    let rig = clips.rig;
    let stride = report.stride.max(1);
    let (train, validation) = strided_clips(clips, stride);
    check_stride(clips.train, stride)?;
    let frames: Vec<Vec<f64>> = train.iter().flat_map(|c| c.frames.clone()).collect();
    let layout = PoseLayout::from_training(&rig.angle_names(), &frames)?;
    let plan = plan_bake(scene, &lighting, rig.bind_mesh(), frames.len())?;
    let settings = BakeSettings {
        order: MAX_ORDER,
        ..plan.bake
    };
    reporter.note(&format!(
        "baking the reference (SH order {MAX_ORDER}, {} rays) on 1 frame in {stride}",
        settings.rays
    ));
    let fitting = rig_fitting_surfaces(rig, clips.train)?;
    let progress = reporter.step_progress(CANDIDATES.len());
    let e = &scene.effects;
    let lights = &lighting.lights;
    let order = plan.order.order;
    let irradiance_rig = choose_rig(e.rig, lights, &fitting, order, e.error_target, &*progress)?;
    progress.finish();
    reporter.note(&format!("rig: {}", irradiance_rig.1.reason));
    let poses = report.validation_poses;
    let base = bake_set(
        rig,
        &layout,
        (&train, &validation, poses),
        &settings,
        reporter,
    )?;
    let tests = clips
        .tests
        .iter()
        .map(|c| strided(c, stride))
        .map(|c| Ok(bake_clip(rig, &layout, &c.name, c.frames, &settings, &Silent)?.0))
        .collect::<Result<Vec<_>>>()?;
    let (surface, surface_tests) = bake_surface_truth(clips, stride, &settings, report, reporter)?;
    Ok(Reference {
        layout,
        base,
        tests,
        plan,
        lighting,
        settings,
        stride,
        validation_poses: poses,
        irradiance_rig,
        fitting,
        surface,
        surface_tests,
    })
}

/// `report.surface_points` points spread over the character's bind surface, and their
/// transfer in every (`stride`-th) frame of every test clip with `settings`.
fn bake_surface_truth(
    clips: &SceneClips<'_>,
    stride: usize,
    settings: &BakeSettings,
    report: &ReportSettings,
    reporter: &dyn Reporter,
) -> Result<(SurfacePoints, Vec<Vec<Vec<f32>>>)> {
    let rig = clips.rig;
    let surface = SurfacePoints::spread(rig.bind_mesh(), report.surface_points)
        .with_context(|| format!("--surface-points {}", report.surface_points))?;
    reporter.note(&format!(
        "baking the surface truth: {} points spread by area on every test frame",
        surface.len()
    ));
    let truth = clips
        .tests
        .iter()
        .map(|c| {
            let clip = strided(c, stride);
            let meshes = pose_all(rig, &clip.name, &clip.frames)?;
            Ok(bake_surface(&surface, &meshes, settings)?)
        })
        .collect::<Result<Vec<_>>>()?;
    Ok((surface, truth))
}

/// Sweeps the knobs on `scene` and returns the measured points.
pub fn run(
    scene: &Scene,
    lighting: SceneLighting,
    clips: &SceneClips<'_>,
    settings: &ReportSettings,
    reporter: &dyn Reporter,
) -> Result<SweepReport> {
    let started = Instant::now();
    let reference = bake_reference(scene, lighting, clips, settings, reporter)?;
    // A light-map scene sweeps light maps alone (`sweep` adds them for any but a vertex scene).
    let list = match scene.effects.method {
        Choice::Fixed(Method::LightMap) => Vec::new(),
        _ => candidates(scene, reference.plan.order.order, Knobs::All),
    };
    let mut report = sweep(scene, clips, &reference, &list, settings, reporter)?;
    report.seconds = started.elapsed().as_secs_f64();
    Ok(report)
}

/// Fits and measures every candidate against `reference`.
pub fn sweep(
    scene: &Scene,
    clips: &SceneClips<'_>,
    reference: &Reference,
    candidates: &[Candidate],
    settings: &ReportSettings,
    reporter: &dyn Reporter,
) -> Result<SweepReport> {
    let started = Instant::now();
    let rig = clips.rig;
    let e = &scene.effects;
    let plan = &reference.plan;
    let bind = rig.bind_mesh();
    let lum: Vec<f32> = (reference.lighting.sh_at_centre(MAX_ORDER, bind)?)
        .into_iter()
        .map(luminance)
        .collect();
    let truth = Truth {
        tests: &reference.tests,
        lighting: &lum,
        scene: &reference.lighting,
        bind,
        target: e.error_target,
        surface: &reference.surface,
        surface_tests: &reference.surface_tests,
        surface_weights: reference.surface.points.iter().map(|p| p.weight).collect(),
    };
    let rig_sections = rig_sections(reference, candidates)?;
    let progress = reporter.step_progress(candidates.len() + 2);
    let mut points = Vec::new();
    let mut extra: Option<(Data, Baked)> = None;
    for candidate in candidates {
        progress.step(&format!("fitting {}", candidate.label));
        let data = match candidate.data {
            Data::Reference => truncated(&reference.base, candidate.order),
            other => {
                if extra.as_ref().is_none_or(|(d, _)| *d != other) {
                    let bake = match other {
                        Data::Rays(rays) => BakeSettings { rays, ..plan.bake },
                        Data::Bounces(bounces) => BakeSettings {
                            bounces,
                            ..plan.bake
                        },
                        Data::Reference => unreachable!("handled above"),
                    };
                    let (train, validation) = strided_clips(clips, reference.stride);
                    let (layout, poses) = (&reference.layout, reference.validation_poses);
                    let clips = (&train[..], &validation[..], poses);
                    extra = Some((other, bake_set(rig, layout, clips, &bake, &Silent)?));
                }
                let (_, baked) = extra.as_ref().expect("baked above");
                truncated(baked, candidate.order)
            }
        };
        let fit = Fit {
            rig,
            layout: &reference.layout,
            frame: e.frame,
            irradiance_rig: rig_sections[candidate.order].as_deref(),
        };
        points.extend(fit_and_measure(&fit, candidate, &data, scene, &truth)?);
    }
    progress.step("light maps");
    let mut not_swept = not_swept(scene);
    let error_at = with_light_maps(scene, (clips, reference), &truth, &mut points, reporter)?
        .map_or("vertices", |notes| {
            not_swept.extend(notes);
            "surface"
        });
    progress.step("the Pareto fronts");
    mark_fronts(&mut points);
    let budget_us = settings.budget_us.or(scene.budget.us_per_frame);
    let budget_bytes = settings.budget_bytes.or(scene.budget.bytes);
    let costs: Vec<Cost> = points.iter().map(cost).collect();
    let recommended = recommend(&costs, budget_us, budget_bytes.map(|b| b as f64));
    progress.finish();
    let base = &reference.base;
    let mut frames = vec![(base.train.name.clone(), base.train.angles.len())];
    frames.extend(
        base.validation
            .iter()
            .chain(&reference.tests)
            .map(|c| (c.name.clone(), c.angles.len())),
    );
    Ok(SweepReport {
        scene: scene.path.clone(),
        character: format!(
            "{} vertices, {} pose entries",
            bind.vertex_count(),
            reference.layout.names().len()
        ),
        reference: format!(
            "{}, SH order {MAX_ORDER}, {} rays per vertex, {} bounces, 1 frame in {}",
            if e.shadows { "shadowed" } else { "unshadowed" },
            reference.settings.rays,
            reference.settings.bounces,
            reference.stride
        ),
        frames,
        validation_poses: reference.validation_poses,
        validation_bake_s: base.validation_bake_s,
        scene_order: (plan.order.order, plan.order.reason.clone()),
        presets: presets(&costs),
        surface_points: reference.surface.len(),
        error_at,
        points,
        recommended,
        irradiance_rig: reference.irradiance_rig.1.clone(),
        budget: (budget_us, budget_bytes),
        not_swept,
        seconds: started.elapsed().as_secs_f64(),
    })
}

/// For a scene whose method is not `vertex`: adds the pose-driven light maps to `points`
/// (measured against `truth`) and ranks every point by its error over the surface, the only
/// one in which texels and interpolated vertices are judged alike; returns the resolutions
/// left out and why. `None` for a vertex scene, whose points keep their vertex error.
fn with_light_maps(
    scene: &Scene,
    (clips, reference): (&SceneClips<'_>, &Reference),
    truth: &Truth<'_>,
    points: &mut Vec<Point>,
    reporter: &dyn Reporter,
) -> Result<Option<Vec<String>>> {
    let e = &scene.effects;
    if e.method == Choice::Fixed(Method::Vertex) {
        return Ok(None);
    }
    let sweep = LightMapSweep {
        clips,
        stride: reference.stride,
        layout: &reference.layout,
        bake: reference.plan.bake,
        frame: e.frame,
    };
    let (maps, notes) = sweep_light_maps(&sweep, &light_map_candidates(scene), truth, reporter)?;
    points.extend(maps);
    for p in points.iter_mut() {
        p.error = p.measured.surface_grey_rms;
    }
    Ok(Some(notes))
}

/// The irradiance rig section the scene's model carries, at each order `candidates` fit (its
/// error table, which splits the lights between rig and vertex, is per order), indexed by
/// order; all `None` when the scene stores no rig.
fn rig_sections(reference: &Reference, candidates: &[Candidate]) -> Result<Vec<Option<Vec<u8>>>> {
    let mut sections = vec![None; MAX_ORDER + 1];
    if let Some(kind) = reference.irradiance_rig.0 {
        for order in candidates.iter().map(|c| c.order) {
            if sections[order].is_none() {
                sections[order] = Some(fit_irradiance_rig(kind, &reference.fitting, order)?);
            }
        }
    }
    Ok(sections)
}

/// Every `stride`-th frame of `clip`.
fn strided(clip: &Clip, stride: usize) -> Clip {
    Clip {
        name: clip.name.clone(),
        fps: clip.fps / stride as f64,
        frames: clip.frames.iter().step_by(stride).cloned().collect(),
    }
}

/// The training and validation clips, every `stride`-th frame.
fn strided_clips(clips: &SceneClips<'_>, stride: usize) -> (Vec<Clip>, Vec<Clip>) {
    let each = |list: &[Clip]| list.iter().map(|c| strided(c, stride)).collect();
    (each(clips.train), each(clips.validation))
}

/// Which knobs a sweep turns.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Knobs {
    /// Every knob: order, k_v, k_a, rays, bounces.
    All,
    /// SH order and k_v only (the demo's short sweep).
    OrderAndBasis,
}

/// The knobs' settings to fit: every order with the default shape, then at the scene's order
/// k_v and, for [`Knobs::All`], k_a, fewer rays and fewer bounces.
pub fn candidates(scene: &Scene, order: usize, knobs: Knobs) -> Vec<Candidate> {
    let at = |label: String, pose_dims, coef_dims, data| Candidate {
        label,
        order,
        pose_dims,
        coef_dims,
        data,
        proxies: Occluders::Auto,
    };
    let defaults = FitOptions::default();
    let mut list: Vec<Candidate> = (1..=MAX_ORDER)
        .map(|n| Candidate {
            label: format!("order {n}"),
            order: n,
            pose_dims: defaults.pose_dims,
            coef_dims: defaults.coef_dims,
            data: Data::Reference,
            proxies: Occluders::Auto,
        })
        .collect();
    // What the occluder proxies cost and buy: the model without them and with them always.
    for (proxies, name) in [(Occluders::None, "no proxies"), (Occluders::On, "proxies")] {
        list.push(Candidate {
            proxies,
            ..at(
                format!("order {order}, {name}"),
                defaults.pose_dims,
                defaults.coef_dims,
                Data::Reference,
            )
        });
    }
    for k in [4, 8, 16, 32] {
        list.push(at(
            format!("order {order}, k_v {k}"),
            defaults.pose_dims,
            CoefDims::Count(k),
            Data::Reference,
        ));
    }
    if knobs == Knobs::OrderAndBasis {
        return list;
    }
    for k in [1, 2] {
        list.push(at(
            format!("order {order}, k_a {k}"),
            Dims::Count(k),
            defaults.coef_dims,
            Data::Reference,
        ));
    }
    let e = &scene.effects;
    if e.shadows {
        for rays in [e.rays / 4].into_iter().filter(|&r| r >= 4) {
            list.push(at(
                format!("order {order}, {rays} rays"),
                defaults.pose_dims,
                defaults.coef_dims,
                Data::Rays(rays),
            ));
        }
    }
    for bounces in 0..e.bounces {
        list.push(at(
            format!("order {order}, {bounces} bounces"),
            defaults.pose_dims,
            defaults.coef_dims,
            Data::Bounces(bounces),
        ));
    }
    list
}

/// The knobs this sweep leaves alone for `scene`, and why.
fn not_swept(scene: &Scene) -> Vec<String> {
    let e = &scene.effects;
    let mut out = Vec::new();
    if !e.shadows {
        out.push("rays: the scene casts no shadows, so its transfer is exact without any".into());
    }
    if e.bounces == 0 {
        out.push("bounces: the scene asks for none, so there is nothing cheaper to try".into());
    }
    out.push(
        "irradiance-rig kinds: every setting carries the rig `aprt train --scene` chooses for the scene and is timed with it; the kinds are compared for the scene's lights by `aprt irradiance-rig` and `aprt train --scene` (irradiance_rig = \"auto\"), not in this sweep"
            .into(),
    );
    if e.method == Choice::Fixed(Method::Vertex) {
        out.push(
            "light maps: the scene's method is vertex (method = \"auto\" sweeps pose-driven light maps beside the vertex settings); stored light-map sequences, which hold only the clips they were baked from, are measured by `aprt lightmap study` (docs/results/lightmaps)".into(),
        );
    } else {
        out.push(
            "light maps with an irradiance rig or near lights per texel: each light map is composed under the scene's lighting at the character's centre; stored light-map sequences, which hold only the clips they were baked from, are measured by `aprt lightmap study`".into(),
        );
    }
    out
}

/// Bakes the training clips (joined), each validation clip, `poses` validation poses sampled
/// from the training frames (as `aprt train` samples them) and the rest pose with `settings`.
fn bake_set(
    rig: &dyn Rig,
    layout: &PoseLayout,
    (train, validation, poses): (&[Clip], &[Clip], usize),
    settings: &BakeSettings,
    reporter: &dyn Reporter,
) -> Result<Baked> {
    let mut seconds = 0.0;
    let mut frames = 0usize;
    let mut parts = Vec::new();
    for clip in train {
        let (baked, per_frame) = bake_clip(
            rig,
            layout,
            &clip.name,
            clip.frames.clone(),
            settings,
            &Silent,
        )?;
        seconds += per_frame * clip.frames.len() as f64;
        frames += clip.frames.len();
        parts.push(baked);
    }
    let train = BakedClip::concat(parts);
    let mut validation = validation
        .iter()
        .map(|c| Ok(bake_clip(rig, layout, &c.name, c.frames.clone(), settings, &Silent)?.0))
        .collect::<Result<Vec<_>>>()?;
    let sampled = baked_validation_poses(rig, layout, &train, poses, settings, reporter)?;
    let validation_bake_s = sampled.as_ref().map_or(0.0, |(_, s)| *s);
    validation.extend(sampled.map(|(clip, _)| clip));
    Ok(Baked {
        train,
        validation,
        rest: bake_rest(rig, layout, settings, &Silent)?,
        seconds: seconds / frames.max(1) as f64,
        validation_bake_s,
    })
}

/// `baked` with every clip's transfer cut to `order`.
pub fn truncated(baked: &Baked, order: usize) -> Baked {
    Baked {
        train: baked.train.truncated(order),
        validation: baked
            .validation
            .iter()
            .map(|c| c.truncated(order))
            .collect(),
        rest: baked.rest.truncated(order),
        seconds: baked.seconds,
        validation_bake_s: baked.validation_bake_s,
    }
}

/// What every candidate of a sweep is fitted for and written with.
struct Fit<'a> {
    /// The character.
    rig: &'a dyn Rig,
    /// Its pose layout.
    layout: &'a PoseLayout,
    /// The frame the model learns transfer in.
    frame: ModelFrame,
    /// The irradiance rig section the scene's model carries, at the candidate's order.
    irradiance_rig: Option<&'a [u8]>,
}

/// Fits `candidate` on `data` and measures it at every precision, written with the scene's
/// irradiance rig as `train --scene` writes it.
fn fit_and_measure(
    fit: &Fit<'_>,
    candidate: &Candidate,
    data: &Baked,
    scene: &Scene,
    truth: &Truth<'_>,
) -> Result<Vec<Point>> {
    let (rig, layout, frame) = (fit.rig, fit.layout, fit.frame);
    let options = FitOptions {
        pose_dims: candidate.pose_dims,
        coef_dims: candidate.coef_dims,
        proxies: candidate.proxies,
        ..FitOptions::default()
    };
    let set = ClipSet {
        train: &data.train,
        rest: Some(&data.rest),
        validation: &data.validation,
    };
    let started = Instant::now();
    let fitted = fit_clip(rig, layout, set, candidate.order, &options, frame)
        .with_context(|| format!("fitting {}", candidate.label))?;
    let fit_s = started.elapsed().as_secs_f64();
    let model = &fitted.model;
    let mut points = Vec::new();
    for precision in [Precision::F32, Precision::F16, Precision::I8] {
        let blob = encode_model_with_rig(model, precision, fit.irradiance_rig)
            .with_context(|| format!("writing {} in {}", candidate.label, precision.name()))?;
        let measured = measure(&blob, truth)
            .with_context(|| format!("measuring {}, {}", candidate.label, precision.name()))?;
        let info = *aprt_core::Model::parse(&blob)?.info();
        points.push(Point::new(
            Setting {
                label: format!("{}, {}", candidate.label, precision.name()),
                method: "vertex",
                resolution: None,
                order: candidate.order,
                pose_dims: match candidate.pose_dims {
                    Dims::Count(k) => k.to_string(),
                    Dims::Variance(f) => format!("{f} of the variance"),
                    Dims::All => "all".into(),
                    Dims::Auto => "auto".into(),
                },
                coef_dims: match candidate.coef_dims.at_order(candidate.order) {
                    CoefDims::Count(k) => k.to_string(),
                    CoefDims::Variance(f) => format!("{f} of the energy"),
                    CoefDims::Full => "full".into(),
                    CoefDims::FieldsPlus(extra) => format!("n² + {extra}"),
                },
                fitted: (info.pose_dims(), info.coef_dims()),
                precision: precision.name(),
                rays: match candidate.data {
                    Data::Rays(r) => r,
                    _ => scene.effects.rays,
                },
                bounces: match candidate.data {
                    Data::Bounces(b) => b,
                    _ => scene.effects.bounces,
                },
                proxies: (candidate.proxies.name(), info.has_proxies()),
            },
            (measured, blob),
            (data.seconds, fit_s),
        ));
    }
    Ok(points)
}

fn cost(p: &Point) -> Cost {
    Cost {
        error: p.error,
        us: p.us_per_frame,
        bytes: p.bytes as f64,
    }
}

/// Marks each point's membership of the two fronts.
fn mark_fronts(points: &mut [Point]) {
    let costs: Vec<Cost> = points.iter().map(cost).collect();
    let by_time = front(&costs, |c| c.us);
    let by_bytes = front(&costs, |c| c.bytes);
    for ((p, t), b) in points.iter_mut().zip(by_time).zip(by_bytes) {
        p.pareto = t;
        p.pareto_bytes = b;
    }
}
