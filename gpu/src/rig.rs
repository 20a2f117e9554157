//! Irradiance-rig shading on the device: each frame the rig's lighting weights (aprt-core's
//! `Model::light_rig`), its place and shape and the skinned positions are written, and
//! `rig.wgsl` shades every vertex under the rig's lighting at its own position.

use aprt_core::{IrradianceRig, ModelInfo, Placement, RigShape};
use bytemuck::Zeroable;

use crate::device::{Gpu, GpuError, Growing};
use crate::model::{FrameError, Kernel};
use crate::shaders::RIG;

/// The uniform block `Rig` of `rig.wgsl`, field for field (128 bytes).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct RigBlock {
    rotation: [[f32; 4]; 3],
    translation: [f32; 4],
    centre: [f32; 4],
    half: [f32; 4],
    axes: [u32; 4],
    gradient: u32,
    lit_len: u32,
    pad: [u32; 2],
}

impl RigBlock {
    fn of(rig: &IrradianceRig<'_>, placement: &Placement, lit_len: usize) -> RigBlock {
        let (gradient, axes) = match rig.shape() {
            RigShape::Gradient => (1, [0; 3]),
            RigShape::Product([x, y, z]) => (0, [x, y, z].map(|a| u32::from(a.code()))),
        };
        let axes = [axes[0], axes[1], axes[2], 0];
        let padded = |v: [f32; 3]| [v[0], v[1], v[2], 0.0];
        RigBlock {
            rotation: placement.rotation.map(padded),
            translation: padded(placement.translation),
            centre: padded(rig.centre()),
            half: padded(rig.half()),
            axes,
            gradient,
            lit_len: lit_len as u32,
            pad: [0; 2],
        }
    }
}

/// The buffers of rig shading and the kernel bound to them.
pub(crate) struct GpuRig {
    /// The model's rows layout and rows, which the kernel reads.
    shared: [wgpu::Buffer; 2],
    block: wgpu::Buffer,
    lit: Growing,
    positions: wgpu::Buffer,
    rgb: wgpu::Buffer,
    kernel: Kernel,
}

impl GpuRig {
    /// The buffers, zeroed, with room for one set of weights, and the kernel bound to them and
    /// to `shared` (the model's rows layout and rows).
    pub(crate) fn new(
        gpu: &Gpu,
        info: &ModelInfo,
        shared: [wgpu::Buffer; 2],
    ) -> Result<Self, GpuError> {
        let input = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
        let uniform = wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST;
        let vertices = info.vertices();
        let block = gpu.buffer("rig", &[RigBlock::zeroed()], uniform)?;
        let lit = Growing::new(gpu, "rig weights", 4 * info.lit_weights_len())?;
        let positions = gpu.buffer("rig positions", &vec![0f32; 3 * vertices], input)?;
        let rgb = gpu.output::<f32>("rig rgb", 3 * vertices)?;
        let kernel = Kernel::new(
            gpu,
            (&RIG, "shade_rig"),
            &bindings(&shared, [lit.buffer(), &rgb, &positions, &block]),
            vertices as u32,
        );
        Ok(GpuRig {
            shared,
            block,
            lit,
            positions,
            rgb,
            kernel,
        })
    }

    /// The RGB shading of the last [`GpuRig::shade`], three f32 per vertex.
    pub(crate) fn rgb(&self) -> &wgpu::Buffer {
        &self.rgb
    }

    /// Shades every vertex under `rig` placed by `placement`, from its weights `q` (checked by
    /// aprt-core) at the skinned `positions`.
    pub(crate) fn shade(
        &mut self,
        gpu: &Gpu,
        info: &ModelInfo,
        (q, rig, placement): (&[f32], &IrradianceRig<'_>, &Placement),
        positions: &[[f32; 3]],
    ) -> Result<(), FrameError> {
        let block = RigBlock::of(rig, placement, info.lit_weights_len());
        let queue = gpu.queue();
        queue.write_buffer(&self.block, 0, bytemuck::bytes_of(&block));
        queue.write_buffer(&self.positions, 0, bytemuck::cast_slice(positions));
        if self.lit.write(gpu, q)? {
            let own = [self.lit.buffer(), &self.rgb, &self.positions, &self.block];
            self.kernel.rebind(gpu, &bindings(&self.shared, own));
        }
        self.kernel.submit(gpu);
        Ok(())
    }
}

/// The kernel's bindings in `rig.wgsl`'s order: the model's two, then its own four.
fn bindings<'a>(
    shared: &'a [wgpu::Buffer; 2],
    own: [&'a wgpu::Buffer; 4],
) -> Vec<(u32, &'a wgpu::Buffer)> {
    (0..).zip(shared.iter().chain(own)).collect()
}
