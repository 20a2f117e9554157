//! The light-map comparison (`aprt lightmap study`, docs/results/lightmaps): on the real glTF
//! characters, SH light maps stored as a compressed sequence, the pose-driven light-map model
//! (world and bone frames) and the per-vertex pose model, on the same clips — bytes, bake and
//! fit time, decode or evaluation time per frame, and error on the training clip and on a
//! novel one (where the stored sequence can only fall back to its nearest frame), each at the
//! vertices and on the whole surface ([`surface`]: points spread by area, every method read
//! there as an engine shows it), with a picture per method drawn from the surface points.

mod picture;
pub mod surface;

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result};

use crate::bake::BakeSettings;
use crate::bake::checkpoint::OnExisting;
use crate::lightmap::bake::{BakedMaps, CheckpointSettings, bake_light_maps};
use crate::lightmap::codec::{CodecSettings, ShlmFile, encode};
use crate::lightmap::layout::{AtlasSpec, LightMapUvs};
use crate::lightmap::model::{LightMapFit, fit_light_maps, predict_maps};
use crate::lightmap::sample::maps_at_vertices;
use crate::model::ModelFrame;
use crate::model::export::{Precision, encode_model};
use crate::model::fit::FitOptions;
use crate::model::predict::predict_clip;
use crate::model::runtime::describe;
use crate::pipeline::train::{ClipSet, fit_clip};
use crate::progress::Reporter;
use crate::report::evaluate::{nearest_pose, relative_error};
use crate::rig::pose_layout::PoseLayout;
use crate::rig::{Clip, Rig};
use crate::surface::SurfacePoints;
use crate::surface::error::Accuracy;

use picture::{PictureOf, save_surface_picture};
use surface::{ClipTruth, Probe, bake_surface, clip_truth, luminance_sh};

/// What the study measures with: the atlas size, the simulation (one for the vertices, the
/// texels and the surface points) and how many surface points the surface error is read at.
#[derive(Clone, Copy, Debug)]
pub struct StudySettings<'a> {
    /// Atlas width and height in texels.
    pub resolution: usize,
    /// The simulation.
    pub bake: &'a BakeSettings,
    /// Surface points spread over each character.
    pub surface_points: usize,
}

/// One character of the study: the clip the stored representations are made from and a novel
/// clip they are tested on.
pub struct LightMapCase {
    /// Heading.
    pub title: String,
    /// The character.
    pub rig: Box<dyn Rig>,
    /// The clip baked, stored and trained on.
    pub train: Clip,
    /// The novel clip.
    pub test: Clip,
}

/// One row of a case's table.
struct Row {
    method: &'static str,
    bytes: usize,
    bake_s: f64,
    fit_s: Option<f64>,
    ms_per_frame: f64,
    train: Errors,
    test: Errors,
}

/// A method's error on one clip: relative transfer error at the vertices, and at the surface
/// points (with its grey levels under the preview lights).
#[derive(Clone, Copy, Debug)]
struct Errors {
    vertices: f64,
    surface: Accuracy,
}

/// A method's prediction of every frame of a clip, at the vertices and at the surface points,
/// `n2` values each.
struct Prediction {
    vertices: Vec<Vec<f32>>,
    points: Vec<Vec<f32>>,
    n2: usize,
}

impl Prediction {
    /// Frame `frames[i]` of this prediction as frame `i`: the stored sequence on a novel clip,
    /// falling back to its nearest stored frame.
    fn frames(&self, frames: &[usize]) -> Prediction {
        Prediction {
            vertices: frames.iter().map(|&k| self.vertices[k].clone()).collect(),
            points: frames.iter().map(|&k| self.points[k].clone()).collect(),
            n2: self.n2,
        }
    }
}

/// A case's two clips' truths and where methods are read at the surface.
struct Truths<'a> {
    train: &'a ClipTruth,
    test: &'a ClipTruth,
    probe: &'a Probe<'a>,
}

