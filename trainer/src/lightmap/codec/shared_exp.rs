//! Shared-exponent (RGBE-style) quantisation of a frame's SH coefficients, and the three ways
//! of keeping their signs.
//!
//! Ward's RGBE stores one 8-bit exponent for a group of values and an `m`-bit mantissa per
//! value. A group (the `n²` coefficients of a texel, or three coefficient maps at a time as the
//! paper tiles RGB) with largest magnitude `M` gets the exponent `e` with `M < 2^e`
//! (`frexp`, raised by one when `M` would round up to `2^m`), and each value `v` becomes
//! `q = round(|v| · 2^(m−e))`. Decoding gives `q · 2^(e−m)`, so
//!
//! > `|v − v̂| ≤ max(M / (2^m − ½), 2^(E_MIN − m − 1))`
//!
//! for every value of the group (half a step `2^(e−m−1)`; the step is at most
//! `2M / (2^m − ½)`), with `E_MIN = −126` the floor below which a group flushes to tiny
//! steps. Scaling by powers of two is exact in f64, so the bound holds with no rounding slack.
//!
//! Coefficients above band 0 are signed; [`SignMode`] holds three ways of keeping signs,
//! measured by `compare` on the synthetic clip (128², order 4, 40 frames; the `shlm_codecs`
//! example prints its table):
//!
//! | sign mode | independent frames, m = 7 | PCA 1 %, m = 7 |
//! | --- | --- | --- |
//! | (a) offset per map | 721 kB, 1.28 % | 244 kB, 1.43 % |
//! | (b) sign plane | 1082 kB, 0.65 % | 462 kB, 0.92 % |
//! | (c) ratio to band 0 | 486 kB, 1.64 % | 238 kB, 15.2 % |
//!
//! The sign plane has the tightest per-value bound (steps relative to each texel's own
//! magnitude) but spends bits on small texels that the L2 error hardly sees; the offset per
//! map makes the steps nearly uniform over a map, which is what an L2 metric rewards, and wins
//! on bytes against error (`offset m8` ≈ `sign plane m7` in error at 25–35 % fewer bytes).
//! Ratios to band 0 win on independent frames of real transfer but fail on PCA components,
//! which are signed fields rather than non-negative functions. Of these three, (a) is the best
//! under PCA; the default is now a fourth, (d) [`SignMode::Uniform`], which drops exponents
//! for one absolute step per map and a 2-D predictor (on real bakes, PCA 2 %: 61:1 and 93:1
//! at 2.1–2.3 % against (a) m7's 36:1 and 49:1 at 2.4–2.6 %).

/// The smallest exponent a group gets: below `2^(E_MIN−1)` values flush to steps of
/// `2^(E_MIN−m)`, which f32 still represents (denormals reach `2^−149`).
const E_MIN: i32 = -126;

use super::uniform::{self, Grid};
/// The largest exponent: f32 magnitudes are below `2^128`.
const E_MAX: i32 = 128;
/// The stored byte is `e − E_MIN`; 255 is never written and refused on reading.
const MAX_EXP_BYTE: u8 = (E_MAX - E_MIN) as u8;

/// How the signs of coefficients above band 0 survive a magnitude-only mantissa.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SignMode {
    /// (a) Subtract each map's minimum (stored as f32) so every value is ≥ 0; the bound
    /// applies to `v − min` (plus an f32 rounding of the sum). Error grows with the map's
    /// range, not the texel's magnitude: near-uniform steps, the best bytes for L2 error.
    OffsetScale,
    /// (b) Magnitudes in the mantissas, signs in a bit plane. The bound above holds per value.
    SignPlane,
    /// (c) Band 0 alone in shared-exponent form; `c_i / ĉ₀` as signed `m`-bit fixed point over
    /// `±√(2l+1)`, which bounds the ratio for any non-negative transfer function
    /// (`|c_lm| ≤ max|y_lm| · c₀ / y₀₀`). Error `≤ ĉ₀ · √(2l+1) / (2^m − 2)` plus band 0's;
    /// negative band 0 (bake noise) is clamped to 0 and takes its texel's other bands with it.
    /// Only for transfer itself: PCA components are not non-negative (15 % error measured).
    Band0Ratio,
    /// (d) No exponents: one uniform absolute step per coefficient map (stored as f32), the
    /// signed integer `round(v / step)` predicted over the `R × R` grid (LOCO-I's median edge
    /// detector) and its residual stored in two byte planes ([`super::uniform`]). Error
    /// `≤ step / 2` per value. `mantissa_bits` `m` picks the step for a relative L2 error of
    /// about `2^−m` of the plane set (PCA picks its own steps from the same `m`); grouping
    /// and spatial delta do not apply.
    Uniform,
}

