//! Opening a model: decode the header, validate every dimension, offset and length, and
//! verify every section's checksum and values once, so evaluation can trust the layout.

use super::atlas::{AtlasCheck, AtlasFailure, atlas_len, trailer_len};
use super::format::{
    Basis, Encoding, Frame, MAX_BONES, MAX_COEF_DIMS, MAX_LIT, MAX_POSE_DIMS, MAX_POSE_LEN,
    MAX_SECTIONS, MAX_VERTICES, SECTION_ALIGN, SectionEntry, SectionKind, VERTEX_BLOCK,
    padded_vertices,
};
use super::header::decode_header;
use super::info::{ModelInfo, Span};
use super::names::NamesCheck;
use super::{Dim, Error, Reader};
use crate::irradiance_rig::{RigCheck, RigFailure};
use crate::proxies::ProxyCheck;
use crate::sh::{MAX_ORDER, coeff_count};

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

/// A blob's header and section table, read and checked by [`ModelInfo::layout`].
pub(crate) struct Layout {
    /// The dimensions and spans, not yet verified against the sections' bytes.
    pub(crate) info: ModelInfo,
    sections: heapless::Vec<SectionEntry, MAX_SECTIONS>,
    header_end: u64,
    found: [Option<Span>; SectionKind::KNOWN_COUNT],
}

impl Layout {
    /// The rest of [`ModelInfo::open`], on the blob the layout was read from: every
    /// section's checksum and values, the bone indices and the pose bounds.
    pub(crate) fn verify<R: Reader>(self, r: &mut R) -> Result<ModelInfo, Error> {
        let info = self.info;
        let sizes = (info.vertices, info.pose_len, info.frame.bones());
        verify_sections(r, (&self.sections, self.header_end), &self.found, sizes)?;
        info.verify_bones(r)?;
        info.verify_bounds(r)?;
        Ok(info)
    }
}

impl ModelInfo {
    /// Validates a whole blob: header, dimensions, section table, checksums, finiteness of
    /// every value, bone indices and angle names. A streaming reader's buffer must hold at
    /// least 4 bytes.
    pub(crate) fn open<R: Reader>(r: &mut R) -> Result<ModelInfo, Error> {
        Self::layout(r)?.verify(r)
    }

