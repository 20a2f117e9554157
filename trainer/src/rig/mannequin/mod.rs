//! A mannequin built automatically from a BVH skeleton and driven by motion capture: the
//! [`Rig`] that trains on real motion (the paper trained on CMU mocap).
//!
//! **Frame and units.** BVH is y-up; the mannequin stands z-up like every other aprt
//! character, through the fixed change of axes `(x, y, z)_file → (x, −z, y)` (a +90° turn about
//! x), so a CMU actor, who faces +z in the file's rest pose, faces −y as the built-in character
//! does. Lengths stay in the file's units (CMU/cgspeed files are about 27 units tall): transfer
//! is scale invariant, so there is nothing to gain from converting.
//!
//! **Pose vector.** For each joint with rotation channels, in file order, its local rotation
//! relative to the rest pose (all channels zero) as a rotation vector (axis × angle in
//! radians, the log map), expressed in the file's axes: entries `<joint>.x`, `.y`, `.z`. The
//! root's rotation is included: transfer in the world frame depends on which way the body
//! faces, while bone-frame models absorb it. Every rotating joint is listed even if a clip
//! never moves it (callers drop constant joints with their own report). Position channels:
//! on a non-root joint they change the skeleton's shape and are always entries
//! (`<joint>.tx`, `.ty`, `.tz`, file units, added to the offset); on the root they only move
//! the whole body, and PRT transfer is invariant under translation, so they are entries only
//! when [`MocapOptions::root_translation`] asks for them (to render the actor walking).
//! [`Rig::joint_matrices`] rebuilds the skeleton from the pose vector alone.
//!
//! **Clips.** A clip's frames are pose vectors sampled from the file's frames, optionally
//! resampled to another rate (the paper used subsampled mocap: 120 fps capture moves little
//! between frames, so 30 fps gives as many distinct poses per baked frame at a quarter of the
//! cost). A rotation vector is only defined up to whole turns about its axis; clips choose,
//! frame by frame, the representative nearest the previous frame so that entries stay
//! continuous through half turns (the root turning round), which the linear fit needs.
//! Motion from another file drives the mannequin by joint name ([`MocapRig::retarget`]).

mod body;

use std::ops::Range;
use std::path::Path;

use glam::{DAffine3, DQuat, DVec3, Mat4};

use crate::limits::MAX_EXTENT;
use crate::limits::MAX_FRAMES;
use crate::rig::mesh::Mesh;
use crate::rig::mocap::{Mocap, MocapError};
use crate::rig::rotation_vector;
use crate::rig::skin::Skin;
use crate::rig::uv::UvLayout;
use crate::rig::{Clip, PoseError, Rig, RigError, check_fps, check_pose};

/// Most joints a mannequin is built for: the most bones a model may have
/// (`aprt_core::MAX_BONES`). Checked right after parsing, before any surface is made, so a
/// file of thousands of joints is refused at once instead of growing a mesh of gigabytes.
pub const MAX_JOINTS: usize = aprt_core::MAX_BONES;

/// How to build a [`MocapRig`].
#[derive(Clone, Debug, PartialEq)]
pub struct MocapOptions {
    /// Keep the root's position channels as pose entries (see the module docs). Off by
    /// default: transfer does not depend on where the body is.
    pub root_translation: bool,
    /// Put the wide-brimmed hat on the head: a large occluder that shadows the shoulders.
    pub hat: bool,
    /// Resample clips to this rate (frames per second); `None` keeps the file's rate.
    pub fps: Option<f64>,
}

impl Default for MocapOptions {
    fn default() -> Self {
        MocapOptions {
            root_translation: false,
            hat: true,
            fps: None,
        }
    }
}

