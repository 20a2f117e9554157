//! `aprt demo`: the whole pipeline on the built-in character, with the paper's tables
//! (Tables 1 and 2) against three baselines, and pictures of a novel pose.

use std::fmt::Write as _;

use anyhow::{Context, Result};
use glam::Vec3;

use std::path::{Path, PathBuf};

use crate::bake::BakeSettings;
use crate::bake::clip::BakedClip;
use crate::io::atomic::write_atomic;
use crate::irradiance_rig::fit::FIT_POSES;
use crate::irradiance_rig::{RigKind, fit_rig};
use crate::model::LinearModel;
use crate::model::export::{Precision, encode_model_with_rig};
use crate::model::predict::predict_world;
use crate::progress::Reporter;
use crate::report::evaluate::{hard_vertex_errors, mean_transfer, nearest_pose};
use crate::report::experiment::{self, Row, standard_configs, table_markdown};
use crate::report::figures::{
    ErrorPanel, picture_lighting, save_model_frame, save_panels, shade_with,
};
use crate::report::irradiance_rig_frame::{RigFrame, demo_lights, save_rig_frame};
use crate::report::sweep::{self, SceneClips};
use crate::rig::character::Character;
use crate::rig::mesh::Mesh;
use crate::rig::{Clip, Rig};
use crate::scene::file::{Scene, parse_scene};
use crate::scene::lighting::SceneLighting;

/// The rig the demo's model carries: the paper's mixed rig turned to a standing figure, three
/// lattice nodes up its height, a gradient front to back, constant across.
const DEMO_RIG: &str = "mixed:x=constant,y=gradient,z=lattice3";

/// Everything the demo measured.
#[derive(Debug, serde::Serialize)]
pub struct Report {
    /// The character.
    pub character: String,
    /// SH order.
    pub order: usize,
    /// Rays per vertex of the ground truth.
    pub rays: usize,
    /// Training clip name.
    pub train_clip: String,
    /// Training frames.
    pub train_frames: usize,
    /// The clip held out of training to choose the model by, and its frame count.
    pub validation_clip: (String, usize),
    /// Validation poses sampled from the training frames (as `aprt train --validation-poses`
    /// samples them) and used with the validation clip to choose each model by.
    pub validation_poses: usize,
    /// Seconds their bake took (all cores).
    pub validation_bake_s: f64,
    /// Novel clips and their frame counts.
    pub test_clips: Vec<(String, usize)>,
    /// Bake seconds per training frame (all cores).
    pub bake_s_per_frame: f64,
    /// Bytes of one frame of f32 PRT.
    pub frame_prt_bytes: usize,
    /// The table.
    pub rows: Vec<Row>,
    /// The irradiance rig stored in the model.
    pub irradiance_rig: String,
    /// The rig-lit frame of the novel pose.
    pub rig_frame: RigFrame,
    /// What the built-in scene called for, one sentence each.
    pub computed: Vec<String>,
    /// What it did not, one sentence each.
    pub skipped: Vec<String>,
    /// The short sweep's recommendation within the scene's budget (sweep/report.md).
    pub recommended: Option<String>,
    /// Per test clip, on the [`HARD_FRACTION`] of vertices the skinned bind transfer gets most
    /// wrong: the default's relative error there, and the baseline's.
    pub hard_vertices: Vec<HardVertices>,
}

/// The share of vertices [`Report::hard_vertices`] measures: the shadows a pose casts fall on
/// few vertices, and the error over all of them dilutes what a model gets right there.
pub const HARD_FRACTION: f64 = 0.05;

/// One test clip's errors on the vertices the skinned bind transfer gets most wrong.
#[derive(Debug, serde::Serialize)]
pub struct HardVertices {
    /// The clip.
    pub clip: String,
    /// The default model's relative error on those vertices.
    pub default: f64,
    /// The skinned bind transfer's.
    pub baseline: f64,
}

/// [`HardVertices`] of the default model `blob` on each test clip.
fn hard_vertices(
    blob: &[u8],
    tests: &[BakedClip],
    skinned: &[Vec<Vec<f32>>],
    coeffs: usize,
) -> Result<Vec<HardVertices>> {
    tests
        .iter()
        .zip(skinned)
        .map(|(clip, baseline)| {
            let pred = predict_world(blob, &clip.angles, &clip.rotations, Some(clip.geometry()))?;
            let (default, baseline) =
                hard_vertex_errors(&pred, baseline, &clip.transfer, coeffs, HARD_FRACTION);
            Ok(HardVertices {
                clip: clip.name.clone(),
                default,
                baseline,
            })
        })
        .collect()
}