    /// What [`open`](Self::open) checks before it reads a section's bytes: the header, the
    /// dimensions and where each section lies (the few bytes of the pose features are read
    /// and checked), so the scratch a streamed model needs is known without streaming the
    /// blob. Its info is not to be trusted until [`Layout::verify`] has passed.
    pub(crate) fn layout<R: Reader>(r: &mut R) -> Result<Layout, Error> {
        let decoded = decode_header(r)?;
        let h = &decoded.header;
        let order = dim(Dim::Order, h.order as u64, 1, MAX_ORDER as u64)?;
        let vertices = dim(Dim::Vertices, h.vertices as u64, 1, MAX_VERTICES as u64)?;
        let pose_len = dim(Dim::PoseLen, h.pose_len as u64, 1, MAX_POSE_LEN as u64)?;
        // The dimensions are checked before the section table, so at first against the most
        // features the blob could have (each entry adds at most its cosine), and exactly once
        // the pose-features section is read.
        let cosines = h
            .sections
            .iter()
            .any(|e| e.kind == SectionKind::PoseFeatures.tag());
        let most_features = pose_len * (1 + usize::from(cosines));
        let pose_dims_in = |features: usize| {
            let most = MAX_POSE_DIMS.min(features) as u64;
            dim(Dim::PoseDims, h.pose_dims as u64, 0, most)
        };
        let pose_dims = pose_dims_in(most_features)?;
        let coef_dims = coef_dims(h.basis, h.coef_dims, vertices)?;
        let n2 = coeff_count(order);
        let padded = padded_vertices(vertices);
        let row_width = match h.basis {
            Basis::Stored => coef_dims,
            Basis::Identity => n2 * (1 + pose_dims),
        };
        let lead = lead_rows(h.frame, row_width)?;
        check_no_overlap(&h.sections, decoded.end, r.len())?;
        let (feature_len, pose_features) = pose_features(r, &h.sections, pose_len)?;
        pose_dims_in(feature_len)?;
        // Elements of each array section this basis uses; `None` for the others.
        let expected_elems = |kind: SectionKind| -> Option<Result<u64, Error>> {
            Some(match (kind, h.basis) {
                (SectionKind::RowScales, _) => product(&[row_width]),
                (SectionKind::PoseMean, _) => product(&[feature_len]),
                (SectionKind::PoseProjection, _) => product(&[pose_dims, feature_len]),
                (SectionKind::PoseBounds, _) => product(&[4, pose_len]),
                (SectionKind::Weights, Basis::Stored) => product(&[n2, 1 + pose_dims, coef_dims]),
                (SectionKind::VertexBasis, Basis::Stored) => product(&[padded, lead + row_width]),
                (SectionKind::VertexWeights, Basis::Identity) => {
                    product(&[padded, lead + row_width])
                }
                _ => return None,
            })
        };

        let found = locate_sections(&h.sections, &expected_elems)?;
        let get = |kind: SectionKind| kind.known_index().and_then(|i| found[i]);
        let need = |kind: SectionKind| get(kind).ok_or(Error::MissingSection { section: kind });
        let (weights, rows) = match h.basis {
            Basis::Stored => (
                Some(need(SectionKind::Weights)?),
                need(SectionKind::VertexBasis)?,
            ),
            Basis::Identity => (None, need(SectionKind::VertexWeights)?),
        };
        // Scaled bytes need their scales; other encodings ignore a scales section.
        let row_scales = match rows.encoding {
            Encoding::I8 => Some(need(SectionKind::RowScales)?),
            Encoding::F32 | Encoding::F16 => None,
        };
        let info = ModelInfo {
            id: decoded.crc,
            order,
            vertices,
            pose_len,
            feature_len,
            pose_dims,
            coef_dims,
            basis: h.basis,
            frame: h.frame,
            alpha: h.alpha,
            pose_mean: need(SectionKind::PoseMean)?,
            pose_projection: need(SectionKind::PoseProjection)?,
            weights,
            rows,
            row_scales,
            angle_names: get(SectionKind::AngleNames),
            pose_bounds: get(SectionKind::PoseBounds),
            pose_features,
            irradiance_rig: get(SectionKind::IrradianceRig),
            texel_atlas: get(SectionKind::TexelAtlas),
            proxies: get(SectionKind::Proxies),
        };
        Ok(Layout {
            info,
            sections: decoded.header.sections,
            header_end: decoded.end,
            found,
        })
    }

    /// Checks every block's bone row: integers below the bone count.
    fn verify_bones<R: Reader>(&self, r: &mut R) -> Result<(), Error> {
        let Frame::Bones { count } = self.frame else {
            return Ok(());
        };
        let size = self.rows.encoding.size();
        let blocks = padded_vertices(self.vertices) / VERTEX_BLOCK;
        let mut ok = true;
        let mut check = |v: f32| ok &= v >= 0.0 && v < count as f32 && v == (v as u32) as f32;
        for b in 0..blocks {
            let offset = self.rows.offset + (b * self.block_bytes()) as u64;
            // Item by item, so any scratch that holds one value will do.
            r.chunks(offset, size, VERTEX_BLOCK, |_, bytes| {
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
                    Encoding::I8 => bytes.iter().for_each(|&b| check(f32::from(b))),
                }
                Ok(())
            })?;
        }
        if ok { Ok(()) } else { Err(Error::BadBoneIndex) }
    }
}

/// k_v: 1..=[`MAX_COEF_DIMS`] for a stored basis, the vertex count for the identity basis.
fn coef_dims(basis: Basis, coef_dims: u32, vertices: usize) -> Result<usize, Error> {
    let (lo, hi) = match basis {
        Basis::Stored => (1, MAX_COEF_DIMS as u64),
        Basis::Identity => (vertices as u64, vertices as u64),
    };
    dim(Dim::CoefDims, coef_dims as u64, lo, hi)
}

