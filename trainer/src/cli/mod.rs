//! Command-line definitions and dispatch. Each command reads its inputs, calls one library
//! stage after another, and writes its outputs atomically; errors carry the file and item.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::{Args, Parser, Subcommand};

use crate::bake::checkpoint::Checkpoint;
mod terminal;

pub use terminal::Terminal;

use crate::io::atomic::write_atomic;
use crate::io::source::{Poses, SourceArgs};
use crate::model::export::Precision;
use crate::model::fit::fit;
use crate::report::experiment::{BakedClip, fit_clip, pose_all, predict_world};
use crate::rig::bone_frames::all_rotations;
use crate::rig::pose_layout::PoseLayout;

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
    /// Validate a model blob and print its header, dimensions and section sizes.
    Inspect(InspectArgs),
    /// Regenerate the results document on the real glTF characters and BVH motion capture.
    Results(ResultsArgs),
}

/// `aprt results`.
#[derive(Debug, Args)]
pub struct ResultsArgs {
    /// The assets directory (with gltf/ and bvh/); default $APRT_ASSETS or ../shared/assets.
    #[arg(long)]
    pub assets: Option<PathBuf>,
    /// Output directory for README.md and the PNG figures.
    #[arg(long, default_value = "docs/results")]
    pub out: PathBuf,
    /// SH order of the ground truth and the models.
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u8).range(1..=6))]
    pub order: u8,
    /// Directions per vertex for the ground-truth bakes.
    #[arg(long, default_value_t = 128)]
    pub rays: usize,
}

/// `aprt demo`.
#[derive(Debug, Args)]
pub struct DemoArgs {
    /// Output directory for model.aprt, report.md, report.json and the PNG renders.
    #[arg(long, default_value = "aprt-demo")]
    pub out: PathBuf,
    /// SH order of the demo model.
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u8).range(1..=6))]
    pub order: u8,
    /// Directions per vertex for the ground-truth bakes.
    #[arg(long, default_value_t = 128)]
    pub rays: usize,
    /// Use every k-th frame of the clips (1 = all 250 training frames; larger is faster).
    #[arg(long, default_value_t = 2)]
    pub stride: usize,
}

/// Simulation settings shared by the commands that bake.
#[derive(Debug, Clone, Args)]
pub struct BakeArgs {
    /// SH order n (n² coefficients per vertex).
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u8).range(1..=6))]
    pub order: u8,
    /// Directions per vertex (low-discrepancy, cosine-weighted).
    #[arg(long, default_value_t = 256)]
    pub rays: usize,
    /// Inter-reflection bounces (0 = direct shadowed transfer only).
    #[arg(long, default_value_t = 0)]
    pub bounces: usize,
    /// Albedo of the inter-reflecting surfaces, used when --bounces > 0.
    #[arg(long, default_value_t = 0.5)]
    pub albedo: f32,
}

/// `aprt transfer`.
#[derive(Debug, Args)]
pub struct TransferArgs {
    /// The mesh.
    pub mesh: PathBuf,
    /// Simulation settings.
    #[command(flatten)]
    pub bake: BakeArgs,
    /// Output .npy file.
    #[arg(long)]
    pub npy: PathBuf,
}

/// Model-shape options shared by every training source.
#[derive(Debug, Clone, Args)]
pub struct FitArgs {
    /// Keep this many pose PCA dimensions k_a.
    #[arg(long, conflicts_with = "pose_variance")]
    pub pose_dims: Option<usize>,
    /// Keep the pose PCA dimensions that explain this fraction of the pose variance.
    #[arg(long)]
    pub pose_variance: Option<f64>,
    /// Keep this many vertex-basis vectors k_v.
    #[arg(long, conflicts_with_all = ["coef_variance", "full"])]
    pub coef_dims: Option<usize>,
    /// Keep the vertex-basis vectors that capture this fraction of the transfer energy.
    #[arg(long, conflicts_with = "full")]
    pub coef_variance: Option<f64>,
    /// No vertex reduction: the paper's full linear model (large).
    #[arg(long)]
    pub full: bool,
    /// Tikhonov parameter: `auto` (cross-validated, the default), `loo`, `loso`, or a number.
    #[arg(long, default_value = "auto", allow_negative_numbers = true)]
    pub alpha: String,
    /// Precision of the large sections.
    #[arg(long, value_enum, default_value_t = Precision::F32)]
    pub precision: Precision,
}