/// What the demo is asked for.
#[derive(Clone, Debug, PartialEq)]
pub struct DemoSettings {
    /// Directory for model.aprt, report.md, report.json and the PNG renders.
    pub out: PathBuf,
    /// SH order of the model (default: the order the built-in scene's lighting needs).
    pub order: Option<usize>,
    /// Directions per vertex for the ground-truth bakes (default: the scene's).
    pub rays: Option<usize>,
    /// Use every `stride`-th frame of the clips (1 = all).
    pub stride: usize,
    /// Validation poses sampled from the training frames as `aprt train --validation-poses`
    /// samples them, baked, and used with the validation clip to choose each model by.
    pub validation_poses: usize,
}

/// The built-in scene the demo runs (fixtures/scenes/builtin.toml, compiled in).
pub const BUILTIN_SCENE: &str = include_str!("../../../fixtures/scenes/builtin.toml");

/// The built-in scene, parsed.
pub fn builtin_scene() -> Result<Scene> {
    Ok(parse_scene(
        BUILTIN_SCENE,
        Path::new("fixtures/scenes/builtin.toml"),
    )?)
}

/// Runs the demo, writes its files into `args.out` and returns the report as markdown (the
/// command line prints it). Progress goes to `reporter`.
pub fn run(args: &DemoSettings, reporter: &dyn Reporter) -> Result<String> {
    let out = &args.out;
    std::fs::create_dir_all(out).with_context(|| format!("cannot create {}", out.display()))?;
    let mut scene = builtin_scene()?;
    if let Some(rays) = args.rays {
        scene.effects.rays = rays;
    }
    let character = Character::builtin();
    let bind = character.bind_mesh();
    let named = |names: &[String]| -> Result<Vec<Clip>> {
        names.iter().map(|n| Ok(character.clip(n)?)).collect()
    };
    let (train_clips, validation_clips, test_clips) = (
        named(&scene.train)?,
        named(&scene.validate)?,
        named(&scene.test)?,
    );
    let clips = SceneClips {
        rig: &character,
        train: &train_clips,
        validation: &validation_clips,
        tests: &test_clips,
    };
    let lighting = SceneLighting::of(&scene, character.up())?;
    let sweep_settings = sweep::ReportSettings {
        budget_us: None,
        budget_bytes: None,
        stride: args.stride,
        validation_poses: args.validation_poses,
        surface_points: crate::surface::DEFAULT_SURFACE_POINTS as usize,
    };
    let reference = sweep::bake_reference(&scene, lighting, &clips, &sweep_settings, reporter)?;
    let plan = &reference.plan;
    for line in plan.computed.iter().chain(&plan.skipped) {
        reporter.note(line);
    }
    let order = args.order.unwrap_or(plan.order.order);
    reporter.note(&format!(
        "aprt demo: built-in character, {} vertices, {} triangles, {} joint angles; order {order}, {} rays",
        bind.vertex_count(),
        bind.triangles.len(),
        character.pose_len(),
        scene.effects.rays
    ));
    let settings = BakeSettings { order, ..plan.bake };
    let layout = &reference.layout;
    let baked = sweep::truncated(&reference.base, order);
    let (train, bake_s) = (&baked.train, baked.seconds);
    // The validation clip, then the validation poses, as `aprt train` orders them.
    let (validation, choose_by) = (&baked.validation[0], &baked.validation);
    let tests: Vec<BakedClip> = reference.tests.iter().map(|t| t.truncated(order)).collect();
    let lighting = picture_lighting(order, Vec3::new(0.5, -0.8, 0.9));
    let validation_poses = choose_by[1..].iter().map(|c| c.angles.len()).sum();
    let result = experiment::run(
        &character,
        layout,
        train,
        choose_by,
        &tests,
        &standard_configs(),
        &settings,
        &lighting,
        reporter,
    )?;
    let default = result.model(experiment::DEFAULT_CONFIG)?;
    let (kind, blob) = with_demo_rig(&default.fit.model, bind, train, order)?;
    write_atomic(&out.join("model.aprt"), &blob)
        .with_context(|| format!("cannot write {}", out.join("model.aprt").display()))?;

    let hard = hard_vertices(&default.blob, &tests, &result.skinned_tests, order * order)?;
    let test = &tests[0];
    let frame = test.angles.len() / 2;
    save_pictures(out, &blob, train, test, frame, &lighting)?;
    let lights = demo_lights(&test.meshes[frame]);
    let rig_frame = save_rig_frame(&out.join("rig_frame.png"), &blob, test, frame, &lights)?;
    let recommended = cost_sweep(
        &scene,
        &clips,
        &reference,
        &sweep_settings,
        order,
        out,
        reporter,
    )?;

    let report = Report {
        character: format!(
            "built-in, {} vertices, {} joint angles",
            bind.vertex_count(),
            character.pose_len()
        ),
        order,
        rays: scene.effects.rays,
        computed: plan.computed.clone(),
        skipped: plan.skipped.clone(),
        recommended,
        train_clip: train.name.clone(),
        train_frames: train.angles.len(),
        validation_clip: (validation.name.clone(), validation.angles.len()),
        validation_poses,
        validation_bake_s: baked.validation_bake_s,
        test_clips: tests
            .iter()
            .map(|t| (t.name.clone(), t.angles.len()))
            .collect(),
        bake_s_per_frame: bake_s,
        frame_prt_bytes: result.frame_bytes,
        rows: result.rows,
        irradiance_rig: kind.to_string(),
        rig_frame,
        hard_vertices: hard,
    };
    write_atomic(
        &out.join("report.json"),
        serde_json::to_string_pretty(&report)?.as_bytes(),
    )?;
    let markdown = report.markdown(test, frame);
    write_atomic(&out.join("report.md"), markdown.as_bytes())?;
    Ok(markdown)
}

