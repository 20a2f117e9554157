//! aprt-trainer: bakes SH precomputed radiance transfer for posed characters, fits the
//! pose-driven linear model, and writes model blobs that `aprt-core` evaluates.
//!
//! Its stages, lowest first; each uses only those above it in this list (ARCHITECTURE.md's
//! "Stages", enforced by `tests/layering.rs`):
//!
//! - [`limits`]: the limits one run holds to;
//! - [`text`]: a user's text as read and quoted in errors;
//! - [`input`]: the one way a user's file is opened (regular files, size limits);
//! - [`progress`]: the reporting seam;
//! - [`rig`]: characters posed by a pose vector (the [`Rig`] trait, meshes, skinning, bone
//!   frames, UV atlases, the built-in characters, glTF skins, the motion-capture mannequin);
//! - [`io`]: OBJ, angle CSV and `.npy` files, atomic writes, and where poses come from;
//! - [`bake`]: the transfer simulation, with checkpoints and shards for long bakes;
//! - [`lighting`]: lights, environment maps, irradiance through SH and exactly;
//! - [`irradiance_rig`]: irradiance rigs (*Irradiance Rigs*): kinds, fit, accuracy;
//! - [`model`]: the linear model, its fit, the blob writer and evaluation through `aprt-core`;
//! - [`lightmap`]: SH light maps: texel bake, the `.shlm` codec, the light-map model;
//! - [`scene`]: scene files and what a scene needs computed;
//! - [`pipeline`]: `aprt train` and `aprt train --scene`, which call the stages in order;
//! - [`report`]: experiments against baselines, pictures, plots, the demo, results, sweeps;
//! - [`cli`]: the `aprt` command line.

pub mod bake;
pub mod cli;
pub mod input;
pub mod io;
pub mod irradiance_rig;
pub mod lighting;
pub mod lightmap;
pub mod limits;
pub mod model;
pub mod pipeline;
pub mod progress;
pub mod report;
pub mod rig;
pub mod scene;
pub mod surface;
pub mod text;

// Module paths the tests, benches and fuzz harnesses use.
pub use model::{export, runtime};
pub use report::evaluate;
pub use rig::bone_frames::{self, BoneFrames};

pub use bake::{
    Accel, BakeError, BakeSettings, bake_pose, bake_pose_with, bake_poses, bake_vertices,
};
pub use io::obj::{LineError, ObjError, read_obj, read_obj_with_uvs};
pub use model::export::{
    ExportError, Extras, Precision, TexelAtlasExtra, encode_model, encode_model_with,
    encode_model_with_rig,
};
pub use model::features::PoseFeatures;
pub use model::fit::{Alpha, CoefDims, Dims, Fit, FitError, FitOptions, FitReport, fit};
pub use model::{LinearModel, ModelFrame, PoseBounds, VertexBasis};
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
