//! The source options of `train`, `simulate` and `eval`, and what they name: an OBJ sequence
//! (with angles), or a character and its clip, loaded by [`crate::io::source`].

use std::ops::Range;
use std::path::PathBuf;

use anyhow::{Context, Result, bail};

use crate::bake::clip::pose_all;
use crate::io::outputs::{Input, gltf_inputs, obj_sequence_inputs};
use crate::io::source::{Poses, RigSource, obj_sequence_meshes};
use crate::progress::Reporter;
use crate::rig::mannequin::MocapOptions;
use crate::rig::mesh::Mesh;
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

/// The rate glTF clips are sampled at unless --fps says otherwise.
const GLTF_FPS: f64 = 30.0;

impl SourceArgs {
    /// The files and directories the options read, which no output may be.
    pub fn inputs(&self) -> Vec<Input> {
        let mut inputs = Vec::new();
        if let Some(dir) = &self.obj_seq {
            inputs.extend(obj_sequence_inputs(dir));
        }
        if let Some(csv) = &self.angles {
            inputs.push(Input::new(csv, "the angles CSV"));
        }
        if let Some(gltf) = &self.gltf {
            inputs.extend(gltf_inputs(gltf));
        }
        if let Some(bvh) = &self.bvh {
            inputs.push(Input::new(bvh, "the BVH motion"));
        }
        if let Some(skeleton) = &self.mannequin {
            inputs.push(Input::new(skeleton, "the mannequin's BVH"));
        }
        inputs
    }

    /// Whether a rig (rather than files of meshes or angles) was named.
    pub fn names_rig(&self) -> bool {
        self.builtin || self.gltf.is_some() || self.bvh.is_some()
    }

    /// The character the options name, if any.
    fn rig_source(&self) -> Option<RigSource> {
        if self.builtin {
            return Some(RigSource::Builtin);
        }
        if let Some(path) = &self.gltf {
            return Some(RigSource::Gltf {
                path: path.clone(),
                fps: self.fps.unwrap_or(GLTF_FPS),
            });
        }
        let path = self.bvh.as_ref()?;
        Some(RigSource::Mocap {
            path: path.clone(),
            skeleton: self.mannequin.clone(),
            frames: self.frames.clone(),
            options: MocapOptions {
                root_translation: self.root_translation,
                hat: !self.no_hat,
                fps: self.fps,
            },
        })
    }

    /// The rig and clip the options name. Errors when they name no rig. Notes on what the rig
    /// leaves out of the clip go to `reporter`.
    pub fn rig(&self, reporter: &dyn Reporter) -> Result<(Box<dyn Rig>, Clip)> {
        let Some(source) = self.rig_source() else {
            bail!("no character given: use --builtin, --gltf or --bvh (or --obj-seq with --angles)")
        };
        source.load(|rig| self.clip_name(rig), reporter)
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
        obj_sequence_meshes(dir, reporter)
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
        Poses::from_obj_sequence(dir, csv, reporter)
    }
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
