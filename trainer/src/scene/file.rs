//! The scene file: which character and clips, which effects to simulate at what error, the
//! budget, and the lighting (an environment and the lights file's `[[light]]` tables). Read by
//! `aprt train --scene`, `aprt report` and `aprt demo`; planned by [`crate::scene`].
//!
//! ```toml
//! confine = false          # true: refuse paths outside the scene's directory (--confine)
//! [source]                 # exactly one of: builtin, gltf, bvh, obj_seq (+ angles)
//! gltf = "Fox.gltf"        # paths relative to the scene file
//! train = ["Survey"]       # clips (BVH: frame ranges "0..240" of the bvh file, or other files)
//! test = ["Walk", "Run"]   # clips the report measures on (never trained on)
//! validate = []            # clips held out of training to choose the model by (optional)
//!                          # train, validate and test share no frame (checked when read)
//! up = "z"                 # optional: "y" or "z", the character's up axis (default: the
//!                          # rig's own; an OBJ sequence's is z); environment maps turn to it
//!
//! [effects]
//! shadows = true           # false: no visibility rays at all
//! bounces = 0
//! albedo = 0.6             # of the surfaces bounces reflect from
//! rays = 256               # directions per vertex
//! order = "auto"           # or 1..=6; auto: the lowest order that meets error_target
//! error_target = 1.0       # 8-bit grey levels of shading error
//! irradiance_rig = "auto"  # "none", a rig kind ("gradient", "lattice:2x2x2", …) or auto
//! precision = "auto"       # f32 | f16 | i8 | auto
//! frame = "bone"           # bone | world: the frame the model learns transfer in
//! method = "vertex"        # vertex | lightmap | auto: transfer per vertex, or per texel of
//!                          # a pose-driven SH light map; auto: what the report recommends
//! lightmap_resolution = "auto"  # or 8..=8192 texels a side; auto: 64, 128 or 256 by the report
//!
//! [budget]                 # optional
//! us_per_frame = 100
//! bytes = 1_000_000
//!
//! [environment]            # optional: sh = [[r, g, b], ...] (1, 4, 9, … coefficients) or
//! hdr = "studio.hdr"       # an equirectangular .hdr or .exr map, projected to SH
//!
//! [[light]]                # the lights file's schema, exactly
//! kind = "sphere"
//! position = [0.0, 1.2, 0.8]
//! radius = 0.1
//! radiance = [4.0, 3.5, 3.0]
//! ```

use std::path::{Path, PathBuf};

use aprt_core::{Light, MAX_ORDER};
use serde::Deserialize;

use crate::input::{InputKind, read_input_text};
use crate::io::outputs::gltf_inputs;
use crate::io::source::{BuiltinCharacter, ClipSpec, parse_frames};
use crate::irradiance_rig::RigKind;
use crate::lighting::lights_file::check_light_count;
use crate::lighting::{finite_f32s, light_from_table};
use crate::model::ModelFrame;
use crate::model::export::Precision;

/// A scene, validated, with its paths resolved against the scene file's directory.
#[derive(Clone, Debug)]
pub struct Scene {
    /// The scene file.
    pub path: PathBuf,
    /// The character.
    pub source: SceneSource,
    /// Training clips (for BVH: frame ranges of the file, or other BVH files).
    pub train: Vec<String>,
    /// Clips the report measures on.
    pub test: Vec<String>,
    /// Clips held out of training to choose the model by (`aprt train --validate`).
    pub validate: Vec<String>,
    /// What to simulate.
    pub effects: Effects,
    /// What the runtime may spend.
    pub budget: Budget,
    /// The character's up axis from `[source] up`, overriding the rig's: environment maps,
    /// projected with +Y up, are turned to it.
    pub up: Option<glam::Vec3>,
    /// The distant lighting, if any.
    pub environment: Option<Environment>,
    /// The local and directional lights.
    pub lights: Vec<Light>,
    /// The clips of `train`, `validate` and `test` ([`CLIP_KEYS`]'s order), read once with
    /// their paths resolved, so every command takes the same clips.
    specs: [Vec<ClipSpec>; 3],
    /// The paths the scene spells as absolute, which [`Scene::confine`] refuses even inside
    /// the scene's directory: resolved against an absolute scene path, they look alike.
    absolute: Vec<PathBuf>,
}

/// The `[source]` keys that name clips, in the order they are checked and taken.
pub const CLIP_KEYS: [&str; 3] = ["train", "validate", "test"];

