//! Tikhonov ridge regression of many outputs on the pose coordinates, with α chosen by
//! closed-form cross validation or by the error on held-out clips.
//!
//! Minimises `‖Y − 1bᵀ − Z X‖² + α²‖X‖²`. With centred `Z_c = U S Vᵀ` (thin, cut at the
//! numerical rank) and centred `Y_c`: `X = V diag(s / (s² + α²)) Uᵀ Y_c`, `b = ȳ − Xᵀ z̄`.
//! The SVD form is the minimum-norm solution when Z is rank-deficient, and the intercept being
//! unpenalised means a huge α tends to the mean output (the mean transfer), not to zero.
//!
//! An *anchored* problem fits through a given point `(z₀, y₀)` instead: no intercept, `Z` and
//! `Y` taken relative to the anchor (`ŷ(z) = y₀ + Xᵀ (z − z₀)`), so a huge α tends to `y₀`
//! exactly (a prior such as the rest pose's transfer) and the regression only adds what the
//! data supports.
//!
//! The fit is a linear smoother `Ŷ = H Y` with `H = 11ᵀ/p + U F Uᵀ` (`H = U F Uᵀ` when
//! anchored), `F = diag(s²/(s²+α²))`, so held-out residuals follow from the in-sample ones
//! without refits: for a held-out set S, `e_S = (I − H_SS)⁻¹ r_S` (leave-one-out is the case
//! |S| = 1). All that is needed of Y is its Gram `K = Y_c Y_cᵀ`, through products with a few
//! columns: the residual Gram is `(I − H) K (I − H)`, and `H_SS = Q D Qᵀ` has rank r + 1
//! (`Q = [U_S, 1/√p]`), so by Woodbury each held-out run reduces to `(r+1) × (r+1)` matrices
//! formed once ([`RunProducts`]) and each α costs `O(runs·r³)`, whatever the output width
//! (the full model has ~400k outputs per pose) and the run length (a tenth of the poses: a
//! solve of the run's own `L × L` system made the search cubic in the pose count). The Gram
//! is stored when it is no larger than the outputs (`p ≤ q`) and otherwise applied through
//! `Y_c`, so that time and memory stay linear in the pose count of a long sequence.
//! The price of the Gram form is resolution: residuals below about `√ε · ‖Y_c‖` cancel in
//! `K` and read as zero, which only matters once the fit is already exact to ~1e-8.

use std::ops::Range;

use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;

use super::FitError;
use super::dims;

/// Grid points of the α search, log-spaced between [`GRID_LOW`] and [`GRID_HIGH`] times the
/// largest singular value of `Z_c`.
const GRID_POINTS: usize = 60;
/// Below this α every direction is fitted as in least squares (filter factors ≥ 1 − 1e-12 for
/// the leading directions).
const GRID_LOW: f64 = 1e-6;
/// Above this α every filter factor is below 1e-6: the model is the mean (or the anchor).
const GRID_HIGH: f64 = 1e3;
/// Golden-section refinement stops when the log-α bracket is this narrow (0.01 % in α).
const REFINE_LOG_WIDTH: f64 = 1e-4;
/// Output columns per block of the Gram product, summed in a fixed order for determinism.
const GRAM_COLUMNS_PER_BLOCK: usize = 4096;

/// The outputs of a ridge problem, centred on their column means, and their Gram when it is
/// the smaller of the two.
#[derive(Clone, Debug)]
pub struct RidgeOutputs {
    /// The mean output.
    mean: DVector<f64>,
    /// `p × q` outputs minus their mean.
    y_centred: DMatrix<f64>,
    /// `K = Y_c Y_cᵀ`, `p × p`, when `p ≤ q`; else `None` and `K` is applied through `Y_c`.
    gram: Option<DMatrix<f64>>,
}

impl RidgeOutputs {
    /// `y` (`p × q`, taken by value and centred in place: for the full model it is the largest
    /// array of the fit).
    pub fn new(y: DMatrix<f64>) -> Self {
        let stored = y.nrows() <= y.ncols();
        Self::with_gram(y, stored)
    }

    /// [`Self::new`], with the Gram stored or not as asked (the tests try both forms).
    fn with_gram(mut y: DMatrix<f64>, stored: bool) -> Self {
        let mean = DVector::from_fn(y.ncols(), |j, _| y.column(j).mean());
        for (mut col, m) in y.column_iter_mut().zip(mean.iter()) {
            col.add_scalar_mut(-m);
        }
        let gram = stored.then(|| {
            let (p, q) = y.shape();
            let starts: Vec<usize> = (0..q).step_by(GRAM_COLUMNS_PER_BLOCK).collect();
            let parts: Vec<DMatrix<f64>> = starts
                .par_iter()
                .map(|&c| {
                    let block = y.columns(c, GRAM_COLUMNS_PER_BLOCK.min(q - c));
                    block * block.transpose()
                })
                .collect();
            parts
                .into_iter()
                .fold(DMatrix::zeros(p, p), |acc, part| acc + part)
        });
        Self {
            mean,
            y_centred: y,
            gram,
        }
    }

    /// The fit with an unpenalised intercept: a huge α tends to the mean output.
    pub fn around_mean(&self) -> RidgeTarget<'_> {
        self.around(self.mean.clone(), false)
    }

    /// The fit through an anchor whose output is `y0`: a huge α tends to `y0`. The outputs
    /// relative to it are `Y_c + 1 dᵀ` with `d = ȳ − y0`, so their Gram follows from the
    /// centred one without another copy of the outputs.
    pub fn around_anchor(&self, y0: &DVector<f64>) -> RidgeTarget<'_> {
        assert_eq!(y0.len(), self.mean.len(), "ridge: anchor output shape");
        self.around(y0.clone(), true)
    }

    fn around(&self, centre: DVector<f64>, anchored: bool) -> RidgeTarget<'_> {
        let shift = &self.mean - &centre;
        let y_shift = &self.y_centred * &shift;
        let norm = shift.norm_squared();
        // `‖y_i + d‖² = ‖y_i‖² + 2 y_i·d + ‖d‖²`: the diagonal of the Gram relative to the centre.
        let row_norms = DVector::from_fn(self.y_centred.nrows(), |i, _| {
            self.y_centred.row(i).norm_squared() + 2.0 * y_shift[i] + norm
        });
        RidgeTarget {
            outputs: self,
            centre,
            shift,
            y_shift,
            row_norms,
            anchored,
        }
    }
}

