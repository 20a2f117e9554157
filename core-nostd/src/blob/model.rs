//! Opening a model: decode the header, validate every dimension, offset and length, and
//! verify every section's checksum and values once, so evaluation can trust the layout.

use super::format::{
    Basis, Encoding, Frame, Header, MAGIC, MAX_BONES, MAX_COEF_DIMS, MAX_HEADER_LEN, MAX_JOINTS,
    MAX_LIT, MAX_POSE_DIMS, MAX_SECTIONS, MAX_VERTICES, PREAMBLE_LEN, SECTION_ALIGN, SectionEntry,
    SectionKind, VERSION, VERTEX_BLOCK, padded_vertices,
};
use super::source::{BlobSource, SliceSource, for_each_chunk};
use super::{Dim, Error};
use crate::sh::{MAX_ORDER, coeff_count};

/// Where one validated section lives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Section {
    /// Byte offset in the blob.
    pub offset: u64,
    /// Byte length.
    pub len: u64,
    /// Element encoding.
    pub encoding: Encoding,
}

/// A validated model: its dimensions and where its arrays are. Small and `Copy`; the arrays
/// stay in the blob (or its source) and are streamed by the evaluator.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Model {
    pub(crate) order: usize,
    pub(crate) vertices: usize,
    pub(crate) joints: usize,
    pub(crate) pose_dims: usize,
    pub(crate) coef_dims: usize,
    pub(crate) basis: Basis,
    pub(crate) frame: Frame,
    pub(crate) alpha: f32,
    pub(crate) pose_mean: Section,
    pub(crate) pose_projection: Section,
    /// Stored basis: the `n² × (1 + k_a) × k_v` weights; identity basis: unused.
    pub(crate) weights: Option<Section>,
    /// Per-vertex rows: the vertex basis (stored) or the vertex weights (identity).
    pub(crate) rows: Section,
}

/// Reads and checks the preamble and header of a resident blob.
pub fn read_header(blob: &[u8]) -> Result<Header, Error> {
    header_from(&mut SliceSource(blob), &mut [0u8; MAX_HEADER_LEN as usize]).map(|(h, _)| h)
}

/// Returns the header and the byte offset where the header ends.
fn header_from<S: BlobSource + ?Sized>(
    src: &mut S,
    buf: &mut [u8; MAX_HEADER_LEN as usize],
) -> Result<(Header, u64), Error> {
    let mut pre = [0u8; PREAMBLE_LEN];
    if src.len() < PREAMBLE_LEN as u64 {
        return Err(Error::Truncated {
            needed: PREAMBLE_LEN as u64,
        });
    }
    src.read_at(0, &mut pre).map_err(|_| Error::Source)?;
    let word = |i: usize| u32::from_le_bytes([pre[i], pre[i + 1], pre[i + 2], pre[i + 3]]);
    if pre[..8] != MAGIC {
        return Err(Error::BadMagic);
    }
    let (version, len, crc) = (word(8), word(12), word(16));
    if version != VERSION {
        return Err(Error::UnsupportedVersion { found: version });
    }
    if len > MAX_HEADER_LEN {
        return Err(Error::HeaderTooLarge { len });
    }
    let end = PREAMBLE_LEN as u64 + len as u64;
    if src.len() < end {
        return Err(Error::Truncated { needed: end });
    }
    let bytes = &mut buf[..len as usize];
    src.read_at(PREAMBLE_LEN as u64, bytes)
        .map_err(|_| Error::Source)?;
    if super::crc32(bytes) != crc {
        return Err(Error::HeaderChecksum);
    }
    let (header, rest) =
        postcard::take_from_bytes::<Header>(bytes).map_err(|_| Error::HeaderMalformed)?;
    if !rest.is_empty() {
        return Err(Error::TrailingBytes {
            extra: rest.len() as u64,
        });
    }
    // NaN never leaves the trainer, and a NaN α would make the model unequal to itself.
    if !header.alpha.is_finite() {
        return Err(Error::HeaderMalformed);
    }
    Ok((header, end))
}

