//! Fitting stage of the trainer: from poses and baked transfer to a [`LinearModel`].
//!
//! Pipeline (Nowrouzezahrai et al., *Compact and Efficient Generation of Radiance Transfer for
//! Dynamically Articulated Characters*): pose PCA (`z = P (a − μ)`) → shared vertex basis over
//! all `p·n²` coefficient rows (randomized SVD) → basis coordinates of each pose's rows → one
//! ridge regression of all `n²·k_v` outputs on z with a single α chosen by closed-form cross
//! validation → weights packed in the runtime layout.

mod dims;
mod local;
mod pose_pca;
mod ridge;
mod rsvd;
mod vertex_basis;

#[cfg(test)]
mod tests;

pub use dims::Dims;
pub use local::{EntryGroup, Locality};
pub use pose_pca::PosePca;
pub use ridge::{
    AlphaSelection, CvPoint, HeldOut, RidgeOutputs, RidgeProblem, RidgeSolution, RidgeTarget,
    segments,
};
pub use rsvd::{RowOperator, SketchOptions, TruncatedSvd, randomized_svd};
pub use vertex_basis::{
    Deflated, PoseRows, VertexBasisFit, field_basis, fit_vertex_basis, project_rows, raw_rows,
};

use std::time::Instant;

use aprt_core::{MAX_POSE_DIMS, MAX_POSE_LEN};
use nalgebra::{DMatrix, DVector};

use crate::model::features::PoseFeatures;
use crate::model::occluders::{OccluderChoice, Occluders};
use crate::model::{LinearModel, PoseBounds, VertexBasis};
use local::{LocalFit, LocalScoring, fit_local};

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

/// What the model tends to as α grows (and where a bounded model goes far from its poses).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Prior {
    /// The mean training transfer at the mean pose: the paper's unpenalised intercept.
    Mean,
    /// The anchor (the rest pose and its transfer) when the source has one (bone-frame models
    /// of characters), the mean otherwise: the fit passes through the anchor and only adds
    /// what the data supports.
    Rest,
    /// Whichever of the two has the lower held-out error (the mean when there is no anchor).
    Auto,
}

/// The prior a fit chose.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum PriorKind {
    /// The mean training transfer.
    Mean,
    /// The rest pose's transfer.
    Rest,
}

impl PriorKind {
    /// The name of the command line and the reports.
    pub fn name(self) -> &'static str {
        match self {
            PriorKind::Mean => "mean",
            PriorKind::Rest => "rest",
        }
    }
}

/// Options of [`fit`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FitOptions {
    /// k_a ([`Dims::Auto`]: chosen by held-out error).
    pub pose_dims: Dims,
    /// k_v.
    pub coef_dims: CoefDims,
    /// α selection.
    pub alpha: Alpha,
    /// The prior the model tends to.
    pub prior: Prior,
    /// `Some(falloff)`: poses are brought inside the box of the training poses (and the
    /// prior's), and blended towards the prior's pose as they leave it, reaching the prior
    /// `falloff` box widths outside (infinite: clamped only); `None`: the paper's unbounded
    /// linear extrapolation.
    pub bound: Option<f64>,
    /// Whether the local model (each vertex on the entries that move geometry near it, from
    /// [`FitInput::locality`]) is a candidate, the only one, or not tried.
    pub local: Local,
    /// The pose features the model is linear in.
    pub features: Features,
    /// Whether occluder proxies shadow what the poses do not show (bone-frame models of
    /// characters; `model::train::fit_clip` fits with and without them).
    pub proxies: Occluders,
}

/// The pose features a fit may use (see [`PoseFeatures`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Features {
    /// The angles alone, as in the paper.
    Angles,
    /// The angles and `1 − cos a` of every entry some vertex depends on: shadowing that is the
    /// same whichever way a joint turns.
    Cosines,
    /// Whichever of the two has the lower held-out error.
    Auto,
}

/// Whether the selection tries the local model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Local {
    /// A candidate beside the shared ones, kept when its held-out error is lower.
    Auto,
    /// The only candidate (an error when the fit has no groups or no anchor for it).
    Only,
    /// Not tried: the paper's model, every vertex on every entry.
    Off,
}

/// The radius of the locality, as a fraction of the bind mesh's bounding-box diagonal: a
/// vertex depends on the entries that move geometry within it.
pub const LOCALITY_RADIUS: f64 = 0.1;

/// The falloff of the default bound, in box widths (see [`FitOptions::bound`]).
pub const DEFAULT_FALLOFF: f64 = 0.5;

impl Default for FitOptions {
    /// The prior and k_a chosen by held-out error, the paper's 22 vertex vectors, α by
    /// leave-segment-out with ten segments, bounded poses, the angles as features (the
    /// cosines chosen by held-out segments lost on the real characters' novel clips: see
    /// docs/results).
    fn default() -> Self {
        Self {
            pose_dims: Dims::Auto,
            coef_dims: CoefDims::Count(22),
            alpha: Alpha::Loso { segment: None },
            prior: Prior::Auto,
            bound: Some(DEFAULT_FALLOFF),
            local: Local::Auto,
            features: Features::Angles,
            proxies: Occluders::Auto,
        }
    }
}