/// Outputs relative to the point the fit is centred on: their mean, or an anchor.
#[derive(Clone, Debug)]
pub struct RidgeTarget<'a> {
    outputs: &'a RidgeOutputs,
    /// The mean output, or the anchor's.
    centre: DVector<f64>,
    /// `ȳ − centre`: the outputs relative to the centre are `Y_c + 1 shiftᵀ`.
    shift: DVector<f64>,
    /// `Y_c shift`, `p`.
    y_shift: DVector<f64>,
    /// Each pose's squared norm relative to the centre: the diagonal of their Gram.
    row_norms: DVector<f64>,
    /// Whether the intercept is given (the anchor) rather than fitted.
    anchored: bool,
}

impl RidgeTarget<'_> {
    /// `K_SS X` for the poses `rows` (S) and `x` with one row per pose of S, `K` the Gram of
    /// the outputs relative to the centre, `(Y_c + 1 dᵀ)(Y_c + 1 dᵀ)ᵀ`: from the stored Gram
    /// (`O(|S|²)` a column of `x`), or through `Y_c` (`O(|S|·q)`).
    fn gram_times(&self, rows: Range<usize>, x: &DMatrix<f64>) -> DMatrix<f64> {
        let (start, len) = (rows.start, rows.len());
        let ones = DVector::from_element(len, 1.0);
        let sums = x.row_sum();
        match &self.outputs.gram {
            Some(k) => {
                let yd = self.y_shift.rows(start, len);
                k.view((start, start), (len, len)) * x
                    + yd * &sums
                    + &ones * (yd.transpose() * x + &sums * self.shift.norm_squared())
            }
            None => {
                let y = self.outputs.y_centred.rows(start, len);
                let w = y.tr_mul(x) + &self.shift * &sums;
                y * &w + ones * self.shift.tr_mul(&w)
            }
        }
    }

    /// `Uᵀ (Y − 1 centreᵀ)` for `u` with one row per pose.
    fn project(&self, u: &DMatrix<f64>) -> DMatrix<f64> {
        let ones = DVector::from_element(u.nrows(), 1.0);
        u.tr_mul(&self.outputs.y_centred) + u.tr_mul(&ones) * self.shift.transpose()
    }

    fn shape(&self) -> (usize, usize) {
        self.outputs.y_centred.shape()
    }

    /// The prior's prediction: the anchor's output, or the mean output (the limit α → ∞).
    pub fn centre(&self) -> &DVector<f64> {
        &self.centre
    }

    /// The limit α → ∞ scored over the held-out `runs`, in closed form: anchored, every pose
    /// is predicted by the anchor's output whatever is held out; around the mean, a held-out
    /// run S of L poses by the mean of the other `p − L` (infinite when there are none).
    /// Errors per output entry, as [`CvPoint`]'s, at α = ∞.
    pub fn prior_point(&self, runs: &[Range<usize>]) -> CvPoint {
        let (p, q) = self.shape();
        let y = &self.outputs.y_centred;
        // Outputs relative to the centre: `Y_c + 1 shiftᵀ`.
        let relative = |i: usize| y.row(i).transpose() + &self.shift;
        let train: f64 = (0..p).map(|i| relative(i).norm_squared()).sum();
        let cv = if self.anchored {
            train
        } else {
            runs.iter()
                .map(|run| {
                    let rest = p - run.len();
                    if rest == 0 {
                        return f64::INFINITY;
                    }
                    // The other poses' mean, relative to the mean of all: −Σ_S c_i / (p − L).
                    let sum = run
                        .clone()
                        .fold(DVector::zeros(q), |acc, i| acc + relative(i));
                    let others = sum / -(rest as f64);
                    run.clone()
                        .map(|i| (relative(i) - &others).norm_squared())
                        .sum::<f64>()
                })
                .sum()
        };
        let entries = (p * q.max(1)).max(1) as f64;
        CvPoint {
            alpha: f64::INFINITY,
            cv_error: cv / entries,
            train_error: train / entries,
        }
    }

    /// Each held-out pose's squared error (summed over the outputs) at α = ∞: its distance
    /// from the centre. In the order of `held`, pose by pose.
    pub fn prior_held_out_rows(&self, held: &[HeldOut]) -> Vec<f64> {
        held.iter()
            .flat_map(|h| h.y.row_iter().map(|row| (h.weight, row)))
            .map(|(w, row)| w * (row.transpose() - &self.centre).norm_squared())
            .collect()
    }

    /// The limit α → ∞ scored on poses held out whole: each predicted by the centre.
    pub fn prior_held_out(&self, held: &[HeldOut]) -> CvPoint {
        let (p, q) = self.shape();
        let err: f64 = self.prior_held_out_rows(held).iter().sum();
        let rows: f64 = held.iter().map(|h| h.weight * h.y.nrows() as f64).sum();
        let y = &self.outputs.y_centred;
        let train: f64 = (0..p)
            .map(|i| (y.row(i).transpose() + &self.shift).norm_squared())
            .sum();
        CvPoint {
            alpha: f64::INFINITY,
            cv_error: err / (rows * q.max(1) as f64).max(1.0),
            train_error: train / (p * q.max(1)).max(1) as f64,
        }
    }
}

/// A ridge problem: the factored inputs and the outputs they predict.
#[derive(Clone, Debug)]
pub struct RidgeProblem<'a> {
    /// The point the inputs are centred on: their mean, or the anchor's.
    z_centre: DVector<f64>,
    /// `p × r` left singular vectors of `Z_c`.
    u: DMatrix<f64>,
    /// r singular values, descending, all above the rank tolerance.
    s: DVector<f64>,
    /// `k × r` right singular vectors.
    v: DMatrix<f64>,
    target: &'a RidgeTarget<'a>,
}

