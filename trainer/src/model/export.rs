//! Model blob writer: quantises a [`LinearModel`] into the layout of `aprt_core::format`.

use aprt_core::format::{
    Header, MAGIC, MAX_HEADER_LEN, MAX_SECTIONS, PREAMBLE_LEN, SectionEntry, align_up, crc32,
    padded_vertices,
};
use aprt_core::{
    Basis, Encoding, FORMAT_VERSION, Frame, MAX_ATLAS_RESOLUTION, MAX_ATLAS_TRIANGLES, MAX_BONES,
    MAX_COEF_DIMS, MAX_LIT, MAX_ORDER, MAX_POSE_DIMS, MAX_POSE_LEN, MAX_VERTICES, SectionKind,
    VERTEX_BLOCK,
};

use crate::model::{LinearModel, VertexBasis};
use crate::rig::bone_frames::BoneFrames;

/// Storage precision of the large sections (weights and per-vertex rows); pose sections are
/// always f32.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize)]
pub enum Precision {
    /// 4 bytes per value.
    #[default]
    F32,
    /// 2 bytes per value, about 3 significant digits: IEEE half, rounded to nearest, so the
    /// stored value is within 2⁻¹¹ relative of the f64 one above 6.1e-5 and within 2⁻²⁵ ≈ 3e-8
    /// absolute below (subnormals; smaller values become 0). Values beyond ±65504 are refused
    /// with [`ExportError::NotRepresentable`], never clamped.
    F16,
    /// 1 byte per per-vertex value, the weights f32: each vector of the per-vertex section
    /// (basis vector k of a stored basis, row `(c, i)` of the identity basis) is stored as
    /// `s · q` with `s = max |v| / 127` over the vertices and `q` the nearest integer to
    /// `v / s`, so every value is within `s / 2` of the f64 one (a zero vector stores 0), and
    /// shading under lighting weights `w_k` is within `Σ_k |w_k| s_k / 2` of the f32 model's
    /// (plus f32 rounding).
    I8,
}

impl Precision {
    /// The encoding of the weights and of the per-vertex rows.
    fn encodings(self) -> (Float, Encoding) {
        match self {
            Precision::F32 => (Float::F32, Encoding::F32),
            Precision::F16 => (Float::F16, Encoding::F16),
            Precision::I8 => (Float::F32, Encoding::I8),
        }
    }
}

/// The float encodings [`encode`] writes; scaled bytes have their own writer, [`encode_i8`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Float {
    F32,
    F16,
}

impl Float {
    fn encoding(self) -> Encoding {
        match self {
            Float::F32 => Encoding::F32,
            Float::F16 => Encoding::F16,
        }
    }
}

impl Precision {
    /// The name `--precision` and scene files give it.
    pub fn name(self) -> &'static str {
        match self {
            Precision::F32 => "f32",
            Precision::F16 => "f16",
            Precision::I8 => "i8",
        }
    }
}

/// Why a model cannot be written.
#[derive(Clone, Debug, thiserror::Error, PartialEq)]
pub enum ExportError {
    /// The occluder proxies do not fit the model (a world-frame model, another bone count) or
    /// are malformed.
    #[error("occluder proxies: {0} (they need a bone-frame model of the same bones)")]
    Proxies(aprt_core::Error),
    /// A dimension exceeds what `aprt-core` accepts.
    #[error("{what} = {value} exceeds the runtime limit {max}")]
    TooLarge {
        /// Which dimension.
        what: &'static str,
        /// Its value.
        value: usize,
        /// The limit.
        max: usize,
    },
    /// A value is NaN or infinite, or overflows the chosen precision.
    #[error(
        "section {section:?}: value {value} at index {index} is not representable (NaN, infinite, or beyond the precision's range: ±3.4e38 for f32, ±65504 for f16)"
    )]
    NotRepresentable {
        /// The section.
        section: SectionKind,
        /// Element index.
        index: usize,
        /// The value.
        value: f64,
    },
    /// The arrays do not match the model's dimensions.
    #[error("section {section:?} has {found} values, the dimensions need {expected}")]
    Shape {
        /// The section.
        section: SectionKind,
        /// Required count.
        expected: usize,
        /// Given count.
        found: usize,
    },
    /// A dimension is below what a model needs.
    #[error("{what} = {value} is below the minimum {min}")]
    TooSmall {
        /// Which dimension.
        what: &'static str,
        /// Its value.
        value: usize,
        /// The least the runtime accepts.
        min: usize,
    },
    /// The Tikhonov parameter cannot be stored: the header holds it as an f32.
    #[error(
        "alpha {0:e} cannot be stored: a model records alpha as an f32, so it must be finite, at least 0 and at most 3.4e38, and a positive alpha at least 1.4e-45"
    )]
    Alpha(f64),
    /// The texel atlas cannot be recorded.
    #[error("texel atlas: {problem}")]
    TexelAtlas {
        /// What is wrong.
        problem: String,
    },
    /// The pose-entry names cannot be recorded.
    #[error("angle names: {problem}")]
    AngleNames {
        /// What is wrong.
        problem: String,
    },
}

