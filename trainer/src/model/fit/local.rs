//! Local models: each vertex's transfer may depend only on the pose entries that move
//! geometry near it (the entries of its [`EntryGroup`]), fitted through the anchor.
//!
//! A model linear in every entry learns whatever the training clip correlates: a false shadow
//! on a raised arm because the chest happened to twist while the arm rose. Restricting each
//! vertex to the entries that change its surroundings removes those terms. Every group is
//! its own anchored ridge (`ŷ = y₀ + Wᵀ(a − a₀)` over its entries), all groups share one α
//! chosen by the summed held-out error, and the assembled per-vertex map `W` is then stored
//! in the runtime's layout through the shared vertex basis (see `fit_input`), so the core
//! needs nothing new.

use std::ops::Range;

use nalgebra::{DMatrix, DVector};

use super::ridge::{CvPoint, HeldOut, RidgeOutputs, RidgeProblem};
use super::{Alpha, FitError};

/// Vertices whose transfer depends on the same pose entries.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct EntryGroup {
    /// Indices into the pose vector, ascending.
    pub entries: Vec<usize>,
    /// Vertex indices, ascending.
    pub vertices: Vec<usize>,
}

/// A partition of the vertices into [`EntryGroup`]s.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Locality {
    /// Every vertex is in exactly one group.
    pub groups: Vec<EntryGroup>,
}

/// A clip held out whole: its pose entries, its transfer and what each of its poses weighs.
pub(super) type WeightedClip<'a> = (&'a DMatrix<f64>, &'a [Vec<f32>], f64);

/// How the local fit is scored: held-out runs of the training poses, or whole clips.
pub(super) enum LocalScoring<'a> {
    Segments(&'a [Range<usize>]),
    Clips(&'a [WeightedClip<'a>]),
}

/// The fitted local model: `ŷ(a) = y₀ + deltaᵀ (a − a₀)`.
pub(super) struct LocalFit {
    /// The shared α.
    pub alpha: f64,
    /// Summed held-out and in-sample squared error over every transfer value, per α.
    pub curve: Vec<CvPoint>,
    /// `a × (v·n²)`, column `j·n² + c`; rows of entries a vertex ignores are zero.
    pub delta: DMatrix<f64>,
    /// Each validation pose's squared error over every transfer value at the chosen α
    /// (empty when scored on held-out runs).
    pub held_rows: Vec<f64>,
}

/// One group's outputs: `p × (|vertices|·n²)`, column `jj·n² + c`.
fn group_rows(transfers: &[Vec<f32>], vertices: &[usize], n2: usize) -> DMatrix<f64> {
    DMatrix::from_fn(transfers.len(), vertices.len() * n2, |i, col| {
        f64::from(transfers[i][vertices[col / n2] * n2 + col % n2])
    })
}

/// Fits every group through the anchor (`a0`, `y0`: the rest pose and its transfer) with
/// one α, chosen on `scoring` (or fixed by `alpha`).
pub(super) fn fit_local(
    locality: &Locality,
    angles: &DMatrix<f64>,
    transfers: &[Vec<f32>],
    n2: usize,
    (a0, y0): (&[f64], &[f32]),
    scoring: &LocalScoring<'_>,
    alpha: Alpha,
) -> Result<LocalFit, FitError> {
    let anchor_row = DVector::from_column_slice(a0);
    let problem_of = |group: &EntryGroup| {
        let z = angles.select_columns(&group.entries);
        let z0 = anchor_row.select_rows(&group.entries);
        let outputs = RidgeOutputs::new(group_rows(transfers, &group.vertices, n2));
        let y0 = DVector::from_fn(group.vertices.len() * n2, |col, _| {
            f64::from(y0[group.vertices[col / n2] * n2 + col % n2])
        });
        (z, z0, outputs, y0)
    };
    let held_of = |group: &EntryGroup| -> Vec<HeldOut> {
        let LocalScoring::Clips(clips) = scoring else {
            return Vec::new();
        };
        clips
            .iter()
            .map(|(a, t, weight)| HeldOut {
                z: a.select_columns(&group.entries),
                y: group_rows(t, &group.vertices, n2),
                weight: *weight,
            })
            .collect()
    };
    let alphas = match alpha {
        Alpha::Fixed(alpha) => vec![alpha],
        _ => {
            let mut centred = angles.clone();
            for mut row in centred.row_iter_mut() {
                row -= anchor_row.transpose();
            }
            let s_max = centred.singular_values().max();
            if s_max > 0.0 {
                RidgeProblem::alpha_grid(s_max)
            } else {
                vec![0.0]
            }
        }
    };
    let mut sums = vec![(0.0, 0.0); alphas.len()];
    let (mut scored_values, mut train_values) = (0.0, 0.0);
    for group in &locality.groups {
        let (z, z0, outputs, y0) = problem_of(group);
        let target = outputs.around_anchor(&y0);
        let problem = RidgeProblem::new(&z, Some(&z0), &target);
        let width = (group.vertices.len() * n2) as f64;
        let (points, scored_poses) = match scoring {
            LocalScoring::Segments(runs) => {
                (problem.cv_points(&alphas, runs), angles.nrows() as f64)
            }
            LocalScoring::Clips(clips) => {
                let poses = clips.iter().map(|(a, _, _)| a.nrows()).sum::<usize>();
                (
                    problem.held_out_points(&alphas, &held_of(group)),
                    poses as f64,
                )
            }
        };
        for (sum, point) in sums.iter_mut().zip(&points) {
            sum.0 += point.cv_error * scored_poses * width;
            sum.1 += point.train_error * angles.nrows() as f64 * width;
        }
        scored_values += scored_poses * width;
        train_values += angles.nrows() as f64 * width;
    }
    let curve: Vec<CvPoint> = alphas
        .iter()
        .zip(&sums)
        .map(|(&alpha, &(cv, train))| CvPoint {
            alpha,
            cv_error: cv / scored_values.max(1.0),
            train_error: train / train_values.max(1.0),
        })
        .collect();
    // A fixed α stands whatever its score (least squares may leave a run unpredictable).
    let best = curve
        .iter()
        .filter(|c| c.cv_error.is_finite() || matches!(alpha, Alpha::Fixed(_)))
        .min_by(|l, r| l.cv_error.total_cmp(&r.cv_error))
        .copied()
        .ok_or(FitError::NoFiniteCvError)?;

    let vertices = transfers.first().map_or(0, |t| t.len() / n2.max(1));
    let mut delta = DMatrix::zeros(angles.ncols(), vertices * n2);
    let mut held_rows: Vec<f64> = Vec::new();
    for group in &locality.groups {
        let (z, z0, outputs, y0) = problem_of(group);
        let target = outputs.around_anchor(&y0);
        let problem = RidgeProblem::new(&z, Some(&z0), &target);
        let rows = problem.held_out_rows(best.alpha, &held_of(group));
        held_rows.resize(rows.len(), 0.0);
        held_rows
            .iter_mut()
            .zip(rows)
            .for_each(|(sum, e)| *sum += e);
        let solution = problem.solve(best.alpha);
        for (i, &entry) in group.entries.iter().enumerate() {
            for (jj, &j) in group.vertices.iter().enumerate() {
                for c in 0..n2 {
                    delta[(entry, j * n2 + c)] = solution.coefficients[(i, jj * n2 + c)];
                }
            }
        }
    }
    Ok(LocalFit {
        alpha: best.alpha,
        curve,
        delta,
        held_rows,
    })
}