impl Truths<'_> {
    /// `pred`'s error against `truth`, one of this case's clips.
    fn errors(&self, pred: &Prediction, truth: &ClipTruth) -> Errors {
        Errors {
            vertices: relative_error(&pred.vertices, &truth.vertices.transfer),
            surface: self.probe.error(&pred.points, pred.n2, &truth.surface),
        }
    }

    /// Maps (`resolution`² × `n2` each) laid out as the probe's UVs, read at the vertices and
    /// at the surface points.
    fn read_maps(&self, rig: &dyn Rig, baked: &BakedMaps, maps: &[Vec<f32>]) -> Prediction {
        let (r, n2) = (baked.sequence.resolution, baked.sequence.order.pow(2));
        Prediction {
            vertices: maps_at_vertices(rig, &baked.layout, maps, r, n2),
            points: self.probe.of_maps(maps, r, n2),
            n2,
        }
    }
}

/// The stored sequence: encode, decode every frame (timed), read at the vertices and at the
/// surface points; on the novel clip each frame takes the nearest stored frame's map.
fn sequence_rows(case: &LightMapCase, baked: &BakedMaps, truths: &Truths<'_>) -> Result<Vec<Row>> {
    let seq = &baked.sequence;
    let bytes = encode(seq, &CodecSettings::default())?;
    let file = ShlmFile::parse(&bytes)?;
    let start = Instant::now();
    let decoded = file.decode_all()?;
    let decode_ms = start.elapsed().as_secs_f64() * 1e3 / file.frames().max(1) as f64;
    let nearest: Vec<usize> = (truths.test.vertices.angles.iter())
        .map(|a| nearest_pose(&truths.train.vertices.angles, a))
        .collect();
    let mut rows = Vec::new();
    for (method, maps, size, ms) in [
        (
            "SH light maps, f32 sequence",
            &seq.frames,
            file.raw_bytes() as usize,
            0.0,
        ),
        (
            "SH light maps, compressed sequence",
            &decoded,
            bytes.len(),
            decode_ms,
        ),
    ] {
        let on_train = truths.read_maps(case.rig.as_ref(), baked, maps);
        let on_test = on_train.frames(&nearest);
        rows.push(Row {
            method,
            bytes: size,
            bake_s: baked.seconds,
            fit_s: None,
            ms_per_frame: ms,
            train: truths.errors(&on_train, truths.train),
            test: truths.errors(&on_test, truths.test),
        });
    }
    Ok(rows)
}

/// The pose-driven light-map model fitted in `frame` to the training clip's maps, evaluated
/// through aprt-core at both clips' poses and read at the vertices and the surface points.
fn light_map_model_row(
    case: &LightMapCase,
    layout: &PoseLayout,
    baked: &BakedMaps,
    truths: &Truths<'_>,
    frame: ModelFrame,
) -> Result<Row> {
    let rig = case.rig.as_ref();
    let model = LightMapFit {
        options: &FitOptions::default(),
        precision: Precision::F16,
        frame,
    };
    let (blob, _, fit_s) = fit_light_maps(rig, layout, &case.train, baked, &model)?;
    let predict = |clip: &Clip| -> Result<(Prediction, f64)> {
        let start = Instant::now();
        let (_, _, maps) = predict_maps(&blob, "the light-map model", rig, clip)?;
        let ms = start.elapsed().as_secs_f64() * 1e3 / clip.frames.len().max(1) as f64;
        Ok((truths.read_maps(rig, baked, &maps), ms))
    };
    let (on_train, ms) = predict(&case.train)?;
    let (on_test, _) = predict(&case.test)?;
    Ok(Row {
        method: match frame {
            ModelFrame::World => "pose-driven light maps (texel rows, world frame)",
            ModelFrame::Bone => "pose-driven light maps (texel rows, bone frames)",
        },
        bytes: blob.len(),
        bake_s: baked.seconds,
        fit_s: Some(fit_s),
        ms_per_frame: ms,
        train: truths.errors(&on_train, truths.train),
        test: truths.errors(&on_test, truths.test),
    })
}