/// A solved ridge: `ŷ(z) = intercept + coefficientsᵀ z`.
#[derive(Clone, Debug, PartialEq)]
pub struct RidgeSolution {
    /// q values (the unpenalised intercept).
    pub intercept: DVector<f64>,
    /// `k × q`.
    pub coefficients: DMatrix<f64>,
}

/// One α of the cross-validation curve. Errors are mean squared errors per output entry
/// (sum over poses and outputs divided by `p·q`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CvPoint {
    /// The Tikhonov parameter.
    pub alpha: f64,
    /// Held-out error (infinite where a held-out set cannot be predicted at all).
    pub cv_error: f64,
    /// In-sample error.
    pub train_error: f64,
}

/// The α chosen by cross validation and every α evaluated on the way, sorted by α.
#[derive(Clone, Debug, PartialEq)]
pub struct AlphaSelection {
    /// The minimiser of the held-out error.
    pub alpha: f64,
    /// Grid and refinement points, ascending in α.
    pub curve: Vec<CvPoint>,
}

/// Poses held out whole: their pose coordinates and outputs, to score a fit on.
#[derive(Clone, Debug)]
pub struct HeldOut {
    /// `p_h × k'` pose coordinates, `k' ≥ k`: a problem on the leading k coordinates reads
    /// only those.
    pub z: DMatrix<f64>,
    /// `p_h × q` outputs.
    pub y: DMatrix<f64>,
    /// What each of its poses weighs in the error (see `scoring::set_weights`): 1 when every
    /// held-out pose counts alike.
    pub weight: f64,
}

/// Contiguous runs of at most `segment` poses inside each of the consecutive clips of
/// `clip_lengths` poses, so that no held-out run straddles two clips.
pub fn segments(clip_lengths: &[usize], segment: usize) -> Vec<Range<usize>> {
    let segment = segment.max(1);
    let mut start = 0;
    let mut runs = Vec::new();
    for &len in clip_lengths {
        let end = start + len;
        runs.extend(
            (start..end)
                .step_by(segment)
                .map(|s| s..(s + segment).min(end)),
        );
        start = end;
    }
    runs
}

impl<'a> RidgeProblem<'a> {
    /// Factors the inputs `z` (`p × k`) for `outputs`: centred on their means, or on `z0` when
    /// the outputs are anchored (then `z0` must be given, and only then).
    pub fn new(z: &DMatrix<f64>, z0: Option<&DVector<f64>>, target: &'a RidgeTarget<'a>) -> Self {
        let (p, k) = z.shape();
        assert_eq!(
            target.shape().0,
            p,
            "ridge: Z and Y must have one row per pose"
        );
        assert_eq!(
            z0.is_some(),
            target.anchored,
            "ridge: an anchored fit needs the anchor's inputs, and only it"
        );
        let z_centre = match z0 {
            Some(z0) => {
                assert_eq!(z0.len(), k, "ridge: anchor input shape");
                z0.clone()
            }
            None => DVector::from_fn(k, |j, _| z.column(j).mean()),
        };
        let mut zc = z.clone();
        for (mut col, m) in zc.column_iter_mut().zip(z_centre.iter()) {
            col.add_scalar_mut(-m);
        }
        if p == 0 || k == 0 {
            // No pose coordinates (e.g. a single pose): nothing to factor, the fit is the centre.
            return Self {
                z_centre,
                u: DMatrix::zeros(p, 0),
                s: DVector::zeros(0),
                v: DMatrix::zeros(k, 0),
                target,
            };
        }
        let svd = zc.svd(true, true);
        let rank = dims::numerical_rank(svd.singular_values.as_slice(), p, k, f64::EPSILON);
        let u = svd
            .u
            .expect("SVD computed with U")
            .columns(0, rank)
            .into_owned();
        let v = svd
            .v_t
            .expect("SVD computed with V")
            .rows(0, rank)
            .transpose();
        let s = svd.singular_values.rows(0, rank).into_owned();
        Self {
            z_centre,
            u,
            s,
            v,
            target,
        }
    }

