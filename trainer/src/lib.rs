//! aprt-trainer: bakes SH precomputed radiance transfer for posed characters, fits the
//! pose-driven linear model, and writes model blobs that `aprt-core` evaluates.

pub mod angles;
pub mod atomic;
pub mod evaluate;
pub mod export;
pub mod mesh;
pub mod model;
pub mod npy;
pub mod runtime;
pub mod sh_rotate;

pub use export::{ExportError, Precision, encode_model};
pub use mesh::Mesh;
pub use model::{LinearModel, VertexBasis};