/// The per-vertex pose model (the default: bone frames) on the same training clip, its
/// per-vertex prediction interpolated at the surface points.
fn vertex_model_row(
    case: &LightMapCase,
    layout: &PoseLayout,
    truths: &Truths<'_>,
    bake_s: f64,
    order: usize,
) -> Result<Row> {
    let start = Instant::now();
    let clips = ClipSet {
        train: &truths.train.vertices,
        rest: None,
        validation: &[],
    };
    let fitted = fit_clip(
        case.rig.as_ref(),
        layout,
        clips,
        order,
        &FitOptions::default(),
        ModelFrame::Bone,
    )?;
    let fit_s = start.elapsed().as_secs_f64();
    let blob = encode_model(&fitted.model, Precision::F16)?;
    let info = describe(&blob)?;
    let n2 = order * order;
    let predict = |clip: &Clip| -> Result<(Prediction, f64)> {
        let start = Instant::now();
        let vertices = predict_clip(&blob, &info, "the model", case.rig.as_ref(), clip)?;
        let ms = start.elapsed().as_secs_f64() * 1e3 / clip.frames.len().max(1) as f64;
        let points = truths.probe.of_vertices(&vertices, n2);
        Ok((
            Prediction {
                vertices,
                points,
                n2,
            },
            ms,
        ))
    };
    let (on_train, ms) = predict(&case.train)?;
    let (on_test, _) = predict(&case.test)?;
    Ok(Row {
        method: "per-vertex pose model (bone frames)",
        bytes: blob.len(),
        bake_s,
        fit_s: Some(fit_s),
        ms_per_frame: ms,
        train: truths.errors(&on_train, truths.train),
        test: truths.errors(&on_test, truths.test),
    })
}

/// Per-vertex ray-traced truth interpolated at the surface points, on each clip: the floor
/// of every per-vertex method at the surface (exact at the vertices), what vertices cannot
/// hold between them however well a model predicts them. Bytes: its f32 values.
fn vertex_truth_row(truths: &Truths<'_>, bake_s: f64) -> Row {
    let errors = |truth: &ClipTruth| {
        let n2 = truths.probe.lighting.len();
        let vertices = truth.vertices.transfer.clone();
        let points = truths.probe.of_vertices(&vertices, n2);
        truths.errors(
            &Prediction {
                vertices,
                points,
                n2,
            },
            truth,
        )
    };
    let values: usize = truths.train.vertices.transfer.iter().map(Vec::len).sum();
    Row {
        method: "per-vertex ray-traced truth, interpolated (floor of any per-vertex method)",
        bytes: 4 * values,
        bake_s,
        fit_s: None,
        ms_per_frame: 0.0,
        train: errors(truths.train),
        test: errors(truths.test),
    }
}

/// A case's surface points (the study's count, and a quarter of it: the figure at both says
/// whether the count is enough) and the luminance lighting its grey levels are measured under.
pub struct CaseSurface {
    /// The points the tables are measured at.
    pub points: SurfacePoints,
    /// A quarter as many, spread afresh.
    pub coarse: SurfacePoints,
    /// Luminance SH of [`preview_lights`], at the bake's order.
    pub lighting: Vec<f32>,
}

impl CaseSurface {
    /// `count` points (and `count / 4`) over `rig`'s bind mesh, lit at `order`.
    pub fn new(rig: &dyn Rig, count: usize, order: usize) -> Result<CaseSurface> {
        let bind = rig.bind_mesh();
        Ok(CaseSurface {
            points: SurfacePoints::spread(bind, count)?,
            coarse: SurfacePoints::spread(bind, (count / 4).max(1))?,
            lighting: luminance_sh(&preview_lights(rig.up()), order)?,
        })
    }
}