fn dim(what: Dim, value: u64, min: u64, max: u64) -> Result<usize, Error> {
    if value < min || value > max {
        return Err(Error::BadDimension { what, value });
    }
    usize::try_from(value).map_err(|_| Error::BadDimension { what, value })
}

fn product(factors: &[usize]) -> Result<u64, Error> {
    factors
        .iter()
        .try_fold(1u64, |acc, &f| acc.checked_mul(f as u64))
        .ok_or(Error::LengthOverflow)
}

impl Model {
    /// Opens a resident blob, validating it completely. Works in place: no buffer needed.
    pub fn parse(blob: &[u8]) -> Result<Model, Error> {
        Model::open(&mut SliceSource(blob), &mut [])
    }

    /// Opens a blob from any source, validating it completely: header, dimensions, section
    /// table, checksums and finiteness of every value. Section bytes are streamed through
    /// `scratch`; any size of at least 4 bytes works (larger reads fewer times). A resident
    /// source needs no scratch.
    pub fn open<S: BlobSource + ?Sized>(src: &mut S, scratch: &mut [u8]) -> Result<Model, Error> {
        let (h, header_end) = header_from(src, &mut [0u8; MAX_HEADER_LEN as usize])?;
        let order = dim(Dim::Order, h.order as u64, 1, MAX_ORDER as u64)?;
        let vertices = dim(Dim::Vertices, h.vertices as u64, 1, MAX_VERTICES as u64)?;
        let joints = dim(Dim::Joints, h.joints as u64, 1, MAX_JOINTS as u64)?;
        let pose_dims = dim(
            Dim::PoseDims,
            h.pose_dims as u64,
            0,
            MAX_POSE_DIMS.min(joints) as u64,
        )?;
        let coef_dims = match h.basis {
            Basis::Stored => dim(Dim::CoefDims, h.coef_dims as u64, 1, MAX_COEF_DIMS as u64)?,
            Basis::Identity => dim(
                Dim::CoefDims,
                h.coef_dims as u64,
                vertices as u64,
                vertices as u64,
            )?,
        };
        let n2 = coeff_count(order);
        let padded = padded_vertices(vertices);
        let lead = match h.frame {
            Frame::World => 0,
            Frame::Bones { count } => {
                let bones = dim(Dim::Bones, count as u64, 1, MAX_BONES as u64)?;
                let width = match h.basis {
                    Basis::Stored => coef_dims,
                    Basis::Identity => n2 * (1 + pose_dims),
                };
                if bones * width > MAX_LIT {
                    return Err(Error::BadDimension {
                        what: Dim::Bones,
                        value: bones as u64,
                    });
                }
                1
            }
        };
        let expected_elems = |kind: SectionKind| -> Option<Result<u64, Error>> {
            Some(match (kind, h.basis) {
                (SectionKind::PoseMean, _) => product(&[joints]),
                (SectionKind::PoseProjection, _) => product(&[pose_dims, joints]),
                (SectionKind::Weights, Basis::Stored) => product(&[n2, 1 + pose_dims, coef_dims]),
                (SectionKind::VertexBasis, Basis::Stored) => product(&[padded, lead + coef_dims]),
                (SectionKind::VertexWeights, Basis::Identity) => {
                    product(&[padded, lead + n2 * (1 + pose_dims)])
                }
                _ => return None,
            })
        };

        let mut found: [Option<Section>; 6] = [None; 6];
        let mut end_of_data = header_end;
        check_no_overlap(&h.sections, header_end, src.len())?;
        for e in &h.sections {
            end_of_data = end_of_data.max(e.offset + e.len); // no overflow: checked above
            let Some(kind) = SectionKind::from_tag(e.kind) else {
                if e.required {
                    return Err(Error::UnknownRequiredSection { kind: e.kind });
                }
                // An optional section from a newer writer, or metadata for tools.
                check_crc(src, e, scratch)?;
                continue;
            };
            let Some(elems) = expected_elems(kind) else {
                check_crc(src, e, scratch)?; // a known section that this basis does not use
                continue;
            };
            let encoding = Encoding::from_tag(e.encoding)
                .filter(|enc| *enc == Encoding::F32 || kind.allows_f16())
                .ok_or(Error::BadEncoding { kind: e.kind })?;
            let expected = elems?
                .checked_mul(encoding.size() as u64)
                .ok_or(Error::LengthOverflow)?;
            if e.len != expected {
                return Err(Error::SectionLength {
                    kind: e.kind,
                    expected,
                    found: e.len,
                });
            }
            let slot = &mut found[kind as usize];
            if slot.is_some() {
                return Err(Error::DuplicateSection { kind: e.kind });
            }
            let section = Section {
                offset: e.offset,
                len: e.len,
                encoding,
            };
            verify(src, e, section, scratch)?;
            *slot = Some(section);
        }
        if src.len() > end_of_data {
            return Err(Error::TrailingBytes {
                extra: src.len() - end_of_data,
            });
        }
        let need = |kind: SectionKind| found[kind as usize].ok_or(Error::MissingSection { kind });
        let (weights, rows) = match h.basis {
            Basis::Stored => (
                Some(need(SectionKind::Weights)?),
                need(SectionKind::VertexBasis)?,
            ),
            Basis::Identity => (None, need(SectionKind::VertexWeights)?),
        };
        let model = Model {
            order,
            vertices,
            joints,
            pose_dims,
            coef_dims,
            basis: h.basis,
            frame: h.frame,
            alpha: h.alpha,
            pose_mean: need(SectionKind::PoseMean)?,
            pose_projection: need(SectionKind::PoseProjection)?,
            weights,
            rows,
        };
        model.verify_bones(src, scratch)?;
        Ok(model)
    }

