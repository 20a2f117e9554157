//! aprt-core: the `no_std`, allocation-free runtime of aprt.
//!
//! It reads a model blob written by the trainer (from a byte slice, or streamed from any
//! [`BlobSource`] through a caller-owned buffer) and turns joint angles and an SH lighting
//! vector into per-vertex shading or transfer. Every entry point returns a `Result`; no input
//! makes it panic, allocate, or read out of bounds.
//!
//! ```text
//! let model = Model::parse(&blob)?;                              // validates everything once
//! let mut src = SliceSource(&blob);
//! model.set_pose(&mut src, &angles, &mut [], &mut pose)?;         // per frame
//! model.light(&pose, &sh_lighting, &mut lit)?;
//! model.shade(&mut src, &lit, 0, &mut shading, &mut [])?;         // or any vertex range
//! ```
#![no_std]
#![forbid(unsafe_code)]

pub mod blob;
pub mod euler;
pub mod eval;
pub mod math;
pub mod rotate;
pub mod sh;

pub use blob::{BlobSource, Error, Model, SliceSource, SourceError};
pub use eval::{LitWeights, PoseWeights};