/// Measures one case and returns its markdown section.
pub fn run_case(
    case: &LightMapCase,
    spec: AtlasSpec,
    (bake, surface): (&BakeSettings, &CaseSurface),
    scratch: &Path,
    reporter: &dyn Reporter,
) -> Result<String> {
    let rig = case.rig.as_ref();
    let layout = PoseLayout::from_training(&rig.angle_names(), &case.train.frames)
        .with_context(|| format!("clip {}", case.train.name))?;
    let points = &surface.points;
    let train = clip_truth(rig, &layout, &case.train, points, bake, reporter)?;
    let test = clip_truth(rig, &layout, &case.test, points, bake, reporter)?;
    let checkpoint = CheckpointSettings {
        dir: &scratch.join("study.bake"),
        existing: OnExisting::Refuse,
    };
    let baked = bake_light_maps(
        rig,
        &case.title,
        &case.train,
        spec,
        bake,
        &checkpoint,
        reporter,
    )?;
    let triangles = &rig.bind_mesh().triangles;
    let probe = Probe::new(points, &baked.layout, triangles, &surface.lighting);
    let truths = Truths {
        train: &train,
        test: &test,
        probe: &probe,
    };
    let mut rows = sequence_rows(case, &baked, &truths)?;
    for frame in [ModelFrame::World, ModelFrame::Bone] {
        rows.push(light_map_model_row(case, &layout, &baked, &truths, frame)?);
    }
    let vertex_bake_s = train.vertex_s * case.train.frames.len() as f64;
    rows.push(vertex_model_row(
        case,
        &layout,
        &truths,
        vertex_bake_s,
        bake.order,
    )?);
    rows.push(vertex_truth_row(&truths, vertex_bake_s));
    Ok(section(case, &baked, points.len(), &rows))
}

fn section(case: &LightMapCase, baked: &BakedMaps, points: usize, rows: &[Row]) -> String {
    let seq = &baked.sequence;
    let filled = seq.filled.iter().filter(|&&f| f).count();
    let mut md = format!(
        "## {}\n\nStored and trained on `{}` ({} frames), novel clip `{}` ({} frames). Atlas {r}x{r} ({filled} texels filled, {} overlapping), SH order {}. Errors at the vertices and at {points} surface points; grey levels RMS at the surface under the preview lights.\n\n",
        case.title,
        case.train.name,
        case.train.frames.len(),
        case.test.name,
        case.test.frames.len(),
        baked.atlas.overlapping_texels(),
        seq.order,
        r = seq.resolution,
    );
    md.push_str("| method | bytes | bake s | fit s | decode or eval ms/frame | its clip: vertices | surface | surface grey RMS | novel clip: vertices | surface | surface grey RMS |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    for r in rows {
        let _ = writeln!(
            md,
            "| {} | {} | {:.1} | {} | {:.2} | {} | {} |",
            r.method,
            r.bytes,
            r.bake_s,
            r.fit_s.map_or("–".to_owned(), |s| format!("{s:.1}")),
            r.ms_per_frame,
            errors_cells(&r.train),
            errors_cells(&r.test),
        );
    }
    md
}

/// A clip's three error cells: vertices, surface, surface grey levels.
fn errors_cells(e: &Errors) -> String {
    format!(
        "{:.2}% | {:.2}% | {:.2}",
        100.0 * e.vertices,
        100.0 * e.surface.transfer_error,
        e.surface.grey_rms
    )
}

