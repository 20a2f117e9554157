//! aprt-trainer: bakes SH precomputed radiance transfer for posed characters, fits the
//! pose-driven linear model, and writes model blobs that `aprt-core` evaluates.

pub mod fit;
pub mod mesh;
pub mod model;

pub use fit::{Alpha, CoefDims, Dims, Fit, FitError, FitOptions, FitReport, fit};
pub use mesh::Mesh;
pub use model::{LinearModel, VertexBasis};
