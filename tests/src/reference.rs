//! Judges the core's f32 evaluation against the trainer's f64 `LinearModel::predict`, with
//! error bounds derived from the magnitudes involved rather than a fixed tolerance: fuzzed
//! models span many orders of magnitude, and a fixed tolerance would either miss real errors
//! on small values or fail on honest rounding of large ones.

use crate::quadrature::QuadratureRotation;
use aprt_trainer::{LinearModel, VertexBasis};

use crate::harness::Evaluation;

/// Relative rounding of binary16 (2⁻¹¹) and its absolute rounding below the normal range (half
/// the smallest subnormal, 2⁻²⁵): the most a value moves when stored in half precision.
pub fn f16_rounding(x: f64) -> f64 {
    x.abs() * f64::powi(2.0, -11) + f64::powi(2.0, -25)
}

/// `predict` of the model with every value replaced by a magnitude: `|x|` in the pose
/// sections, `big(|x|)` in the weights and per-vertex rows (the sections a writer may store in
/// half precision), and the pose mean folded into the features as `|φ(a)| + |μ|`. Every product in
/// `predict` becomes a product of magnitudes, so with `big = |x| ↦ |x|` each value bounds the
/// sum of the absolute terms of the matching transfer value, and with `big = |x| ↦ |x| + e(x)`
/// the difference to that bounds the effect of perturbing every big value by at most `e`.
pub fn magnitude(model: &LinearModel, angles: &[f64], big: impl Fn(f64) -> f64) -> Vec<f64> {
    let abs = |xs: &[f64]| xs.iter().map(|x| x.abs()).collect::<Vec<_>>();
    // The features of the bounded pose become the pose vector of a model without cosines.
    let f = model.feature_len();
    let m = LinearModel {
        pose_len: f,
        pose_mean: vec![0.0; f],
        pose_projection: abs(&model.pose_projection),
        weights: model.weights.iter().map(|x| big(x.abs())).collect(),
        basis: match &model.basis {
            VertexBasis::Identity => VertexBasis::Identity,
            VertexBasis::Stored { coef_dims, data } => VertexBasis::Stored {
                coef_dims: *coef_dims,
                data: data.iter().map(|x| big(x.abs())).collect(),
            },
        },
        // The magnitudes of the bounded pose: the bound itself is not a sum of products.
        bounds: None,
        cosines: Vec::new(),
        proxies: None,
        angle_names: Vec::new(),
        ..model.clone()
    };
    let bounded = model.bounds.as_ref().map(|b| b.apply(angles));
    let features = model.features().of(bounded.as_deref().unwrap_or(angles));
    let a: Vec<f64> = features
        .iter()
        .zip(&model.pose_mean)
        .map(|(a, m)| a.abs() + m.abs())
        .collect();
    m.predict(&a)
}

fn max_abs(xs: &[f64]) -> f64 {
    xs.iter().fold(0.0, |m, x| m.max(x.abs()))
}

/// Rounding steps along the longest chain of f32 operations from the inputs to one shading
/// value (subtraction of the mean, projection, weights, lighting, basis, rotation).
fn steps(model: &LinearModel) -> usize {
    let n2 = model.order * model.order;
    let kv = match model.basis {
        VertexBasis::Stored { coef_dims, .. } => coef_dims,
        VertexBasis::Identity => 0,
    };
    // The bounded pose is rounded to f32 once more than the angles; a cosine feature (a sine,
    // a square) takes a few steps more.
    let bound = usize::from(model.bounds.is_some());
    let cosine = if model.features().is_angles() { 0 } else { 4 };
    model.feature_len()
        + bound
        + cosine
        + (model.pose_dims() + 1) * (n2 + 1)
        + kv
        + 2 * model.order
        + 16
}

/// Roundings that feed one shading value: every product of the lighting-weight stage (pose
/// weights × lighting, per coefficient and basis vector) and of the basis stage. Relative
/// errors grow along the longest chain ([`steps`]); absolute ones, the subnormal results'
/// (at most 2⁻¹⁴⁹ each), add up over every term, so they are counted here instead.
fn shading_terms(model: &LinearModel) -> usize {
    let n2 = model.order * model.order;
    let kv = match model.basis {
        VertexBasis::Stored { coef_dims, .. } => coef_dims,
        VertexBasis::Identity => 1,
    };
    (model.pose_dims() + 1) * (n2 + 1) * kv + kv + n2
}

/// Relative error bound of the f32 evaluation: ε = 2u per rounding step, doubled for margin.
pub fn rounding(model: &LinearModel) -> f64 {
    steps(model) as f64 * f32::EPSILON as f64
}

/// The smallest subnormal f32, 2⁻¹⁴⁹: below the normal range rounding errors are absolute.
const TINY: f64 = 1.401_298_464_324_817e-45;

