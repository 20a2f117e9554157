//! The `aprt` command line: argument types (in `args` and `source`) and dispatch. Each
//! command turns its flags into library settings, calls the library stage that does the work,
//! and prints what it wrote; the library reports progress through [`Terminal`].

mod args;
mod irradiance_rig;
mod lightmap;
mod simulate;
mod source;
mod stdout;
mod terminal;

use std::path::Path;

use anyhow::{Context, Result, bail};
use clap::{Parser, Subcommand};

pub use args::{
    BakeArgs, DemoArgs, DeringArg, EnvArgs, EvalArgs, ExportWebArgs, FitArgs, InspectArgs,
    IrradianceArgs, LightArgs, LightCommand, PrecisionArg, ReportArgs, ResultsArgs, RigArgs,
    RigStudyArgs, SimulateArgs, TrainArgs, TransferArgs,
};
pub use source::SourceArgs;
pub use stdout::StdoutClosed;
pub use terminal::Terminal;

use crate::bake::budget::Workload;
use crate::bake::checkpoint::{Checkpoint, OnExisting, ShardBaked};
use crate::cli::stdout::outln;
use crate::input::{InputKind, read_input};
use crate::io::atomic::write_atomic;
use crate::io::outputs::{Input, Output, check};
use crate::io::source::ClipSpec;
use crate::model::ModelFrame;
use crate::model::predict::{predict_clip, predict_world};
use crate::pipeline::scene::{SceneOutcome, SceneTrainOptions, SceneTrainReport, train_scene};
use crate::pipeline::train::{Outcome, TrainSettings};
use crate::progress::Reporter;
use crate::report::sweep::choice::swept_method;
use crate::rig::mesh::degenerate_note;
use crate::scene::file::{CLIP_KEYS, Environment, Scene, SceneSource, read_scene};
use crate::scene::lighting::SceneLighting;
use crate::scene::method::{MethodDecision, fixed_method};

/// Pose-driven precomputed radiance transfer for skinned characters.
#[derive(Debug, Parser)]
#[command(name = "aprt", version, about, long_about = None)]
pub struct Cli {
    /// The command to run.
    #[command(subcommand)]
    pub command: Command,
}

/// The `aprt` commands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Bake, fit, evaluate and report on the built-in character, end to end.
    Demo(DemoArgs),
    /// Bake the static transfer of one OBJ mesh into a (vertices, n²) float32 .npy.
    Transfer(TransferArgs),
    /// Train a model on a character's clip, or on an OBJ sequence with a joint-angle CSV.
    Train(TrainArgs),
    /// Bake the ground-truth transfer of every frame into a (frames, vertices, n²) .npy.
    Simulate(SimulateArgs),
    /// Predict transfer through aprt-core into a (frames, vertices, n²) .npy, for a clip of the
    /// model's character or rows of joint angles.
    Eval(EvalArgs),
    /// Write what the web page (web/) needs to play a clip through aprt-core in the browser:
    /// the mesh, its skin, each frame's skinning, pose vector and bone rotations, and the blob.
    ExportWeb(ExportWebArgs),
    /// Validate a model blob and print its header, dimensions and section sizes.
    Inspect(InspectArgs),
    /// Regenerate the results document on the real glTF characters and BVH motion capture.
    Results(ResultsArgs),
    /// Lights: irradiance at a point from a lights file, through SH and exactly; environment
    /// maps projected to SH.
    Light(LightArgs),
    /// Fit an irradiance rig to a mesh or character and report, for a lights file, which
    /// lights it carries, its error against exact evaluation and its cost per frame (also
    /// spelled `rig`, its earlier name).
    #[command(alias = "rig")]
    IrradianceRig(RigArgs),
    /// Sweep a scene's accuracy knobs and report error against µs per frame (as the scene
    /// ships each model) and bytes, the Pareto-optimal settings, and the cheapest of the most
    /// accurate within a budget (errors within 0.05 grey levels or 1 % tie).
    Report(ReportArgs),
    /// Regenerate the irradiance-rig study on the built-in creature (docs/rigs; also spelled
    /// `rig-study`, its earlier name).
    #[command(alias = "rig-study")]
    IrradianceRigStudy(RigStudyArgs),
    /// SH light maps (`.shlm` files): bake a clip into a compressed light-map sequence, sample
    /// it at the vertices, inspect it, compose it under lights, or train the pose-driven
    /// light-map model (also spelled `shlm`, its earlier name).
    #[command(alias = "shlm")]
    Lightmap(lightmap::LightmapArgs),
}