impl FitOptions {
    /// The paper's model: every pose dimension, the mean as prior, no bound, no local model,
    /// no proxies.
    pub fn paper() -> Self {
        Self {
            pose_dims: Dims::All,
            prior: Prior::Mean,
            bound: None,
            local: Local::Off,
            proxies: Occluders::None,
            ..Self::default()
        }
    }
}

/// One candidate of the model selection and its held-out error.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Choice {
    /// The prior.
    pub prior: PriorKind,
    /// k_a.
    pub pose_dims: usize,
    /// Whether this is the local model (each vertex on the entries near it, every entry
    /// kept) rather than the shared map from k_a pose coordinates.
    pub local: bool,
    /// Whether the pose features hold the cosines besides the angles.
    pub cosines: bool,
    /// The best α for this candidate.
    pub alpha: f64,
    /// Held-out mean squared error per transfer value (`v·n²` per pose, the basis's
    /// truncation included) at that α: comparable across every candidate.
    pub held_out_error: f64,
    /// In-sample error at that α, in the same units.
    pub train_error: f64,
}

/// What the selection held out.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum HeldOutKind {
    /// Contiguous runs of this many poses within each training clip.
    Segments(usize),
    /// This many whole validation clips.
    Clips(usize),
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
    /// The anchor's or a validation clip's shape disagrees with the training poses.
    #[error("{what}: {found}, expected {expected}")]
    HeldOutShape {
        /// The anchor or validation clip.
        what: String,
        /// What it has.
        found: String,
        /// What the training poses imply.
        expected: String,
    },
    /// The cosine features were asked for but would outnumber the runtime's limit.
    #[error(
        "{features} pose features (the angles and their cosines) exceed the runtime's {max}; use --features angles"
    )]
    TooManyFeatures {
        /// Features the cosines would make.
        features: usize,
        /// The runtime's limit.
        max: usize,
    },
    /// The local model was asked for alone but cannot be fitted.
    #[error("the local model cannot be fitted: {0}")]
    NoLocalModel(&'static str),
    /// Every α of the grid left some held-out set unpredictable.
    #[error("cross validation error is infinite for every alpha")]
    NoFiniteCvError,
}

/// Wall-clock seconds per stage (summed over the feature sets tried).
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

impl StageSeconds {
    /// Adds `other`'s seconds stage by stage.
    fn add(&mut self, other: &StageSeconds) {
        self.validate += other.validate;
        self.pose_pca += other.pose_pca;
        self.vertex_basis += other.vertex_basis;
        self.projection += other.projection;
        self.cross_validation += other.cross_validation;
        self.solve += other.solve;
    }
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
    /// Poses per held-out segment, when α was cross-validated on segments.
    pub cv_segment: Option<usize>,
    /// The prior of the model.
    pub prior: PriorKind,
    /// What the selection held out.
    pub held_out: HeldOutKind,
    /// Every candidate (features, prior, k_a or local) with its best α and held-out error, in
    /// the order tried.
    pub choices: Vec<Choice>,
    /// The candidate the model is.
    pub chosen: Choice,
    /// [`rest_distance`] of the anchor, when the fit has one and some entry moves.
    pub rest_distance: Option<f64>,
    /// Time per stage.
    pub seconds: StageSeconds,
    /// What the occluder proxies did, when they were tried.
    pub occluders: Option<OccluderChoice>,
}

/// A fitted model and its report.
#[derive(Clone, Debug, PartialEq)]
pub struct Fit {
    /// The model, in the runtime semantics of [`LinearModel::predict`].
    pub model: LinearModel,
    /// Spectra, CV curve, timings.
    pub report: FitReport,
}

/// A pose whose transfer is known and that the model tends to as α grows: for bone-frame
/// models the rest pose, whose bone-frame transfer is the rest transfer carried by the skin.
#[derive(Clone, Copy, Debug)]
pub struct Anchor<'a> {
    /// Its pose vector (a values).
    pub angles: &'a [f64],
    /// Its transfer, `v × n²` vertex-major, in the frame the model learns.
    pub transfer: &'a [f32],
}

/// A clip held out whole to choose the model by (`--validate`).
#[derive(Clone, Copy, Debug)]
pub struct Validation<'a> {
    /// `p_h × a` pose vectors.
    pub angles: &'a DMatrix<f64>,
    /// Transfer of each pose, in the frame the model learns.
    pub transfers: &'a [Vec<f32>],
}

