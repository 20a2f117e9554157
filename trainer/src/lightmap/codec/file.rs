//! The `.shlm` container: writing the sections, and [`ShlmFile`], a validated view that
//! decodes one frame at a time.

use std::ops::Range;

use super::CodecError;
use super::MapSequence;
use super::entropy::{compress, decompress_chunk, decompress_exact};
use super::header::{Header, StoredKind};
use super::shared_exp::{Grouping, SignMode, decode_planes_on};
use super::uniform::{self, Grid};
use super::uvs::{read_uvs, write_uvs};
use crate::bake::budget::bytes as show_bytes;
use crate::limits::MAX_BYTES;
use crate::rig::uv::UvLayout;

/// Whether frame `f` of `frames` is stored under keyframe interval `interval`: every
/// `interval`-th frame, and the last, so every in-between has a keyframe on each side.
pub fn is_keyframe(f: usize, interval: usize, frames: usize) -> bool {
    f.is_multiple_of(interval) || f + 1 == frames
}

/// Writes header, mask, positions, shared section, light-map UVs, offset table, chunks and
/// CRC, for the sequence `seq` (its mask, positions and UVs).
pub fn assemble(
    mut header: Header,
    seq: &MapSequence,
    shared: &[Vec<u8>],
    chunks: &[Vec<u8>],
    level: i32,
) -> Result<Vec<u8>, CodecError> {
    let filled = &seq.filled;
    let mut mask = vec![0u8; filled.len().div_ceil(8)];
    for t in (0..filled.len()).filter(|&t| filled[t]) {
        mask[t / 8] |= 1 << (t % 8);
    }
    let mask = compress(&mask, level)?;
    let points: Vec<u8> = seq
        .positions
        .iter()
        .flatten()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    let points = compress(&points, level)?;
    let mut shared_section = Vec::new();
    if !shared.is_empty() {
        shared_section.extend_from_slice(&u32_len(shared.len())?.to_le_bytes());
        for blob in shared {
            shared_section.extend_from_slice(&u32_len(blob.len())?.to_le_bytes());
        }
        shared
            .iter()
            .for_each(|b| shared_section.extend_from_slice(b));
    }
    let uvs = match &seq.layout {
        Some(layout) if header.atlas == Some(layout.fingerprint()) => write_uvs(layout, level)?,
        Some(_) => {
            return Err(CodecError::Input(
                "the light-map UVs are not the ones the atlas fingerprint names".into(),
            ));
        }
        None => Vec::new(),
    };
    header.uv_triangles = seq.layout.as_ref().map_or(0, |l| l.corners.len());
    header.sections = [mask.len(), points.len(), shared_section.len(), uvs.len()];
    let mut out = Vec::new();
    header.write(&mut out)?;
    for section in [&mask, &points, &shared_section, &uvs] {
        out.extend_from_slice(section);
    }
    let mut offset = 0u64;
    out.extend_from_slice(&offset.to_le_bytes());
    for chunk in chunks {
        offset += chunk.len() as u64;
        out.extend_from_slice(&offset.to_le_bytes());
    }
    chunks.iter().for_each(|c| out.extend_from_slice(c));
    let crc = crc32fast::hash(&out);
    out.extend_from_slice(&crc.to_le_bytes());
    Ok(out)
}

fn u32_len(len: usize) -> Result<u32, CodecError> {
    u32::try_from(len).map_err(|_| CodecError::Input(format!("section of {len} bytes")))
}

/// The atlas fingerprint a `.shlm` file's header records (`None` before version 3), and the
/// triangles of the light-map UVs it stores (0: the character's texture UVs), read without
/// parsing the rest: for the readers that pair a file with a character.
pub fn atlas_record(bytes: &[u8]) -> Result<(Option<u32>, usize), CodecError> {
    let header = Header::read(bytes)?;
    Ok((header.atlas, header.uv_triangles))
}