/// `aprt train`.
#[derive(Debug, Args)]
pub struct TrainArgs {
    /// The training poses.
    #[command(flatten)]
    pub source: SourceArgs,
    /// Output model file.
    #[arg(short, long)]
    pub output: PathBuf,
    /// For characters: learn transfer in world space instead of each vertex's bone frame
    /// (bone frames generalise better; world frame needs no bone rotations at runtime).
    #[arg(long)]
    pub world_frame: bool,
    /// Simulation settings.
    #[command(flatten)]
    pub bake: BakeArgs,
    /// Model shape.
    #[command(flatten)]
    pub fit: FitArgs,
    /// Checkpoint directory: every baked pose is saved there until the model is written
    /// (default: OUTPUT.bake beside the model).
    #[arg(long)]
    pub checkpoint: Option<PathBuf>,
    /// Continue an interrupted bake from its checkpoint (same inputs and bake settings).
    #[arg(long)]
    pub resume: bool,
}

/// `aprt simulate`.
#[derive(Debug, Args)]
pub struct SimulateArgs {
    /// The poses.
    #[command(flatten)]
    pub source: SourceArgs,
    /// Simulation settings.
    #[command(flatten)]
    pub bake: BakeArgs,
    /// Output .npy file, float32 (frames, vertices, n²).
    #[arg(long)]
    pub npy: PathBuf,
}

/// `aprt eval`.
#[derive(Debug, Args)]
pub struct EvalArgs {
    /// The model.
    pub model: PathBuf,
    /// The poses: a clip of the model's character, or --angles alone.
    #[command(flatten)]
    pub source: SourceArgs,
    /// Output .npy file, float32 (frames, vertices, n²), world-frame transfer.
    #[arg(long)]
    pub npy: PathBuf,
}

/// `aprt inspect`.
#[derive(Debug, Args)]
pub struct InspectArgs {
    /// The model.
    pub model: PathBuf,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

/// Runs one command.
pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Demo(args) => demo(&args),
        Command::Transfer(args) => transfer(&args),
        Command::Train(args) => train(&args),
        Command::Simulate(args) => simulate(&args),
        Command::Eval(args) => eval(&args),
        Command::Inspect(args) => inspect(&args),
        Command::Results(args) => results(&args),
    }
}

fn demo(args: &DemoArgs) -> Result<()> {
    let markdown = crate::report::demo::run(args, &Terminal)?;
    print!("{markdown}");
    eprintln!(
        "wrote {}/{{model.aprt, report.md, report.json, novel_pose.png, baselines.png}}",
        args.out.display()
    );
    Ok(())
}

fn read_file(path: &Path) -> Result<Vec<u8>> {
    std::fs::read(path).with_context(|| format!("cannot read {}", path.display()))
}

fn write_npy(path: &Path, shape: &[usize], data: &[f32]) -> Result<()> {
    write_atomic(path, &crate::io::npy::encode_f32(shape, data))
        .with_context(|| format!("cannot write {}", path.display()))
}

fn inspect(args: &InspectArgs) -> Result<()> {
    let blob = read_file(&args.model)?;
    let info = crate::model::runtime::describe(&blob)
        .with_context(|| format!("{}: invalid model", args.model.display()))?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&info)?);
    } else {
        print!("{info}");
    }
    Ok(())
}