/// `err` and its causes on one line, each cause said once: a cause whose text its parent's
/// message already includes is left out (an image decoder's error that quotes its own source
/// would otherwise print "invalid: file identifier missing" twice).
pub fn error_line(err: &anyhow::Error) -> String {
    let mut line = String::new();
    for cause in err.chain() {
        let text = cause.to_string();
        if line.is_empty() {
            line = text;
        } else if !line.contains(&text) {
            line = format!("{line}: {text}");
        }
    }
    line
}

/// Runs one command. An interrupted run (SIGINT, SIGTERM, SIGHUP) leaves no temporary file; a
/// command whose standard output is closed ends there, quietly ([`StdoutClosed`]).
pub fn run(cli: Cli) -> Result<()> {
    crate::io::atomic::clean_up_on_signals().context("cannot install the signal handler")?;
    match command(cli.command) {
        Err(e) if e.is::<StdoutClosed>() => Ok(()),
        done => done,
    }
}

fn command(command: Command) -> Result<()> {
    match command {
        Command::Demo(args) => demo(&args),
        Command::Transfer(args) => transfer(&args),
        Command::Train(args) => train(&args),
        Command::Simulate(args) => simulate::run(&args),
        Command::Eval(args) => eval(&args),
        Command::ExportWeb(args) => export_web(&args),
        Command::Inspect(args) => inspect(&args),
        Command::Results(args) => results(&args),
        Command::IrradianceRig(args) => irradiance_rig::run(&args),
        Command::IrradianceRigStudy(args) => irradiance_rig_study(&args),
        Command::Report(args) => report(&args),
        Command::Lightmap(args) => lightmap::run(&args),

        Command::Light(args) => match args.command {
            LightCommand::Irradiance(args) => light_irradiance(&args),
            LightCommand::Env(args) => light_env(&args),
        },
    }
}

fn light_irradiance(args: &IrradianceArgs) -> Result<()> {
    if args.normal.iter().all(|&x| x == 0.0) {
        bail!("--normal 0,0,0: the normal must have non-zero length");
    }
    let lights = crate::lighting::read_lights(&args.lights)?;
    let report = crate::lighting::irradiance(
        &lights,
        args.at,
        args.normal,
        args.order as usize,
        args.dering.map(Into::into),
    )
    .with_context(|| {
        let [x, y, z] = args.at;
        format!("{}: at {x},{y},{z}", args.lights.display())
    })?;
    if args.json {
        outln!("{}", serde_json::to_string_pretty(&report)?)?;
        return Ok(());
    }
    let rgb = |c: [f32; 3]| format!("{:.6} {:.6} {:.6}", c[0], c[1], c[2]);
    outln!(
        "{} light(s) at {:?}, normal {:?}, SH order {}{}",
        report.lights.len(),
        report.at,
        report.normal,
        report.order,
        report
            .window
            .map(|w| format!(", {w} window"))
            .unwrap_or_default()
    )?;
    outln!("  irradiance, SH path  {}", rgb(report.sh))?;
    outln!("  irradiance, exact    {}", rgb(report.exact))?;
    outln!("  |SH - exact|         {}", rgb(report.abs_error))?;
    let g = report.grey_levels;
    outln!(
        "  8-bit grey levels    {:.2} {:.2} {:.2}  (white Lambertian surface, 255 |SH - exact| / pi)",
        g[0],
        g[1],
        g[2]
    )?;
    Ok(())
}

/// The frame `aprt light env` prints in: the map's, before a scene turns it to a character's
/// up axis, which the built-in characters (z-up) do not share.
const ENV_FRAME: &str = "frame +Y up (the map's; scenes turn it to the character's up axis)";

/// What `aprt light env --json` prints.
#[derive(serde::Serialize)]
struct EnvReport<'a> {
    file: &'a Path,
    /// The frame the coefficients are in: the map's own, +Y up, not yet a character's.
    frame: &'static str,
    order: usize,
    width: usize,
    height: usize,
    coefficients: Vec<[f32; 3]>,
}

