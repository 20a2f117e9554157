//! PCA over the frames (the paper's §7 suggestion): a mean map plus `k` component maps and
//! `k` weights per frame, `k` chosen by an error target.

use nalgebra::DMatrix;

/// The mean, the components (each scaled by its singular value, so quantising them with a
/// shared exponent spends steps where the energy is) and the per-frame weights.
pub struct Pca {
    /// The mean of the frames, `D` values.
    pub mean: Vec<f32>,
    /// `k` components of `D` values, `U_j = Σ_f v_j[f] (x_f − mean)`, norm `√λ_j`.
    pub components: Vec<Vec<f32>>,
    /// `weights[f][j]`: frame `f ≈ mean + Σ_j weights[f][j] · U_j` (before quantisation).
    pub weights: Vec<Vec<f32>>,
}

/// Fits the smallest `k ≤ max_components` whose discarded energy is within
/// `target_error · ‖X‖` (the relative error of the transfer metric, before quantisation).
/// The eigenproblem is the `F × F` Gram matrix of the centred frames, cheap for clips of
/// 20–150 frames however large the maps.
pub fn fit(frames: &[Vec<f32>], target_error: f64, max_components: usize) -> Pca {
    let count = frames.len();
    let dim = frames.first().map_or(0, Vec::len);
    let mut mean = vec![0f64; dim];
    for frame in frames {
        mean.iter_mut()
            .zip(frame)
            .for_each(|(m, &x)| *m += f64::from(x));
    }
    mean.iter_mut().for_each(|m| *m /= count as f64);
    let centred = |f: usize| frames[f].iter().zip(&mean).map(|(&x, m)| f64::from(x) - m);
    let mut gram = DMatrix::zeros(count, count);
    for i in 0..count {
        for j in 0..=i {
            let g: f64 = centred(i).zip(centred(j)).map(|(a, b)| a * b).sum();
            gram[(i, j)] = g;
            gram[(j, i)] = g;
        }
    }
    let eigen = gram.symmetric_eigen();
    let mut order: Vec<usize> = (0..count).collect();
    order.sort_by(|&a, &b| eigen.eigenvalues[b].total_cmp(&eigen.eigenvalues[a]));
    let total: f64 = frames.iter().map(|f| dot_f32(f, f)).sum();
    let budget = (target_error * target_error * total).max(0.0);
    let mut residual: f64 = order.iter().map(|&j| eigen.eigenvalues[j].max(0.0)).sum();
    let mut kept = Vec::new();
    for &j in order.iter().take(max_components.min(count)) {
        if residual <= budget {
            break;
        }
        residual -= eigen.eigenvalues[j].max(0.0);
        kept.push(j);
    }
    let components = kept
        .iter()
        .map(|&j| {
            let mut u = vec![0f64; dim];
            for (f, &w) in eigen.eigenvectors.column(j).iter().enumerate() {
                u.iter_mut().zip(centred(f)).for_each(|(u, c)| *u += w * c);
            }
            u.iter().map(|&x| x as f32).collect()
        })
        .collect();
    let weights = (0..count)
        .map(|f| {
            kept.iter()
                .map(|&j| eigen.eigenvectors[(f, j)] as f32)
                .collect()
        })
        .collect();
    Pca {
        mean: mean.iter().map(|&m| m as f32).collect(),
        components,
        weights,
    }
}

/// Re-fits each frame's weights by least squares against the quantised mean and components,
/// so the weights absorb part of the quantisation error instead of adding to it. `None` when
/// the quantised components are linearly dependent (keep the fitted weights then).
pub fn refit_weights(
    frames: &[Vec<f32>],
    mean: &[f32],
    components: &[Vec<f32>],
) -> Option<Vec<Vec<f32>>> {
    let k = components.len();
    let gram = DMatrix::from_fn(k, k, |i, j| dot_f32(&components[i], &components[j]));
    let solver = gram.cholesky()?;
    let weights = frames
        .iter()
        .map(|frame| {
            let residual: Vec<f32> = frame.iter().zip(mean).map(|(x, m)| x - m).collect();
            let rhs = nalgebra::DVector::from_fn(k, |j, _| dot_f32(&components[j], &residual));
            solver.solve(&rhs).iter().map(|&x| x as f32).collect()
        })
        .collect();
    Some(weights)
}

fn dot_f32(a: &[f32], b: &[f32]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(&x, &y)| f64::from(x) * f64::from(y))
        .sum()
}