fn limit(what: &'static str, value: usize, min: usize, max: usize) -> Result<(), ExportError> {
    if value < min {
        return Err(ExportError::TooSmall { what, value, min });
    }
    if value > max {
        return Err(ExportError::TooLarge { what, value, max });
    }
    Ok(())
}

/// Whether `alpha` survives the header's f32: finite, non-negative, not beyond `f32::MAX`,
/// and not a positive value that would round to 0.
pub fn check_alpha(alpha: f64) -> Result<(), ExportError> {
    let stored = alpha as f32;
    if alpha.is_finite() && alpha >= 0.0 && stored.is_finite() && (stored > 0.0 || alpha == 0.0) {
        Ok(())
    } else {
        Err(ExportError::Alpha(alpha))
    }
}

/// Encodes `values` as one section's bytes, rejecting what the reader would reject.
fn encode(
    section: SectionKind,
    values: &[f64],
    expected: usize,
    encoding: Float,
) -> Result<Vec<u8>, ExportError> {
    check_len(section, values.len(), expected)?;
    let mut out = Vec::with_capacity(values.len() * encoding.encoding().size());
    for (index, &value) in values.iter().enumerate() {
        let bad = || ExportError::NotRepresentable {
            section,
            index,
            value,
        };
        match encoding {
            Float::F32 => {
                let x = value as f32;
                if !x.is_finite() {
                    return Err(bad());
                }
                out.extend_from_slice(&x.to_le_bytes());
            }
            Float::F16 => {
                let x = half::f16::from_f64(value);
                if !x.is_finite() {
                    return Err(bad());
                }
                out.extend_from_slice(&x.to_le_bytes());
            }
        }
    }
    Ok(out)
}

/// A blocked per-vertex section (`lead` rows of bone indices, then `width` rows, in every
/// block of [`VERTEX_BLOCK`] lanes) as scaled bytes, and the f32 scale of each of the
/// `width` rows: `s_r = max_j |v_jr| / 127` (rounded to f32; 0 for a zero row) and
/// `q = round(v / s_r)` as `i8`, so `|v − s_r q| ≤ s_r / 2`. Bone indices (below 256) are
/// stored as unsigned bytes.
fn encode_i8(
    section: SectionKind,
    values: &[f64],
    lead: usize,
    width: usize,
) -> Result<(Vec<u8>, Vec<f64>), ExportError> {
    let row_of = |index: usize| index / VERTEX_BLOCK % (lead + width);
    let mut max = vec![0.0f64; width];
    for (index, &value) in values.iter().enumerate() {
        if !value.is_finite() {
            return Err(ExportError::NotRepresentable {
                section,
                index,
                value,
            });
        }
        if let Some(m) = row_of(index).checked_sub(lead).map(|r| &mut max[r]) {
            *m = m.max(value.abs());
        }
    }
    let scales: Vec<f64> = max.iter().map(|m| f64::from((m / 127.0) as f32)).collect();
    let bytes = values
        .iter()
        .enumerate()
        .map(|(index, &value)| match row_of(index).checked_sub(lead) {
            None => value as u8,
            Some(r) if scales[r] == 0.0 => 0,
            Some(r) => (value / scales[r]).round().clamp(-127.0, 127.0) as i8 as u8,
        })
        .collect();
    Ok((bytes, scales))
}

