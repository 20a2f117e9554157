//! Which candidates the selection tries, each scored by the same held-out error: for every
//! prior, the prior alone (α = ∞: the skinned bind transfer or the mean training transfer,
//! the compact baselines) and the shared map on each k_a of the ladder at its best α; then
//! the local model. The lowest held-out error is the model.

use nalgebra::{DMatrix, DVector};

use super::choose::{Offer, Verdict, choose};
use super::local::{LocalScoring, WeightedClip, fit_local};
use super::local_model::LocalModel;
use super::report::Choice;
use super::ridge::{CvPoint, RidgeProblem, RidgeTarget};
use super::scoring::{PerValue, Projected, Scoring, set_weights};
use super::{Alpha, CoefDims, Dims, FitError, FitInput, FitOptions, Local, Prior, PriorKind};
use aprt_core::MAX_POSE_DIMS;

/// What the selection may try besides what the options say.
pub(super) struct Tried<'a> {
    /// The pose PCA's rank (the longest k_a).
    pub pose_rank: usize,
    /// The training poses.
    pub poses: usize,
    /// Whether the priors alone are scored with this feature set.
    pub priors_alone: bool,
    /// The held-out runs, when no validation clip is given.
    pub runs: &'a [std::ops::Range<usize>],
}

/// Scores every candidate `options` allow, in order: for each prior, the prior alone and the
/// k_a ladder; then the local model. Returns them and the local model's storage.
pub(super) fn score_candidates(
    input: &FitInput<'_>,
    options: &FitOptions,
    shared: &Shared<'_>,
    tried: &Tried<'_>,
) -> Result<(Tally, Option<LocalModel>), FitError> {
    let local_ready = local_readiness(input, options);
    if options.local == Local::Only
        && let Err(why) = local_ready
    {
        return Err(FitError::NoLocalModel(why));
    }
    let mut tally = Tally::default();
    if options.local != Local::Only {
        let ladder = pose_dim_candidates(options.pose_dims, tried.pose_rank);
        for prior in priors_tried(options.prior, shared.projected.anchor.is_some()) {
            if tried.priors_alone && priors_alone_tried(options, tried.poses) {
                shared.prior_alone(prior, &mut tally);
            }
            shared.ladder(prior, &ladder, &mut tally)?;
        }
    }
    let local = match local_ready {
        Ok(k) if options.local != Local::Off => {
            let shape = (k, shared.cosines);
            local_candidate(input, options.alpha, shape, tried.runs, &mut tally)?
        }
        _ => None,
    };
    Ok((tally, local))
}

/// The k_a values tried: the one asked for, or (for [`Dims::Auto`]) a doubling ladder up to
/// the rank, so that the selection can trade pose detail for generalisation.
pub(super) fn pose_dim_candidates(dims: Dims, rank: usize) -> Vec<usize> {
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

/// The priors tried: the mean alone without an anchor.
pub(super) fn priors_tried(prior: Prior, anchored: bool) -> Vec<PriorKind> {
    match (prior, anchored) {
        (_, false) | (Prior::Mean, _) => vec![PriorKind::Mean],
        (Prior::Rest, true) => vec![PriorKind::Rest],
        (Prior::Auto, true) => vec![PriorKind::Rest, PriorKind::Mean],
    }
}

/// Whether the priors alone (α = ∞) are candidates: whenever α is chosen by held-out error
/// and the shared candidates are tried (a fixed α is the caller's; the local model alone is
/// what was asked for), and some pose can be held out of the others. Even when the pose
/// coordinates do not move (the shared maps are then their priors, unscored), the priors
/// alone are scored, so that the local model competes with the bind transfer.
pub(super) fn priors_alone_tried(options: &FitOptions, poses: usize) -> bool {
    !matches!(options.alpha, Alpha::Fixed(_)) && options.local != Local::Only && poses >= 2
}

/// k_v of the local model, or why it cannot be fitted.
pub(super) fn local_readiness(
    input: &FitInput<'_>,
    options: &FitOptions,
) -> Result<usize, &'static str> {
    let n2 = input.order * input.order;
    let k = match (input.locality, input.anchor, options.coef_dims) {
        (None, _, _) => {
            Err("no vertex groups were given (bone-frame models of characters have them)")
        }
        (_, None, _) => Err("it needs the rest pose as anchor"),
        _ if options.prior == Prior::Mean => Err("it is anchored at the rest pose, not the mean"),
        (_, _, CoefDims::Count(k)) if k > n2 => Ok(k),
        _ => Err("it needs --coef-dims above n² (the rest transfer's fields)"),
    }?;
    if input.angles.ncols() > MAX_POSE_DIMS {
        Err("it keeps every pose entry, more than the runtime's 128 pose dimensions")
    } else if input.transfers.len() < 2 {
        Err("it needs at least two poses")
    } else {
        Ok(k)
    }
}

