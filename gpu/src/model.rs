//! A validated aprt-core model on the device: its vertex rows uploaded once as the blob stores
//! them (blocks of eight vertices; f16 pairs and i8 quads widened in the shader), and each
//! frame's small weights, computed by aprt-core on the CPU exactly as for the CPU path,
//! written before the kernels run over the vertices. The outputs stay on the device, in
//! storage buffers an engine can bind as vertex buffers, or are read back.

use std::fmt;

use aprt_core::{
    Basis, Encoding, IrradianceRig, Light, LitWeights, Model, ModelInfo, Placement, PoseWeights,
    ProxyFrame, RigLitWeights, Rotation,
};

use crate::device::{Gpu, GpuError};
use crate::lights::GpuLights;
use crate::proxies::{GpuProxies, Shared};
use crate::rig::GpuRig;
use crate::shaders::{SHADE, Shader, TRANSFER};

/// Threads per workgroup, as `@workgroup_size` in the kernels.
const WORKGROUP: u32 = 64;

/// The uniform block `Rows` of `rows.wgsl`, field for field.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct RowsLayout {
    vertices: u32,
    encoding: u32,
    lead_rows: u32,
    row_width: u32,
    block_words: u32,
    bones: u32,
    coeffs: u32,
    identity: u32,
}

/// Why a frame was not computed.
#[derive(Debug)]
pub enum FrameError {
    /// aprt-core refused the frame's inputs (weights of another model, or not set): nothing
    /// was uploaded.
    Core(aprt_core::Error),
    /// The device failed.
    Gpu(GpuError),
}

impl From<GpuError> for FrameError {
    fn from(e: GpuError) -> Self {
        FrameError::Gpu(e)
    }
}

impl From<aprt_core::Error> for FrameError {
    fn from(e: aprt_core::Error) -> Self {
        FrameError::Core(e)
    }
}

/// The caller's skinned mesh this frame: world positions and normals, one per vertex.
pub type Vertices<'a> = (&'a [[f32; 3]], &'a [[f32; 3]]);

/// One kernel bound to a model's buffers.
pub(crate) struct Kernel {
    pipeline: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
    /// Its shader's name, for labels.
    label: &'static str,
    /// Invocations of a frame.
    invocations: u32,
}

impl Kernel {
    /// `shader`'s `entry` over `invocations`, with each buffer of `bindings` at its binding.
    pub(crate) fn new(
        gpu: &Gpu,
        (shader, entry): (&Shader, &str),
        bindings: &[(u32, &wgpu::Buffer)],
        invocations: u32,
    ) -> Kernel {
        let pipeline = gpu.pipeline(shader, entry);
        let bind_group = bind_group(gpu, &pipeline, shader.name, bindings);
        Kernel {
            pipeline,
            bind_group,
            label: shader.name,
            invocations,
        }
    }

    /// Binds `bindings` in place of the kernel's buffers (one that outgrew its buffer).
    pub(crate) fn rebind(&mut self, gpu: &Gpu, bindings: &[(u32, &wgpu::Buffer)]) {
        self.bind_group = bind_group(gpu, &self.pipeline, self.label, bindings);
    }

    /// Records the kernel into `encoder`: rows of at most the device's workgroups per
    /// dimension, which the kernels turn back into one index (`invocation` in `rows.wgsl`).
    fn record(&self, gpu: &Gpu, encoder: &mut wgpu::CommandEncoder) {
        let groups = self.invocations.div_ceil(WORKGROUP);
        let max = gpu.device().limits().max_compute_workgroups_per_dimension;
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.bind_group, &[]);
        pass.dispatch_workgroups(groups.min(max), groups.div_ceil(max), 1);
    }

    /// Records the kernel alone and submits it.
    pub(crate) fn submit(&self, gpu: &Gpu) {
        let mut encoder = gpu.device().create_command_encoder(&Default::default());
        self.record(gpu, &mut encoder);
        gpu.queue().submit([encoder.finish()]);
    }
}

