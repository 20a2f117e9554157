//! `aprt lightmap`: SH light maps. Bake a clip into a compressed light-map sequence, read it back
//! at the vertices (comparable with `aprt simulate`), inspect it, compose it under lights, and
//! train the pose-driven light-map model.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::{Args, Subcommand};

use crate::bake::shard::Shard;
use crate::cli::args::{BakeArgs, FitArgs, PrecisionArg, parse_rays, parse_resolution};
use crate::cli::source::SourceArgs;
use crate::cli::stdout::outln;
use crate::cli::terminal::Terminal;
use crate::cli::{checkpoint_output, on_existing, read_file, shard_done, write_npy};
use crate::input::InputKind;
use crate::io::atomic::write_atomic;
use crate::io::outputs::{Input, Output, check};
use crate::lightmap::bake::{
    CheckpointSettings, bake_light_map_shard, bake_light_maps, check_atlas,
};
use crate::lightmap::codec::{CodecSettings, encode};
use crate::lightmap::eval::eval_at_vertices;
use crate::lightmap::layout::{AtlasSpec, LightMapUvs};
use crate::lightmap::model::{LightMapFit, LightMapTraining, train_light_maps};
use crate::lightmap::summary::summarize;
use crate::model::ModelFrame;
use crate::progress::Reporter;
use crate::report::lightmap_preview::{ComposeSource, save_preview};
use crate::report::lightmap_study::StudySettings;
use crate::rig::uv::generate::{DEFAULT_HARD_ANGLE_DEG, DEFAULT_MARGIN_TEXELS};

/// `aprt lightmap`.
#[derive(Debug, Args)]
pub struct LightmapArgs {
    /// What to do.
    #[command(subcommand)]
    pub command: LightmapCommand,
}

/// The `aprt lightmap` commands.
#[derive(Debug, Subcommand)]
pub enum LightmapCommand {
    /// Bake every frame of a clip into SH light maps on the character's UV atlas and write the
    /// compressed sequence.
    Bake(LightmapBakeArgs),
    /// Sample a sequence (or a light-map model) at every vertex's UV into a (frames,
    /// vertices, n²) float32 .npy, comparable with `aprt simulate`.
    Eval(LightmapEvalArgs),
    /// Print a sequence's dimensions, sizes and decode time.
    Inspect(LightmapInspectArgs),
    /// Compose a frame's light map under a lights file and write it as a PNG.
    Compose(LightmapComposeArgs),
    /// Bake a clip's light maps and fit the pose-driven light-map model to them.
    Train(LightmapTrainArgs),
    /// Regenerate the light-map comparison on the real glTF characters (docs/results/lightmaps).
    Study(LightmapStudyArgs),
}

/// `aprt lightmap study`.
#[derive(Debug, Args)]
pub struct LightmapStudyArgs {
    /// Output directory (README.md and the previews).
    #[arg(long)]
    pub out: PathBuf,
    /// The assets directory (with gltf/Fox.gltf and gltf/CesiumMan.gltf).
    #[arg(long)]
    pub assets: Option<PathBuf>,
    /// Atlas width and height in texels.
    #[arg(long, default_value_t = 256, value_parser = parse_resolution)]
    pub resolution: usize,
    /// Points spread over each character by area where every method's surface error is read
    /// (each baked on every frame the study measures, as the vertices are). The study also
    /// reports the figure at a quarter as many, which says whether this count is enough.
    #[arg(long, default_value_t = 16384, value_parser = clap::value_parser!(u32).range(4..=4_000_000))]
    pub surface_points: u32,
    /// Simulation settings.
    #[command(flatten)]
    pub bake: BakeArgs,
}