fn eval(args: &EvalArgs) -> Result<()> {
    let blob = read_file(&args.model)?;
    let info = crate::model::runtime::describe(&blob)
        .with_context(|| format!("{}: invalid model", args.model.display()))?;
    let model_name = args.model.display();
    let transfer = if args.source.names_rig() {
        let (rig, clip) = args.source.rig(&Terminal)?;
        if info.angle_names.is_empty() {
            bail!("{model_name} records no pose-entry names, so a clip cannot be mapped onto it; use --angles");
        }
        let layout = PoseLayout::from_names(&rig.angle_names(), &info.angle_names)
            .with_context(|| format!("{model_name} does not fit this character"))?;
        if rig.bind_mesh().vertex_count() != info.vertices {
            bail!(
                "{model_name} has {} vertices, the character has {}",
                info.vertices,
                rig.bind_mesh().vertex_count()
            );
        }
        let angles: Vec<Vec<f64>> = clip.frames.iter().map(|p| layout.reduce(p)).collect();
        let rotations = all_rotations(rig.as_ref(), &clip.frames)?;
        predict_world(&blob, &angles, &rotations)
    } else {
        let Some(csv) = &args.source.angles else {
            bail!("give the poses: --angles FILE, or a clip of the model's character");
        };
        let poses = crate::io::angles::read_angles(csv, Some(info.joints))?;
        if crate::model::runtime::bone_frames(&blob)?.is_some() {
            bail!("{model_name} learns transfer in bone frames: give its character's clip (not --angles) so the bones' rotations are known");
        }
        predict_world(&blob, &poses, &[])
    }
    .with_context(|| format!("evaluating {model_name}"))?;
    let flat: Vec<f32> = transfer.concat();
    write_npy(
        &args.npy,
        &[transfer.len(), info.vertices, info.order * info.order],
        &flat,
    )
}

fn bake_settings(args: &BakeArgs) -> crate::bake::BakeSettings {
    crate::bake::BakeSettings {
        order: args.order as usize,
        rays: args.rays,
        bounces: args.bounces,
        albedo: args.albedo,
    }
}

impl FitArgs {
    /// The fit options these flags ask for; unset flags keep the defaults.
    pub fn options(&self) -> Result<crate::model::fit::FitOptions> {
        use crate::model::fit::{Alpha, CoefDims, Dims, FitOptions};
        let mut options = FitOptions::default();
        if let Some(k) = self.pose_dims {
            options.pose_dims = Dims::Count(k);
        }
        if let Some(f) = self.pose_variance {
            options.pose_dims = Dims::Variance(f);
        }
        if let Some(k) = self.coef_dims {
            options.coef_dims = CoefDims::Count(k);
        }
        if let Some(f) = self.coef_variance {
            options.coef_dims = CoefDims::Variance(f);
        }
        if self.full {
            options.coef_dims = CoefDims::Full;
        }
        options.alpha = match self.alpha.as_str() {
            "auto" => options.alpha,
            "loo" => Alpha::Loo,
            "loso" => Alpha::Loso { segment: None },
            other => match other.parse::<f64>() {
                Ok(x) if x.is_finite() && x >= 0.0 => Alpha::Fixed(x),
                _ => bail!("--alpha {other}: expected auto, loo, loso or a non-negative number"),
            },
        };
        Ok(options)
    }
}

fn transfer(args: &TransferArgs) -> Result<()> {
    let mesh = crate::io::obj::read_obj(&args.mesh)?;
    let settings = bake_settings(&args.bake);
    let transfer = crate::bake::bake_poses(std::slice::from_ref(&mesh), &settings, &Terminal)
        .with_context(|| format!("baking {}", args.mesh.display()))?;
    let n2 = settings.order * settings.order;
    write_npy(&args.npy, &[mesh.vertex_count(), n2], &transfer[0])
}

