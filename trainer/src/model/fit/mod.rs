//! Fitting stage of the trainer: from poses and baked transfer to a [`LinearModel`].
//!
//! Pipeline (Nowrouzezahrai et al., *Compact and Efficient Generation of Radiance Transfer for
//! Dynamically Articulated Characters*): pose PCA (`z = P (a − μ)`) → shared vertex basis over
//! all `p·n²` coefficient rows (randomized SVD) → basis coordinates of each pose's rows → one
//! ridge regression of all `n²·k_v` outputs on z with a single α chosen by closed-form cross
//! validation → weights packed in the runtime layout.

mod dims;
mod pose_pca;
mod ridge;
mod rsvd;
mod vertex_basis;

#[cfg(test)]
mod tests;

pub use dims::Dims;
pub use pose_pca::PosePca;
pub use ridge::{AlphaSelection, CvPoint, RidgeProblem, RidgeSolution};
pub use rsvd::{RowOperator, SketchOptions, TruncatedSvd, randomized_svd};
pub use vertex_basis::{PoseRows, VertexBasisFit, fit_vertex_basis, project_rows, raw_rows};

use std::time::Instant;

use nalgebra::DMatrix;

use crate::model::{LinearModel, VertexBasis};

/// Size of the vertex side of the model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CoefDims {
    /// k_v basis vectors (fewer if the rows have lower rank).
    Count(usize),
    /// The fewest basis vectors capturing this fraction of `‖R‖_F²` (uncentred energy).
    Variance(f64),
    /// No vertex reduction: the identity basis, the paper's "full linear model".
    Full,
}

/// How the Tikhonov parameter is chosen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Alpha {
    /// Leave-one-out cross validation (closed form).
    Loo,
    /// Leave-one-segment-out over contiguous runs of `segment` poses (closed form). Frames
    /// of a clip are strongly correlated, so LOO rewards interpolating a neighbour; holding
    /// out whole runs measures generalisation to unseen motion. `None` picks `⌈p / 10⌉`;
    /// `Some(0)` is treated as 1 (leave-one-out). The last run may be shorter.
    Loso {
        /// Poses per held-out run.
        segment: Option<usize>,
    },
    /// Use this α (≥ 0) without cross validation.
    Fixed(f64),
}

/// Options of [`fit`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FitOptions {
    /// k_a.
    pub pose_dims: Dims,
    /// k_v.
    pub coef_dims: CoefDims,
    /// α selection.
    pub alpha: Alpha,
}

impl Default for FitOptions {
    /// All pose dimensions up to the rank, the paper's 22 vertex vectors, α by leave-segment-out
    /// with ten segments.
    fn default() -> Self {
        Self {
            pose_dims: Dims::All,
            coef_dims: CoefDims::Count(22),
            alpha: Alpha::Loso { segment: None },
        }
    }
}

/// Why a fit was refused.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum FitError {
    /// No poses were given.
    #[error("no poses to fit")]
    NoPoses,
    /// `angles` and `transfers` disagree on the number of poses.
    #[error("{angles} poses of angles but {transfers} of transfer")]
    PoseCountMismatch {
        /// Rows of the angle matrix.
        angles: usize,
        /// Transfer arrays.
        transfers: usize,
    },
    /// SH order 0 has no coefficients.
    #[error("SH order must be at least 1")]
    ZeroOrder,
    /// A transfer array is not `v · n²` long for the same `v` as pose 0.
    #[error(
        "pose {pose}: transfer has {len} values, expected {expected} (v · n² with n² = {coefs})"
    )]
    TransferLength {
        /// Pose index.
        pose: usize,
        /// Its length.
        len: usize,
        /// The length pose 0 implies (for pose 0: the next multiple of n²).
        expected: usize,
        /// n².
        coefs: usize,
    },
    /// The transfer arrays are empty (no vertices).
    #[error("transfer has no vertices")]
    NoVertices,
    /// A joint angle is NaN or infinite.
    #[error("pose {pose}: joint angle {joint} is not finite")]
    NonFiniteAngle {
        /// Pose index.
        pose: usize,
        /// Joint index.
        joint: usize,
    },
    /// A joint angle is beyond what the runtime's f32 pose vector can hold.
    #[error(
        "pose {pose}: joint angle {joint} is {value:e}, beyond ±3.4e38, the largest angle the runtime's f32 pose vector holds"
    )]
    AngleOutOfRange {
        /// Pose index.
        pose: usize,
        /// Joint index.
        joint: usize,
        /// The angle.
        value: f64,
    },
    /// A transfer value is NaN or infinite.
    #[error("pose {pose}: transfer value {index} is not finite")]
    NonFiniteTransfer {
        /// Pose index.
        pose: usize,
        /// Index into the vertex-major array.
        index: usize,
    },
    /// A fixed α must be finite and non-negative.
    #[error("alpha {0} must be finite and non-negative")]
    InvalidAlpha(f64),
    /// Energy fractions must lie in (0, 1].
    #[error("variance fraction {0} must lie in (0, 1]")]
    InvalidFraction(f64),
    /// A held-out segment must leave at least one pose to fit on.
    #[error("segment of {segment} poses leaves nothing to train on ({poses} poses)")]
    SegmentTooLong {
        /// Segment length.
        segment: usize,
        /// Number of poses.
        poses: usize,
    },
    /// Every α of the grid left some held-out set unpredictable.
    #[error("cross validation error is infinite for every alpha")]
    NoFiniteCvError,
}

