//! The built-in procedural character: a deterministic, articulated, smoothly skinned figure
//! with a wide-brimmed hat, and the clips used to train and test on it.
//!
//! It exists so every stage can run and be tested without external assets, on a character
//! that stresses what PRT must capture: large pose-dependent self-shadowing (the hat's brim
//! over the shoulders, arms against the torso) and smooth deformation across joints.
//!
//! Frame: z up, feet on z = 0, facing −y (the character's left is +x). Units are metres and
//! joint angles are radians.

pub(crate) mod body;
mod clips;
mod skeleton;

use std::ops::Range;

use glam::Mat4;

use crate::rig::mesh::Mesh;
use crate::rig::procedural::{self, Articulated, find_clip};
use crate::rig::skin::{Skin, SkinError};
use crate::rig::{Clip, PoseError, Rig, RigError};
use skeleton::Skeleton;

/// Why a pose or clip request failed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CharacterError {
    /// A pose that cannot pose the character.
    #[error(transparent)]
    Pose(#[from] PoseError),
    /// No clip has the requested name.
    #[error("no clip named {name:?}; available: {available}")]
    UnknownClip {
        /// The name asked for.
        name: String,
        /// Comma-separated names of the clips that exist.
        available: String,
    },
    /// Skinning failed (an internal inconsistency; the built-in skin always matches).
    #[error(transparent)]
    Skin(#[from] SkinError),
}

/// One named joint angle: its bind-pose value and the range poses and clips stay within.
/// Angles outside the limits are still posed (they are a sampling range, not a constraint).
/// Poses are not collision-checked: near the limits, limbs can pass through the body or the
/// hat's brim, as with any joint-limit-only rig.
#[derive(Clone, Debug, PartialEq)]
pub struct JointAngle {
    /// Stable name, e.g. `l_elbow_flex`; see the skeleton docs for sign conventions.
    pub name: &'static str,
    /// Value in the bind pose, radians.
    pub rest: f64,
    /// Lower limit, radians.
    pub min: f64,
    /// Upper limit, radians.
    pub max: f64,
}

/// The built-in character: bind mesh, skin, skeleton and joint angles.
#[derive(Clone, Debug)]
pub struct Character {
    body: Articulated,
}

impl Character {
    /// Builds the character. Deterministic: every call gives bit-identical results on every
    /// platform (the geometry is computed in f64 and rounded once to f32).
    pub fn builtin() -> Character {
        let skeleton = Skeleton::new();
        let (body, names) = body::build(&skeleton);
        Character {
            body: Articulated::new(
                &skeleton.parents,
                &skeleton.bind,
                skeleton::dofs(),
                body,
                names,
            ),
        }
    }

    /// Number of joint angles a pose has.
    pub fn pose_len(&self) -> usize {
        self.body.angles.len()
    }

    /// The joint angles, in pose order.
    pub fn joint_angles(&self) -> &[JointAngle] {
        &self.body.angles
    }

    /// `(min, max)` of each joint angle, in pose order.
    pub fn limits(&self) -> Vec<(f64, f64)> {
        self.body.limits()
    }

    /// The training clip ("training", 250 frames at 30 fps) that spans the pose space.
    pub fn training_clip(&self) -> Clip {
        procedural::clips::training(&self.body.angles, clips::TRAINING_SEED)
    }

    /// The novel test clips ("wave", "walk", "reach"): motions unlike the training clip,
    /// inside the limits.
    pub fn novel_clips(&self) -> Vec<Clip> {
        clips::novel(&self.body.angles)
    }

    /// The validation clip ("stretch"): a motion unlike the training clip and the novel
    /// clips, held out of training to choose the model by.
    pub fn validation_clip(&self) -> Clip {
        clips::stretch(&self.body.angles)
    }

    /// Names and triangle ranges of the closed parts the mesh is made of, in mesh order.
    pub fn parts(&self) -> impl Iterator<Item = (&'static str, Range<usize>)> + '_ {
        self.body.parts.iter().cloned()
    }

    /// Every clip, in the order [`Rig::clip_names`] lists them.
    fn clips(&self) -> Vec<Clip> {
        let mut clips = vec![self.training_clip()];
        clips.extend(self.novel_clips());
        clips.push(self.validation_clip());
        clips
    }
}

/// The built-in character as a [`Rig`]. Its errors are [`RigError::Character`].
impl Rig for Character {
    fn angle_names(&self) -> Vec<String> {
        self.body.angle_names()
    }

    fn bind_mesh(&self) -> &Mesh {
        &self.body.bind
    }

    /// The bind pose: the angles for which `pose` returns the bind mesh.
    fn rest_pose(&self) -> Vec<f64> {
        self.body.rest_pose()
    }

    fn skin(&self) -> &Skin {
        &self.body.skin
    }

    /// Skinning matrices (bind space → posed space) for each joint at the joint angles `pose`.
    fn joint_matrices(&self, pose: &[f64]) -> Result<Vec<Mat4>, RigError> {
        self.body.joint_matrices(pose)
    }

    /// The training clip first, then the novel clips, then the validation clip.
    fn clip_names(&self) -> Vec<String> {
        self.clips().into_iter().map(|c| c.name).collect()
    }

    fn clip(&self, name: &str) -> Result<Clip, RigError> {
        find_clip(self.clips(), name)
    }
}

#[cfg(test)]
mod tests;