    /// The outputs the problem predicts.
    pub fn target(&self) -> &RidgeTarget<'a> {
        self.target
    }

    /// Numerical rank r of the centred inputs: 0 means the outputs cannot depend on the pose.
    pub fn rank(&self) -> usize {
        self.s.len()
    }

    /// Ridge solution at `alpha` (α = 0 is the minimum-norm least-squares solution).
    pub fn solve(&self, alpha: f64) -> RidgeSolution {
        let filter = self.s.map(|s| s / (s * s + alpha * alpha));
        let mut uty = self.target.project(&self.u);
        for (mut row, f) in uty.row_iter_mut().zip(filter.iter()) {
            row *= *f;
        }
        let coefficients = &self.v * uty;
        let intercept = &self.target.centre - coefficients.tr_mul(&self.z_centre);
        RidgeSolution {
            intercept,
            coefficients,
        }
    }

    /// Chooses α minimising the leave-segment-out error over the held-out `runs` (disjoint,
    /// covering every pose; runs of one pose are leave-one-out), on a log grid of α refined by
    /// golden-section search.
    pub fn select_alpha(&self, runs: &[Range<usize>]) -> Result<AlphaSelection, FitError> {
        let p = self.u.nrows();
        if self.rank() == 0 {
            // No pose dependence: nothing to choose, whatever the runs.
            return self.select_by(|_| unreachable!("rank 0 evaluates nothing"));
        }
        // Holding out every pose leaves nothing to fit on.
        if let Some(run) = runs.iter().find(|r| r.len() >= p) {
            return Err(FitError::SegmentTooLong {
                segment: run.len(),
                poses: p,
            });
        }
        let cv = GramCv::new(self, runs);
        self.select_by(|alpha| cv.evaluate(alpha))
    }

    /// Chooses α minimising the error on poses held out whole (`held`, not among the fitted
    /// poses), on the same grid and search.
    pub fn select_on(&self, held: &[HeldOut]) -> Result<AlphaSelection, FitError> {
        let score = HeldOutScore::new(self, held);
        self.select_by(|alpha| score.evaluate(alpha))
    }

    /// A 60-point log grid of α relative to `s_max`, then golden-section search on log α
    /// around the best grid point.
    fn select_by(&self, evaluate: impl Fn(f64) -> CvPoint) -> Result<AlphaSelection, FitError> {
        // Rank 0: no pose dependence to regularise; the fit is the centre whatever α.
        let Some(&s_max) = self.s.as_slice().first() else {
            return Ok(AlphaSelection {
                alpha: 0.0,
                curve: Vec::new(),
            });
        };
        let log_lo = (GRID_LOW * s_max).ln();
        let step = ((GRID_HIGH * s_max).ln() - log_lo) / (GRID_POINTS - 1) as f64;
        let mut curve: Vec<CvPoint> = Self::alpha_grid(s_max).into_iter().map(&evaluate).collect();
        let best = argmin(&curve).ok_or(FitError::NoFiniteCvError)?;
        // Golden-section search on log α inside the neighbouring grid points.
        let inv_phi = (5f64.sqrt() - 1.0) / 2.0;
        let (mut a, mut b) = (
            log_lo + step * best.saturating_sub(1) as f64,
            log_lo + step * (best + 1).min(GRID_POINTS - 1) as f64,
        );
        let mut x1 = b - inv_phi * (b - a);
        let mut x2 = a + inv_phi * (b - a);
        let (mut f1, mut f2) = (evaluate(x1.exp()), evaluate(x2.exp()));
        curve.extend([f1, f2]);
        while b - a > REFINE_LOG_WIDTH {
            if f1.cv_error <= f2.cv_error {
                (b, x2, f2) = (x2, x1, f1);
                x1 = b - inv_phi * (b - a);
                f1 = evaluate(x1.exp());
                curve.push(f1);
            } else {
                (a, x1, f1) = (x1, x2, f2);
                x2 = a + inv_phi * (b - a);
                f2 = evaluate(x2.exp());
                curve.push(f2);
            }
        }
        curve.sort_by(|l, r| l.alpha.total_cmp(&r.alpha));
        let alpha = curve[argmin(&curve).expect("the grid had a finite point")].alpha;
        Ok(AlphaSelection { alpha, curve })
    }

    /// Each pose held out whole's squared error (summed over the outputs) at `alpha`, in the
    /// order of `held`, pose by pose: the solution's prediction compared directly, for the
    /// spread that the closed-form held-out sums do not keep.
    pub fn held_out_rows(&self, alpha: f64, held: &[HeldOut]) -> Vec<f64> {
        let solution = self.solve(alpha);
        let intercept = solution.intercept.transpose();
        let k = self.v.nrows();
        let mut rows = Vec::new();
        for h in held {
            let predicted = h.z.columns(0, k) * &solution.coefficients;
            rows.extend(
                (0..h.y.nrows()).map(|i| {
                    h.weight * (h.y.row(i) - predicted.row(i) - &intercept).norm_squared()
                }),
            );
        }
        rows
    }

    /// Held-out and in-sample error at one α (see [`CvPoint`]) over the held-out `runs`.
    pub fn cv_point(&self, alpha: f64, runs: &[Range<usize>]) -> CvPoint {
        GramCv::new(self, runs).evaluate(alpha)
    }

    /// Error on poses held out whole, and in-sample error, at one α.
    pub fn held_out_point(&self, alpha: f64, held: &[HeldOut]) -> CvPoint {
        HeldOutScore::new(self, held).evaluate(alpha)
    }

    /// [`Self::cv_point`] at each of `alphas`, the α-independent products formed once.
    pub fn cv_points(&self, alphas: &[f64], runs: &[Range<usize>]) -> Vec<CvPoint> {
        let cv = GramCv::new(self, runs);
        alphas.iter().map(|&alpha| cv.evaluate(alpha)).collect()
    }

    /// [`Self::held_out_point`] at each of `alphas`, the α-independent products formed once.
    pub fn held_out_points(&self, alphas: &[f64], held: &[HeldOut]) -> Vec<CvPoint> {
        let score = HeldOutScore::new(self, held);
        alphas.iter().map(|&alpha| score.evaluate(alpha)).collect()
    }

    /// The α grid the selection searches: log-spaced from `1e-6` to `1e3` times `s_max`.
    pub fn alpha_grid(s_max: f64) -> Vec<f64> {
        let log_lo = (GRID_LOW * s_max).ln();
        let step = ((GRID_HIGH * s_max).ln() - log_lo) / (GRID_POINTS - 1) as f64;
        (0..GRID_POINTS)
            .map(|i| (log_lo + step * i as f64).exp())
            .collect()
    }
}

/// Index of the smallest finite CV error (the first one on ties: the least regularised).
fn argmin(curve: &[CvPoint]) -> Option<usize> {
    curve
        .iter()
        .enumerate()
        .filter(|(_, c)| c.cv_error.is_finite())
        .min_by(|(_, l), (_, r)| l.cv_error.total_cmp(&r.cv_error))
        .map(|(i, _)| i)
}

/// Filter factors `s² / (s² + α²)`.
fn filter(s: &DVector<f64>, alpha: f64) -> DVector<f64> {
    s.map(|s| s * s / (s * s + alpha * alpha))
}

/// In-sample squared error at α from the Gram: `tr((I − H) K (I − H))` with the `11ᵀ/p` part
/// vanishing against the centred K, i.e. `tr K − 2 tr(F M) + tr(F M F)` (`UᵀU = I`).
fn train_sum(m: &DMatrix<f64>, k_trace: f64, f: &DVector<f64>) -> f64 {
    k_trace
        + f.iter()
            .enumerate()
            .map(|(i, fi)| (fi * fi - 2.0 * fi) * m[(i, i)])
            .sum::<f64>()
}

