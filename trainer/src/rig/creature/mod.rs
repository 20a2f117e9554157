//! The built-in long-tailed creature: a deterministic, four-legged, smoothly skinned figure
//! about 4.2 m long and 1.25 m high (body 1.2 m, neck and head 0.85 m, a tapering tail
//! 2 m), and the clips used to train and test on it.
//!
//! It exists for lighting that varies over a character's length (*Irradiance Rigs*): a light
//! near the head barely reaches the tail tip. Its self-shadowing is the tail's (curled beside
//! the body, swung over the legs), the neck's over the chest and the body's over the legs.
//!
//! Frame: z up, feet on z = 0, the long axis along y, facing −y as the human does (head at −y,
//! tail tip at +y, its left is +x). Units are metres and joint angles are radians. Its joints,
//! angles and sign conventions are in the skeleton's docs; it shares its construction, pose
//! errors ([`CharacterError`]) and clip machinery with the human ([`crate::rig::character`]).

mod body;
mod clips;
mod skeleton;

use std::ops::Range;

use glam::Mat4;

#[cfg(doc)]
use crate::rig::character::CharacterError;
use crate::rig::character::JointAngle;
use crate::rig::mesh::Mesh;
use crate::rig::procedural::{self, Articulated, find_clip};
use crate::rig::skin::Skin;
use crate::rig::{Clip, Rig, RigError};
use skeleton::Skeleton;

/// The built-in creature: bind mesh, skin, skeleton and joint angles.
#[derive(Clone, Debug)]
pub struct Creature {
    body: Articulated,
}

impl Creature {
    /// Builds the creature. Deterministic: every call gives bit-identical results on every
    /// platform (the geometry is computed in f64 and rounded once to f32).
    pub fn builtin() -> Creature {
        let skeleton = Skeleton::new();
        let (body, names) = body::build(&skeleton);
        Creature {
            body: Articulated::new(
                &skeleton.parents,
                &skeleton.bind,
                skeleton::dofs(),
                body,
                names,
            ),
        }
    }

    /// Number of joint angles a pose has (34).
    pub fn pose_len(&self) -> usize {
        self.body.angles.len()
    }

    /// The joint angles, in pose order: the back (`spine_pitch` … `chest_yaw`), the neck and
    /// head (`neck_1_pitch` … `head_yaw`), the tail (`tail_1_pitch` … `tail_6_yaw`), then each
    /// leg's `*_hip_swing`, `*_hip_splay` and `*_knee_bend` (fore left `fl`, fore right `fr`,
    /// hind left `hl`, hind right `hr`). All are 0 in the bind pose.
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

    /// The novel test clips ("prowl", "lash"): motions unlike the training clip, inside the
    /// limits.
    pub fn novel_clips(&self) -> Vec<Clip> {
        clips::novel(&self.body.angles)
    }

    /// The validation clip ("crouch"): a motion unlike the training clip and the novel clips,
    /// held out of training to choose the model by.
    pub fn validation_clip(&self) -> Clip {
        clips::crouch(&self.body.angles)
    }

    /// Names and triangle ranges of the closed parts the mesh is made of, in mesh order.
    pub fn parts(&self) -> impl Iterator<Item = (&'static str, Range<usize>)> + '_ {
        self.body.parts.iter().cloned()
    }

    /// Every clip: training, the novel clips, the validation clip.
    fn clips(&self) -> Vec<Clip> {
        let mut clips = vec![self.training_clip()];
        clips.extend(self.novel_clips());
        clips.push(self.validation_clip());
        clips
    }
}

/// The creature as a [`Rig`]. Its errors are [`RigError::Character`], as the human's.
impl Rig for Creature {
    fn angle_names(&self) -> Vec<String> {
        self.body.angle_names()
    }

    fn bind_mesh(&self) -> &Mesh {
        &self.body.bind
    }

    /// The bind pose: all angles 0.
    fn rest_pose(&self) -> Vec<f64> {
        self.body.rest_pose()
    }

    fn skin(&self) -> &Skin {
        &self.body.skin
    }

    fn joint_matrices(&self, pose: &[f64]) -> Result<Vec<Mat4>, RigError> {
        self.body.joint_matrices(pose)
    }

    /// "training", "prowl", "lash", "crouch".
    fn clip_names(&self) -> Vec<String> {
        self.clips().into_iter().map(|c| c.name).collect()
    }

    fn clip(&self, name: &str) -> Result<Clip, RigError> {
        find_clip(self.clips(), name)
    }
}

#[cfg(test)]
mod tests;