/// The per-vertex section `kind` of `values` (blocked, `lead` bone rows then `width` rows per
/// block) in `encoding`, followed by its `RowScales` section for scaled bytes.
fn rows_sections(
    kind: SectionKind,
    values: &[f64],
    (lead, width): (usize, usize),
    encoding: Encoding,
) -> Result<Vec<(SectionKind, Encoding, Vec<u8>)>, ExportError> {
    let float = match encoding {
        Encoding::F32 => Float::F32,
        Encoding::F16 => Float::F16,
        Encoding::I8 => {
            let (bytes, scales) = encode_i8(kind, values, lead, width)?;
            let scales = encode(SectionKind::RowScales, &scales, width, Float::F32)?;
            return Ok(vec![
                (kind, Encoding::I8, bytes),
                (SectionKind::RowScales, Encoding::F32, scales),
            ]);
        }
    };
    Ok(vec![(
        kind,
        encoding,
        encode(kind, values, values.len(), float)?,
    )])
}

fn check_len(section: SectionKind, found: usize, expected: usize) -> Result<(), ExportError> {
    if found != expected {
        return Err(ExportError::Shape {
            section,
            expected,
            found,
        });
    }
    Ok(())
}

/// Per-vertex values `get(j, r)` (`r < width`) in the core's blocked layout: blocks of
/// `VERTEX_BLOCK` vertices, value-major within a block, the last block zero-padded; for
/// bone-frame models each block starts with a row of the vertices' bone indices.
fn blocked(
    vertices: usize,
    width: usize,
    bones: Option<&BoneFrames>,
    get: impl Fn(usize, usize) -> f64,
) -> Vec<f64> {
    let lead = usize::from(bones.is_some());
    let mut out = Vec::with_capacity(padded_vertices(vertices) * (lead + width));
    for b in 0..padded_vertices(vertices) / VERTEX_BLOCK {
        if let Some(frames) = bones {
            for lane in 0..VERTEX_BLOCK {
                let j = b * VERTEX_BLOCK + lane;
                out.push(frames.vertex_bone.get(j).map_or(0.0, |&x| x as f64));
            }
        }
        for r in 0..width {
            for lane in 0..VERTEX_BLOCK {
                let j = b * VERTEX_BLOCK + lane;
                out.push(if j < vertices { get(j, r) } else { 0.0 });
            }
        }
    }
    out
}

/// The optional sections a blob may carry beside the model itself.
#[derive(Clone, Copy, Debug, Default)]
pub struct Extras<'a> {
    /// An irradiance rig's bytes (from [`aprt_core::RigLayout::write`]), written as the
    /// `IrradianceRig` section.
    pub irradiance_rig: Option<&'a [u8]>,
    /// A light-map model's atlas, written as the `TexelAtlas` section.
    pub texel_atlas: Option<TexelAtlasExtra<'a>>,
}

/// A light-map model's atlas as [`Extras`] carries it to the `TexelAtlas` section.
#[derive(Clone, Copy, Debug)]
pub struct TexelAtlasExtra<'a> {
    /// The map's resolution R: it is R × R texels.
    pub resolution: u32,
    /// Each row's texel index `y · R + x`: one per row, strictly increasing, below R².
    pub texels: &'a [u32],
    /// The light-map UVs `[u, v]` of every triangle's three corners, in the mesh's triangle
    /// order (u right, v down, each in `[0, 1]`), so an engine can draw the map: the
    /// section's optional trailer. `None` records no UVs; `Some` holds at least one triangle.
    pub corner_uvs: Option<&'a [[[f32; 2]; 3]]>,
}

/// Serialises `model` into a complete blob.
pub fn encode_model(model: &LinearModel, precision: Precision) -> Result<Vec<u8>, ExportError> {
    encode_model_with(model, precision, &Extras::default())
}