/// Everything cross validation needs, independent of α: the output Gram's projections.
struct GramCv<'a, 'b> {
    problem: &'b RidgeProblem<'a>,
    /// One per held-out run.
    runs: Vec<RunProducts>,
    /// `M = Uᵀ K U`, `r × r`.
    m: DMatrix<f64>,
    /// `tr K`.
    k_trace: f64,
    /// `p·q`, the error normalisation.
    entries: f64,
}

/// One held-out run S's products, independent of α, with `Q = [U_S, 1/√p]` (`U_S` alone when
/// the fit is anchored: no mean to hold out): `H_SS = Q D Qᵀ`, `D = diag(F, 1)`.
struct RunProducts {
    /// `QᵀQ`; its first r columns are `Qᵀ U_S`.
    qq: DMatrix<f64>,
    /// `Qᵀ K_SS Q`.
    qkq: DMatrix<f64>,
    /// `Qᵀ (K U)_S`.
    qku: DMatrix<f64>,
    /// `tr K_SS`.
    trace: f64,
}

impl RunProducts {
    fn new(
        target: &RidgeTarget<'_>,
        run: Range<usize>,
        (u, ku): (&DMatrix<f64>, &DMatrix<f64>),
        mean: Option<f64>,
    ) -> Self {
        let (start, len, r) = (run.start, run.len(), u.ncols());
        let mut q =
            DMatrix::from_element(len, r + usize::from(mean.is_some()), mean.unwrap_or(0.0));
        q.columns_mut(0, r).copy_from(&u.rows(start, len));
        Self {
            qq: q.tr_mul(&q),
            qkq: q.tr_mul(&target.gram_times(run.clone(), &q)),
            qku: q.tr_mul(&ku.rows(start, len)),
            trace: target.row_norms.rows(start, len).sum(),
        }
    }

    /// `Σ‖e_S‖²` at filter factors `f`, `e_S = (I − H_SS)⁻¹ r_S` with `r_S = R_S`, the run's
    /// in-sample residuals `Y_S − U_S F B` (`B = Uᵀ Y`). With `W = Q D^½`, `H_SS = W Wᵀ` and
    /// `(I − WWᵀ)⁻¹ = I + W C Wᵀ`, `C = (I − WᵀW)⁻¹`, so `Σ‖e_S‖² = ‖R_S‖² + tr((C + C²) T Tᵀ)`
    /// with `T = Wᵀ R_S`; `Qᵀ R_S = A − G F B` (`A = Qᵀ Y_S`, `G = Qᵀ U_S`) makes `T Tᵀ` and
    /// `‖R_S‖²` sums of the products. Infinite when `I − H_SS` is singular: a run the others
    /// cannot predict.
    fn held_out_sum(&self, f: &DVector<f64>, m: &DMatrix<f64>) -> f64 {
        let r = f.len();
        let g = self.qq.columns(0, r);
        let gf = DMatrix::from_fn(g.nrows(), r, |i, j| g[(i, j)] * f[j]);
        let zfg = &self.qku * gf.transpose();
        let aa = &self.qkq - &zfg - zfg.transpose() + &gf * m * gf.transpose();
        // ‖R_S‖² = tr K_SS − 2 tr(F (K U)_Sᵀ U_S) + tr(F U_SᵀU_S F M).
        let gfu = gf.rows(0, r);
        let residual = self.trace - 2.0 * (0..r).map(|i| f[i] * self.qku[(i, i)]).sum::<f64>()
            + (0..r)
                .map(|i| f[i] * gfu.row(i).dot(&m.column(i).transpose()))
                .sum::<f64>();
        let half = DVector::from_fn(self.qq.nrows(), |i, _| f.get(i).map_or(1.0, |x| x.sqrt()));
        let scale = |x: &DMatrix<f64>| {
            DMatrix::from_fn(x.nrows(), x.ncols(), |i, j| half[i] * x[(i, j)] * half[j])
        };
        let tt = scale(&aa);
        let i_minus_n = DMatrix::identity(half.len(), half.len()) - scale(&self.qq);
        match i_minus_n.cholesky() {
            Some(chol) => {
                let c_tt = chol.solve(&tt);
                residual + c_tt.trace() + chol.solve(&c_tt).trace()
            }
            None => f64::INFINITY,
        }
    }
}

impl<'a, 'b> GramCv<'a, 'b> {
    fn new(problem: &'b RidgeProblem<'a>, runs: &[Range<usize>]) -> Self {
        let (p, q) = problem.target.shape();
        let u = &problem.u;
        let ku = problem.target.gram_times(0..p, u);
        let m = u.tr_mul(&ku);
        // The mean's column `1/√p` of Q, unless the fit has no intercept.
        let mean = (!problem.target.anchored).then(|| (p as f64).sqrt().recip());
        let runs = runs
            .iter()
            .map(|run| RunProducts::new(problem.target, run.clone(), (u, &ku), mean))
            .collect();
        Self {
            problem,
            runs,
            m,
            k_trace: problem.target.row_norms.sum(),
            entries: (p * q.max(1)) as f64,
        }
    }

    fn evaluate(&self, alpha: f64) -> CvPoint {
        let f = filter(&self.problem.s, alpha);
        let cv: f64 = self
            .runs
            .iter()
            .map(|run| run.held_out_sum(&f, &self.m))
            .sum();
        let train = train_sum(&self.m, self.k_trace, &f);
        // Cancellation in the Gram expansion can leave tiny negative values.
        CvPoint {
            alpha,
            cv_error: cv.max(0.0) / self.entries,
            train_error: train.max(0.0) / self.entries,
        }
    }
}

/// The error on whole held-out clips as a function of α, from α-independent products: with
/// `A = (Z_h − 1z_cᵀ) V` and `B = Uᵀ Y_c`, the prediction error is
/// `‖E‖² − 2 tr(F Aᵀ E Bᵀ) + tr(F AᵀA F B Bᵀ)`, `E = Y_h − 1y_cᵀ`; each α costs `O(r²)`.
struct HeldOutScore {
    s: DVector<f64>,
    /// `tr EᵀE` over the held-out poses.
    e_sq: f64,
    /// `Aᵀ E Bᵀ`, `r × r`.
    aeb: DMatrix<f64>,
    /// `AᵀA`, `r × r`.
    ata: DMatrix<f64>,
    /// `B Bᵀ = Uᵀ K U`, `r × r`, which with `tr K` gives the in-sample error.
    bbt: DMatrix<f64>,
    k_trace: f64,
    entries: f64,
    train_entries: f64,
}

