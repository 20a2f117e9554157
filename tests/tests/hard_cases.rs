//! Hard numerical cases that cross the trainer → blob → core boundary.

use aprt_core::{Model, PoseWeights};
use aprt_trainer::{ExportError, LinearModel, Precision, VertexBasis, encode_model};

/// A model whose transfer is the constant `values` (order 1, one coefficient per vertex, no
/// pose dimensions): what the core returns is exactly what the f16 section stored.
fn constant_model(values: &[f64]) -> LinearModel {
    LinearModel {
        order: 1,
        vertices: values.len(),
        pose_len: 1,
        pose_mean: vec![0.0],
        pose_projection: Vec::new(),
        weights: values.to_vec(),
        basis: VertexBasis::Identity,
        alpha: 0.0,
        bones: None,
        angle_names: Vec::new(),
        bounds: None,
        cosines: Vec::new(),
        proxies: None,
    }
}

/// f16 sections with a large dynamic range. Expected (the documented bound of
/// `Precision::F16`): round to nearest, so within 2⁻¹¹ relative in the normal range
/// (down to 6.1e-5) and 2⁻²⁵ absolute among the subnormals, where values under 3e-8 become 0;
/// 65504 is the largest finite value and 65519 still rounds down to it, while 65520 rounds to
/// infinity and the export fails, naming the section and the index, instead of clamping.
#[test]
fn f16_sections_keep_the_documented_bound_and_refuse_overflow() {
    let values = [
        65504.0,
        -65504.0,
        65519.0,
        1.0 + 1.0 / 2048.0,
        std::f64::consts::PI,
        6.103_515_625e-5,
        1e-5,
        1e-7,
        -1e-7,
        2.9e-8,
        1e-30,
        0.0,
    ];
    let blob = encode_model(&constant_model(&values), Precision::F16).unwrap();
    let model = Model::parse(&blob).unwrap();
    let mut pose = PoseWeights::new();
    model.set_pose(&[0.3], &mut pose).unwrap();
    let mut got = vec![0.0f32; values.len()];
    model.transfer(&pose, 0, &mut got).unwrap();
    for (&want, &got) in values.iter().zip(&got) {
        let bound = (want.abs() * 2f64.powi(-11)).max(2f64.powi(-25));
        let err = (f64::from(got) - want).abs();
        assert!(
            got.is_finite() && err <= bound,
            "{want:e} stored as {got:e}"
        );
    }
    assert_eq!(got[2], 65504.0);
    assert_eq!((got[9], got[10]), (0.0, 0.0));

    for (index, too_big) in [(3, 65520.0), (1, -1e6), (0, f64::INFINITY)] {
        let mut v = values;
        v[index] = too_big;
        let err = encode_model(&constant_model(&v), Precision::F16).unwrap_err();
        assert!(
            matches!(err, ExportError::NotRepresentable { index: i, .. } if i == index),
            "{err}"
        );
        assert!(err.to_string().contains("±65504 for f16"), "{err}");
    }
    // f32 takes what f16 cannot.
    let mut v = values;
    v[3] = 1e6;
    assert!(encode_model(&constant_model(&v), Precision::F32).is_ok());
}

/// Angles and pose means at opposite ends of the f32 range. `2¹⁰³ − (−f32::MAX)` rounds up
/// to infinity in f32 (it is half an ulp above `f32::MAX`, with an odd mantissa), and a zero
/// projection weight times infinity is NaN, although the exact pose projection ignores that
/// joint. Expected: the core forms the centred angles in f64, so the transfer is the exact
/// `c₀ + c₁·z` with `z = 0.5` from the other joint. (Found by the `round_trip` proptest.)
#[test]
fn a_joint_the_projection_ignores_cannot_overflow_the_pose() {
    let model = LinearModel {
        order: 1,
        vertices: 1,
        pose_len: 2,
        pose_mean: vec![-f64::from(f32::MAX), 0.0],
        pose_projection: vec![0.0, 1.0],
        weights: vec![0.25, 2.0],
        basis: VertexBasis::Identity,
        alpha: 0.0,
        bones: None,
        angle_names: Vec::new(),
        bounds: None,
        cosines: Vec::new(),
        proxies: None,
    };
    let blob = encode_model(&model, Precision::F32).unwrap();
    let core = Model::parse(&blob).unwrap();
    let mut pose = PoseWeights::new();
    core.set_pose(&[2f32.powi(103), 0.5], &mut pose).unwrap();
    let mut got = [0.0f32; 1];
    core.transfer(&pose, 0, &mut got).unwrap();
    assert_eq!(got[0], 0.25 + 2.0 * 0.5);
}
