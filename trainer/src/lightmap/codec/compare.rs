//! Measuring every codec variant on one sequence: bytes, ratio, error, decode time.

use std::time::Instant;

use super::shared_exp::{Grouping, PlaneSettings, SignMode};
use super::{CodecKind, CodecSettings, MapSequence, ShlmFile, encode};

/// One variant's figures on a sequence.
#[derive(Debug, Clone, PartialEq)]
pub struct CodecReport {
    /// The variant, e.g. `pca 1% m7 sign-plane`.
    pub name: String,
    /// The `.shlm` file's size.
    pub bytes: usize,
    /// Raw f32 maps (all `R²` texels, every frame) over `bytes`.
    pub ratio: f64,
    /// `‖decoded − original‖₂ / ‖original‖₂` over all frames, filled texels, coefficients.
    pub relative_error: f64,
    /// The largest `|decoded − original|`.
    pub max_abs_error: f64,
    /// Median wall time of one `decode_frame`, frames decoded in order (the median, so a
    /// busy machine's preemptions do not swamp the figure).
    pub decode_ms_per_frame: f64,
}

/// Every variant worth comparing, by name: the sign modes and groupings at equal mantissa
/// bits, quality steps of independent frames, keyframe intervals, PCA error targets.
fn variants() -> Vec<(String, CodecSettings)> {
    let planes = |bits: u8, sign: SignMode, grouping: Grouping| PlaneSettings {
        mantissa_bits: bits,
        sign,
        grouping,
        spatial_delta: true,
    };
    let sp = SignMode::SignPlane;
    let with = |kind: CodecKind, p: PlaneSettings| CodecSettings {
        kind,
        planes: p,
        ..CodecSettings::default()
    };
    let pca = |target: f32| CodecKind::Pca {
        target_error: target,
        max_components: 32,
    };
    let mut out = vec![
        (
            "frames m8 offset-per-map".into(),
            with(
                CodecKind::Frames,
                planes(8, SignMode::OffsetScale, Grouping::Texel),
            ),
        ),
        (
            "frames m8 sign-plane".into(),
            with(CodecKind::Frames, planes(8, sp, Grouping::Texel)),
        ),
        (
            "frames m8 band0-ratio".into(),
            with(
                CodecKind::Frames,
                planes(8, SignMode::Band0Ratio, Grouping::Texel),
            ),
        ),
        (
            "frames m8 sign-plane triples".into(),
            with(CodecKind::Frames, planes(8, sp, Grouping::Triples)),
        ),
    ];
    let no_delta = PlaneSettings {
        spatial_delta: false,
        ..planes(6, sp, Grouping::Texel)
    };
    out.push((
        "frames m6 sign-plane no-delta".into(),
        with(CodecKind::Frames, no_delta),
    ));
    let signs = [
        ("offset-per-map", SignMode::OffsetScale),
        ("sign-plane", sp),
        ("band0-ratio", SignMode::Band0Ratio),
    ];
    for bits in [7, 6, 5, 4] {
        for (label, sign) in signs {
            out.push((
                format!("frames m{bits} {label}"),
                with(CodecKind::Frames, planes(bits, sign, Grouping::Texel)),
            ));
        }
    }
    for interval in [2, 4] {
        let kind = CodecKind::Keyframes { interval };
        out.push((
            format!("keyframes K={interval} m6 sign-plane"),
            with(kind, planes(6, sp, Grouping::Texel)),
        ));
    }
    for (target, bits) in [(0.005, 8), (0.01, 7), (0.01, 6), (0.02, 6), (0.02, 5)] {
        let name = format!("pca {}% m{bits} sign-plane", target * 100.0);
        out.push((name, with(pca(target), planes(bits, sp, Grouping::Texel))));
    }
    for (target, bits) in [(0.005, 8), (0.01, 8), (0.01, 7), (0.01, 6), (0.02, 6)] {
        let name = format!("pca {}% m{bits} offset-per-map", target * 100.0);
        out.push((
            name,
            with(
                pca(target),
                planes(bits, SignMode::OffsetScale, Grouping::Texel),
            ),
        ));
    }
    out.push((
        "pca 1% m7 band0-ratio".into(),
        with(pca(0.01), planes(7, SignMode::Band0Ratio, Grouping::Texel)),
    ));
    out
}

/// Encodes, parses and decodes `seq` with every variant; a variant that fails to encode is
/// left out (the sequence is the caller's, already validated by [`encode`] in practice).
pub fn compare(seq: &MapSequence) -> Vec<CodecReport> {
    variants()
        .into_iter()
        .filter_map(|(name, settings)| measure(seq, name, &settings))
        .collect()
}

/// One row of [`compare`].
fn measure(seq: &MapSequence, name: String, settings: &CodecSettings) -> Option<CodecReport> {
    let bytes = encode(seq, settings).ok()?;
    let file = ShlmFile::parse(&bytes).ok()?;
    let n2 = seq.order * seq.order;
    let mut decoded = vec![0f32; seq.resolution * seq.resolution * n2];
    let (mut err2, mut norm2, mut max_abs) = (0f64, 0f64, 0f64);
    let mut times = Vec::with_capacity(seq.frames.len());
    for (k, original) in seq.frames.iter().enumerate() {
        let start = Instant::now();
        file.decode_frame(k, &mut decoded).ok()?;
        times.push(start.elapsed().as_secs_f64());
        for t in (0..seq.filled.len()).filter(|&t| seq.filled[t]) {
            for c in t * n2..(t + 1) * n2 {
                let d = f64::from(decoded[c]) - f64::from(original[c]);
                err2 += d * d;
                norm2 += f64::from(original[c]).powi(2);
                max_abs = max_abs.max(d.abs());
            }
        }
    }
    Some(CodecReport {
        name,
        bytes: bytes.len(),
        ratio: file.raw_bytes() as f64 / bytes.len() as f64,
        relative_error: if norm2 > 0.0 {
            (err2 / norm2).sqrt()
        } else {
            err2.sqrt()
        },
        max_abs_error: max_abs,
        decode_ms_per_frame: 1e3 * median(&mut times),
    })
}

/// The median of `values` (0 if empty).
fn median(values: &mut [f64]) -> f64 {
    values.sort_by(f64::total_cmp);
    values.get(values.len() / 2).copied().unwrap_or(0.0)
}
