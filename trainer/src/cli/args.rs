//! The command line's arguments, and the library settings each asks for.

use std::path::PathBuf;

use anyhow::{Result, bail};
use clap::Args;

use crate::bake::BakeSettings;
use crate::cli::source::SourceArgs;
#[cfg(doc)]
use crate::model::export::ExportError;
use crate::model::export::Precision;
use crate::model::fit::{Alpha, CoefDims, Dims, Features, FitOptions, Local, Prior};
use crate::model::occluders::Occluders;
use crate::pipeline::train::{OptionError, check_options};
use crate::report::demo::DemoSettings;
use crate::rig::pose_sampler::DEFAULT_VALIDATION_POSES;
use crate::surface::DEFAULT_SURFACE_POINTS;

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
    #[arg(long, default_value_t = 128, value_parser = parse_rays)]
    pub rays: usize,
    /// Validation poses per study, sampled as `aprt train --validation-poses` samples them,
    /// baked and used to choose each model by (0: held-out runs of the training clip).
    #[arg(long, value_name = "N", default_value_t = DEFAULT_VALIDATION_POSES)]
    pub validation_poses: usize,
    /// Run only this study (repeatable: `cesiumman`, `riggedfigure`, `riggedsimple`, `fox`,
    /// `cmu`), for experiments: the document then holds only their sections.
    #[arg(long, value_name = "ID")]
    pub study: Vec<String>,
}

/// `aprt report`.
#[derive(Debug, Args)]
pub struct ReportArgs {
    /// The scene file (see fixtures/scenes/); its `test` clips are what the report measures on.
    pub scene: PathBuf,
    /// Refuse any path the scene names that is absolute or leaves the scene's directory
    /// (symlinks followed), for scenes from users (also the scene key `confine`).
    #[arg(long)]
    pub confine: bool,
    /// Output directory for report.md, report.json and the Pareto plots (PNG and SVG).
    #[arg(long)]
    pub out: PathBuf,
    /// Microseconds per frame the recommendation may cost (default: the scene's `[budget]`).
    #[arg(long, allow_negative_numbers = true)]
    pub budget_us: Option<f64>,
    /// Bytes the recommended model may take (default: the scene's `[budget]`).
    #[arg(long)]
    pub budget_bytes: Option<u64>,
    /// Write the recommended model here.
    #[arg(long)]
    pub write_model: Option<PathBuf>,
    /// Use every k-th frame of every clip (1 = all; larger is faster).
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u64).range(1..))]
    pub stride: u64,
    /// Validation poses sampled from the training frames, baked with every bake of the sweep
    /// and used to choose each setting's model by, as `aprt train --scene` does (0: the
    /// scene's validation clips, or held-out runs of the training frames).
    #[arg(long, value_name = "N", default_value_t = DEFAULT_VALIDATION_POSES)]
    pub validation_poses: usize,
    /// Points spread over the character's surface by area, where every setting's surface
    /// error is measured (the method read there as a renderer shows it) beside the vertex
    /// error; their transfer is baked on every test frame at the reference settings.
    #[arg(long, value_name = "N", default_value_t = DEFAULT_SURFACE_POINTS, value_parser = clap::value_parser!(u64).range(1..))]
    pub surface_points: u64,
}

/// `aprt irradiance-rig-study`.
#[derive(Debug, Args)]
pub struct RigStudyArgs {
    /// Output directory for README.md, results.json and the PNG figures.
    #[arg(long, default_value = "docs/rigs")]
    pub out: PathBuf,
    /// SH order of the lighting.
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u8).range(1..=6))]
    pub order: u8,
}