/// Wall-clock seconds per stage.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StageSeconds {
    /// Input checks.
    pub validate: f64,
    /// Pose PCA.
    pub pose_pca: f64,
    /// Vertex basis (randomized SVD).
    pub vertex_basis: f64,
    /// Basis coordinates of every row (or the raw outputs for the identity basis).
    pub projection: f64,
    /// Ridge factorisation and α selection.
    pub cross_validation: f64,
    /// Final solve and packing.
    pub solve: f64,
}

/// What the fit measured, for reports and the paper's figures.
#[derive(Clone, Debug, PartialEq)]
pub struct FitReport {
    /// Angle-covariance eigenvalues, descending (Figure 4).
    pub pose_eigenvalues: Vec<f64>,
    /// Captured energy `σ_k²` of the leading vertex components (empty for the identity basis).
    pub coef_energy: Vec<f64>,
    /// `‖R‖_F²` of all coefficient rows (the total `coef_energy` is a fraction of).
    pub coef_total_energy: f64,
    /// CV and train error against α (Figure 3); empty for a fixed α or no pose dependence.
    pub cv_curve: Vec<CvPoint>,
    /// The α of the model.
    pub alpha: f64,
    /// Poses per held-out segment, when α was cross-validated.
    pub cv_segment: Option<usize>,
    /// Time per stage.
    pub seconds: StageSeconds,
}

/// A fitted model and its report.
#[derive(Clone, Debug, PartialEq)]
pub struct Fit {
    /// The model, in the runtime semantics of [`LinearModel::predict`].
    pub model: LinearModel,
    /// Spectra, CV curve, timings.
    pub report: FitReport,
}

/// Fits the pose-driven linear model.
///
/// `angles` is `p × a` (one row of joint angles per pose); `transfers[i]` is pose i's
/// transfer, `v × n²` vertex-major (`[j·n² + c]`), for SH order `order` (`n²` coefficients).
pub fn fit(
    angles: &DMatrix<f64>,
    transfers: &[Vec<f32>],
    order: usize,
    options: &FitOptions,
) -> Result<Fit, FitError> {
    let clock = Instant::now();
    let vertices = validate(angles, transfers, order, options)?;
    let (p, n2) = (transfers.len(), order * order);
    let mut seconds = StageSeconds {
        validate: clock.elapsed().as_secs_f64(),
        ..Default::default()
    };

    let clock = Instant::now();
    let pca = PosePca::fit(angles, options.pose_dims);
    let z = pca.project(angles);
    seconds.pose_pca = clock.elapsed().as_secs_f64();

    let rows = PoseRows::new(transfers, n2, vertices);
    let clock = Instant::now();
    let (basis, coef_energy, coef_total_energy) = match options.coef_dims {
        CoefDims::Full => (None, Vec::new(), rows.frobenius_sq()),
        CoefDims::Count(k) => split(fit_vertex_basis(&rows, Dims::Count(k))),
        CoefDims::Variance(f) => split(fit_vertex_basis(&rows, Dims::Variance(f))),
    };
    seconds.vertex_basis = clock.elapsed().as_secs_f64();

    let clock = Instant::now();
    let outputs = match &basis {
        Some(b) => project_rows(&rows, b),
        None => raw_rows(&rows),
    };
    seconds.projection = clock.elapsed().as_secs_f64();

    let clock = Instant::now();
    let problem = RidgeProblem::new(&z, outputs);
    let (alpha, cv_curve, cv_segment) = match options.alpha {
        Alpha::Fixed(alpha) => (alpha, Vec::new(), None),
        Alpha::Loo => select(&problem, 1)?,
        Alpha::Loso { segment } => select(&problem, segment.unwrap_or(p.div_ceil(10)))?,
    };
    seconds.cross_validation = clock.elapsed().as_secs_f64();

    let clock = Instant::now();
    let solution = problem.solve(alpha);
    let kv = basis.as_ref().map_or(vertices, |b| b.ncols());
    let ka = pca.dims();
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
    let model = LinearModel {
        order,
        vertices,
        pose_len: angles.ncols(),
        pose_mean: pca.mean.clone(),
        // nalgebra is column-major; the model stores P row-major.
        pose_projection: pca.projection.transpose().as_slice().to_vec(),
        weights,
        basis: match basis {
            // v × k_v vertex-major is the row-major layout, i.e. the transpose's column-major one.
            Some(b) => VertexBasis::Stored {
                coef_dims: b.ncols(),
                data: b.transpose().as_slice().to_vec(),
            },
            None => VertexBasis::Identity,
        },
        alpha,
        bones: None,
        angle_names: Vec::new(),
    };
    seconds.solve = clock.elapsed().as_secs_f64();

    let report = FitReport {
        pose_eigenvalues: pca.eigenvalues,
        coef_energy,
        coef_total_energy,
        cv_curve,
        alpha,
        cv_segment,
        seconds,
    };
    Ok(Fit { model, report })
}