/// A parsed `.shlm` file over its bytes. [`ShlmFile::parse`] validates the header, the
/// checksum, the offset table, the mask, the positions and the shared PCA basis once;
/// [`ShlmFile::decode_frame`] then touches only the chunks its frame needs.
#[derive(Debug)]
pub struct ShlmFile<'a> {
    bytes: &'a [u8],
    header: Header,
    /// The texel index of each filled texel.
    texels: Vec<usize>,
    /// Their neighbours on the grid (sign mode 3 only; empty otherwise).
    grid: Grid,
    positions: Vec<[f32; 3]>,
    /// The light-map UVs the maps were baked on, when not the character's texture UVs.
    layout: Option<UvLayout>,
    /// PCA: the quantised mean, then the components (`T · n²` each); empty otherwise.
    basis: Vec<Vec<f32>>,
    /// PCA under sign mode 3: the components as their steps and integers instead (half the
    /// bytes of f32 for `combine` to stream); `basis` then holds the mean alone.
    int_basis: Vec<IntComponent>,
    /// Where the offset table starts, and the chunk area after it.
    table: usize,
    chunk_area: Range<usize>,
}

impl<'a> ShlmFile<'a> {
    /// Validates `bytes` as a `.shlm` file. Hostile bytes give an error, never a panic, and
    /// no allocation exceeds what the header's limits allow.
    pub fn parse(bytes: &'a [u8]) -> Result<Self, CodecError> {
        let header = Header::read(bytes)?;
        let [mask_len, points_len, shared_len, uvs_len] = header.sections;
        let table_len = (header.frames + 1) * 8;
        let sections = [mask_len, points_len, shared_len, uvs_len, table_len, 4];
        let needed = sections
            .iter()
            .try_fold(header.header_len(), |a, &b| a.checked_add(b));
        let len = bytes.len();
        match needed {
            Some(n) if n <= len => {}
            n => {
                return Err(CodecError::Truncated {
                    what: "sections",
                    needed: n.map_or(u64::MAX, |n| n as u64),
                    len: len as u64,
                });
            }
        }
        check_compressed_sizes(&header)?;
        let (body, stored) = bytes.split_at(len - 4);
        let stored = u32::from_le_bytes([stored[0], stored[1], stored[2], stored[3]]);
        let computed = crc32fast::hash(body);
        if stored != computed {
            return Err(CodecError::Checksum { stored, computed });
        }
        let mask_at = header.header_len();
        let points_at = mask_at + mask_len;
        let shared_at = points_at + points_len;
        let uvs_at = shared_at + shared_len;
        let table = uvs_at + uvs_len;
        let texels = read_mask(&bytes[mask_at..points_at], &header)?;
        let grid = match header.planes.sign {
            SignMode::Uniform => Grid::new(&texels, header.resolution),
            _ => Grid::default(),
        };
        let mut file = ShlmFile {
            bytes,
            header,
            texels,
            grid,
            positions: read_positions(&bytes[points_at..shared_at], header.texels)?,
            layout: match (header.uv_triangles, header.atlas) {
                (0, _) | (_, None) => None,
                (triangles, Some(fingerprint)) => {
                    Some(read_uvs(&bytes[uvs_at..table], triangles, fingerprint)?)
                }
            },
            basis: Vec::new(),
            int_basis: Vec::new(),
            table,
            chunk_area: table + table_len..len - 4,
        };
        file.check_table()?;
        (file.basis, file.int_basis) = file.read_basis(&bytes[shared_at..uvs_at])?;
        file.check_chunks()?;
        Ok(file)
    }

    /// `R`.
    pub fn resolution(&self) -> usize {
        self.header.resolution
    }

    /// SH order `n`.
    pub fn order(&self) -> usize {
        self.header.order
    }

    /// Frames in the clip.
    pub fn frames(&self) -> usize {
        self.header.frames
    }

    /// The `R²` filled flags.
    pub fn filled(&self) -> Vec<bool> {
        let mut filled = vec![false; self.header.resolution * self.header.resolution];
        self.texels.iter().for_each(|&t| filled[t] = true);
        filled
    }

    /// The bind-pose point of each filled texel, in texel order.
    pub fn positions(&self) -> &[[f32; 3]] {
        &self.positions
    }

    /// The light-map UVs the maps were baked on (`--uv generate`); `None` when they lie on
    /// the character's texture UVs.
    pub fn layout(&self) -> Option<&UvLayout> {
        self.layout.as_ref()
    }