/// Which coefficients of a texel share one exponent.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Grouping {
    /// All `n²` coefficients of a texel: one exponent byte per texel.
    Texel,
    /// Coefficients `3g..3g+3` of a texel, as the paper's tiles go through RGBE three maps
    /// at a time: `⌈n²/3⌉` exponent bytes per texel, each fitted more tightly.
    Triples,
}

/// The quantiser's parameters, stored in the file header.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PlaneSettings {
    /// Mantissa bits `m`, 2..=8: the quantisation step is `2^(e−m)` of the group's exponent.
    pub mantissa_bits: u8,
    /// How signs are kept.
    pub sign: SignMode,
    /// Which coefficients share an exponent (ignored by [`SignMode::Band0Ratio`], whose
    /// exponent is band 0's alone).
    pub grouping: Grouping,
    /// Store each byte plane as differences to the previous filled texel of the same plane
    /// (wrapping), so zstd sees the small residuals of a smooth map.
    pub spatial_delta: bool,
}

impl PlaneSettings {
    /// Exponent groups per texel.
    fn groups(&self, n2: usize) -> usize {
        match (self.sign, self.grouping) {
            (SignMode::Uniform, _) => 0,
            (SignMode::Band0Ratio, _) | (_, Grouping::Texel) => 1,
            (_, Grouping::Triples) => n2.div_ceil(3),
        }
    }

    /// The coefficients of group `g`.
    fn group_range(&self, g: usize, n2: usize) -> std::ops::Range<usize> {
        match (self.sign, self.grouping) {
            (SignMode::Band0Ratio, _) | (_, Grouping::Texel) => 0..n2,
            (_, Grouping::Triples) => 3 * g..(3 * g + 3).min(n2),
        }
    }

    /// Bytes of the plane set for `texels` filled texels; `None` on overflow.
    pub fn plane_bytes(&self, texels: usize, n2: usize) -> Option<usize> {
        if self.sign == SignMode::Uniform {
            return uniform::plane_bytes(texels, n2);
        }
        let values = texels.checked_mul(n2)?;
        let exps = texels.checked_mul(self.groups(n2))?;
        let extra = match self.sign {
            SignMode::OffsetScale => n2 * 4,
            SignMode::SignPlane => texels.div_ceil(8).checked_mul(n2)?,
            SignMode::Band0Ratio | SignMode::Uniform => 0,
        };
        values.checked_add(exps)?.checked_add(extra)
    }

    /// The byte planes (each `texels` long) that the spatial delta applies to: exponents and
    /// mantissas, which come after the offsets of [`SignMode::OffsetScale`].
    fn delta_span(&self, texels: usize, n2: usize) -> std::ops::Range<usize> {
        let start = if self.sign == SignMode::OffsetScale {
            n2 * 4
        } else {
            0
        };
        start..start + texels * (n2 + self.groups(n2))
    }
}

/// The exponent of a group whose largest magnitude is `max`: `max < 2^e` and `max` does not
/// round to `2^m` steps (unless `e` is already [`E_MAX`]).
fn group_exponent(max: f64, m: u32) -> i32 {
    if max < f64::from(f32::MIN_POSITIVE) / 2.0 {
        return E_MIN;
    }
    // frexp: max = f · 2^e, f in [0.5, 1); max comes from an f32, so it is an f64 normal.
    let e = ((max.to_bits() >> 52) & 0x7ff) as i32 - 1022;
    let top = (max * pow2(m as i32 - e)).round();
    let e = if top >= pow2(m as i32) && e < E_MAX {
        e + 1
    } else {
        e
    };
    e.clamp(E_MIN, E_MAX)
}

/// `2^k`, exact for the exponents used here.
fn pow2(k: i32) -> f64 {
    2f64.powi(k)
}

/// Quantises `values` (texel-major, `n2` per filled texel) into the byte planes of
/// `settings`: see the module's layout table.
pub fn encode_planes(values: &[f32], n2: usize, settings: &PlaneSettings) -> Vec<u8> {
    let texels = values.len() / n2;
    encode_planes_on(values, n2, settings, &Grid::row(texels), None)
}

