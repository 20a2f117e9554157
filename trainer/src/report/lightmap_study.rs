//! The light-map comparison (`aprt lightmap study`, docs/results/lightmaps): on the real glTF
//! characters, SH light maps stored as a compressed sequence, the pose-driven light-map model
//! (world and bone frames) and the per-vertex pose model, on the same clips — bytes, bake and fit time, decode or
//! evaluation time per frame, error at the vertices on the training clip and on a novel one
//! (where the stored sequence can only fall back to its nearest frame).

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result};

use crate::bake::BakeSettings;
use crate::bake::checkpoint::OnExisting;
use crate::bake::clip::{BakedClip, bake_clip};
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
    train_error: f64,
    test_error: f64,
}

/// Per-vertex ground truth of `clip` of the case's character, with `layout`'s pose vectors.
fn truth(
    case: &LightMapCase,
    layout: &PoseLayout,
    clip: &Clip,
    bake: &BakeSettings,
    reporter: &dyn Reporter,
) -> Result<(BakedClip, f64)> {
    let frames = clip.frames.clone();
    bake_clip(
        case.rig.as_ref(),
        layout,
        &clip.name,
        frames,
        bake,
        reporter,
    )
}

/// The stored sequence: encode, decode every frame (timed), sample at the vertices; on the
/// novel clip each frame takes the nearest stored frame's map.
fn sequence_rows(
    case: &LightMapCase,
    baked: &BakedMaps,
    truths: (&BakedClip, &BakedClip),
) -> Result<Vec<Row>> {
    let seq = &baked.sequence;
    let n2 = seq.order * seq.order;
    let bytes = encode(seq, &CodecSettings::default())?;
    let file = ShlmFile::parse(&bytes)?;
    let start = Instant::now();
    let decoded = file.decode_all()?;
    let decode_ms = start.elapsed().as_secs_f64() * 1e3 / file.frames().max(1) as f64;
    let (train, test) = truths;
    let nearest: Vec<usize> = test
        .angles
        .iter()
        .map(|a| nearest_pose(&train.angles, a))
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
        let at = maps_at_vertices(case.rig.as_ref(), &baked.layout, maps, seq.resolution, n2);
        let novel: Vec<Vec<f32>> = nearest.iter().map(|&k| at[k].clone()).collect();
        rows.push(Row {
            method,
            bytes: size,
            bake_s: baked.seconds,
            fit_s: None,
            ms_per_frame: ms,
            train_error: relative_error(&at, &train.transfer),
            test_error: relative_error(&novel, &test.transfer),
        });
    }
    Ok(rows)
}

/// The pose-driven light-map model fitted in `frame` to the training clip's maps, evaluated
/// through aprt-core at both clips' poses and sampled at the vertices.
fn light_map_model_row(
    case: &LightMapCase,
    layout: &PoseLayout,
    baked: &BakedMaps,
    truths: (&BakedClip, &BakedClip),
    frame: ModelFrame,
) -> Result<Row> {
    let seq = &baked.sequence;
    let n2 = seq.order * seq.order;
    let rig = case.rig.as_ref();
    let model = LightMapFit {
        options: &FitOptions::default(),
        precision: Precision::F16,
        frame,
    };
    let (blob, _, fit_s) = fit_light_maps(rig, layout, &case.train, baked, &model)?;
    let at_vertices = |clip: &Clip| -> Result<(Vec<Vec<f32>>, f64)> {
        let start = Instant::now();
        let (_, _, maps) = predict_maps(&blob, "the light-map model", rig, clip)?;
        let ms = start.elapsed().as_secs_f64() * 1e3 / clip.frames.len().max(1) as f64;
        Ok((
            maps_at_vertices(rig, &baked.layout, &maps, seq.resolution, n2),
            ms,
        ))
    };
    let (on_train, ms) = at_vertices(&case.train)?;
    let (on_test, _) = at_vertices(&case.test)?;
    let (train, test) = truths;
    Ok(Row {
        method: match frame {
            ModelFrame::World => "pose-driven light maps (texel rows, world frame)",
            ModelFrame::Bone => "pose-driven light maps (texel rows, bone frames)",
        },
        bytes: blob.len(),
        bake_s: baked.seconds,
        fit_s: Some(fit_s),
        ms_per_frame: ms,
        train_error: relative_error(&on_train, &train.transfer),
        test_error: relative_error(&on_test, &test.transfer),
    })
}