/// Why a mannequin, a pose or a clip could not be made.
#[derive(Debug, thiserror::Error)]
pub enum MocapRigError {
    /// The BVH file could not be read or parsed.
    #[error(transparent)]
    Mocap(#[from] MocapError),
    /// The skeleton has no bone of nonzero length to put a surface around.
    #[error("the skeleton of {} has no bone of nonzero length", crate::text::quote(.clip))]
    NoBones {
        /// The clip (file stem).
        clip: String,
    },
    /// The rest skeleton reaches farther from the origin than a bake can represent.
    #[error(
        "the skeleton of {} reaches {extent:e} from the origin at rest, beyond the \
         {MAX_EXTENT:e} a bake can represent",
        crate::text::quote(.clip)
    )]
    Extent {
        /// The clip (file stem).
        clip: String,
        /// The largest coordinate of a joint or End Site (infinite when the offsets overflow).
        extent: f64,
    },
    /// A requested frame range is empty or runs past the end of the motion.
    #[error("frames {start}..{end} of {}: the motion has {count} frames (0..{count})", crate::text::quote(.clip))]
    FrameRange {
        /// The motion's name.
        clip: String,
        /// First frame asked for.
        start: usize,
        /// One past the last frame asked for.
        end: usize,
        /// Frames available.
        count: usize,
    },
    /// A skeleton with more joints than a mannequin is built for.
    #[error(
        "the skeleton of {} has {joints} joints; a mannequin is built for at most {MAX_JOINTS} (aprt-core's bone limit; a CMU skeleton has 31)",
        crate::text::quote(.clip)
    )]
    TooManyJoints {
        /// The clip (file stem).
        clip: String,
        /// Joints of the skeleton.
        joints: usize,
    },
    /// A skeleton whose mannequin would have more vertices than a model may have.
    #[error(
        "the mannequin of {} would have {vertices} vertices, more than the {} a model may have (its bones are very long for its height, which sets the ring spacing)",
        crate::text::quote(.clip),
        body::MAX_VERTICES
    )]
    TooManyVertices {
        /// The clip (file stem).
        clip: String,
        /// Vertices its bones would have.
        vertices: usize,
    },
    /// A clip (at the rate asked for) of more frames than one run bakes or evaluates,
    /// refused before any frame is sampled.
    #[error(
        "{} at {fps} fps would have {frames:.0} frames, more than the {MAX_FRAMES} one run bakes or evaluates: take fewer frames or a lower frame rate",
        crate::text::quote(.clip)
    )]
    TooManyFrames {
        /// The clip.
        clip: String,
        /// The frame rate.
        fps: f64,
        /// Frames the clip would have.
        frames: f64,
    },
    /// A resampling rate that is not a positive finite number.
    #[error("frame rate {fps} is not a positive finite number")]
    BadFps {
        /// The rate asked for.
        fps: f64,
    },
    /// A pose that cannot pose the mannequin.
    #[error(transparent)]
    Pose(#[from] PoseError),
    /// Retargeting found no joint name shared by the two skeletons.
    #[error("no joint of {} has the name of a joint of this mannequin", crate::text::quote(.source_clip))]
    NoCommonJoint {
        /// The motion being retargeted.
        source_clip: String,
    },
    /// No clip has the requested name.
    #[error("no clip named {}; available: {available}", crate::text::quote(.name))]
    UnknownClip {
        /// The name asked for.
        name: String,
        /// The clip that exists.
        available: String,
    },
}

/// One block of three pose entries.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Entry {
    /// Position channels of joint `.0`, added to its offset.
    Translation(usize),
    /// Rotation vector of joint `.0`.
    Rotation(usize),
}

/// Motion from another file mapped onto a mannequin by joint name.
#[derive(Clone, Debug, PartialEq)]
pub struct Retargeted {
    /// The clip, in the mannequin's pose layout.
    pub clip: Clip,
    /// Joints of the mannequin with pose entries that the source lacks: held at rest.
    pub missing: Vec<String>,
    /// Joints of the source that the mannequin lacks: ignored.
    pub extra: Vec<String>,
}

/// A skinned mannequin around a BVH skeleton, with the file's motion as its clip. As a [`Rig`]
/// its errors are [`RigError::Mocap`].
#[derive(Clone, Debug)]
pub struct MocapRig {
    clip_name: String,
    mocap: Mocap,
    options: MocapOptions,
    entries: Vec<Entry>,
    rest: Vec<DVec3>,
    height: f64,
    bind: Mesh,
    skin: Skin,
    parts: Vec<(String, Range<usize>)>,
    /// The lathe charts, packed (see [`crate::rig::lathe`]).
    uv_layout: Option<UvLayout>,
}

