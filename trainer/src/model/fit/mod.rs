//! Fitting stage of the trainer: from poses and baked transfer to a [`LinearModel`].
//!
//! Pipeline (Nowrouzezahrai et al., *Compact and Efficient Generation of Radiance Transfer for
//! Dynamically Articulated Characters*): pose PCA (`z = P (a − μ)`) → shared vertex basis over
//! all `p·n²` coefficient rows (randomized SVD) → basis coordinates of each pose's rows → one
//! ridge regression of all `n²·k_v` outputs on z with a single α chosen by closed-form cross
//! validation → weights packed in the runtime layout.

mod assemble;
mod candidates;
mod choose;
mod dims;
mod error;
mod input;
mod local;
mod local_model;
mod pose_pca;
mod report;
mod ridge;
mod rsvd;
mod scoring;
mod vertex_basis;

#[cfg(test)]
mod tests;

pub use choose::{Offer, RULE, Verdict, choose};
pub use dims::Dims;
pub use error::FitError;
pub use input::{Anchor, FitInput, Validation};
pub use local::{EntryGroup, Locality};
pub use pose_pca::PosePca;
pub use report::{
    Choice, Decision, FAR_REST_DISTANCE, Fit, FitReport, FitSeconds, HeldOutKind, rest_distance,
    rest_distance_sentence,
};
pub use ridge::{
    AlphaSelection, CvPoint, HeldOut, RidgeOutputs, RidgeProblem, RidgeSolution, RidgeTarget,
    segments,
};
pub use rsvd::{RowOperator, SketchOptions, TruncatedSvd, randomized_svd};
pub use vertex_basis::{
    Deflated, PoseRows, VertexBasisFit, field_basis, fit_vertex_basis, project_rows, raw_rows,
};

use std::time::Instant;

use aprt_core::MAX_POSE_LEN;
use nalgebra::DMatrix;

use crate::model::LinearModel;
#[cfg(test)]
use crate::model::PoseBounds;
use crate::model::features::PoseFeatures;
use crate::model::occluders::Occluders;
use assemble::{Assembly, beside};
use candidates::{Shared, Tried, score_candidates};
use input::{Featured, pin_entries, unused_entries, validate, with_poses};
use scoring::{PerValue, Projected, Scoring, held_out_runs, segment_length};

/// Size of the vertex side of the model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CoefDims {
    /// k_v basis vectors (fewer if the rows have lower rank).
    Count(usize),
    /// The fewest basis vectors capturing this fraction of `‖R‖_F²` (uncentred energy).
    Variance(f64),
    /// No vertex reduction: the identity basis, the paper's "full linear model".
    Full,
    /// `n² + extra` basis vectors at SH order n: room for the rest transfer's n² fields
    /// (which an anchored basis spans exactly) and `extra` more for what the pose changes.
    FieldsPlus(usize),
}

impl CoefDims {
    /// The default, `n² + 6`: 22 at order 4 (the paper's k_v), 31 at order 5, 42 at order 6.
    /// The paper's fixed 22 cannot even span the rest transfer's 25 and 36 fields at orders 5
    /// and 6. Measured with `aprt report fixtures/scenes/builtin.toml` (RMS grey levels on the
    /// test clips / relative transfer error / bytes of the f32 model):
    ///
    /// | rule | order 4 | order 5 | order 6 |
    /// |---|---|---|---|
    /// | 22 | 4.19 / 0.232 / 1.21 MB | 5.82 / 0.258 / 1.23 MB | 5.81 / 0.257 / 1.24 MB |
    /// | n² + 6 | 4.19 / 0.232 / 1.21 MB | 4.15 / 0.210 / 1.68 MB | 4.12 / 0.203 / 2.27 MB |
    /// | n² + 16 | 4.14 / 0.231 / 1.73 MB | 4.08 / 0.208 / 2.24 MB | 4.04 / 0.201 / 2.86 MB |
    /// | 2n² | 4.14 / 0.231 / 1.73 MB | 4.04 / 0.207 / 2.72 MB | 3.99 / 0.200 / 3.94 MB |
    ///
    /// n² + 6 makes orders 5 and 6 no worse than order 4 and keeps order 4 (the demo's) as it
    /// was; more vectors buy at most 0.16 grey levels for 40 to 75 % more bytes.
    pub const DEFAULT: CoefDims = CoefDims::FieldsPlus(6);