    /// `frames × R² × n² × 4`: the raw f32 maps of the whole clip, the ratio's denominator.
    pub fn raw_bytes(&self) -> u64 {
        let h = &self.header;
        (h.frames as u64) * (h.resolution as u64).pow(2) * (h.n2() as u64) * 4
    }

    /// Every frame decoded, in order (`frames` maps of `R² · n²`); refused before any is
    /// decoded when they would not fit the run's memory budget.
    pub fn decode_all(&self) -> Result<Vec<Vec<f32>>, CodecError> {
        let h = &self.header;
        if self.raw_bytes() > MAX_BYTES {
            return Err(CodecError::OverBudget(format!(
                "decoding all {} frames of {}² texels at SH order {} holds {}; a run holds at most {}",
                h.frames,
                h.resolution,
                h.order,
                show_bytes(self.raw_bytes()),
                show_bytes(MAX_BYTES)
            )));
        }
        (0..h.frames)
            .map(|k| {
                let mut map = vec![0.0f32; h.resolution * h.resolution * h.n2()];
                self.decode_frame(k, &mut map).map(|()| map)
            })
            .collect()
    }

    /// The texel index of each filled texel, ascending: what each of [`Self::decode_rows`]'s
    /// rows stands for.
    pub fn texels(&self) -> &[usize] {
        &self.texels
    }

    /// Decodes frame `k`'s filled texels only (`n²` values each, in [`Self::texels`] order):
    /// a frame without the `R²` map, for readers that need only some texels.
    pub fn decode_rows(&self, k: usize) -> Result<Vec<f32>, CodecError> {
        let h = &self.header;
        if k >= h.frames {
            return Err(CodecError::FrameOutOfRange {
                index: k,
                frames: h.frames,
            });
        }
        let compact = self.decode_compact(k)?;
        if compact.iter().any(|x| !x.is_finite()) {
            return Err(CodecError::Invalid {
                what: "frame",
                message: format!("frame {k} decodes to a non-finite value"),
            });
        }
        Ok(compact)
    }

    /// Decodes frame `k` into `out` (`R² · n²`, texel-major, zero where not filled).
    pub fn decode_frame(&self, k: usize, out: &mut [f32]) -> Result<(), CodecError> {
        let h = &self.header;
        let n2 = h.n2();
        let expected = h.resolution * h.resolution * n2;
        if out.len() != expected {
            return Err(CodecError::SizeMismatch {
                what: "output frame",
                expected: expected as u64,
                got: out.len() as u64,
            });
        }
        let compact = self.decode_rows(k)?;
        out.fill(0.0);
        for (&t, values) in self.texels.iter().zip(compact.chunks_exact(n2)) {
            out[t * n2..(t + 1) * n2].copy_from_slice(values);
        }
        Ok(())
    }

    /// The codec and its parameters, for `aprt inspect`.
    pub fn describe(&self) -> String {
        let h = &self.header;
        let kind = match h.kind {
            StoredKind::Frames => "independent frames".to_string(),
            StoredKind::Keyframes { interval } => {
                format!("keyframes every {interval}, lerp between")
            }
            StoredKind::Pca { components } => format!("PCA over frames, {components} components"),
        };
        let p = &h.planes;
        let sign = match p.sign {
            SignMode::OffsetScale => "offset per map",
            SignMode::SignPlane => "sign plane",
            SignMode::Band0Ratio => "ratios to band 0",
            SignMode::Uniform => "uniform step per map, MED-predicted over the grid",
        };
        let group = match p.grouping {
            Grouping::Texel => "one exponent per texel",
            Grouping::Triples => "one exponent per 3 coefficients",
        };
        let delta = if p.spatial_delta {
            ", spatial delta"
        } else {
            ""
        };
        let quantiser = match p.sign {
            SignMode::Uniform => format!("{sign} (target 2^-{})", p.mantissa_bits),
            _ => format!(
                "shared-exponent {}-bit mantissas, {sign}, {group}{delta}",
                p.mantissa_bits
            ),
        };
        format!(
            "shlm v{}: {kind}; {quantiser}; zstd; \
             {} frames of {}² texels ({} filled) × {} coefficients",
            // The file's own version (parse checked that the bytes hold one), not the writer's.
            u32::from_le_bytes([self.bytes[8], self.bytes[9], self.bytes[10], self.bytes[11]]),
            h.frames,
            h.resolution,
            h.texels,
            h.n2()
        )
    }