/// How closely a stored sequence reproduces ray-traced transfer on the clip it was baked from:
/// at the vertices (what `aprt lightmap eval` against `aprt simulate` measures) and on the
/// whole surface.
pub struct Fidelity {
    /// The clip.
    pub clip: String,
    /// Frames.
    pub frames: usize,
    /// Relative transfer error of the f32 maps sampled at the vertices (the atlas alone).
    pub atlas_error: f64,
    /// Relative transfer error after compression.
    pub error: f64,
    /// The compressed maps' error at the surface points, and at a quarter as many.
    pub surface: (Accuracy, Accuracy),
    /// File size and the f32 maps' size.
    pub bytes: (usize, u64),
    /// Median milliseconds to decode a frame, and to copy its f32 maps (interleaved).
    pub decode_ms: (f64, f64),
    /// Seconds the texel bake took.
    pub bake_s: f64,
}

/// The fidelity clip's truth at the vertices, at the case's surface points and at the coarse
/// ones: baked once, measured against each atlas.
pub struct FidelityTruth {
    /// At the vertices and the surface points.
    pub truth: ClipTruth,
    /// At [`CaseSurface::coarse`].
    pub coarse: Vec<Vec<f32>>,
}

impl FidelityTruth {
    /// Bakes `clip` of `rig` at its vertices and at both densities of `surface`'s points.
    pub fn bake(
        rig: &dyn Rig,
        clip: &Clip,
        (bake, surface): (&BakeSettings, &CaseSurface),
        reporter: &dyn Reporter,
    ) -> Result<FidelityTruth> {
        let layout = PoseLayout::from_training(&rig.angle_names(), &clip.frames)
            .with_context(|| format!("clip {}", clip.name))?;
        let truth = clip_truth(rig, &layout, clip, &surface.points, bake, reporter)?;
        let coarse = bake_surface(&truth.vertices.meshes, &surface.coarse, bake, reporter)?;
        Ok(FidelityTruth { truth, coarse })
    }
}

/// Bakes `clip` of `case`'s character into light maps and measures the sequence against
/// `truth`, at the vertices and at the surface points.
pub fn fidelity(
    case: &LightMapCase,
    clip: &Clip,
    spec: AtlasSpec,
    (truth, surface): (&FidelityTruth, &CaseSurface),
    bake: &BakeSettings,
    scratch: &Path,
    reporter: &dyn Reporter,
) -> Result<Fidelity> {
    let rig = case.rig.as_ref();
    let checkpoint = CheckpointSettings {
        dir: &scratch.join("fidelity.bake"),
        existing: OnExisting::Refuse,
    };
    let baked = bake_light_maps(rig, &case.title, clip, spec, bake, &checkpoint, reporter)?;
    let seq = &baked.sequence;
    let (r, n2) = (seq.resolution, seq.order * seq.order);
    let bytes = encode(seq, &CodecSettings::default())?;
    let summary = crate::lightmap::summary::summarize(&bytes)?;
    let file = ShlmFile::parse(&bytes)?;
    let decoded = file.decode_all()?;
    let at_vertices = |maps: &[Vec<f32>]| {
        relative_error(
            &maps_at_vertices(rig, &baked.layout, maps, r, n2),
            &truth.truth.vertices.transfer,
        )
    };
    let triangles = &rig.bind_mesh().triangles;
    let at_surface = |points: &SurfacePoints, truth: &[Vec<f32>]| {
        let probe = Probe::new(points, &baked.layout, triangles, &surface.lighting);
        probe.error(&probe.of_maps(&decoded, r, n2), n2, truth)
    };
    Ok(Fidelity {
        clip: clip.name.clone(),
        frames: clip.frames.len(),
        atlas_error: at_vertices(&seq.frames),
        error: at_vertices(&decoded),
        surface: (
            at_surface(&surface.points, &truth.truth.surface),
            at_surface(&surface.coarse, &truth.coarse),
        ),
        bytes: (bytes.len(), file.raw_bytes()),
        decode_ms: (summary.decode_ms_per_frame, summary.memcpy_ms_per_frame),
        bake_s: baked.seconds,
    })
}