fn results(args: &ResultsArgs) -> Result<()> {
    use crate::report::results::{ResultsSettings, asset_studies, default_assets, write_document};
    let assets = args.assets.clone().unwrap_or_else(default_assets);
    let studies = asset_studies(&assets)
        .with_context(|| format!("loading the assets in {}", assets.display()))?;
    let settings = ResultsSettings {
        bake: crate::bake::BakeSettings {
            order: args.order as usize,
            rays: args.rays,
            bounces: 0,
            albedo: 0.0,
        },
        alphas: (-6..=3).map(|e| 10f64.powi(e)).collect(),
    };
    let command = format!(
        "cargo run --release -p aprt-trainer --bin aprt -- results --out {} --order {} --rays {}",
        args.out.display(),
        args.order,
        args.rays
    );
    let path = write_document(&studies, &settings, &args.out, &command, &Terminal)?;
    eprintln!("wrote {}", path.display());
    Ok(())
}

fn simulate(args: &SimulateArgs) -> Result<()> {
    let settings = bake_settings(&args.bake);
    let meshes = args.source.meshes(&Terminal)?;
    let transfer = crate::bake::bake_poses(&meshes, &settings, &Terminal)?;
    let n2 = settings.order * settings.order;
    write_npy(
        &args.npy,
        &[meshes.len(), meshes[0].vertex_count(), n2],
        &transfer.concat(),
    )
}

fn train(args: &TrainArgs) -> Result<()> {
    let options = args.fit.options()?;
    let settings = bake_settings(&args.bake);
    let checkpoint_dir = args
        .checkpoint
        .clone()
        .unwrap_or_else(|| Checkpoint::default_dir(&args.output));
    let (fitted, checkpoint, poses) = match args.source.poses(&Terminal)? {
        Poses::Meshes {
            files,
            meshes,
            angles,
        } => {
            let mut checkpoint =
                Checkpoint::open(&checkpoint_dir, args.resume, &settings, &meshes)?;
            let name = |i: usize| files[i].display().to_string();
            let transfers = checkpoint.bake(&meshes, name, &Terminal)?;
            let a = nalgebra::DMatrix::from_fn(angles.len(), angles[0].len(), |i, j| angles[i][j]);
            let fitted = fit(&a, &transfers, settings.order, &options)?;
            (fitted, checkpoint, angles.len())
        }
        Poses::Rig { rig, clip } => {
            let layout = PoseLayout::from_training(&rig.angle_names(), &clip.frames)
                .with_context(|| format!("clip {}", clip.name))?;
            if !layout.dropped().is_empty() {
                eprintln!(
                    "joints that never move in {} and are left out of the model: {}",
                    clip.name,
                    layout.dropped().join(", ")
                );
            }
            let meshes = pose_all(rig.as_ref(), &clip.name, &clip.frames)?;
            let mut checkpoint =
                Checkpoint::open(&checkpoint_dir, args.resume, &settings, &meshes)?;
            let name = |i: usize| format!("clip {} frame {i}", clip.name);
            let transfer = checkpoint.bake(&meshes, name, &Terminal)?;
            let frames = clip.frames.len();
            let baked = BakedClip::new(
                rig.as_ref(),
                &layout,
                &clip.name,
                clip.frames,
                meshes,
                transfer,
            )?;
            let fitted = fit_clip(
                rig.as_ref(),
                &layout,
                &baked,
                settings.order,
                &options,
                !args.world_frame,
            )?;
            (fitted, checkpoint, frames)
        }
    };
    let blob = crate::model::export::encode_model(&fitted.model, args.fit.precision)?;
    write_atomic(&args.output, &blob)
        .with_context(|| format!("cannot write {}", args.output.display()))?;
    checkpoint.remove()?;
    let info = crate::model::runtime::describe(&blob)?;
    eprintln!(
        "wrote {}: {} poses, k_a {}, k_v {}, alpha {:.3e}, {} bytes",
        args.output.display(),
        poses,
        info.pose_dims,
        info.coef_dims,
        info.alpha,
        info.bytes
    );
    Ok(())
}
