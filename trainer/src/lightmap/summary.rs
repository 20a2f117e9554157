//! What `aprt lightmap inspect` reports about a light-map sequence file, decode time included.

use std::time::Instant;

use anyhow::{Context, Result};
use serde::Serialize;

use super::codec::ShlmFile;

/// A sequence file's dimensions, sizes and decode cost (the JSON of `aprt lightmap inspect`).
#[derive(Debug, Clone, Serialize)]
pub struct Summary {
    /// Frames stored.
    pub frames: usize,
    /// Atlas width and height in texels.
    pub resolution: usize,
    /// SH order n (n² maps per frame).
    pub order: usize,
    /// Size of the file.
    pub bytes: usize,
    /// Size of the f32 maps of every frame (frames × resolution² × n² × 4).
    pub raw_bytes: u64,
    /// `raw_bytes / bytes`.
    pub ratio: f64,
    /// Texels that hold transfer (the charts and their gutters).
    pub filled_texels: usize,
    /// Median wall-clock milliseconds to decode one frame into f32 maps, on one thread.
    pub decode_ms_per_frame: f64,
    /// Median milliseconds to copy one frame's f32 maps, timed interleaved with the decodes:
    /// the floor any decoder writing the same bytes pays on this machine.
    pub memcpy_ms_per_frame: f64,
    /// The codec and its parameters.
    pub codec: String,
    /// Triangles of the light-map UVs the file stores (`--uv generate`); 0 when the maps lie
    /// on the character's texture UVs.
    pub uv_triangles: usize,
}

/// Parses `bytes` and decodes every frame once, timing each against a copy of its maps.
pub fn summarize(bytes: &[u8]) -> Result<Summary> {
    let file = ShlmFile::parse(bytes)?;
    let n2 = file.order() * file.order();
    let mut map = vec![0.0f32; file.resolution() * file.resolution() * n2];
    let mut copy = map.clone();
    let (mut times, mut copies) = (Vec::new(), Vec::new());
    for k in 0..file.frames() {
        let start = Instant::now();
        file.decode_frame(k, &mut map)
            .with_context(|| format!("decoding frame {k}"))?;
        times.push(start.elapsed().as_secs_f64() * 1e3);
        let start = Instant::now();
        copy.copy_from_slice(std::hint::black_box(&map));
        std::hint::black_box(&copy);
        copies.push(start.elapsed().as_secs_f64() * 1e3);
    }
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v.get(v.len() / 2).copied().unwrap_or(0.0)
    };
    let filled = file.filled().iter().filter(|&&f| f).count();
    Ok(Summary {
        frames: file.frames(),
        resolution: file.resolution(),
        order: file.order(),
        bytes: bytes.len(),
        raw_bytes: file.raw_bytes(),
        ratio: file.raw_bytes() as f64 / bytes.len().max(1) as f64,
        filled_texels: filled,
        decode_ms_per_frame: median(times),
        memcpy_ms_per_frame: median(copies),
        codec: file.describe(),
        uv_triangles: file.layout().map_or(0, |l| l.corners.len()),
    })
}