fn light_env(args: &EnvArgs) -> Result<()> {
    let order = usize::from(args.order);
    let image = crate::lighting::read_equirect(&args.file)?;
    let coefficients = image.project(order)?;
    if args.json {
        let report = EnvReport {
            file: &args.file,
            frame: ENV_FRAME,
            order,
            width: image.width,
            height: image.height,
            coefficients,
        };
        outln!("{}", serde_json::to_string_pretty(&report)?)?;
        return Ok(());
    }
    outln!(
        "{}: {}x{} equirectangular, SH order {order} ({} RGB coefficients, {ENV_FRAME})",
        args.file.display(),
        image.width,
        image.height,
        coefficients.len()
    )?;
    let bands = (0..order as i32).flat_map(|l| (-l..=l).map(move |m| (l, m)));
    for ((l, m), [r, g, b]) in bands.zip(&coefficients) {
        outln!("  l={l} m={m:+}  {r:.6} {g:.6} {b:.6}")?;
    }
    Ok(())
}

fn demo(args: &DemoArgs) -> Result<()> {
    // The demo reads no file of the user's (its character and scene are built in).
    check(&[Output::directory(&args.out, "--out", &[])], &[])?;
    let markdown = crate::report::demo::run(&args.settings()?, &Terminal)?;
    stdout::print(&markdown)?;
    eprintln!(
        "wrote {}/{{model.aprt, report.md, report.json, novel_pose.png, baselines.png, rig_frame.png, sweep/}}",
        args.out.display()
    );
    Ok(())
}

/// A user's file, through the one reader every input goes through (its error names the path).
fn read_file(path: &Path, kind: InputKind) -> Result<Vec<u8>> {
    Ok(read_input(path, kind)?)
}

fn write_npy(path: &Path, shape: &[usize], data: &[f32]) -> Result<()> {
    write_atomic(path, &crate::io::npy::encode_f32(shape, data))
        .with_context(|| format!("cannot write {}", path.display()))
}

fn inspect(args: &InspectArgs) -> Result<()> {
    let blob = read_file(&args.model, InputKind::Model)?;
    let info = crate::model::runtime::describe(&blob)
        .with_context(|| format!("{}: invalid model", args.model.display()))?;
    if args.json {
        outln!("{}", serde_json::to_string_pretty(&info)?)?;
    } else {
        stdout::print(&info.to_string())?;
    }
    Ok(())
}

fn eval(args: &EvalArgs) -> Result<()> {
    if let Some(dir) = &args.source.obj_seq {
        bail!(
            "--obj-seq {}: eval reads no meshes (the model holds its own): give the poses with --angles FILE alone, or a clip of the model's character",
            dir.display()
        );
    }
    let mut inputs = vec![Input::new(&args.model, "the model")];
    inputs.extend(args.source.inputs());
    check(&[Output::file(&args.npy, "--npy")], &inputs)?;
    let blob = read_file(&args.model, InputKind::Model)?;
    let info = crate::model::runtime::describe(&blob)
        .with_context(|| format!("{}: invalid model", args.model.display()))?;
    let model_name = args.model.display().to_string();
    let n2 = info.order * info.order;
    // The prediction, its move from bone frames to world space, the array written and its
    // encoding.
    let copies = 3 + usize::from(info.bones > 0);
    let transfer = if args.source.names_rig() {
        let (rig, clip) = args.source.rig(&Terminal)?;
        if info.angle_names.is_empty() {
            bail!("{model_name} records no pose-entry names, so a clip cannot be mapped onto it; use --angles");
        }
        let work = Workload::evaluation(clip.frames.len(), info.vertices, n2, copies);
        args.source.in_origin(work.check(&format!("clip {}", clip.name)))?;
        predict_clip(&blob, &info, &model_name, rig.as_ref(), &clip)
    } else {
        args.source.check_flags()?;
        let Some(csv) = &args.source.angles else {
            bail!("give the poses: --angles FILE, or a clip of the model's character");
        };
        let poses = crate::io::angles::read_angles(csv, Some(info.pose_len))?;
        if crate::model::runtime::bone_frames(&blob)?.is_some() {
            bail!("{model_name} learns transfer in bone frames: give its character's clip (not --angles) so the bones' rotations are known");
        }
        Workload::evaluation(poses.len(), info.vertices, n2, copies)
            .check(&csv.display().to_string())?;
        predict_world(&blob, &poses, &[], None)
    }
    .with_context(|| format!("evaluating {model_name}"))?;
    let flat: Vec<f32> = transfer.concat();
    write_npy(
        &args.npy,
        &[transfer.len(), info.vertices, info.order * info.order],
        &flat,
    )
}