/// `pipeline`'s bind group with each buffer of `bindings` at its binding.
fn bind_group(
    gpu: &Gpu,
    pipeline: &wgpu::ComputePipeline,
    label: &str,
    bindings: &[(u32, &wgpu::Buffer)],
) -> wgpu::BindGroup {
    let entries: Vec<_> = bindings
        .iter()
        .map(|&(binding, buffer)| wgpu::BindGroupEntry {
            binding,
            resource: buffer.as_entire_binding(),
        })
        .collect();
    gpu.device().create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &entries,
    })
}

/// A model's vertex rows on the device and the kernels bound to them. Each frame, compute the
/// pose and lighting weights with aprt-core's [`Model::set_pose`] and [`Model::light`] (the
/// same calls, the same bits as on the CPU), then call [`GpuModel::shade`] or
/// [`GpuModel::transfer`]; the results are in [`GpuModel::shading`] and
/// [`GpuModel::transfer_values`]. Those calls submit the work and return: later work on the
/// same queue sees the results, and [`Gpu::wait`] blocks until they are there.
pub struct GpuModel {
    info: ModelInfo,
    lit: wgpu::Buffer,
    weights: wgpu::Buffer,
    shading: wgpu::Buffer,
    transfer: wgpu::Buffer,
    shade_kernel: Kernel,
    transfer_kernel: Kernel,
    proxies: Option<GpuProxies>,
    lights: GpuLights,
    rig: GpuRig,
}