    /// Checks every block's bone row: integers below the bone count.
    fn verify_bones<S: BlobSource + ?Sized>(
        &self,
        src: &mut S,
        scratch: &mut [u8],
    ) -> Result<(), Error> {
        let Frame::Bones { count } = self.frame else {
            return Ok(());
        };
        let size = self.rows.encoding.size();
        let blocks = padded_vertices(self.vertices) / VERTEX_BLOCK;
        let mut ok = true;
        let mut check = |v: f32| ok &= v >= 0.0 && v < count as f32 && v == (v as u32) as f32;
        for b in 0..blocks {
            let offset = self.rows.offset + (b * self.block_bytes()) as u64;
            // Item by item, so any scratch that holds one value will do, as `open` promises.
            for_each_chunk(src, offset, size, VERTEX_BLOCK, scratch, |_, bytes| {
                match self.rows.encoding {
                    Encoding::F32 => bytes
                        .as_chunks::<4>()
                        .0
                        .iter()
                        .for_each(|x| check(f32::from_le_bytes(*x))),
                    Encoding::F16 => bytes
                        .as_chunks::<2>()
                        .0
                        .iter()
                        .for_each(|x| check(half::f16::from_le_bytes(*x).to_f32())),
                }
                Ok(())
            })?;
        }
        if ok { Ok(()) } else { Err(Error::BadBoneIndex) }
    }

    /// The frame transfer is expressed in.
    pub fn frame(&self) -> Frame {
        self.frame
    }

    /// Extra leading rows per block: 1 (the bone indices) for bone-frame models, else 0.
    pub(crate) fn lead_rows(&self) -> usize {
        match self.frame {
            Frame::World => 0,
            Frame::Bones { .. } => 1,
        }
    }