fn export_web(args: &ExportWebArgs) -> Result<()> {
    use crate::report::web::{WEB_FILES, web_export, write_web_export};
    let mut inputs = vec![Input::new(&args.model, "the model")];
    inputs.extend(args.source.inputs());
    check(
        &[Output::directory(&args.out, "--out", &WEB_FILES)],
        &inputs,
    )?;
    let blob = read_file(&args.model, InputKind::Model)?;
    let info = crate::model::runtime::describe(&blob)
        .with_context(|| format!("{}: invalid model", args.model.display()))?;
    if !args.source.names_rig() {
        bail!("give the clip the page plays: a character (--builtin, --gltf, --bvh) and --clip");
    }
    let (rig, clip) = args.source.rig(&Terminal)?;
    let (manifest, bin) = web_export(rig.as_ref(), &clip, &info)
        .with_context(|| format!("exporting {} for the web", args.model.display()))?;
    write_web_export(&args.out, &manifest, &bin, &blob)?;
    eprintln!(
        "wrote {}/{{{}}}: clip {}, {} frames, {} vertices, {} bytes of arrays",
        args.out.display(),
        WEB_FILES.join(", "),
        manifest.clip,
        manifest.frames,
        manifest.vertices,
        bin.len()
    );
    Ok(())
}

fn transfer(args: &TransferArgs) -> Result<()> {
    check(
        &[Output::file(&args.npy, "--npy")],
        &[Input::new(&args.mesh, "the mesh")],
    )?;
    let mesh = crate::io::obj::read_obj(&args.mesh)?;
    if let Some(note) = degenerate_note(&args.mesh.display().to_string(), &mesh) {
        Terminal.note(&note);
    }
    let settings = args.bake.settings();
    let transfer = crate::bake::bake_poses(std::slice::from_ref(&mesh), &settings, &Terminal)
        .with_context(|| format!("baking {}", args.mesh.display()))?;
    let n2 = settings.order * settings.order;
    write_npy(&args.npy, &[mesh.vertex_count(), n2], &transfer[0])
}

fn results(args: &ResultsArgs) -> Result<()> {
    use crate::report::results::{ResultsSettings, asset_studies, default_assets, write_document};
    let assets = args.assets.clone().unwrap_or_else(default_assets);
    check(
        // Inputs are files of the assets directory, which the output may not lie inside.
        &[Output::directory(&args.out, "--out", &[])],
        &[Input::new(&assets, "the assets directory")],
    )?;
    let mut studies = asset_studies(&assets)
        .with_context(|| format!("loading the assets in {}", assets.display()))?;
    if !args.study.is_empty() {
        let ids: Vec<String> = studies.iter().map(|s| s.id.clone()).collect();
        if let Some(unknown) = args.study.iter().find(|id| !ids.contains(id)) {
            bail!(
                "--study {}: no such study (they are {})",
                crate::text::quote(unknown),
                ids.join(", ")
            );
        }
        studies.retain(|s| args.study.contains(&s.id));
    }
    let settings = ResultsSettings {
        bake: crate::bake::BakeSettings {
            order: args.order as usize,
            rays: args.rays,
            bounces: 0,
            albedo: 0.0,
            shadows: true,
        },
        alphas: (-6..=3).map(|e| 10f64.powi(e)).collect(),
        validation_poses: args.validation_poses,
    };
    let mut command = format!(
        "cargo run --release -p aprt-trainer --bin aprt -- results --out {} --order {} --rays {}",
        args.out.display(),
        args.order,
        args.rays
    );
    if args.validation_poses != crate::rig::pose_sampler::DEFAULT_VALIDATION_POSES {
        command += &format!(" --validation-poses {}", args.validation_poses);
    }
    for id in &args.study {
        command += &format!(" --study {id}");
    }
    let path = write_document(&studies, &settings, &args.out, &command, &Terminal)?;
    eprintln!("wrote {}", path.display());
    Ok(())
}