impl Scene {
    /// Refuses the scene when a path it names (its character, the buffers and images its glTF
    /// references, its environment map or a BVH clip) is absolute or leaves the scene's
    /// directory once symlinks are followed, so a service that takes users' scenes reads no
    /// other file. `why` is what asked (`--confine`, or the scene's own key), for the error. A
    /// path that does not exist yet is judged as written: it may not climb with `..`.
    pub fn confine(&self, why: &str) -> Result<(), SceneError> {
        let base = self.path.parent().unwrap_or(Path::new(""));
        let home = Path::new(".").join(base).canonicalize();
        for (item, path) in self.named_paths() {
            let inside = match (path.strip_prefix(base), &home, path.canonicalize()) {
                _ if self.absolute.contains(&path) => false,
                (Err(_), ..) => false,
                (Ok(_), Ok(home), Ok(real)) => real.starts_with(home),
                (Ok(rel), ..) => !rel
                    .components()
                    .any(|c| matches!(c, std::path::Component::ParentDir)),
            };
            if !inside {
                return Err(SceneError {
                    path: self.path.clone(),
                    item,
                    message: format!(
                        "{}: outside the scene's directory, refused by {why}",
                        path.display()
                    ),
                });
            }
        }
        Ok(())
    }

    /// Every path the scene names, resolved, with the item that names it; a glTF character's
    /// external files (as its importer resolves them) count as named by `[source] gltf`.
    fn named_paths(&self) -> Vec<(String, PathBuf)> {
        let mut named: Vec<(String, PathBuf)> = match &self.source {
            SceneSource::Builtin(_) => Vec::new(),
            SceneSource::Gltf { path, .. } => gltf_inputs(path)
                .into_iter()
                .enumerate()
                .map(|(i, input)| match i {
                    0 => ("[source] gltf".into(), input.path),
                    _ => (format!("[source] gltf, {}", input.role), input.path),
                })
                .collect(),
            SceneSource::Bvh(path) => vec![("[source] bvh".into(), path.clone())],
            SceneSource::ObjSeq { dir, angles } => vec![
                ("[source] obj_seq".into(), dir.clone()),
                ("[source] angles".into(), angles.clone()),
            ],
        };
        if let Some(Environment::Map(path)) = &self.environment {
            named.push(("[environment]".into(), path.clone()));
        }
        for key in CLIP_KEYS {
            for spec in self.clip_specs(key) {
                if let ClipSpec::Motion { path, .. } = spec {
                    named.push((format!("[source] {key}"), path.clone()));
                }
            }
        }
        named
    }

    /// The clips `[source] key` names, to take from the character (`key` one of
    /// [`CLIP_KEYS`]; any other key names none).
    pub fn clip_specs(&self, key: &str) -> &[ClipSpec] {
        CLIP_KEYS
            .iter()
            .position(|k| *k == key)
            .map_or(&[], |i| &self.specs[i])
    }
}

/// Where the character comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum SceneSource {
    /// A built-in character.
    Builtin(BuiltinCharacter),
    /// A glTF character, sampled at `fps` (30 by default).
    Gltf {
        /// The .gltf or .glb file.
        path: PathBuf,
        /// Sampling rate of its animations.
        fps: Option<f64>,
    },
    /// A mannequin built from a BVH file's skeleton.
    Bvh(PathBuf),
    /// A directory of OBJ poses with their joint angles.
    ObjSeq {
        /// One OBJ per pose, sorted by name.
        dir: PathBuf,
        /// The angles CSV.
        angles: PathBuf,
    },
}

/// A setting the trainer may choose (`"auto"`) or the scene fixes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Choice<T> {
    /// The trainer chooses, and says why.
    Auto,
    /// The scene's value.
    Fixed(T),
}

/// The irradiance rig a scene asks for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RigChoice {
    /// The cheapest that meets the error target, or none when every light is far enough.
    Auto,
    /// No rig.
    None,
    /// This kind.
    Kind(RigKind),
}

/// The effects to simulate and the error they may cost.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Effects {
    /// Self-shadowing; without it no ray is cast.
    pub shadows: bool,
    /// Inter-reflection bounces.
    pub bounces: usize,
    /// Albedo of the surfaces the bounces reflect from.
    pub albedo: f32,
    /// Directions per vertex.
    pub rays: usize,
    /// SH order.
    pub order: Choice<usize>,
    /// The shading error the automatic choices may cost, in 8-bit grey levels.
    pub error_target: f32,
    /// The irradiance rig.
    pub rig: RigChoice,
    /// Precision of the blob's large sections.
    pub precision: Choice<Precision>,
    /// The frame transfer is learned in.
    pub frame: ModelFrame,
    /// Per-vertex transfer, a pose-driven light map, or whichever the report recommends.
    pub method: Choice<Method>,
    /// Texels a side of a light map (`Auto`: [`LIGHTMAP_RESOLUTIONS`], by the report).
    pub lightmap_resolution: Choice<usize>,
}

/// How a scene's transfer reaches the screen.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// Per vertex, interpolated across each triangle by the renderer.
    Vertex,
    /// Per texel of the character's light-map atlas, predicted from the pose (the pose-driven
    /// light map) and composed under the lighting each frame.
    #[serde(rename = "lightmap")]
    LightMap,
}

impl Method {
    /// The scene file's word for it.
    pub fn name(self) -> &'static str {
        match self {
            Method::Vertex => "vertex",
            Method::LightMap => "lightmap",
        }
    }
}