/// Atlas resolution and checkpointing, shared by `bake` and `train`.
#[derive(Debug, Args)]
pub struct AtlasArgs {
    /// Atlas width and height in texels.
    #[arg(long, default_value_t = 256, value_parser = parse_resolution)]
    pub resolution: usize,
    /// Checkpoint directory: every baked frame is saved there until the output is written
    /// (default: OUTPUT.bake beside it).
    #[arg(long)]
    pub checkpoint: Option<PathBuf>,
    /// Continue an interrupted bake from its checkpoint (same inputs and bake settings).
    #[arg(long)]
    pub resume: bool,
    /// Which UVs the light map lies on. `generate` (the default) makes a light-map atlas for
    /// the bind mesh: the texture's islands (or a fresh LSCM + ARAP unwrap) cut at hard edges
    /// (split shading normals, or faces folding by more than --hard-angle) and repacked at
    /// uniform texel density with --margin; the .shlm (or the model's texel atlas) stores it.
    /// It reads back far better on the faceted Fox (8.45 % against 36 % at 256², order 4) and
    /// as well on the smooth CesiumMan (4.42 % against 4.38 %): docs/results/lightmaps.
    /// `texture` uses the character's texture UVs (glTF TEXCOORD_0, OBJ vt), laid out for
    /// painting.
    #[arg(long, value_enum, default_value_t = UvArg::Generate)]
    pub uv: UvArg,
    /// With --uv generate: an edge between faces whose normals are more than this many degrees
    /// apart is cut (Unity's "Generate Lightmap UVs" default).
    #[arg(long, default_value_t = DEFAULT_HARD_ANGLE_DEG, value_name = "DEGREES")]
    pub hard_angle: f32,
    /// With --uv generate: empty texels around each chart (charts are twice this apart); the
    /// default keeps each chart's two gutter rings apart from its neighbours'.
    #[arg(long, default_value_t = DEFAULT_MARGIN_TEXELS, value_name = "TEXELS")]
    pub margin: u32,
}

/// `--uv`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum UvArg {
    /// A light-map atlas generated for the bind mesh.
    Generate,
    /// The character's texture UVs.
    Texture,
}

impl AtlasArgs {
    /// The atlas the flags name.
    pub fn spec(&self) -> AtlasSpec {
        AtlasSpec {
            resolution: self.resolution,
            uvs: match self.uv {
                UvArg::Texture => LightMapUvs::Texture,
                UvArg::Generate => LightMapUvs::Generate {
                    hard_angle_deg: self.hard_angle,
                    margin_texels: self.margin,
                },
            },
        }
    }
}

/// `aprt lightmap bake`.
#[derive(Debug, Args)]
pub struct LightmapBakeArgs {
    /// The character and its clip.
    #[command(flatten)]
    pub source: SourceArgs,
    /// Atlas and checkpoint.
    #[command(flatten)]
    pub atlas: AtlasArgs,
    /// Simulation settings.
    #[command(flatten)]
    pub bake: BakeArgs,
    /// Output sequence file (.shlm).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Bake only shard I of N (frames f with f % N == I, 0-based) into the checkpoint and
    /// stop; when every shard is done, the same command with --resume instead writes the
    /// sequence (see docs/guide/bake-farms.md).
    #[arg(long, value_name = "I/N")]
    pub shard: Option<Shard>,
}

/// `aprt lightmap eval`.
#[derive(Debug, Args)]
pub struct LightmapEvalArgs {
    /// The sequence (.shlm), or a light-map model (.aprt from `aprt lightmap train`).
    pub input: PathBuf,
    /// The character and the clip: for a sequence, the clip it was baked from.
    #[command(flatten)]
    pub source: SourceArgs,
    /// Output .npy file, float32 (frames, vertices, n²).
    #[arg(long)]
    pub npy: PathBuf,
    /// Print the relative transfer error ‖eval − truth‖ / ‖truth‖ against this .npy of the
    /// same shape (the output of `aprt simulate` on the same clip and order).
    #[arg(long)]
    pub against: Option<PathBuf>,
}