    /// Frame `k`'s filled texels, `T · n²` values.
    fn decode_compact(&self, k: usize) -> Result<Vec<f32>, CodecError> {
        let h = &self.header;
        match h.kind {
            StoredKind::Frames => self.decode_planes_chunk(k),
            StoredKind::Keyframes { interval } => {
                let before = k - k % interval;
                if before == k {
                    return self.decode_planes_chunk(k);
                }
                let after = (before + interval).min(h.frames - 1);
                let (a, b) = (
                    self.decode_planes_chunk(before)?,
                    self.decode_planes_chunk(after)?,
                );
                let w = (k - before) as f32 / (after - before) as f32;
                Ok(a.iter().zip(&b).map(|(a, b)| a + (b - a) * w).collect())
            }
            StoredKind::Pca { .. } => Ok(self.combine(k)),
        }
    }

    /// PCA: `mean + Σ_j w_j U_j`, a block at a time so the block stays in L1 while every
    /// component streams through it once.
    fn combine(&self, k: usize) -> Vec<f32> {
        const BLOCK: usize = 2048;
        let weights: Vec<f32> = self.weights(k).collect();
        let mut out = self.basis[0].clone();
        if !self.int_basis.is_empty() {
            // `w_j · step_jc` once per frame, repeated over a block of texels so the inner
            // loop is a flat multiply-add of contiguous slices (vectorised).
            let n2 = self.header.n2().max(1);
            let block_len = n2 * 128;
            let coefs: Vec<Vec<f32>> = (weights.iter().zip(&self.int_basis))
                .map(|(w, comp)| {
                    let texel: Vec<f32> = comp.steps.iter().map(|s| w * s).collect();
                    texel.iter().copied().cycle().take(block_len).collect()
                })
                .collect();
            for (b, block) in out.chunks_mut(block_len).enumerate() {
                for (coef, comp) in coefs.iter().zip(&self.int_basis) {
                    let part = &comp.q[b * block_len..b * block_len + block.len()];
                    for ((o, &q), &c) in block.iter_mut().zip(part).zip(coef) {
                        *o += c * f32::from(q);
                    }
                }
            }
            return out;
        }
        for (b, block) in out.chunks_mut(BLOCK).enumerate() {
            for (w, component) in weights.iter().zip(&self.basis[1..]) {
                let part = &component[b * BLOCK..b * BLOCK + block.len()];
                block.iter_mut().zip(part).for_each(|(o, c)| *o += w * c);
            }
        }
        out
    }

    /// Decompresses and dequantises frame `k`'s plane set.
    fn decode_planes_chunk(&self, k: usize) -> Result<Vec<f32>, CodecError> {
        let h = &self.header;
        let mut planes = decompress_chunk(self.chunk(k), plane_bytes(h)?, "frame chunk")?;
        dequantise(&mut planes, h, &self.grid, "frame chunk")
    }