/// Largest intermediate of the f32 evaluation (pose projection, pose weights, transfer,
/// shading), bounded from the largest values of each section: the product of the factors of
/// each stage, each at least 1. Above about 10³⁰ the f32 evaluation may overflow and nothing is
/// compared. The same product bounds how much an absolute (subnormal) rounding error anywhere
/// can grow on the way to the output.
fn largest(model: &LinearModel, angles: &[f32], lighting: &[f32]) -> f64 {
    let n2 = model.order * model.order;
    let (kv, u) = match &model.basis {
        VertexBasis::Stored { coef_dims, data } => (*coef_dims as f64, max_abs(data)),
        VertexBasis::Identity => (1.0, 1.0),
    };
    // A cosine feature lies in [0, 2].
    let angle = angles.iter().fold(0.0f64, |m, a| m.max((*a as f64).abs()));
    let feature = if model.features().is_angles() {
        angle
    } else {
        angle.max(2.0)
    };
    let a = feature + max_abs(&model.pose_mean);
    let light = lighting.iter().map(|l| (*l as f64).abs()).sum::<f64>();
    let p = model.feature_len() as f64 * max_abs(&model.pose_projection);
    let w = (model.pose_dims() + 1) as f64 * max_abs(&model.weights);
    let l = n2 as f64 * light;
    [p * a, w, kv * u, l].iter().map(|f| f.max(1.0)).product()
}

/// Asserts that `eval` equals `reference` evaluated exactly at the same inputs, up to the f32
/// rounding of the evaluator and a perturbation of at most `stored(|x|)` of every weight and
/// per-vertex value (0 when `reference` is exactly what the blob stores; half precision
/// rounding when it is the model before quantisation). Bone-frame shading is compared against
/// the lighting rotated by the exact-quadrature rotation, which agrees with the evaluator's
/// recurrences to about 10⁻⁵ of the lighting's 1-norm (plus subnormal rounding).
pub fn assert_matches(reference: &LinearModel, eval: &Evaluation, stored: impl Fn(f64) -> f64) {
    let largest = largest(reference, &eval.angles, &eval.lighting);
    // Past this the f32 evaluation may overflow (NaN included): only "no panic" is asked.
    if largest.is_nan() || largest >= 1e30 {
        return;
    }
    let slack = steps(reference) as f64 * TINY * largest;
    let n2 = reference.order * reference.order;
    let angles: Vec<f64> = eval.angles.iter().map(|&x| x as f64).collect();
    let want = reference.predict(&angles);
    let terms = magnitude(reference, &angles, |x| x);
    let perturbed = magnitude(reference, &angles, |x| x + stored(x));
    let gamma = rounding(reference);
    let bound: Vec<f64> = (0..want.len())
        .map(|i| gamma * terms[i] + (perturbed[i] - terms[i]) + slack)
        .collect();
    for (i, (got, want)) in eval.transfer.iter().zip(&want).enumerate() {
        assert!(
            (*got as f64 - want).abs() <= bound[i],
            "transfer[{}][{}] = {got}, reference {want}, bound {}",
            i / n2,
            i % n2,
            bound[i]
        );
    }

    // Lighting per vertex: the world lighting, or the bone's lighting rotated by Rᵀ.
    let norm1: f64 = eval.lighting.iter().map(|x| (*x as f64).abs()).sum();
    let local: Vec<Vec<f32>> = match &reference.bones {
        None => vec![eval.lighting.clone()],
        Some(_) => {
            let rotation = QuadratureRotation::new(reference.order).expect("orders 1..=6 rotate");
            eval.rotations
                .iter()
                .map(|r| {
                    let rt = std::array::from_fn(|i| std::array::from_fn(|j| r[j][i]));
                    let mut out = vec![0.0f32; n2];
                    rotation.rotate(&rt, &eval.lighting, &mut out).unwrap();
                    out
                })
                .collect()
        }
    };
    // Both rotations round relatively, and absolutely for subnormal lighting (a quadrature
    // node per direction and coefficient).
    let order = reference.order;
    let turn_error = match reference.bones {
        Some(_) => 2e-4 * norm1 + (order * (2 * order - 1) * (n2 + 2) + 4 * order) as f64 * TINY,
        None => 0.0,
    };
    // Scaled bytes fold each row's scale into the weight that multiplies the row's integers
    // (|i| ≤ 128), so a weight's subnormal rounding reaches the output 128 times larger.
    let integers = match eval.encoding {
        aprt_core::Encoding::I8 => 128.0,
        _ => 1.0,
    };
    let shade_slack = slack + shading_terms(reference) as f64 * TINY * largest * integers;
    for (j, got) in eval.shading.iter().enumerate() {
        let l = &local[eval.bones[j] as usize];
        let (mut want_j, mut bound_j) = (0.0f64, shade_slack);
        for (c, &lc) in l.iter().enumerate().take(n2) {
            let i = j * n2 + c;
            want_j += lc as f64 * want[i];
            bound_j += (lc as f64).abs() * (bound[i] + gamma * terms[i]) + turn_error * terms[i];
        }
        assert!(
            (*got as f64 - want_j).abs() <= bound_j,
            "shade[{j}] = {got}, reference {want_j}, bound {bound_j}"
        );
    }
}