    /// SH order n.
    pub fn order(&self) -> usize {
        self.order
    }
    /// Vertex count v.
    pub fn vertices(&self) -> usize {
        self.vertices
    }
    /// Joint angles per pose a.
    pub fn joints(&self) -> usize {
        self.joints
    }
    /// Pose dimensions k_a.
    pub fn pose_dims(&self) -> usize {
        self.pose_dims
    }
    /// Vertex-basis dimensions k_v (`vertices` for the identity basis).
    pub fn coef_dims(&self) -> usize {
        self.coef_dims
    }
    /// Vertex side representation.
    pub fn basis(&self) -> Basis {
        self.basis
    }
    /// The fit's Tikhonov parameter.
    pub fn alpha(&self) -> f32 {
        self.alpha
    }

    /// Values per streamed vertex row: k_v (stored basis) or n²(1 + k_a) (identity basis).
    pub fn row_width(&self) -> usize {
        match self.basis {
            Basis::Stored => self.coef_dims,
            Basis::Identity => coeff_count(self.order) * (1 + self.pose_dims),
        }
    }

    /// Bytes of one streamed block of [`VERTEX_BLOCK`] vertex rows, the unit of streaming.
    pub fn block_bytes(&self) -> usize {
        VERTEX_BLOCK * (self.lead_rows() + self.row_width()) * self.rows.encoding.size()
    }
}

/// Sections must lie after the header, inside the blob, aligned, and not share bytes.
fn check_no_overlap(
    sections: &heapless::Vec<SectionEntry, MAX_SECTIONS>,
    header_end: u64,
    len: u64,
) -> Result<(), Error> {
    for (i, e) in sections.iter().enumerate() {
        let end = e
            .offset
            .checked_add(e.len)
            .ok_or(Error::SectionOutOfRange { kind: e.kind })?;
        if e.offset < header_end || end > len {
            return Err(Error::SectionOutOfRange { kind: e.kind });
        }
        if e.offset % SECTION_ALIGN != 0 {
            return Err(Error::SectionMisaligned { kind: e.kind });
        }
        for other in &sections[..i] {
            if e.offset < other.offset + other.len && other.offset < end {
                return Err(Error::SectionOverlap { kind: e.kind });
            }
        }
    }
    Ok(())
}

/// Checks the CRC of a section the reader does not interpret, so a flipped bit anywhere in a
/// blob is caught, whatever the section.
fn check_crc<S: BlobSource + ?Sized>(
    src: &mut S,
    e: &SectionEntry,
    scratch: &mut [u8],
) -> Result<(), Error> {
    let len = usize::try_from(e.len).map_err(|_| Error::LengthOverflow)?;
    let mut hasher = crc32fast::Hasher::new();
    for_each_chunk(src, e.offset, 1, len, scratch, |_, bytes| {
        hasher.update(bytes);
        Ok(())
    })?;
    if hasher.finalize() != e.crc32 {
        return Err(Error::ChecksumMismatch { kind: e.kind });
    }
    Ok(())
}

/// Checks a section's CRC and that every value is finite, streaming through `scratch`.
fn verify<S: BlobSource + ?Sized>(
    src: &mut S,
    e: &SectionEntry,
    s: Section,
    scratch: &mut [u8],
) -> Result<(), Error> {
    let size = s.encoding.size();
    let count = usize::try_from(s.len).map_err(|_| Error::LengthOverflow)? / size;
    // Stream in chunks of whole elements: 4-byte words hold 1 f32 or 2 f16.
    let mut hasher = crc32fast::Hasher::new();
    let mut finite = true;
    for_each_chunk(src, s.offset, size, count, scratch, |_, bytes| {
        hasher.update(bytes);
        finite &= match s.encoding {
            Encoding::F32 => bytes
                .as_chunks::<4>()
                .0
                .iter()
                .all(|w| f32::from_le_bytes(*w).is_finite()),
            Encoding::F16 => bytes
                .as_chunks::<2>()
                .0
                .iter()
                .all(|w| half::f16::from_le_bytes(*w).is_finite()),
        };
        Ok(())
    })?;
    if hasher.finalize() != e.crc32 {
        return Err(Error::ChecksumMismatch { kind: e.kind });
    }
    if !finite {
        return Err(Error::NonFinite { kind: e.kind });
    }
    Ok(())
}