fn irradiance_rig_study(args: &RigStudyArgs) -> Result<()> {
    // The study reads no file of the user's (its creature is built in).
    check(&[Output::directory(&args.out, "--out", &[])], &[])?;
    let command = format!(
        "cargo run --release -p aprt-trainer --bin aprt -- rig-study --out {} --order {}",
        args.out.display(),
        args.order
    );
    let path = crate::report::irradiance_rig_study::run(
        &args.out,
        args.order as usize,
        &command,
        &Terminal,
    )?;
    eprintln!("wrote {}", path.display());
    Ok(())
}

/// The checkpoint directory of a command writing `output` (named `output_flag` on the command
/// line): `--checkpoint`'s `dir`, or `OUTPUT.bake` beside the output; and the files of a
/// checkpoint being resumed there, which are inputs the outputs must not land on.
fn checkpoint_output(dir: Option<&Path>, output: &Path, output_flag: &str) -> (Output, Vec<Input>) {
    let checkpoint = match dir {
        Some(dir) => Output::directory(dir, "--checkpoint", &[]),
        None => Output::directory(
            Checkpoint::default_dir(output),
            format!("the checkpoint directory ({output_flag}'s path + .bake)"),
            &[],
        ),
    };
    let stored = std::fs::read_dir(&checkpoint.path).into_iter().flatten();
    let inputs = stored
        .flatten()
        .map(|e| Input::new(e.path(), "a file of the checkpoint"))
        .collect();
    (checkpoint, inputs)
}

/// What `--resume` asks of a checkpoint that is already there.
fn on_existing(resume: bool) -> OnExisting {
    if resume {
        OnExisting::Resume
    } else {
        OnExisting::Refuse
    }
}

/// Prints what a shard of `command` baked, and what finishes the bake.
fn shard_done(baked: &ShardBaked, command: &str) {
    eprintln!("{baked}");
    let next = if baked.stored == baked.frames {
        "every frame is baked"
    } else {
        "when every shard is done"
    };
    eprintln!(
        "{next}: run {command} with the same arguments and --resume instead of --shard (over the merged checkpoint, if the shards baked into separate directories)"
    );
}

/// Why `aprt train` cannot fit occluder proxies, which ride the bones of a character's
/// bone-frame model: an OBJ sequence (no bones) or a model learnt in world space, by flag or
/// by `scene`'s keys.
fn proxies_without(args: &TrainArgs, scene: Option<&Scene>) -> Option<String> {
    const RIDE: &str = "occluder proxies ride the bones of a bone-frame model";
    let Some(scene) = scene else {
        return match &args.source.obj_seq {
            Some(dir) => Some(format!(
                "--obj-seq {}: an OBJ sequence has no bones, and {RIDE}",
                dir.display()
            )),
            None => args.world_frame.then(|| {
                format!("--world-frame learns in world space, and {RIDE}: give one of the two")
            }),
        };
    };
    let file = scene.path.display();
    match (&scene.source, scene.effects.frame) {
        (SceneSource::ObjSeq { .. }, _) => Some(format!(
            "{file}: [source] obj_seq: an OBJ sequence has no bones, and {RIDE}"
        )),
        (_, ModelFrame::World) => Some(format!(
            "{file}: [effects] frame = \"world\" learns in world space, and {RIDE}"
        )),
        _ => None,
    }
}