/// `aprt lightmap inspect`.
#[derive(Debug, Args)]
pub struct LightmapInspectArgs {
    /// The sequence (.shlm).
    pub input: PathBuf,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

/// `aprt lightmap compose`.
#[derive(Debug, Args)]
pub struct LightmapComposeArgs {
    /// The sequence (.shlm), or a light-map model (.aprt from `aprt lightmap train`).
    pub input: PathBuf,
    /// The character and clip: needed for a model (the pose), optional for a sequence (adds
    /// the character rendered with the light map beside its per-vertex ray-traced shading).
    #[command(flatten)]
    pub source: SourceArgs,
    /// The frame (of the sequence, or of the clip for a model).
    #[arg(long, default_value_t = 0)]
    pub frame: usize,
    /// The lights (TOML, `[[light]]` tables), each texel lit at its bind-pose position.
    #[arg(long)]
    pub lights: PathBuf,
    /// Output PNG.
    #[arg(long)]
    pub png: PathBuf,
    /// Rays per vertex of the per-vertex reference panel.
    #[arg(long, default_value_t = 256, value_parser = parse_rays)]
    pub rays: usize,
}

/// `aprt lightmap train`.
#[derive(Debug, Args)]
pub struct LightmapTrainArgs {
    /// The character and its training clips.
    #[command(flatten)]
    pub source: SourceArgs,
    /// Atlas and checkpoint.
    #[command(flatten)]
    pub atlas: AtlasArgs,
    /// Simulation settings.
    #[command(flatten)]
    pub bake: BakeArgs,
    /// Model shape.
    #[command(flatten)]
    pub fit: FitArgs,
    /// Learn transfer in world space instead of each texel's bone frame (the bone that drives
    /// its triangles most; bone frames generalise better; world frame needs no bone rotations
    /// at runtime).
    #[arg(long)]
    pub world_frame: bool,
    /// Fit an irradiance rig of this kind (constant, gradient, lattice:NXxNYxNZ,
    /// mixed:x=KIND,y=KIND,z=KIND) to the character's bind and training poses, as `aprt train
    /// --rig` does, and store it in the model: `compose` then lights the texels through it.
    #[arg(long)]
    pub rig: Option<crate::irradiance_rig::RigKind>,
    /// Output model file.
    #[arg(short, long)]
    pub output: PathBuf,
}

/// Runs `aprt lightmap`.
pub fn run(args: &LightmapArgs) -> Result<()> {
    match &args.command {
        LightmapCommand::Bake(args) => bake(args),
        LightmapCommand::Eval(args) => eval(args),
        LightmapCommand::Inspect(args) => inspect(args),
        LightmapCommand::Compose(args) => compose(args),
        LightmapCommand::Train(args) => train(args),
        LightmapCommand::Study(args) => study(args),
    }
}

/// What errors about the source call it: the character, or the OBJ sequence's directory.
fn subject(source: &SourceArgs) -> String {
    match &source.obj_seq {
        Some(dir) if !source.names_rig() => format!("the OBJ sequence {}", dir.display()),
        _ => "the character".to_owned(),
    }
}

/// What `bake` and `train` check before any work: the output and the checkpoint are none of
/// the inputs, and the bake settings are valid. Returns the checkpoint directory and settings.
fn prepare(
    atlas: &AtlasArgs,
    output: &std::path::Path,
    source: &SourceArgs,
    bake: &BakeArgs,
) -> Result<(PathBuf, crate::bake::BakeSettings)> {
    let (checkpoint, mut inputs) = checkpoint_output(atlas.checkpoint.as_deref(), output, "-o");
    inputs.extend(source.inputs());
    check(&[Output::file(output, "-o"), checkpoint.clone()], &inputs)?;
    let settings = bake.settings();
    settings.validate()?;
    Ok((checkpoint.path, settings))
}

fn bake(args: &LightmapBakeArgs) -> Result<()> {
    let (checkpoint, settings) = prepare(&args.atlas, &args.output, &args.source, &args.bake)?;
    let (rig, clip) = args.source.light_map_rig(&Terminal)?;
    let what = &subject(&args.source);
    if let Some(shard) = args.shard {
        let baked = args.source.in_origin(bake_light_map_shard(
            rig.as_ref(),
            what,
            &clip,
            args.atlas.spec(),
            &settings,
            (&checkpoint, shard),
            &Terminal,
        ))?;
        shard_done(&baked, "aprt lightmap bake");
        return Ok(());
    }
    let baked = args.source.in_origin(bake_light_maps(
        rig.as_ref(),
        what,
        &clip,
        args.atlas.spec(),
        &settings,
        &CheckpointSettings {
            dir: &checkpoint,
            existing: on_existing(args.atlas.resume),
        },
        &Terminal,
    ))?;
    let bytes = encode(&baked.sequence, &CodecSettings::default())?;
    write_atomic(&args.output, &bytes)
        .with_context(|| format!("cannot write {}", args.output.display()))?;
    let summary = summarize(&bytes)?;
    eprintln!(
        "wrote {}: {} frames of {r}x{r} texels ({} filled), order {}, {} bytes ({:.1}:1 against {} raw), bake {:.1} s, decode {:.2} ms/frame",
        args.output.display(),
        summary.frames,
        summary.filled_texels,
        summary.order,
        summary.bytes,
        summary.ratio,
        summary.raw_bytes,
        baked.seconds,
        summary.decode_ms_per_frame,
        r = summary.resolution,
    );
    Ok(())
}

fn eval(args: &LightmapEvalArgs) -> Result<()> {
    let mut inputs = vec![Input::new(&args.input, "the light maps")];
    inputs.extend(args.source.inputs());
    if let Some(truth) = &args.against {
        inputs.push(Input::new(truth, "--against"));
    }
    check(&[Output::file(&args.npy, "--npy")], &inputs)?;
    // The truth is read first, so a file that cannot be one is refused before any work.
    let truth = args.against.as_deref().map(read_truth).transpose()?;
    let bytes = read_file(&args.input, InputKind::LightMap)?;
    let (rig, clip) = args.source.light_map_rig(&Terminal)?;
    let name = args.input.display().to_string();
    let (flat, shape) = eval_at_vertices(&name, &bytes, rig.as_ref(), &clip, &Terminal)?;
    if let (Some(path), Some((truth_shape, _))) = (&args.against, &truth)
        && truth_shape != &shape
    {
        bail!(
            "--against {}: the shape is {truth_shape:?}, the evaluation's {shape:?}",
            path.display()
        );
    }
    write_npy(&args.npy, &shape, &flat)?;
    if let (Some(path), Some((_, truth))) = (&args.against, truth) {
        let error = crate::report::evaluate::relative_error(&[flat], &[truth]);
        outln!(
            "relative transfer error against {}: {:.2}%",
            path.display(),
            100.0 * error
        )?;
    }
    Ok(())
}

/// The `--against` array: its shape and values, every value finite (a NaN made the error
/// "NaN%").
fn read_truth(path: &Path) -> Result<(Vec<usize>, Vec<f32>)> {
    let (shape, values) = crate::io::npy::decode_f32(&read_file(path, InputKind::Npy)?)
        .with_context(|| format!("--against {}", path.display()))?;
    if let Some(i) = values.iter().position(|v| !v.is_finite()) {
        bail!(
            "--against {}: value {i} (index {:?}) is {}: the truth must be finite",
            path.display(),
            unravel(i, &shape),
            values[i]
        );
    }
    Ok((shape, values))
}

/// The C-order index of the flat position `i` in an array of `shape`.
fn unravel(mut i: usize, shape: &[usize]) -> Vec<usize> {
    let mut index = vec![0; shape.len()];
    for (slot, &d) in index.iter_mut().zip(shape).rev() {
        *slot = i % d;
        i /= d;
    }
    index
}

fn inspect(args: &LightmapInspectArgs) -> Result<()> {
    check(&[], &[Input::new(&args.input, "the sequence")])?;
    let bytes = read_file(&args.input, InputKind::LightMap)?;
    let summary =
        summarize(&bytes).with_context(|| format!("{}: invalid sequence", args.input.display()))?;
    if args.json {
        outln!("{}", serde_json::to_string_pretty(&summary)?)?;
        return Ok(());
    }
    let s = &summary;
    outln!("{}", args.input.display())?;
    outln!(
        "  {} frames, {r}x{r} texels ({} filled), SH order {}",
        s.frames,
        s.filled_texels,
        s.order,
        r = s.resolution
    )?;
    outln!(
        "  {} bytes, {:.1}:1 against {} bytes of f32 maps",
        s.bytes,
        s.ratio,
        s.raw_bytes
    )?;
    outln!("  codec: {}", s.codec)?;
    match s.uv_triangles {
        0 => outln!("  UVs: the character's texture UVs")?,
        t => outln!("  UVs: generated light-map UVs of {t} triangles, stored in the file")?,
    }
    outln!(
        "  decode: {:.3} ms per frame ({:.1}x a copy of the frame's f32 maps, {:.3} ms)",
        s.decode_ms_per_frame,
        s.decode_ms_per_frame / s.memcpy_ms_per_frame.max(1e-9),
        s.memcpy_ms_per_frame
    )?;
    Ok(())
}

fn compose(args: &LightmapComposeArgs) -> Result<()> {
    let mut inputs = vec![
        Input::new(&args.input, "the light maps"),
        Input::new(&args.lights, "the lights file"),
    ];
    inputs.extend(args.source.inputs());
    check(&[Output::file(&args.png, "--png")], &inputs)?;
    let bytes = read_file(&args.input, InputKind::LightMap)?;
    let lights = crate::lighting::read_lights(&args.lights)?;
    let character = if args.source.names_light_map_source() {
        Some(args.source.light_map_rig(&Terminal)?)
    } else {
        None
    };
    let name = args.input.display().to_string();
    if let Some((rig, _)) = &character
        && bytes.starts_with(crate::lightmap::codec::MAGIC)
    {
        check_atlas(&name, &bytes, rig.as_ref(), &Terminal)?;
    }
    let source = ComposeSource {
        name: &name,
        bytes: &bytes,
        character: character.as_ref().map(|(rig, clip)| (rig.as_ref(), clip)),
        frame: args.frame,
        rays: args.rays,
    };
    let report = save_preview(&args.png, &source, &lights)?;
    eprintln!("wrote {}: {report}", args.png.display());
    Ok(())
}

fn train(args: &LightmapTrainArgs) -> Result<()> {
    let (checkpoint, settings) = prepare(&args.atlas, &args.output, &args.source, &args.bake)?;
    args.fit
        .check_proxies(Some("light-map models carry no occluder proxies".into()))?;
    let fit = args.fit.options()?;
    let (rig, clips) = args.source.light_map_source(&Terminal)?;
    let what = &subject(&args.source);
    // Meshes read from files have no bones, so their texels are learned in world space, as
    // `aprt train` learns their vertices.
    let frame = if args.world_frame {
        ModelFrame::World
    } else if !args.source.names_rig() {
        Terminal.note(&format!(
            "note: {what} has no skin: its texels are learned in world space (as with --world-frame)"
        ));
        ModelFrame::World
    } else {
        ModelFrame::Bone
    };
    let training = LightMapTraining {
        atlas: args.atlas.spec(),
        bake: settings,
        model: LightMapFit {
            options: &fit,
            precision: PrecisionArg::into(args.fit.precision),
            frame,
        },
        checkpoint: CheckpointSettings {
            dir: &checkpoint,
            existing: on_existing(args.atlas.resume),
        },
        irradiance_rig: args.rig,
    };
    let trained = args.source.in_origin(train_light_maps(
        rig.as_ref(),
        what,
        clips,
        &training,
        &Terminal,
    ))?;
    write_atomic(&args.output, &trained.blob)
        .with_context(|| format!("cannot write {}", args.output.display()))?;
    let info = &trained.info;
    let rig = match &info.irradiance_rig {
        Some(rig) => format!(", {} irradiance rig", rig.kind),
        None => String::new(),
    };
    eprintln!(
        "wrote {}: {} frames, {} texel rows in {}{rig}, k_a {}, k_v {}, alpha {:.3e}, {} bytes (bake {:.1} s, fit {:.1} s)",
        args.output.display(),
        trained.frames,
        info.vertices,
        match info.bones {
            0 => "world space".to_owned(),
            n => format!("the frames of {n} bones"),
        },
        info.pose_dims,
        info.coef_dims,
        info.alpha,
        info.bytes,
        trained.seconds.0,
        trained.seconds.1,
    );
    Ok(())
}

fn study(args: &LightmapStudyArgs) -> Result<()> {
    let assets = args
        .assets
        .clone()
        .unwrap_or_else(crate::report::results::default_assets);
    check(
        // Inputs are files of the assets directory, which the output may not lie inside.
        &[Output::directory(&args.out, "--out", &[])],
        &[Input::new(&assets, "the assets directory")],
    )?;
    let bake = args.bake.settings();
    bake.validate()?;
    let command = format!(
        "cargo run --release -p aprt-trainer --bin aprt -- lightmap study --out {} --resolution {} --order {} --rays {} --surface-points {}",
        args.out.display(),
        args.resolution,
        bake.order,
        bake.rays,
        args.surface_points,
    );
    let settings = StudySettings {
        resolution: args.resolution,
        bake: &bake,
        surface_points: args.surface_points as usize,
    };
    let path =
        crate::report::lightmap_study::run(&assets, &args.out, &settings, &command, &Terminal)?;
    eprintln!("wrote {}", path.display());
    Ok(())
}