/// Serialises `model` into a complete blob, with an irradiance rig's bytes (from
/// [`aprt_core::RigLayout::write`]) as its optional `IrradianceRig` section when given.
pub fn encode_model_with_rig(
    model: &LinearModel,
    precision: Precision,
    irradiance_rig: Option<&[u8]>,
) -> Result<Vec<u8>, ExportError> {
    let extras = Extras {
        irradiance_rig,
        ..Extras::default()
    };
    encode_model_with(model, precision, &extras)
}

/// Serialises `model` into a complete blob with the optional sections of `extras`.
pub fn encode_model_with(
    model: &LinearModel,
    precision: Precision,
    extras: &Extras<'_>,
) -> Result<Vec<u8>, ExportError> {
    let (n2, v, a, f, ka) = (
        model.order * model.order,
        model.vertices,
        model.pose_len,
        model.feature_len(),
        model.pose_dims(),
    );
    limit("order", model.order, 1, MAX_ORDER)?;
    limit("vertices", v, 1, MAX_VERTICES)?;
    limit("joints", a, 1, MAX_POSE_LEN)?;
    limit("pose features", f, 1, MAX_POSE_LEN)?;
    limit("pose dims", ka, 0, MAX_POSE_DIMS.min(f))?;
    check_alpha(model.alpha)?;
    if let VertexBasis::Stored { coef_dims, .. } = model.basis {
        limit("coef dims", coef_dims, 1, MAX_COEF_DIMS)?;
    }
    let frame = frame_of(model, n2 * (1 + ka))?;
    let (weights, rows) = precision.encodings();
    let lead = usize::from(model.bones.is_some());
    let mut sections: Vec<(SectionKind, Encoding, Vec<u8>)> = vec![
        (
            SectionKind::PoseMean,
            Encoding::F32,
            encode(SectionKind::PoseMean, &model.pose_mean, f, Float::F32)?,
        ),
        (
            SectionKind::PoseProjection,
            Encoding::F32,
            encode(
                SectionKind::PoseProjection,
                &model.pose_projection,
                ka * f,
                Float::F32,
            )?,
        ),
    ];
    let basis = match &model.basis {
        VertexBasis::Stored { coef_dims, data } => {
            let kv = *coef_dims;
            let w = encode(
                SectionKind::Weights,
                &model.weights,
                n2 * (ka + 1) * kv,
                weights,
            )?;
            sections.push((SectionKind::Weights, weights.encoding(), w));
            check_len(SectionKind::VertexBasis, data.len(), v * kv)?;
            let u = blocked(v, kv, model.bones.as_ref(), |j, k| data[j * kv + k]);
            let kind = SectionKind::VertexBasis;
            sections.extend(rows_sections(kind, &u, (lead, kv), rows)?);
            Basis::Stored
        }
        VertexBasis::Identity => {
            let width = n2 * (ka + 1);
            check_len(SectionKind::VertexWeights, model.weights.len(), width * v)?;
            let x = blocked(v, width, model.bones.as_ref(), |j, r| {
                model.weights[r * v + j]
            });
            let kind = SectionKind::VertexWeights;
            sections.extend(rows_sections(kind, &x, (lead, width), rows)?);
            Basis::Identity
        }
    };
    let mut table: Vec<SectionBytes> = sections
        .into_iter()
        .map(|(kind, encoding, bytes)| SectionBytes {
            tag: kind.tag(),
            required: true,
            encoding,
            bytes,
        })
        .collect();
    table.extend(optional_sections(model, extras)?);
    assemble(model, basis, frame, &table)
}

