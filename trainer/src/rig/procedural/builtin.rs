//! A built-in character once built, written once for the human and the creature:
//! [`BuiltinRig`] holds the bind mesh, skin, skeleton, angles and parts, answers the accessors and
//! implements [`Rig`]; each character says what differs through its [`Spec`].

use std::marker::PhantomData;
use std::ops::Range;

use glam::Mat4;

use super::skeleton::{Dof, Skeleton, joint_matrices};
use crate::rig::lathe::Body;
use crate::rig::mesh::Mesh;
use crate::rig::skin::{Skin, SkinError};
use crate::rig::uv::UvLayout;
use crate::rig::{Clip, PoseError, Rig, RigError, check_pose};

/// Why a pose or clip request failed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CharacterError {
    /// A pose that cannot pose the character.
    #[error(transparent)]
    Pose(#[from] PoseError),
    /// No clip has the requested name.
    #[error("no clip named {}; available: {available}", crate::text::quote(.name))]
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

/// What one built-in character is made of: its joints, the angles that pose them, its surface
/// and its clips. Implemented only inside the crate (its items name crate-private types).
pub trait Spec {
    /// Seed of the training clip's random walk ([`super::clips::training`]).
    const TRAINING_SEED: u64;

    /// The joints in the bind pose.
    fn skeleton() -> Skeleton;

    /// The joint angles, in pose order.
    fn dofs() -> Vec<Dof>;

    /// The surface over `skeleton` and the name of each of its parts, in mesh order.
    fn body(skeleton: &Skeleton) -> (Body, Vec<&'static str>);

    /// The novel test clips, in a fixed order.
    fn novel_clips(angles: &[JointAngle]) -> Vec<Clip>;

    /// The validation clip.
    fn validation_clip(angles: &[JointAngle]) -> Clip;
}

/// A built-in character: bind mesh, skin, skeleton and joint angles, laid out by `S`.
/// [`Character`](crate::rig::character::Character) and
/// [`Creature`](crate::rig::creature::Creature) are its two instances.
#[derive(Clone, Debug)]
pub struct BuiltinRig<S> {
    bind: Mesh,
    skin: Skin,
    skeleton: Skeleton,
    dofs: Vec<Dof>,
    angles: Vec<JointAngle>,
    parts: Vec<(&'static str, Range<usize>)>,
    /// The lathe charts, packed ([`Body::uv_layout`]).
    uv_layout: Option<UvLayout>,
    /// Only a type-level tag: `S` is never stored, so it need not be `Send` or `Sync`.
    spec: PhantomData<fn() -> S>,
}

impl<S: Spec> BuiltinRig<S> {
    /// Builds the character. Deterministic: every call gives bit-identical results on every
    /// platform (the geometry is computed in f64 and rounded once to f32).
    pub fn builtin() -> BuiltinRig<S> {
        let skeleton = S::skeleton();
        debug_assert!(
            skeleton
                .parents
                .iter()
                .enumerate()
                .all(|(j, p)| p.is_none_or(|p| p < j))
        );
        let (body, names) = S::body(&skeleton);
        let dofs = S::dofs();
        let uv_layout = body.uv_layout();
        let bind = Mesh::with_area_weighted_normals(body.positions, body.triangles);
        let skin = Skin::from_influences(&body.influences).unwrap_or_else(|e| {
            unreachable!("built-in weights are positive partitions of unity: {e}")
        });
        let angles = dofs
            .iter()
            .map(|d| JointAngle {
                name: d.name,
                rest: d.rest,
                min: d.min,
                max: d.max,
            })
            .collect();
        BuiltinRig {
            bind,
            skin,
            skeleton,
            dofs,
            angles,
            parts: names.into_iter().zip(body.parts).collect(),
            uv_layout,
            spec: PhantomData,
        }
    }

    /// Number of joint angles a pose has.
    pub fn pose_len(&self) -> usize {
        self.angles.len()
    }

    /// The joint angles, in pose order; the character's skeleton docs give their sign
    /// conventions.
    pub fn joint_angles(&self) -> &[JointAngle] {
        &self.angles
    }

    /// `(min, max)` of each joint angle, in pose order.
    pub fn limits(&self) -> Vec<(f64, f64)> {
        self.angles.iter().map(|a| (a.min, a.max)).collect()
    }

    /// The training clip ("training", 250 frames at 30 fps) that spans the pose space.
    pub fn training_clip(&self) -> Clip {
        super::clips::training(&self.angles, S::TRAINING_SEED)
    }

    /// The novel test clips: motions unlike the training clip, inside the limits.
    pub fn novel_clips(&self) -> Vec<Clip> {
        S::novel_clips(&self.angles)
    }

    /// The validation clip: a motion unlike the training clip and the novel clips, held out of
    /// training to choose the model by.
    pub fn validation_clip(&self) -> Clip {
        S::validation_clip(&self.angles)
    }

    /// Names and triangle ranges of the closed parts the mesh is made of, in mesh order.
    pub fn parts(&self) -> impl Iterator<Item = (&'static str, Range<usize>)> + '_ {
        self.parts.iter().cloned()
    }

    /// Every clip, in the order [`Rig::clip_names`] lists them.
    fn clips(&self) -> Vec<Clip> {
        let mut clips = vec![self.training_clip()];
        clips.extend(self.novel_clips());
        clips.push(self.validation_clip());
        clips
    }
}

/// A built-in character as a [`Rig`]. Its errors are [`RigError::Character`].
impl<S: Spec> Rig for BuiltinRig<S> {
    fn angle_names(&self) -> Vec<String> {
        self.angles.iter().map(|a| a.name.to_owned()).collect()
    }

    fn bind_mesh(&self) -> &Mesh {
        &self.bind
    }

    fn joint_limits(&self) -> Option<Vec<(f64, f64)>> {
        Some(self.limits())
    }

    /// The bind pose: the angles for which `pose` returns the bind mesh.
    fn rest_pose(&self) -> Vec<f64> {
        self.angles.iter().map(|a| a.rest).collect()
    }

    fn skin(&self) -> &Skin {
        &self.skin
    }

    /// Skinning matrices (bind space → posed space) for each joint at the joint angles `pose`,
    /// checked first (count, NaN).
    fn joint_matrices(&self, pose: &[f64]) -> Result<Vec<Mat4>, RigError> {
        check_pose(pose, self.angles.len(), |i| self.angles[i].name.to_owned())
            .map_err(CharacterError::Pose)?;
        Ok(joint_matrices(&self.skeleton, &self.dofs, pose))
    }

    /// The training clip first, then the novel clips, then the validation clip.
    fn clip_names(&self) -> Vec<String> {
        self.clips().into_iter().map(|c| c.name).collect()
    }

    fn clip(&self, name: &str) -> Result<Clip, RigError> {
        find_clip(self.clips(), name)
    }

    /// One chart per closed part, packed into the unit square (the lathe layout: `u` around,
    /// `v` along the profile, uniform texel density, charts padded apart).
    fn uv_layout(&self) -> Option<&UvLayout> {
        self.uv_layout.as_ref()
    }
}

/// The clip called `name` among `clips`; the error lists every name.
fn find_clip(clips: Vec<Clip>, name: &str) -> Result<Clip, RigError> {
    let available = clips
        .iter()
        .map(|c| c.name.as_str())
        .collect::<Vec<_>>()
        .join(", ");
    clips.into_iter().find(|c| c.name == name).ok_or_else(|| {
        RigError::from(CharacterError::UnknownClip {
            name: name.into(),
            available,
        })
    })
}
