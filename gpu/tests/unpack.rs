//! `unpack` on the device against the CPU, bit for bit: widening f16 to f32 is exact and an
//! i8 times its row's f32 scale is rounded once, so the device has no slack to use.

mod common;

use aprt_gpu::{Packed, UnpackError, unpack};
use common::gpu_or_skip;
use half::f16;

/// The f16 bit patterns of every finite value, subnormals and both zeros included (WGSL leaves
/// infinities and NaNs of `unpack2x16float` to the implementation).
fn finite_f16_bits() -> Vec<u16> {
    (0..=u16::MAX)
        .filter(|&bits| f16::from_bits(bits).is_finite())
        .collect()
}

fn widened_on_the_cpu(bits: &[u16]) -> Vec<u32> {
    bits.iter()
        .map(|&b| f16::from_bits(b).to_f32().to_bits())
        .collect()
}

fn scaled_on_the_cpu(values: &[i8], row_len: usize, scales: &[f32]) -> Vec<u32> {
    values
        .iter()
        .enumerate()
        .map(|(i, &v)| (f32::from(v) * scales[i / row_len]).to_bits())
        .collect()
}

fn bits(values: &[f32]) -> Vec<u32> {
    values.iter().map(|v| v.to_bits()).collect()
}

#[test]
fn unpack_widens_f16_and_scales_i8_as_the_cpu_does() {
    let Some(gpu) = gpu_or_skip("unpack_widens_f16_and_scales_i8_as_the_cpu_does") else {
        return;
    };
    let f16_bits = finite_f16_bits();
    // Every i8 value, in rows of 7 so rows straddle the shader's 4-value words, and a last
    // word of 3 values.
    let row_len = 7;
    let i8_values: Vec<i8> = (0..259).map(|i| (i % 256) as u8 as i8).collect();
    let i8_scales: Vec<f32> = (0..i8_values.len() / row_len)
        .map(|row| match row {
            0 => 1.0,
            1 => 1.0 / 127.0,
            _ => (row as f32 * 0.37).sin() * 10f32.powi(row as i32 % 9 - 4),
        })
        .collect();
    let packed = Packed {
        f16_bits: &f16_bits,
        i8_values: &i8_values,
        i8_row_len: row_len,
        i8_scales: &i8_scales,
    };
    let out = unpack(&gpu, &packed).unwrap();
    assert_eq!(bits(&out.from_f16), widened_on_the_cpu(&f16_bits));
    assert_eq!(
        bits(&out.from_i8),
        scaled_on_the_cpu(&i8_values, row_len, &i8_scales)
    );

    // An odd f16 count (the last word half padding) and no i8 rows at all.
    let odd = &f16_bits[1000..1003];
    let packed = Packed {
        f16_bits: odd,
        i8_values: &[],
        i8_row_len: 0,
        i8_scales: &[],
    };
    let out = unpack(&gpu, &packed).unwrap();
    assert_eq!(bits(&out.from_f16), widened_on_the_cpu(odd));
    assert!(out.from_i8.is_empty());
}

#[test]
fn unpack_dispatches_in_2d_past_65535_workgroups() {
    let Some(gpu) = gpu_or_skip("unpack_dispatches_in_2d_past_65535_workgroups") else {
        return;
    };
    // 65,535 workgroups of 64 words and a few more: the grid needs a second row.
    let words = 65_535 * 64 + 100;
    let finite = finite_f16_bits();
    let f16_bits: Vec<u16> = finite.iter().copied().cycle().take(words * 2).collect();
    let packed = Packed {
        f16_bits: &f16_bits,
        i8_values: &[],
        i8_row_len: 0,
        i8_scales: &[],
    };
    let out = unpack(&gpu, &packed).unwrap();
    assert!(bits(&out.from_f16) == widened_on_the_cpu(&f16_bits));
}

#[test]
fn unpack_refuses_i8_values_that_are_not_whole_rows() {
    let Some(gpu) = gpu_or_skip("unpack_refuses_i8_values_that_are_not_whole_rows") else {
        return;
    };
    for (values, row_len, scales) in [(10, 4, 3), (8, 4, 3), (8, 4, 1), (4, 0, 1), (0, 0, 1)] {
        let packed = Packed {
            f16_bits: &[],
            i8_values: &vec![1; values],
            i8_row_len: row_len,
            i8_scales: &vec![1.0; scales],
        };
        assert!(
            matches!(
                unpack(&gpu, &packed),
                Err(UnpackError::Rows { values: v, row_len: r, scales: s })
                    if (v, r, s) == (values, row_len, scales)
            ),
            "{values} values in rows of {row_len} with {scales} scales"
        );
    }
}