/// What the fit learns from: the training poses and their transfer, how they split into
/// clips, the anchor and the held-out clips.
#[derive(Clone, Debug)]
pub struct FitInput<'a> {
    /// `p × a`, one row of pose entries per pose.
    pub angles: &'a DMatrix<f64>,
    /// `transfers[i]` is pose i's transfer, `v × n²` vertex-major (`[j·n² + c]`).
    pub transfers: &'a [Vec<f32>],
    /// SH order n.
    pub order: usize,
    /// Poses per clip, in order (held-out segments never straddle two clips); empty: one clip.
    pub clips: Vec<usize>,
    /// The prior pose, if the model has one besides the mean.
    pub anchor: Option<Anchor<'a>>,
    /// Clips held out whole: when given, they alone choose α, k_a and the prior.
    pub validation: Vec<Validation<'a>>,
    /// The vertex groups of the local model (needs the anchor), when the caller offers one.
    pub locality: Option<&'a Locality>,
}

impl<'a> FitInput<'a> {
    /// Poses of one clip, no anchor, no held-out clips.
    pub fn new(angles: &'a DMatrix<f64>, transfers: &'a [Vec<f32>], order: usize) -> Self {
        Self {
            angles,
            transfers,
            order,
            clips: Vec::new(),
            anchor: None,
            validation: Vec::new(),
            locality: None,
        }
    }
}

/// The pose entries no vertex group depends on (none without a locality).
fn unused_entries(input: &FitInput<'_>) -> Vec<usize> {
    let Some(locality) = input.locality else {
        return Vec::new();
    };
    (0..input.angles.ncols())
        .filter(|&i| !locality.groups.iter().any(|g| g.entries.contains(&i)))
        .collect()
}

/// The training and validation poses with `entries` set to the anchor's values; `None` when
/// there is nothing to pin (no entries, or no anchor).
fn pin_entries(
    input: &FitInput<'_>,
    entries: &[usize],
) -> Option<(DMatrix<f64>, Vec<DMatrix<f64>>)> {
    let anchor = input.anchor.filter(|_| !entries.is_empty())?;
    let pin = |angles: &DMatrix<f64>| {
        let mut pinned = angles.clone();
        for &i in entries {
            pinned.column_mut(i).fill(anchor.angles[i]);
        }
        pinned
    };
    let held = input.validation.iter().map(|v| pin(v.angles)).collect();
    Some((pin(input.angles), held))
}

/// Fits the pose-driven linear model to one clip: [`fit_input`] with no anchor.
///
/// `angles` is `p × a` (one row of joint angles per pose); `transfers[i]` is pose i's
/// transfer, `v × n²` vertex-major (`[j·n² + c]`), for SH order `order` (`n²` coefficients).
pub fn fit(
    angles: &DMatrix<f64>,
    transfers: &[Vec<f32>],
    order: usize,
    options: &FitOptions,
) -> Result<Fit, FitError> {
    fit_input(&FitInput::new(angles, transfers, order), options)
}

/// Fits the pose-driven linear model: the vertex basis over the training poses (and the
/// anchor), then for each candidate feature set, prior and k_a (and the local model) the
/// ridge, with α and all of these chosen by held-out error (segments of the clips, or the
/// validation clips).
pub fn fit_input(input: &FitInput<'_>, options: &FitOptions) -> Result<Fit, FitError> {
    let clock = Instant::now();
    let vertices = validate(input, options)?;
    // Entries no vertex depends on (a root turn, in bone frames) are held at the anchor's
    // value in every pose the fit sees, so nothing is learnt from them, and the bound does not
    // blend the pose towards the prior when they move: the character turning round is not a
    // pose it was not trained on.
    let unused = unused_entries(input);
    let pinned = pin_entries(input, &unused);
    let pinned_input;
    let input = match &pinned {
        Some((angles, held)) => {
            pinned_input = FitInput {
                angles,
                validation: input
                    .validation
                    .iter()
                    .zip(held)
                    .map(|(v, angles)| Validation {
                        angles,
                        transfers: v.transfers,
                    })
                    .collect(),
                ..input.clone()
            };
            &pinned_input
        }
        None => input,
    };
    let a = input.angles.ncols();
    let used: Vec<bool> = (0..a).map(|i| !unused.contains(&i)).collect();
    let (angles_only, cosines) = (PoseFeatures::new(a, &[]), PoseFeatures::new(a, &used));
    let cosines_fit = cosines.count() <= MAX_POSE_LEN && !cosines.is_angles();
    let sets = match options.features {
        Features::Angles => vec![angles_only],
        Features::Cosines if cosines.count() > MAX_POSE_LEN => {
            return Err(FitError::TooManyFeatures {
                features: cosines.count(),
                max: MAX_POSE_LEN,
            });
        }
        Features::Cosines => vec![cosines],
        Features::Auto if cosines_fit => vec![angles_only, cosines],
        Features::Auto => vec![angles_only],
    };
    // A rest pose far from every training pose is a poor prior: the anchored fit must bridge
    // the whole distance, and poses the bound blends towards it are lit like a pose the
    // character never took. `auto` then keeps the mean.
    let rest_distance = input
        .anchor
        .and_then(|a| rest_distance(input.angles, a.angles));
    let far = rest_distance.is_some_and(|d| d > REST_DISTANCE_LIMIT);
    let options = &FitOptions {
        prior: match options.prior {
            Prior::Auto if far => Prior::Mean,
            prior => prior,
        },
        ..*options
    };
    let validated = clock.elapsed().as_secs_f64();
    let mut best: Option<Fit> = None;
    let mut choices = Vec::new();
    let mut seconds = StageSeconds {
        validate: validated,
        ..Default::default()
    };
    for features in &sets {
        let fit = fit_features(input, options, vertices, &unused, features)?;
        choices.extend_from_slice(&fit.report.choices);
        seconds.add(&fit.report.seconds);
        let better = best.as_ref().is_none_or(|b| {
            let (new, old) = (
                fit.report.chosen.held_out_error,
                b.report.chosen.held_out_error,
            );
            new.is_finite() && new < old
        });
        if better {
            best = Some(fit);
        }
    }
    let mut fit = best.expect("every fit has at least one feature set");
    fit.report.choices = choices;
    fit.report.seconds = seconds;
    fit.report.rest_distance = rest_distance;
    Ok(fit)
}