/// The largest coordinate of any joint or End Site at rest (NaN or infinite when the offsets
/// overflow).
fn rest_extent(mocap: &Mocap, rest: &[DVec3]) -> f64 {
    let ends = mocap
        .joints()
        .iter()
        .zip(rest)
        .flat_map(|(joint, &at)| joint.end_sites.iter().map(move |&e| at + e));
    rest.iter()
        .copied()
        .chain(ends)
        .map(|p| p.abs().max_element())
        .fold(0.0, |m: f64, x| {
            if m.is_nan() || x.is_nan() {
                f64::NAN
            } else {
                m.max(x)
            }
        })
}

/// The file-to-mesh change of axes: y-up to z-up (see the module docs).
fn to_mesh_frame() -> DQuat {
    DQuat::from_rotation_x(std::f64::consts::FRAC_PI_2)
}

impl MocapRig {
    /// Reads a BVH file and builds its mannequin; the clip is named after the file stem.
    pub fn from_file(path: &Path, options: &MocapOptions) -> Result<MocapRig, MocapRigError> {
        let mocap = Mocap::read(path)?;
        let name = path
            .file_stem()
            .map_or_else(|| "motion".into(), |s| s.to_string_lossy().into_owned());
        MocapRig::from_mocap(mocap, &name, options)
    }

    /// Builds the mannequin of a parsed file; `clip_name` names its motion.
    pub fn from_mocap(
        mocap: Mocap,
        clip_name: &str,
        options: &MocapOptions,
    ) -> Result<MocapRig, MocapRigError> {
        if let Some(fps) = options.fps {
            check_fps(fps, |fps| MocapRigError::BadFps { fps })?;
        }
        let joints = mocap.joints().len();
        if joints > MAX_JOINTS {
            return Err(MocapRigError::TooManyJoints {
                clip: clip_name.into(),
                joints,
            });
        }
        let rest = mocap.rest_positions();
        let extent = rest_extent(&mocap, &rest);
        if extent.is_nan() || extent > MAX_EXTENT {
            return Err(MocapRigError::Extent {
                clip: clip_name.into(),
                extent,
            });
        }
        let body = body::build(&mocap, &rest, to_mesh_frame(), options.hat).map_err(|refusal| {
            let clip = clip_name.into();
            match refusal {
                body::Refusal::NoBones => MocapRigError::NoBones { clip },
                body::Refusal::TooManyVertices(vertices) => {
                    MocapRigError::TooManyVertices { clip, vertices }
                }
            }
        })?;
        let uv_layout = body.body.uv_layout();
        let bind = Mesh::with_area_weighted_normals(body.body.positions, body.body.triangles);
        let skin = Skin::from_influences(&body.body.influences).unwrap_or_else(|e| {
            unreachable!("lathe weights are positive partitions of unity: {e}")
        });
        let mut entries = Vec::new();
        for (j, joint) in mocap.joints().iter().enumerate() {
            if joint.translates() && (joint.parent.is_some() || options.root_translation) {
                entries.push(Entry::Translation(j));
            }
            if joint.rotates() {
                entries.push(Entry::Rotation(j));
            }
        }
        Ok(MocapRig {
            clip_name: clip_name.into(),
            mocap,
            options: options.clone(),
            entries,
            rest,
            height: body.height,
            bind,
            skin,
            parts: body.names.into_iter().zip(body.body.parts).collect(),
            uv_layout,
        })
    }

    /// The parsed file.
    pub fn mocap(&self) -> &Mocap {
        &self.mocap
    }

    /// The skeleton's rest height in the file's units (lowest to highest joint or End Site
    /// along the up axis): the measure the mannequin's proportions are fractions of.
    pub fn height(&self) -> f64 {
        self.height
    }

    /// Number of pose entries.
    pub fn pose_len(&self) -> usize {
        3 * self.entries.len()
    }