impl GpuModel {
    /// Uploads `model`'s vertex rows (validated by [`Model::parse`]) and builds its kernels.
    /// Refused before anything is uploaded when a buffer exceeds the device's binding limit.
    pub fn upload(gpu: &Gpu, model: &Model<'_>) -> Result<GpuModel, GpuError> {
        let info = *model.info();
        let rows = model.vertex_rows();
        let n2 = info.coeffs();
        let vertices = info.vertices();
        let storage = wgpu::BufferUsages::STORAGE;
        let frame_input = storage | wgpu::BufferUsages::COPY_DST;
        // Sizes first: nothing is uploaded unless every buffer fits.
        gpu.check_size("transfer", 4 * (vertices * n2) as u64)?;
        gpu.check_size("vertex rows", rows.bytes.len() as u64)?;
        // A section's length is whole blocks of 8 values of 4, 2 or 1 bytes: whole words.
        let words: Vec<u32> = rows
            .bytes
            .chunks_exact(4)
            .map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]]))
            .collect();
        let layout = RowsLayout {
            vertices: vertices as u32,
            encoding: match rows.encoding {
                Encoding::F32 => 0,
                Encoding::F16 => 1,
                Encoding::I8 => 2,
            },
            lead_rows: rows.lead_rows as u32,
            row_width: rows.row_width as u32,
            block_words: (rows.bytes.len() / 4 / rows.blocks.max(1)) as u32,
            bones: info.bones().max(1) as u32,
            coeffs: n2 as u32,
            identity: u32::from(info.basis() == Basis::Identity),
        };
        let layout = gpu.buffer("rows layout", &[layout], wgpu::BufferUsages::UNIFORM)?;
        let rows = gpu.buffer("vertex rows", &words, storage)?;
        let lit = gpu.buffer(
            "lit weights",
            &vec![0f32; info.lit_weights_len()],
            frame_input,
        )?;
        let weights = gpu.buffer(
            "transfer weights",
            &vec![0f32; info.transfer_weights_len()],
            frame_input,
        )?;
        let shading = gpu.output::<f32>("shading", vertices)?;
        let transfer = gpu.output::<f32>("transfer", vertices * n2)?;
        let shade_kernel = Kernel::new(
            gpu,
            (&SHADE, "shade"),
            &[(0, &layout), (1, &rows), (2, &lit), (3, &shading)],
            vertices as u32,
        );
        let transfer_kernel = Kernel::new(
            gpu,
            (&TRANSFER, "transfer_values"),
            &[(0, &layout), (1, &rows), (2, &weights), (3, &transfer)],
            vertices as u32,
        );
        let shared = Shared {
            layout: &layout,
            rows: &rows,
            shading: &shading,
            transfer: &transfer,
        };
        let proxies = match info.has_proxies() {
            true => Some(GpuProxies::new(gpu, &info, shared)?),
            false => None,
        };
        let lights = GpuLights::new(gpu, &info, [layout.clone(), rows.clone(), weights.clone()])?;
        let rig = GpuRig::new(gpu, &info, [layout.clone(), rows.clone()])?;
        Ok(GpuModel {
            info,
            lit,
            weights,
            shading,
            transfer,
            shade_kernel,
            transfer_kernel,
            proxies,
            lights,
            rig,
        })
    }

    /// The model's dimensions.
    pub fn info(&self) -> &ModelInfo {
        &self.info
    }

    /// Shades every vertex under the lighting weights `lit` of [`Model::light`] into
    /// [`GpuModel::shading`]. Weights of another model, or never set, are refused before
    /// anything is written.
    pub fn shade<const L: usize>(&self, gpu: &Gpu, lit: &LitWeights<L>) -> Result<(), FrameError> {
        let q = self.info.lit_values(lit)?;
        gpu.queue()
            .write_buffer(&self.lit, 0, bytemuck::cast_slice(q));
        self.shade_kernel.submit(gpu);
        Ok(())
    }

    /// Every vertex's n² transfer values for the pose of [`Model::set_pose`] into
    /// [`GpuModel::transfer_values`], vertex-major, in its bone's frame for a bone-frame model
    /// (as [`Model::transfer`]). Weights of another model are refused before anything is
    /// written.
    pub fn transfer<const P: usize>(
        &self,
        gpu: &Gpu,
        pose: &PoseWeights<P>,
    ) -> Result<(), FrameError> {
        let mut w = vec![0f32; self.info.transfer_weights_len()];
        self.info.transfer_weights(pose, &mut w)?;
        gpu.queue()
            .write_buffer(&self.weights, 0, bytemuck::cast_slice(&w));
        self.transfer_kernel.submit(gpu);
        Ok(())
    }

    /// Subtracts the occluder proxies' occlusion under the world SH `lighting` (as given to
    /// [`Model::light`]) from [`GpuModel::shading`]: call after [`GpuModel::shade`], with the
    /// frame's proxies posed by [`Model::pose_proxies`] and the skinned mesh's world
    /// positions and normals, as [`Model::occlude`] takes them. Everything is checked by
    /// aprt-core before anything is written; a model without proxies refuses.
    pub fn occlude(
        &self,
        gpu: &Gpu,
        (frame, lighting): (&ProxyFrame, &[f32]),
        vertices: Vertices<'_>,
    ) -> Result<(), FrameError> {
        self.proxies()?
            .occlude(gpu, &self.info, (frame, lighting), vertices)
    }

    /// Subtracts the proxies' occlusion from [`GpuModel::transfer_values`], each vertex's in
    /// its bone's frame (`rotations` as given to [`Model::light`]), as
    /// [`Model::occlude_transfer`] does: call after [`GpuModel::transfer`].
    pub fn occlude_transfer(
        &self,
        gpu: &Gpu,
        (frame, rotations): (&ProxyFrame, &[Rotation]),
        vertices: Vertices<'_>,
    ) -> Result<(), FrameError> {
        self.proxies()?
            .occlude_transfer(gpu, &self.info, (frame, rotations), vertices)
    }

    /// The RGB shading of every vertex under `lights`, each scaled by its weight, evaluated at
    /// the vertex's world position (`positions`, the skinned mesh) against its transfer for
    /// `pose`, into [`GpuModel::lights_rgb`], as [`Model::shade_lights`] adds it (`bones` as
    /// given to [`Model::light`]). Everything is checked by aprt-core before anything is
    /// written. Takes `&mut self`: the lights' buffer grows to the most lights a frame has had.
    pub fn shade_lights<const P: usize>(
        &mut self,
        gpu: &Gpu,
        (pose, bones): (&PoseWeights<P>, &[Rotation]),
        lights: (&[Light], &[f32]),
        positions: &[[f32; 3]],
    ) -> Result<(), FrameError> {
        self.info.light_inputs(pose, bones, lights, positions)?;
        let mut w = vec![0f32; self.info.transfer_weights_len()];
        self.info.transfer_weights(pose, &mut w)?;
        self.lights
            .shade(gpu, &self.info, &w, lights, (positions, bones))
    }

    /// The last [`GpuModel::shade_lights`], RGB, three f32 per vertex.
    pub fn lights_rgb(&self) -> &wgpu::Buffer {
        self.lights.rgb()
    }

    /// The last [`GpuModel::shade_lights`], read back (a blocking wait).
    pub fn read_lights(&self, gpu: &Gpu) -> Result<Vec<[f32; 3]>, GpuError> {
        read_rgb(gpu, self.lights.rgb(), self.info.vertices())
    }

    /// The RGB shading of every vertex under an irradiance rig's lighting at its own world
    /// position (`positions`, the skinned mesh), from the weights of [`Model::light_rig`],
    /// into [`GpuModel::rig_rgb`], as [`Model::shade_rig`] gives it. Everything is checked by
    /// aprt-core before anything is written. Takes `&mut self`: the weights' buffer grows to
    /// the largest rig a frame has had.
    pub fn shade_rig(
        &mut self,
        gpu: &Gpu,
        (lit, rig, placement): (&RigLitWeights<'_>, &IrradianceRig<'_>, &Placement),
        positions: &[[f32; 3]],
    ) -> Result<(), FrameError> {
        let q = self.info.rig_inputs(lit, rig, positions)?;
        self.rig
            .shade(gpu, &self.info, (q, rig, placement), positions)
    }

    /// The last [`GpuModel::shade_rig`], RGB, three f32 per vertex.
    pub fn rig_rgb(&self) -> &wgpu::Buffer {
        self.rig.rgb()
    }

    /// The last [`GpuModel::shade_rig`], read back (a blocking wait).
    pub fn read_rig(&self, gpu: &Gpu) -> Result<Vec<[f32; 3]>, GpuError> {
        read_rgb(gpu, self.rig.rgb(), self.info.vertices())
    }

    fn proxies(&self) -> Result<&GpuProxies, FrameError> {
        self.proxies
            .as_ref()
            .ok_or(FrameError::Core(aprt_core::Error::NoProxies))
    }

    /// The last shading, one f32 per vertex: bind it as a vertex buffer (`Float32`), or
    /// read it back with [`GpuModel::read_shading`].
    pub fn shading(&self) -> &wgpu::Buffer {
        &self.shading
    }

    /// The last transfer, n² f32 per vertex.
    pub fn transfer_values(&self) -> &wgpu::Buffer {
        &self.transfer
    }

    /// The last shading, read back (a blocking wait).
    pub fn read_shading(&self, gpu: &Gpu) -> Result<Vec<f32>, GpuError> {
        gpu.read_back(&self.shading, self.info.vertices())
    }

    /// The last transfer, read back (a blocking wait).
    pub fn read_transfer(&self, gpu: &Gpu) -> Result<Vec<f32>, GpuError> {
        gpu.read_back(&self.transfer, self.info.vertices() * self.info.coeffs())
    }
}

/// `vertices` RGB triples of `buffer`, read back.
fn read_rgb(gpu: &Gpu, buffer: &wgpu::Buffer, vertices: usize) -> Result<Vec<[f32; 3]>, GpuError> {
    let values: Vec<f32> = gpu.read_back(buffer, 3 * vertices)?;
    Ok(values.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect())
}

impl fmt::Display for FrameError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            FrameError::Core(e) => write!(f, "refused on the CPU: {e}"),
            FrameError::Gpu(e) => e.fmt(f),
        }
    }
}

impl std::error::Error for FrameError {}