/// Above this [`rest_distance`], `--prior auto` does not try the rest prior. Measured on the
/// training poses of docs/results and the demo, the rest prior gave the lower test error at
/// 1.2 (built-in character) and 3.3 (RiggedFigure), the higher at 2.9 (CesiumMan), 3.9 (the
/// CMU mannequin's T-pose under a walk) and 13.5 (Fox): no threshold separates them, and 2
/// keeps it where the demo needs it and drops it where the larger studies lose by it.
pub const REST_DISTANCE_LIMIT: f64 = 2.0;

/// How far the rest pose lies from the training poses: the RMS over the entries that move of
/// its distance from their mean in standard deviations. `None` when no entry moves.
pub fn rest_distance(angles: &DMatrix<f64>, rest: &[f64]) -> Option<f64> {
    let z2: Vec<f64> = angles
        .column_iter()
        .zip(rest)
        .filter_map(|(column, &r)| {
            let sd = column.variance().sqrt();
            (sd > 1e-9).then(|| ((r - column.mean()) / sd).powi(2))
        })
        .collect();
    (!z2.is_empty()).then(|| (z2.iter().sum::<f64>() / z2.len() as f64).sqrt())
}

/// [`fit_input`] for one set of pose features, of training and validation poses that are
/// already pinned (`unused` entries held at the anchor's value).
fn fit_features(
    pinned: &FitInput<'_>,
    options: &FitOptions,
    vertices: usize,
    unused: &[usize],
    features: &PoseFeatures,
) -> Result<Fit, FitError> {
    // Everything but the bound sees the features; the bound stays on the angles the runtime
    // is given.
    let raw = pinned.angles;
    let x = features.of_rows(raw);
    let held_x: Vec<DMatrix<f64>> = pinned
        .validation
        .iter()
        .map(|v| features.of_rows(v.angles))
        .collect();
    let anchor_x = pinned.anchor.map(|a| features.of(a.angles));
    let locality = pinned.locality.map(|l| Locality {
        groups: l
            .groups
            .iter()
            .map(|g| EntryGroup {
                entries: features.of_entries(&g.entries),
                vertices: g.vertices.clone(),
            })
            .collect(),
    });
    let input = &FitInput {
        angles: &x,
        validation: pinned
            .validation
            .iter()
            .zip(&held_x)
            .map(|(v, angles)| Validation {
                angles,
                transfers: v.transfers,
            })
            .collect(),
        anchor: pinned
            .anchor
            .zip(anchor_x.as_deref())
            .map(|(a, angles)| Anchor {
                angles,
                transfer: a.transfer,
            }),
        locality: locality.as_ref(),
        ..pinned.clone()
    };
    let (angles, transfers, order) = (input.angles, input.transfers, input.order);
    let (p, n2) = (transfers.len(), order * order);
    let mut seconds = StageSeconds::default();
    let with_cosines = !features.is_angles();

    let clock = Instant::now();
    let pca = PosePca::fit(angles, options.pose_dims);
    let z = pca.project(angles);
    seconds.pose_pca = clock.elapsed().as_secs_f64();

    let rows = PoseRows::new(transfers, n2, vertices);
    let clock = Instant::now();
    // An anchored basis spans the anchor's coefficient fields exactly (when k_v leaves room
    // for more), so the prior costs no truncation error.
    let anchor_basis = input.anchor.filter(|_| options.prior != Prior::Mean);
    let prior_fields = match (anchor_basis, options.coef_dims) {
        (Some(anchor), CoefDims::Count(k)) if k > n2 => Some(field_basis(anchor.transfer, n2)),
        (Some(anchor), CoefDims::Variance(_)) => Some(field_basis(anchor.transfer, n2)),
        _ => None,
    };
    let (basis, coef_energy, coef_total_energy) = match (options.coef_dims, &prior_fields) {
        (CoefDims::Full, _) => (None, Vec::new(), rows.frobenius_sq()),
        (CoefDims::Count(k), None) => split(fit_vertex_basis(&rows, Dims::Count(k))),
        (CoefDims::Variance(f), None) => split(fit_vertex_basis(&rows, Dims::Variance(f))),
        (dims, Some(q)) => {
            let rest = match dims {
                CoefDims::Count(k) => Dims::Count(k - q.ncols()),
                CoefDims::Variance(f) => Dims::Variance(f),
                CoefDims::Full => unreachable!("the full model has no basis"),
            };
            let residual = fit_vertex_basis(&Deflated::new(&rows, q), rest);
            let both = beside(q, &residual.basis);
            (Some(both), residual.energies, residual.total_energy)
        }
    };
    seconds.vertex_basis = clock.elapsed().as_secs_f64();

    let clock = Instant::now();
    let outputs_of = |transfers: &[&[f32]]| {
        let rows = PoseRows::from_slices(transfers.to_vec(), n2, vertices);
        match &basis {
            Some(b) => project_rows(&rows, b),
            None => raw_rows(&rows),
        }
    };
    // The part of a pose's transfer outside the basis: the same for every candidate that
    // predicts in the basis, and part of its error.
    let outside = |transfers: &[&[f32]], outputs: &DMatrix<f64>| {
        let rows = PoseRows::from_slices(transfers.to_vec(), n2, vertices);
        (rows.frobenius_sq() - outputs.norm_squared()).max(0.0)
    };
    let train_slices: Vec<&[f32]> = transfers.iter().map(Vec::as_slice).collect();
    let train_outputs = outputs_of(&train_slices);
    let outside_train = outside(&train_slices, &train_outputs);
    let outputs = RidgeOutputs::new(train_outputs);
    let anchor = input.anchor.map(|a| {
        let z0 = pca.project(&DMatrix::from_row_slice(1, a.angles.len(), a.angles));
        let y0 = outputs_of(&[a.transfer]);
        (
            z0.row(0).transpose(),
            y0.row(0).transpose(),
            a.angles.to_vec(),
        )
    });
    let mut held = Vec::new();
    let mut outside_held = 0.0;
    for v in &input.validation {
        let slices: Vec<&[f32]> = v.transfers.iter().map(Vec::as_slice).collect();
        let y = outputs_of(&slices);
        outside_held += outside(&slices, &y);
        held.push(HeldOut {
            z: pca.project(v.angles),
            y,
        });
    }
    let held_poses: usize = held.iter().map(|h| h.y.nrows()).sum();
    seconds.projection = clock.elapsed().as_secs_f64();

    let clock = Instant::now();
    let clips = if input.clips.is_empty() {
        vec![p]
    } else {
        input.clips.clone()
    };
    let segment = match options.alpha {
        Alpha::Loo => 1,
        Alpha::Loso { segment } => segment.unwrap_or(p.div_ceil(10)).max(1),
        Alpha::Fixed(_) => p.div_ceil(10).max(1),
    };
    let runs = segments(&clips, segment);
    let scoring = if held.is_empty() {
        Scoring::Segments(&runs)
    } else {
        Scoring::Clips(&held)
    };
    let priors: Vec<PriorKind> = match (options.prior, &anchor) {
        (_, None) | (Prior::Mean, _) => vec![PriorKind::Mean],
        (Prior::Rest, Some(_)) => vec![PriorKind::Rest],
        (Prior::Auto, Some(_)) => vec![PriorKind::Rest, PriorKind::Mean],
    };
    let candidates = pose_dim_candidates(options.pose_dims, pca.dims());
    let target_of = |prior: PriorKind| match (prior, &anchor) {
        (PriorKind::Rest, Some((_, y0, _))) => outputs.around_anchor(y0),
        _ => outputs.around_mean(),
    };
    // The leading k pose coordinates, and the anchor's when the prior is the rest pose.
    let inputs_of = |prior: PriorKind, k: usize| {
        let z0 = match (prior, &anchor) {
            (PriorKind::Rest, Some((z0, _, _))) => Some(z0.rows(0, k).into_owned()),
            _ => None,
        };
        (z.columns(0, k).into_owned(), z0)
    };
    // Errors per transfer value: basis coordinates plus what lies outside the basis.
    let kv = basis.as_ref().map_or(vertices, |b| b.ncols());
    let per_value = |mse: f64, poses: usize, outside: f64| {
        if mse == f64::MAX {
            return mse;
        }
        let poses = poses.max(1) as f64;
        (mse * poses * (n2 * kv) as f64 + outside) / (poses * (vertices * n2) as f64)
    };
    let (scored_poses, outside_scored) = if held.is_empty() {
        (p, outside_train)
    } else {
        (held_poses, outside_held)
    };
    let mut choices = Vec::new();
    let mut best: Option<(Choice, Vec<CvPoint>)> = None;
    let local_wanted = options.local != Local::Off;
    let local_ready = match (input.locality, input.anchor, options.coef_dims) {
        (None, _, _) => {
            Err("no vertex groups were given (bone-frame models of characters have them)")
        }
        (_, None, _) => Err("it needs the rest pose as anchor"),
        _ if options.prior == Prior::Mean => Err("it is anchored at the rest pose, not the mean"),
        (_, _, CoefDims::Count(k)) if k > n2 => Ok(k),
        _ => Err("it needs --coef-dims above n² (the rest transfer's fields)"),
    };
    let local_ready = local_ready.and_then(|k| {
        if angles.ncols() > MAX_POSE_DIMS {
            Err("it keeps every pose entry, more than the runtime's 128 pose dimensions")
        } else if p < 2 {
            Err("it needs at least two poses")
        } else {
            Ok(k)
        }
    });
    if options.local == Local::Only
        && let Err(why) = local_ready
    {
        return Err(FitError::NoLocalModel(why));
    }
    let shared = if options.local == Local::Only {
        &[][..]
    } else {
        &priors[..]
    };
    for &prior in shared {
        let target = target_of(prior);
        for &k in &candidates {
            let (zk, z0) = inputs_of(prior, k);
            let problem = RidgeProblem::new(&zk, z0.as_ref(), &target);
            let (alpha, curve) = match options.alpha {
                Alpha::Fixed(alpha) => (alpha, vec![scoring.point(&problem, alpha)]),
                _ => {
                    let selection = scoring.select(&problem)?;
                    (selection.alpha, selection.curve)
                }
            };
            let point = match curve.iter().find(|c| c.alpha == alpha) {
                Some(point) => *point,
                // No pose dependence (one pose, or joints that never move): the candidates
                // are constant, nothing is held out, and they tie.
                None if problem.rank() == 0 => CvPoint {
                    alpha,
                    cv_error: f64::MAX,
                    train_error: f64::MAX,
                },
                None => scoring.point(&problem, alpha),
            };
            let choice = Choice {
                prior,
                pose_dims: k,
                local: false,
                cosines: with_cosines,
                alpha,
                held_out_error: per_value(point.cv_error, scored_poses, outside_scored),
                train_error: per_value(point.train_error, p, outside_train),
            };
            consider(&mut choices, &mut best, choice, curve);
        }
    }
    let local = match (input.locality, input.anchor, local_ready) {
        (Some(locality), Some(anchor), Ok(k)) if local_wanted => {
            let pairs: Vec<(&DMatrix<f64>, &[Vec<f32>])> = input
                .validation
                .iter()
                .map(|v| (v.angles, v.transfers))
                .collect();
            let scoring = if pairs.is_empty() {
                LocalScoring::Segments(&runs)
            } else {
                LocalScoring::Clips(&pairs)
            };
            let fitted = fit_local(
                locality,
                angles,
                transfers,
                n2,
                (anchor.angles, anchor.transfer),
                &scoring,
                options.alpha,
            )?;
            let scored: Vec<&DMatrix<f64>> = if pairs.is_empty() {
                vec![angles]
            } else {
                pairs.iter().map(|(a, _)| *a).collect()
            };
            let model = LocalModel::new(&fitted, anchor, n2, k, angles, &scored);
            let best_point = fitted
                .curve
                .iter()
                .find(|c| c.alpha == fitted.alpha)
                .copied()
                .ok_or(FitError::NoFiniteCvError)?;
            let choice = Choice {
                prior: PriorKind::Rest,
                pose_dims: angles.ncols(),
                local: true,
                cosines: with_cosines,
                alpha: fitted.alpha,
                held_out_error: best_point.cv_error + model.outside_scored,
                train_error: best_point.train_error + model.outside_train,
            };
            consider(&mut choices, &mut best, choice, fitted.curve.clone());
            Some(model)
        }
        _ => None,
    };
    let (chosen, cv_curve) = best.ok_or(FitError::NoFiniteCvError)?;
    if !chosen.held_out_error.is_finite() && !matches!(options.alpha, Alpha::Fixed(_)) {
        return Err(FitError::NoFiniteCvError);
    }
    seconds.cross_validation = clock.elapsed().as_secs_f64();

    let clock = Instant::now();
    let alpha = chosen.alpha;
    let bound_of = |prior: &[f64]| {
        options
            .bound
            .map(|f| PoseBounds::of(raw, prior, f).ignoring(unused.to_vec()))
    };
    let flags = features.flags();
    let (model, problem_rank, coef_energy) = match &local {
        Some(local) if chosen.local => {
            let anchor = input.anchor.expect("the local model needs the anchor");
            let raw_anchor = pinned.anchor.expect("the local model needs the anchor");
            let bounds = bound_of(raw_anchor.angles);
            let model = LinearModel {
                order,
                vertices,
                pose_len: raw.ncols(),
                pose_mean: anchor.angles.to_vec(),
                pose_projection: DMatrix::<f64>::identity(angles.ncols(), angles.ncols())
                    .as_slice()
                    .to_vec(),
                weights: local.weights.clone(),
                basis: stored(&local.basis),
                alpha,
                bones: None,
                angle_names: Vec::new(),
                bounds,
                cosines: flags,
                proxies: None,
            };
            (model, 1, local.energies.clone())
        }
        _ => {
            // Solved again rather than kept from the loop: the full model's solutions are large.
            let ka = chosen.pose_dims;
            let target = target_of(chosen.prior);
            let (zk, z0) = inputs_of(chosen.prior, ka);
            let problem = RidgeProblem::new(&zk, z0.as_ref(), &target);
            let solution = problem.solve(alpha);
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
            // The prior's pose in angles: the rest pose, or the mean of the training poses.
            let prior_angles = match (chosen.prior, pinned.anchor) {
                (PriorKind::Rest, Some(a)) => a.angles.to_vec(),
                _ => raw.row_mean().iter().copied().collect(),
            };
            let projection = pca.projection.rows(0, ka).into_owned();
            let model = LinearModel {
                order,
                vertices,
                pose_len: raw.ncols(),
                pose_mean: pca.mean.clone(),
                // nalgebra is column-major; the model stores P row-major.
                pose_projection: projection.transpose().as_slice().to_vec(),
                weights,
                basis: match &basis {
                    Some(b) => stored(b),
                    None => VertexBasis::Identity,
                },
                alpha,
                bones: None,
                angle_names: Vec::new(),
                bounds: bound_of(&prior_angles),
                cosines: flags,
                proxies: None,
            };
            (model, problem.rank(), coef_energy)
        }
    };
    seconds.solve = clock.elapsed().as_secs_f64();

    let report = FitReport {
        pose_eigenvalues: pca.eigenvalues,
        coef_energy,
        coef_total_energy,
        cv_curve,
        alpha,
        cv_segment: (problem_rank > 0 && held.is_empty()).then_some(segment),
        prior: chosen.prior,
        held_out: if held.is_empty() {
            HeldOutKind::Segments(segment)
        } else {
            HeldOutKind::Clips(held.len())
        },
        choices,
        chosen,
        rest_distance: None,
        seconds,
        occluders: None,
    };
    Ok(Fit { model, report })
}