/// Two directional lights and no environment for the previews, placed from the character's up
/// axis (scale-free, so they suit a fox in centimetres and a man in metres): a warm key from
/// above and in front of the camera's side, a cool rim from behind.
pub fn preview_lights(up: glam::Vec3) -> Vec<aprt_core::Light> {
    let q = glam::Quat::from_rotation_arc(glam::Vec3::Z, up.normalize());
    let toward = |x: f32, y: f32, z: f32| (q * glam::Vec3::new(x, y, z)).normalize().to_array();
    vec![
        aprt_core::Light::Directional(aprt_core::DirectionalLight {
            direction: toward(0.5, -0.6, 0.8),
            irradiance: [0.75, 0.68, 0.6],
        }),
        aprt_core::Light::Directional(aprt_core::DirectionalLight {
            direction: toward(-0.4, 0.8, 0.3),
            irradiance: [0.15, 0.2, 0.3],
        }),
    ]
}

/// The study's cases on the assets in `assets`: the Fox stored and trained on `Survey`,
/// tested on `Walk`; CesiumMan on the first two thirds of its clip, tested on the rest. Each
/// with the clip the fidelity figure is measured on (the Fox's `Walk`, CesiumMan's
/// whole clip).
pub fn cases(assets: &Path) -> Result<Vec<(LightMapCase, Clip)>> {
    use crate::rig::gltf::GltfRig;
    let gltf = assets.join("gltf");
    let fox = GltfRig::load(&gltf.join("Fox.gltf"), 30.0)?;
    let (survey, walk) = (fox.clip("Survey")?, fox.clip("Walk")?);
    let man = GltfRig::load(&gltf.join("CesiumMan.gltf"), 30.0)?;
    let whole = man.clip(&man.clip_names()[0])?;
    let cut = whole.frames.len() * 2 / 3;
    let part = |name: String, frames: &[Vec<f64>]| Clip {
        name,
        fps: whole.fps,
        frames: frames.to_vec(),
    };
    let (train, test) = (
        part(format!("{} [0, {cut})", whole.name), &whole.frames[..cut]),
        part(
            format!("{} [{cut}, {})", whole.name, whole.frames.len()),
            &whole.frames[cut..],
        ),
    );
    Ok(vec![
        (
            LightMapCase {
                title: "Fox (glTF)".into(),
                rig: Box::new(fox),
                train: survey,
                test: walk.clone(),
            },
            walk,
        ),
        (
            LightMapCase {
                title: "CesiumMan (glTF)".into(),
                rig: Box::new(man),
                train,
                test,
            },
            whole,
        ),
    ])
}

