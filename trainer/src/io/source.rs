//! Where poses come from: an OBJ sequence with a joint-angle CSV, or a rig (the built-in
//! character, a glTF skin, a mannequin driven by motion capture) and clips of it. The command
//! line's source options (`cli::source`) name one of these; loading happens here.

use std::collections::HashMap;
use std::ops::Range;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};

use crate::limits::MAX_FRAMES;
use crate::progress::Reporter;
use crate::rig::character::Character;
use crate::rig::creature::Creature;
use crate::rig::gltf::{GltfError, GltfRig};
use crate::rig::mannequin::{MocapOptions, MocapRig, MocapRigError};
use crate::rig::mesh::{Mesh, degenerate_note};
use crate::rig::mesh_sequence::MeshSequence;
use crate::rig::mocap::Mocap;
use crate::rig::{Clip, Rig};

/// Poses from a source, ready to bake or evaluate.
pub enum Poses {
    /// Meshes read from files, with one row of angles each.
    Meshes {
        /// The files, sorted by name.
        files: Vec<PathBuf>,
        /// The meshes, in file order.
        meshes: Vec<Mesh>,
        /// One row of joint angles per mesh.
        angles: Vec<Vec<f64>>,
    },
    /// A rig and clips of it.
    Rig {
        /// The character.
        rig: Box<dyn Rig>,
        /// The clips to train on (or to bake or evaluate), in order.
        clips: Vec<Clip>,
        /// Clips held out whole to choose the model by (`--validate`).
        validation: Vec<Clip>,
    },
}

impl Poses {
    /// The character's up axis: the rig's, or z for an OBJ sequence, which has no rig to say
    /// and is taken to stand like the built-in characters.
    pub fn up(&self) -> glam::Vec3 {
        match self {
            Poses::Meshes { .. } => glam::Vec3::Z,
            Poses::Rig { rig, .. } => rig.up(),
        }
    }

    /// An OBJ sequence (every `.obj` file of `dir`, sorted by name, all with the same mesh)
    /// with one row of `angles` per file. Degenerate triangles are noted to `reporter`.
    pub fn from_obj_sequence(dir: &Path, angles: &Path, reporter: &dyn Reporter) -> Result<Poses> {
        let (files, meshes, angles) = read_obj_sequence(dir, angles, reporter)?;
        Ok(Poses::Meshes {
            files,
            meshes,
            angles,
        })
    }
}

/// An OBJ sequence's files, their meshes and one row of angles each.
type ObjSequence = (Vec<PathBuf>, Vec<Mesh>, Vec<Vec<f64>>);

/// The files of an OBJ sequence, their meshes and one row of `angles` each (see
/// [`Poses::from_obj_sequence`]).
fn read_obj_sequence(dir: &Path, angles: &Path, reporter: &dyn Reporter) -> Result<ObjSequence> {
    let files = obj_sequence(dir)?;
    let rows = crate::io::angles::read_angles(angles, None)?;
    if rows.len() != files.len() {
        bail!(
            "{} has {} rows of angles but {} holds {} OBJ files: one row per pose is needed",
            angles.display(),
            rows.len(),
            dir.display(),
            files.len()
        );
    }
    let meshes = read_same_meshes(&files, reporter)?;
    Ok((files, meshes, rows))
}

/// An OBJ sequence with its angles (as [`Poses::from_obj_sequence`] reads them) as a skinless
/// character, [`MeshSequence`], and its one clip: what the commands written for characters
/// (the light-map ones) take. The first file's texture coordinates (`vt`) are its UVs.
pub fn obj_sequence_rig(
    dir: &Path,
    angles: &Path,
    reporter: &dyn Reporter,
) -> Result<(Box<dyn Rig>, Clip)> {
    let (files, meshes, angles) = read_obj_sequence(dir, angles, reporter)?;
    let (_, uvs) = crate::io::obj::read_obj_with_uvs(&files[0])?;
    let sequence = MeshSequence::new(dir.display().to_string(), meshes, angles, uvs)?;
    let clip = sequence.clip(&dir.display().to_string())?;
    Ok((Box::new(sequence), clip))
}

/// The meshes of an OBJ sequence, without angles: every `.obj` file of `dir`, sorted by name,
/// all with the same mesh. Degenerate triangles are noted to `reporter`.
pub fn obj_sequence_meshes(dir: &Path, reporter: &dyn Reporter) -> Result<Vec<Mesh>> {
    read_same_meshes(&obj_sequence(dir)?, reporter)
}

