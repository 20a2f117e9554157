//! Reads a blob back into a trainer [`LinearModel`], following `FORMAT.md` with none of the
//! evaluator's code, so the f64 reference `LinearModel::predict` of what the blob *stores* can
//! judge the core's f32 evaluation, and the writer's quantisation can be checked value by value.

use aprt_core::format::{SectionEntry, padded_vertices, read_header};
use aprt_core::{Basis, Encoding, Frame, SectionKind, VERTEX_BLOCK};
use aprt_trainer::{BoneFrames, LinearModel, PoseBounds, VertexBasis};

/// The values of one section, exactly widened to f64.
fn values(blob: &[u8], e: &SectionEntry) -> Option<Vec<f64>> {
    let bytes =
        blob.get(usize::try_from(e.offset).ok()?..usize::try_from(e.offset + e.len).ok()?)?;
    Some(match Encoding::from_tag(e.encoding)? {
        Encoding::F32 => bytes
            .chunks_exact(4)
            .map(|w| f32::from_le_bytes(w.try_into().unwrap()) as f64)
            .collect(),
        Encoding::F16 => bytes
            .chunks_exact(2)
            .map(|w| half::f16::from_le_bytes([w[0], w[1]]).to_f64())
            .collect(),
        // The integers; `decode` applies the scales.
        Encoding::I8 => bytes.iter().map(|&b| f64::from(b as i8)).collect(),
    })
}

/// The model a blob stores. Meant for blobs `Model::parse` accepted; `None` when a section it
/// needs is missing or does not fit (the first entry of each kind is used).
pub fn decode(blob: &[u8]) -> Option<LinearModel> {
    let h = read_header(blob).ok()?;
    let entry = |kind: SectionKind| h.sections.iter().find(|e| e.kind == kind.tag());
    let section = |kind: SectionKind| values(blob, entry(kind)?);
    let (n2, v, ka) = (
        (h.order as usize).pow(2),
        h.vertices as usize,
        h.pose_dims as usize,
    );
    let kv = h.coef_dims as usize;
    let (width, rows_entry) = match h.basis {
        Basis::Stored => (kv, entry(SectionKind::VertexBasis)?),
        Basis::Identity => (n2 * (1 + ka), entry(SectionKind::VertexWeights)?),
    };
    // Bone-frame models start every block with a row of bone indices.
    let lead = usize::from(matches!(h.frame, Frame::Bones { .. }));
    let mut rows = values(blob, rows_entry)?;
    if Encoding::from_tag(rows_entry.encoding)? == Encoding::I8 {
        // Row r of a vertex is scale_r times its byte as i8; the bone row's bytes are
        // unsigned.
        let scales = section(SectionKind::RowScales)?;
        for (i, x) in rows.iter_mut().enumerate() {
            let r = i / VERTEX_BLOCK % (lead + width);
            *x = match r.checked_sub(lead) {
                None => f64::from(*x as i8 as u8),
                Some(r) => scales.get(r)? * *x,
            };
        }
    }
    if rows.len() != padded_vertices(v) * (lead + width) {
        return None;
    }
    // Row `r` of vertex `j` (bone row included): block j / 8, row r, lane j % 8.
    let at = |j: usize, r: usize| {
        rows[(j / VERTEX_BLOCK * (lead + width) + r) * VERTEX_BLOCK + j % VERTEX_BLOCK]
    };
    let (weights, basis) = match h.basis {
        Basis::Stored => (
            section(SectionKind::Weights)?,
            VertexBasis::Stored {
                coef_dims: kv,
                data: (0..v * kv).map(|i| at(i / kv, lead + i % kv)).collect(),
            },
        ),
        Basis::Identity => (
            (0..width * v).map(|i| at(i % v, lead + i / v)).collect(),
            VertexBasis::Identity,
        ),
    };
    Some(LinearModel {
        order: h.order as usize,
        vertices: v,
        pose_len: h.pose_len as usize,
        pose_mean: section(SectionKind::PoseMean)?,
        pose_projection: section(SectionKind::PoseProjection)?,
        weights,
        basis,
        alpha: h.alpha as f64,
        angle_names: entry(SectionKind::AngleNames)
            .and_then(|e| blob.get(e.offset as usize..(e.offset + e.len) as usize))
            .and_then(|bytes| std::str::from_utf8(bytes).ok())
            .map_or_else(Vec::new, |text| text.lines().map(str::to_owned).collect()),
        bounds: match section(SectionKind::PoseBounds) {
            Some(rows) if rows.len() == 4 * h.pose_len as usize => {
                let mut rows = rows.chunks_exact(h.pose_len as usize).map(<[f64]>::to_vec);
                Some(PoseBounds {
                    lo: rows.next()?,
                    hi: rows.next()?,
                    scale: rows.next()?,
                    prior: rows.next()?,
                })
            }
            _ => None,
        },
        cosines: section(SectionKind::PoseFeatures)
            .map_or_else(Vec::new, |flags| flags.iter().map(|&f| f == 1.0).collect()),
        // Its own layout, kept as bytes: FORMAT.md's `Proxies`.
        proxies: entry(SectionKind::Proxies).and_then(|e| {
            let start = usize::try_from(e.offset).ok()?;
            let end = start.checked_add(usize::try_from(e.len).ok()?)?;
            Some(blob.get(start..end)?.to_vec())
        }),
        bones: match h.frame {
            Frame::World => None,
            Frame::Bones { count } => Some(BoneFrames {
                count: count as usize,
                vertex_bone: (0..v).map(|j| at(j, 0) as u16).collect(),
            }),
        },
    })
}