/// The two atlases the study compares at `resolution`: the character's texture UVs and the
/// generated light-map UVs (the default), with the names its tables and files use.
fn atlases(resolution: usize) -> [(&'static str, AtlasSpec); 2] {
    let at = |uvs| AtlasSpec { resolution, uvs };
    [
        ("texture", at(LightMapUvs::Texture)),
        ("generated", at(LightMapUvs::DEFAULT_GENERATE)),
    ]
}

/// Runs the study and writes `out/README.md`, previews and surface pictures per character;
/// returns the document's path. The stored sequence is measured on both UV layouts (texture
/// and generated); the models are compared on the generated one.
pub fn run(
    assets: &Path,
    out: &Path,
    settings: &StudySettings<'_>,
    command: &str,
    reporter: &dyn Reporter,
) -> Result<std::path::PathBuf> {
    std::fs::create_dir_all(out).with_context(|| format!("cannot create {}", out.display()))?;
    let scratch = tempfile::tempdir().context("cannot create a scratch directory")?;
    let (bake, resolution) = (settings.bake, settings.resolution);
    let mut fidelity_rows = String::new();
    let mut sections = String::new();
    let [_, (_, generated)] = atlases(resolution);
    for (case, clip) in cases(assets)? {
        let surface = CaseSurface::new(case.rig.as_ref(), settings.surface_points, bake.order)?;
        reporter.note(&format!("{}: truth on {}", case.title, clip.name));
        let truth = FidelityTruth::bake(case.rig.as_ref(), &clip, (bake, &surface), reporter)?;
        for (uvs, spec) in atlases(resolution) {
            reporter.note(&format!(
                "{}: fidelity on {}, {uvs} UVs",
                case.title, clip.name
            ));
            let measured = (&truth, &surface);
            let f = fidelity(&case, &clip, spec, measured, bake, scratch.path(), reporter)?;
            fidelity_rows.push_str(&fidelity_row(&case, uvs, &f));
        }
        reporter.note(&format!("{}: comparison", case.title));
        let measured = (bake, &surface);
        sections.push_str(&run_case(
            &case,
            generated,
            measured,
            scratch.path(),
            reporter,
        )?);
        sections.push('\n');
        for (uvs, spec) in atlases(resolution) {
            let shown = Preview {
                clip: &clip,
                uvs,
                spec,
            };
            let middle = bake_middle(&case, &shown, bake, scratch.path(), reporter)?;
            sections.push_str(&preview(&case, &shown, &middle, bake, out)?);
            if spec == generated {
                sections.push_str(&picture(&case, &middle, &surface, bake, out, reporter)?);
            }
        }
    }
    let coarse = (settings.surface_points / 4).max(1);
    let doc = format!(
        "# SH light maps against the per-vertex pose model\n\nRegenerate with `{command}`. SH order {}, {} rays per texel, per vertex and per surface point, atlas {resolution}x{resolution}. Errors are relative transfer errors ‖pred − truth‖ / ‖truth‖ against ray-traced transfer from one simulator (`aprt simulate`'s), over all frames, points and coefficients, at two places: at the vertices, where a light map is read at each vertex's UV bilinearly (`aprt lightmap eval`); and on the whole surface, at {points} points spread over the bind mesh by area and riding the skin, where a per-vertex method is interpolated across each triangle as a GPU interpolates varyings and a light map is read bilinearly at the point's UV, each point weighted by the area it stands for. The surface figures are what an engine shows: a shadow inside a large face is in the truth and in a light map's texels, but not between the vertices that bound it. Grey levels are the RMS shading error at the surface under the previews' two directional lights (luminance), in 8-bit grey levels of a white surface (255/π per unit of irradiance). Texture UVs are the character's own (`--uv texture`); generated UVs are the light-map atlas `--uv generate` makes (the default: charts cut at hard edges, repacked at uniform density with a margin). Times are one run on this machine; decode and evaluation on one core.\n\n## Fidelity of the stored sequence\n\nThe surface error is also given at {coarse} points (a quarter as many, spread afresh): where the two agree, {points} points are enough.\n\n| character | clip | UVs | frames | error, f32 maps | error, compressed | surface error, compressed ({coarse} points) | surface grey RMS | bytes | f32 bytes | ratio | decode ms/frame | bake s |\n|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n{fidelity_rows}\n{sections}",
        bake.order,
        bake.rays,
        points = settings.surface_points,
    );
    let path = out.join("README.md");
    crate::io::atomic::write_atomic(&path, doc.as_bytes())
        .with_context(|| format!("cannot write {}", path.display()))?;
    Ok(path)
}

/// One row of the fidelity table.
fn fidelity_row(case: &LightMapCase, uvs: &str, f: &Fidelity) -> String {
    let (fine, coarse) = f.surface;
    format!(
        "| {} | `{}` | {uvs} | {} | {:.2}% | {:.2}% | {:.2}% ({:.2}%) | {:.2} | {} | {} | {:.1}:1 | {:.2} ({:.1}x a copy) | {:.1} |\n",
        case.title,
        f.clip,
        f.frames,
        100.0 * f.atlas_error,
        100.0 * f.error,
        100.0 * fine.transfer_error,
        100.0 * coarse.transfer_error,
        fine.grey_rms,
        f.bytes.0,
        f.bytes.1,
        f.bytes.1 as f64 / f.bytes.0.max(1) as f64,
        f.decode_ms.0,
        f.decode_ms.0 / f.decode_ms.1.max(1e-9),
        f.bake_s,
    )
}

/// What a preview shows: the middle frame of `clip`, baked on `spec` (called `uvs`).
struct Preview<'a> {
    clip: &'a Clip,
    uvs: &'a str,
    spec: AtlasSpec,
}

