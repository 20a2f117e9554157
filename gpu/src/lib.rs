//! aprt on the GPU: WGSL compute kernels run through wgpu on a headless device.
//!
//! [`Gpu::new`] finds an adapter (Vulkan, then GL; a software one such as lavapipe will do),
//! [`GpuModel::upload`] puts a validated aprt-core model's vertex rows on it, and each frame
//! [`GpuModel::shade`] or [`GpuModel::transfer`] runs the per-vertex loops there from the
//! small weights aprt-core computes on the CPU. [`shaders`] holds every kernel's WGSL,
//! validated with naga by the tests without a device: the reference for ports to other
//! shading languages.

mod device;
mod lights;
mod model;
mod proxies;
mod rig;
pub mod shaders;

pub use device::{Gpu, GpuError, NoAdapter};
pub use model::{FrameError, GpuModel, Vertices};

/// How far a kernel's output may be from aprt-core's, relative to the largest magnitude of
/// the frame's output (its peak): WGSL allows a device to fuse multiply-adds and to sum in
/// its own order, so the GPU cannot promise the CPU's bits, only sums of the same terms.
/// The tests hold every kernel to it on the golden blobs and the built-in character's model.
pub const TOLERANCE: f32 = 1e-5;
