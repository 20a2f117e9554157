//! What a fit reports: every candidate of the selection with its held-out error, what was
//! held out, the spectra and timings, and how far the rest pose lies from the training poses.

use crate::model::occluders::OccluderChoice;
use nalgebra::DMatrix;

use super::PriorKind;
use super::choose::Verdict;
use super::ridge::CvPoint;
use crate::model::LinearModel;

/// One candidate of the model selection and its held-out error.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Choice {
    /// The prior.
    pub prior: PriorKind,
    /// k_a (0 for the prior itself, α = ∞).
    pub pose_dims: usize,
    /// Whether this is the local model (each vertex on the entries near it, every entry
    /// kept) rather than the shared map from k_a pose coordinates.
    pub local: bool,
    /// Whether the pose features hold the cosines besides the angles.
    pub cosines: bool,
    /// The best α for this candidate; infinite for the prior itself (the rest prior's is the
    /// bind transfer carried by the skin, the mean prior's the mean training transfer: the
    /// compact baselines), which JSON writes as `null`.
    pub alpha: f64,
    /// Held-out mean squared error per transfer value (`v·n²` per pose, the basis's
    /// truncation included) at that α: comparable across every candidate.
    pub held_out_error: f64,
    /// In-sample error at that α, in the same units.
    pub train_error: f64,
}

impl Choice {
    /// Whether the candidate is its prior alone (α = ∞): the same transfer at every pose.
    pub fn is_prior(&self) -> bool {
        self.alpha == f64::INFINITY
    }

    /// What the candidate is, as the selection report names it: `k_a 4`, `local 23`, or
    /// `α ∞ (bind transfer, skinned)` for the prior alone.
    pub fn shape(&self) -> String {
        match (self.is_prior(), self.local, self.prior) {
            (true, _, PriorKind::Rest) => "α ∞ (bind transfer, skinned)".to_owned(),
            (true, _, PriorKind::Mean) => "α ∞ (mean training transfer)".to_owned(),
            (false, true, _) => format!("local {:>2}", self.pose_dims),
            (false, false, _) => format!("k_a   {:>2}", self.pose_dims),
        }
    }

    /// The candidate in one phrase: features, prior and shape (`angles, prior rest, k_a 4`).
    pub fn label(&self) -> String {
        let features = if self.cosines { "cosines" } else { "angles" };
        let shape = self
            .shape()
            .split_whitespace()
            .collect::<Vec<_>>()
            .join(" ");
        format!("{features}, prior {}, {shape}", self.prior.name())
    }
}

/// One choice the selection made on validation poses, and by how much (see
/// [`choose`](super::choose)): among the candidates of one feature set, between feature
/// sets, or with and without occluder proxies.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Decision {
    /// `candidates`, `features` or `proxies`.
    pub stage: &'static str,
    /// What was chosen.
    pub chosen: String,
    /// What had the lowest mean validation error.
    pub best: String,
    /// The chosen one's mean error minus the best's; when the best was chosen, its lead
    /// over the nearest rival. Per transfer value, as the errors.
    pub margin: f64,
    /// The standard error of that difference, paired over the validation poses.
    pub standard_error: f64,
    /// Validation poses the errors are over (0: no per-pose errors, the lowest mean won).
    pub poses: usize,
    /// Whether the rule chose a simpler candidate than the best.
    pub tie: bool,
}

impl Decision {
    /// The decision of `verdict` among candidates named by `label`.
    pub fn of(stage: &'static str, verdict: &Verdict, label: impl Fn(usize) -> String) -> Self {
        Self {
            stage,
            chosen: label(verdict.chosen),
            best: label(verdict.best),
            margin: verdict.margin,
            standard_error: verdict.standard_error,
            poses: verdict.poses,
            tie: verdict.tie,
        }
    }