/// The light-map resolutions `lightmap_resolution = "auto"` chooses between.
pub const LIGHTMAP_RESOLUTIONS: [usize; 3] = [64, 128, 256];

/// Fewest texels a side a scene's light map may have: below it a character's charts do not fit.
const MIN_LIGHTMAP_RESOLUTION: usize = 8;

impl Default for Effects {
    /// Shadows, no bounces, 256 rays, every choice automatic at one grey level, bone frames.
    fn default() -> Self {
        Effects {
            shadows: true,
            bounces: 0,
            albedo: 0.6,
            rays: 256,
            order: Choice::Auto,
            error_target: 1.0,
            rig: RigChoice::Auto,
            precision: Choice::Auto,
            frame: ModelFrame::Bone,
            method: Choice::Fixed(Method::Vertex),
            lightmap_resolution: Choice::Auto,
        }
    }
}

/// What the runtime may spend per frame and in memory.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Budget {
    /// Microseconds per frame on one core.
    pub us_per_frame: Option<f64>,
    /// Bytes of the model.
    pub bytes: Option<u64>,
}

/// The distant lighting.
#[derive(Clone, Debug, PartialEq)]
pub enum Environment {
    /// SH radiance coefficients, RGB, in aprt-core's basis.
    Sh(Vec<[f32; 3]>),
    /// An equirectangular .hdr or .exr map.
    Map(PathBuf),
}