/// The clips one after the other, as one clip named by their names joined with `+` (a
/// simulation or an evaluation of several clips writes their frames in order).
pub fn joined(clips: Vec<Clip>) -> Clip {
    let name = clip_names(&clips);
    let fps = clips.first().map_or(0.0, |c| c.fps);
    Clip {
        name,
        fps,
        frames: clips.into_iter().flat_map(|c| c.frames).collect(),
    }
}

/// The clips' names joined with `+`.
pub fn clip_names(clips: &[Clip]) -> String {
    let names: Vec<&str> = clips.iter().map(|c| c.name.as_str()).collect();
    names.join(" + ")
}

/// One of the built-in procedural characters.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BuiltinCharacter {
    /// The human with the wide-brimmed hat ([`Character`]).
    #[default]
    Human,
    /// The long-tailed, four-legged creature ([`Creature`]).
    Creature,
}

impl BuiltinCharacter {
    /// What messages call it.
    pub fn description(self) -> &'static str {
        match self {
            BuiltinCharacter::Human => "the built-in character",
            BuiltinCharacter::Creature => "the built-in creature",
        }
    }

    /// Builds it.
    pub fn build(self) -> Box<dyn Rig> {
        match self {
            BuiltinCharacter::Human => Box::new(Character::builtin()),
            BuiltinCharacter::Creature => Box::new(Creature::builtin()),
        }
    }
}

/// A character to load, and how to sample its clips.
#[derive(Clone, Debug)]
pub enum RigSource {
    /// A built-in procedural character.
    Builtin(BuiltinCharacter),
    /// A glTF 2.0 character (`.gltf` or `.glb`) with a skin, its animations sampled at `fps`.
    Gltf {
        /// The file.
        path: PathBuf,
        /// Frames per second.
        fps: f64,
    },
    /// A mannequin built from the skeleton of a BVH file, driven by motion capture: that
    /// file's own motion, or other files' retargeted onto it by joint name.
    Mocap {
        /// The file whose skeleton the mannequin is built from.
        skeleton: PathBuf,
        /// How the mannequin is built and the motion resampled.
        options: MocapOptions,
    },
}

/// Parses frames `A..B` (half-open indices), refusing an empty or reversed range: the one
/// reading of `--frames`, `--validate A..B` and a BVH scene's clips.
pub fn parse_frames(text: &str) -> Result<Range<usize>, String> {
    let (a, b) = text
        .split_once("..")
        .ok_or_else(|| format!("{text:?}: expected A..B, e.g. 0..120"))?;
    let number = |s: &str| {
        s.trim()
            .parse::<usize>()
            .map_err(|_| format!("{text:?}: {s:?} is not a frame index"))
    };
    let range = number(a)?..number(b)?;
    if range.is_empty() {
        return Err(format!(
            "{text:?}: the frame range is empty or reversed (A..B needs A < B)"
        ));
    }
    Ok(range)
}

/// A clip to take from a loaded character.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum ClipSpec {
    /// A named clip: the built-in character's, or a glTF animation.
    Named(String),
    /// Frames of a BVH file's motion (half-open, at the file's rate; all when `None`), on the
    /// mannequin: its own when the file is the mannequin's skeleton, otherwise retargeted.
    Motion {
        /// The motion-capture file.
        path: PathBuf,
        /// The frames.
        frames: Option<Range<usize>>,
    },
}

/// A loaded character, from which clips are taken.
pub enum LoadedRig {
    /// A built-in character.
    Builtin(Box<dyn Rig>),
    /// A glTF character, with its file.
    Gltf(Box<GltfRig>, PathBuf),
    /// A mannequin, with the file its skeleton (and its own motion) comes from.
    Mannequin(Box<MocapRig>, PathBuf),
}

impl RigSource {
    /// Loads the character. A file that does not exist is an error listing the files of its
    /// kind beside it. The bind mesh's degenerate triangles are noted to `reporter`.
    pub fn load(&self, reporter: &dyn Reporter) -> Result<LoadedRig> {
        let loaded = match self {
            RigSource::Builtin(which) => LoadedRig::Builtin(which.build()),
            RigSource::Gltf { path, fps } => {
                must_exist(path, &["gltf", "glb"])?;
                let rig = GltfRig::load(path, *fps)?;
                if rig.clip_names().is_empty() {
                    return Err(GltfError::NoAnimations { path: path.clone() }.into());
                }
                LoadedRig::Gltf(Box::new(rig), path.clone())
            }
            RigSource::Mocap { skeleton, options } => {
                must_exist(skeleton, &["bvh"])?;
                LoadedRig::Mannequin(
                    Box::new(build_mannequin(skeleton, options)?),
                    skeleton.clone(),
                )
            }
        };
        if let Some(note) = degenerate_note(&self.mesh_name(), loaded.rig().bind_mesh()) {
            reporter.note(&note);
        }
        Ok(loaded)
    }

