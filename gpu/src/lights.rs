//! Per-vertex lights on the device: each frame the lights' geometry (aprt-core's
//! `Light::shape`), colours and weights, the skinned positions and the bones' rotations are
//! written, and `lights.wgsl` shades every vertex through its own transfer.

use aprt_core::{Light, LightShape, ModelInfo, Rotation};
use bytemuck::Zeroable;

use crate::device::{Gpu, GpuError, Growing};
use crate::model::{FrameError, Kernel};
use crate::shaders::LIGHTS;

/// The struct `Light` of `lights.wgsl`, field for field (48 bytes).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct LightRecord {
    position: [f32; 3],
    radius: f32,
    colour: [f32; 3],
    radiance: f32,
    weight: f32,
    directional: u32,
    pad: [u32; 2],
}

impl LightRecord {
    fn of(light: &Light, weight: f32) -> LightRecord {
        let (position, radius, radiance, directional) = match light.shape() {
            LightShape::Sphere {
                centre,
                radius,
                radiance,
            } => (centre, radius, radiance, 0),
            LightShape::Directional(direction) => (direction, 0.0, 0.0, 1),
        };
        LightRecord {
            position,
            radius,
            colour: light.colour(),
            radiance,
            weight,
            directional,
            pad: [0; 2],
        }
    }
}

/// The uniform block `LightsInfo` of `lights.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct LightsInfo {
    count: u32,
    order: u32,
}

/// The buffers of per-vertex lights and the kernel bound to them.
pub(crate) struct GpuLights {
    /// The model's rows layout, rows and transfer weights, which the kernel reads.
    shared: [wgpu::Buffer; 3],
    block: wgpu::Buffer,
    lights: Growing,
    positions: wgpu::Buffer,
    rotations: wgpu::Buffer,
    rgb: wgpu::Buffer,
    kernel: Kernel,
}

impl GpuLights {
    /// The buffers, zeroed, with room for one light, and the kernel bound to them and to
    /// `shared` (the model's rows layout, rows and transfer weights).
    pub(crate) fn new(
        gpu: &Gpu,
        info: &ModelInfo,
        shared: [wgpu::Buffer; 3],
    ) -> Result<Self, GpuError> {
        let input = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
        let uniform = wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST;
        let vertices = info.vertices();
        let bones = info.bones().max(1);
        let block = gpu.buffer("lights info", &[LightsInfo::zeroed()], uniform)?;
        let lights = Growing::new(gpu, "lights", size_of::<LightRecord>())?;
        let positions = gpu.buffer("light positions", &vec![0f32; 3 * vertices], input)?;
        let rotations = gpu.buffer("light rotations", &vec![0f32; 9 * bones], input)?;
        let rgb = gpu.output::<f32>("lights rgb", 3 * vertices)?;
        let kernel = Kernel::new(
            gpu,
            (&LIGHTS, "shade_lights"),
            &bindings(
                &shared,
                [&rgb, lights.buffer(), &positions, &rotations, &block],
            ),
            vertices as u32,
        );
        Ok(GpuLights {
            shared,
            block,
            lights,
            positions,
            rotations,
            rgb,
            kernel,
        })
    }

    /// The RGB shading of the last [`GpuLights::shade`], three f32 per vertex.
    pub(crate) fn rgb(&self) -> &wgpu::Buffer {
        &self.rgb
    }

    /// Shades every vertex under `lights` (each scaled by its weight) at `positions`, after
    /// aprt-core's checks; `transfer_weights` are the frame's, from the same pose.
    pub(crate) fn shade(
        &mut self,
        gpu: &Gpu,
        info: &ModelInfo,
        transfer_weights: &[f32],
        (lights, weights): (&[Light], &[f32]),
        (positions, bones): (&[[f32; 3]], &[Rotation]),
    ) -> Result<(), FrameError> {
        let records: Vec<LightRecord> = lights
            .iter()
            .zip(weights)
            .map(|(light, &weight)| LightRecord::of(light, weight))
            .collect();
        let block = LightsInfo {
            count: lights.len() as u32,
            order: info.order() as u32,
        };
        let queue = gpu.queue();
        queue.write_buffer(&self.shared[2], 0, bytemuck::cast_slice(transfer_weights));
        queue.write_buffer(&self.block, 0, bytemuck::bytes_of(&block));
        queue.write_buffer(&self.positions, 0, bytemuck::cast_slice(positions));
        if !bones.is_empty() {
            queue.write_buffer(&self.rotations, 0, bytemuck::cast_slice(bones));
        }
        if self.lights.write(gpu, &records)? {
            let own = [
                &self.rgb,
                self.lights.buffer(),
                &self.positions,
                &self.rotations,
                &self.block,
            ];
            self.kernel.rebind(gpu, &bindings(&self.shared, own));
        }
        self.kernel.submit(gpu);
        Ok(())
    }
}

/// The kernel's bindings in `lights.wgsl`'s order: the model's three, then its own five.
fn bindings<'a>(
    shared: &'a [wgpu::Buffer; 3],
    own: [&'a wgpu::Buffer; 5],
) -> Vec<(u32, &'a wgpu::Buffer)> {
    (0..).zip(shared.iter().chain(own)).collect()
}