/// Records a candidate and keeps it as the best when its held-out error is lower (the first
/// candidate stands until a finite, lower one comes).
fn consider(
    choices: &mut Vec<Choice>,
    best: &mut Option<(Choice, Vec<CvPoint>)>,
    choice: Choice,
    curve: Vec<CvPoint>,
) {
    choices.push(choice);
    let better = best.as_ref().is_none_or(|(b, _)| {
        choice.held_out_error.is_finite() && choice.held_out_error < b.held_out_error
    });
    if better {
        *best = Some((choice, curve));
    }
}

/// `v × k_v` basis columns as the model stores them.
fn stored(basis: &DMatrix<f64>) -> VertexBasis {
    VertexBasis::Stored {
        coef_dims: basis.ncols(),
        // v × k_v vertex-major is the row-major layout, i.e. the transpose's column-major one.
        data: basis.transpose().as_slice().to_vec(),
    }
}

/// The columns of `a` followed by those of `b`.
fn beside(a: &DMatrix<f64>, b: &DMatrix<f64>) -> DMatrix<f64> {
    DMatrix::from_fn(a.nrows(), a.ncols() + b.ncols(), |j, k| {
        match k.checked_sub(a.ncols()) {
            None => a[(j, k)],
            Some(k) => b[(j, k)],
        }
    })
}