/// The per-vertex pose model (the default: bone frames) on the same training clip.
fn vertex_model_row(
    case: &LightMapCase,
    layout: &PoseLayout,
    truths: (&BakedClip, &BakedClip),
    bake_s: f64,
    order: usize,
) -> Result<Row> {
    let (train, test) = truths;
    let start = Instant::now();
    let clips = ClipSet {
        train,
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
    let start = Instant::now();
    let on_train = predict_clip(&blob, &info, "the model", case.rig.as_ref(), &case.train)?;
    let ms = start.elapsed().as_secs_f64() * 1e3 / case.train.frames.len().max(1) as f64;
    let on_test = predict_clip(&blob, &info, "the model", case.rig.as_ref(), &case.test)?;
    Ok(Row {
        method: "per-vertex pose model (bone frames)",
        bytes: blob.len(),
        bake_s,
        fit_s: Some(fit_s),
        ms_per_frame: ms,
        train_error: relative_error(&on_train, &train.transfer),
        test_error: relative_error(&on_test, &test.transfer),
    })
}

/// Measures one case and returns its markdown section.
pub fn run_case(
    case: &LightMapCase,
    spec: AtlasSpec,
    bake: &BakeSettings,
    scratch: &Path,
    reporter: &dyn Reporter,
) -> Result<String> {
    let rig = case.rig.as_ref();
    let layout = PoseLayout::from_training(&rig.angle_names(), &case.train.frames)
        .with_context(|| format!("clip {}", case.train.name))?;
    let (train, vertex_bake_s) = truth(case, &layout, &case.train, bake, reporter)?;
    let (test, _) = truth(case, &layout, &case.test, bake, reporter)?;
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
    let truths = (&train, &test);
    let mut rows = sequence_rows(case, &baked, truths)?;
    for frame in [ModelFrame::World, ModelFrame::Bone] {
        rows.push(light_map_model_row(case, &layout, &baked, truths, frame)?);
    }
    rows.push(vertex_model_row(
        case,
        &layout,
        truths,
        vertex_bake_s * case.train.frames.len() as f64,
        bake.order,
    )?);
    Ok(section(case, &baked, &rows))
}

fn section(case: &LightMapCase, baked: &BakedMaps, rows: &[Row]) -> String {
    let seq = &baked.sequence;
    let filled = seq.filled.iter().filter(|&&f| f).count();
    let mut md = format!(
        "## {}\n\nStored and trained on `{}` ({} frames), novel clip `{}` ({} frames). Atlas {r}x{r} ({filled} texels filled, {} overlapping), SH order {}.\n\n",
        case.title,
        case.train.name,
        case.train.frames.len(),
        case.test.name,
        case.test.frames.len(),
        baked.atlas.overlapping_texels(),
        seq.order,
        r = seq.resolution,
    );
    md.push_str("| method | bytes | bake s | fit s | decode or eval ms/frame | error on its clip | error on the novel clip |\n|---|---:|---:|---:|---:|---:|---:|\n");
    for r in rows {
        let _ = writeln!(
            md,
            "| {} | {} | {:.1} | {} | {:.2} | {:.2}% | {:.2}% |",
            r.method,
            r.bytes,
            r.bake_s,
            r.fit_s.map_or("–".to_owned(), |s| format!("{s:.1}")),
            r.ms_per_frame,
            100.0 * r.train_error,
            100.0 * r.test_error,
        );
    }
    md
}

/// How closely a stored sequence reproduces per-vertex ray-traced transfer on the clip it was
/// baked from (what `aprt lightmap eval` against `aprt simulate` measures).
pub struct Fidelity {
    /// The clip.
    pub clip: String,
    /// Frames.
    pub frames: usize,
    /// Relative transfer error of the f32 maps sampled at the vertices (the atlas alone).
    pub atlas_error: f64,
    /// Relative transfer error after compression.
    pub error: f64,
    /// File size and the f32 maps' size.
    pub bytes: (usize, u64),
    /// Median milliseconds to decode a frame, and to copy its f32 maps (interleaved).
    pub decode_ms: (f64, f64),
    /// Seconds the texel bake took.
    pub bake_s: f64,
}

/// Bakes `clip` of `case`'s character into light maps and per vertex, and measures the
/// sequence against the vertices.
pub fn fidelity(
    case: &LightMapCase,
    clip: &Clip,
    spec: AtlasSpec,
    bake: &BakeSettings,
    scratch: &Path,
    reporter: &dyn Reporter,
) -> Result<Fidelity> {
    let rig = case.rig.as_ref();
    let meshes = crate::bake::clip::pose_all(rig, &clip.name, &clip.frames)?;
    let truth = crate::bake::bake_poses(&meshes, bake, reporter)?;
    let checkpoint = CheckpointSettings {
        dir: &scratch.join("fidelity.bake"),
        existing: OnExisting::Refuse,
    };
    let baked = bake_light_maps(rig, &case.title, clip, spec, bake, &checkpoint, reporter)?;
    let seq = &baked.sequence;
    let n2 = seq.order * seq.order;
    let bytes = encode(seq, &CodecSettings::default())?;
    let summary = crate::lightmap::summary::summarize(&bytes)?;
    let file = ShlmFile::parse(&bytes)?;
    let decoded = file.decode_all()?;
    Ok(Fidelity {
        clip: clip.name.clone(),
        frames: clip.frames.len(),
        atlas_error: relative_error(
            &maps_at_vertices(rig, &baked.layout, &seq.frames, seq.resolution, n2),
            &truth,
        ),
        error: relative_error(
            &maps_at_vertices(rig, &baked.layout, &decoded, seq.resolution, n2),
            &truth,
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

/// Runs the study and writes `out/README.md` and previews per character; returns the
/// document's path. The stored sequence is measured on both UV layouts (texture and generated); the
/// models are compared on the generated one.
pub fn run(
    assets: &Path,
    out: &Path,
    resolution: usize,
    bake: &BakeSettings,
    command: &str,
    reporter: &dyn Reporter,
) -> Result<std::path::PathBuf> {
    std::fs::create_dir_all(out).with_context(|| format!("cannot create {}", out.display()))?;
    let scratch = tempfile::tempdir().context("cannot create a scratch directory")?;
    let mut fidelity_rows = String::new();
    let mut sections = String::new();
    let [_, (_, generated)] = atlases(resolution);
    for (case, clip) in cases(assets)? {
        for (uvs, spec) in atlases(resolution) {
            reporter.note(&format!(
                "{}: fidelity on {}, {uvs} UVs",
                case.title, clip.name
            ));
            let f = fidelity(&case, &clip, spec, bake, scratch.path(), reporter)?;
            fidelity_rows.push_str(&fidelity_row(&case, uvs, &f));
        }
        reporter.note(&format!("{}: comparison", case.title));
        sections.push_str(&run_case(&case, generated, bake, scratch.path(), reporter)?);
        sections.push('\n');
        for (uvs, spec) in atlases(resolution) {
            let shown = Preview {
                clip: &clip,
                uvs,
                spec,
            };
            sections.push_str(&preview(
                &case,
                &shown,
                bake,
                out,
                scratch.path(),
                reporter,
            )?);
        }
    }
    let doc = format!(
        "# SH light maps against the per-vertex pose model\n\nRegenerate with `{command}`. SH order {}, {} rays per texel and per vertex, atlas {resolution}x{resolution}. Errors are relative transfer errors ‖pred − truth‖ / ‖truth‖ at the vertices against per-vertex ray-traced transfer (`aprt simulate`), over all frames, vertices and coefficients; a light map is read at each vertex's UV bilinearly (`aprt lightmap eval`). Texture UVs are the character's own (`--uv texture`); generated UVs are the light-map atlas `--uv generate` makes (the default: charts cut at hard edges, repacked at uniform density with a margin). Times are one run on this machine; decode and evaluation on one core.\n\n## Fidelity of the stored sequence\n\n| character | clip | UVs | frames | error, f32 maps | error, compressed | bytes | f32 bytes | ratio | decode ms/frame | bake s |\n|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|\n{fidelity_rows}\n{sections}",
        bake.order, bake.rays,
    );
    let path = out.join("README.md");
    crate::io::atomic::write_atomic(&path, doc.as_bytes())
        .with_context(|| format!("cannot write {}", path.display()))?;
    Ok(path)
}

/// One row of the fidelity table.
fn fidelity_row(case: &LightMapCase, uvs: &str, f: &Fidelity) -> String {
    format!(
        "| {} | `{}` | {uvs} | {} | {:.2}% | {:.2}% | {} | {} | {:.1}:1 | {:.2} ({:.1}x a copy) | {:.1} |\n",
        case.title,
        f.clip,
        f.frames,
        100.0 * f.atlas_error,
        100.0 * f.error,
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

/// Writes `out/<id>_lightmap_<uvs>.png`: the light map of the middle frame of the clip under
/// [`preview_lights`], the character rendered with it, its per-vertex shading and the error;
/// returns the markdown that shows it.
fn preview(
    case: &LightMapCase,
    shown: &Preview<'_>,
    bake: &BakeSettings,
    out: &Path,
    scratch: &Path,
    reporter: &dyn Reporter,
) -> Result<String> {
    use crate::report::lightmap_preview::{ComposeSource, save_preview};
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
    let bytes = encode(&baked.sequence, &CodecSettings::default())?;
    let id: String = case
        .title
        .split_whitespace()
        .next()
        .unwrap_or("case")
        .to_lowercase();
    let file = format!("{id}_lightmap_{}.png", shown.uvs);
    let source = ComposeSource {
        name: &case.title,
        bytes: &bytes,
        character: Some((rig, &one)),
        frame: 0,
        rays: bake.rays,
    };
    let line = save_preview(&out.join(&file), &source, &preview_lights(rig.up()))?;
    Ok(format!(
        "![{title} light map, {uvs} UVs]({file})\n\n*{title}, `{}` frame {frame}, {uvs} UVs: {line}.*\n\n",
        clip.name,
        uvs = shown.uvs,
        title = case.title,
    ))
}