/// Why a scene file was refused: the file, the item (a `[section] key`, or `light N`) and
/// what is wrong.
#[derive(Debug, thiserror::Error)]
#[error("{}: {item}: {message}", path.display())]
pub struct SceneError {
    /// The scene file.
    pub path: PathBuf,
    /// What is wrong where.
    pub item: String,
    /// What is wrong.
    pub message: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScene {
    #[serde(default)]
    confine: bool,
    source: RawSource,
    #[serde(default)]
    effects: RawEffects,
    #[serde(default)]
    budget: RawBudget,
    environment: Option<RawEnvironment>,
    /// `None` when the key is absent; `light = []` is refused rather than read as no lights.
    light: Option<Vec<toml::Table>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSource {
    builtin: Option<String>,
    gltf: Option<String>,
    bvh: Option<String>,
    obj_seq: Option<String>,
    angles: Option<String>,
    fps: Option<f64>,
    up: Option<String>,
    #[serde(default)]
    train: Vec<String>,
    #[serde(default)]
    test: Vec<String>,
    #[serde(default)]
    validate: Vec<String>,
}

/// A key that is `"auto"` or a value; `Other` catches a value of any other type (`2.0`), so
/// the error says what the key takes rather than how serde failed to match it.
#[derive(Deserialize)]
#[serde(untagged)]
enum Word {
    Number(i64),
    Text(String),
    Other(toml::Value),
}

#[derive(Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawEffects {
    shadows: Option<bool>,
    bounces: Option<i64>,
    albedo: Option<f64>,
    rays: Option<i64>,
    order: Option<Word>,
    error_target: Option<f64>,
    /// `rig` was its name before the irradiance rig had one of its own; still read.
    #[serde(alias = "rig")]
    irradiance_rig: Option<String>,
    precision: Option<String>,
    frame: Option<String>,
    method: Option<String>,
    lightmap_resolution: Option<Word>,
}

#[derive(Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawBudget {
    us_per_frame: Option<f64>,
    bytes: Option<i64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawEnvironment {
    sh: Option<Vec<[f64; 3]>>,
    hdr: Option<String>,
    exr: Option<String>,
}

/// Reads and validates a scene file.
pub fn read_scene(path: &Path) -> Result<Scene, SceneError> {
    let text = read_input_text(path, InputKind::Scene).map_err(|e| SceneError {
        path: path.to_owned(),
        item: "file".into(),
        message: e.problem(),
    })?;
    parse_scene(&text, path)
}

/// Parses the text of a scene file; `path` names it in errors and its directory anchors the
/// relative paths.
pub fn parse_scene(text: &str, path: &Path) -> Result<Scene, SceneError> {
    let fail = |item: &str, message: String| SceneError {
        path: path.to_owned(),
        item: item.to_owned(),
        message,
    };
    let raw: RawScene =
        toml::from_str(text).map_err(|e| fail("TOML", crate::text::toml_problem(text, &e)))?;
    let base = path.parent().unwrap_or(Path::new(""));
    let absolute = std::cell::RefCell::new(Vec::new());
    let resolve = |p: &str| {
        if Path::new(p).is_absolute() {
            absolute.borrow_mut().push(PathBuf::from(p));
        }
        base.join(p)
    };
    let source = source(&raw.source, &resolve).map_err(|m| fail("[source]", m))?;
    let up = match raw.source.up.as_deref() {
        None => None,
        Some("y") => Some(glam::Vec3::Y),
        Some("z") => Some(glam::Vec3::Z),
        Some(other) => {
            return Err(fail(
                "[source] up",
                format!(
                    "{:?}: expected \"y\" or \"z\" (the character's up axis)",
                    crate::text::excerpt(other)
                ),
            ));
        }
    };
    let effects = effects(&raw.effects).map_err(|(k, m)| fail(&format!("[effects] {k}"), m))?;
    let budget = budget(&raw.budget).map_err(|(k, m)| fail(&format!("[budget] {k}"), m))?;
    let environment = match &raw.environment {
        None => None,
        Some(env) => Some(
            environment(env, &resolve).map_err(|(k, m)| fail(&format!("[environment]{k}"), m))?,
        ),
    };
    if raw.light.as_ref().is_some_and(Vec::is_empty) {
        return Err(fail(
            "light",
            "`light = []` lists no lights: give [[light]] tables, or leave the key out when the [environment] alone lights the scene".into(),
        ));
    }
    check_light_count(raw.light.as_ref().map_or(0, Vec::len)).map_err(|m| fail("[[light]]", m))?;
    let lights = raw
        .light
        .iter()
        .flatten()
        .enumerate()
        .map(|(i, t)| {
            light_from_table(t).map_err(|(kind, m)| fail(&format!("light {} ({kind})", i + 1), m))
        })
        .collect::<Result<Vec<_>, _>>()?;
    if lights.is_empty() && environment.is_none() {
        return Err(fail(
            "lighting",
            "the scene has neither [[light]] tables nor an [environment]: nothing lights it".into(),
        ));
    }
    let s = &raw.source;
    if s.train.is_empty() && !matches!(source, SceneSource::ObjSeq { .. }) {
        return Err(fail(
            "[source] train",
            "name the training clips (train = [\"…\"])".into(),
        ));
    }
    if let SceneSource::ObjSeq { .. } = source
        && !(s.train.is_empty() && s.test.is_empty() && s.validate.is_empty())
    {
        return Err(fail(
            "[source] train",
            "an OBJ sequence is one clip: its OBJ files with their angles; train, test and validate name clips of a character".into(),
        ));
    }
    let specs = clip_lists(&source, [&s.train, &s.validate, &s.test], &resolve)
        .map_err(|(key, m)| fail(&format!("[source] {key}"), m))?;
    let scene = Scene {
        path: path.to_owned(),
        source,
        train: s.train.clone(),
        test: s.test.clone(),
        validate: s.validate.clone(),
        effects,
        budget,
        up,
        environment,
        lights,
        specs,
        absolute: absolute.into_inner(),
    };
    if raw.confine {
        scene.confine("confine = true")?;
    }
    Ok(scene)
}

/// The clips each of [`CLIP_KEYS`] names, read, and refused where two keys share a frame: a
/// model chosen or measured on frames it was trained on would be reported as held out. An
/// error is the key at fault and what is wrong, naming both clips.
fn clip_lists(
    source: &SceneSource,
    names: [&Vec<String>; 3],
    resolve: &dyn Fn(&str) -> PathBuf,
) -> Result<[Vec<ClipSpec>; 3], (&'static str, String)> {
    let mut specs: [Vec<ClipSpec>; 3] = Default::default();
    for (k, list) in names.iter().enumerate() {
        specs[k] = list
            .iter()
            .map(|text| clip_spec(source, text, resolve))
            .collect::<Result<_, _>>()
            .map_err(|m| (CLIP_KEYS[k], m))?;
    }
    for (i, j) in [(0, 1), (0, 2), (1, 2)] {
        for (a, a_spec) in names[i].iter().zip(&specs[i]) {
            for (b, b_spec) in names[j].iter().zip(&specs[j]) {
                if let Some(frames) = shared_frames(a_spec, b_spec) {
                    return Err((
                        CLIP_KEYS[j],
                        format!(
                            "clip {} shares {frames} with {} clip {}: train, validate and test clips must share no frame",
                            crate::text::quote(b),
                            CLIP_KEYS[i],
                            crate::text::quote(a)
                        ),
                    ));
                }
            }
        }
    }
    Ok(specs)
}

/// The clip `text` names: a clip of a built-in or glTF character by name; for a BVH scene,
/// frames `A..B` of the scene's file when written as two numbers (an empty or reversed range
/// is refused, not taken for a file name), else another BVH file, relative to the scene.
fn clip_spec(
    source: &SceneSource,
    text: &str,
    resolve: &dyn Fn(&str) -> PathBuf,
) -> Result<ClipSpec, String> {
    let SceneSource::Bvh(file) = source else {
        return Ok(ClipSpec::Named(text.to_owned()));
    };
    let numeric = |s: &str| !s.trim().is_empty() && s.trim().bytes().all(|b| b.is_ascii_digit());
    Ok(match text.split_once("..") {
        Some((a, b)) if numeric(a) && numeric(b) => ClipSpec::Motion {
            path: file.clone(),
            frames: Some(parse_frames(text)?),
        },
        _ => ClipSpec::Motion {
            path: resolve(text),
            frames: None,
        },
    })
}

/// The frames clips `a` and `b` both take, in words, or `None`: the same named clip, or
/// overlapping frames of one BVH file (a whole file's frames overlap any of its ranges; two
/// whole files start at frame 0, so they share every frame).
fn shared_frames(a: &ClipSpec, b: &ClipSpec) -> Option<String> {
    match (a, b) {
        (ClipSpec::Named(x), ClipSpec::Named(y)) => (x == y).then(|| "every frame".to_owned()),
        (
            ClipSpec::Motion { path, frames: f },
            ClipSpec::Motion {
                path: other,
                frames: g,
            },
        ) if same_file(path, other) => {
            let whole = 0..usize::MAX;
            let (f, g) = (
                f.clone().unwrap_or(whole.clone()),
                g.clone().unwrap_or(whole),
            );
            let (start, end) = (f.start.max(g.start), f.end.min(g.end));
            (start < end).then(|| match end {
                usize::MAX => format!("every frame of {}", path.display()),
                _ => format!("frames {start}..{end} of {}", path.display()),
            })
        }
        _ => None,
    }
}

/// Whether two paths name one file: equal as written, or once canonicalised (`./a.bvh`, a
/// symlink).
fn same_file(a: &Path, b: &Path) -> bool {
    a == b || matches!((a.canonicalize(), b.canonicalize()), (Ok(x), Ok(y)) if x == y)
}

fn source(raw: &RawSource, resolve: &dyn Fn(&str) -> PathBuf) -> Result<SceneSource, String> {
    let given: Vec<&str> = [
        ("builtin", raw.builtin.is_some()),
        ("gltf", raw.gltf.is_some()),
        ("bvh", raw.bvh.is_some()),
        ("obj_seq", raw.obj_seq.is_some()),
    ]
    .iter()
    .filter(|(_, g)| *g)
    .map(|(k, _)| *k)
    .collect();
    if given.len() != 1 {
        return Err(format!(
            "give exactly one of builtin, gltf, bvh or obj_seq (found {})",
            if given.is_empty() {
                "none".to_owned()
            } else {
                given.join(", ")
            }
        ));
    }
    if raw.angles.is_some() != raw.obj_seq.is_some() {
        return Err("angles goes with obj_seq, and obj_seq needs angles".into());
    }
    if raw.fps.is_some() && raw.gltf.is_none() {
        return Err("fps resamples a gltf character's animations only".into());
    }
    if let Some(fps) = raw.fps
        && !(fps.is_finite() && fps > 0.0)
    {
        return Err(format!("fps {fps}: expected a positive number"));
    }
    Ok(match (&raw.builtin, &raw.gltf, &raw.bvh, &raw.obj_seq) {
        (Some(name), ..) => SceneSource::Builtin(match name.as_str() {
            "human" => BuiltinCharacter::Human,
            "creature" => BuiltinCharacter::Creature,
            other => {
                return Err(format!(
                    "builtin = {other:?}: expected \"human\" or \"creature\""
                ));
            }
        }),
        (_, Some(gltf), ..) => SceneSource::Gltf {
            path: resolve(gltf),
            fps: raw.fps,
        },
        (_, _, Some(bvh), _) => SceneSource::Bvh(resolve(bvh)),
        (.., Some(dir)) => SceneSource::ObjSeq {
            dir: resolve(dir),
            angles: resolve(raw.angles.as_deref().unwrap_or_default()),
        },
        _ => unreachable!("exactly one source was checked above"),
    })
}

fn effects(raw: &RawEffects) -> Result<Effects, (&'static str, String)> {
    let mut e = Effects::default();
    if let Some(s) = raw.shadows {
        e.shadows = s;
    }
    if let Some(b) = raw.bounces {
        e.bounces = usize::try_from(b)
            .ok()
            .filter(|&b| b <= 8)
            .ok_or(("bounces", format!("{b}: expected 0 to 8")))?;
    }
    if let Some(a) = raw.albedo {
        if !(0.0..=1.0).contains(&a) {
            return Err(("albedo", format!("{a}: expected a number in [0, 1]")));
        }
        e.albedo = a as f32;
    }
    if let Some(r) = raw.rays {
        e.rays = usize::try_from(r)
            .ok()
            .filter(|&r| (1..=crate::limits::MAX_RAYS).contains(&r))
            .ok_or((
                "rays",
                format!("{r}: expected 1 to {}", crate::limits::MAX_RAYS),
            ))?;
    }
    e.order = match &raw.order {
        None => Choice::Auto,
        Some(Word::Text(t)) if t == "auto" => Choice::Auto,
        Some(Word::Number(n)) if (1..=MAX_ORDER as i64).contains(n) => Choice::Fixed(*n as usize),
        Some(Word::Number(n)) => {
            return Err((
                "order",
                format!("{n}: expected 1 to {MAX_ORDER} or \"auto\""),
            ));
        }
        Some(Word::Text(t)) => {
            return Err((
                "order",
                format!("{t:?}: expected 1 to {MAX_ORDER} or \"auto\""),
            ));
        }
        Some(Word::Other(v)) => {
            return Err((
                "order",
                // An excerpt: a table or a string with a line break prints over lines.
                format!(
                    "{}: order must be an integer 1..={MAX_ORDER} or \"auto\"",
                    crate::text::excerpt(&v.to_string())
                ),
            ));
        }
    };
    if let Some(t) = raw.error_target {
        // Compared with f32 errors, so it must be a positive f32 (1e300 became infinity).
        let t32 = t as f32;
        if !(t32.is_finite() && t32 > 0.0) {
            return Err((
                "error_target",
                format!(
                    "{t:?}: expected a positive number of grey levels that an f32 holds (up to {:e})",
                    f32::MAX
                ),
            ));
        }
        e.error_target = t32;
    }
    e.rig = match raw.irradiance_rig.as_deref() {
        None | Some("auto") => RigChoice::Auto,
        Some("none") => RigChoice::None,
        Some(kind) => RigChoice::Kind(
            kind.parse()
                .map_err(|err| ("irradiance_rig", format!("{err}")))?,
        ),
    };
    e.precision = match raw.precision.as_deref() {
        None | Some("auto") => Choice::Auto,
        Some("f32") => Choice::Fixed(Precision::F32),
        Some("f16") => Choice::Fixed(Precision::F16),
        Some("i8") => Choice::Fixed(Precision::I8),
        Some(other) => {
            return Err((
                "precision",
                format!("{other:?}: expected f32, f16, i8 or auto"),
            ));
        }
    };
    e.frame = match raw.frame.as_deref() {
        None | Some("bone") => ModelFrame::Bone,
        Some("world") => ModelFrame::World,
        Some(other) => return Err(("frame", format!("{other:?}: expected bone or world"))),
    };
    (e.method, e.lightmap_resolution) = method(raw)?;
    if e.bounces > 0 && !e.shadows {
        return Err((
            "bounces",
            "bounces need shadows: without occlusion no ray hits the character, so nothing reflects (set bounces = 0 or shadows = true)".into(),
        ));
    }
    Ok(e)
}

/// What an `[effects]` key's value is refused for: the key and the message.
type Refusal = (&'static str, String);

/// The method and light-map resolution of `raw`.
fn method(raw: &RawEffects) -> Result<(Choice<Method>, Choice<usize>), Refusal> {
    let method = match raw.method.as_deref() {
        None | Some("vertex") => Choice::Fixed(Method::Vertex),
        Some("lightmap") => Choice::Fixed(Method::LightMap),
        Some("auto") => Choice::Auto,
        Some(other) => {
            return Err((
                "method",
                format!("{other:?}: expected vertex, lightmap or auto"),
            ));
        }
    };
    let range = MIN_LIGHTMAP_RESOLUTION..=crate::rig::uv::MAX_RESOLUTION;
    let expected = format!(
        "expected {} to {} texels a side or \"auto\"",
        range.start(),
        range.end()
    );
    let resolution = match &raw.lightmap_resolution {
        None => Choice::Auto,
        Some(Word::Text(t)) if t == "auto" => Choice::Auto,
        Some(Word::Number(n)) if usize::try_from(*n).is_ok_and(|n| range.contains(&n)) => {
            Choice::Fixed(*n as usize)
        }
        Some(Word::Number(n)) => return Err(("lightmap_resolution", format!("{n}: {expected}"))),
        Some(Word::Text(t)) => return Err(("lightmap_resolution", format!("{t:?}: {expected}"))),
        Some(Word::Other(v)) => {
            let v = crate::text::excerpt(&v.to_string());
            return Err(("lightmap_resolution", format!("{v}: {expected}")));
        }
    };
    if method == Choice::Fixed(Method::Vertex) && raw.lightmap_resolution.is_some() {
        return Err((
            "lightmap_resolution",
            "a light-map resolution needs method = \"lightmap\" or \"auto\": the scene's method is vertex".into(),
        ));
    }
    Ok((method, resolution))
}

fn budget(raw: &RawBudget) -> Result<Budget, (&'static str, String)> {
    if let Some(us) = raw.us_per_frame
        && !(us.is_finite() && us > 0.0)
    {
        return Err(("us_per_frame", format!("{us}: expected a positive number")));
    }
    let bytes = match raw.bytes {
        None => None,
        Some(b) => Some(
            u64::try_from(b)
                .ok()
                .filter(|&b| b > 0)
                .ok_or(("bytes", format!("{b}: expected a positive number")))?,
        ),
    };
    Ok(Budget {
        us_per_frame: raw.us_per_frame,
        bytes,
    })
}

/// The environment; on error, the key (after `[environment]`) and what is wrong.
fn environment(
    raw: &RawEnvironment,
    resolve: &dyn Fn(&str) -> PathBuf,
) -> Result<Environment, (&'static str, String)> {
    match (&raw.sh, &raw.hdr, &raw.exr) {
        (Some(sh), None, None) => {
            let n = sh.len();
            let order = (1..=MAX_ORDER).find(|o| o * o == n);
            if order.is_none() {
                return Err((
                    " sh",
                    format!(
                        "{n} coefficients: expected a square number up to {} (1, 4, 9, …)",
                        MAX_ORDER * MAX_ORDER
                    ),
                ));
            }
            // Lighting is computed in f32: 1e300 is finite here and infinite there.
            let sh = sh
                .iter()
                .enumerate()
                .map(|(i, c)| finite_f32s(&format!("sh[{i}]"), c))
                .collect::<Result<Vec<_>, _>>()
                .map_err(|m| (" sh", m))?;
            if let Some(x) = sh[0].iter().find(|&&x| x < 0.0) {
                return Err((
                    " sh",
                    format!(
                        "`sh[0]` (band 0) holds {x}: it is the environment's mean radiance, which must not be negative"
                    ),
                ));
            }
            Ok(Environment::Sh(sh))
        }
        (None, Some(map), None) | (None, None, Some(map)) => Ok(Environment::Map(resolve(map))),
        _ => Err(("", "give exactly one of sh, hdr or exr".into())),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Scene, SceneError> {
        parse_scene(text, Path::new("scenes/fox.toml"))
    }

    const LIGHT: &str =
        "[[light]]\nkind = \"directional\"\ndirection = [0, 1, 0]\nirradiance = [1, 1, 1]\n";

    #[test]
    fn the_documented_example_reads_with_paths_relative_to_the_scene() {
        let text = "[source]\ngltf = \"Fox.gltf\"\ntrain = [\"Survey\"]\ntest = [\"Walk\", \"Run\"]\n\
             [effects]\nshadows = true\nbounces = 0\nalbedo = 0.6\norder = \"auto\"\nerror_target = 1.0\nrig = \"auto\"\nprecision = \"auto\"\n\
             [budget]\nus_per_frame = 100\nbytes = 1_000_000\n\
             [environment]\nhdr = \"studio.hdr\"\n\
             [[light]]\nkind = \"sphere\"\nposition = [0.0, 1.2, 0.8]\nradius = 0.1\nradiance = [4.0, 3.5, 3.0]\n";
        let scene = parse(text).unwrap();
        assert_eq!(
            scene.source,
            SceneSource::Gltf {
                path: PathBuf::from("scenes/Fox.gltf"),
                fps: None
            }
        );
        assert_eq!(scene.test, ["Walk", "Run"]);
        assert_eq!(scene.effects, Effects::default());
        assert_eq!(scene.budget.us_per_frame, Some(100.0));
        assert_eq!(scene.budget.bytes, Some(1_000_000));
        assert_eq!(
            scene.environment,
            Some(Environment::Map(PathBuf::from("scenes/studio.hdr")))
        );
        assert_eq!(scene.lights.len(), 1);
    }

    #[test]
    fn fixed_choices_read() {
        // `rig`, the irradiance rig's key before it was `irradiance_rig`, still reads.
        let text = format!(
            "[source]\nbuiltin = \"creature\"\ntrain = [\"training\"]\n[effects]\nshadows = false\norder = 3\nrig = \"gradient\"\nprecision = \"f16\"\nframe = \"world\"\n{LIGHT}"
        );
        let e = parse(&text).unwrap().effects;
        assert!(!e.shadows);
        assert_eq!(e.order, Choice::Fixed(3));
        assert!(matches!(e.rig, RigChoice::Kind(_)));
        assert_eq!(e.precision, Choice::Fixed(Precision::F16));
        assert_eq!(e.frame, ModelFrame::World);
        assert_eq!(e.method, Choice::Fixed(Method::Vertex));
        let methods = format!(
            "[source]\nbuiltin = \"creature\"\ntrain = [\"training\"]\n[effects]\nmethod = \"lightmap\"\nlightmap_resolution = 128\n{LIGHT}"
        );
        let e = parse(&methods).unwrap().effects;
        assert_eq!(e.method, Choice::Fixed(Method::LightMap));
        assert_eq!(e.lightmap_resolution, Choice::Fixed(128));
        let auto = methods
            .replace("\"lightmap\"", "\"auto\"")
            .replace("128", "\"auto\"");
        let e = parse(&auto).unwrap().effects;
        assert_eq!(
            (e.method, e.lightmap_resolution),
            (Choice::Auto, Choice::Auto)
        );
    }

    #[test]
    fn bad_scenes_name_the_item_and_what_is_wrong() {
        let base = "[source]\nbuiltin = \"human\"\ntrain = [\"training\"]\n";
        let cases = [
            (
                format!("{base}[effects]\nmethod = \"texel\"\n{LIGHT}"),
                "[effects] method",
                "expected vertex, lightmap or auto",
            ),
            (
                format!("{base}[effects]\nmethod = \"auto\"\nlightmap_resolution = 4\n{LIGHT}"),
                "[effects] lightmap_resolution",
                "4: expected 8 to 8192",
            ),
            (
                format!("{base}[effects]\nlightmap_resolution = 128\n{LIGHT}"),
                "[effects] lightmap_resolution",
                "needs method",
            ),
            (
                "[source]\ntrain = [\"a\"]\n".to_owned() + LIGHT,
                "[source]",
                "exactly one",
            ),
            (
                "[source]\nbuiltin = \"human\"\ngltf = \"a.gltf\"\ntrain = [\"a\"]\n".to_owned()
                    + LIGHT,
                "[source]",
                "builtin, gltf",
            ),
            (
                format!("{base}[effects]\norder = 7\n{LIGHT}"),
                "[effects] order",
                "1 to 6",
            ),
            (
                format!("{base}[effects]\norder = \"high\"\n{LIGHT}"),
                "[effects] order",
                "auto",
            ),
            (
                format!("{base}[effects]\norder = 2.0\n{LIGHT}"),
                "[effects] order",
                "order must be an integer 1..=6",
            ),
            (
                format!("{base}[effects]\norder = {{ a = 1, b = \"x\\ny\" }}\n{LIGHT}"),
                "[effects] order",
                "{ a = 1, b = \"\"\"…: order must be an integer 1..=6",
            ),
            (
                format!(
                    "[source]\nbuiltin = \"human\"\ntrain = [\"walk\"]\nvalidate = [\"walk\"]\n{LIGHT}"
                ),
                "[source] validate",
                "clip \"walk\" shares every frame with train clip \"walk\"",
            ),
            (
                format!(
                    "[source]\nbvh = \"a.bvh\"\ntrain = [\"0..9\"]\ntest = [\"a.bvh\"]\n{LIGHT}"
                ),
                "[source] test",
                "shares frames 0..9 of scenes/a.bvh with train clip \"0..9\"",
            ),
            (
                format!("{base}[effects]\nshadows = false\nbounces = 1\n{LIGHT}"),
                "[effects] bounces",
                "need shadows",
            ),
            (
                format!("{base}[effects]\nalbedo = 1.5\n{LIGHT}"),
                "[effects] albedo",
                "[0, 1]",
            ),
            (
                format!("{base}[effects]\nerror_target = 0\n{LIGHT}"),
                "error_target",
                "positive",
            ),
            (
                format!("{base}[effects]\nirradiance_rig = \"blob\"\n{LIGHT}"),
                "[effects] irradiance_rig",
                "blob",
            ),
            (
                format!("{base}[effects]\nshadow = true\n{LIGHT}"),
                "TOML",
                "unknown field",
            ),
            (
                format!("{base}[budget]\nbytes = -3\n{LIGHT}"),
                "[budget] bytes",
                "positive",
            ),
            (
                format!("{base}[environment]\nsh = [[1,1,1],[0,0,0]]\n"),
                "[environment] sh",
                "square",
            ),
            (
                format!("{base}[environment]\nsh = [[1,1,1]]\nhdr = \"a.hdr\"\n"),
                "[environment]",
                "exactly one",
            ),
            (base.to_owned(), "lighting", "nothing lights it"),
            (
                format!("{base}[[light]]\nkind = \"sphere\"\nposition = [0, 0, 0]\n"),
                "light 1 (sphere)",
                "radius",
            ),
            (
                "[source]\nbuiltin = \"human\"\n".to_owned() + LIGHT,
                "[source] train",
                "training clips",
            ),
            (
                "[source]\nbuiltin = \"dog\"\ntrain = [\"a\"]\n".to_owned() + LIGHT,
                "[source]",
                "dog",
            ),
        ];
        for (text, item, words) in cases {
            let err = parse(&text).unwrap_err();
            let shown = err.to_string();
            assert!(shown.starts_with("scenes/fox.toml: "), "{shown}");
            assert!(!shown.contains('\n'), "{shown:?}");
            assert!(err.item.contains(item), "{item}: {shown}");
            assert!(shown.contains(words), "{words}: {shown}");
        }
    }

    /// Every example in fixtures/scenes reads, and its paths resolve against its directory.
    #[test]
    fn every_fixture_scene_reads() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../fixtures/scenes");
        let mut read = 0;
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_some_and(|e| e == "toml") {
                let scene = read_scene(&path).unwrap_or_else(|e| panic!("{e}"));
                if let SceneSource::Gltf { path: gltf, .. } = &scene.source {
                    assert!(gltf.starts_with(&dir), "{}", gltf.display());
                }
                read += 1;
            }
        }
        assert!(read >= 5, "{read} scenes");
    }

    #[test]
    fn sh_environments_and_obj_sequences_read() {
        let text = "[source]\nobj_seq = \"poses\"\nangles = \"poses.csv\"\n[environment]\nsh = [[1, 1, 1], [0, 0.5, 0], [0, 0, 0], [0, 0, 0]]\n";
        let scene = parse(text).unwrap();
        assert_eq!(
            scene.source,
            SceneSource::ObjSeq {
                dir: PathBuf::from("scenes/poses"),
                angles: PathBuf::from("scenes/poses.csv")
            }
        );
        let Some(Environment::Sh(sh)) = scene.environment else {
            panic!("no SH environment");
        };
        assert_eq!(sh.len(), 4);
        assert!(scene.lights.is_empty());
    }
}
