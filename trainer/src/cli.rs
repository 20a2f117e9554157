//! Command-line definitions and dispatch. Each command reads its inputs, calls one library
//! stage after another, and writes its outputs atomically; errors carry the file and item.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::{Args, Parser, Subcommand};

use crate::atomic::write_atomic;
use crate::checkpoint::{Checkpoint, NamedMeshes};
use crate::export::Precision;

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
    /// Train a model from an OBJ sequence and a joint-angle CSV.
    Train(TrainArgs),
    /// Predict transfer for joint angles through aprt-core into a (poses, vertices, n²) .npy.
    Eval(EvalArgs),
    /// Validate a model blob and print its header, dimensions and section sizes.
    Inspect(InspectArgs),
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
    #[arg(long, default_value = "auto")]
    pub alpha: String,
    /// Precision of the large sections.
    #[arg(long, value_enum, default_value_t = Precision::F32)]
    pub precision: Precision,
}

/// `aprt train`.
#[derive(Debug, Args)]
pub struct TrainArgs {
    /// Directory of OBJ files, one per pose, sorted by file name, all with the same vertices.
    #[arg(long)]
    pub obj_seq: PathBuf,
    /// CSV with one row of joint angles per pose (a header row is allowed).
    #[arg(long)]
    pub angles: PathBuf,
    /// Output model file.
    #[arg(short, long)]
    pub output: PathBuf,
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

/// `aprt eval`.
#[derive(Debug, Args)]
pub struct EvalArgs {
    /// The model.
    pub model: PathBuf,
    /// CSV with one row of joint angles per pose.
    #[arg(long)]
    pub angles: PathBuf,
    /// Output .npy file, float32 (poses, vertices, n²).
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
        Command::Demo(args) => crate::demo::run(&args),
        Command::Transfer(args) => transfer(&args),
        Command::Train(args) => train(&args),
        Command::Eval(args) => eval(&args),
        Command::Inspect(args) => inspect(&args),
    }
}

fn read_file(path: &Path) -> Result<Vec<u8>> {
    std::fs::read(path).with_context(|| format!("cannot read {}", path.display()))
}

fn write_npy(path: &Path, shape: &[usize], data: &[f32]) -> Result<()> {
    write_atomic(path, &crate::npy::encode_f32(shape, data))
        .with_context(|| format!("cannot write {}", path.display()))
}

fn inspect(args: &InspectArgs) -> Result<()> {
    let blob = read_file(&args.model)?;
    let info = crate::runtime::describe(&blob)
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
    let info = crate::runtime::describe(&blob)
        .with_context(|| format!("{}: invalid model", args.model.display()))?;
    let poses = crate::angles::read_angles_for(&args.angles, info.joints)?;
    let transfer = crate::runtime::predict_transfer(&blob, &poses)
        .with_context(|| format!("evaluating {}", args.model.display()))?;
    let flat: Vec<f32> = transfer.concat();
    write_npy(
        &args.npy,
        &[poses.len(), info.vertices, info.order * info.order],
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
    pub fn options(&self) -> Result<crate::fit::FitOptions> {
        use crate::fit::{Alpha, CoefDims, Dims, FitOptions};
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
    let mesh = crate::obj::read_obj(&args.mesh)?;
    let settings = bake_settings(&args.bake);
    let transfer = crate::bake::bake_poses(std::slice::from_ref(&mesh), &settings, true)
        .with_context(|| format!("baking {}", args.mesh.display()))?;
    let n2 = settings.order * settings.order;
    write_npy(&args.npy, &[mesh.vertex_count(), n2], &transfer[0])
}

/// The OBJ files of a sequence directory, sorted by file name.
fn obj_sequence(dir: &Path) -> Result<Vec<PathBuf>> {
    let entries = std::fs::read_dir(dir)
        .with_context(|| format!("cannot read directory {}", dir.display()))?;
    let mut files = Vec::new();
    for entry in entries {
        let path = entry
            .with_context(|| format!("cannot list {}", dir.display()))?
            .path();
        if path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("obj"))
        {
            files.push(path);
        }
    }
    files.sort();
    if files.is_empty() {
        bail!("{}: no .obj files", dir.display());
    }
    Ok(files)
}

fn train(args: &TrainArgs) -> Result<()> {
    let options = args.fit.options()?;
    let files = obj_sequence(&args.obj_seq)?;
    let poses = crate::angles::read_angles(&args.angles)?;
    if poses.len() != files.len() {
        bail!(
            "{} has {} rows of angles but {} holds {} OBJ files: one row per pose is needed",
            args.angles.display(),
            poses.len(),
            args.obj_seq.display(),
            files.len()
        );
    }
    let mut meshes = Vec::with_capacity(files.len());
    for file in &files {
        let mesh = crate::obj::read_obj(file)?;
        if let Some(first) = meshes.first() {
            let first: &crate::Mesh = first;
            if mesh.vertex_count() != first.vertex_count() || mesh.triangles != first.triangles {
                bail!(
                    "{}: {} vertices and {} triangles, but {} has {} and {}; every pose must share the same mesh",
                    file.display(),
                    mesh.vertex_count(),
                    mesh.triangles.len(),
                    files[0].display(),
                    first.vertex_count(),
                    first.triangles.len()
                );
            }
        }
        meshes.push(mesh);
    }
    let settings = bake_settings(&args.bake);
    let checkpoint_dir = args
        .checkpoint
        .clone()
        .unwrap_or_else(|| Checkpoint::default_dir(&args.output));
    let mut source = NamedMeshes {
        meshes: &meshes,
        names: &files,
    };
    let mut checkpoint = Checkpoint::open(&checkpoint_dir, args.resume, &settings, &mut source)?;
    let transfers = checkpoint.bake(&mut source, true)?;
    let angles = nalgebra::DMatrix::from_fn(poses.len(), poses[0].len(), |i, j| poses[i][j]);
    let fitted = crate::fit::fit(&angles, &transfers, settings.order, &options)?;
    let blob = crate::export::encode_model(&fitted.model, args.fit.precision)?;
    write_atomic(&args.output, &blob)
        .with_context(|| format!("cannot write {}", args.output.display()))?;
    checkpoint.remove()?;
    let info = crate::runtime::describe(&blob)?;
    eprintln!(
        "wrote {}: {} poses, k_a {}, k_v {}, alpha {:.3e}, {} bytes",
        args.output.display(),
        poses.len(),
        info.pose_dims,
        info.coef_dims,
        info.alpha,
        info.bytes
    );
    Ok(())
}