/// The lead rows of a block in `frame` (1, the bone indices, for bone frames), once the bone
/// count is in range and every bone's lighting weights (`row_width` each) fit [`MAX_LIT`].
fn lead_rows(frame: Frame, row_width: usize) -> Result<usize, Error> {
    let Frame::Bones { count } = frame else {
        return Ok(0);
    };
    let bones = dim(Dim::Bones, count as u64, 1, MAX_BONES as u64)?;
    if bones * row_width > MAX_LIT {
        return Err(Error::BadDimension {
            what: Dim::Bones,
            value: bones as u64,
        });
    }
    Ok(1)
}

/// Sections must lie after the header, inside the blob, aligned, and not share bytes.
fn check_no_overlap(
    sections: &heapless::Vec<SectionEntry, MAX_SECTIONS>,
    header_end: u64,
    len: u64,
) -> Result<(), Error> {
    for (i, e) in sections.iter().enumerate() {
        let section = SectionKind::from_tag(e.kind);
        let end = e
            .offset
            .checked_add(e.len)
            .ok_or(Error::SectionOutOfRange { section })?;
        if e.offset < header_end || end > len {
            return Err(Error::SectionOutOfRange { section });
        }
        if e.offset % SECTION_ALIGN != 0 {
            return Err(Error::SectionMisaligned { section });
        }
        for other in &sections[..i] {
            if e.offset < other.offset + other.len && other.offset < end {
                return Err(Error::SectionOverlap { section });
            }
        }
    }
    Ok(())
}

/// The pose-features section, read before the others because the mean's and the
/// projection's lengths depend on it: the feature count (`pose_len` without the section) and
/// where the flags are. Checks the checksum, one flag of 0 or 1 per entry, and the limit.
fn pose_features<R: Reader>(
    r: &mut R,
    sections: &[SectionEntry],
    pose_len: usize,
) -> Result<(usize, Option<Span>), Error> {
    let section = SectionKind::PoseFeatures;
    let mut entries = sections.iter().filter(|e| e.kind == section.tag());
    let Some(e) = entries.next() else {
        return Ok((pose_len, None));
    };
    if entries.next().is_some() {
        return Err(Error::DuplicateSection { section });
    }
    let span = array_span(e, section, pose_len as u64)?;
    verify_array(r, e, span)?;
    let (mut flagged, mut ok) = (0, true);
    r.chunks(span.offset, 4, pose_len, |_, bytes| {
        for word in bytes.as_chunks::<4>().0 {
            let flag = f32::from_le_bytes(*word);
            ok &= flag == 0.0 || flag == 1.0;
            flagged += usize::from(flag == 1.0);
        }
        Ok(())
    })?;
    if !ok || pose_len + flagged > MAX_POSE_LEN {
        return Err(Error::BadPoseFeatures);
    }
    Ok((pose_len + flagged, Some(span)))
}

/// Streams a section's bytes to `visit` in chunks and checks its CRC, so a flipped bit
/// anywhere in a blob is caught, whatever the section.
fn check_crc<R: Reader>(
    r: &mut R,
    e: &SectionEntry,
    mut visit: impl FnMut(&[u8]),
) -> Result<(), Error> {
    let len = usize::try_from(e.len).map_err(|_| Error::LengthOverflow)?;
    let mut hasher = crc32fast::Hasher::new();
    r.chunks(e.offset, 1, len, |_, bytes| {
        hasher.update(bytes);
        visit(bytes);
        Ok(())
    })?;
    if hasher.finalize() != e.crc32 {
        return Err(Error::ChecksumMismatch {
            section: SectionKind::from_tag(e.kind),
        });
    }
    Ok(())
}