fn train(args: &TrainArgs) -> Result<()> {
    // Clap drops a flag's `requires` when its target conflicts with a flag given (`--scene`
    // conflicts with the source flags), so these are checked here.
    for (flag, given) in [
        ("--confine", args.confine),
        ("--report", args.report.is_some()),
    ] {
        if given && args.scene.is_none() {
            bail!("{flag} applies to --scene only: give a scene file, or leave {flag} out");
        }
    }
    let scene = args.scene.as_deref().map(read_scene).transpose()?;
    args.fit
        .check_proxies(proxies_without(args, scene.as_ref()))?;
    if let Some(scene) = &scene
        && args.confine
    {
        scene.confine("--confine")?;
    }
    let (source, validate) = match &scene {
        Some(scene) => (SourceArgs::from_scene(scene), Vec::new()),
        None => (args.source.clone(), args.validate.clone()),
    };
    // A checkpoint being resumed is read too: the model must not land on one of its files.
    let (checkpoint, mut inputs) =
        checkpoint_output(args.checkpoint.as_deref(), &args.output, "-o");
    inputs.extend(source.inputs());
    inputs.extend(source.validation_inputs(&validate));
    if let Some(scene) = &scene {
        inputs.extend(scene_inputs(scene));
    }
    let mut outputs = vec![Output::file(&args.output, "-o"), checkpoint.clone()];
    if let Some(report) = &args.report {
        outputs.push(Output::file(report, "--report"));
    }
    check(&outputs, &inputs)?;
    let existing = on_existing(args.resume);
    if let Some(scene) = &scene {
        let (poses, tests) = scene_poses(&source, scene)?;
        let lighting = SceneLighting::of(scene, poses.up())?;
        let method = match fixed_method(scene) {
            Some(fixed) => fixed,
            None => source.in_origin(scene_method(scene, &lighting, (&poses, &tests), args))?,
        };
        let options = SceneTrainOptions {
            output: &args.output,
            checkpoint: checkpoint.path,
            existing,
            fit: args.fit.options()?,
            shard: args.shard,
            validation_poses: args.validation_poses,
            method,
        };
        return match source.in_origin(train_scene(scene, &lighting, poses, options, &Terminal))? {
            SceneOutcome::Trained(report) => print_scene_report(&report, args.report.as_deref()),
            SceneOutcome::Shard(baked) => {
                shard_done(&baked, "aprt train --scene");
                Ok(())
            }
        };
    }
    let settings = TrainSettings {
        fit: args.fit.options()?,
        bake: args.bake.settings(),
        precision: crate::model::precision::PrecisionChoice::Fixed(args.fit.precision.into()),
        frame: if args.world_frame {
            ModelFrame::World
        } else {
            ModelFrame::Bone
        },
        checkpoint: checkpoint.path,
        existing,
        irradiance_rig: args.rig,
        shard: args.shard,
        sample_poses: args.sample_poses,
        validation_poses: args.validation_poses,
    };
    settings.bake.validate()?;
    let poses = args.source.poses(&args.validate, &Terminal)?;
    args.source
        .in_origin(crate::pipeline::train::check(&poses, &settings))?;
    let trained = match crate::pipeline::train::train(poses, &args.output, &settings, &Terminal)? {
        Outcome::Trained(trained) => *trained,
        Outcome::Shard(baked) => {
            shard_done(&baked, "aprt train");
            return Ok(());
        }
    };
    let info = &trained.info;
    for line in trained.selection.lines() {
        eprintln!("{line}");
    }
    eprintln!(
        "wrote {}: {} poses, k_a {}, k_v {}, alpha {:.3e}, {} bytes{}",
        args.output.display(),
        trained.poses,
        info.pose_dims,
        info.coef_dims,
        info.alpha,
        info.bytes,
        validation_sentence(trained.validation_poses, trained.validation_bake_s)
    );
    Ok(())
}

/// `, N validation poses baked in S s` for the line that says what was written; empty
/// without validation poses.
fn validation_sentence(poses: usize, seconds: f64) -> String {
    match poses {
        0 => String::new(),
        1 => format!(", 1 validation pose baked in {seconds:.1} s"),
        n => format!(", {n} validation poses baked in {seconds:.1} s"),
    }
}

/// The poses `aprt train --scene` trains on: the scene's OBJ sequence, or its character's
/// `train` clips with its `validate` clips held out; and its `test` clips, which choose an
/// automatic method (and a missing one is refused before the bake rather than by the report
/// that needs it).
fn scene_poses(
    source: &SourceArgs,
    scene: &Scene,
) -> Result<(crate::io::source::Poses, Vec<crate::rig::Clip>)> {
    if !source.names_rig() {
        return Ok((source.poses(&[], &Terminal)?, Vec::new()));
    }
    let (rig, [clips, validation, tests]) = source.load_scene(scene, &Terminal)?;
    let poses = crate::io::source::Poses::Rig {
        rig,
        clips,
        validation,
    };
    Ok((poses, tests))
}