/// `aprt demo`.
#[derive(Debug, Args)]
pub struct DemoArgs {
    /// Output directory for model.aprt, report.md, report.json and the PNG renders.
    #[arg(long, default_value = "aprt-demo")]
    pub out: PathBuf,
    /// SH order of the demo model (default: the order the built-in scene's lighting needs).
    #[arg(long, value_parser = clap::value_parser!(u8).range(1..=6))]
    pub order: Option<u8>,
    /// Directions per vertex for the ground-truth bakes (default: the built-in scene's, 128).
    #[arg(long, value_parser = parse_rays)]
    pub rays: Option<usize>,
    /// Use every k-th frame of the clips (1 = all 250 training frames; larger is faster).
    #[arg(long, default_value_t = 2)]
    pub stride: usize,
    /// Validation poses sampled from the training frames as `aprt train --validation-poses`
    /// samples them, baked and used with the `stretch` clip to choose each model by.
    #[arg(long, value_name = "N", default_value_t = DEFAULT_VALIDATION_POSES)]
    pub validation_poses: usize,
}

/// Simulation settings shared by the commands that bake.
#[derive(Debug, Clone, Args)]
pub struct BakeArgs {
    /// SH order n (n² coefficients per vertex).
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u8).range(1..=6))]
    pub order: u8,
    /// Directions per vertex (low-discrepancy, cosine-weighted).
    #[arg(long, default_value_t = 256, value_parser = parse_rays)]
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
    /// What the model tends to as α grows: `auto` (the one of the two below with the lower
    /// held-out error, the rest prior only when the rest pose lies within 2 standard
    /// deviations of the training poses; the default), `rest` (the rest pose's transfer
    /// carried by the skin, for bone-frame models; others keep the mean) or `mean`.
    #[arg(long, value_enum)]
    pub prior: Option<PriorArg>,
    /// Bounded extrapolation: poses are clamped into the training range and reach the prior
    /// this many range widths outside it (`none`: the paper's unbounded linear model; default
    /// 0.5, or none with `--paper`).
    #[arg(long)]
    pub falloff: Option<String>,
    /// The local model of bone-frame models (each vertex depends only on the pose entries
    /// that move geometry within a tenth of the character's diagonal of it, through the rest
    /// pose): `auto` (a candidate of the selection; the default), `only`, or `none` (the
    /// default with `--paper`).
    #[arg(long, value_enum)]
    pub local: Option<LocalArg>,
    /// The pose features the model is linear in: `angles` (the default), `cosines` (each angle
    /// a and 1 − cos a, for shadowing that is the same whichever way a joint turns) or `auto`
    /// (the one of the two with the lower held-out error).
    #[arg(long, value_enum)]
    pub features: Option<FeaturesArg>,
    /// Occluder proxies for bone-frame models of characters (spheres fitted per bone that
    /// shadow other parts in poses the training never showed; the model learns the rest):
    /// `auto` (fitted with and without, the lower held-out error wins; the default), `on`, or
    /// `none` (the model alone; the default with `--paper`).
    #[arg(long, value_enum)]
    pub proxies: Option<ProxiesArg>,
    /// The paper's model: every pose dimension, the mean as prior, no bound, no local model,
    /// no proxies, the angles as features (other flags may still change its shape).
    #[arg(long, conflicts_with_all = ["prior", "local", "features", "proxies"])]
    pub paper: bool,
    /// Precision of the large sections.
    #[arg(long, value_enum, default_value_t = PrecisionArg::F32)]
    pub precision: PrecisionArg,
}

/// `--prior`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum PriorArg {
    /// Whichever of the two has the lower held-out error.
    Auto,
    /// The rest pose's transfer, carried by the skin.
    Rest,
    /// The mean training transfer.
    Mean,
}

/// `--local`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum LocalArg {
    /// A candidate, kept when its held-out error is lower.
    Auto,
    /// The only candidate.
    Only,
    /// Not tried.
    None,
}

/// `--proxies`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ProxiesArg {
    /// Fitted with and without, kept when the held-out error is lower.
    Auto,
    /// Always.
    On,
    /// Never.
    None,
}

/// `--features`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum FeaturesArg {
    /// Whichever of the two has the lower held-out error.
    Auto,
    /// The angles and their cosines.
    Cosines,
    /// The angles alone.
    Angles,
}

