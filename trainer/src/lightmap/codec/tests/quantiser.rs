//! The shared-exponent quantiser against its documented bounds, on adversarial values.

use crate::lightmap::codec::shared_exp::{decode_planes, encode_planes};
use crate::lightmap::codec::{Grouping, PlaneSettings, SignMode};

/// `2^(E_MIN − m − 1)`: the absolute floor of the bound.
fn floor(m: u8) -> f64 {
    2f64.powi(-126 - i32::from(m) - 1)
}

fn round_trip(values: &[f32], n2: usize, settings: &PlaneSettings) -> Vec<f32> {
    let mut planes = encode_planes(values, n2, settings);
    let mut out = vec![f32::NAN; values.len()];
    decode_planes(&mut planes, n2, settings, &mut out).expect("own planes decode");
    out
}

/// Groups of `n2 = 4` that stress the exponent: tiny, denormal, huge, mixed signs, zeros.
fn adversarial() -> Vec<[f32; 4]> {
    let d = f32::from_bits(1); // the smallest denormal
    vec![
        [0.0, 0.0, -0.0, 0.0],
        [1e-30, -1e-31, 3e-32, 0.0],
        [d, -d, 7.0 * d, 1e-40],
        [f32::MIN_POSITIVE, -f32::MIN_POSITIVE / 3.0, 0.0, 1e-39],
        [f32::MAX, -f32::MAX, 1e38, -1.0],
        [3e38, 1.0, -1e-20, 2.5e38],
        [1.0, -0.999, 0.001, -1e-7],
        [0.999_999_9, -0.5, 0.25, 0.0],
        [255.5, -127.25, 1.0, 0.0], // rounds up past 2^m steps at m = 8
        [-1e6, 3.0, -2.0, 1e-3],
    ]
}

/// Signs in a bit plane: every value within `max(M / (2^m − ½), floor)` of its group's
/// largest magnitude `M`, for every grouping and mantissa width.
#[test]
fn sign_plane_is_within_its_bound() {
    for grouping in [Grouping::Texel, Grouping::Triples] {
        for m in 2..=8u8 {
            let settings = PlaneSettings {
                mantissa_bits: m,
                sign: SignMode::SignPlane,
                grouping,
                spatial_delta: m % 2 == 0,
            };
            let values: Vec<f32> = adversarial().into_iter().flatten().collect();
            let back = round_trip(&values, 4, &settings);
            for (g, (v, b)) in values.chunks(4).zip(back.chunks(4)).enumerate() {
                let groups: Vec<&[f32]> = match grouping {
                    Grouping::Texel => vec![v],
                    Grouping::Triples => vec![&v[..3], &v[3..]],
                };
                let mut at = 0;
                for group in groups {
                    let max = group.iter().map(|x| f64::from(x.abs())).fold(0.0, f64::max);
                    let bound = (max / (2f64.powi(i32::from(m)) - 0.5)).max(floor(m));
                    for (x, y) in group.iter().zip(&b[at..]) {
                        let err = (f64::from(*x) - f64::from(*y)).abs();
                        assert!(
                            err <= bound,
                            "m={m} {grouping:?} group {g}: {x} -> {y}, {err} > {bound}"
                        );
                        assert!(y.is_finite());
                    }
                    at += group.len();
                }
            }
        }
    }
}

/// Values on the quantiser's grid come back bit for bit.
#[test]
fn representable_values_are_exact() {
    let settings = PlaneSettings {
        mantissa_bits: 8,
        sign: SignMode::SignPlane,
        grouping: Grouping::Texel,
        spatial_delta: true,
    };
    let values = [
        1.0, -0.5, 0.25, 0.0, 0.75, -0.0078125, 0.9921875, -0.375, 0.0, 64.0, -32.5, 1.5,
    ];
    assert_eq!(round_trip(&values, 4, &settings), values);
}

/// The offset per map: the bound is relative to the group's largest `v − offset`, which is
/// why it loses to the sign plane on signed bands (the `compare` table measures how much).
#[test]
fn offset_per_map_is_within_its_bound() {
    let values: Vec<f32> = adversarial()
        .into_iter()
        .skip(1)
        .take(3)
        .flatten()
        .chain([0.9, -0.4, 0.3, -0.1, 0.5, 0.2, -0.3, 0.05])
        .collect();
    let m = 8;
    let settings = PlaneSettings {
        mantissa_bits: m,
        sign: SignMode::OffsetScale,
        grouping: Grouping::Texel,
        spatial_delta: false,
    };
    let back = round_trip(&values, 4, &settings);
    let offsets: Vec<f64> = (0..4)
        .map(|c| {
            values
                .iter()
                .skip(c)
                .step_by(4)
                .map(|&x| f64::from(x))
                .fold(0.0, f64::min)
        })
        .collect();
    for (v, b) in values.chunks(4).zip(back.chunks(4)) {
        let max = (0..4)
            .map(|c| f64::from(v[c]) - offsets[c])
            .fold(0.0, f64::max);
        for c in 0..4 {
            let bound = (max / (2f64.powi(i32::from(m)) - 0.5)).max(floor(m))
                + f64::from(f32::EPSILON) * (max + offsets[c].abs());
            let err = (f64::from(v[c]) - f64::from(b[c])).abs();
            assert!(err <= bound, "{} -> {}: {err} > {bound}", v[c], b[c]);
        }
    }
}

