//! The headless device: no window and no surface (the kernels only compute), so the same code
//! runs on a desktop GPU, on a server and in CI on a software adapter (lavapipe).

use std::fmt;

use bytemuck::Pod;
use wgpu::util::DeviceExt;

use crate::shaders::Shader;

/// A device, its queue and what the adapter said about itself.
#[derive(Debug)]
pub struct Gpu {
    device: wgpu::Device,
    queue: wgpu::Queue,
    info: wgpu::AdapterInfo,
}

/// No backend gave a usable device; [`fmt::Display`] says what each one answered.
#[derive(Debug)]
pub struct NoAdapter {
    tried: Vec<String>,
}

/// Why the device could not do what was asked.
#[derive(Debug)]
pub enum GpuError {
    /// A buffer would exceed what the device allows for one binding; refused before upload.
    TooLarge {
        /// The buffer's label.
        buffer: &'static str,
        /// Its size.
        bytes: u64,
        /// The device's limit.
        limit: u64,
    },
    /// Mapping a read-back buffer failed (the device was lost, or the buffer destroyed).
    Map(wgpu::BufferAsyncError),
    /// The mapped bytes could not be viewed.
    View(wgpu::MapRangeError),
    /// Waiting for the device failed (lost, or timed out).
    Poll(wgpu::PollError),
}

/// The backends tried, in order: Vulkan first (lavapipe in CI, the desktop drivers of Linux
/// and Windows), then OpenGL (llvmpipe, older drivers). Metal and DX12 are not tried yet:
/// nothing here can test them.
const BACKENDS: [(wgpu::Backends, &str); 2] = [
    (wgpu::Backends::VULKAN, "Vulkan"),
    (wgpu::Backends::GL, "GL"),
];

impl Gpu {
    /// A device on the first adapter that gives one, trying Vulkan, then GL. It has WebGPU's
    /// default limits (so what runs here runs in a browser) except the buffer sizes, which
    /// are the adapter's (up to 4 GiB): a model's largest section is one binding.
    ///
    /// Any adapter is accepted, a software one (CPU) included; when a backend has several,
    /// wgpu's high-performance preference picks a discrete GPU first.
    pub fn new() -> Result<Gpu, NoAdapter> {
        let mut tried = Vec::new();
        for (backends, name) in BACKENDS {
            match pollster::block_on(Self::on(backends)) {
                Ok(gpu) => return Ok(gpu),
                Err(why) => tried.push(format!("{name}: {why}")),
            }
        }
        Err(NoAdapter { tried })
    }