/// `model` in f32 with the demo's irradiance rig ([`DEMO_RIG`]) fitted over the bind pose
/// and the training poses, and that rig's kind.
fn with_demo_rig(
    model: &LinearModel,
    bind: &Mesh,
    train: &BakedClip,
    order: usize,
) -> Result<(RigKind, Vec<u8>)> {
    let kind: RigKind = DEMO_RIG.parse()?;
    let stride = train.meshes.len().div_ceil(FIT_POSES).max(1);
    let meshes: Vec<&Mesh> = std::iter::once(bind)
        .chain(train.meshes.iter().step_by(stride))
        .collect();
    let mut rig = fit_rig(kind, &meshes, None);
    rig.tabulate(bind, order)
        .context("tabulating the irradiance rig's error")?;
    let blob = encode_model_with_rig(model, Precision::F32, Some(&rig.bytes()))?;
    Ok((kind, blob))
}

/// The demo's short sweep (every order, then k_v at the model's order, f32, f16 and i8) on the
/// reference bake, written to `out/sweep/`; returns the recommendation within the scene's
/// budget.
fn cost_sweep(
    scene: &Scene,
    clips: &SceneClips<'_>,
    reference: &sweep::Reference,
    settings: &sweep::ReportSettings,
    order: usize,
    out: &Path,
    reporter: &dyn Reporter,
) -> Result<Option<String>> {
    let list = sweep::candidates(scene, order, sweep::Knobs::OrderAndBasis);
    let report = sweep::sweep(scene, clips, reference, &list, settings, reporter)?;
    sweep::document::write(&report, &out.join("sweep"), "aprt demo")?;
    Ok(report.recommended.map(|i| {
        let p = &report.points[i];
        format!(
            "{}: {:.2} grey levels RMS, {:.1} µs per frame, {} bytes",
            p.setting.label, p.error, p.us_per_frame, p.bytes
        )
    }))
}

/// Pictures of frame `frame` of `test` in `out`: ground truth | `blob`'s prediction | 4× error
/// (`novel_pose.png`), and ground truth | mean training transfer | nearest training pose
/// (`baselines.png`).
fn save_pictures(
    out: &Path,
    blob: &[u8],
    train: &BakedClip,
    test: &BakedClip,
    frame: usize,
    lighting: &[f32],
) -> Result<()> {
    let truth = save_model_frame(
        &out.join("novel_pose.png"),
        blob,
        test,
        frame,
        lighting,
        Vec3::Z,
    )?;
    let mesh = &test.meshes[frame];
    let mean = shade_with(&mean_transfer(&train.transfer), lighting);
    let nearest = shade_with(
        &train.transfer[nearest_pose(&train.angles, &test.angles[frame])],
        lighting,
    );
    save_panels(
        &out.join("baselines.png"),
        mesh,
        &[&truth, &mean, &nearest],
        &[
            "ground truth (ray-traced)",
            "mean training transfer",
            "nearest training pose",
        ],
        ErrorPanel::Omitted,
    )
}