/// [`encode_planes`] with the texels' grid (mode (d) predicts over it) and, for mode (d), an
/// absolute step chosen by the caller instead of the one `mantissa_bits` implies.
pub fn encode_planes_on(
    values: &[f32],
    n2: usize,
    settings: &PlaneSettings,
    grid: &Grid,
    step: Option<f64>,
) -> Vec<u8> {
    let texels = values.len() / n2;
    if settings.sign == SignMode::Uniform {
        let step = step.unwrap_or_else(|| uniform::step_for_bits(values, settings.mantissa_bits));
        return uniform::encode(values, n2, step, grid);
    }
    let mut out = Vec::with_capacity(settings.plane_bytes(texels, n2).unwrap_or(0));
    match settings.sign {
        SignMode::Band0Ratio => encode_ratio(values, n2, settings.mantissa_bits, &mut out),
        SignMode::OffsetScale | SignMode::SignPlane => {
            encode_magnitudes(values, n2, settings, &mut out)
        }
        SignMode::Uniform => unreachable!("handled above"),
    }
    if settings.spatial_delta {
        for plane in out[settings.delta_span(texels, n2)].chunks_mut(texels.max(1)) {
            for i in (1..plane.len()).rev() {
                plane[i] = plane[i].wrapping_sub(plane[i - 1]);
            }
        }
    }
    out
}

/// Modes (a) and (b): optional per-map offsets, exponent planes, mantissa planes, sign planes.
fn encode_magnitudes(values: &[f32], n2: usize, settings: &PlaneSettings, out: &mut Vec<u8>) {
    let texels = values.len() / n2;
    let m = u32::from(settings.mantissa_bits);
    let offsets: Vec<f32> = match settings.sign {
        SignMode::OffsetScale => (0..n2)
            .map(|c| {
                values
                    .iter()
                    .skip(c)
                    .step_by(n2)
                    .fold(0f32, |a, &v| a.min(v))
            })
            .collect(),
        _ => vec![0.0; n2],
    };
    if settings.sign == SignMode::OffsetScale {
        offsets
            .iter()
            .for_each(|o| out.extend_from_slice(&o.to_le_bytes()));
    }
    let groups = settings.groups(n2);
    let base = out.len();
    out.resize(base + texels * (groups + n2), 0);
    let mut signs = vec![0u8; texels.div_ceil(8) * n2];
    let (exps, mants) = out[base..].split_at_mut(texels * groups);
    let qmax = f64::from((1u32 << m) - 1);
    for (t, texel) in values.chunks_exact(n2).enumerate() {
        for g in 0..groups {
            let range = settings.group_range(g, n2);
            let mag = |c: usize| (f64::from(texel[c]) - f64::from(offsets[c])).abs();
            let max = range.clone().map(mag).fold(0.0, f64::max);
            let e = group_exponent(max, m);
            exps[g * texels + t] = (e - E_MIN) as u8;
            let scale = pow2(m as i32 - e);
            for c in range {
                let q = (mag(c) * scale).round().min(qmax) as u8;
                mants[c * texels + t] = q;
                // No sign for a zero mantissa: noise-only bands would fill the plane with
                // random bits.
                if q != 0 && texel[c] < offsets[c] {
                    signs[c * texels.div_ceil(8) + t / 8] |= 1 << (t % 8);
                }
            }
        }
    }
    if settings.sign == SignMode::SignPlane {
        out.extend_from_slice(&signs);
    }
}

/// Mode (c): band 0's exponent plane and mantissa plane, then `n²−1` ratio planes.
fn encode_ratio(values: &[f32], n2: usize, bits: u8, out: &mut Vec<u8>) {
    let texels = values.len() / n2;
    let m = u32::from(bits);
    let s = f64::from((1i32 << (m - 1)) - 1);
    let base = out.len();
    out.resize(base + texels * (n2 + 1), 0);
    let (exps, planes) = out[base..].split_at_mut(texels);
    for (t, texel) in values.chunks_exact(n2).enumerate() {
        let c0 = f64::from(texel[0]).max(0.0);
        let e = group_exponent(c0, m);
        exps[t] = (e - E_MIN) as u8;
        let q0 = (c0 * pow2(m as i32 - e))
            .round()
            .min(f64::from((1u32 << m) - 1));
        planes[t] = q0 as u8;
        let c0_hat = q0 * pow2(e - m as i32);
        for c in 1..n2 {
            let range = band_range(c);
            let r = if c0_hat > 0.0 {
                f64::from(texel[c]) / c0_hat
            } else {
                0.0
            };
            let q = (r / range * s).round().clamp(-s, s);
            planes[c * texels + t] = (q + s) as u8;
        }
    }
}

/// `√(2l+1)`: the largest `|c_lm / c₀|` of a non-negative function, `l` the band of `c`.
fn band_range(c: usize) -> f64 {
    let l = aprt_core::band_of(c);
    ((2 * l + 1) as f64).sqrt()
}