    /// Names and triangle ranges of the closed parts the mesh is made of, in mesh order.
    pub fn parts(&self) -> impl Iterator<Item = (&str, Range<usize>)> + '_ {
        self.parts.iter().map(|(n, r)| (n.as_str(), r.clone()))
    }

    /// The pose vector of the file's frame `f` (root translation per the options). Rotation
    /// vectors have angles in `[0, π]`; clips unwrap them (see the module docs).
    ///
    /// # Panics
    /// If `f >= self.mocap().frame_count()`.
    pub fn frame_pose(&self, f: usize) -> Vec<f64> {
        let identity: Vec<Option<usize>> = (0..self.mocap.joints().len()).map(Some).collect();
        self.pose_of(&self.mocap, &identity, f as f64)
    }

    /// Frames `frames` of the file (indices at the file's rate), resampled to
    /// [`MocapOptions::fps`] if set. Errors if the range is empty or runs past the end, saying
    /// how many frames there are.
    pub fn clip_range(&self, frames: Range<usize>) -> Result<Clip, MocapRigError> {
        let identity: Vec<Option<usize>> = (0..self.mocap.joints().len()).map(Some).collect();
        self.sample(&self.mocap, &self.clip_name, &identity, frames)
    }

    /// Drives the mannequin with `source`'s motion (frames `frames` of it, resampled like
    /// [`MocapRig::clip_range`]) by copying the local rotations, and position channels where
    /// the mannequin has them as entries, of same-named joints. Joints of the mannequin the
    /// source lacks stay at rest; both lists are reported. Rotations are copied as they are,
    /// which is right when both skeletons share a rest pose convention (as CMU's do); root
    /// translation is copied in the source's units.
    pub fn retarget(
        &self,
        source: &Mocap,
        name: &str,
        frames: Range<usize>,
    ) -> Result<Retargeted, MocapRigError> {
        let map: Vec<Option<usize>> = self
            .mocap
            .joints()
            .iter()
            .map(|j| source.joint_index(&j.name))
            .collect();
        if map.iter().all(Option::is_none) {
            return Err(MocapRigError::NoCommonJoint {
                source_clip: name.into(),
            });
        }
        let joint = |e: &Entry| match *e {
            Entry::Translation(j) | Entry::Rotation(j) => j,
        };
        let mut missing: Vec<String> = Vec::new();
        for j in self.entries.iter().map(joint) {
            let name = &self.mocap.joints()[j].name;
            if map[j].is_none() && missing.last() != Some(name) {
                missing.push(name.clone());
            }
        }
        let extra = source
            .joints()
            .iter()
            .filter(|j| self.mocap.joint_index(&j.name).is_none())
            .map(|j| j.name.clone())
            .collect();
        Ok(Retargeted {
            clip: self.sample(source, name, &map, frames)?,
            missing,
            extra,
        })
    }

    /// Samples `source` over `frames` at the target rate through the joint `map` (mannequin
    /// joint → source joint).
    fn sample(
        &self,
        source: &Mocap,
        name: &str,
        map: &[Option<usize>],
        frames: Range<usize>,
    ) -> Result<Clip, MocapRigError> {
        let count = source.frame_count();
        if frames.start >= frames.end || frames.end > count {
            return Err(MocapRigError::FrameRange {
                clip: name.into(),
                start: frames.start,
                end: frames.end,
                count,
            });
        }
        let fps = self.options.fps.unwrap_or(source.fps());
        // Output frame k sits at source frame start + k·step; the last is at or before
        // frames.end − 1. A tiny tolerance keeps exact ratios (120 → 30) from losing the
        // last frame to rounding.
        let step = frame_step(source.fps() / fps);
        let last = (frames.end - 1 - frames.start) as f64;
        let n = (last / step + 1e-9).floor() + 1.0;
        if n > MAX_FRAMES as f64 {
            return Err(MocapRigError::TooManyFrames {
                clip: name.into(),
                fps,
                frames: n,
            });
        }
        let n = n as usize;
        let mut out: Vec<Vec<f64>> = (0..n)
            .map(|k| {
                self.pose_of(
                    source,
                    map,
                    frames.start as f64 + (k as f64 * step).min(last),
                )
            })
            .collect();
        let rotations = (self.entries.iter().enumerate())
            .filter_map(|(i, e)| matches!(e, Entry::Rotation(_)).then_some(i));
        crate::rig::rotation_vector::continue_turns(&mut out, rotations);
        Ok(Clip {
            name: name.into(),
            fps,
            frames: out,
        })
    }

    /// The pose at fractional source frame `at`: rotations slerped and translations
    /// interpolated linearly between the two frames around it.
    fn pose_of(&self, source: &Mocap, map: &[Option<usize>], at: f64) -> Vec<f64> {
        let a = at.floor() as usize;
        let t = at - a as f64;
        let b = (a + 1).min(source.frame_count() - 1);
        let local = |k: usize| {
            let joint = &source.joints()[k];
            let (qa, pa) = joint.local(source.frame(a));
            if t == 0.0 {
                return (qa, pa - joint.offset);
            }
            let (qb, pb) = joint.local(source.frame(b));
            (qa.slerp(qb, t), pa.lerp(pb, t) - joint.offset)
        };
        let mut pose = Vec::with_capacity(self.pose_len());
        for e in &self.entries {
            let v = match *e {
                Entry::Translation(j) => map[j].map_or(DVec3::ZERO, |k| local(k).1),
                Entry::Rotation(j) => {
                    map[j].map_or(DVec3::ZERO, |k| rotation_vector::log(local(k).0))
                }
            };
            pose.extend(v.to_array());
        }
        pose
    }
}

