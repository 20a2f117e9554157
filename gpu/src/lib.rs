//! aprt on the GPU: WGSL compute kernels run through wgpu on a headless device.
//!
//! [`Gpu::new`] finds an adapter (Vulkan, then GL; a software one such as lavapipe will do)
//! and [`shaders`] holds every kernel's WGSL, validated with naga by the tests without a
//! device. [`unpack`] widens packed f16 and i8 rows to f32, exactly as the CPU does.

mod device;
pub mod shaders;
mod unpack;

pub use device::{Gpu, GpuError, NoAdapter};
pub use unpack::{Packed, UnpackError, Unpacked, unpack};
