//! Where the command line's poses come from: an OBJ sequence with a joint-angle CSV, or a
//! rig (the built-in character, a glTF skin, a BVH-driven mannequin) and one of its clips.

use std::ops::Range;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};

use crate::progress::Reporter;
use crate::report::experiment::pose_all;
use crate::rig::character::Character;
use crate::rig::gltf::GltfRig;
use crate::rig::mannequin::{MocapOptions, MocapRig};
use crate::rig::mesh::Mesh;
use crate::rig::mocap::Mocap;
use crate::rig::{Clip, Rig};

/// Source options shared by `train`, `simulate` and `eval`.
#[derive(Debug, Clone, Default, clap::Args)]
pub struct SourceArgs {
    /// Directory of OBJ files, one per pose, sorted by file name, all with the same mesh
    /// (with --angles for `train`).
    #[arg(long, conflicts_with_all = ["builtin"])]
    pub obj_seq: Option<PathBuf>,
    /// CSV with one row of joint angles per pose (a header row is allowed).
    #[arg(long)]
    pub angles: Option<PathBuf>,
    /// The built-in procedural character; pick its clip with --clip (training, wave, walk,
    /// reach).
    #[arg(long, conflicts_with_all = ["gltf", "bvh"])]
    pub builtin: bool,
    /// A glTF 2.0 character (.gltf with embedded or external buffers, or .glb) with a skin;
    /// pick its animation with --clip.
    #[arg(long, conflicts_with_all = ["bvh", "obj_seq"])]
    pub gltf: Option<PathBuf>,
    /// A BVH motion-capture file driving a mannequin built from its skeleton (or from
    /// --mannequin's).
    #[arg(long, conflicts_with = "obj_seq")]
    pub bvh: Option<PathBuf>,
    /// The clip to use: a glTF animation or a built-in clip.
    #[arg(long)]
    pub clip: Option<String>,
    /// Sampling rate of the clip in frames per second (glTF default 30; BVH default: the
    /// file's own rate).
    #[arg(long, allow_negative_numbers = true)]
    pub fps: Option<f64>,
    /// BVH frames A..B (half-open, at the file's rate, before resampling); default all.
    #[arg(long, value_parser = parse_range)]
    pub frames: Option<Range<usize>>,
    /// Build the mannequin from this BVH's skeleton and retarget --bvh's motion onto it by
    /// joint name, so a model trained on one file can be evaluated on another.
    #[arg(long, requires = "bvh")]
    pub mannequin: Option<PathBuf>,
    /// Leave the hat off the BVH mannequin.
    #[arg(long, requires = "bvh")]
    pub no_hat: bool,
    /// Keep the BVH root's translation as pose entries (transfer does not depend on it).
    #[arg(long, requires = "bvh")]
    pub root_translation: bool,
}

/// Parses `A..B` (half-open frame indices).
fn parse_range(text: &str) -> Result<Range<usize>, String> {
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
        return Err(format!("{text:?}: the range is empty"));
    }
    Ok(range)
}

/// The rate glTF clips are sampled at unless --fps says otherwise.
const GLTF_FPS: f64 = 30.0;

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
    /// A rig and the frames of one of its clips.
    Rig {
        /// The character.
        rig: Box<dyn Rig>,
        /// The clip.
        clip: Clip,
    },
}

impl SourceArgs {
    /// Whether a rig (rather than files of meshes or angles) was named.
    pub fn names_rig(&self) -> bool {
        self.builtin || self.gltf.is_some() || self.bvh.is_some()
    }