fn split(fit: VertexBasisFit) -> (Option<DMatrix<f64>>, Vec<f64>, f64) {
    (Some(fit.basis), fit.energies, fit.total_energy)
}

fn select(
    problem: &RidgeProblem,
    segment: usize,
) -> Result<(f64, Vec<CvPoint>, Option<usize>), FitError> {
    let selection = problem.select_alpha(segment)?;
    Ok((
        selection.alpha,
        selection.curve,
        (problem.rank() > 0).then_some(segment.max(1)),
    ))
}

/// Checks shapes, finiteness and options; returns the vertex count.
fn validate(
    angles: &DMatrix<f64>,
    transfers: &[Vec<f32>],
    order: usize,
    options: &FitOptions,
) -> Result<usize, FitError> {
    let p = transfers.len();
    if p == 0 && angles.nrows() == 0 {
        return Err(FitError::NoPoses);
    }
    if angles.nrows() != p {
        return Err(FitError::PoseCountMismatch {
            angles: angles.nrows(),
            transfers: p,
        });
    }
    if order == 0 {
        return Err(FitError::ZeroOrder);
    }
    let n2 = order * order;
    let len0 = transfers[0].len();
    if !len0.is_multiple_of(n2) {
        return Err(FitError::TransferLength {
            pose: 0,
            len: len0,
            expected: len0.next_multiple_of(n2),
            coefs: n2,
        });
    }
    if len0 == 0 {
        return Err(FitError::NoVertices);
    }
    for (pose, t) in transfers.iter().enumerate() {
        if t.len() != len0 {
            return Err(FitError::TransferLength {
                pose,
                len: t.len(),
                expected: len0,
                coefs: n2,
            });
        }
        if let Some(index) = t.iter().position(|x| !x.is_finite()) {
            return Err(FitError::NonFiniteTransfer { pose, index });
        }
        if let Some(joint) = angles.row(pose).iter().position(|x| !x.is_finite()) {
            return Err(FitError::NonFiniteAngle { pose, joint });
        }
        // Squares of larger angles overflow in the solvers, and the runtime could not take them.
        let largest = f64::from(f32::MAX);
        if let Some(joint) = angles.row(pose).iter().position(|x| x.abs() > largest) {
            let value = angles[(pose, joint)];
            return Err(FitError::AngleOutOfRange { pose, joint, value });
        }
    }
    match options.alpha {
        Alpha::Fixed(alpha) if !(alpha.is_finite() && alpha >= 0.0) => {
            return Err(FitError::InvalidAlpha(alpha));
        }
        _ => {}
    }
    let fractions = [
        match options.pose_dims {
            Dims::Variance(f) => Some(f),
            _ => None,
        },
        match options.coef_dims {
            CoefDims::Variance(f) => Some(f),
            _ => None,
        },
    ];
    if let Some(f) = fractions
        .into_iter()
        .flatten()
        .find(|f| !(*f > 0.0 && *f <= 1.0))
    {
        return Err(FitError::InvalidFraction(f));
    }
    Ok(len0 / n2)
}
