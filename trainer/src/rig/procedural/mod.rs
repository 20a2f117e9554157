//! What the built-in procedural characters share: the human of [`character`](super::character)
//! and the long-tailed creature of [`creature`](super::creature) are both a chain of joints
//! posed by named angles about fixed bind-space axes, covered by closed lathes
//! ([`crate::rig::lathe`]) with smooth weights, and both give scripted clips ([`clips`]).
//!
//! [`BuiltinRig`] is a built-in character once built, with its accessors and its
//! [`Rig`](crate::rig::Rig) implementation written once; each character only lays out its
//! joints ([`skeleton`]), its surface and its clips, and hands them over as a [`Spec`].

mod builtin;
#[cfg(test)]
pub(crate) mod checks;
pub(crate) mod clips;
pub(crate) mod skeleton;

pub use builtin::{BuiltinRig, CharacterError, JointAngle, Spec};
pub(crate) use skeleton::{Dof, Skeleton, dof};