/// The optional sections of `model` and `extras`: angle names, pose bounds, pose features,
/// the irradiance rig and the texel atlas, each when present.
fn optional_sections(
    model: &LinearModel,
    extras: &Extras<'_>,
) -> Result<Vec<SectionBytes>, ExportError> {
    let (a, v) = (model.pose_len, model.vertices);
    let mut table = Vec::new();
    if !model.angle_names.is_empty() {
        table.push(angle_names_section(&model.angle_names, a)?);
    }
    if let Some(bounds) = &model.bounds {
        let kind = SectionKind::PoseBounds;
        table.push(SectionBytes {
            tag: kind.tag(),
            required: true,
            encoding: Encoding::F32,
            bytes: encode(kind, &bounds.rows(), 4 * a, Float::F32)?,
        });
    }
    if !model.features().is_angles() {
        let kind = SectionKind::PoseFeatures;
        check_len(kind, model.cosines.len(), a)?;
        let flags: Vec<f64> = model
            .cosines
            .iter()
            .map(|&c| f64::from(u8::from(c)))
            .collect();
        table.push(SectionBytes {
            tag: kind.tag(),
            required: true,
            encoding: Encoding::F32,
            bytes: encode(kind, &flags, a, Float::F32)?,
        });
    }
    if let Some(rig) = extras.irradiance_rig {
        table.push(SectionBytes {
            tag: SectionKind::IrradianceRig.tag(),
            required: false,
            encoding: Encoding::F32,
            bytes: rig.to_vec(),
        });
    }
    if let Some(atlas) = &extras.texel_atlas {
        table.push(texel_atlas_section(atlas, v)?);
    }
    if let Some(proxies) = &model.proxies {
        let bones = model.bones.as_ref().map_or(0, |b| b.count);
        aprt_core::ProxySet::parse(proxies, bones).map_err(ExportError::Proxies)?;
        table.push(SectionBytes {
            tag: SectionKind::Proxies.tag(),
            required: true,
            encoding: Encoding::F32,
            bytes: proxies.to_vec(),
        });
    }
    Ok(table)
}

/// The blob's frame: world, or bones (checked: every vertex's bone exists, and the weights
/// the runtime lights per frame, bones × `identity_width` for an identity basis or × k_v,
/// fit its limit).
fn frame_of(model: &LinearModel, identity_width: usize) -> Result<Frame, ExportError> {
    let v = model.vertices;
    Ok(match &model.bones {
        None => Frame::World,
        Some(b) => {
            limit("bones", b.count, 1, MAX_BONES)?;
            check_len(SectionKind::VertexBasis, b.vertex_bone.len(), v)?;
            if let Some(&bad) = b.vertex_bone.iter().find(|&&x| x as usize >= b.count) {
                return Err(ExportError::TooLarge {
                    what: "vertex bone",
                    value: bad as usize,
                    max: b.count - 1,
                });
            }
            // The runtime lights every bone's row width of weights per frame.
            let width = match model.basis {
                VertexBasis::Stored { coef_dims, .. } => coef_dims,
                VertexBasis::Identity => identity_width,
            };
            limit("bones × lit row width", b.count * width, 1, MAX_LIT)?;
            Frame::Bones {
                count: b.count as u16,
            }
        }
    })
}

/// One section ready to lay out.
struct SectionBytes {
    tag: u16,
    required: bool,
    encoding: Encoding,
    bytes: Vec<u8>,
}

/// The optional section of pose-entry names: one per line, so a name may not hold a newline.
fn angle_names_section(names: &[String], pose_len: usize) -> Result<SectionBytes, ExportError> {
    if names.len() != pose_len {
        return Err(ExportError::AngleNames {
            problem: format!("{} names for {pose_len} pose entries", names.len()),
        });
    }
    if let Some(bad) = names.iter().find(|n| n.is_empty() || n.contains('\n')) {
        return Err(ExportError::AngleNames {
            problem: format!("{bad:?} is empty or holds a newline"),
        });
    }
    let bytes = names
        .iter()
        .flat_map(|n| n.bytes().chain([b'\n']))
        .collect();
    Ok(SectionBytes {
        tag: SectionKind::AngleNames.tag(),
        required: false,
        encoding: Encoding::F32,
        bytes,
    })
}