/// `aprt train`.
#[derive(Debug, Args)]
pub struct TrainArgs {
    /// A scene file (see fixtures/scenes/): its character, clips, effects, error target and
    /// lighting decide what is baked and how the model is stored; only what the scene calls
    /// for is computed. Replaces the source, bake, --rig, --precision and --world-frame flags.
    #[arg(long, conflicts_with_all = [
        "obj_seq", "angles", "builtin", "character", "gltf", "bvh", "clip", "fps", "frames",
        "mannequin", "no_hat", "root_translation", "validate", "world_frame", "order", "rays",
        "bounces", "albedo", "rig", "precision",
    ])]
    pub scene: Option<PathBuf>,
    /// With --scene: refuse any path the scene names that is absolute or leaves the scene's
    /// directory (symlinks followed), for scenes from users (also the scene key `confine`).
    #[arg(long, requires = "scene")]
    pub confine: bool,
    /// With --scene: write what was computed and skipped, what the full simulation would have
    /// cost, and the model's µs a frame against the scene's `[budget]`, as JSON (keys rays_cast,
    /// bounce_passes, sh_order, skipped, seconds, us_per_frame, within_budget, …).
    #[arg(long, requires = "scene")]
    pub report: Option<PathBuf>,
    /// The training poses.
    #[command(flatten)]
    pub source: SourceArgs,
    /// Output model file.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Hold this clip out of training and choose the model (prior, α, k_a and, with --features auto, the features) by its error: a
    /// clip name (--builtin, --gltf), or for --bvh frames A..B of the first file or another
    /// BVH file. Repeat for several; without it, segments of the training clips are held out.
    #[arg(long, value_name = "CLIP")]
    pub validate: Vec<String>,
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
    /// Fit an irradiance rig of this kind (constant, gradient, lattice:NXxNYxNZ,
    /// mixed:x=KIND,y=KIND,z=KIND) to the character's bind and training poses and store it in
    /// the model, so an engine lights it from a handful of SH vectors (see `aprt irradiance-rig`).
    #[arg(long)]
    pub rig: Option<crate::irradiance_rig::RigKind>,
    /// Bake only shard I of N (frames f with f % N == I, 0-based) into the checkpoint and
    /// stop; when every shard is done, the same command with --resume instead fits the model
    /// (see docs/guide/bake-farms.md).
    #[arg(long, value_name = "I/N")]
    pub shard: Option<crate::bake::shard::Shard>,
    /// Add N training poses, each a random training frame with 1 to 3 random joints re-drawn
    /// uniformly within the range each entry takes over the training clips (and, for the
    /// built-in characters, their joint limits); fixed seed, baked as the training part
    /// `sampled`. Characters only; 0 (the default) adds none.
    #[arg(long, value_name = "N", default_value_t = 0, conflicts_with = "scene")]
    pub sample_poses: usize,
    /// Sample N validation poses from the training frames (as --sample-poses samples, with
    /// another seed and up to 15 % of each entry's range beyond it, within the joint limits),
    /// bake them with the same settings and choose the model by them, after any --validate
    /// clip; never trained on. Default 64 for a character, none for an OBJ sequence (which
    /// refuses a count); 0 chooses by held-out runs of the training frames alone.
    #[arg(long, value_name = "N")]
    pub validation_poses: Option<usize>,
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
    /// Output .npy file, float32 (frames, vertices, n²); with --surface N, (frames, N, n²).
    #[arg(long)]
    pub npy: PathBuf,
    /// Bake N points spread over the bind surface by area instead of the vertices: each
    /// triangle gets its share of N by area, evenly spread inside it, and every point rides
    /// the skin (the same blend of its triangle's corners in every pose). The truth a
    /// renderer's per-vertex interpolation or light map is judged against between the
    /// vertices. Baked through a checkpoint, like `aprt train`'s, so --resume and --shard
    /// apply.
    #[arg(long, value_name = "N", value_parser = parse_surface_points)]
    pub surface: Option<usize>,
    /// With --surface: also write the points to this .npy, float32 (N, 5), one row per point
    /// in the order of --npy's: column 0 its triangle's index in the bind mesh (exact in
    /// float32 below 2^24 triangles), columns 1–3 its barycentric coordinates (the weights of
    /// the triangle's first, second and third corner, summing to 1), column 4 the share of the
    /// bind surface's area it stands for (the column sums to 1). Evaluate any method at these
    /// points to compare it with the truth there. Written with --npy (a --shard run writes
    /// neither).
    #[arg(long, value_name = "FILE.npy")]
    pub points: Option<PathBuf>,
    /// With --surface: checkpoint directory, every baked frame is saved there until the .npy
    /// is written (default: the --npy path + .bake).
    #[arg(long)]
    pub checkpoint: Option<PathBuf>,
    /// With --surface: continue an interrupted bake from its checkpoint (same inputs, points
    /// and bake settings).
    #[arg(long)]
    pub resume: bool,
    /// With --surface: bake only shard I of N (frames f with f % N == I, 0-based) into the
    /// checkpoint and stop; when every shard is done, the same command with --resume instead
    /// writes the .npy (see docs/guide/bake-farms.md).
    #[arg(long, value_name = "I/N")]
    pub shard: Option<crate::bake::shard::Shard>,
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

