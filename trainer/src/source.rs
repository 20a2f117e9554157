//! Where the command line's poses come from: an OBJ sequence with a joint-angle CSV, or a
//! rig (the built-in character, a glTF skin, a BVH-driven mannequin) and one of its clips.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};

use crate::character::Character;
use crate::mesh::Mesh;
use crate::rig::{Clip, Rig};

/// Source options shared by `train`, `simulate` and `eval`.
#[derive(Debug, Clone, Default, clap::Args)]
pub struct SourceArgs {
    /// Directory of OBJ files, one per pose, sorted by file name, all with the same mesh
    /// (with --angles).
    #[arg(long, conflicts_with_all = ["builtin"])]
    pub obj_seq: Option<PathBuf>,
    /// CSV with one row of joint angles per pose (a header row is allowed).
    #[arg(long)]
    pub angles: Option<PathBuf>,
    /// The built-in procedural character; pick its clip with --clip (training, wave, walk,
    /// reach).
    #[arg(long)]
    pub builtin: bool,
    /// The clip to use.
    #[arg(long)]
    pub clip: Option<String>,
}

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
        self.builtin
    }

    /// The rig and clip the options name. Errors when they name no rig.
    pub fn rig(&self) -> Result<(Box<dyn Rig>, Clip)> {
        if self.builtin {
            let character = Character::builtin();
            let clip = Rig::clip(&character, self.clip_name(&character)?)?;
            return Ok((Box::new(character), clip));
        }
        bail!("no character given: use --builtin (or --obj-seq with --angles)")
    }

    fn clip_name<'a>(&'a self, rig: &dyn Rig) -> Result<&'a str> {
        self.clip.as_deref().with_context(|| {
            format!(
                "--clip is needed; available: {}",
                rig.clip_names().join(", ")
            )
        })
    }

    /// The poses the options name: a rig's clip, or an OBJ sequence with its angles.
    pub fn poses(&self) -> Result<Poses> {
        if self.names_rig() {
            let (rig, clip) = self.rig()?;
            return Ok(Poses::Rig { rig, clip });
        }
        let (Some(dir), Some(csv)) = (&self.obj_seq, &self.angles) else {
            bail!("give a character (--builtin) or --obj-seq DIR with --angles FILE");
        };
        let files = obj_sequence(dir)?;
        let angles = crate::angles::read_angles(csv)?;
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
        let mesh = crate::obj::read_obj(file)?;
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