/// The irradiance rig: checksummed and its contents validated as they stream past
/// ([`RigCheck`], which the resident `IrradianceRig::parse` runs too); a length its prelude
/// does not announce is a section-length error. Its encoding byte carries no meaning.
fn check_irradiance_rig<R: Reader>(r: &mut R, e: &SectionEntry) -> Result<(), Error> {
    let mut rig = RigCheck::new();
    check_crc(r, e, |bytes| rig.feed(bytes))?;
    rig.finish().map_err(|failure| match failure {
        RigFailure::Content(error) => error,
        RigFailure::Length { expected } => Error::SectionLength {
            section: SectionKind::IrradianceRig,
            expected: expected as u64,
            found: e.len,
        },
    })?;
    Ok(())
}

/// The texel atlas: one `u32` texel per row after the resolution, then optionally the corner
/// UVs, checksummed and validated as it streams past ([`AtlasCheck`], which the resident
/// `TexelAtlas::parse` runs too). A length that is not the row count's, nor that plus a
/// trailer's, is a section-length error. Its encoding byte carries no meaning.
fn check_texel_atlas<R: Reader>(r: &mut R, e: &SectionEntry, vertices: usize) -> Result<(), Error> {
    let section = SectionKind::TexelAtlas;
    let base = atlas_len(vertices).ok_or(Error::LengthOverflow)?;
    let wrong_length = |expected| Error::SectionLength {
        section,
        expected,
        found: e.len,
    };
    // Refused before reading: too short for the rows, or for a trailer of one triangle.
    if e.len != base && e.len < base.saturating_add(trailer_len(1)) {
        return Err(wrong_length(base));
    }
    let mut atlas = AtlasCheck::new(vertices);
    check_crc(r, e, |bytes| atlas.feed(bytes))?;
    atlas.finish().map_err(|failure| match failure {
        AtlasFailure::Content => Error::BadTexelAtlas,
        AtlasFailure::Length { expected } => wrong_length(expected),
    })?;
    Ok(())
}

/// The occluder proxies: checksummed and validated as they stream past ([`ProxyCheck`]), for
/// a bone-frame model only (`bones` is 0 for a world-frame one, which no proxy fits). Their
/// encoding byte carries no meaning.
fn check_proxies<R: Reader>(r: &mut R, e: &SectionEntry, bones: usize) -> Result<(), Error> {
    if bones == 0 {
        return Err(Error::BadProxies);
    }
    let mut proxies = ProxyCheck::new(bones);
    check_crc(r, e, |bytes| proxies.feed(bytes))?;
    proxies.finish()?;
    Ok(())
}

/// The angle names: checksummed, then one UTF-8 line per pose entry. Their encoding byte
/// carries no meaning and is not checked.
fn check_angle_names<R: Reader>(r: &mut R, e: &SectionEntry, pose_len: usize) -> Result<(), Error> {
    let mut names = NamesCheck::default();
    check_crc(r, e, |bytes| names.feed(bytes))?;
    names.finish(pose_len)?;
    Ok(())
}

/// Where an array section lies, once its encoding is allowed for its kind and its length is
/// what the dimensions require.
fn array_span(e: &SectionEntry, section: SectionKind, elems: u64) -> Result<Span, Error> {
    let encoding = Encoding::from_tag(e.encoding)
        .filter(|enc| section.allows(*enc))
        .ok_or(Error::BadEncoding { section })?;
    let expected = elems
        .checked_mul(encoding.size() as u64)
        .ok_or(Error::LengthOverflow)?;
    if e.len != expected {
        return Err(Error::SectionLength {
            section,
            expected,
            found: e.len,
        });
    }
    Ok(Span {
        offset: e.offset,
        len: e.len,
        encoding,
    })
}