/// `aprt export-web`.
#[derive(Debug, Args)]
pub struct ExportWebArgs {
    /// The model.
    pub model: PathBuf,
    /// The clip the page plays: a clip of the model's character.
    #[command(flatten)]
    pub source: SourceArgs,
    /// Output directory (manifest.json, clip.bin, model.aprt), for example web/data.
    #[arg(long)]
    pub out: PathBuf,
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

/// `aprt light`.
#[derive(Debug, Args)]
pub struct LightArgs {
    /// What to compute.
    #[command(subcommand)]
    pub command: LightCommand,
}

/// The `aprt light` commands.
#[derive(Debug, clap::Subcommand)]
pub enum LightCommand {
    /// Irradiance at a point from a lights file, through SH and exactly (unshadowed).
    Irradiance(IrradianceArgs),
    /// Project an equirectangular .hdr or .exr environment map to SH radiance.
    Env(EnvArgs),
}

/// `aprt light env`.
#[derive(Debug, Args)]
pub struct EnvArgs {
    /// The map: equirectangular, .hdr (Radiance RGBE) or .exr (OpenEXR), row 0 at +Y, the
    /// centre column facing +X (three.js's and Blender's convention).
    pub file: PathBuf,
    /// SH order of the projection (order² RGB coefficients).
    #[arg(long, value_parser = clap::value_parser!(u8).range(1..=6))]
    pub order: u8,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

/// `aprt light irradiance`.
#[derive(Debug, Args)]
pub struct IrradianceArgs {
    /// The lights file (`[[light]]` tables; see fixtures/lights/).
    pub lights: PathBuf,
    /// The point, X,Y,Z.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub at: [f32; 3],
    /// The surface normal, X,Y,Z (any non-zero length).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub normal: [f32; 3],
    /// SH order of the SH path.
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u8).range(1..=6))]
    pub order: u8,
    /// Window each light's SH radiance against ringing (costs accuracy; see `aprt_core::Window`).
    #[arg(long, value_enum)]
    pub dering: Option<DeringArg>,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

