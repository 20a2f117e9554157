//! aprt-trainer: bakes SH precomputed radiance transfer for posed characters, fits the
//! pose-driven linear model, and writes model blobs that `aprt-core` evaluates.

pub mod bake;
pub mod mesh;
pub mod model;
pub mod obj;

pub use bake::{
    Accel, BakeError, BakeSettings, bake_pose, bake_pose_with, bake_poses, bake_vertices,
};
pub use mesh::Mesh;
pub use model::{LinearModel, VertexBasis};
pub use obj::{LineError, ObjError, read_obj};