/// Ratios to band 0 on transfer-like vectors (non-negative functions, so `|c_i/c₀| ≤ √(2l+1)`):
/// error `≤ ĉ₀ √(2l+1) / (2^m − 2) + |c_i / c₀| · |c₀ − ĉ₀|`.
#[test]
fn band0_ratio_is_within_its_bound() {
    let order = 4;
    let mut values = Vec::new();
    for (i, scale) in [1e-30f32, 1e-3, 0.3, 1.0, 7.5, 1e20, 0.0]
        .iter()
        .enumerate()
    {
        let mut lobe = [0f32; 16];
        let angle = i as f32;
        aprt_core::clamped_cosine(order, [angle.cos(), 0.3, angle.sin()], &mut lobe)
            .expect("unit normal");
        values.extend(lobe.iter().map(|x| x * scale));
    }
    for m in 2..=8u8 {
        let settings = PlaneSettings {
            mantissa_bits: m,
            sign: SignMode::Band0Ratio,
            grouping: Grouping::Texel,
            spatial_delta: true,
        };
        let back = round_trip(&values, 16, &settings);
        let s = f64::from((1u32 << (m - 1)) - 1);
        for (v, b) in values.chunks(16).zip(back.chunks(16)) {
            let (c0, c0_hat) = (f64::from(v[0]), f64::from(b[0]));
            let bound0 = (c0 / (2f64.powi(i32::from(m)) - 0.5)).max(floor(m));
            assert!((c0 - c0_hat).abs() <= bound0, "band 0: {c0} -> {c0_hat}");
            for c in 1..16 {
                let range = ((2 * aprt_core::band_of(c) + 1) as f64).sqrt();
                let ratio = if c0 > 0.0 {
                    f64::from(v[c]).abs() / c0
                } else {
                    0.0
                };
                let bound = c0_hat * range / (2.0 * s) * (1.0 + 1e-6)
                    + ratio * (c0 - c0_hat).abs()
                    + floor(m);
                let err = (f64::from(v[c]) - f64::from(b[c])).abs();
                assert!(
                    err <= bound,
                    "m={m} c={c}: {} -> {}: {err} > {bound}",
                    v[c],
                    b[c]
                );
            }
        }
    }
}

/// Mode (d): every value within half its map's step (plus the f32 rounding of `q · step`),
/// over a grid with holes (every predictor case), for given steps and for `m`'s step; the
/// adversarial values decode finite.
#[test]
fn uniform_is_within_half_a_step() {
    use crate::lightmap::codec::shared_exp::{decode_planes_on, encode_planes_on};
    use crate::lightmap::codec::uniform::Grid;
    let r = 9;
    let texels: Vec<usize> = (0..r * r).filter(|t| (t * 7) % 5 != 1).collect();
    let grid = Grid::new(&texels, r);
    let n2 = 4;
    let smooth: Vec<f32> = texels
        .iter()
        .flat_map(|&t| {
            let (x, y) = ((t % r) as f32, (t / r) as f32);
            [
                1.0 + 0.1 * x,
                -0.3 * y + 0.02 * x * y,
                (x - y).sin(),
                1e-4 * x,
            ]
        })
        .collect();
    let mut adversarial: Vec<f32> = adversarial().into_iter().flatten().collect();
    adversarial.resize(smooth.len(), 0.5);
    for values in [smooth, adversarial] {
        for (m, step) in [(6u8, None), (3, None), (8, Some(1e-3)), (8, Some(0.0))] {
            let settings = PlaneSettings {
                mantissa_bits: m,
                sign: SignMode::Uniform,
                grouping: Grouping::Texel,
                spatial_delta: false,
            };
            let mut planes = encode_planes_on(&values, n2, &settings, &grid, step);
            assert_eq!(Some(planes.len()), settings.plane_bytes(texels.len(), n2));
            let steps: Vec<f64> = planes[..n2 * 4]
                .chunks_exact(4)
                .map(|b| f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])))
                .collect();
            let mut out = vec![f32::NAN; values.len()];
            decode_planes_on(&mut planes, n2, &settings, &grid, &mut out).expect("decodes");
            for (i, (&v, &d)) in values.iter().zip(&out).enumerate() {
                assert!(d.is_finite(), "{v} -> {d}");
                if v.abs() > 1e38 {
                    continue; // clamped so that q · step stays finite
                }
                let err = (f64::from(v) - f64::from(d)).abs();
                let bound = 0.5 * steps[i % n2] + f64::from(v.abs()) * 2e-7 + 1e-45;
                assert!(err <= bound, "m={m} {step:?}: {v} -> {d}: {err} > {bound}");
            }
        }
    }
}

/// Mode (d) refuses integers past what the encoder writes (`|q| ≤ 2^14 − 1`), so PCA
/// components fit the decoder's 16-bit storage.
#[test]
fn uniform_refuses_out_of_range_integers() {
    use crate::lightmap::codec::shared_exp::decode_planes_on;
    use crate::lightmap::codec::uniform::Grid;
    let settings = PlaneSettings {
        mantissa_bits: 7,
        sign: SignMode::Uniform,
        grouping: Grouping::Texel,
        spatial_delta: false,
    };
    let grid = Grid::row(2);
    // Residual +16383 twice (zigzag 0x7ffe): the second texel reaches 32766.
    let mut planes = [1f32.to_le_bytes().as_slice(), &[0xfe, 0xfe, 0x7f, 0x7f]].concat();
    let mut out = [0f32; 2];
    assert!(decode_planes_on(&mut planes, 1, &settings, &grid, &mut out).is_err());
    // Second residual 0 (its low byte at 5, its high byte at 7): both texels 16383, in range.
    planes[5] = 0;
    planes[7] = 0;
    decode_planes_on(&mut planes, 1, &settings, &grid, &mut out).expect("in range");
    assert_eq!(out, [16383.0, 16383.0]);
}
