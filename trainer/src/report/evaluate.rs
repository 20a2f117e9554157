//! Accuracy against ground truth, and the baselines every model is measured against.

use aprt_core::ShRotation;
use glam::{DMat3, Mat4};

use crate::rig::transfer_rotation::{nearest_rotation, rotate_each};

/// Relative error `‖pred − truth‖ / ‖truth‖` over all frames, vertices and coefficients:
/// the transfer error of the reports (0 is perfect, 1 is as wrong as predicting zero).
pub fn relative_error(pred: &[Vec<f32>], truth: &[Vec<f32>]) -> f64 {
    let (mut num, mut den) = (0.0f64, 0.0f64);
    for (p, t) in pred.iter().zip(truth) {
        for (a, b) in p.iter().zip(t) {
            num += (*a as f64 - *b as f64).powi(2);
            den += (*b as f64).powi(2);
        }
    }
    if den > 0.0 {
        (num / den).sqrt()
    } else {
        num.sqrt()
    }
}

/// The errors of `pred` and of `reference` on the `fraction` of vertices where `reference`
/// errs most (squared error summed over frames and `coeffs` coefficients per vertex), each
/// relative to the truth there, as [`relative_error`]: how much of a baseline's worst error a
/// model removes, which the error over all vertices dilutes when the worst are few.
pub fn hard_vertex_errors(
    pred: &[Vec<f32>],
    reference: &[Vec<f32>],
    truth: &[Vec<f32>],
    coeffs: usize,
    fraction: f64,
) -> (f64, f64) {
    let vertices = truth.first().map_or(0, |t| t.len() / coeffs.max(1));
    // Per vertex, Σ (value − truth)² over frames and coefficients; Σ truth² without values.
    let per_vertex = |values: Option<&[Vec<f32>]>| -> Vec<f64> {
        let mut sums = vec![0.0f64; vertices];
        for (f, t) in truth.iter().enumerate() {
            for (v, sum) in sums.iter_mut().enumerate() {
                let span = v * coeffs..(v + 1) * coeffs;
                *sum += t[span.clone()]
                    .iter()
                    .enumerate()
                    .map(|(k, b)| {
                        let a = values.map_or(0.0, |p| p[f][span.start + k] as f64);
                        (a - *b as f64).powi(2)
                    })
                    .sum::<f64>();
            }
        }
        sums
    };
    let (reference_err, pred_err, truth_norm) = (
        per_vertex(Some(reference)),
        per_vertex(Some(pred)),
        per_vertex(None),
    );
    let mut order: Vec<usize> = (0..vertices).collect();
    order.sort_by(|&a, &b| reference_err[b].total_cmp(&reference_err[a]));
    let hard = &order[..((vertices as f64 * fraction).ceil() as usize).min(vertices)];
    let total = |err: &[f64]| hard.iter().map(|&v| err[v]).sum::<f64>();
    let norm = total(&truth_norm).max(f64::MIN_POSITIVE);
    (
        (total(&pred_err) / norm).sqrt(),
        (total(&reference_err) / norm).sqrt(),
    )
}

/// Mean transfer of the training poses: the model with no pose dependence at all.
pub fn mean_transfer(train: &[Vec<f32>]) -> Vec<f32> {
    let n = train.len().max(1) as f64;
    let mut mean = vec![0.0f64; train.first().map_or(0, Vec::len)];
    for t in train {
        for (m, x) in mean.iter_mut().zip(t) {
            *m += *x as f64;
        }
    }
    mean.into_iter().map(|m| (m / n) as f32).collect()
}

/// Index of the training pose nearest to `angles` (Euclidean in joint-angle space).
pub fn nearest_pose(train_angles: &[Vec<f64>], angles: &[f64]) -> usize {
    let dist = |a: &[f64]| {
        a.iter()
            .zip(angles)
            .map(|(x, y)| (x - y).powi(2))
            .sum::<f64>()
    };
    (0..train_angles.len())
        .min_by(|&i, &j| dist(&train_angles[i]).total_cmp(&dist(&train_angles[j])))
        .unwrap_or(0)
}

/// Bind-pose transfer carried by the skinning: each vertex's bind transfer rotated by the
/// nearest rotation to its blended skinning matrix. Right for rigid motion of an isolated
/// part; blind to the shadows that other parts cast as they move.
pub fn skinned_transfer(
    rotation: &ShRotation,
    bind_transfer: &[f32],
    influences: impl Fn(usize) -> Vec<(u32, f32)> + Sync,
    joint_matrices: &[Mat4],
) -> Vec<f32> {
    rotate_each(rotation, bind_transfer, |j| {
        let mut blend = DMat3::ZERO;
        for (joint, w) in influences(j) {
            blend += DMat3::from_mat4(joint_matrices[joint as usize].as_dmat4()) * w as f64;
        }
        nearest_rotation(blend)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hard_vertices_are_the_references_worst() {
        // Two coefficients, four vertices; the reference is wrong on vertex 2 only.
        let truth = vec![vec![1.0f32, 0.0, 1.0, 0.0, 2.0, 0.0, 1.0, 0.0]];
        let mut reference = truth.clone();
        reference[0][4] = 0.0;
        let mut pred = truth.clone();
        pred[0][4] = 1.0;
        pred[0][0] = 5.0; // wrong elsewhere: not counted
        let (model, base) = hard_vertex_errors(&pred, &reference, &truth, 2, 0.25);
        assert_eq!((model, base), (0.5, 1.0));
        // All vertices: the plain relative error.
        let (all, _) = hard_vertex_errors(&pred, &reference, &truth, 2, 1.0);
        assert!((all - relative_error(&pred, &truth)).abs() < 1e-12);
    }

    #[test]
    fn relative_error_is_scale_free() {
        let truth = vec![vec![1.0f32, 2.0, 2.0]];
        assert_eq!(relative_error(&truth, &truth), 0.0);
        assert!((relative_error(&[vec![0.0; 3]], &truth) - 1.0).abs() < 1e-12);
        assert!((relative_error(&[vec![1.5, 3.0, 3.0]], &truth) - 0.5).abs() < 1e-12);
    }

    #[test]
    fn nearest_pose_and_mean() {
        let angles = vec![vec![0.0, 0.0], vec![1.0, 1.0], vec![0.2, -0.1]];
        assert_eq!(nearest_pose(&angles, &[0.9, 1.2]), 1);
        assert_eq!(nearest_pose(&angles, &[0.15, 0.0]), 2);
        assert_eq!(
            mean_transfer(&[vec![1.0, 2.0], vec![3.0, 6.0]]),
            vec![2.0, 4.0]
        );
    }

    #[test]
    fn skinning_rotates_transfer_with_a_rigid_joint() {
        let order = 3;
        let rot = ShRotation::new(order).unwrap();
        let mut t = [0.0f32; 9];
        aprt_core::clamped_cosine(order, [0.0, 0.0, 1.0], &mut t).unwrap();
        let m = Mat4::from_rotation_x(std::f32::consts::FRAC_PI_2);
        let out = skinned_transfer(&rot, &t, |_| vec![(0, 1.0)], &[m]);
        // +z rotated a quarter turn about x points along −y.
        let mut expect = [0.0f32; 9];
        aprt_core::clamped_cosine(order, [0.0, -1.0, 0.0], &mut expect).unwrap();
        for (a, b) in out.iter().zip(expect) {
            assert!((a - b).abs() < 1e-5, "{out:?} vs {expect:?}");
        }
    }
}
