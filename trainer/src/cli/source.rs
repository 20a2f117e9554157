//! The source options of `train`, `simulate` and `eval`, and what they name: an OBJ sequence
//! (with angles), or a character and its clip, loaded by [`crate::io::source`].

use std::ops::Range;
use std::path::PathBuf;

use anyhow::{Context, Result, bail};

use crate::bake::BakeSettings;
use crate::bake::budget::Workload;
use crate::bake::clip::pose_all;
use crate::io::outputs::{Input, gltf_inputs, obj_sequence_inputs};
use crate::io::source::{
    BuiltinCharacter, ClipSpec, Poses, RigSource, joined, obj_sequence_meshes, obj_sequence_rig,
    parse_frames,
};
use crate::progress::Reporter;
use crate::rig::mannequin::MocapOptions;
use crate::rig::mesh::Mesh;
use crate::rig::{Clip, Rig};
use crate::scene::file::{CLIP_KEYS, Scene, SceneSource};

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
    /// A built-in procedural character (see --character); pick its clips with --clip (the
    /// human's: training, wave, walk, reach, stretch; the creature's: training, prowl, lash,
    /// crouch).
    #[arg(long, conflicts_with_all = ["gltf", "bvh"])]
    pub builtin: bool,
    /// Which built-in character --builtin gives: the human (the default) or the long-tailed,
    /// four-legged creature, about 4 m long.
    #[arg(long, value_enum)]
    pub character: Option<CharacterArg>,
    /// A glTF 2.0 character (.gltf with embedded or external buffers, or .glb) with a skin;
    /// pick its animations with --clip.
    #[arg(long, conflicts_with_all = ["bvh", "obj_seq"])]
    pub gltf: Option<PathBuf>,
    /// A BVH motion-capture file driving a mannequin built from the first one's skeleton (or
    /// from --mannequin's); repeat for several files, whose frames are used in order.
    #[arg(long, conflicts_with = "obj_seq")]
    pub bvh: Vec<PathBuf>,
    /// A clip to use: a glTF animation or a built-in clip; repeat for several, used in order.
    #[arg(long)]
    pub clip: Vec<String>,
    /// Sampling rate of the clip in frames per second (glTF default 30; BVH default: the
    /// file's own rate).
    #[arg(long, allow_negative_numbers = true)]
    pub fps: Option<f64>,
    /// BVH frames A..B (half-open, at the file's rate, before resampling); default all.
    /// Repeat for several ranges of one --bvh file, or give one per --bvh file.
    #[arg(long, value_parser = parse_frames)]
    pub frames: Vec<Range<usize>>,
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

/// What a bake of `aprt simulate` works on ([`SourceArgs::meshes`]).
pub struct PosedMeshes {
    /// The mesh whose topology every pose shares: the character's bind mesh, or the first
    /// mesh of an OBJ sequence. Surface points are spread on it.
    pub bind: Mesh,
    /// One posed mesh per frame.
    pub poses: Vec<Mesh>,
}

/// `--character`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum CharacterArg {
    /// The human with the wide-brimmed hat.
    Human,
    /// The long-tailed creature.
    Creature,
}

impl From<CharacterArg> for BuiltinCharacter {
    fn from(arg: CharacterArg) -> BuiltinCharacter {
        match arg {
            CharacterArg::Human => BuiltinCharacter::Human,
            CharacterArg::Creature => BuiltinCharacter::Creature,
        }
    }
}

/// A character, the clips to use and the clips held out to validate on.
type RigClips = (Box<dyn Rig>, Vec<Clip>, Vec<Clip>);

/// A scene's character and the clips of its `train`, `validate` and `test` keys.
type SceneRigClips = (Box<dyn Rig>, [Vec<Clip>; 3]);

/// The rate glTF clips are sampled at unless --fps says otherwise.
const GLTF_FPS: f64 = 30.0;

impl SourceArgs {
    /// The source options a scene's `[source]` stands for: its character, without clips
    /// (take them with [`SourceArgs::load_scene`]).
    pub fn from_scene(scene: &Scene) -> SourceArgs {
        let mut args = SourceArgs::default();
        match &scene.source {
            SceneSource::Builtin(character) => {
                args.builtin = true;
                args.character = Some(match character {
                    BuiltinCharacter::Human => CharacterArg::Human,
                    BuiltinCharacter::Creature => CharacterArg::Creature,
                });
            }
            SceneSource::Gltf { path, fps } => {
                args.gltf = Some(path.clone());
                args.fps = *fps;
            }
            SceneSource::Bvh(file) => args.bvh = vec![file.clone()],
            SceneSource::ObjSeq { dir, angles } => {
                args.obj_seq = Some(dir.clone());
                args.angles = Some(angles.clone());
            }
        }
        args
    }