/// The method the report's sweep recommends for `scene` (`method`, or a light map's
/// resolution or precision, left to `auto`), on its character's clips and `tests`. Refused
/// for a shard, whose choice would time models on one machine of the farm, and for an OBJ
/// sequence, which has no test clips to choose on.
fn scene_method(
    scene: &Scene,
    lighting: &SceneLighting,
    (poses, tests): (&crate::io::source::Poses, &[crate::rig::Clip]),
    args: &TrainArgs,
) -> Result<MethodDecision> {
    let file = scene.path.display();
    if args.shard.is_some() {
        bail!(
            "{file}: [effects] method, lightmap_resolution or a light map's precision is \"auto\", which times models to choose: a shard cannot, so fix them (run aprt report {file} to see which to fix)"
        );
    }
    let crate::io::source::Poses::Rig {
        rig,
        clips,
        validation,
    } = poses
    else {
        bail!(
            "{file}: [effects] method = \"auto\" chooses on a character's test clips, and an OBJ sequence has none: give method = \"vertex\""
        );
    };
    let clips = crate::report::sweep::SceneClips {
        rig: rig.as_ref(),
        train: clips,
        validation,
        tests,
    };
    swept_method(scene, lighting, &clips, &Terminal)
}

/// The files a scene reads besides its character: itself, its environment map and the BVH
/// files its clips name.
fn scene_inputs(scene: &Scene) -> Vec<Input> {
    let mut inputs = vec![Input::new(&scene.path, "the scene file")];
    if let Some(Environment::Map(map)) = &scene.environment {
        inputs.push(Input::new(map, "the scene's environment map"));
    }
    for spec in CLIP_KEYS.iter().flat_map(|key| scene.clip_specs(key)) {
        if let ClipSpec::Motion { path, .. } = spec {
            inputs.push(Input::new(path, "a BVH clip of the scene"));
        }
    }
    inputs
}

/// Prints what `aprt train --scene` computed and skipped, and writes it as JSON to `json`.
fn print_scene_report(report: &SceneTrainReport, json: Option<&Path>) -> Result<()> {
    eprintln!("method: {}", report.method.reason);
    eprintln!("computed:");
    for line in &report.computed {
        eprintln!("  - {line}");
    }
    eprintln!("skipped:");
    for line in &report.skipped {
        eprintln!("  - {line}");
    }
    eprintln!(
        "wrote {}: {} bytes, SH order {}, {} rays cast, {} bounce passes, {:.1} s ({:.1} s baking, {:.1} s fitting){}",
        report.model.display(),
        report.bytes,
        report.sh_order,
        crate::scene::group(report.rays_cast),
        report.bounce_passes,
        report.seconds,
        report.stages.bake,
        report.stages.fit,
        validation_sentence(report.validation_poses, report.validation_bake_s)
    );
    match (&report.over_budget, report.within_budget) {
        (Some(miss), _) => eprintln!("{miss}"),
        (None, fits) => eprintln!(
            "the model costs {:.1} µs a frame through aprt-core (the scene's lighting, rig and per-vertex lights included){}",
            report.us_per_frame,
            if fits == Some(true) {
                ", within the scene's [budget] us_per_frame"
            } else {
                ""
            }
        ),
    }
    match &report.full_simulation {
        None => {}
        Some(full) if full.poses_timed == 0 => eprintln!(
            "the scene needs the full simulation ({}): nothing saved",
            full.settings
        ),
        Some(full) => eprintln!(
            "the full simulation ({}) takes {:.3} s a pose against this scene's {:.4} s ({:.1}x, measured on {} poses): about {:.1} s saved",
            full.settings,
            full.seconds_per_pose,
            full.scene_seconds_per_pose,
            full.speedup,
            full.poses_timed,
            full.saved_seconds
        ),
    }
    if let Some(path) = json {
        let text = serde_json::to_string_pretty(report)? + "\n";
        write_atomic(path, text.as_bytes())
            .with_context(|| format!("cannot write {}", path.display()))?;
        eprintln!("wrote {}", path.display());
    }
    Ok(())
}