    /// Frame `k`'s PCA weights (chunk lengths were checked at parse).
    fn weights(&self, k: usize) -> impl Iterator<Item = f32> + '_ {
        self.chunk(k)
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    /// Frame `k`'s chunk (the table was checked at parse).
    fn chunk(&self, k: usize) -> &'a [u8] {
        let (start, end) = (self.offset(k), self.offset(k + 1));
        &self.bytes[self.chunk_area.start + start..self.chunk_area.start + end]
    }

    fn offset(&self, k: usize) -> usize {
        let b = &self.bytes[self.table + 8 * k..self.table + 8 * k + 8];
        let mut word = [0u8; 8];
        word.copy_from_slice(b);
        usize::try_from(u64::from_le_bytes(word)).unwrap_or(usize::MAX)
    }

    /// The offset table starts at 0, never goes backwards, and ends at the chunk area's size.
    fn check_table(&self) -> Result<(), CodecError> {
        let frames = self.header.frames;
        let area = self.chunk_area.len();
        let offsets: Vec<usize> = (0..=frames).map(|k| self.offset(k)).collect();
        let ordered = offsets.windows(2).all(|w| w[0] <= w[1]);
        if offsets[0] != 0 || !ordered || offsets[frames] != area {
            return Err(CodecError::Invalid {
                what: "frame offset table",
                message: format!("offsets must rise from 0 to the chunk area's {area} bytes"),
            });
        }
        Ok(())
    }

    /// Reads the PCA mean and components, or checks the section is empty for other kinds.
    fn read_basis(&self, section: &[u8]) -> Result<Basis, CodecError> {
        let StoredKind::Pca { components } = self.header.kind else {
            return match section.is_empty() {
                true => Ok((Vec::new(), Vec::new())),
                false => Err(size("shared section", 0, section.len())),
            };
        };
        let count = components + 1;
        let word = |i: usize| -> Result<usize, CodecError> {
            let b = section.get(4 * i..4 * i + 4).ok_or(size(
                "shared section",
                4 * i + 4,
                section.len(),
            ))?;
            Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize)
        };
        if word(0)? != count {
            return Err(size("shared section count", count, word(0)?));
        }
        let mut at = 4 * (count + 1);
        let mut basis = Vec::with_capacity(count);
        let mut int_basis = Vec::new();
        for i in 0..count {
            let end = at.checked_add(word(i + 1)?).filter(|&e| e <= section.len());
            let end = end.ok_or(size("shared section", at, section.len()))?;
            if i > 0 && self.header.planes.sign == SignMode::Uniform {
                int_basis.push(read_int_component(
                    &section[at..end],
                    &self.header,
                    &self.grid,
                )?);
                at = end;
                continue;
            }
            let values =
                decode_plane_set(&section[at..end], &self.header, &self.grid, "PCA basis")?;
            if values.iter().any(|x| !x.is_finite()) {
                return Err(CodecError::Invalid {
                    what: "PCA basis",
                    message: "non-finite".into(),
                });
            }
            basis.push(values);
            at = end;
        }
        if at != section.len() {
            return Err(size("shared section", at, section.len()));
        }
        Ok((basis, int_basis))
    }

    /// Chunk sizes the kind implies: `4k` bytes of finite weights for PCA, nothing between
    /// keyframes, and enough bytes for zstd to give a plane set otherwise.
    fn check_chunks(&self) -> Result<(), CodecError> {
        let h = &self.header;
        for k in 0..h.frames {
            let len = self.chunk(k).len();
            match h.kind {
                StoredKind::Pca { components } if len != 4 * components => {
                    return Err(size("PCA weights chunk", 4 * components, len));
                }
                StoredKind::Pca { .. } if self.weights(k).any(|w| !w.is_finite()) => {
                    return Err(CodecError::Invalid {
                        what: "PCA weights chunk",
                        message: format!("frame {k} has a non-finite weight"),
                    });
                }
                StoredKind::Keyframes { interval } if !is_keyframe(k, interval, h.frames) => {
                    if len != 0 {
                        return Err(size("in-between frame chunk", 0, len));
                    }
                }
                StoredKind::Pca { .. } => {}
                StoredKind::Frames | StoredKind::Keyframes { .. } => {
                    zstd_can_hold("frame chunk", len, plane_bytes(h)?)?;
                }
            }
        }
        Ok(())
    }
}

/// The mean and the components as f32, and the components as integers (sign mode 3).
type Basis = (Vec<Vec<f32>>, Vec<IntComponent>);

/// A PCA component under sign mode 3: `n2` steps and the integers `q` (texel-major).
#[derive(Debug)]
struct IntComponent {
    steps: Vec<f32>,
    q: Vec<i16>,
}

/// Most bytes zstd decompresses per byte of input: a frame's blocks hold at most 128 KiB each,
/// and the smallest block (an RLE block) is 4 bytes. Real sections compress 3–60:1.
const ZSTD_MAX_RATIO: usize = 32 * 1024;

/// Refuses a compressed section of `len` bytes that cannot decompress to the `expected` bytes
/// the header implies, before anything is decompressed or allocated.
fn zstd_can_hold(what: &str, len: usize, expected: usize) -> Result<(), CodecError> {
    if len.saturating_mul(ZSTD_MAX_RATIO) >= expected {
        return Ok(());
    }
    Err(CodecError::Header(format!(
        "the {len}-byte {what} cannot hold the {expected} bytes the header implies (zstd gives at most {ZSTD_MAX_RATIO} bytes per byte)"
    )))
}