impl HeldOutScore {
    fn new(problem: &RidgeProblem<'_>, held: &[HeldOut]) -> Self {
        let r = problem.rank();
        let target = problem.target;
        let b = target.project(&problem.u);
        let bbt = &b * b.transpose();
        let (mut e_sq, mut aeb, mut ata, mut rows) =
            (0.0, DMatrix::zeros(r, r), DMatrix::zeros(r, r), 0.0);
        for h in held {
            let mut zc = h.z.columns(0, problem.v.nrows()).into_owned();
            for (mut col, m) in zc.column_iter_mut().zip(problem.z_centre.iter()) {
                col.add_scalar_mut(-m);
            }
            let mut e = h.y.clone();
            for (mut col, m) in e.column_iter_mut().zip(target.centre.iter()) {
                col.add_scalar_mut(-m);
            }
            let a = zc * &problem.v;
            let w = h.weight;
            e_sq += w * e.norm_squared();
            aeb += a.tr_mul(&(e * b.transpose())) * w;
            ata += a.tr_mul(&a) * w;
            rows += w * h.y.nrows() as f64;
        }
        let (p, q) = target.shape();
        Self {
            s: problem.s.clone(),
            e_sq,
            aeb,
            ata,
            bbt,
            k_trace: target.row_norms.sum(),
            entries: (rows * q.max(1) as f64).max(1.0),
            train_entries: (p * q.max(1)).max(1) as f64,
        }
    }

