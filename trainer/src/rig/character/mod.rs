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

use crate::rig::Clip;
use crate::rig::lathe::Body;
use crate::rig::procedural::{BuiltinRig, Dof, Skeleton, Spec};
pub use crate::rig::procedural::{CharacterError, JointAngle};

/// The built-in character: bind mesh, skin, skeleton and joint angles. Its joint angles and
/// their sign conventions are listed in the skeleton's docs.
pub type Character = BuiltinRig<Human>;

/// The human's layout: its skeleton, body (with the hat) and clips. Its clips are "training",
/// the novel "wave", "walk" and "reach", and the validation clip "stretch".
#[derive(Clone, Copy, Debug)]
pub struct Human;

impl Spec for Human {
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

    /// "wave", "walk", "reach".
    fn novel_clips(angles: &[JointAngle]) -> Vec<Clip> {
        clips::novel(angles)
    }

    /// "stretch".
    fn validation_clip(angles: &[JointAngle]) -> Clip {
        clips::stretch(angles)
    }
}

#[cfg(test)]
mod tests;
