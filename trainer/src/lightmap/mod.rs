//! SH light maps (*Real-time Rendering of Dynamic Objects in Dynamic, Low-frequency Lighting
//! Environments*, Xu, Pattanaik and Hughes): transfer stored per texel of the character's UV
//! atlas, one map per SH coefficient per frame, compressed as a sequence and composed under
//! any lighting; and the pose-driven light map, the linear model fitted with texels as rows.

pub mod bake;
pub mod codec;
pub mod eval;
pub mod layout;
pub mod model;
pub mod sample;
pub mod summary;