    /// The decision as the selection report says it (the rule is
    /// [`RULE`](super::choose::RULE)).
    pub fn sentence(&self) -> String {
        match (self.poses, self.tie) {
            (0, _) => format!("{}: {}, the lowest held-out error", self.stage, self.chosen),
            (n, true) => format!(
                "{}: {}, simpler than the best ({}) and {:.2e} behind it, within one standard \
                 error ({:.2e} over {n} poses): a tie",
                self.stage, self.chosen, self.best, self.margin, self.standard_error
            ),
            (n, false) => format!(
                "{}: {}, the best, ahead of the nearest by {:.2e}: {:.1} standard errors over \
                 {n} poses",
                self.stage,
                self.chosen,
                self.margin,
                self.margin / self.standard_error.max(f64::MIN_POSITIVE)
            ),
        }
    }
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

/// Wall-clock seconds per stage (summed over the feature sets tried).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FitSeconds {
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

impl FitSeconds {
    /// Adds `other`'s seconds stage by stage.
    pub(super) fn add(&mut self, other: &FitSeconds) {
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
    /// CV and train error against α (Figure 3); empty for a fixed α, no pose dependence, or
    /// the prior alone.
    pub cv_curve: Vec<CvPoint>,
    /// The α of the model (infinite when it is its prior alone).
    pub alpha: f64,
    /// Poses per held-out segment, when α was cross-validated on segments.
    pub cv_segment: Option<usize>,
    /// The prior of the model.
    pub prior: PriorKind,
    /// What the selection held out.
    pub held_out: HeldOutKind,
    /// Every candidate (features, prior, k_a, local or α = ∞) with its best α and held-out
    /// error, in the order tried.
    pub choices: Vec<Choice>,
    /// The candidate the model is.
    pub chosen: Choice,
    /// Each candidate's error on each validation pose, as `choices` (`None` when scored on
    /// held-out runs).
    pub choice_rows: Vec<Option<Vec<f64>>>,
    /// The validation sets, in the order of those poses: name and pose count.
    pub validation_sets: Vec<(String, usize)>,
    /// How the selection decided, stage by stage.
    pub decisions: Vec<Decision>,
    /// [`rest_distance`] of the anchor, when the fit has one and some entry moves.
    pub rest_distance: Option<f64>,
    /// Time per stage.
    pub seconds: FitSeconds,
    /// What the occluder proxies did, when they were tried (`pipeline::train::fit_clip`).
    pub occluders: Option<OccluderChoice>,
}

impl FitReport {
    /// Candidate `i`'s mean error on each validation set alone (NaN without per-pose errors),
    /// its poses' weights in the pooled error undone.
    pub fn set_errors(&self, i: usize) -> Vec<f64> {
        let sizes: Vec<usize> = self.validation_sets.iter().map(|(_, n)| *n).collect();
        let rows = self.choice_rows.get(i).and_then(Option::as_deref);
        let mut start = 0;
        sizes
            .iter()
            .zip(super::scoring::set_weights(&sizes))
            .map(|(&n, weight)| {
                let part = rows.and_then(|r| r.get(start..start + n));
                start += n;
                part.map_or(f64::NAN, |p| {
                    p.iter().sum::<f64>() / (weight * n.max(1) as f64)
                })
            })
            .collect()
    }

    /// The chosen candidate's error on each validation pose, when scored on them.
    pub fn chosen_rows(&self) -> Option<&[f64]> {
        let i = self.choices.iter().position(|c| *c == self.chosen)?;
        self.choice_rows.get(i)?.as_deref()
    }
}

/// A fitted model and its report.
#[derive(Clone, Debug, PartialEq)]
pub struct Fit {
    /// The model, in the runtime semantics of [`LinearModel::predict`].
    pub model: LinearModel,
    /// Spectra, CV curve, timings.
    pub report: FitReport,
}

/// Above this [`rest_distance`] the rest pose is far from every training pose, and the
/// selection report says so ([`rest_distance_sentence`]). The rest prior is scored all the
/// same: measured on the training poses of docs/results and the demo, the rest prior gave the
/// lower test error at 1.2 (built-in character) and 3.3 (RiggedFigure), the higher at 2.9
/// (CesiumMan), 3.9 (the CMU mannequin's T-pose under a walk) and 13.5 (Fox), so no distance
/// separates them; held-out error decides.
pub const FAR_REST_DISTANCE: f64 = 2.0;

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

/// The selection report's sentence on a rest pose `distance` standard deviations from the
/// training poses: beyond [`FAR_REST_DISTANCE`] it says that the rest prior, and the bind
/// transfer with it, are scored on poses far from the one they are anchored at.
pub fn rest_distance_sentence(distance: f64) -> String {
    if distance > FAR_REST_DISTANCE {
        format!(
            "the rest pose is {distance:.2} standard deviations from the training poses, far from \
             every one of them (beyond {FAR_REST_DISTANCE}): the rest prior's candidates must \
             bridge that distance, and only their held-out errors below say whether they do"
        )
    } else {
        format!(
            "the rest pose is {distance:.2} standard deviations from the training poses, among \
             them (within {FAR_REST_DISTANCE})"
        )
    }
}