    /// The rig and clip the options name. Errors when they name no rig. Notes on what the rig
    /// leaves out of the clip go to `reporter`.
    pub fn rig(&self, reporter: &dyn Reporter) -> Result<(Box<dyn Rig>, Clip)> {
        if self.builtin {
            let character = Character::builtin();
            let clip = character.clip(self.clip_name(&character)?)?;
            return Ok((Box::new(character), clip));
        }
        if let Some(path) = &self.gltf {
            must_exist(path, &["gltf", "glb"])?;
            let rig = GltfRig::load(path, self.fps.unwrap_or(GLTF_FPS))?;
            let clip = rig.clip(self.clip_name(&rig)?)?;
            for held in rig
                .held_channels()
                .iter()
                .filter(|h| h.animation == clip.name)
            {
                reporter.note(&format!("note: {}: {held}", path.display()));
            }
            return Ok((Box::new(rig), clip));
        }
        if let Some(path) = &self.bvh {
            must_exist(path, &["bvh"])?;
            if let Some(skeleton) = &self.mannequin {
                must_exist(skeleton, &["bvh"])?;
            }
            return self.bvh_rig(path, reporter);
        }
        bail!("no character given: use --builtin, --gltf or --bvh (or --obj-seq with --angles)")
    }

    /// The mannequin (of --mannequin's skeleton, or the file's own) and the file's motion.
    fn bvh_rig(&self, path: &Path, reporter: &dyn Reporter) -> Result<(Box<dyn Rig>, Clip)> {
        let options = MocapOptions {
            root_translation: self.root_translation,
            hat: !self.no_hat,
            fps: self.fps,
        };
        let Some(skeleton) = &self.mannequin else {
            let rig = MocapRig::from_file(path, &options)?;
            let frames = self.frames.clone().unwrap_or(0..rig.mocap().frame_count());
            let clip = rig.clip_range(frames)?;
            return Ok((Box::new(rig), clip));
        };
        let rig = MocapRig::from_file(skeleton, &options)?;
        let motion = Mocap::read(path)?;
        let frames = self.frames.clone().unwrap_or(0..motion.frame_count());
        let name = path
            .file_stem()
            .map_or_else(|| "motion".into(), |s| s.to_string_lossy().into_owned());
        let retargeted = rig.retarget(&motion, &name, frames)?;
        if !retargeted.missing.is_empty() {
            reporter.note(&format!(
                "joints of the mannequin that {} does not animate (kept at rest): {}",
                path.display(),
                retargeted.missing.join(", ")
            ));
        }
        Ok((Box::new(rig), retargeted.clip))
    }

    fn clip_name<'a>(&'a self, rig: &dyn Rig) -> Result<&'a str> {
        self.clip.as_deref().with_context(|| {
            format!(
                "--clip is needed; available: {}",
                rig.clip_names().join(", ")
            )
        })
    }

    /// The meshes to bake, without angles: every OBJ of --obj-seq (--angles is not needed), or
    /// the rig posed at every frame of its clip.
    pub fn meshes(&self, reporter: &dyn Reporter) -> Result<Vec<Mesh>> {
        if self.names_rig() {
            let (rig, clip) = self.rig(reporter)?;
            return pose_all(rig.as_ref(), &clip.name, &clip.frames);
        }
        let Some(dir) = &self.obj_seq else {
            bail!("give a character (--builtin, --gltf or --bvh) or --obj-seq DIR");
        };
        read_same_meshes(&obj_sequence(dir)?)
    }

    /// The poses the options name: a rig's clip, or an OBJ sequence with its angles.
    pub fn poses(&self, reporter: &dyn Reporter) -> Result<Poses> {
        if self.names_rig() {
            let (rig, clip) = self.rig(reporter)?;
            return Ok(Poses::Rig { rig, clip });
        }
        let (Some(dir), Some(csv)) = (&self.obj_seq, &self.angles) else {
            bail!(
                "give a character (--builtin, --gltf or --bvh) or --obj-seq DIR with --angles FILE"
            );
        };
        let files = obj_sequence(dir)?;
        let angles = crate::io::angles::read_angles(csv, None)?;
        if angles.len() != files.len() {
            bail!(
                "{} has {} rows of angles but {} holds {} OBJ files: one row per pose is needed",
                csv.display(),
                angles.len(),
                dir.display(),
                files.len()
            );
        }
        Ok(Poses::Meshes {
            meshes: read_same_meshes(&files)?,
            files,
            angles,
        })
    }
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

/// Reads every file; all must share the first one's vertex count and triangles.
fn read_same_meshes(files: &[PathBuf]) -> Result<Vec<Mesh>> {
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
    Ok(meshes)
}
