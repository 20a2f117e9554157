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
//! errors ([`CharacterError`]) and clip machinery with the human ([`crate::rig::character`]):
//! both are a [`BuiltinRig`].

mod body;
mod clips;
mod skeleton;

use crate::rig::Clip;
#[cfg(doc)]
use crate::rig::character::CharacterError;
use crate::rig::lathe::Body;
use crate::rig::procedural::{BuiltinRig, Dof, JointAngle, Skeleton, Spec};

/// The built-in creature: bind mesh, skin, skeleton and joint angles. Its 34 joint angles are
/// the back (`spine_pitch` … `chest_yaw`), the neck and head (`neck_1_pitch` … `head_yaw`),
/// the tail (`tail_1_pitch` … `tail_6_yaw`), then each leg's `*_hip_swing`, `*_hip_splay` and
/// `*_knee_bend` (fore left `fl`, fore right `fr`, hind left `hl`, hind right `hr`), all 0 in
/// the bind pose.
pub type Creature = BuiltinRig<Lizard>;

/// The creature's layout: its skeleton, body and clips. Its clips are "training", the novel
/// "prowl" and "lash", and the validation clip "crouch".
#[derive(Clone, Copy, Debug)]
pub struct Lizard;

impl Spec for Lizard {
    const TRAINING_SEED: u64 = clips::TRAINING_SEED;

    fn skeleton() -> Skeleton {
        skeleton::skeleton()
    }

    fn dofs() -> Vec<Dof> {
        skeleton::dofs()
    }

    fn body(skeleton: &Skeleton) -> (Body, Vec<&'static str>) {
        body::build(skeleton)
    }

    /// "prowl", "lash".
    fn novel_clips(angles: &[JointAngle]) -> Vec<Clip> {
        clips::novel(angles)
    }

    /// "crouch".
    fn validation_clip(angles: &[JointAngle]) -> Clip {
        clips::crouch(angles)
    }
}

#[cfg(test)]
mod tests;