fn report(args: &ReportArgs) -> Result<()> {
    use crate::report::sweep::{ReportSettings, SceneClips, document, run};
    if let Some(us) = args.budget_us
        && !(us.is_finite() && us > 0.0)
    {
        bail!("--budget-us {us}: expected a positive number of microseconds per frame");
    }
    let scene = read_scene(&args.scene)?;
    if args.confine {
        scene.confine("--confine")?;
    }
    let source = SourceArgs::from_scene(&scene);
    let mut inputs = source.inputs();
    inputs.extend(scene_inputs(&scene));
    let mut outputs = vec![Output::directory(&args.out, "--out", document::FILES)];
    if let Some(model) = &args.write_model {
        outputs.push(Output::file(model, "--write-model"));
    }
    check(&outputs, &inputs)?;
    if !source.names_rig() {
        bail!(
            "{}: the report measures on test clips of a character; an OBJ sequence has none",
            args.scene.display()
        );
    }
    let (rig, [clips, validation, tests]) = source.load_scene(&scene, &Terminal)?;
    // Before `run`, whose errors are the character's.
    crate::report::sweep::check_stride(&clips, args.stride as usize)?;
    let lighting = SceneLighting::of(&scene, rig.up())?;
    let settings = ReportSettings {
        budget_us: args.budget_us,
        budget_bytes: args.budget_bytes,
        stride: args.stride as usize,
        validation_poses: args.validation_poses,
        surface_points: args.surface_points as usize,
    };
    let scene_clips = SceneClips {
        rig: rig.as_ref(),
        train: &clips,
        validation: &validation,
        tests: &tests,
    };
    let report = source.in_origin(run(&scene, lighting, &scene_clips, &settings, &Terminal))?;
    let mut command = format!(
        "aprt report {} --out {}",
        args.scene.display(),
        args.out.display()
    );
    if let Some(us) = args.budget_us {
        command += &format!(" --budget-us {us}");
    }
    if let Some(bytes) = args.budget_bytes {
        command += &format!(" --budget-bytes {bytes}");
    }
    if args.stride != 3 {
        command += &format!(" --stride {}", args.stride);
    }
    if args.validation_poses != crate::rig::pose_sampler::DEFAULT_VALIDATION_POSES {
        command += &format!(" --validation-poses {}", args.validation_poses);
    }
    if args.surface_points != crate::surface::DEFAULT_SURFACE_POINTS {
        command += &format!(" --surface-points {}", args.surface_points);
    }
    document::write(&report, &args.out, &command)?;
    match report.recommended {
        Some(i) => {
            let p = &report.points[i];
            eprintln!(
                "recommended: {}: {:.2} grey levels RMS, {:.1} us per frame, {} bytes",
                p.setting.label, p.error, p.us_per_frame, p.bytes
            );
            if let Some(model) = &args.write_model {
                write_atomic(model, &p.blob)
                    .with_context(|| format!("cannot write {}", model.display()))?;
                eprintln!("wrote {}", model.display());
            }
        }
        None => {
            if args.write_model.is_some() {
                bail!(
                    "no measured setting fits the budget, so there is no model to write (see {}/report.md)",
                    args.out.display()
                );
            }
            eprintln!("no measured setting fits the budget");
        }
    }
    eprintln!(
        "wrote {}/{{report.md, report.json, {p}.png, {p}.svg, {b}.png, {b}.svg}}",
        args.out.display(),
        p = document::TIME_PLOT,
        b = document::BYTES_PLOT
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Clap's own consistency checks over every command's flags (no two flags of one command
    /// share a name, every `requires` and `conflicts_with` names a flag), which it runs by
    /// itself in debug builds only.
    #[test]
    fn every_command_line_is_consistent() {
        use clap::CommandFactory;
        Cli::command().debug_assert();
    }

    /// A cause its parent already quotes is said once; distinct causes all are.
    #[test]
    fn each_cause_is_said_once() {
        #[derive(Debug, thiserror::Error)]
        #[error("decoding: {0}")]
        struct Quoting(#[source] std::io::Error);
        let inner = std::io::Error::other("identifier missing");
        let err = anyhow::Error::new(Quoting(inner)).context("sky.exr");
        assert_eq!(error_line(&err), "sky.exr: decoding: identifier missing");
        let err = anyhow::anyhow!("no such clip").context("scene.toml: [source] test");
        assert_eq!(error_line(&err), "scene.toml: [source] test: no such clip");
    }
}