/// The optional texel-atlas section, refusing what the reader would refuse: a resolution
/// outside 1..=[`MAX_ATLAS_RESOLUTION`], a row count that is not the model's, indices that
/// are not strictly increasing or not below R², and corner UVs as [`corner_uv_bytes`] says.
fn texel_atlas_section(
    atlas: &TexelAtlasExtra<'_>,
    rows: usize,
) -> Result<SectionBytes, ExportError> {
    let TexelAtlasExtra {
        resolution,
        texels,
        corner_uvs,
    } = *atlas;
    let bad = |problem: String| Err(ExportError::TexelAtlas { problem });
    if !(1..=MAX_ATLAS_RESOLUTION).contains(&resolution) {
        return bad(format!(
            "resolution {resolution} is not in 1..={MAX_ATLAS_RESOLUTION}"
        ));
    }
    if texels.len() != rows {
        return bad(format!("{} texels for {rows} rows", texels.len()));
    }
    let squared = u64::from(resolution) * u64::from(resolution);
    if let Some(row) = texels.iter().position(|&t| u64::from(t) >= squared) {
        return bad(format!(
            "row {row}'s texel {} is not below {squared}",
            texels[row]
        ));
    }
    if let Some(row) = texels.windows(2).position(|w| w[0] >= w[1]) {
        return bad(format!(
            "row {}'s texel {} does not follow {}",
            row + 1,
            texels[row + 1],
            texels[row]
        ));
    }
    let mut bytes: Vec<u8> = std::iter::once(resolution)
        .chain(texels.iter().copied())
        .flat_map(u32::to_le_bytes)
        .collect();
    if let Some(corners) = corner_uvs {
        bytes.extend(corner_uv_bytes(corners)?);
    }
    Ok(SectionBytes {
        tag: SectionKind::TexelAtlas.tag(),
        required: false,
        encoding: Encoding::F32,
        bytes,
    })
}

/// The texel atlas's trailer: the triangle count, 1..=[`MAX_ATLAS_TRIANGLES`], then every
/// corner's UV, refused (naming the triangle and corner) unless within `[0, 1]`.
fn corner_uv_bytes(corners: &[[[f32; 2]; 3]]) -> Result<Vec<u8>, ExportError> {
    let count = u32::try_from(corners.len())
        .ok()
        .filter(|t| (1..=MAX_ATLAS_TRIANGLES).contains(t))
        .ok_or_else(|| ExportError::TexelAtlas {
            problem: format!(
                "{} triangles of corner UVs is not in 1..={MAX_ATLAS_TRIANGLES}",
                corners.len()
            ),
        })?;
    for (triangle, uvs) in corners.iter().enumerate() {
        if let Some(corner) = uvs
            .iter()
            .position(|uv| !uv.iter().all(|x| (0.0..=1.0).contains(x)))
        {
            return Err(ExportError::TexelAtlas {
                problem: format!(
                    "triangle {triangle}'s corner {corner} has UV {:?}, not in [0, 1]²",
                    uvs[corner]
                ),
            });
        }
    }
    let floats = corners.iter().flatten().flatten().map(|x| x.to_bits());
    Ok(std::iter::once(count)
        .chain(floats)
        .flat_map(u32::to_le_bytes)
        .collect())
}