    fn evaluate(&self, alpha: f64) -> CvPoint {
        // The prediction of a held-out pose is A diag(s/(s²+α²)) B.
        let g = self.s.map(|s| s / (s * s + alpha * alpha));
        let mut err = self.e_sq;
        for i in 0..g.len() {
            err -= 2.0 * g[i] * self.aeb[(i, i)];
            for j in 0..g.len() {
                err += g[i] * self.ata[(i, j)] * g[j] * self.bbt[(j, i)];
            }
        }
        let train = train_sum(&self.bbt, self.k_trace, &filter(&self.s, alpha));
        CvPoint {
            alpha,
            cv_error: err.max(0.0) / self.entries,
            train_error: train.max(0.0) / self.train_entries,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::model::fit::tests::uniform;

    /// Independent reference: normal equations of `[1 Z] β ≈ y` with penalty `diag(0, α² I)`,
    /// solved by LU. Returns (intercept, coefficients).
    fn normal_equations(
        z: &DMatrix<f64>,
        y: &DMatrix<f64>,
        alpha: f64,
    ) -> (DVector<f64>, DMatrix<f64>) {
        let (p, k) = z.shape();
        let x = DMatrix::from_fn(p, k + 1, |i, j| if j == 0 { 1.0 } else { z[(i, j - 1)] });
        let mut lhs = x.transpose() * &x;
        for j in 1..=k {
            lhs[(j, j)] += alpha * alpha;
        }
        let beta = lhs
            .lu()
            .solve(&(x.transpose() * y))
            .expect("regular system");
        (beta.row(0).transpose(), beta.rows(1, k).into_owned())
    }

    /// Sum of squared held-out residuals by refitting without each contiguous segment.
    fn brute_force_cv(z: &DMatrix<f64>, y: &DMatrix<f64>, alpha: f64, segment: usize) -> f64 {
        let p = z.nrows();
        let mut total = 0.0;
        for start in (0..p).step_by(segment) {
            let held: Vec<usize> = (start..(start + segment).min(p)).collect();
            let kept: Vec<usize> = (0..p).filter(|i| !held.contains(i)).collect();
            let (b, x) = normal_equations(&z.select_rows(&kept), &y.select_rows(&kept), alpha);
            for &i in &held {
                let prediction = b.transpose() + z.row(i) * &x;
                total += (y.row(i) - prediction).norm_squared();
            }
        }
        total
    }

    fn problem(p: usize, k: usize, q: usize, seed: u64) -> (DMatrix<f64>, DMatrix<f64>) {
        let z = uniform(p, k, seed);
        let x = uniform(k, q, seed + 1);
        let y = &z * x + uniform(p, q, seed + 2) * 0.3 + DMatrix::from_element(p, q, 2.0);
        (z, y)
    }

    #[test]
    fn closed_form_loo_equals_refits() {
        let (z, y) = problem(17, 4, 6, 1);
        for stored in [false, true] {
            let outputs = RidgeOutputs::with_gram(y.clone(), stored);
            let target = outputs.around_mean();
            let ridge = RidgeProblem::new(&z, None, &target);
            for alpha in [1e-3, 0.05, 0.4, 3.0] {
                let closed =
                    ridge.cv_point(alpha, &segments(&[z.nrows()], 1)).cv_error * (17 * 6) as f64;
                let brute = brute_force_cv(&z, &y, alpha, 1);
                assert!(
                    (closed - brute).abs() <= 1e-9 * brute,
                    "Gram stored {stored}, α = {alpha}: {closed} vs {brute}"
                );
            }
        }
    }

    #[test]
    fn closed_form_loso_equals_refits() {
        let (z, y) = problem(23, 5, 4, 7);
        for stored in [false, true] {
            let outputs = RidgeOutputs::with_gram(y.clone(), stored);
            let target = outputs.around_mean();
            let ridge = RidgeProblem::new(&z, None, &target);
            for segment in [2, 5, 7] {
                for alpha in [1e-2, 0.3, 2.0] {
                    let closed = ridge
                        .cv_point(alpha, &segments(&[z.nrows()], segment))
                        .cv_error
                        * (23 * 4) as f64;
                    let brute = brute_force_cv(&z, &y, alpha, segment);
                    assert!(
                        (closed - brute).abs() <= 1e-9 * brute,
                        "Gram stored {stored}, L = {segment}, α = {alpha}: {closed} vs {brute}"
                    );
                }
            }
        }
    }

    #[test]
    fn train_error_is_the_in_sample_residual() {
        let (z, y) = problem(12, 3, 5, 3);
        let outputs = RidgeOutputs::new(y.clone());
        let target = outputs.around_mean();
        let ridge = RidgeProblem::new(&z, None, &target);
        let alpha = 0.2;
        let (b, x) = normal_equations(&z, &y, alpha);
        let fitted = DMatrix::from_fn(12, 5, |_, j| b[j]) + &z * x;
        let direct = (&y - fitted).norm_squared() / 60.0;
        let closed = ridge
            .cv_point(alpha, &segments(&[z.nrows()], 3))
            .train_error;
        assert!((closed - direct).abs() <= 1e-9 * direct);
    }

    #[test]
    fn solution_matches_normal_equations_and_zero_alpha_is_least_squares() {
        let (z, y) = problem(15, 4, 3, 11);
        let outputs = RidgeOutputs::new(y.clone());
        let target = outputs.around_mean();
        let ridge = RidgeProblem::new(&z, None, &target);
        for alpha in [0.0, 0.7] {
            let (b, x) = normal_equations(&z, &y, alpha);
            let s = ridge.solve(alpha);
            assert!((&s.intercept - &b).amax() <= 1e-10 * b.amax());
            assert!((&s.coefficients - &x).amax() <= 1e-10 * x.amax());
        }
    }

    #[test]
    fn rank_deficient_inputs_give_the_minimum_norm_solution() {
        let base = uniform(14, 3, 5);
        // Column 3 = column 0 + 2·column 1: Z has rank 3 of 4.
        let z = DMatrix::from_fn(14, 4, |i, j| {
            if j < 3 {
                base[(i, j)]
            } else {
                base[(i, 0)] + 2.0 * base[(i, 1)]
            }
        });
        let y = uniform(14, 3, 6);
        let outputs = RidgeOutputs::new(y.clone());
        let target = outputs.around_mean();
        let ridge = RidgeProblem::new(&z, None, &target);
        assert_eq!(ridge.rank(), 3);
        let mut zc = z.clone();
        let mut yc = y.clone();
        for j in 0..4 {
            let m = zc.column(j).mean();
            zc.column_mut(j).add_scalar_mut(-m);
        }
        for j in 0..3 {
            let m = yc.column(j).mean();
            yc.column_mut(j).add_scalar_mut(-m);
        }
        // α = 0: the pseudo-inverse solution.
        let pinv = zc.clone().pseudo_inverse(1e-12).unwrap() * &yc;
        let s0 = ridge.solve(0.0);
        assert!((&s0.coefficients - &pinv).amax() <= 1e-9 * pinv.amax());
        // α > 0: the unique ridge solution, (Z_cᵀZ_c + α²I)⁻¹ Z_cᵀ Y_c.
        let alpha: f64 = 0.3;
        let lhs = zc.transpose() * &zc + DMatrix::identity(4, 4) * alpha.powi(2);
        let reference = lhs.cholesky().unwrap().solve(&(zc.transpose() * &yc));
        let s = ridge.solve(alpha);
        assert!((&s.coefficients - &reference).amax() <= 1e-10 * reference.amax());
        // Both lie in the row space of Z_c: orthogonal to its null vector (1, 2, 0, −1).
        let null = DVector::from_vec(vec![1.0, 2.0, 0.0, -1.0]);
        assert!((s0.coefficients.tr_mul(&null)).amax() <= 1e-10 * s0.coefficients.amax());
    }

    #[test]
    fn huge_alpha_gives_the_mean() {
        let (z, y) = problem(10, 3, 4, 2);
        let outputs = RidgeOutputs::new(y.clone());
        let target = outputs.around_mean();
        let ridge = RidgeProblem::new(&z, None, &target);
        let s = ridge.solve(1e12);
        let mean = DVector::from_fn(4, |j, _| y.column(j).mean());
        assert!((&s.intercept - &mean).amax() <= 1e-12 * mean.amax());
        assert!(s.coefficients.amax() <= 1e-20);
    }

    #[test]
    fn selection_minimises_the_curve() {
        let (z, y) = problem(40, 5, 8, 21);
        let outputs = RidgeOutputs::new(y);
        let target = outputs.around_mean();
        let ridge = RidgeProblem::new(&z, None, &target);
        let selection = ridge.select_alpha(&segments(&[40], 4)).unwrap();
        assert!(selection.curve.len() > GRID_POINTS);
        assert!(selection.curve.windows(2).all(|w| w[0].alpha <= w[1].alpha));
        let best = selection
            .curve
            .iter()
            .find(|c| c.alpha == selection.alpha)
            .unwrap();
        assert!(selection.curve.iter().all(|c| c.cv_error >= best.cv_error));
        // The refined α is a local minimum at the refinement resolution.
        for factor in [0.99, 1.01] {
            assert!(
                ridge
                    .cv_point(selection.alpha * factor, &segments(&[40], 4))
                    .cv_error
                    >= best.cv_error * (1.0 - 1e-12)
            );
        }
        assert_eq!(
            ridge.select_alpha(&segments(&[40], 40)),
            Err(FitError::SegmentTooLong {
                segment: 40,
                poses: 40
            })
        );
    }

    /// Independent reference for the anchored fit: `X = (DᵀD + α²I)⁻¹ Dᵀ E` with `D = Z − 1z0ᵀ`,
    /// `E = Y − 1y0ᵀ`, by Cholesky.
    fn anchored_reference(
        z: &DMatrix<f64>,
        y: &DMatrix<f64>,
        z0: &DVector<f64>,
        y0: &DVector<f64>,
        alpha: f64,
    ) -> DMatrix<f64> {
        let d = DMatrix::from_fn(z.nrows(), z.ncols(), |i, j| z[(i, j)] - z0[j]);
        let e = DMatrix::from_fn(y.nrows(), y.ncols(), |i, j| y[(i, j)] - y0[j]);
        let lhs = d.transpose() * &d + DMatrix::identity(z.ncols(), z.ncols()) * alpha.powi(2);
        lhs.cholesky().unwrap().solve(&(d.transpose() * e))
    }

    fn anchor(k: usize, q: usize) -> (DVector<f64>, DVector<f64>) {
        (
            DVector::from_fn(k, |j, _| 0.1 * j as f64 - 0.2),
            DVector::from_fn(q, |j, _| 1.5 + 0.25 * j as f64),
        )
    }

    #[test]
    fn anchored_fit_matches_its_normal_equations_and_passes_through_the_anchor() {
        let (z, y) = problem(16, 4, 3, 31);
        let (z0, y0) = anchor(4, 3);
        let outputs = RidgeOutputs::new(y.clone());
        let target = outputs.around_anchor(&y0);
        let ridge = RidgeProblem::new(&z, Some(&z0), &target);
        for alpha in [1e-3, 0.5, 4.0] {
            let x = anchored_reference(&z, &y, &z0, &y0, alpha);
            let s = ridge.solve(alpha);
            assert!(
                (&s.coefficients - &x).amax() <= 1e-10 * x.amax(),
                "α = {alpha}"
            );
            let at_anchor = &s.intercept + s.coefficients.tr_mul(&z0);
            assert!((at_anchor - &y0).amax() <= 1e-12 * y0.amax(), "α = {alpha}");
        }
    }

    #[test]
    fn anchored_fit_at_huge_alpha_is_the_anchor_exactly() {
        let (z, y) = problem(10, 3, 4, 2);
        let (z0, y0) = anchor(3, 4);
        let outputs = RidgeOutputs::new(y);
        let target = outputs.around_anchor(&y0);
        let s = RidgeProblem::new(&z, Some(&z0), &target).solve(1e150);
        assert_eq!(s.intercept, y0);
        assert!(s.coefficients.amax() <= 1e-140);
    }

    #[test]
    fn anchored_closed_form_cv_equals_refits() {
        let (z, y) = problem(19, 4, 5, 41);
        let (z0, y0) = anchor(4, 5);
        for stored in [false, true] {
            let outputs = RidgeOutputs::with_gram(y.clone(), stored);
            let target = outputs.around_anchor(&y0);
            let ridge = RidgeProblem::new(&z, Some(&z0), &target);
            for segment in [1, 3, 6] {
                for alpha in [1e-2, 0.3, 2.0] {
                    let mut brute = 0.0;
                    for start in (0..19).step_by(segment) {
                        let held: Vec<usize> = (start..(start + segment).min(19)).collect();
                        let kept: Vec<usize> = (0..19).filter(|i| !held.contains(i)).collect();
                        let (zk, yk) = (z.select_rows(&kept), y.select_rows(&kept));
                        let x = anchored_reference(&zk, &yk, &z0, &y0, alpha);
                        for &i in &held {
                            let prediction = y0.transpose() + (z.row(i) - z0.transpose()) * &x;
                            brute += (y.row(i) - prediction).norm_squared();
                        }
                    }
                    let closed = ridge
                        .cv_point(alpha, &segments(&[z.nrows()], segment))
                        .cv_error
                        * (19 * 5) as f64;
                    assert!(
                        (closed - brute).abs() <= 1e-9 * brute,
                        "Gram stored {stored}, L = {segment}, α = {alpha}: {closed} vs {brute}"
                    );
                }
            }
        }
    }

    #[test]
    fn held_out_clip_error_equals_the_direct_prediction_error() {
        let (z, y) = problem(20, 3, 4, 51);
        let (zh, yh) = problem(7, 3, 4, 52);
        let (z0, y0) = anchor(3, 4);
        let outputs = RidgeOutputs::new(y);
        for anchored in [false, true] {
            let target = if anchored {
                outputs.around_anchor(&y0)
            } else {
                outputs.around_mean()
            };
            let ridge = RidgeProblem::new(&z, anchored.then_some(&z0), &target);
            let held = [HeldOut {
                z: zh.clone(),
                y: yh.clone(),
                weight: 1.0,
            }];
            for alpha in [1e-2, 0.4, 3.0] {
                let s = ridge.solve(alpha);
                let prediction =
                    &zh * &s.coefficients + DMatrix::from_fn(7, 4, |_, j| s.intercept[j]);
                let direct = (&yh - prediction).norm_squared() / 28.0;
                let closed = ridge.held_out_point(alpha, &held).cv_error;
                assert!(
                    (closed - direct).abs() <= 1e-9 * direct,
                    "anchored {anchored}, α = {alpha}: {closed} vs {direct}"
                );
                // Pose by pose, over two held-out sets: what the sums add up.
                let halves = [
                    HeldOut {
                        z: zh.rows(0, 3).into_owned(),
                        y: yh.rows(0, 3).into_owned(),
                        weight: 1.0,
                    },
                    HeldOut {
                        z: zh.rows(3, 4).into_owned(),
                        y: yh.rows(3, 4).into_owned(),
                        weight: 1.0,
                    },
                ];
                let rows = ridge.held_out_rows(alpha, &halves);
                assert_eq!(rows.len(), 7);
                let pooled = rows.iter().sum::<f64>() / 28.0;
                assert!(
                    (pooled - direct).abs() <= 1e-9 * direct,
                    "{pooled} vs {direct}"
                );
            }
            let prior = target.prior_held_out_rows(&held);
            let pooled = prior.iter().sum::<f64>() / 28.0;
            let closed = target.prior_held_out(&held).cv_error;
            assert!(
                (pooled - closed).abs() <= 1e-12 * closed,
                "{pooled} vs {closed}"
            );
        }
    }

    #[test]
    fn segments_stay_inside_their_clips() {
        assert_eq!(segments(&[5, 3], 2), vec![0..2, 2..4, 4..5, 5..7, 7..8]);
        assert_eq!(segments(&[4], 0), vec![0..1, 1..2, 2..3, 3..4]);
    }
}