/// The mask, positions and PCA sections against the bytes the header says they decompress to.
fn check_compressed_sizes(h: &Header) -> Result<(), CodecError> {
    let [mask, points, shared, uvs] = h.sections;
    let r2 = h.resolution * h.resolution;
    zstd_can_hold("light-map UVs", uvs, h.uv_triangles * 24)?;
    zstd_can_hold("filled mask", mask, r2.div_ceil(8))?;
    zstd_can_hold("positions section", points, h.texels * 12)?;
    if let StoredKind::Pca { components } = h.kind {
        let basis = plane_bytes(h)?.saturating_mul(components + 1);
        zstd_can_hold("shared PCA section", shared, basis)?;
    }
    Ok(())
}

/// Reads one sign-mode-3 component: every `q · step` must be finite.
fn read_int_component(bytes: &[u8], h: &Header, grid: &Grid) -> Result<IntComponent, CodecError> {
    let what = "PCA basis";
    let planes = decompress_exact(bytes, plane_bytes(h)?, what)?;
    let (steps, q) = uniform::decode_ints(&planes, h.n2(), grid)
        .map_err(|message| CodecError::Invalid { what, message })?;
    let n2 = h.n2().max(1);
    let finite = (0..n2).all(|c| {
        let max = q.iter().skip(c).step_by(n2).map(|q| q.unsigned_abs()).max();
        (f32::from(max.unwrap_or(0)) * steps[c]).is_finite()
    });
    if !finite {
        return Err(CodecError::Invalid {
            what,
            message: "non-finite".into(),
        });
    }
    Ok(IntComponent { steps, q })
}

fn size(what: &'static str, expected: usize, got: usize) -> CodecError {
    CodecError::SizeMismatch {
        what,
        expected: expected as u64,
        got: got as u64,
    }
}

/// Decompresses (growing with the data, for the shared section read at parse) and
/// dequantises one plane set of the header's `T` texels.
fn decode_plane_set(
    bytes: &[u8],
    h: &Header,
    grid: &Grid,
    what: &'static str,
) -> Result<Vec<f32>, CodecError> {
    let mut planes = decompress_exact(bytes, plane_bytes(h)?, what)?;
    dequantise(&mut planes, h, grid, what)
}

/// The bytes of one plane set.
fn plane_bytes(h: &Header) -> Result<usize, CodecError> {
    (h.planes.plane_bytes(h.texels, h.n2()))
        .ok_or_else(|| CodecError::Header("plane set size overflows".into()))
}

/// The values of one decompressed plane set.
fn dequantise(
    planes: &mut [u8],
    h: &Header,
    grid: &Grid,
    what: &'static str,
) -> Result<Vec<f32>, CodecError> {
    let n2 = h.n2();
    let mut values = vec![0f32; h.texels * n2];
    decode_planes_on(planes, n2, &h.planes, grid, &mut values)
        .map_err(|message| CodecError::Invalid { what, message })?;
    Ok(values)
}

/// The bit-packed mask: exactly `T` bits set, none past `R²`.
fn read_mask(section: &[u8], h: &Header) -> Result<Vec<usize>, CodecError> {
    let count = h.resolution * h.resolution;
    let mask = decompress_exact(section, count.div_ceil(8), "filled mask")?;
    let texels: Vec<usize> = (0..mask.len() * 8)
        .filter(|&t| mask[t / 8] & (1 << (t % 8)) != 0)
        .collect();
    if texels.len() != h.texels || texels.last().is_some_and(|&t| t >= count) {
        return Err(CodecError::Invalid {
            what: "filled mask",
            message: format!(
                "{} bits set (header: {}), or bits past R²",
                texels.len(),
                h.texels
            ),
        });
    }
    Ok(texels)
}

/// `T` finite points.
fn read_positions(section: &[u8], texels: usize) -> Result<Vec<[f32; 3]>, CodecError> {
    let bytes = decompress_exact(section, texels * 12, "positions")?;
    let floats: Vec<f32> = bytes
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    if floats.iter().any(|x| !x.is_finite()) {
        return Err(CodecError::Invalid {
            what: "positions",
            message: "non-finite".into(),
        });
    }
    Ok(floats.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect())
}
