//! How the candidates are scored: what is held out (runs of the training clips, or whole
//! validation clips), the transfer as the candidates see it (coordinates in the vertex basis
//! and what lies outside it), and errors per transfer value, comparable across candidates.

use std::ops::Range;

use nalgebra::{DMatrix, DVector};

use super::ridge::{
    AlphaSelection, CvPoint, HeldOut, RidgeOutputs, RidgeProblem, RidgeTarget, segments,
};
use super::rsvd::RowOperator;
use super::vertex_basis::{PoseRows, project_rows, raw_rows};
use super::{Alpha, FitError, FitInput, PosePca};

/// How a candidate is scored: held-out runs of the training clips, or whole held-out clips.
#[derive(Clone, Copy)]
pub(super) enum Scoring<'a> {
    Segments(&'a [Range<usize>]),
    Clips(&'a [HeldOut]),
}

impl Scoring<'_> {
    /// α by held-out error, and the curve it was chosen on.
    pub fn select(&self, problem: &RidgeProblem<'_>) -> Result<AlphaSelection, FitError> {
        match self {
            Scoring::Segments(runs) => problem.select_alpha(runs),
            Scoring::Clips(held) => problem.select_on(held),
        }
    }

    /// The errors at one α.
    pub fn point(&self, problem: &RidgeProblem<'_>, alpha: f64) -> CvPoint {
        match self {
            Scoring::Segments(runs) => problem.cv_point(alpha, runs),
            Scoring::Clips(held) => problem.held_out_point(alpha, held),
        }
    }

    /// The errors of the target's prior alone (α = ∞), in closed form.
    pub fn prior(&self, target: &RidgeTarget<'_>) -> CvPoint {
        match self {
            Scoring::Segments(runs) => target.prior_point(runs),
            Scoring::Clips(held) => target.prior_held_out(held),
        }
    }

    /// Each validation pose's squared error (summed over the outputs) at `alpha`, for the
    /// noise of the choice; `None` for held-out runs, whose poses are not independent.
    pub fn rows(&self, problem: &RidgeProblem<'_>, alpha: f64) -> Option<Vec<f64>> {
        match self {
            Scoring::Segments(_) => None,
            Scoring::Clips(held) => Some(problem.held_out_rows(alpha, held)),
        }
    }

    /// [`rows`](Self::rows) of the target's prior alone (α = ∞).
    pub fn prior_rows(&self, target: &RidgeTarget<'_>) -> Option<Vec<f64>> {
        match self {
            Scoring::Segments(_) => None,
            Scoring::Clips(held) => Some(target.prior_held_out_rows(held)),
        }
    }
}

/// Poses per held-out run: 1 for leave-one-out, the asked length or `⌈p / 10⌉` otherwise.
pub(super) fn segment_length(alpha: Alpha, poses: usize) -> usize {
    match alpha {
        Alpha::Loo => 1,
        Alpha::Loso { segment } => segment.unwrap_or(poses.div_ceil(10)).max(1),
        Alpha::Fixed(_) => poses.div_ceil(10).max(1),
    }
}

/// The held-out runs of `segment` poses inside each training clip.
pub(super) fn held_out_runs(input: &FitInput<'_>, segment: usize) -> Vec<Range<usize>> {
    let clips = if input.clips.is_empty() {
        vec![input.transfers.len()]
    } else {
        input.clips.clone()
    };
    segments(&clips, segment)
}

/// What each pose of each validation set weighs, for sets of `sizes` poses: every set
/// weighs the same in the error whatever its length (a 48-frame clip the user held out as
/// much as 64 sampled poses), and the weights of all poses sum to their count, so that a
/// single set, or sets of one length, weigh 1 a pose.
pub(super) fn set_weights(sizes: &[usize]) -> Vec<f64> {
    let total: usize = sizes.iter().sum();
    let sets = sizes.iter().filter(|&&n| n > 0).count().max(1);
    sizes
        .iter()
        .map(|&n| total as f64 / (sets * n.max(1)) as f64)
        .collect()
}

/// The transfer as the candidates see it: each pose's coordinates in the vertex basis (its
/// raw values for the identity basis), the anchor's, the validation clips', and the part of
/// each pose's transfer outside the basis, which is the same for every candidate that
/// predicts in the basis and part of its error.
pub(super) struct Projected {
    /// The training poses' outputs.
    pub outputs: RidgeOutputs,
    /// `‖t‖² − ‖coordinates‖²` summed over the training poses.
    pub outside_train: f64,
    /// The anchor's pose coordinates and outputs.
    pub anchor: Option<(DVector<f64>, DVector<f64>)>,
    /// The validation clips' pose coordinates and outputs.
    pub held: Vec<HeldOut>,
    /// What lies outside the basis, per validation pose, weighted as its set.
    pub outside_held: Vec<f64>,
}