/// `aprt irradiance-rig`.
#[derive(Debug, Args)]
pub struct RigArgs {
    /// A static mesh (OBJ); or name a character with the source flags instead: the rig is
    /// fitted over its bind pose and up to 24 frames of the clips given (name its training
    /// clip to fit as `train --rig` does), and frame --frame of them is evaluated.
    pub mesh: Option<PathBuf>,
    /// The character, when no mesh is given.
    #[command(flatten)]
    pub source: SourceArgs,
    /// Frame of the clip to evaluate on (characters only).
    #[arg(long, default_value_t = 0)]
    pub frame: usize,
    /// The lights file (`[[light]]` tables; see fixtures/lights/).
    #[arg(long)]
    pub lights: PathBuf,
    /// Rig kind: constant, gradient, lattice:NXxNYxNZ or mixed:x=KIND,y=KIND,z=KIND (KIND
    /// constant, gradient or latticeN), over the character's own axes.
    #[arg(long)]
    pub rig: crate::irradiance_rig::RigKind,
    /// The error a light may cost the rig before it is evaluated per vertex, in 8-bit grey
    /// levels (of a white Lambertian surface, radiance 1 = white).
    #[arg(long, default_value_t = 1.0)]
    pub target_error: f32,
    /// SH order of the lighting.
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u8).range(1..=6))]
    pub order: u8,
    /// Surface samples of the fit (default 6 per SH vector, at least 64).
    #[arg(long)]
    pub samples: Option<usize>,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

/// `--dering`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum DeringArg {
    /// `(1 + cos(π l / n))/2`.
    Hann,
    /// `sin(π l / n)/(π l / n)`.
    Lanczos,
}

impl From<DeringArg> for aprt_core::Window {
    fn from(arg: DeringArg) -> aprt_core::Window {
        match arg {
            DeringArg::Hann => aprt_core::Window::Hann,
            DeringArg::Lanczos => aprt_core::Window::Lanczos,
        }
    }
}

/// `--rays`: directions per vertex, 1 to [`MAX_RAYS`] (0 was refused by the bake, naming no
/// flag).
///
/// [`MAX_RAYS`]: crate::limits::MAX_RAYS
pub fn parse_rays(text: &str) -> std::result::Result<usize, String> {
    let max = crate::limits::MAX_RAYS;
    match text.parse::<usize>() {
        Ok(rays) if (1..=max).contains(&rays) => Ok(rays),
        _ => Err(format!("expected 1 to {max} directions per vertex")),
    }
}

/// `--surface`: at least one point (an upper bound is the run's budget, checked with the
/// character's frames).
pub fn parse_surface_points(text: &str) -> std::result::Result<usize, String> {
    match text.parse::<usize>() {
        Ok(points) if points >= 1 => Ok(points),
        _ => Err("expected a whole number of surface points, 1 or more".to_owned()),
    }
}

/// `--resolution`: a light-map atlas of 1 to [`MAX_RESOLUTION`] texels a side (0 was refused
/// blaming `--margin`).
///
/// [`MAX_RESOLUTION`]: crate::rig::uv::MAX_RESOLUTION
pub fn parse_resolution(text: &str) -> std::result::Result<usize, String> {
    let max = crate::rig::uv::MAX_RESOLUTION;
    match text.parse::<usize>() {
        Ok(texels) if (1..=max).contains(&texels) => Ok(texels),
        _ => Err(format!("expected 1 to {max} texels a side")),
    }
}

/// Three finite numbers separated by commas.
fn parse_vec3(text: &str) -> std::result::Result<[f32; 3], String> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    let [x, y, z] = parts[..] else {
        return Err(format!("expected X,Y,Z, got {} values", parts.len()));
    };
    let mut out = [0.0f32; 3];
    for (o, p) in out.iter_mut().zip([x, y, z]) {
        *o = p
            .parse::<f32>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| format!("{p:?} is not a finite number"))?;
    }
    Ok(out)
}

/// Precision of a model's large sections (weights and per-vertex rows), as `--precision`
/// names it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum PrecisionArg {
    /// 4 bytes per value.
    F32,
    /// 2 bytes per value, about 3 significant digits: IEEE half, rounded to nearest, so the
    /// stored value is within 2⁻¹¹ relative of the f64 one above 6.1e-5 and within 2⁻²⁵ ≈ 3e-8
    /// absolute below (subnormals; smaller values become 0). Values beyond ±65504 are refused
    /// with [`ExportError::NotRepresentable`], never clamped.
    F16,
    /// 1 byte per per-vertex value plus one f32 scale per vector (`s = max |v| / 127`), the
    /// weights f32: each value within `s / 2` of the f64 one, so shading under lighting
    /// weights `w_k` is within `Σ_k |w_k| s_k / 2` of the f32 model's.
    I8,
}