/// Source frames per output frame. `Frame Time` is printed to a few digits (CMU: `.0083333`
/// for 1/120 s), so a ratio within 0.01 % of a whole number is that number: 120 → 30 fps then
/// takes every fourth frame exactly instead of blending neighbours by a 0.002 % weight.
fn frame_step(ratio: f64) -> f64 {
    let whole = ratio.round();
    if whole >= 1.0 && (ratio - whole).abs() <= 1e-4 * ratio {
        whole
    } else {
        ratio
    }
}

impl Rig for MocapRig {
    /// BVH is y-up.
    fn up(&self) -> glam::Vec3 {
        glam::Vec3::Y
    }

    fn angle_names(&self) -> Vec<String> {
        let mut names = Vec::with_capacity(self.pose_len());
        for e in &self.entries {
            let (j, axes) = match *e {
                Entry::Translation(j) => (j, ["tx", "ty", "tz"]),
                Entry::Rotation(j) => (j, ["x", "y", "z"]),
            };
            let joint = &self.mocap.joints()[j].name;
            names.extend(axes.map(|a| format!("{joint}.{a}")));
        }
        names
    }

    fn bind_mesh(&self) -> &Mesh {
        &self.bind
    }

    fn skin(&self) -> &Skin {
        &self.skin
    }

    /// Rebuilds the skeleton from the pose vector alone (see the module docs).
    fn joint_matrices(&self, pose: &[f64]) -> Result<Vec<Mat4>, RigError> {
        check_pose(pose, self.pose_len(), |i| self.angle_names().swap_remove(i))
            .map_err(MocapRigError::Pose)?;
        let joints = self.mocap.joints();
        let mut rotation = vec![DQuat::IDENTITY; joints.len()];
        let mut translation: Vec<DVec3> = joints.iter().map(|j| j.offset).collect();
        for (e, v) in self.entries.iter().zip(pose.chunks_exact(3)) {
            let v = DVec3::from_slice(v);
            match *e {
                Entry::Translation(j) => translation[j] += v,
                Entry::Rotation(j) => rotation[j] = crate::rig::rotation_vector::exp(v),
            }
        }
        let axes = DAffine3::from_quat(to_mesh_frame());
        let world = self.mocap.chain(|j| (rotation[j], translation[j]));
        Ok(world
            .iter()
            .zip(&self.rest)
            .map(|(w, &rest)| {
                let m = axes * *w * DAffine3::from_translation(-rest) * axes.inverse();
                glam::DMat4::from(m).as_mat4()
            })
            .collect())
    }

    fn clip_names(&self) -> Vec<String> {
        vec![self.clip_name.clone()]
    }

    fn clip(&self, name: &str) -> Result<Clip, RigError> {
        if name != self.clip_name {
            return Err(MocapRigError::UnknownClip {
                name: name.into(),
                available: crate::text::shown(&self.clip_name),
            }
            .into());
        }
        Ok(self.clip_range(0..self.mocap.frame_count())?)
    }

    /// One chart per closed part, packed into the unit square (the lathe layout: `u` around,
    /// `v` along the profile, uniform texel density, charts padded apart).
    fn uv_layout(&self) -> Option<&UvLayout> {
        self.uv_layout.as_ref()
    }
}

#[cfg(test)]
mod tests;