/// The local model in the runtime's layout: its per-vertex map stored through a vertex basis
/// of k_v vectors (the anchor's n² fields exactly, the rest the leading components of the
/// map itself), with what that truncation costs on the scored and the training poses.
struct LocalModel {
    basis: DMatrix<f64>,
    energies: Vec<f64>,
    weights: Vec<f64>,
    /// Truncation error per transfer value on the scored poses.
    outside_scored: f64,
    /// The same on the training poses.
    outside_train: f64,
}

impl LocalModel {
    fn new(
        fitted: &LocalFit,
        anchor: Anchor<'_>,
        n2: usize,
        kv: usize,
        angles: &DMatrix<f64>,
        scored: &[&DMatrix<f64>],
    ) -> Self {
        let (a, vertices) = (angles.ncols(), anchor.transfer.len() / n2);
        let a0 = DVector::from_column_slice(anchor.angles);
        let offsets = |m: &DMatrix<f64>| {
            let mut d = m.clone();
            for mut row in d.row_iter_mut() {
                row -= a0.transpose();
            }
            d
        };
        // Each entry's map weighted by how far the training poses move it, so the basis
        // spends its vectors where predictions vary.
        let train_offsets = offsets(angles);
        let spread: Vec<f64> = (0..a)
            .map(|i| (train_offsets.column(i).norm_squared() / angles.nrows().max(1) as f64).sqrt())
            .collect();
        let pseudo: Vec<Vec<f32>> = (0..a)
            .map(|i| {
                fitted
                    .delta
                    .row(i)
                    .iter()
                    .map(|&x| (x * spread[i]) as f32)
                    .collect()
            })
            .collect();
        let rows = PoseRows::new(&pseudo, n2, vertices);
        let fields = field_basis(anchor.transfer, n2);
        let residual = fit_vertex_basis(
            &Deflated::new(&rows, &fields),
            Dims::Count(kv.saturating_sub(fields.ncols()).max(1)),
        );
        let basis = beside(&fields, &residual.basis);
        let kv = basis.ncols();
        // Per coefficient c: the `v × a` map, its coordinates and what the basis misses.
        let mut weights = vec![0.0; n2 * (a + 1) * kv];
        let mut missed = DMatrix::zeros(a, a);
        for c in 0..n2 {
            let map = DMatrix::from_fn(vertices, a, |j, i| fitted.delta[(i, j * n2 + c)]);
            let coords = basis.tr_mul(&map);
            let y0 = DVector::from_fn(vertices, |j, _| f64::from(anchor.transfer[j * n2 + c]));
            let intercept = basis.tr_mul(&y0);
            for k in 0..kv {
                weights[c * (a + 1) * kv + k] = intercept[k];
                for i in 0..a {
                    weights[(c * (a + 1) + 1 + i) * kv + k] = coords[(k, i)];
                }
            }
            let rest = &map - &basis * coords;
            missed += rest.tr_mul(&rest);
        }
        // Σ over poses of ‖Δaᵀ E‖² = tr(ΔAᵀΔA · EᵀE), per transfer value.
        let outside = |sets: &[&DMatrix<f64>]| {
            let (mut sum, mut poses) = (0.0, 0);
            for m in sets {
                let d = offsets(m);
                sum += (d.tr_mul(&d)).component_mul(&missed).sum();
                poses += m.nrows();
            }
            sum / (poses.max(1) * vertices * n2) as f64
        };
        Self {
            outside_scored: outside(scored),
            outside_train: outside(&[angles]),
            basis,
            energies: residual.energies,
            weights,
        }
    }
}