    async fn on(backends: wgpu::Backends) -> Result<Gpu, String> {
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
            backends,
            ..wgpu::InstanceDescriptor::new_without_display_handle()
        });
        let adapter = instance
            .request_adapter(&wgpu::RequestAdapterOptions {
                power_preference: wgpu::PowerPreference::HighPerformance,
                ..Default::default()
            })
            .await
            .map_err(|e| e.to_string())?;
        let info = adapter.get_info();
        let offered = adapter.limits();
        let required_limits = wgpu::Limits {
            // At most 4 GiB, so every element count and index in a kernel fits its u32.
            max_storage_buffer_binding_size: offered
                .max_storage_buffer_binding_size
                .min(u64::from(u32::MAX)),
            max_buffer_size: offered.max_buffer_size,
            ..wgpu::Limits::default()
        };
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("aprt-gpu"),
                required_limits,
                ..Default::default()
            })
            .await
            .map_err(|e| format!("adapter {:?} refused a device: {e}", info.name))?;
        Ok(Gpu {
            device,
            queue,
            info,
        })
    }

    /// An engine's own device and queue (wgpu 30, as this crate pins), with its adapter's
    /// info: the kernels then run beside the engine's passes and their output buffers bind in
    /// its pipelines. The device's limits are the engine's to choose; a buffer beyond them is
    /// refused before upload.
    pub fn from_parts(device: wgpu::Device, queue: wgpu::Queue, info: wgpu::AdapterInfo) -> Gpu {
        Gpu {
            device,
            queue,
            info,
        }
    }

    /// The device, to create buffers and pipelines.
    pub fn device(&self) -> &wgpu::Device {
        &self.device
    }

    /// The device's queue, to upload and submit.
    pub fn queue(&self) -> &wgpu::Queue {
        &self.queue
    }

    /// Everything the adapter reported (vendor, device type, ...).
    pub fn info(&self) -> &wgpu::AdapterInfo {
        &self.info
    }

    /// The adapter's name, for example `llvmpipe (LLVM 15.0.6, 256 bits)` for lavapipe: the
    /// tests and the bench print it so a figure says what it was measured on.
    pub fn name(&self) -> &str {
        &self.info.name
    }

    /// The backend the device runs on.
    pub fn backend(&self) -> wgpu::Backend {
        self.info.backend
    }

    /// The driver and its version, for example `llvmpipe, Mesa 22.3.6 (LLVM 15.0.6)`.
    pub fn driver(&self) -> String {
        match (self.info.driver.as_str(), self.info.driver_info.as_str()) {
            ("", info) | (info, "") => info.to_owned(),
            (driver, info) => format!("{driver}, {info}"),
        }
    }

    /// Blocks until the device has finished everything submitted so far. [`GpuModel::shade`]
    /// and [`GpuModel::transfer`] only submit, as a frame loop wants; a caller that times a
    /// frame, or hands the output to work outside this queue, waits here.
    ///
    /// [`GpuModel::shade`]: crate::GpuModel::shade
    /// [`GpuModel::transfer`]: crate::GpuModel::transfer
    pub fn wait(&self) -> Result<(), GpuError> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map(drop)
            .map_err(GpuError::Poll)
    }

    /// A compute pipeline for `entry` of `shader`, its bind group layout taken from the WGSL.
    pub(crate) fn pipeline(&self, shader: &Shader, entry: &str) -> wgpu::ComputePipeline {
        let module = self
            .device
            .create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(shader.name),
                source: wgpu::ShaderSource::Wgsl(shader.source.into()),
            });
        self.device
            .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(shader.name),
                layout: None,
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            })
    }

    /// A buffer holding `contents`, refused before upload if the device cannot bind it. An
    /// empty one gets a word of zeros: a binding cannot be empty.
    pub(crate) fn buffer<T: Pod>(
        &self,
        label: &'static str,
        contents: &[T],
        usage: wgpu::BufferUsages,
    ) -> Result<wgpu::Buffer, GpuError> {
        let bytes: &[u8] = bytemuck::cast_slice(contents);
        self.check_size(label, bytes.len() as u64)?;
        let contents = if bytes.is_empty() { &[0; 4] } else { bytes };
        Ok(self
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage,
            }))
    }

    /// A storage buffer for `len` values of `T` that a kernel writes, an engine may bind as a
    /// vertex buffer and the CPU may read back.
    pub(crate) fn output<T: Pod>(
        &self,
        label: &'static str,
        len: usize,
    ) -> Result<wgpu::Buffer, GpuError> {
        let bytes = (len as u64).saturating_mul(size_of::<T>() as u64);
        self.check_size(label, bytes)?;
        Ok(self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: bytes.max(4),
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::VERTEX
                | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        }))
    }

    /// Refuses a buffer of `bytes` the device cannot bind.
    pub(crate) fn check_size(&self, buffer: &'static str, bytes: u64) -> Result<(), GpuError> {
        let limits = self.device.limits();
        let limit = limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size);
        if bytes > limit {
            return Err(GpuError::TooLarge {
                buffer,
                bytes,
                limit,
            });
        }
        Ok(())
    }

    /// The first `len` values of `buffer`, copied to a mappable buffer and read back once the
    /// queue has finished everything submitted before (a blocking wait: for tests, tools and
    /// the bench, not a frame loop).
    pub(crate) fn read_back<T: Pod>(
        &self,
        buffer: &wgpu::Buffer,
        len: usize,
    ) -> Result<Vec<T>, GpuError> {
        let bytes = (len * size_of::<T>()) as u64;
        if bytes == 0 {
            return Ok(Vec::new());
        }
        // Copies and maps move whole words; a `T` narrower than 4 bytes is rounded up.
        let padded = bytes.next_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT);
        let staging = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("read-back"),
            size: padded,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder = self.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(buffer, 0, &staging, 0, padded);
        self.queue.submit([encoder.finish()]);

        let (sender, receiver) = std::sync::mpsc::channel();
        staging.map_async(wgpu::MapMode::Read, .., move |mapped| {
            // The receiver is alive until `recv` below returns.
            let _ = sender.send(mapped);
        });
        self.wait()?;
        // `poll` ran the callback before returning, so the value is there.
        receiver
            .recv()
            .map_err(|_| GpuError::Map(wgpu::BufferAsyncError))?
            .map_err(GpuError::Map)?;
        let view = staging.get_mapped_range(..).map_err(GpuError::View)?;
        // Copied out whatever the mapping's alignment.
        let values = bytemuck::pod_collect_to_vec(&view[..bytes as usize]);
        drop(view);
        staging.unmap();
        Ok(values)
    }
}

/// A storage input whose size each frame decides (its lights, its rig's weights): it grows to
/// the largest a frame has had, and says when it did, so the kernels reading it bind it again.
pub(crate) struct Growing {
    label: &'static str,
    buffer: wgpu::Buffer,
}

impl Growing {
    /// A buffer of `bytes` zeros (at least a word).
    pub(crate) fn new(gpu: &Gpu, label: &'static str, bytes: usize) -> Result<Self, GpuError> {
        let zeros = vec![0u32; bytes.div_ceil(4).max(1)];
        let buffer = gpu.buffer(label, &zeros, Self::USAGE)?;
        Ok(Growing { label, buffer })
    }

    const USAGE: wgpu::BufferUsages =
        wgpu::BufferUsages::STORAGE.union(wgpu::BufferUsages::COPY_DST);

    /// The buffer, to bind.
    pub(crate) fn buffer(&self) -> &wgpu::Buffer {
        &self.buffer
    }

    /// Writes `values`, in a new buffer when they outgrow this one: `true` when it is new.
    pub(crate) fn write<T: Pod>(&mut self, gpu: &Gpu, values: &[T]) -> Result<bool, GpuError> {
        let bytes: &[u8] = bytemuck::cast_slice(values);
        if bytes.len() as u64 > self.buffer.size() {
            self.buffer = gpu.buffer(self.label, values, Self::USAGE)?;
            return Ok(true);
        }
        gpu.queue.write_buffer(&self.buffer, 0, bytes);
        Ok(false)
    }
}

impl fmt::Display for Gpu {
    /// `name (backend, driver)`, the line the tests print.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} ({}, {})", self.name(), self.backend(), self.driver())
    }
}

impl fmt::Display for NoAdapter {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "no GPU adapter ({})", self.tried.join("; "))
    }
}

impl std::error::Error for NoAdapter {}

impl fmt::Display for GpuError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            GpuError::TooLarge {
                buffer,
                bytes,
                limit,
            } => write!(
                f,
                "buffer {buffer:?} would be {bytes} bytes, over the device's {limit}-byte binding limit"
            ),
            GpuError::Map(e) => write!(f, "reading back failed: {e}"),
            GpuError::View(e) => write!(f, "reading back failed: {e}"),
            GpuError::Poll(e) => write!(f, "waiting for the device failed: {e}"),
        }
    }
}

impl std::error::Error for GpuError {}
