//! Widening packed rows to f32 on the device ([`UNPACK`](crate::shaders::UNPACK)): the
//! conversions a model's f16 and i8 sections need, run end to end (upload, dispatch, read
//! back) so the device plumbing is tested against the CPU bit for bit. Both conversions are
//! exact on the CPU (f16 to f32 widens; i8 times a scale rounds once), so a GPU must agree.

use std::fmt;

use crate::device::{Gpu, GpuError};
use crate::shaders::UNPACK;

/// Threads per workgroup, as `@workgroup_size` in `unpack.wgsl`.
const WORKGROUP: u32 = 64;

/// The packed inputs.
#[derive(Clone, Copy, Debug)]
pub struct Packed<'a> {
    /// f16 values, as their bits.
    pub f16_bits: &'a [u16],
    /// i8 values in rows of `i8_row_len`.
    pub i8_values: &'a [i8],
    /// Values per i8 row.
    pub i8_row_len: usize,
    /// One scale per i8 row.
    pub i8_scales: &'a [f32],
}

/// The inputs widened to f32, in the same order.
#[derive(Clone, Debug, PartialEq)]
pub struct Unpacked {
    /// `f16_bits` as f32.
    pub from_f16: Vec<f32>,
    /// Each i8 value times its row's scale.
    pub from_i8: Vec<f32>,
}

/// Why [`unpack`] failed.
#[derive(Debug)]
pub enum UnpackError {
    /// The i8 values are not whole rows of `i8_row_len`, one per scale; refused before upload.
    Rows {
        /// The i8 values given.
        values: usize,
        /// The row length given.
        row_len: usize,
        /// The scales given.
        scales: usize,
    },
    /// The device refused or failed.
    Gpu(GpuError),
}

impl From<GpuError> for UnpackError {
    fn from(e: GpuError) -> Self {
        UnpackError::Gpu(e)
    }
}

/// The uniform block of `unpack.wgsl`, field for field.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    half_words: u32,
    quad_words: u32,
    quad_values: u32,
    row_len: u32,
    grid_width: u32,
}

/// `packed` widened to f32 on `gpu`, with one blocking read-back.
pub fn unpack(gpu: &Gpu, packed: &Packed<'_>) -> Result<Unpacked, UnpackError> {
    let Packed {
        f16_bits,
        i8_values,
        i8_row_len,
        i8_scales,
    } = *packed;
    let whole_rows = match i8_values.len().checked_div(i8_row_len) {
        Some(rows) => rows * i8_row_len == i8_values.len() && rows == i8_scales.len(),
        None => i8_values.is_empty() && i8_scales.is_empty(),
    };
    if !whole_rows {
        return Err(UnpackError::Rows {
            values: i8_values.len(),
            row_len: i8_row_len,
            scales: i8_scales.len(),
        });
    }

    // Little-endian words, as the shader reads them; a short last word is padded with zeros.
    let halves: Vec<u32> = f16_bits
        .chunks(2)
        .map(|pair| u32::from(pair[0]) | (u32::from(pair.get(1).copied().unwrap_or(0)) << 16))
        .collect();
    let quads: Vec<u32> = i8_values
        .chunks(4)
        .map(|quad| {
            let mut bytes = [0; 4];
            for (byte, &value) in bytes.iter_mut().zip(quad) {
                *byte = value.to_le_bytes()[0];
            }
            u32::from_le_bytes(bytes)
        })
        .collect();
    let words = halves.len().max(quads.len());
    if words == 0 {
        return Ok(Unpacked {
            from_f16: Vec::new(),
            from_i8: Vec::new(),
        });
    }

    let storage = wgpu::BufferUsages::STORAGE;
    let halves_buffer = gpu.buffer("halves", &halves, storage)?;
    let quads_buffer = gpu.buffer("quads", &quads, storage)?;
    let scales_buffer = gpu.buffer("scales", i8_scales, storage)?;
    // `from_f16` holds whole pairs: the padding value of an odd count is read back and dropped.
    let from_f16 = gpu.output::<f32>("from_f16", halves.len() * 2)?;
    let from_i8 = gpu.output::<f32>("from_i8", i8_values.len())?;

    // Every count fits a u32: the buffers passed the device's binding limit, which
    // `Gpu::new` keeps within 4 GiB.
    let groups = words.div_ceil(WORKGROUP as usize) as u32;
    let max_groups = gpu.device().limits().max_compute_workgroups_per_dimension;
    let (groups_x, groups_y) = (groups.min(max_groups), groups.div_ceil(max_groups));
    let params = Params {
        half_words: halves.len() as u32,
        quad_words: quads.len() as u32,
        quad_values: i8_values.len() as u32,
        // Any non-zero value when there are no i8 rows: the shader divides by it.
        row_len: i8_row_len.max(1) as u32,
        grid_width: groups_x * WORKGROUP,
    };
    let params_buffer = gpu.buffer("params", &[params], wgpu::BufferUsages::UNIFORM)?;

    let pipeline = gpu.pipeline(&UNPACK, "main");
    // In binding order, as declared in `unpack.wgsl`.
    let bindings = [
        &params_buffer,
        &halves_buffer,
        &quads_buffer,
        &scales_buffer,
        &from_f16,
        &from_i8,
    ];
    let entries: Vec<_> = (0..)
        .zip(bindings)
        .map(|(binding, buffer)| wgpu::BindGroupEntry {
            binding,
            resource: buffer.as_entire_binding(),
        })
        .collect();
    let bind_group = gpu.device().create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(UNPACK.name),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &entries,
    });
    let mut encoder = gpu.device().create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.dispatch_workgroups(groups_x, groups_y, 1);
    }
    gpu.queue().submit([encoder.finish()]);

    let mut widened_f16 = gpu.read_back::<f32>(&from_f16, halves.len() * 2)?;
    widened_f16.truncate(f16_bits.len());
    Ok(Unpacked {
        from_f16: widened_f16,
        from_i8: gpu.read_back(&from_i8, i8_values.len())?,
    })
}

impl fmt::Display for UnpackError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            UnpackError::Rows {
                values,
                row_len,
                scales,
            } => write!(
                f,
                "{values} i8 values are not {scales} rows of {row_len} (one scale per row)"
            ),
            UnpackError::Gpu(e) => e.fmt(f),
        }
    }
}

impl std::error::Error for UnpackError {}
