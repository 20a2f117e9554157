//! aprt-trainer: bakes SH precomputed radiance transfer for posed characters, fits the
//! pose-driven linear model, and writes model blobs that `aprt-core` evaluates.
//!
//! One folder per stage:
//!
//! - [`rig`]: characters posed by a pose vector (the [`Rig`] trait, meshes, skinning, the
//!   built-in character, glTF skins, the motion-capture mannequin) and the frames transfer is
//!   learned in;
//! - [`input`]: the one way a user's file is opened (regular files, size limits);
//! - [`io`]: OBJ, angle CSV and `.npy` files, atomic writes, and where poses come from;
//! - [`bake`]: the transfer simulation, with checkpoints for long bakes;
//! - [`model`]: the linear model, its fit, the blob writer and evaluation through `aprt-core`;
//! - [`lighting`]: lights (the lights file) and irradiance through SH and exactly
//!   (*Irradiance Rigs*);
//! - [`report`]: experiments against baselines, pictures, plots, the demo and the results
//!   document;
//! - [`cli`]: the `aprt` command line.

pub mod bake;
pub mod cli;
pub mod input;
pub mod io;
pub mod lighting;
pub mod lightmap;
pub mod model;
pub mod progress;
pub mod report;
pub mod rig;
pub mod scene;

// Module paths the tests, benches and fuzz harnesses use.
pub use model::{export, runtime};
pub use report::evaluate;
pub use rig::bone_frames;

pub use bake::{
    Accel, BakeError, BakeSettings, bake_pose, bake_pose_with, bake_poses, bake_vertices,
};
pub use io::obj::{LineError, ObjError, read_obj, read_obj_with_uvs};
pub use model::export::{
    ExportError, Extras, Precision, encode_model, encode_model_with, encode_model_with_rig,
};
pub use model::features::PoseFeatures;
pub use model::fit::{Alpha, CoefDims, Dims, Fit, FitError, FitOptions, FitReport, fit};
pub use model::{BoneFrames, LinearModel, ModelFrame, PoseBounds, VertexBasis};
pub use progress::{BakeProgress, Reporter, Silent};
pub use report::render::{
    Colormap, RenderError, View, lambert, render_scalar, save_png_atomic, side_by_side,
};
pub use rig::character::{Character, CharacterError, JointAngle};
pub use rig::creature::Creature;
pub use rig::gltf::{GltfError, GltfRig, HeldChannel};
pub use rig::mannequin::{MocapOptions, MocapRig, MocapRigError, Retargeted};
pub use rig::mesh::Mesh;
pub use rig::mocap::{Mocap, MocapError};
pub use rig::skin::{Skin, SkinError, skin};
pub use rig::{Clip, Rig, RigError};