    /// The size at SH order `order`: [`CoefDims::FieldsPlus`] becomes a count, the others
    /// stay as they are.
    pub fn at_order(self, order: usize) -> CoefDims {
        match self {
            CoefDims::FieldsPlus(extra) => CoefDims::Count(order * order + extra),
            other => other,
        }
    }
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
    /// characters; `pipeline::train::fit_clip` fits with and without them).
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
    /// The prior and k_a chosen by held-out error, [`CoefDims::DEFAULT`] vertex vectors, α by
    /// leave-segment-out with ten segments, bounded poses, the angles as features (the
    /// cosines chosen by held-out segments lost on the real characters' novel clips: see
    /// docs/results).
    fn default() -> Self {
        Self {
            pose_dims: Dims::Auto,
            coef_dims: CoefDims::DEFAULT,
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
/// anchor), then for each candidate feature set, prior and k_a (and the local model, and each
/// prior alone at α = ∞) the ridge, with α and all of these chosen by held-out error
/// (segments of the clips, or the validation clips).
pub fn fit_input(input: &FitInput<'_>, options: &FitOptions) -> Result<Fit, FitError> {
    let clock = Instant::now();
    let vertices = validate(input, options)?;
    let options = &FitOptions {
        coef_dims: options.coef_dims.at_order(input.order),
        ..*options
    };
    // Entries no vertex depends on (a root turn, in bone frames) are held at the anchor's
    // value in every pose the fit sees, so nothing is learnt from them, and the bound does not
    // blend the pose towards the prior when they move: the character turning round is not a
    // pose it was not trained on.
    let unused = unused_entries(input);
    let pinned = pin_entries(input, &unused);
    let pinned_input;
    let input = match &pinned {
        Some(poses) => {
            pinned_input = with_poses(input, poses);
            &pinned_input
        }
        None => input,
    };
    let sets = feature_sets(input, options.features, &unused)?;
    // A rest pose far from every training pose is scored like any other prior; the report
    // says how far it is (`rest_distance_sentence`).
    let rest_distance = input
        .anchor
        .and_then(|a| rest_distance(input.angles, a.angles));
    let mut seconds = FitSeconds {
        validate: clock.elapsed().as_secs_f64(),
        ..Default::default()
    };
    let mut fits = Vec::new();
    for (i, features) in sets.iter().enumerate() {
        // The priors alone do not depend on the features: scored with the first set only.
        let fit = fit_features(input, options, (vertices, &unused), features, i == 0)?;
        seconds.add(&fit.report.seconds);
        fits.push(fit);
    }
    let (choices, choice_rows) = fits
        .iter()
        .flat_map(|f| f.report.choices.iter().zip(&f.report.choice_rows))
        .map(|(c, r)| (*c, r.clone()))
        .unzip();
    // The angles are simpler than the angles with their cosines.
    let offers: Vec<Offer<'_>> = fits
        .iter()
        .map(|f| Offer {
            error: f.report.chosen.held_out_error,
            rows: f.report.chosen_rows(),
            complexity: usize::from(f.report.chosen.cosines),
        })
        .collect();
    let verdict = choose(&offers).expect("every fit has at least one feature set");
    let features = (fits.len() > 1)
        .then(|| Decision::of("features", &verdict, |i| fits[i].report.chosen.label()));
    let mut fit = fits.swap_remove(verdict.chosen);
    fit.report.choices = choices;
    fit.report.choice_rows = choice_rows;
    fit.report.decisions.extend(features);
    fit.report.seconds = seconds;
    fit.report.rest_distance = rest_distance;
    Ok(fit)
}

/// The pose feature sets `features` asks for: the angles, the angles and the cosines of the
/// `used` entries, or both (the cosines only when the runtime holds them).
fn feature_sets(
    input: &FitInput<'_>,
    features: Features,
    unused: &[usize],
) -> Result<Vec<PoseFeatures>, FitError> {
    let a = input.angles.ncols();
    let used: Vec<bool> = (0..a).map(|i| !unused.contains(&i)).collect();
    let (angles_only, cosines) = (PoseFeatures::new(a, &[]), PoseFeatures::new(a, &used));
    let cosines_fit = cosines.count() <= MAX_POSE_LEN && !cosines.is_angles();
    Ok(match features {
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
    })
}

/// The vertex basis (`None`: the identity), the captured energies of its fitted components
/// and the total energy of the rows. An anchored basis spans the anchor's coefficient fields
/// exactly (when k_v leaves room for more), so the rest prior costs no truncation error.
fn model_basis(
    input: &FitInput<'_>,
    options: &FitOptions,
    vertices: usize,
) -> (Option<DMatrix<f64>>, Vec<f64>, f64) {
    let n2 = input.order * input.order;
    let rows = PoseRows::new(input.transfers, n2, vertices);
    let anchor_basis = input.anchor.filter(|_| options.prior != Prior::Mean);
    let prior_fields = match (anchor_basis, options.coef_dims) {
        (Some(anchor), CoefDims::Count(k)) if k > n2 => Some(field_basis(anchor.transfer, n2)),
        (Some(anchor), CoefDims::Variance(_)) => Some(field_basis(anchor.transfer, n2)),
        _ => None,
    };
    let split = |fit: VertexBasisFit| (Some(fit.basis), fit.energies, fit.total_energy);
    match (options.coef_dims, &prior_fields) {
        (CoefDims::Full, _) => (None, Vec::new(), rows.frobenius_sq()),
        (CoefDims::Count(k), None) => split(fit_vertex_basis(&rows, Dims::Count(k))),
        (CoefDims::Variance(f), None) => split(fit_vertex_basis(&rows, Dims::Variance(f))),
        (dims, Some(q)) => {
            let rest = match dims {
                CoefDims::Count(k) => Dims::Count(k - q.ncols()),
                CoefDims::Variance(f) => Dims::Variance(f),
                CoefDims::Full | CoefDims::FieldsPlus(_) => {
                    unreachable!("the full model has no basis, and the size is resolved")
                }
            };
            let residual = fit_vertex_basis(&Deflated::new(&rows, q), rest);
            let both = beside(q, &residual.basis);
            (Some(both), residual.energies, residual.total_energy)
        }
        (CoefDims::FieldsPlus(_), None) => unreachable!("the size is resolved by fit_input"),
    }
}

/// The chosen shared candidate (or prior alone) as a model, and whether its α was chosen by
/// held-out error (false when no pose coordinate moves). Solved again rather than kept from
/// the selection: the full model's solutions are large.
fn shared_model(
    assembly: &Assembly<'_>,
    shared: &Shared<'_>,
    pca: &PosePca,
    chosen: &Choice,
) -> (LinearModel, bool) {
    if chosen.is_prior() {
        let centre = shared.target(chosen.prior).centre().clone();
        return (assembly.prior_alone(&centre, chosen.prior), true);
    }
    let (zk, z0) = shared.inputs(chosen.prior, chosen.pose_dims);
    let target = shared.target(chosen.prior);
    let problem = RidgeProblem::new(&zk, z0.as_ref(), &target);
    let solution = problem.solve(chosen.alpha);
    let (ka, prior) = (chosen.pose_dims, chosen.prior);
    let model = assembly.shared(&solution, pca, ka, chosen.alpha, prior);
    (model, problem.rank() > 0)
}

/// [`fit_input`] for one set of pose features, of training and validation poses that are
/// already pinned (`unused` entries held at the anchor's value); `priors_alone`: whether the
/// priors alone (α = ∞) are scored with this set.
fn fit_features(
    pinned: &FitInput<'_>,
    options: &FitOptions,
    (vertices, unused): (usize, &[usize]),
    features: &PoseFeatures,
    priors_alone: bool,
) -> Result<Fit, FitError> {
    let featured = Featured::of(pinned, features);
    let input = &featured.input(pinned);
    let (angles, p, n2) = (
        input.angles,
        input.transfers.len(),
        input.order * input.order,
    );
    let mut seconds = FitSeconds::default();
    let with_cosines = !features.is_angles();

    let clock = Instant::now();
    let pca = PosePca::fit(angles, options.pose_dims);
    let z = pca.project(angles);
    seconds.pose_pca = clock.elapsed().as_secs_f64();

    let clock = Instant::now();
    let (basis, coef_energy, coef_total_energy) = model_basis(input, options, vertices);
    seconds.vertex_basis = clock.elapsed().as_secs_f64();

    let clock = Instant::now();
    let projected = Projected::new(input, basis.as_ref(), &pca, vertices);
    seconds.projection = clock.elapsed().as_secs_f64();

    let clock = Instant::now();
    let segment = segment_length(options.alpha, p);
    let runs = held_out_runs(input, segment);
    let scoring = if projected.held.is_empty() {
        Scoring::Segments(&runs)
    } else {
        Scoring::Clips(&projected.held)
    };
    let kv = basis.as_ref().map_or(vertices, |b| b.ncols());
    let errors = PerValue::new(&projected, p, n2, kv, vertices);
    let shared = Shared {
        z: &z,
        projected: &projected,
        scoring,
        errors: &errors,
        alpha: options.alpha,
        cosines: with_cosines,
    };
    let tried = Tried {
        pose_rank: pca.dims(),
        poses: p,
        priors_alone,
        runs: &runs,
    };
    let (tally, local) = score_candidates(input, options, &shared, &tried)?;
    let (chosen, cv_curve, verdict) = tally.best(options.alpha)?;
    let decision = Decision::of("candidates", &verdict, |i| tally.choices[i].label());
    seconds.cross_validation = clock.elapsed().as_secs_f64();

    let clock = Instant::now();
    let assembly = Assembly {
        order: input.order,
        vertices,
        raw: pinned.angles,
        raw_anchor: pinned.anchor.map(|a| a.angles),
        falloff: options.bound,
        unused,
        flags: features.flags(),
        basis: basis.as_ref(),
    };
    let (model, cross_validated, coef_energy) = match &local {
        Some(local) if chosen.local => {
            let anchor = input.anchor.expect("the local model needs the anchor");
            let model = assembly.local(local, anchor.angles, chosen.alpha);
            (model, true, local.energies.clone())
        }
        _ => {
            let (model, cross_validated) = shared_model(&assembly, &shared, &pca, &chosen);
            (model, cross_validated, coef_energy)
        }
    };
    seconds.solve = clock.elapsed().as_secs_f64();

    let held_out = if projected.held.is_empty() {
        HeldOutKind::Segments(segment)
    } else {
        HeldOutKind::Clips(projected.held.len())
    };
    let report = FitReport {
        pose_eigenvalues: pca.eigenvalues,
        coef_energy,
        coef_total_energy,
        cv_curve,
        alpha: chosen.alpha,
        cv_segment: (cross_validated && projected.held.is_empty()).then_some(segment),
        prior: chosen.prior,
        held_out,
        choices: tally.choices,
        choice_rows: tally.rows,
        validation_sets: input
            .validation
            .iter()
            .map(|v| (v.name.to_owned(), v.angles.nrows()))
            .collect(),
        decisions: vec![decision],
        chosen,
        rest_distance: None,
        seconds,
        occluders: None,
    };
    Ok(Fit { model, report })
}
