//! aprt-trainer: bakes SH precomputed radiance transfer for posed characters, fits the
//! pose-driven linear model, and writes model blobs that `aprt-core` evaluates.

pub mod angles;
pub mod atomic;
pub mod bake;
pub mod bone_frames;
pub mod bvh;
pub mod character;
pub mod checkpoint;
pub mod cli;
pub mod demo;
pub mod evaluate;
pub mod experiment;
pub mod export;
pub mod figures;
pub mod fit;
pub mod gltf_rig;
pub(crate) mod lathe;
pub mod mannequin;
pub mod mesh;
pub mod model;
pub mod npy;
pub mod obj;
pub mod plots;
pub mod pose_layout;
pub mod render;
pub mod results;
pub mod rig;
pub mod rotation;
pub mod runtime;
pub mod sh_rotate;
pub mod skin;
pub mod source;

pub use bake::{
    Accel, BakeError, BakeSettings, bake_pose, bake_pose_with, bake_poses, bake_vertices,
};
pub use bvh::{Bvh, BvhError};
pub use character::{Character, CharacterError, JointAngle};
pub use export::{ExportError, Precision, encode_model};
pub use fit::{Alpha, CoefDims, Dims, Fit, FitError, FitOptions, FitReport, fit};
pub use gltf_rig::{GltfError, GltfRig, HeldChannel};
pub use mannequin::{BvhOptions, BvhRig, BvhRigError, Retargeted};
pub use mesh::Mesh;
pub use model::{BoneFrames, LinearModel, VertexBasis};
pub use obj::{LineError, ObjError, read_obj};
pub use render::{
    Colormap, RenderError, View, lambert, render_scalar, save_png_atomic, side_by_side,
};
pub use rig::{Clip, Rig};
pub use skin::{Skin, SkinError, skin};