/// Lays out preamble, header and aligned sections. The header holds the section offsets,
/// which depend on the header's own (varint) length: iterate until the length is stable.
fn assemble(
    model: &LinearModel,
    basis: Basis,
    frame: Frame,
    sections: &[SectionBytes],
) -> Result<Vec<u8>, ExportError> {
    let mut header_len = 0usize;
    for _ in 0..8 {
        let mut table = heapless::Vec::<SectionEntry, MAX_SECTIONS>::new();
        let mut offset = align_up((PREAMBLE_LEN + header_len) as u64).unwrap_or(u64::MAX);
        for section in sections {
            let entry = SectionEntry {
                kind: section.tag,
                required: section.required,
                encoding: section.encoding as u8,
                offset,
                len: section.bytes.len() as u64,
                crc32: crc32(&section.bytes),
            };
            table.push(entry).expect("fewer sections than MAX_SECTIONS");
            offset = align_up(offset + section.bytes.len() as u64).unwrap_or(u64::MAX);
        }
        let header = Header {
            order: model.order as u8,
            vertices: model.vertices as u32,
            pose_len: model.pose_len as u16,
            pose_dims: model.pose_dims() as u16,
            coef_dims: model.coef_dims() as u32,
            basis,
            frame,
            alpha: model.alpha as f32,
            sections: table.clone(),
        };
        let encoded = postcard::to_allocvec(&header).expect("header serialises into a Vec");
        if encoded.len() != header_len {
            header_len = encoded.len();
            continue;
        }
        assert!(
            header_len <= MAX_HEADER_LEN as usize,
            "header of {header_len} bytes"
        );
        let mut blob = Vec::new();
        blob.extend_from_slice(&MAGIC);
        blob.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
        blob.extend_from_slice(&(header_len as u32).to_le_bytes());
        blob.extend_from_slice(&crc32(&encoded).to_le_bytes());
        blob.extend_from_slice(&encoded);
        for (entry, section) in table.iter().zip(sections) {
            blob.resize(entry.offset as usize, 0);
            blob.extend_from_slice(&section.bytes);
        }
        return Ok(blob);
    }
    unreachable!("header length converges: offsets only grow with it")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tiny(basis: VertexBasis, kv: usize) -> LinearModel {
        let (n2, ka, v) = (4, 2, 3);
        LinearModel {
            order: 2,
            vertices: v,
            pose_len: 3,
            pose_mean: vec![0.1, -0.2, 0.3],
            pose_projection: vec![1.0, 0.0, 0.5, 0.0, 1.0, -0.5],
            weights: (0..n2 * (ka + 1) * kv)
                .map(|i| (i as f64 * 0.37).sin())
                .collect(),
            basis,
            alpha: 0.25,
            bones: None,
            angle_names: Vec::new(),
            bounds: None,
            cosines: Vec::new(),
            proxies: None,
        }
    }

    #[test]
    fn blob_parses_back_with_the_same_dimensions() {
        let stored = tiny(
            VertexBasis::Stored {
                coef_dims: 2,
                data: vec![0.5; 6],
            },
            2,
        );
        for model in [stored, tiny(VertexBasis::Identity, 3)] {
            for precision in [Precision::F32, Precision::F16, Precision::I8] {
                let blob = encode_model(&model, precision).unwrap();
                let parsed = aprt_core::Model::parse(&blob).unwrap();
                let info = parsed.info();
                assert_eq!(info.order(), 2);
                assert_eq!(info.vertices(), 3);
                assert_eq!(info.pose_dims(), 2);
                assert_eq!(info.coef_dims(), model.coef_dims());
                assert_eq!(info.encoding(), precision.encodings().1);
            }
            // `aprt inspect` names the rows' encoding and lists the scales beside them.
            let blob = encode_model(&model, Precision::I8).unwrap();
            let described = crate::model::runtime::describe(&blob).unwrap();
            let encodings: Vec<(&str, &str)> = described
                .sections
                .iter()
                .map(|s| (s.kind.as_str(), s.encoding.as_str()))
                .collect();
            assert!(encodings.contains(&("RowScales", "f32")), "{encodings:?}");
            assert!(
                encodings
                    .iter()
                    .any(|&(k, e)| k.starts_with("Vertex") && e == "i8"),
                "{encodings:?}"
            );
        }
    }

    #[test]
    fn texel_atlas_round_trips_and_refuses_what_the_reader_would() {
        let model = tiny(VertexBasis::Identity, 3);
        let with = |resolution: u32, texels: &[u32], corner_uvs: Option<&[[[f32; 2]; 3]]>| {
            let extras = Extras {
                texel_atlas: Some(TexelAtlasExtra {
                    resolution,
                    texels,
                    corner_uvs,
                }),
                ..Extras::default()
            };
            encode_model_with(&model, Precision::F32, &extras)
        };
        let corners = [
            [[0.0, 0.0], [1.0, 0.0], [0.5, 1.0]],
            [[0.125, 0.25], [0.375, 0.25], [0.25, 0.5]],
        ];
        for uvs in [None, Some(&corners[..])] {
            let blob = with(4, &[1, 5, 15], uvs).unwrap();
            let parsed = aprt_core::Model::parse(&blob).unwrap();
            let atlas = parsed.texel_atlas().unwrap();
            assert_eq!((atlas.resolution(), atlas.rows()), (4, 3));
            assert_eq!(atlas.texel(2), Ok(15));
            let read: Vec<_> = (0..atlas.triangles())
                .map(|t| atlas.corner_uvs(t).unwrap())
                .collect();
            assert_eq!(read, uvs.unwrap_or_default());
            let info = crate::model::runtime::describe(&blob).unwrap();
            assert_eq!(
                info.texel_atlas
                    .map(|a| (a.resolution, a.rows, a.triangles)),
                Some((4, 3, read.len()))
            );
            let line = info.to_string();
            assert!(line.contains("texel atlas     4 x 4: 3 rows"), "{line}");
            assert_eq!(
                line.contains("corner UVs of 2 triangles"),
                uvs.is_some(),
                "{line}"
            );
        }
        for (resolution, texels) in [
            (0, &[0u32, 1, 2][..]),
            (MAX_ATLAS_RESOLUTION + 1, &[0, 1, 2]),
            (4, &[0, 1]),
            (4, &[0, 1, 16]),
            (4, &[0, 2, 2]),
            (4, &[3, 2, 5]),
        ] {
            assert!(
                matches!(
                    with(resolution, texels, None),
                    Err(ExportError::TexelAtlas { .. })
                ),
                "{resolution} {texels:?}"
            );
        }
        // Corner UVs outside [0, 1]² or not finite, named by triangle and corner; none at all.
        for (uv, corner) in [
            ([f32::NAN, 0.5], 0),
            ([0.5, -1e-7], 1),
            ([1.0000001, 0.0], 2),
            ([0.0, f32::INFINITY], 1),
        ] {
            let mut bad = corners;
            bad[1][corner] = uv;
            let err = with(4, &[1, 5, 15], Some(&bad)).unwrap_err().to_string();
            assert!(
                err.contains(&format!("triangle 1's corner {corner} has UV")),
                "{err}"
            );
        }
        let err = with(4, &[1, 5, 15], Some(&[])).unwrap_err().to_string();
        assert!(err.contains("0 triangles of corner UVs"), "{err}");
    }

    #[test]
    fn rejects_nan_and_f16_overflow() {
        let mut m = tiny(VertexBasis::Identity, 3);
        m.weights[5] = f64::NAN;
        assert!(matches!(
            encode_model(&m, Precision::F32),
            Err(ExportError::NotRepresentable {
                section: SectionKind::VertexWeights,
                ..
            })
        ));
        m.weights[5] = 1e6;
        assert!(encode_model(&m, Precision::F32).is_ok());
        assert!(matches!(
            encode_model(&m, Precision::F16),
            Err(ExportError::NotRepresentable { .. })
        ));
    }

    #[test]
    fn rejects_shapes_the_runtime_cannot_hold() {
        let m = tiny(
            VertexBasis::Stored {
                coef_dims: MAX_COEF_DIMS + 1,
                data: vec![],
            },
            1,
        );
        assert!(matches!(
            encode_model(&m, Precision::F32),
            Err(ExportError::TooLarge {
                what: "coef dims",
                ..
            })
        ));
    }

    #[test]
    fn refuses_an_alpha_the_header_cannot_hold_and_says_a_dimension_is_too_small() {
        let stored = VertexBasis::Stored {
            coef_dims: 2,
            data: vec![0.5; 6],
        };
        let mut m = tiny(stored, 2);
        for alpha in [1e300, 1e-50, -1.0, f64::NAN] {
            m.alpha = alpha;
            let err = encode_model(&m, Precision::F32).unwrap_err();
            assert!(matches!(err, ExportError::Alpha(_)), "{alpha}: {err}");
        }
        m.alpha = 0.0;
        assert!(encode_model(&m, Precision::F32).is_ok());
        let empty = VertexBasis::Stored {
            coef_dims: 0,
            data: vec![],
        };
        let err = encode_model(&tiny(empty, 0), Precision::F32).unwrap_err();
        assert_eq!(err.to_string(), "coef dims = 0 is below the minimum 1");
    }
}