    /// What the character's mesh is called in notes.
    fn mesh_name(&self) -> String {
        match self {
            RigSource::Builtin(which) => which.description().to_owned(),
            RigSource::Gltf { path, .. } => format!("{}, skinned mesh", path.display()),
            RigSource::Mocap { skeleton, .. } => {
                format!("the mannequin of {}", skeleton.display())
            }
        }
    }
}

impl LoadedRig {
    /// The character.
    pub fn rig(&self) -> &dyn Rig {
        match self {
            LoadedRig::Builtin(rig) => rig.as_ref(),
            LoadedRig::Gltf(rig, _) => rig.as_ref(),
            LoadedRig::Mannequin(rig, _) => rig.as_ref(),
        }
    }

    /// The character, owned.
    pub fn into_rig(self) -> Box<dyn Rig> {
        match self {
            LoadedRig::Builtin(rig) => rig,
            LoadedRig::Gltf(rig, _) => rig,
            LoadedRig::Mannequin(rig, _) => rig,
        }
    }

    /// The clip `spec` names. Notes on what it leaves out (glTF channels held at rest,
    /// mannequin joints a retargeted motion does not animate) go to `reporter`.
    pub fn clip(&self, spec: &ClipSpec, reporter: &dyn Reporter) -> Result<Clip> {
        match (self, spec) {
            (LoadedRig::Builtin(rig), ClipSpec::Named(name)) => Ok(rig.clip(name)?),
            (LoadedRig::Gltf(rig, path), ClipSpec::Named(name)) => {
                let clip = rig.clip(name)?;
                for held in rig
                    .held_channels()
                    .iter()
                    .filter(|h| h.animation == clip.name)
                {
                    reporter.note(&format!("note: {}: {held}", path.display()));
                }
                Ok(clip)
            }
            (LoadedRig::Mannequin(rig, own), ClipSpec::Motion { path, frames }) => {
                must_exist(path, &["bvh"])?;
                let mut clip = if path == own {
                    rig.clip_range(frames.clone().unwrap_or(0..rig.mocap().frame_count()))?
                } else {
                    retargeted(rig, own, path, frames.clone(), reporter)?
                };
                if let Some(range) = frames {
                    clip.name = format!("{}[{}..{}]", clip.name, range.start, range.end);
                }
                Ok(clip)
            }
            (_, ClipSpec::Motion { path, .. }) => bail!(
                "{}: motion capture drives a BVH mannequin, not this character",
                path.display()
            ),
            (LoadedRig::Mannequin(..), ClipSpec::Named(name)) => bail!(
                "clip {}: a BVH file's one clip is its motion (choose frames with A..B)",
                crate::text::quote(name)
            ),
        }
    }

    /// Every clip `specs` names, in order. Their frames together are held to the most one run
    /// bakes or evaluates ([`MAX_FRAMES`]) before the work grows with the names: a glTF
    /// animation's frames are counted from its length before any clip is sampled, a clip named
    /// twice is sampled once, and sampling stops once the distinct clips pass the limit.
    pub fn clips(&self, specs: &[ClipSpec], reporter: &dyn Reporter) -> Result<Vec<Clip>> {
        if let LoadedRig::Gltf(rig, _) = self {
            let mut total = 0usize;
            for spec in specs {
                if let ClipSpec::Named(name) = spec {
                    total = total.saturating_add(rig.frame_count(name)?);
                }
            }
            check_frames(specs, total, "")?;
        }
        let mut index: HashMap<&ClipSpec, usize> = HashMap::new();
        let mut distinct: Vec<Clip> = Vec::new();
        let mut sampled = 0usize;
        for spec in specs {
            if !index.contains_key(spec) {
                let clip = self.clip(spec, reporter)?;
                sampled = sampled.saturating_add(clip.frames.len());
                check_frames(specs, sampled, "at least ")?;
                index.insert(spec, distinct.len());
                distinct.push(clip);
            }
        }
        let total = specs.iter().map(|s| distinct[index[s]].frames.len()).sum();
        check_frames(specs, total, "")?;
        Ok(specs.iter().map(|s| distinct[index[s]].clone()).collect())
    }
}