/// How a candidate is scored: held-out runs of the training clips, or whole held-out clips.
#[derive(Clone, Copy)]
enum Scoring<'a> {
    Segments(&'a [std::ops::Range<usize>]),
    Clips(&'a [HeldOut]),
}

impl Scoring<'_> {
    fn select(&self, problem: &RidgeProblem<'_>) -> Result<AlphaSelection, FitError> {
        match self {
            Scoring::Segments(runs) => problem.select_alpha(runs),
            Scoring::Clips(held) => problem.select_on(held),
        }
    }

    fn point(&self, problem: &RidgeProblem<'_>, alpha: f64) -> CvPoint {
        match self {
            Scoring::Segments(runs) => problem.cv_point(alpha, runs),
            Scoring::Clips(held) => problem.held_out_point(alpha, held),
        }
    }
}

/// The k_a values tried: the one asked for, or (for [`Dims::Auto`]) a doubling ladder up to
/// the rank, so that the selection can trade pose detail for generalisation.
fn pose_dim_candidates(dims: Dims, rank: usize) -> Vec<usize> {
    if dims != Dims::Auto {
        return vec![rank];
    }
    let mut ladder: Vec<usize> = [1, 2, 3, 4, 6, 8, 12, 16, 24, 32, 48, 64]
        .into_iter()
        .filter(|&k| k < rank)
        .collect();
    ladder.push(rank);
    ladder
}

