//! The chosen candidate as a [`LinearModel`] in the runtime's layout: the shared map from k_a
//! pose coordinates, the local model, or the prior alone (k_a = 0, the intercept only).

use nalgebra::{DMatrix, DVector};

use super::local_model::LocalModel;
use super::ridge::RidgeSolution;
use super::{PosePca, PriorKind};
use crate::model::{LinearModel, PoseBounds, VertexBasis};

/// What every model of one fit shares: its shape, the poses its bound is taken over, and
/// the prior poses.
pub(super) struct Assembly<'a> {
    pub order: usize,
    pub vertices: usize,
    /// The training poses in angles (pinned), which the bound is taken over.
    pub raw: &'a DMatrix<f64>,
    /// The anchor's pose in angles (pinned), when the fit has one.
    pub raw_anchor: Option<&'a [f64]>,
    /// The bound's falloff (see `FitOptions::bound`).
    pub falloff: Option<f64>,
    /// Entries the bound ignores.
    pub unused: &'a [usize],
    /// The cosine flags of the features.
    pub flags: Vec<bool>,
    /// The vertex basis (`None`: identity).
    pub basis: Option<&'a DMatrix<f64>>,
}

impl Assembly<'_> {
    fn bounds(&self, prior_angles: &[f64]) -> Option<crate::model::PoseBounds> {
        self.falloff
            .map(|f| PoseBounds::of(self.raw, prior_angles, f).ignoring(self.unused.to_vec()))
    }

    /// The prior's pose in angles: the rest pose, or the mean of the training poses.
    fn prior_angles(&self, prior: PriorKind) -> Vec<f64> {
        match (prior, self.raw_anchor) {
            (PriorKind::Rest, Some(a)) => a.to_vec(),
            _ => self.raw.row_mean().iter().copied().collect(),
        }
    }

    fn stored_basis(&self) -> VertexBasis {
        match self.basis {
            Some(b) => stored(b),
            None => VertexBasis::Identity,
        }
    }

    /// The shared map: the ridge `solution` on the leading `ka` coordinates of `pca`.
    pub fn shared(
        &self,
        solution: &RidgeSolution,
        pca: &PosePca,
        ka: usize,
        alpha: f64,
        prior: PriorKind,
    ) -> LinearModel {
        let n2 = self.order * self.order;
        let kv = solution.intercept.len() / n2;
        let mut weights = vec![0.0; n2 * (ka + 1) * kv];
        for c in 0..n2 {
            for k in 0..kv {
                let col = c * kv + k;
                weights[c * (ka + 1) * kv + k] = solution.intercept[col];
                for i in 0..ka {
                    weights[(c * (ka + 1) + 1 + i) * kv + k] = solution.coefficients[(i, col)];
                }
            }
        }
        let projection = pca.projection.rows(0, ka).into_owned();
        LinearModel {
            order: self.order,
            vertices: self.vertices,
            pose_len: self.raw.ncols(),
            pose_mean: pca.mean.clone(),
            // nalgebra is column-major; the model stores P row-major.
            pose_projection: projection.transpose().as_slice().to_vec(),
            weights,
            basis: self.stored_basis(),
            alpha,
            bones: None,
            angle_names: Vec::new(),
            bounds: self.bounds(&self.prior_angles(prior)),
            cosines: self.flags.clone(),
            proxies: None,
        }
    }

    /// The local model, on every feature around the anchor's (`anchor_features`).
    pub fn local(&self, local: &LocalModel, anchor_features: &[f64], alpha: f64) -> LinearModel {
        let f = anchor_features.len();
        LinearModel {
            order: self.order,
            vertices: self.vertices,
            pose_len: self.raw.ncols(),
            pose_mean: anchor_features.to_vec(),
            pose_projection: DMatrix::<f64>::identity(f, f).as_slice().to_vec(),
            weights: local.weights.clone(),
            basis: stored(&local.basis),
            alpha,
            bones: None,
            angle_names: Vec::new(),
            bounds: self.bounds(&self.prior_angles(PriorKind::Rest)),
            cosines: self.flags.clone(),
            proxies: None,
        }
    }

    /// The prior alone, α = ∞: the same transfer at every pose, `centre` (its coordinates in
    /// the basis) as the intercept and no pose dimension. A constant needs no pose features,
    /// so it has none but the angles; it keeps the bound of its prior's candidates (which
    /// changes nothing it predicts). The header holds α as an f32, so the model records the
    /// largest one it can, where every filter factor of any pose spread is zero.
    pub fn prior_alone(&self, centre: &DVector<f64>, prior: PriorKind) -> LinearModel {
        let a = self.raw.ncols();
        LinearModel {
            order: self.order,
            vertices: self.vertices,
            pose_len: a,
            pose_mean: self.raw.row_mean().iter().copied().collect(),
            pose_projection: Vec::new(),
            weights: centre.as_slice().to_vec(),
            basis: self.stored_basis(),
            alpha: f64::from(f32::MAX),
            bones: None,
            angle_names: Vec::new(),
            bounds: self.bounds(&self.prior_angles(prior)),
            cosines: vec![false; a],
            proxies: None,
        }
    }
}

/// `v × k_v` basis columns as the model stores them.
pub(super) fn stored(basis: &DMatrix<f64>) -> VertexBasis {
    VertexBasis::Stored {
        coef_dims: basis.ncols(),
        // v × k_v vertex-major is the row-major layout, i.e. the transpose's column-major one.
        data: basis.transpose().as_slice().to_vec(),
    }
}

/// The columns of `a` followed by those of `b`.
pub(super) fn beside(a: &DMatrix<f64>, b: &DMatrix<f64>) -> DMatrix<f64> {
    DMatrix::from_fn(a.nrows(), a.ncols() + b.ncols(), |j, k| {
        match k.checked_sub(a.ncols()) {
            None => a[(j, k)],
            Some(k) => b[(j, k)],
        }
    })
}
