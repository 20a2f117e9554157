//! Characters: what every training source provides is a skinned character driven by a pose
//! vector, and named clips of pose vectors. The built-in character, glTF skins and mannequins
//! driven by motion capture all implement [`Rig`], so baking, fitting, bone frames and reports
//! are written once.
//!
//! - the pieces every rig is made of: [`mesh`] (the triangle mesh), [`skin`](mod@skin)
//!   (linear blend skinning), [`rotation_vector`] (the log and exp maps behind glTF and
//!   mannequin pose vectors), and the lathe surfaces of the built-in character and the
//!   mannequin;
//! - the rigs: [`character`] and [`creature`] (built in, both a [`BuiltinRig`] sharing one
//!   construction and clip machinery), [`gltf`] (glTF 2.0 skins and animations), [`mocap`]
//!   (BVH motion-capture files), [`mannequin`] (the rig a motion-capture skeleton drives) and
//!   [`mesh_sequence`] (meshes read from files, skinless, for the light-map commands);
//! - what a model needs of a rig: [`pose_layout`] (which pose entries it takes),
//!   [`bone_frames`] (transfer in each vertex's bone frame) and [`transfer_rotation`]
//!   (rotating each vertex's SH transfer);
//! - [`uv`]: UV layouts per triangle corner, chart packing and the texel atlas a light map is
//!   baked on.

pub mod bone_frames;
pub mod character;
pub mod creature;
pub mod gltf;
pub(crate) mod lathe;
pub mod mannequin;
pub mod mesh;
pub mod mesh_sequence;
pub mod mocap;
pub mod pose_layout;
pub mod pose_sampler;
pub(crate) mod procedural;
pub mod rotation_vector;
pub mod skin;
pub mod transfer_rotation;
pub mod uv;

pub use procedural::BuiltinRig;

use glam::Mat4;

use crate::rig::uv::UvLayout;
use character::CharacterError;
use gltf::GltfError;
use mannequin::MocapRigError;
use mesh::Mesh;
use skin::{Skin, SkinError, skin};

/// Why a pose vector cannot pose a rig.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum PoseError {
    /// Not one value per pose-vector entry.
    #[error("a pose needs {expected} values, got {got}")]
    Length {
        /// Entries the rig has.
        expected: usize,
        /// Values given.
        got: usize,
    },
    /// An entry that is NaN or infinite.
    #[error("pose value {index} ({name}) is {value}, not a finite number")]
    NonFinite {
        /// Index of the entry.
        index: usize,
        /// Its name.
        name: String,
        /// The value given.
        value: f64,
    },
}

/// Refuses, with `error(fps)`, a sampling rate that is not a positive finite number of frames
/// per second.
pub(crate) fn check_fps<E>(fps: f64, error: impl FnOnce(f64) -> E) -> Result<(), E> {
    if fps.is_finite() && fps > 0.0 {
        Ok(())
    } else {
        Err(error(fps))
    }
}

/// Checks a pose vector against a rig of `expected` entries; `name(i)` names entry `i`.
pub fn check_pose(
    pose: &[f64],
    expected: usize,
    name: impl FnOnce(usize) -> String,
) -> Result<(), PoseError> {
    if pose.len() != expected {
        return Err(PoseError::Length {
            expected,
            got: pose.len(),
        });
    }
    match pose.iter().position(|v| !v.is_finite()) {
        Some(index) => Err(PoseError::NonFinite {
            index,
            name: name(index),
            value: pose[index],
        }),
        None => Ok(()),
    }
}

/// Why a rig could not be posed or could not give a clip: the typed error of the rig that was
/// asked, unchanged (its message and its source chain are the rig's own), so code that holds a
/// `dyn Rig` still reports which file, entry or clip was wrong.
#[derive(Debug, thiserror::Error)]
pub enum RigError {
    /// From a built-in character (the human or the creature).
    #[error(transparent)]
    Character(#[from] CharacterError),
    /// From a glTF character.
    #[error(transparent)]
    Gltf(#[from] GltfError),
    /// From a motion-capture mannequin.
    #[error(transparent)]
    Mocap(#[from] MocapRigError),
    /// Linear blend skinning of the posed joints failed.
    #[error(transparent)]
    Skin(#[from] SkinError),
    /// From meshes read from files (an OBJ sequence).
    #[error(transparent)]
    MeshSequence(#[from] mesh_sequence::MeshSequenceError),
}

/// A sequence of poses sampled at a fixed rate. Each frame has one value per pose-vector
/// entry, in the rig's [`Rig::angle_names`] order.
#[derive(Clone, Debug, PartialEq)]
pub struct Clip {
    /// Name used to select the clip ([`Rig::clip`]).
    pub name: String,
    /// Frames per second.
    pub fps: f64,
    /// The poses.
    pub frames: Vec<Vec<f64>>,
}

/// A skinned character posed by a vector of joint parameters.
pub trait Rig: Sync {
    /// Names of the pose vector's entries, in order (for example `l_elbow_flex` or
    /// `LeftArm.y`); a model blob records the ones it was trained on.
    fn angle_names(&self) -> Vec<String>;

    /// The mesh in the bind pose, with its normals.
    fn bind_mesh(&self) -> &Mesh;

    /// The rest pose: the pose vector whose skinning is (closest to) the bind pose. Characters
    /// whose pose entries are rotations relative to the rest (glTF, BVH) rest at all zeros.
    fn rest_pose(&self) -> Vec<f64> {
        vec![0.0; self.angle_names().len()]
    }

    /// Per-vertex joint influences over the joints [`Rig::joint_matrices`] returns.
    fn skin(&self) -> &Skin;

    /// Skinning matrices (bind space → posed space), one per joint, for a pose vector.
    /// Errors name the entry that is wrong (count, NaN).
    fn joint_matrices(&self, pose: &[f64]) -> Result<Vec<Mat4>, RigError>;

    /// The mesh posed by linear blend skinning.
    fn pose(&self, pose: &[f64]) -> Result<Mesh, RigError> {
        Ok(skin(
            self.bind_mesh(),
            self.skin(),
            &self.joint_matrices(pose)?,
        )?)
    }

    /// The character's up axis in its mesh's frame, unit length: renders turn it to the
    /// screen's up. The built-in characters are z-up (the default).
    fn up(&self) -> glam::Vec3 {
        glam::Vec3::Z
    }

    /// `(min, max)` of each pose-vector entry, in [`Rig::angle_names`] order, where the rig
    /// documents joint limits (the built-in characters); None where the training clips' own
    /// range is the only limit (glTF, BVH).
    fn joint_limits(&self) -> Option<Vec<(f64, f64)>> {
        None
    }

    /// Names of every clip [`Rig::clip`] accepts.
    fn clip_names(&self) -> Vec<String>;

    /// The clip called `name`; the error lists the names that exist.
    fn clip(&self, name: &str) -> Result<Clip, RigError>;

    /// The bind mesh's UVs, per triangle corner, if the character has them: what an SH light
    /// map is laid out by ([`crate::rig::uv`]).
    fn uv_layout(&self) -> Option<&UvLayout> {
        None
    }
}