/// Checks an array section's CRC and that every value is finite, streaming it.
fn verify_array<R: Reader>(r: &mut R, e: &SectionEntry, span: Span) -> Result<(), Error> {
    let section = SectionKind::from_tag(e.kind);
    let size = span.encoding.size();
    let count = usize::try_from(span.len).map_err(|_| Error::LengthOverflow)? / size;
    // Stream in chunks of whole elements: 4-byte words hold 1 f32 or 2 f16.
    let mut hasher = crc32fast::Hasher::new();
    let mut finite = true;
    r.chunks(span.offset, size, count, |_, bytes| {
        hasher.update(bytes);
        finite &= match span.encoding {
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
            // Every byte is a value; its scale is checked with the scales.
            Encoding::I8 => true,
        };
        Ok(())
    })?;
    if hasher.finalize() != e.crc32 {
        return Err(Error::ChecksumMismatch { section });
    }
    if !finite {
        return Err(Error::NonFinite { section });
    }
    Ok(())
}

/// Finds the known sections other than the pose features (read first by `pose_features`),
/// without reading their bytes: each array section's encoding and length, no duplicates and
/// no required section of an unknown kind. `expected_elems` gives the element count an array
/// section of this basis must hold, `None` for one it does not use (left unlocated).
fn locate_sections(
    sections: &[SectionEntry],
    expected_elems: &dyn Fn(SectionKind) -> Option<Result<u64, Error>>,
) -> Result<[Option<Span>; SectionKind::KNOWN_COUNT], Error> {
    let mut found: [Option<Span>; SectionKind::KNOWN_COUNT] = [None; SectionKind::KNOWN_COUNT];
    for e in sections {
        let kind = SectionKind::from_tag(e.kind);
        let Some(slot) = kind.known_index() else {
            if e.required {
                return Err(Error::UnknownRequiredSection { section: kind });
            }
            continue;
        };
        if kind == SectionKind::PoseFeatures {
            continue;
        }
        if found[slot].is_some() {
            return Err(Error::DuplicateSection { section: kind });
        }
        found[slot] = match kind {
            SectionKind::IrradianceRig
            | SectionKind::TexelAtlas
            | SectionKind::Proxies
            | SectionKind::AngleNames => Some(Span {
                offset: e.offset,
                len: e.len,
                encoding: Encoding::F32,
            }),
            _ => expected_elems(kind)
                .map(|elems| array_span(e, kind, elems?))
                .transpose()?,
        };
    }
    Ok(found)
}

/// Reads every section but the pose features (checked with the layout), checking its CRC,
/// so a flipped bit anywhere in a blob is caught, and its values: an array's finiteness
/// (`found` holds the span of each array this basis uses), the rig, the atlas, the proxies
/// and the names by their own checks (`(vertices, pose_len, bones)` size the last three).
/// Then no byte may follow the last section (whose lengths are now all checked).
fn verify_sections<R: Reader>(
    r: &mut R,
    (sections, end_of_header): (&[SectionEntry], u64),
    found: &[Option<Span>; SectionKind::KNOWN_COUNT],
    (vertices, pose_len, bones): (usize, usize, usize),
) -> Result<(), Error> {
    let mut end_of_data = end_of_header;
    for e in sections {
        end_of_data = end_of_data.max(e.offset + e.len); // no overflow: checked by the layout
        let kind = SectionKind::from_tag(e.kind);
        match kind {
            SectionKind::PoseFeatures => {}
            SectionKind::IrradianceRig => check_irradiance_rig(r, e)?,
            SectionKind::TexelAtlas => check_texel_atlas(r, e, vertices)?,
            SectionKind::Proxies => check_proxies(r, e, bones)?,
            SectionKind::AngleNames => check_angle_names(r, e, pose_len)?,
            // An array of this basis, or one it does not use, or an optional section from
            // a newer writer or metadata for tools: checksummed all the same.
            _ => match kind.known_index().and_then(|slot| found[slot]) {
                Some(span) => verify_array(r, e, span)?,
                None => check_crc(r, e, |_| {})?,
            },
        }
    }
    if r.len() > end_of_data {
        return Err(Error::TrailingBytes {
            extra: r.len() - end_of_data,
        });
    }
    Ok(())
}
