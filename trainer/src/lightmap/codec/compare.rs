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

/// Every variant worth comparing, by name: the shared-exponent quantiser's sign modes at equal
/// mantissa bits, the uniform quantiser's steps on independent frames, keyframe intervals,
/// PCA error targets under both quantisers. (Trimmed to what decides the default: each row
/// costs a full encode and decode of the clip.)
fn variants() -> Vec<(String, CodecSettings)> {
    let planes = |bits: u8, sign: SignMode| PlaneSettings {
        mantissa_bits: bits,
        sign,
        grouping: Grouping::Texel,
        spatial_delta: true,
    };
    let with = |kind: CodecKind, p: PlaneSettings| CodecSettings {
        kind,
        planes: p,
        ..CodecSettings::default()
    };
    let pca = |target: f32| CodecKind::Pca {
        target_error: target,
        max_components: 32,
    };
    let mut out = Vec::new();
    let signs = [
        ("offset-per-map", SignMode::OffsetScale),
        ("sign-plane", SignMode::SignPlane),
        ("band0-ratio", SignMode::Band0Ratio),
    ];
    for bits in [8, 6] {
        for (label, sign) in signs {
            out.push((
                format!("frames m{bits} {label}"),
                with(CodecKind::Frames, planes(bits, sign)),
            ));
        }
    }
    out.push((
        "frames m8 sign-plane triples".into(),
        with(
            CodecKind::Frames,
            PlaneSettings {
                grouping: Grouping::Triples,
                ..planes(8, SignMode::SignPlane)
            },
        ),
    ));
    for bits in [7, 6, 5] {
        out.push((
            format!("frames uniform m{bits}"),
            with(CodecKind::Frames, planes(bits, SignMode::Uniform)),
        ));
    }
    for interval in [2, 4] {
        let kind = CodecKind::Keyframes { interval };
        out.push((
            format!("keyframes K={interval} uniform m6"),
            with(kind, planes(6, SignMode::Uniform)),
        ));
    }
    for (target, bits) in [(0.01, 8), (0.02, 7)] {
        let name = format!("pca {}% m{bits} offset-per-map", target * 100.0);
        out.push((name, with(pca(target), planes(bits, SignMode::OffsetScale))));
    }
    out.push((
        "pca 1% m7 sign-plane".into(),
        with(pca(0.01), planes(7, SignMode::SignPlane)),
    ));
    for (target, bits) in [(0.01, 7), (0.015, 7), (0.015, 6), (0.02, 6), (0.02, 5)] {
        let name = format!("pca {}% uniform m{bits}", target * 100.0);
        out.push((name, with(pca(target), planes(bits, SignMode::Uniform))));
    }
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