impl Projected {
    /// Projects `input`'s transfer on `basis` (`None`: the identity) and its poses with `pca`.
    pub fn new(
        input: &FitInput<'_>,
        basis: Option<&DMatrix<f64>>,
        pca: &PosePca,
        vertices: usize,
    ) -> Self {
        let n2 = input.order * input.order;
        let outputs_of = |transfers: &[&[f32]]| {
            let rows = PoseRows::from_slices(transfers.to_vec(), n2, vertices);
            match basis {
                Some(b) => project_rows(&rows, b),
                None => raw_rows(&rows),
            }
        };
        let outside = |transfers: &[&[f32]], outputs: &DMatrix<f64>| {
            let rows = PoseRows::from_slices(transfers.to_vec(), n2, vertices);
            (rows.frobenius_sq() - outputs.norm_squared()).max(0.0)
        };
        // Pose by pose for the validation poses, whose spread the choice weighs.
        let outside_each = |transfers: &[&[f32]], outputs: &DMatrix<f64>| {
            let values = |t: &[f32]| t.iter().map(|&x| f64::from(x).powi(2)).sum::<f64>();
            transfers
                .iter()
                .zip(outputs.row_iter())
                .map(|(t, y)| (values(t) - y.norm_squared()).max(0.0))
                .collect::<Vec<f64>>()
        };
        let train_slices: Vec<&[f32]> = input.transfers.iter().map(Vec::as_slice).collect();
        let train_outputs = outputs_of(&train_slices);
        let outside_train = outside(&train_slices, &train_outputs);
        let anchor = input.anchor.map(|a| {
            let z0 = pca.project(&DMatrix::from_row_slice(1, a.angles.len(), a.angles));
            let y0 = outputs_of(&[a.transfer]);
            (z0.row(0).transpose(), y0.row(0).transpose())
        });
        let mut held = Vec::new();
        let mut outside_held = Vec::new();
        let sizes: Vec<usize> = input.validation.iter().map(|v| v.transfers.len()).collect();
        for (v, weight) in input.validation.iter().zip(set_weights(&sizes)) {
            let slices: Vec<&[f32]> = v.transfers.iter().map(Vec::as_slice).collect();
            let y = outputs_of(&slices);
            outside_held.extend(outside_each(&slices, &y).iter().map(|o| weight * o));
            held.push(HeldOut {
                z: pca.project(v.angles),
                y,
                weight,
            });
        }
        Self {
            outputs: RidgeOutputs::new(train_outputs),
            outside_train,
            anchor,
            held,
            outside_held,
        }
    }

    /// Poses in the validation clips.
    pub fn held_poses(&self) -> usize {
        self.held.iter().map(|h| h.y.nrows()).sum()
    }
}

/// Errors per transfer value from errors per output (basis coordinates), with what lies
/// outside the basis added: comparable across every candidate.
pub(super) struct PerValue {
    /// Outputs per pose (`n²·k_v`) and transfer values per pose (`v·n²`).
    outputs: usize,
    values: usize,
    train_poses: usize,
    outside_train: f64,
    scored_poses: usize,
    outside_scored: f64,
    /// What lies outside the basis per validation pose (empty for held-out runs).
    outside_rows: Vec<f64>,
}

impl PerValue {
    /// For `n2` coefficients of `vertices` vertices through `kv` basis vectors, scored on the
    /// training poses (held-out runs) or on the validation clips.
    pub fn new(projected: &Projected, poses: usize, n2: usize, kv: usize, vertices: usize) -> Self {
        let (scored_poses, outside_scored) = if projected.held.is_empty() {
            (poses, projected.outside_train)
        } else {
            (projected.held_poses(), projected.outside_held.iter().sum())
        };
        Self {
            outputs: n2 * kv,
            values: vertices * n2,
            train_poses: poses,
            outside_train: projected.outside_train,
            scored_poses,
            outside_scored,
            outside_rows: projected.outside_held.clone(),
        }
    }

    fn convert(&self, mse: f64, poses: usize, outside: f64) -> f64 {
        if mse == f64::MAX {
            return mse;
        }
        let poses = poses.max(1) as f64;
        (mse * poses * self.outputs as f64 + outside) / (poses * self.values as f64)
    }

    /// The held-out error per transfer value of a point's held-out error per output.
    pub fn held_out(&self, point: &CvPoint) -> f64 {
        self.convert(point.cv_error, self.scored_poses, self.outside_scored)
    }

    /// Each validation pose's error per transfer value, from its squared error (summed over
    /// the outputs, as [`Scoring::rows`] gives them): their mean is
    /// [`held_out`](Self::held_out)'s.
    pub fn held_out_rows(&self, rows: &[f64]) -> Vec<f64> {
        rows.iter()
            .zip(&self.outside_rows)
            .map(|(e, outside)| (e + outside) / self.values as f64)
            .collect()
    }

    /// The same for the in-sample error.
    pub fn train(&self, point: &CvPoint) -> f64 {
        self.convert(point.train_error, self.train_poses, self.outside_train)
    }
}
