//! aprt-trainer: bakes SH precomputed radiance transfer for posed characters, fits the
//! pose-driven linear model, and writes model blobs that `aprt-core` evaluates.

pub mod character;
pub mod mesh;
pub mod model;
pub mod render;
pub mod skin;

pub use character::{Character, CharacterError, Clip, JointAngle};
pub use mesh::Mesh;
pub use model::{LinearModel, VertexBasis};
pub use render::{
    Colormap, RenderError, View, lambert, render_scalar, save_png_atomic, side_by_side,
};
pub use skin::{Skin, SkinError, skin};
