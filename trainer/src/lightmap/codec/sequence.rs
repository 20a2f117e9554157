//! The encoder: a [`MapSequence`] and [`CodecSettings`] to the bytes of a `.shlm` file.

use super::entropy::compress;
use super::file::{assemble, is_keyframe};
use super::header::{Header, MAX_FRAMES, MAX_ORDER, MAX_RESOLUTION, stored_kind};
use super::shared_exp::{SignMode, decode_planes_on, encode_planes_on};
use super::uniform::Grid;
use super::{CodecError, CodecKind, CodecSettings, MapSequence, pca};

/// Encodes the whole clip as a `.shlm` file (layout in the module documentation).
pub fn encode(seq: &MapSequence, settings: &CodecSettings) -> Result<Vec<u8>, CodecError> {
    validate(seq, settings)?;
    let n2 = seq.order * seq.order;
    let filled: Vec<usize> = (0..seq.filled.len()).filter(|&t| seq.filled[t]).collect();
    let compact: Vec<Vec<f32>> = seq
        .frames
        .iter()
        .map(|frame| {
            filled
                .iter()
                .flat_map(|&t| &frame[t * n2..(t + 1) * n2])
                .copied()
                .collect()
        })
        .collect();
    let grid = match settings.planes.sign {
        SignMode::Uniform => Grid::new(&filled, seq.resolution),
        _ => Grid::row(filled.len()),
    };
    let plane_chunk = |values: &[f32]| {
        compress(
            &encode_planes_on(values, n2, &settings.planes, &grid, None),
            settings.zstd_level,
        )
    };
    let frames = compact.len();
    let (components, shared, chunks) = match settings.kind {
        CodecKind::Frames => {
            let chunks = compact
                .iter()
                .map(|f| plane_chunk(f))
                .collect::<Result<_, _>>()?;
            (0, Vec::new(), chunks)
        }
        CodecKind::Keyframes { interval } => {
            let chunk = |(f, values): (usize, &Vec<f32>)| match is_keyframe(f, interval, frames) {
                true => plane_chunk(values),
                false => Ok(Vec::new()),
            };
            let chunks = compact
                .iter()
                .enumerate()
                .map(chunk)
                .collect::<Result<_, _>>()?;
            (0, Vec::new(), chunks)
        }
        CodecKind::Pca {
            target_error,
            max_components,
        } => encode_pca(
            &compact,
            n2,
            &grid,
            settings,
            f64::from(target_error),
            max_components,
        )?,
    };
    let header = Header {
        resolution: seq.resolution,
        order: seq.order,
        frames,
        texels: filled.len(),
        kind: stored_kind(&settings.kind, components),
        planes: settings.planes,
        sections: [0; 4],
        atlas: seq.atlas,
        uv_triangles: 0,
        version: Header::version_for(seq.atlas),
    };
    assemble(header, seq, &shared, &chunks, settings.zstd_level)
}

/// What a temporal scheme produces: PCA's `k` (0 otherwise), the shared section's blobs, one
/// chunk per frame.
type Encoded = (usize, Vec<Vec<u8>>, Vec<Vec<u8>>);

/// The shared plane sets (mean, then components) and the per-frame weight chunks. The weights
/// are re-fitted against the quantised basis, as the decoder will see it.
fn encode_pca(
    frames: &[Vec<f32>],
    n2: usize,
    grid: &Grid,
    settings: &CodecSettings,
    target_error: f64,
    max_components: usize,
) -> Result<Encoded, CodecError> {
    let fitted = pca::fit(frames, target_error, max_components);
    let steps = uniform_pca_steps(
        frames,
        fitted.components.len(),
        settings.planes.mantissa_bits,
    );
    let mut shared = Vec::new();
    let mut quantised = Vec::new();
    for (i, values) in std::iter::once(&fitted.mean)
        .chain(&fitted.components)
        .enumerate()
    {
        let step = (settings.planes.sign == SignMode::Uniform).then_some(steps[usize::from(i > 0)]);
        let mut planes = encode_planes_on(values, n2, &settings.planes, grid, step);
        shared.push(compress(&planes, settings.zstd_level)?);
        let mut back = vec![0f32; values.len()];
        decode_planes_on(&mut planes, n2, &settings.planes, grid, &mut back)
            .map_err(CodecError::Input)?;
        quantised.push(back);
    }
    let (mean, components) = quantised.split_at(1);
    let weights = pca::refit_weights(frames, &mean[0], components).unwrap_or(fitted.weights);
    let chunks = weights
        .iter()
        .map(|w| w.iter().flat_map(|x| x.to_le_bytes()).collect())
        .collect();
    Ok((fitted.components.len(), shared, chunks))
}

/// Sign mode 3's steps for the PCA mean and the components, for a quantisation error of about
/// `2^−m · ‖X‖` over the clip. A component's error reaches the frames through weights of unit
/// norm over the clip (its eigenvector), the mean's through every frame, so the error is
/// about `(k + 1) · D · s² / 12` with the mean's step `s / √F`: the step where a bit buys the
/// same error in every plane set.
fn uniform_pca_steps(frames: &[Vec<f32>], k: usize, m: u8) -> [f64; 2] {
    let total: f64 = frames.iter().flatten().map(|&x| f64::from(x).powi(2)).sum();
    let dim = frames.first().map_or(1, Vec::len).max(1);
    let step = 2f64.powi(-i32::from(m)) * (12.0 * total / ((k + 1) * dim) as f64).sqrt();
    [step / (frames.len().max(1) as f64).sqrt(), step]
}

/// Refuses sequences the file cannot hold or the reader would refuse.
fn validate(seq: &MapSequence, settings: &CodecSettings) -> Result<(), CodecError> {
    let fail = |m: String| Err(CodecError::Input(m));
    let r = seq.resolution;
    if !(1..=MAX_RESOLUTION).contains(&r) || !(1..=MAX_ORDER).contains(&seq.order) {
        return fail(format!(
            "resolution {r} or order {} out of range",
            seq.order
        ));
    }
    if seq.frames.is_empty() || seq.frames.len() > MAX_FRAMES {
        return fail(format!("{} frames (1..={MAX_FRAMES})", seq.frames.len()));
    }
    let texel_values = r * r * seq.order * seq.order;
    if seq.filled.len() != r * r {
        return fail(format!(
            "filled has {} flags for {r}² texels",
            seq.filled.len()
        ));
    }
    let count = seq.filled.iter().filter(|&&f| f).count();
    if seq.positions.len() != count || seq.positions.iter().flatten().any(|p| !p.is_finite()) {
        return fail(format!(
            "{} positions for {count} filled texels, or non-finite",
            seq.positions.len()
        ));
    }
    if let Some(f) = seq.frames.iter().position(|f| f.len() != texel_values) {
        return fail(format!(
            "frame {f} is not {r}² × n² = {texel_values} values"
        ));
    }
    if let Some(f) = seq
        .frames
        .iter()
        .position(|f| f.iter().any(|x| !x.is_finite()))
    {
        return fail(format!("frame {f} holds NaN or infinity"));
    }
    let p = &settings.planes;
    match settings.kind {
        _ if !(2..=8).contains(&p.mantissa_bits) => fail("mantissa bits outside 2..=8".into()),
        CodecKind::Keyframes { interval } if interval == 0 || interval > seq.frames.len() => {
            fail(format!("keyframe interval {interval} outside 1..=frames"))
        }
        CodecKind::Pca { target_error, .. } if !target_error.is_finite() || target_error < 0.0 => {
            fail(format!("PCA target error {target_error}"))
        }
        _ => Ok(()),
    }
}