impl From<PrecisionArg> for Precision {
    fn from(arg: PrecisionArg) -> Precision {
        match arg {
            PrecisionArg::F32 => Precision::F32,
            PrecisionArg::F16 => Precision::F16,
            PrecisionArg::I8 => Precision::I8,
        }
    }
}

impl DemoArgs {
    /// The demo settings these flags ask for; a stride of 0 is refused.
    pub fn settings(&self) -> Result<DemoSettings> {
        if self.stride == 0 {
            bail!(
                "--stride 0: the demo uses every k-th frame, so k must be at least 1 (1 = every frame)"
            );
        }
        Ok(DemoSettings {
            out: self.out.clone(),
            order: self.order.map(usize::from),
            rays: self.rays,
            stride: self.stride,
            validation_poses: self.validation_poses,
        })
    }
}

impl BakeArgs {
    /// The bake settings these flags ask for.
    pub fn settings(&self) -> BakeSettings {
        BakeSettings {
            order: self.order as usize,
            rays: self.rays,
            bounces: self.bounces,
            albedo: self.albedo,
            shadows: true,
        }
    }
}

impl FitArgs {
    /// Refuses `--proxies on` where the model cannot carry occluder proxies: `without` says
    /// why, naming the flag or key at fault. Left alone, the model was written without them and
    /// without a word.
    pub fn check_proxies(&self, without: Option<String>) -> Result<()> {
        match (self.proxies, without) {
            (Some(ProxiesArg::On), Some(why)) => bail!("--proxies on: {why}"),
            _ => Ok(()),
        }
    }

    /// The fit options these flags ask for; unset flags keep the defaults.
    pub fn options(&self) -> Result<FitOptions> {
        let mut options = if self.paper {
            FitOptions::paper()
        } else {
            FitOptions::default()
        };
        options.prior = match self.prior {
            None => options.prior,
            Some(PriorArg::Auto) => Prior::Auto,
            Some(PriorArg::Rest) => Prior::Rest,
            Some(PriorArg::Mean) => Prior::Mean,
        };
        options.local = match self.local {
            None => options.local,
            Some(LocalArg::Auto) => Local::Auto,
            Some(LocalArg::Only) => Local::Only,
            Some(LocalArg::None) => Local::Off,
        };
        options.proxies = match self.proxies {
            None => options.proxies,
            Some(ProxiesArg::Auto) => Occluders::Auto,
            Some(ProxiesArg::On) => Occluders::On,
            Some(ProxiesArg::None) => Occluders::None,
        };
        options.features = match self.features {
            None => options.features,
            Some(FeaturesArg::Auto) => Features::Auto,
            Some(FeaturesArg::Cosines) => Features::Cosines,
            Some(FeaturesArg::Angles) => Features::Angles,
        };
        options.bound = match self.falloff.as_deref() {
            None => options.bound,
            Some("none") => None,
            Some(other) => match other.parse::<f64>() {
                Ok(x) if x > 0.0 && !x.is_nan() => Some(x),
                _ => {
                    bail!("--falloff {other}: expected a positive number (inf: clamp only) or none")
                }
            },
        };
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
        check_options(&options).map_err(|e| {
            let flag = match &e {
                OptionError::PoseDims(k) => format!("--pose-dims {k}"),
                OptionError::PoseFraction(f) => format!("--pose-variance {f}"),
                OptionError::NoCoefDims | OptionError::CoefDims(_) => {
                    format!("--coef-dims {}", self.coef_dims.unwrap_or_default())
                }
                OptionError::CoefFraction(f) => format!("--coef-variance {f}"),
                OptionError::Alpha(_) => format!("--alpha {}", self.alpha),
            };
            anyhow::Error::from(e).context(flag)
        })?;
        Ok(options)
    }
}