fn split(fit: VertexBasisFit) -> (Option<DMatrix<f64>>, Vec<f64>, f64) {
    (Some(fit.basis), fit.energies, fit.total_energy)
}

/// Checks shapes, finiteness and options; returns the vertex count.
fn validate(input: &FitInput<'_>, options: &FitOptions) -> Result<usize, FitError> {
    let (angles, transfers, order) = (input.angles, input.transfers, input.order);
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
    let shape = |what: String, rows: &DMatrix<f64>, transfers: &[Vec<f32>]| {
        let found = (
            rows.ncols(),
            transfers.iter().map(Vec::len).find(|&l| l != len0),
        );
        if rows.nrows() != transfers.len() || found.0 != angles.ncols() || found.1.is_some() {
            return Err(FitError::HeldOutShape {
                what,
                found: format!(
                    "{} poses of {} entries, {} transfers{}",
                    rows.nrows(),
                    found.0,
                    transfers.len(),
                    found
                        .1
                        .map_or(String::new(), |l| format!(" (one of {l} values)"))
                ),
                expected: format!("{} entries and {len0} transfer values", angles.ncols()),
            });
        }
        if rows.iter().any(|x| !x.is_finite()) || transfers.iter().flatten().any(|x| !x.is_finite())
        {
            return Err(FitError::HeldOutShape {
                what,
                found: "a value that is not finite".into(),
                expected: "finite pose entries and transfer".into(),
            });
        }
        Ok(())
    };
    if let Some(anchor) = &input.anchor {
        let a = DMatrix::from_row_slice(1, anchor.angles.len(), anchor.angles);
        shape("the rest pose".into(), &a, &[anchor.transfer.to_vec()])?;
    }
    for (i, v) in input.validation.iter().enumerate() {
        shape(format!("validation clip {i}"), v.angles, v.transfers)?;
    }
    if !input.clips.is_empty() && input.clips.iter().sum::<usize>() != p {
        return Err(FitError::HeldOutShape {
            what: "the training clips".into(),
            found: format!("{} poses in all", input.clips.iter().sum::<usize>()),
            expected: format!("{p} poses"),
        });
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