/// Every candidate scored so far, in order, with its α curve and its error on each
/// validation pose (when scored on them).
#[derive(Default)]
pub(super) struct Tally {
    pub choices: Vec<Choice>,
    pub rows: Vec<Option<Vec<f64>>>,
    curves: Vec<Vec<CvPoint>>,
}

impl Tally {
    /// Records a candidate.
    pub fn consider(&mut self, choice: Choice, curve: Vec<CvPoint>, rows: Option<Vec<f64>>) {
        self.choices.push(choice);
        self.curves.push(curve);
        self.rows.push(rows);
    }

    /// The chosen candidate, its curve and how it was chosen ([`choose`]: the lowest
    /// held-out error, or the simplest within its noise, fewer pose dimensions being
    /// simpler); an error when none was scored, or when the chosen one cannot be predicted
    /// on what was held out and α was to be chosen by it.
    pub fn best(&self, alpha: Alpha) -> Result<(Choice, Vec<CvPoint>, Verdict), FitError> {
        let offers: Vec<Offer<'_>> = self
            .choices
            .iter()
            .zip(&self.rows)
            .map(|(c, rows)| Offer {
                error: c.held_out_error,
                rows: rows.as_deref(),
                complexity: c.pose_dims,
            })
            .collect();
        let verdict = choose(&offers).ok_or(FitError::NoFiniteCvError)?;
        let chosen = self.choices[verdict.chosen];
        if !chosen.held_out_error.is_finite() && !matches!(alpha, Alpha::Fixed(_)) {
            return Err(FitError::NoFiniteCvError);
        }
        Ok((chosen, self.curves[verdict.chosen].clone(), verdict))
    }
}

/// What the shared candidates have in common: the pose coordinates, the projected transfer,
/// how they are scored.
pub(super) struct Shared<'a> {
    /// `p × rank` pose coordinates.
    pub z: &'a DMatrix<f64>,
    pub projected: &'a Projected,
    pub scoring: Scoring<'a>,
    pub errors: &'a PerValue,
    pub alpha: Alpha,
    /// Whether the features hold the cosines.
    pub cosines: bool,
}

