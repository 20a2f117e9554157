//! `--precision i8` on a model trained from the built-in character (order 2, 32 rays, every
//! 10th training frame, as in `quality.rs`): on novel poses its shading differs from the f32
//! model's by at most the bound `Precision::I8` states, `Σ_k |w_k| s_k / 2` with `w_k` the
//! lighting weights and `s_k` the stored scales, and the bound is not vacuous.

use aprt_core::format::read_header;
use aprt_core::{LitWeights, Model, PoseWeights, SectionKind, project_directional};
use aprt_trainer::{
    BakeSettings, Character, FitOptions, LinearModel, Precision, Rig, Silent, VertexBasis,
    bake_poses, encode_model, fit,
};
use nalgebra::DMatrix;

/// The stored scales of an i8 blob.
fn scales(blob: &[u8]) -> Vec<f64> {
    let header = read_header(blob).unwrap();
    let e = header
        .sections
        .iter()
        .find(|e| e.kind == SectionKind::RowScales.tag())
        .expect("an i8 blob holds its scales");
    blob[e.offset as usize..(e.offset + e.len) as usize]
        .chunks_exact(4)
        .map(|w| f64::from(f32::from_le_bytes(w.try_into().unwrap())))
        .collect()
}

/// Shading of every vertex at `angles` under `lighting`, and the projected pose.
fn shade(blob: &[u8], angles: &[f32], lighting: &[f32]) -> (Vec<f32>, Vec<f64>) {
    let model = Model::parse(blob).unwrap();
    let (mut pose, mut lit) = (PoseWeights::new(), LitWeights::new());
    model.set_pose(angles, &mut pose).unwrap();
    model.light(&pose, lighting, &[], &mut lit).unwrap();
    let mut out = vec![0.0; model.info().vertices()];
    model.shade(&lit, 0, &mut out).unwrap();
    let z = pose.projected().iter().map(|&x| f64::from(x)).collect();
    (out, z)
}

/// The lighting weights `w_k = Σ_c L_c Σ_i z'_i W[c][i][k]` of the model at projected pose `z`.
fn lighting_weights(m: &LinearModel, z: &[f64], lighting: &[f32]) -> Vec<f64> {
    let VertexBasis::Stored { coef_dims: kv, .. } = m.basis else {
        panic!("the default fit stores a basis")
    };
    let z1: Vec<f64> = std::iter::once(1.0).chain(z.iter().copied()).collect();
    (0..kv)
        .map(|k| {
            lighting
                .iter()
                .enumerate()
                .map(|(c, &l)| {
                    let w: f64 = z1
                        .iter()
                        .enumerate()
                        .map(|(i, zi)| zi * m.weights[(c * z1.len() + i) * kv + k])
                        .sum();
                    f64::from(l) * w
                })
                .sum()
        })
        .collect()
}

#[test]
fn i8_shading_is_within_its_bound_of_f32() {
    let character = Character::builtin();
    let settings = BakeSettings {
        order: 2,
        rays: 32,
        bounces: 0,
        albedo: 0.0,
        shadows: true,
    };
    let train: Vec<Vec<f64>> = character
        .training_clip()
        .frames
        .into_iter()
        .step_by(10)
        .collect();
    let meshes: Vec<_> = train.iter().map(|a| character.pose(a).unwrap()).collect();
    let truth = bake_poses(&meshes, &settings, &Silent).unwrap();
    let angles = DMatrix::from_fn(train.len(), train[0].len(), |i, j| train[i][j]);
    let model = fit(&angles, &truth, settings.order, &FitOptions::default())
        .unwrap()
        .model;
    let (f32_blob, i8_blob) = (
        encode_model(&model, Precision::F32).unwrap(),
        encode_model(&model, Precision::I8).unwrap(),
    );
    assert!(
        i8_blob.len() * 2 < f32_blob.len(),
        "the rows dominate a blob"
    );
    let s = scales(&i8_blob);
    let mut lighting = [0.0f32; 4];
    project_directional(2, [0.3, -0.5, 0.8], 2.5, &mut lighting).unwrap();
    let (mut worst, mut worst_bound) = (0.0f64, 0.0f64);
    for frame in character.clip("wave").unwrap().frames.iter().step_by(6) {
        let a: Vec<f32> = frame.iter().map(|&x| x as f32).collect();
        let (reference, z) = shade(&f32_blob, &a, &lighting);
        let (quantised, _) = shade(&i8_blob, &a, &lighting);
        let w = lighting_weights(&model, &z, &lighting);
        let bound: f64 = w.iter().zip(&s).map(|(w, s)| w.abs() * s / 2.0).sum();
        // f32 rounding of both evaluations: far below the quantisation (127 levels).
        let slack = 1e-5
            * w.iter()
                .zip(&s)
                .map(|(w, s)| w.abs() * s * 127.0)
                .sum::<f64>();
        for (r, q) in reference.iter().zip(&quantised) {
            let error = f64::from(r - q).abs();
            assert!(error <= bound + slack, "{error} > {bound}");
            worst = worst.max(error);
        }
        worst_bound = worst_bound.max(bound);
    }
    eprintln!("i8 shading: worst error {worst:.3e}, bound {worst_bound:.3e}");
    assert!(
        worst > 0.0 && worst < worst_bound,
        "the test measures quantisation"
    );
}
