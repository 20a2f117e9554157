//! Pose PCA: the projection `z = P (a − μ)` from joint angles to k_a pose coordinates.
//!
//! Joint angles are strongly correlated across a motion (and some joints never move), so the
//! ridge regresses on the leading principal directions of the centred angle matrix instead of
//! the raw angles. The projection is cut at the numerical rank, which removes constant joints
//! and exactly collinear angle combinations before the regression ever sees them.

use aprt_core::MAX_POSE_DIMS;
use nalgebra::DMatrix;

use super::dims::{self, Dims};

/// The fitted pose projection.
#[derive(Clone, Debug, PartialEq)]
pub struct PosePca {
    /// Mean pose μ (a values).
    pub mean: Vec<f64>,
    /// P, `k_a × a`: its rows are the leading orthonormal principal directions.
    pub projection: DMatrix<f64>,
    /// Eigenvalues of the angle covariance (`σ_i² / max(p − 1, 1)`), all `min(p, a)` of them,
    /// descending: the spectrum of the paper's Figure 4.
    pub eigenvalues: Vec<f64>,
}

impl PosePca {
    /// Centres the `p × a` angle matrix, takes its SVD and keeps the leading directions
    /// selected by `dims`, never more than the numerical rank nor, unless counted explicitly,
    /// than the runtime's [`MAX_POSE_DIMS`].
    pub fn fit(angles: &DMatrix<f64>, dims: Dims) -> Self {
        let (p, a) = angles.shape();
        let mean: Vec<f64> = (0..a).map(|j| angles.column(j).mean()).collect();
        let mut centred = angles.clone();
        for (j, m) in mean.iter().enumerate() {
            centred.column_mut(j).add_scalar_mut(-m);
        }
        if p == 0 || a == 0 {
            return Self {
                mean,
                projection: DMatrix::zeros(0, a),
                eigenvalues: Vec::new(),
            };
        }
        let svd = centred.svd(false, true);
        let sigma = svd.singular_values.as_slice();
        let energies: Vec<f64> = sigma.iter().map(|s| s * s).collect();
        let total: f64 = energies.iter().sum();
        let rank = dims::numerical_rank(sigma, p, a, f64::EPSILON);
        let keep = dims::choose(dims, &energies, total, rank)
            .unwrap_or(rank)
            .min(dims.cap(MAX_POSE_DIMS));
        let v_t = svd.v_t.expect("SVD computed with V");
        let scale = 1.0 / (p.max(2) - 1) as f64;
        Self {
            mean,
            projection: v_t.rows(0, keep).into_owned(),
            eigenvalues: energies.iter().map(|e| e * scale).collect(),
        }
    }

    /// k_a, the number of kept pose dimensions.
    pub fn dims(&self) -> usize {
        self.projection.nrows()
    }

    /// Pose coordinates of every row of `angles`: `Z = (A − 1μᵀ) Pᵀ`, `p × k_a`.
    pub fn project(&self, angles: &DMatrix<f64>) -> DMatrix<f64> {
        let mut centred = angles.clone();
        for (j, m) in self.mean.iter().enumerate() {
            centred.column_mut(j).add_scalar_mut(-m);
        }
        centred * self.projection.transpose()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::model::fit::tests::uniform;

    #[test]
    fn constant_and_collinear_joints_are_cut_at_the_rank() {
        let base = uniform(20, 3, 1);
        // Columns: 3 free, one constant, one collinear (2·a0 − a2 + 0.3).
        let angles = DMatrix::from_fn(20, 5, |i, j| match j {
            0..=2 => base[(i, j)],
            3 => 0.7,
            _ => 2.0 * base[(i, 0)] - base[(i, 2)] + 0.3,
        });
        let pca = PosePca::fit(&angles, Dims::All);
        assert_eq!(pca.dims(), 3);
        assert_eq!(PosePca::fit(&angles, Dims::Count(5)).dims(), 3);
        assert!((pca.mean[3] - 0.7).abs() < 1e-15);
        // Rows orthonormal, and the constant joint gets no weight.
        let ppt = &pca.projection * pca.projection.transpose();
        assert!((ppt - DMatrix::identity(3, 3)).amax() < 1e-12);
        assert!(pca.projection.column(3).amax() < 1e-12);
        // The discarded spectrum is at rounding level.
        assert!(pca.eigenvalues[3] < 1e-25 * pca.eigenvalues[0].max(1.0));
        // Projection preserves pairwise distances of the (rank-3) centred poses.
        let z = pca.project(&angles);
        let d_z = (z.row(4) - z.row(9)).norm();
        let d_a = (angles.row(4) - angles.row(9)).norm();
        assert!((d_z - d_a).abs() < 1e-12 * d_a);
    }

    #[test]
    fn eigenvalues_are_sample_covariance_eigenvalues() {
        let angles = uniform(30, 4, 7);
        let pca = PosePca::fit(&angles, Dims::Count(2));
        let mut c = angles.clone();
        for j in 0..4 {
            let m = c.column(j).mean();
            c.column_mut(j).add_scalar_mut(-m);
        }
        let cov = c.transpose() * &c / 29.0;
        let mut eig: Vec<f64> = cov.symmetric_eigenvalues().iter().copied().collect();
        eig.sort_by(|a, b| b.total_cmp(a));
        for (x, y) in pca.eigenvalues.iter().zip(&eig) {
            assert!((x - y).abs() < 1e-12 * eig[0]);
        }
        assert_eq!(pca.dims(), 2);
    }

    #[test]
    fn more_angles_than_poses_and_single_pose() {
        let angles = uniform(4, 10, 3);
        assert_eq!(PosePca::fit(&angles, Dims::All).dims(), 3);
        let one = uniform(1, 10, 3);
        let pca = PosePca::fit(&one, Dims::All);
        assert_eq!(pca.dims(), 0);
        assert_eq!(pca.project(&one).shape(), (1, 0));
    }
}