    /// The character of `scene` (whose source options these are) and the clips of its
    /// `train`, `validate` and `test` keys, in that order. Every clip is taken, so each is
    /// checked (it exists, its frames are in its file) by every command that reads the scene,
    /// before anything is baked; an error names the scene file and the key.
    pub fn load_scene(&self, scene: &Scene, reporter: &dyn Reporter) -> Result<SceneRigClips> {
        let Some(source) = self.rig_source() else {
            bail!(
                "{}: [source]: an OBJ sequence has no clips of a character",
                scene.path.display()
            )
        };
        let loaded = source.load(reporter)?;
        let mut clips: [Vec<Clip>; 3] = Default::default();
        for (list, key) in clips.iter_mut().zip(CLIP_KEYS) {
            *list = loaded
                .clips(scene.clip_specs(key), reporter)
                .with_context(|| format!("{}: [source] {key}", scene.path.display()))?;
        }
        Ok((loaded.into_rig(), clips))
    }

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
        for bvh in &self.bvh {
            inputs.push(Input::new(bvh, "the BVH motion"));
        }
        if let Some(skeleton) = &self.mannequin {
            inputs.push(Input::new(skeleton, "the mannequin's BVH"));
        }
        inputs
    }

    /// Whether a rig (rather than files of meshes or angles) was named.
    pub fn names_rig(&self) -> bool {
        self.builtin || self.gltf.is_some() || !self.bvh.is_empty()
    }

    /// The source the options name, as a flag, for messages about flags that do not apply.
    fn kind(&self) -> &'static str {
        if self.builtin {
            "--builtin"
        } else if self.gltf.is_some() {
            "--gltf"
        } else if !self.bvh.is_empty() {
            "--bvh"
        } else if self.obj_seq.is_some() {
            "--obj-seq"
        } else if self.angles.is_some() {
            "--angles"
        } else {
            "no source"
        }
    }

    /// Refuses flags that do not apply to the source named, rather than ignoring them.
    pub fn check_flags(&self) -> Result<()> {
        let kind = self.kind();
        let bvh_only = [
            ("--frames", !self.frames.is_empty()),
            ("--mannequin", self.mannequin.is_some()),
            ("--no-hat", self.no_hat),
            ("--root-translation", self.root_translation),
        ];
        if self.bvh.is_empty()
            && let Some((flag, _)) = bvh_only.iter().find(|(_, given)| *given)
        {
            bail!("{flag} applies to --bvh motion capture only, not to {kind}");
        }
        if self.character.is_some() && !self.builtin {
            bail!(
                "--character picks a built-in character; it applies to --builtin only, not to {kind}"
            );
        }
        if !(self.clip.is_empty() || self.builtin || self.gltf.is_some()) {
            let instead = if self.bvh.is_empty() {
                ""
            } else {
                ": a BVH file's one clip is its motion (choose frames with --frames A..B)"
            };
            bail!(
                "--clip names a glTF animation or a built-in clip; it does not apply to {kind}{instead}"
            );
        }
        let (files, ranges) = (self.bvh.len(), self.frames.len());
        if files > 1 && ranges > 0 && ranges != files {
            bail!(
                "{ranges} --frames ranges for {files} --bvh files: give one range per file (in the same order), or none to use every frame"
            );
        }
        if self.fps.is_some() && self.gltf.is_none() && self.bvh.is_empty() {
            bail!("--fps resamples a --gltf or --bvh clip; it does not apply to {kind}");
        }
        if self.angles.is_some() && self.names_rig() {
            bail!(
                "--angles gives the poses of an OBJ sequence or of a model; {kind} poses the character by its clip"
            );
        }
        Ok(())
    }

    /// The file the character comes from, to name it in messages; `None` for files of meshes
    /// or angles, whose own errors name them.
    pub fn origin(&self) -> Option<String> {
        if self.builtin {
            return Some(self.builtin_character().description().to_owned());
        }
        let path = self
            .gltf
            .as_ref()
            .or(self.mannequin.as_ref())
            .or(self.bvh.first())?;
        Some(path.display().to_string())
    }

    /// `result` with the character's file named, when there is one.
    pub fn in_origin<T, E: Into<anyhow::Error>>(&self, result: Result<T, E>) -> Result<T> {
        result.map_err(|e| match self.origin() {
            Some(origin) => e.into().context(origin),
            None => e.into(),
        })
    }

    /// The built-in character --builtin gives (the human unless --character says otherwise).
    fn builtin_character(&self) -> BuiltinCharacter {
        self.character
            .map_or_else(BuiltinCharacter::default, BuiltinCharacter::from)
    }

    /// The character the options name, if any.
    fn rig_source(&self) -> Option<RigSource> {
        if self.builtin {
            return Some(RigSource::Builtin(self.builtin_character()));
        }
        if let Some(path) = &self.gltf {
            return Some(RigSource::Gltf {
                path: path.clone(),
                fps: self.fps.unwrap_or(GLTF_FPS),
            });
        }
        let skeleton = self.mannequin.as_ref().or(self.bvh.first())?;
        Some(RigSource::Mocap {
            skeleton: skeleton.clone(),
            options: MocapOptions {
                root_translation: self.root_translation,
                hat: !self.no_hat,
                fps: self.fps,
            },
        })
    }

    /// The clips the options name: the --clip names, or each --bvh file's --frames.
    fn clip_specs(&self) -> Vec<ClipSpec> {
        if !self.clip.is_empty() {
            return self.clip.iter().cloned().map(ClipSpec::Named).collect();
        }
        let motion = |path: &PathBuf, frames: Option<Range<usize>>| ClipSpec::Motion {
            path: path.clone(),
            frames,
        };
        match (self.bvh.as_slice(), self.frames.as_slice()) {
            ([one], ranges) if !ranges.is_empty() => ranges
                .iter()
                .map(|r| motion(one, Some(r.clone())))
                .collect(),
            (files, []) => files.iter().map(|f| motion(f, None)).collect(),
            (files, ranges) => files
                .iter()
                .zip(ranges)
                .map(|(f, r)| motion(f, Some(r.clone())))
                .collect(),
        }
    }

    /// The clip `--validate VALUE` names: a clip of a character with named clips; for a BVH
    /// mannequin, frames `A..B` of the first --bvh file or another BVH file.
    fn validation_spec(&self, value: &str) -> ClipSpec {
        match (self.bvh.first(), parse_frames(value)) {
            (None, _) => ClipSpec::Named(value.to_owned()),
            (Some(first), Ok(range)) => ClipSpec::Motion {
                path: first.clone(),
                frames: Some(range),
            },
            (Some(_), Err(_)) => ClipSpec::Motion {
                path: PathBuf::from(value),
                frames: None,
            },
        }
    }

    /// The files `--validate` values read (BVH files other than the first --bvh).
    pub fn validation_inputs(&self, validate: &[String]) -> Vec<Input> {
        validate
            .iter()
            .filter_map(|v| match self.validation_spec(v) {
                ClipSpec::Motion { path, .. } if self.bvh.first() != Some(&path) => {
                    Some(Input::new(path, "a --validate BVH file"))
                }
                _ => None,
            })
            .collect()
    }

    /// The rig and clips the options name, with the clips `validate` names (`--validate`).
    /// Errors when they name no rig. Notes on what the rig leaves out of a clip go to
    /// `reporter`.
    pub(crate) fn load(&self, validate: &[String], reporter: &dyn Reporter) -> Result<RigClips> {
        self.check_flags()?;
        let Some(source) = self.rig_source() else {
            bail!("no character given: use --builtin, --gltf or --bvh (or --obj-seq with --angles)")
        };
        let loaded = source.load(reporter)?;
        let specs = self.clip_specs();
        if specs.is_empty() {
            bail!(
                "--clip is needed; available: {}",
                loaded.rig().clip_names().join(", ")
            );
        }
        let clips = loaded.clips(&specs, reporter)?;
        let held: Vec<ClipSpec> = validate.iter().map(|v| self.validation_spec(v)).collect();
        let validation = loaded.clips(&held, reporter).context("--validate")?;
        Ok((loaded.into_rig(), clips, validation))
    }

    /// The rig and the clip the options name (several clips joined in order). Errors when
    /// they name no rig. Notes on what the rig leaves out of the clip go to `reporter`.
    pub fn rig(&self, reporter: &dyn Reporter) -> Result<(Box<dyn Rig>, Clip)> {
        let (rig, clips, _) = self.load(&[], reporter)?;
        Ok((rig, joined(clips)))
    }

    /// The character and clips of a light-map command: [`SourceArgs::rig`]'s, or an OBJ
    /// sequence with its angles as a skinless character with one clip
    /// ([`crate::io::source::obj_sequence_rig`]).
    pub fn light_map_source(&self, reporter: &dyn Reporter) -> Result<(Box<dyn Rig>, Vec<Clip>)> {
        let Some(dir) = self.obj_seq.as_ref().filter(|_| !self.names_rig()) else {
            let (rig, clips, _) = self.load(&[], reporter)?;
            return Ok((rig, clips));
        };
        self.check_flags()?;
        let Some(csv) = &self.angles else {
            bail!(
                "--obj-seq {}: the light-map commands pose each mesh by its row of joint angles: give --angles FILE",
                dir.display()
            );
        };
        let (rig, clip) = obj_sequence_rig(dir, csv, reporter)?;
        Ok((rig, vec![clip]))
    }

    /// [`SourceArgs::light_map_source`] with its clips joined in order.
    pub fn light_map_rig(&self, reporter: &dyn Reporter) -> Result<(Box<dyn Rig>, Clip)> {
        let (rig, clips) = self.light_map_source(reporter)?;
        Ok((rig, joined(clips)))
    }

    /// Whether a character or an OBJ sequence, which light-map commands pose, was named.
    pub fn names_light_map_source(&self) -> bool {
        self.names_rig() || self.obj_seq.is_some()
    }

    /// The meshes to bake with `settings`, without angles: every OBJ of --obj-seq (--angles
    /// is not needed), or the rig posed at every frame of its clips; with the bind mesh whose
    /// topology they share (the rig's, or the sequence's first mesh). Baked at the vertices,
    /// or with `surface` at that many points of the surface (checkpointed). A bake beyond the
    /// budget of one run ([`crate::bake::budget`]) is refused before any frame is posed.
    pub fn meshes(
        &self,
        settings: &BakeSettings,
        surface: Option<usize>,
        reporter: &dyn Reporter,
    ) -> Result<PosedMeshes> {
        settings.validate()?;
        // The bake's result, the array written and its encoding.
        let copies = 3;
        let work = |frames: usize, bind: &Mesh| match surface {
            None => Workload::bake(frames, bind, settings, copies),
            Some(points) => {
                Workload::surface_points(frames, bind, points, settings, copies).with_checkpoint()
            }
        };
        if self.names_rig() {
            let (rig, clip) = self.rig(reporter)?;
            let estimate = work(clip.frames.len(), rig.bind_mesh());
            self.in_origin(estimate.check(&format!("clip {}", clip.name)))?;
            return Ok(PosedMeshes {
                poses: pose_all(rig.as_ref(), &clip.name, &clip.frames)?,
                bind: rig.bind_mesh().clone(),
            });
        }
        self.check_flags()?;
        let Some(dir) = &self.obj_seq else {
            bail!("give a character (--builtin, --gltf or --bvh) or --obj-seq DIR");
        };
        let meshes = obj_sequence_meshes(dir, reporter)?;
        work(meshes.len(), &meshes[0]).check(&dir.display().to_string())?;
        Ok(PosedMeshes {
            bind: meshes[0].clone(),
            poses: meshes,
        })
    }

    /// The poses the options name: a rig's clips (with the clips `validate` names held out to
    /// choose the model by), or an OBJ sequence with its angles.
    pub fn poses(&self, validate: &[String], reporter: &dyn Reporter) -> Result<Poses> {
        self.check_flags()?;
        if self.names_rig() {
            let (rig, clips, validation) = self.load(validate, reporter)?;
            return Ok(Poses::Rig {
                rig,
                clips,
                validation,
            });
        }
        if !validate.is_empty() {
            bail!("--validate holds out clips of a character; an OBJ sequence has none");
        }
        let (Some(dir), Some(csv)) = (&self.obj_seq, &self.angles) else {
            bail!(
                "give a character (--builtin, --gltf or --bvh) or --obj-seq DIR with --angles FILE"
            );
        };
        Poses::from_obj_sequence(dir, csv, reporter)
    }
}