/// Inverts [`encode_planes`] into `out` (`texels · n2` values, texel-major). The planes are
/// undone in place (`planes` is scratch). Exponent bytes no encoder writes are refused.
pub fn decode_planes(
    planes: &mut [u8],
    n2: usize,
    settings: &PlaneSettings,
    out: &mut [f32],
) -> Result<(), String> {
    decode_planes_on(planes, n2, settings, &Grid::row(out.len() / n2.max(1)), out)
}

/// [`decode_planes`] over the texels' grid (which mode (d) predicts over; it must be the
/// encoder's).
pub fn decode_planes_on(
    planes: &mut [u8],
    n2: usize,
    settings: &PlaneSettings,
    grid: &Grid,
    out: &mut [f32],
) -> Result<(), String> {
    let texels = out.len() / n2;
    if settings.sign == SignMode::Uniform {
        return uniform::decode(planes, n2, grid, out);
    }
    if settings.plane_bytes(texels, n2) != Some(planes.len()) || out.len() != texels * n2 {
        return Err("plane set size does not match the header".into());
    }
    if settings.spatial_delta {
        for plane in planes[settings.delta_span(texels, n2)].chunks_mut(texels.max(1)) {
            for i in 1..plane.len() {
                plane[i] = plane[i].wrapping_add(plane[i - 1]);
            }
        }
    }
    let m = i32::from(settings.mantissa_bits);
    // scales[b]: the step 2^(e−m) of exponent byte b, exact in f32 (down to 2^−134).
    let scales: Vec<f32> = (0..=MAX_EXP_BYTE)
        .map(|b| pow2(i32::from(b) + E_MIN - m) as f32)
        .collect();
    let groups = settings.groups(n2);
    if planes[settings.delta_span(texels, n2)][..texels * groups]
        .iter()
        .any(|&b| b > MAX_EXP_BYTE)
    {
        return Err("exponent byte out of range".into());
    }
    match settings.sign {
        SignMode::Band0Ratio => decode_ratio(planes, n2, m, &scales, out),
        SignMode::OffsetScale | SignMode::SignPlane => {
            decode_magnitudes(planes, n2, settings, &scales, out)
        }
        SignMode::Uniform => unreachable!("handled above"),
    }
}

/// Modes (a) and (b).
fn decode_magnitudes(
    planes: &[u8],
    n2: usize,
    settings: &PlaneSettings,
    scales: &[f32],
    out: &mut [f32],
) -> Result<(), String> {
    let texels = out.len() / n2;
    let (offsets, rest) = match settings.sign {
        SignMode::OffsetScale => planes.split_at(n2 * 4),
        _ => planes.split_at(0),
    };
    let offsets: Vec<f32> = offsets
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    if offsets.iter().any(|o| !o.is_finite()) {
        return Err("non-finite map offset".into());
    }
    let groups = settings.groups(n2);
    let (exps, rest) = rest.split_at(texels * groups);
    let (mants, signs) = rest.split_at(texels * n2);
    let sign_stride = texels.div_ceil(8);
    let signed = settings.sign == SignMode::SignPlane;
    // Texel-major, so `out` is written once in order while the planes stream alongside.
    for (t, texel) in out.chunks_exact_mut(n2).enumerate() {
        for g in 0..groups {
            let scale = scales[usize::from(exps[g * texels + t])];
            for c in settings.group_range(g, n2) {
                let mag = f32::from(mants[c * texels + t]) * scale;
                let negative = signed && signs[c * sign_stride + t / 8] & (1 << (t % 8)) != 0;
                let off = offsets.get(c).copied().unwrap_or(0.0);
                texel[c] = if negative { -mag } else { mag } + off;
            }
        }
    }
    Ok(())
}

/// Mode (c).
fn decode_ratio(
    planes: &[u8],
    n2: usize,
    m: i32,
    scales: &[f32],
    out: &mut [f32],
) -> Result<(), String> {
    let texels = out.len() / n2;
    let (exps, planes) = planes.split_at(texels);
    let s = ((1i32 << (m - 1)) - 1) as f32;
    let steps: Vec<f32> = (0..n2).map(|c| band_range(c) as f32 / s).collect();
    for (t, texel) in out.chunks_exact_mut(n2).enumerate() {
        let c0 = f32::from(planes[t]) * scales[usize::from(exps[t])];
        texel[0] = c0;
        for c in 1..n2 {
            let q = (f32::from(planes[c * texels + t]) - s).min(s);
            texel[c] = c0 * q * steps[c];
        }
    }
    Ok(())
}