impl<'a> Shared<'a> {
    /// The outputs relative to the prior.
    pub fn target(&self, prior: PriorKind) -> RidgeTarget<'a> {
        match (prior, &self.projected.anchor) {
            (PriorKind::Rest, Some((_, y0))) => self.projected.outputs.around_anchor(y0),
            _ => self.projected.outputs.around_mean(),
        }
    }

    /// The leading `k` pose coordinates, and the anchor's when the prior is the rest pose.
    pub fn inputs(&self, prior: PriorKind, k: usize) -> (DMatrix<f64>, Option<DVector<f64>>) {
        let z0 = match (prior, &self.projected.anchor) {
            (PriorKind::Rest, Some((z0, _))) => Some(z0.rows(0, k).into_owned()),
            _ => None,
        };
        (self.z.columns(0, k).into_owned(), z0)
    }

    /// The prior alone (α = ∞), scored in closed form: every pose predicted by the anchor's
    /// coordinates, or by the mean of the poses not held out, plus what lies outside the basis.
    pub fn prior_alone(&self, prior: PriorKind, tally: &mut Tally) {
        let target = self.target(prior);
        let point = self.scoring.prior(&target);
        let rows = self.scoring.prior_rows(&target);
        let choice = Choice {
            prior,
            pose_dims: 0,
            local: false,
            cosines: false,
            alpha: f64::INFINITY,
            held_out_error: self.errors.held_out(&point),
            train_error: self.errors.train(&point),
        };
        tally.consider(
            choice,
            Vec::new(),
            rows.map(|r| self.errors.held_out_rows(&r)),
        );
    }

    /// The shared map on each k_a of `ladder`, each at its best α (or the fixed one).
    pub fn ladder(
        &self,
        prior: PriorKind,
        ladder: &[usize],
        tally: &mut Tally,
    ) -> Result<(), FitError> {
        let target = self.target(prior);
        for &k in ladder {
            let (zk, z0) = self.inputs(prior, k);
            let problem = RidgeProblem::new(&zk, z0.as_ref(), &target);
            let (alpha, curve) = match self.alpha {
                Alpha::Fixed(alpha) => (alpha, vec![self.scoring.point(&problem, alpha)]),
                _ => {
                    let selection = self.scoring.select(&problem)?;
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
                None => self.scoring.point(&problem, alpha),
            };
            let choice = Choice {
                prior,
                pose_dims: k,
                local: false,
                cosines: self.cosines,
                alpha,
                held_out_error: self.errors.held_out(&point),
                train_error: self.errors.train(&point),
            };
            let rows = self.scoring.rows(&problem, alpha);
            tally.consider(choice, curve, rows.map(|r| self.errors.held_out_rows(&r)));
        }
        Ok(())
    }
}

/// The local model as a candidate (when wanted and ready, with `kv` basis vectors), scored on
/// the same held-out runs or validation clips as the shared ones; `cosines`: whether the
/// features hold the cosines.
pub(super) fn local_candidate(
    input: &FitInput<'_>,
    alpha: Alpha,
    (kv, cosines): (usize, bool),
    runs: &[std::ops::Range<usize>],
    tally: &mut Tally,
) -> Result<Option<LocalModel>, FitError> {
    let (Some(locality), Some(anchor)) = (input.locality, input.anchor) else {
        return Ok(None);
    };
    let (angles, transfers) = (input.angles, input.transfers);
    let n2 = input.order * input.order;
    let sizes: Vec<usize> = input.validation.iter().map(|v| v.transfers.len()).collect();
    let pairs: Vec<WeightedClip<'_>> = input
        .validation
        .iter()
        .zip(set_weights(&sizes))
        .map(|(v, weight)| (v.angles, v.transfers, weight))
        .collect();
    let scoring = if pairs.is_empty() {
        LocalScoring::Segments(runs)
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
        alpha,
    )?;
    let scored: Vec<(&DMatrix<f64>, f64)> = if pairs.is_empty() {
        vec![(angles, 1.0)]
    } else {
        pairs.iter().map(|(a, _, weight)| (*a, *weight)).collect()
    };
    let model = LocalModel::new(&fitted, anchor, n2, kv, angles, &scored);
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
        cosines,
        alpha: fitted.alpha,
        held_out_error: best_point.cv_error + model.outside_scored,
        train_error: best_point.train_error + model.outside_train,
    };
    // Pose by pose, the same sum: the map's error and what its basis misses.
    let values = (input.transfers[0].len()).max(1) as f64;
    let rows = (!pairs.is_empty()).then(|| {
        fitted
            .held_rows
            .iter()
            .zip(&model.outside_rows)
            .map(|(e, outside)| e / values + outside)
            .collect()
    });
    tally.consider(choice, fitted.curve.clone(), rows);
    Ok(Some(model))
}
