//! The occluder proxies on the device: each frame the spheres aprt-core posed on the CPU
//! (`Model::pose_proxies`), the bones' masks and the caller's skinned vertices are written,
//! and `occlude.wgsl` subtracts every vertex's caps from the shading or the transfer the
//! other kernels left in their buffers.

use aprt_core::{MAX_PROXIES, ModelInfo, ProxyFrame, ProxyView, Rotation};
use bytemuck::Zeroable;

use crate::device::{Gpu, GpuError};
use crate::model::{FrameError, Kernel, Vertices};
use crate::shaders::OCCLUDE;

/// The uniform block `Proxies` of `occlude.wgsl`, field for field.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ProxyBlock {
    cull: f32,
    order: u32,
    pad: [u32; 2],
    spheres: [[f32; 4]; 2 * MAX_PROXIES],
}

/// A model's proxy buffers and the two kernels bound to them.
pub(crate) struct GpuProxies {
    block: wgpu::Buffer,
    masks: wgpu::Buffer,
    vertices: wgpu::Buffer,
    lighting: wgpu::Buffer,
    rotations: wgpu::Buffer,
    shading: Kernel,
    transfer: Kernel,
}

/// The buffers the proxies' kernels share with the model's: the rows layout, the rows, and
/// the two outputs they correct.
pub(crate) struct Shared<'a> {
    pub layout: &'a wgpu::Buffer,
    pub rows: &'a wgpu::Buffer,
    pub shading: &'a wgpu::Buffer,
    pub transfer: &'a wgpu::Buffer,
}

impl GpuProxies {
    /// The buffers, zeroed, and the kernels bound to them and to `shared`.
    pub(crate) fn new(gpu: &Gpu, info: &ModelInfo, shared: Shared<'_>) -> Result<Self, GpuError> {
        let input = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
        let uniform = wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST;
        let bones = info.bones().max(1);
        let block = gpu.buffer("proxies", &[ProxyBlock::zeroed()], uniform)?;
        let masks = gpu.buffer("proxy masks", &vec![[0u32; 2]; bones], input)?;
        let vertices = gpu.buffer("skinned vertices", &vec![0f32; 6 * info.vertices()], input)?;
        let lighting = gpu.buffer("lighting", &vec![0f32; info.coeffs()], input)?;
        let rotations = gpu.buffer("bone rotations", &vec![0f32; 9 * bones], input)?;
        let invocations = info.vertices() as u32;
        let Shared {
            layout,
            rows,
            shading,
            transfer,
        } = shared;
        let common = [
            (0, layout),
            (1, rows),
            (2, &block),
            (3, &masks),
            (4, &vertices),
        ];
        let shading = Kernel::new(
            gpu,
            (&OCCLUDE, "occlude_shading"),
            &[&common[..], &[(5, &lighting), (6, shading)]].concat(),
            invocations,
        );
        let transfer = Kernel::new(
            gpu,
            (&OCCLUDE, "occlude_transfer"),
            &[&common[..], &[(7, &rotations), (8, transfer)]].concat(),
            invocations,
        );
        Ok(GpuProxies {
            block,
            masks,
            vertices,
            lighting,
            rotations,
            shading,
            transfer,
        })
    }

    /// Writes the frame's posed proxies and skinned vertices (checked by aprt-core first).
    fn write_frame(
        &self,
        gpu: &Gpu,
        view: &ProxyView<'_>,
        info: &ModelInfo,
        vertices: Vertices<'_>,
    ) {
        let mut block = ProxyBlock {
            cull: view.cull(),
            order: info.order() as u32,
            ..ProxyBlock::zeroed()
        };
        for i in 0..MAX_PROXIES {
            let (centre, radius, reach) = view.sphere(i);
            block.spheres[2 * i] = [centre[0], centre[1], centre[2], radius];
            block.spheres[2 * i + 1] = [reach, 0.0, 0.0, 0.0];
        }
        let masks: Vec<[u32; 2]> = (0..view.bones().max(1))
            .map(|b| {
                let m = view.mask(b);
                [m as u32, (m >> 32) as u32]
            })
            .collect();
        let (positions, normals) = vertices;
        let packed: Vec<f32> = positions
            .iter()
            .zip(normals)
            .flat_map(|(p, n)| [p[0], p[1], p[2], n[0], n[1], n[2]])
            .collect();
        let queue = gpu.queue();
        queue.write_buffer(&self.block, 0, bytemuck::bytes_of(&block));
        queue.write_buffer(&self.masks, 0, bytemuck::cast_slice(&masks));
        queue.write_buffer(&self.vertices, 0, bytemuck::cast_slice(&packed));
    }

    /// Subtracts the caps under the world SH `lighting` from the shading buffer.
    pub(crate) fn occlude(
        &self,
        gpu: &Gpu,
        info: &ModelInfo,
        (frame, lighting): (&ProxyFrame, &[f32]),
        vertices: Vertices<'_>,
    ) -> Result<(), FrameError> {
        let view = info.proxy_inputs(frame, vertices, Some(lighting), None)?;
        self.write_frame(gpu, &view, info, vertices);
        gpu.queue()
            .write_buffer(&self.lighting, 0, bytemuck::cast_slice(lighting));
        self.shading.submit(gpu);
        Ok(())
    }

    /// Subtracts the caps, in each vertex's bone frame (`rotations`), from the transfer buffer.
    pub(crate) fn occlude_transfer(
        &self,
        gpu: &Gpu,
        info: &ModelInfo,
        (frame, rotations): (&ProxyFrame, &[Rotation]),
        vertices: Vertices<'_>,
    ) -> Result<(), FrameError> {
        let view = info.proxy_inputs(frame, vertices, None, Some(rotations))?;
        self.write_frame(gpu, &view, info, vertices);
        gpu.queue()
            .write_buffer(&self.rotations, 0, bytemuck::cast_slice(rotations));
        self.transfer.submit(gpu);
        Ok(())
    }
}