/// The middle frame of a preview's clip, as a one-frame clip, and its light map.
struct Middle {
    clip: String,
    frame: usize,
    one: Clip,
    baked: BakedMaps,
}

/// Bakes the light map of the middle frame of `shown`'s clip on its atlas.
fn bake_middle(
    case: &LightMapCase,
    shown: &Preview<'_>,
    bake: &BakeSettings,
    scratch: &Path,
    reporter: &dyn Reporter,
) -> Result<Middle> {
    let clip = shown.clip;
    let frame = clip.frames.len() / 2;
    let one = Clip {
        name: format!("{} frame {frame}", clip.name),
        fps: clip.fps,
        frames: vec![clip.frames[frame].clone()],
    };
    let checkpoint = CheckpointSettings {
        dir: &scratch.join("preview.bake"),
        existing: OnExisting::Refuse,
    };
    let rig = case.rig.as_ref();
    let baked = bake_light_maps(
        rig,
        &case.title,
        &one,
        shown.spec,
        bake,
        &checkpoint,
        reporter,
    )?;
    Ok(Middle {
        clip: clip.name.clone(),
        frame,
        one,
        baked,
    })
}

/// The case's name in file names: its title's first word, lower case.
fn case_id(case: &LightMapCase) -> String {
    (case.title.split_whitespace().next())
        .unwrap_or("case")
        .to_lowercase()
}

/// Writes `out/<id>_lightmap_<uvs>.png`: the light map of the middle frame of the clip under
/// [`preview_lights`], the character rendered with it, its per-vertex shading and the error;
/// returns the markdown that shows it.
fn preview(
    case: &LightMapCase,
    shown: &Preview<'_>,
    middle: &Middle,
    bake: &BakeSettings,
    out: &Path,
) -> Result<String> {
    use crate::report::lightmap_preview::{ComposeSource, save_preview};
    let rig = case.rig.as_ref();
    let bytes = encode(&middle.baked.sequence, &CodecSettings::default())?;
    let file = format!("{}_lightmap_{}.png", case_id(case), shown.uvs);
    let source = ComposeSource {
        name: &case.title,
        bytes: &bytes,
        character: Some((rig, &middle.one)),
        frame: 0,
        rays: bake.rays,
    };
    let line = save_preview(&out.join(&file), &source, &preview_lights(rig.up()))?;
    Ok(format!(
        "![{title} light map, {uvs} UVs]({file})\n\n*{title}, `{}` frame {}, {uvs} UVs: {line}.*\n\n",
        shown.clip.name,
        middle.frame,
        uvs = shown.uvs,
        title = case.title,
    ))
}

/// Writes `out/<id>_surface.png`, the picture per method of the middle frame drawn from the
/// surface points ([`picture`]), and returns the markdown that shows it.
fn picture(
    case: &LightMapCase,
    middle: &Middle,
    surface: &CaseSurface,
    bake: &BakeSettings,
    out: &Path,
    reporter: &dyn Reporter,
) -> Result<String> {
    let rig = case.rig.as_ref();
    let posed = rig.pose(&middle.one.frames[0])?;
    let path = out.join(format!("{}_surface.png", case_id(case)));
    let of = PictureOf {
        title: &case.title,
        clip: (&middle.clip, middle.frame),
        posed: &posed,
        baked: &middle.baked,
        lighting: &surface.lighting,
        path: &path,
    };
    save_surface_picture(rig, &of, bake, reporter)
}