/// Refuses clips `specs` that hold `total` frames (`at_least` when not all are counted) if
/// that is more than one run bakes or evaluates.
fn check_frames(specs: &[ClipSpec], total: usize, at_least: &str) -> Result<()> {
    if total <= MAX_FRAMES {
        return Ok(());
    }
    let name = |s: &ClipSpec| match s {
        ClipSpec::Named(name) => name.clone(),
        ClipSpec::Motion { path, .. } => path.display().to_string(),
    };
    let mut names: Vec<String> = specs.iter().take(3).map(name).collect();
    if specs.len() > names.len() {
        names.push("…".into());
    }
    bail!(
        "{} clips ({}) hold {at_least}{total} frames, more than the {MAX_FRAMES} one run bakes or evaluates: name fewer clips",
        specs.len(),
        names.join(", ")
    )
}

/// `path`'s motion (frames `frames` of it, all when `None`) retargeted onto `rig`, the
/// mannequin of `skeleton`.
fn retargeted(
    rig: &MocapRig,
    skeleton: &Path,
    path: &Path,
    frames: Option<Range<usize>>,
    reporter: &dyn Reporter,
) -> Result<Clip> {
    let motion = Mocap::read(path)?;
    let frames = frames.unwrap_or(0..motion.frame_count());
    let name = path
        .file_stem()
        .map_or_else(|| "motion".into(), |s| s.to_string_lossy().into_owned());
    let retargeted = rig.retarget(&motion, &name, frames).with_context(|| {
        format!(
            "retargeting {} onto the mannequin of {}",
            path.display(),
            skeleton.display()
        )
    })?;
    if !retargeted.missing.is_empty() {
        reporter.note(&format!(
            "joints of the mannequin that {} does not animate (kept at rest): {}",
            path.display(),
            retargeted.missing.join(", ")
        ));
    }
    if !retargeted.extra.is_empty() {
        reporter.note(&format!(
            "joints of {} that the mannequin of {} lacks (their motion is dropped): {} of {}: {}",
            path.display(),
            skeleton.display(),
            retargeted.extra.len(),
            motion.joints().len(),
            retargeted.extra.join(", ")
        ));
    }
    Ok(retargeted.clip)
}

/// The mannequin of `path`'s skeleton; errors past parsing (a skeleton too large or without
/// bones) name the file.
fn build_mannequin(path: &Path, options: &MocapOptions) -> Result<MocapRig> {
    MocapRig::from_file(path, options).map_err(|e| match e {
        MocapRigError::Mocap(_) => e.into(),
        other => anyhow::Error::from(other).context(path.display().to_string()),
    })
}

/// Errors when `path` does not exist, listing the files with one of `extensions` that its
/// directory does hold.
fn must_exist(path: &Path, extensions: &[&str]) -> Result<()> {
    if path.exists() {
        return Ok(());
    }
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let mut found: Vec<String> = std::fs::read_dir(dir)
        .into_iter()
        .flatten()
        .flatten()
        .map(|e| e.path())
        .filter(|p| {
            p.extension()
                .and_then(|e| e.to_str())
                .is_some_and(|e| extensions.iter().any(|x| e.eq_ignore_ascii_case(x)))
        })
        .filter_map(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()))
        .collect();
    found.sort();
    let available = if found.is_empty() {
        "none".to_owned()
    } else {
        found.join(", ")
    };
    bail!(
        "{}: no such file; .{} files in {}: {available}",
        path.display(),
        extensions.join("/."),
        dir.display()
    )
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

/// Reads every file; all must share the first one's vertex count and triangles. The first file
/// with degenerate triangles is noted to `reporter`, once, with how many files have them.
fn read_same_meshes(files: &[PathBuf], reporter: &dyn Reporter) -> Result<Vec<Mesh>> {
    let mut meshes: Vec<Mesh> = Vec::with_capacity(files.len());
    for file in files {
        let mesh = crate::io::obj::read_obj(file)?;
        if let Some(first) = meshes.first()
            && (mesh.vertex_count() != first.vertex_count() || mesh.triangles != first.triangles)
        {
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
        meshes.push(mesh);
    }
    let mut notes = files
        .iter()
        .zip(&meshes)
        .filter_map(|(file, mesh)| degenerate_note(&file.display().to_string(), mesh));
    if let Some(first) = notes.next() {
        let others = notes.count();
        match others {
            0 => reporter.note(&first),
            n => reporter.note(&format!(
                "{first} (and {n} more of the {} files have such triangles)",
                files.len()
            )),
        }
    }
    Ok(meshes)
}