impl Report {
    fn markdown(&self, test: &BakedClip, frame: usize) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "# aprt demo report\n");
        let _ = writeln!(
            s,
            "Character: {}. SH order {} ({} coefficients), {} rays per vertex. Trained on `{}` ({} frames); α, k_a and the prior of every model chosen on `{}` ({} frames, held out of training{}; it takes the place of the LOSO and LOO selections the rows name); tested on {}.\n",
            self.character,
            self.order,
            self.order * self.order,
            self.rays,
            self.train_clip,
            self.train_frames,
            self.validation_clip.0,
            self.validation_clip.1,
            match self.validation_poses {
                0 => String::new(),
                n => format!(
                    ") and {n} validation poses (sampled from the training frames, baked in {:.1} s",
                    self.validation_bake_s
                ),
            },
            self.test_clips
                .iter()
                .map(|(n, f)| format!("`{n}` ({f} frames)"))
                .collect::<Vec<_>>()
                .join(", ")
        );
        let _ = writeln!(
            s,
            "Bake: {:.2} s per frame on all cores. One frame of f32 PRT is {} bytes.\n",
            self.bake_s_per_frame, self.frame_prt_bytes
        );
        let _ = writeln!(
            s,
            "## What the scene called for\n\nThe built-in scene (fixtures/scenes/builtin.toml) computed:\n"
        );
        for line in &self.computed {
            let _ = writeln!(s, "- {line}");
        }
        let _ = writeln!(s, "\nand skipped:\n");
        for line in &self.skipped {
            let _ = writeln!(s, "- {line}");
        }
        let _ = writeln!(
            s,
            "\n## What accuracy costs\n\nEvery SH order, then k_v at order {}, each in f32, f16 and i8, measured on the test clips against the order-6 ground truth ([the sweep's report](sweep/report.md); `aprt report` sweeps every knob). Recommended within the scene's budget: {}.\n\n![shading error against µs per frame, the Pareto front joined](sweep/pareto_us.png)\n",
            self.order,
            self.recommended.as_deref().unwrap_or("nothing fits")
        );
        let _ = writeln!(s, "{}\n", experiment::TABLE_LEGEND);
        let names: Vec<String> = self.test_clips.iter().map(|(n, _)| n.clone()).collect();
        s.push_str(&table_markdown(&self.rows, &names));
        let _ = writeln!(
            s,
            "\nOn the {:.0} % of vertices the skinned bind transfer gets most wrong (per clip), the default's error against the baseline's: {}.\n",
            100.0 * HARD_FRACTION,
            self.hard_vertices
                .iter()
                .map(|h| format!(
                    "`{}` {:.2} % against {:.2} % ({:.2}×)",
                    h.clip,
                    100.0 * h.default,
                    100.0 * h.baseline,
                    h.default / h.baseline
                ))
                .collect::<Vec<_>>()
                .join(", ")
        );
        if let Some(selection) = experiment::selection_markdown(&self.rows, "##") {
            let _ = writeln!(s, "{selection}");
        }
        let _ = writeln!(
            s,
            "\n## A novel pose\n\nFrame {frame} of `{}` under a directional light and a dim sky: ground truth | default model (through aprt-core) | 4× absolute error.\n",
            test.name
        );
        let _ = writeln!(s, "![ground truth, model, 4x error](novel_pose.png)\n");
        let _ = writeln!(
            s,
            "The same pose: ground truth | mean training transfer | nearest training pose.\n"
        );
        let _ = writeln!(
            s,
            "![ground truth, mean baseline, nearest-pose baseline](baselines.png)"
        );
        let _ = writeln!(
            s,
            "\n## Lit by an irradiance rig, with a near light\n\nThe same pose under three lights, through aprt-core: the model's `{}` irradiance rig carries the lights it can within one grey level, the rest are evaluated per vertex through each vertex's transfer, so both are self-shadowed. Ray-traced transfer lit per vertex by every light | the model with its rig | 4× error (luminance).\n",
            self.irradiance_rig
        );
        for (kind, d, share) in &self.rig_frame.lights {
            let path = match *share {
                s if s >= 1.0 => "in the rig".to_owned(),
                s if s <= 0.0 => "per vertex".to_owned(),
                s => format!("{:.0} % in the rig", 100.0 * s),
            };
            let _ = writeln!(
                s,
                "- {kind} light at {d:.2} m from the rig's centre: {path}"
            );
        }
        let e = self.rig_frame.error_grey;
        let _ = writeln!(
            s,
            "\nError against the ray-traced frame: mean {:.2}, max {:.1} grey levels (model, rig and SH together).\n\n![ray-traced, model with rig, 4x error](rig_frame.png)",
            e.mean, e.max
        );
        s
    }
}
