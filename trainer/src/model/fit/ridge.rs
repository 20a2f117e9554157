//! Tikhonov ridge regression of many outputs on the pose coordinates, with an unpenalised
//! intercept and α chosen by closed-form cross validation.
//!
//! Minimises `‖Y − 1bᵀ − Z X‖² + α²‖X‖²`. With centred `Z_c = U S Vᵀ` (thin, cut at the
//! numerical rank) and centred `Y_c`: `X = V diag(s / (s² + α²)) Uᵀ Y_c`, `b = ȳ − Xᵀ z̄`.
//! The SVD form is the minimum-norm solution when Z is rank-deficient, and the intercept being
//! unpenalised means a huge α tends to the mean output (the mean transfer), not to zero.
//!
//! The fit is a linear smoother `Ŷ = H Y` with `H = 11ᵀ/p + U F Uᵀ`, `F = diag(s²/(s²+α²))`,
//! so held-out residuals follow from the in-sample ones without refits: for a held-out set S,
//! `e_S = (I − H_SS)⁻¹ r_S` (leave-one-out is the case |S| = 1). All that is needed of Y is its
//! `p × p` Gram `K = Y_c Y_cᵀ`: the residual Gram is `(I − H) K (I − H)`, and expanding it in
//! `K' = Uᵀ K` and `M = Uᵀ K U` makes each α cost `O(p·L·r²)` (segment length L, rank r)
//! whatever the output width — the full model has ~400k outputs per pose.
//! The price of the Gram form is resolution: residuals below about `√ε · ‖Y_c‖` cancel in
//! `K` and read as zero, which only matters once the fit is already exact to ~1e-8.
//!
//! [`RidgeProblem::anchored`] fits through a given point `(z₀, y₀)` instead: no intercept, `Z`
//! and `Y` taken relative to the anchor, `H = U F Uᵀ`, so a huge α tends to `y₀` (a prior such
//! as the bind pose's transfer) and the regression only adds what the data supports.

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
/// Above this α every filter factor is below 1e-6: the model is the mean.
const GRID_HIGH: f64 = 1e3;
/// Golden-section refinement stops when the log-α bracket is this narrow (0.01 % in α).
const REFINE_LOG_WIDTH: f64 = 1e-4;
/// Output columns per block of the Gram product, summed in a fixed order for determinism.
const GRAM_COLUMNS_PER_BLOCK: usize = 4096;

/// A ridge problem: centred data and the SVD of the centred inputs.
#[derive(Clone, Debug)]
pub struct RidgeProblem {
    /// The point the data is centred on: the means, or the anchor.
    z_mean: DVector<f64>,
    y_mean: DVector<f64>,
    /// Whether the intercept is fitted (centred on the means) or given (the anchor).
    fitted_intercept: bool,
    /// `p × r` left singular vectors of `Z_c`.
    u: DMatrix<f64>,
    /// r singular values, descending, all above the rank tolerance.
    s: DVector<f64>,
    /// `k × r` right singular vectors.
    v: DMatrix<f64>,
    /// `p × q` centred outputs.
    y_centred: DMatrix<f64>,
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
    /// The minimiser of the CV error.
    pub alpha: f64,
    /// Grid and refinement points, ascending in α.
    pub curve: Vec<CvPoint>,
}

impl RidgeProblem {
    /// Centres `z` (`p × k`) and `y` (`p × q`, taken by value and centred in place: for the full
    /// model it is the largest array of the fit) and factors `Z_c`.
    pub fn new(z: &DMatrix<f64>, y: DMatrix<f64>) -> Self {
        let z_mean = DVector::from_fn(z.ncols(), |j, _| z.column(j).mean());
        let y_mean = DVector::from_fn(y.ncols(), |j, _| y.column(j).mean());
        Self::centred_on(z, y, z_mean, y_mean, true)
    }

    /// The fit through `(z0, y0)`: `ŷ(z) = y0 + Xᵀ (z − z0)` with only `X` penalised, so that
    /// a huge α gives `y0` exactly.
    pub fn anchored(z: &DMatrix<f64>, y: DMatrix<f64>, z0: DVector<f64>, y0: DVector<f64>) -> Self {
        assert_eq!(
            (z0.len(), y0.len()),
            (z.ncols(), y.ncols()),
            "ridge: anchor shape"
        );
        Self::centred_on(z, y, z0, y0, false)
    }

    fn centred_on(
        z: &DMatrix<f64>,
        mut y: DMatrix<f64>,
        z_mean: DVector<f64>,
        y_mean: DVector<f64>,
        fitted_intercept: bool,
    ) -> Self {
        let (p, k) = z.shape();
        assert_eq!(y.nrows(), p, "ridge: Z and Y must have one row per pose");
        for (mut col, m) in y.column_iter_mut().zip(y_mean.iter()) {
            col.add_scalar_mut(-m);
        }
        let mut zc = z.clone();
        for (mut col, m) in zc.column_iter_mut().zip(z_mean.iter()) {
            col.add_scalar_mut(-m);
        }
        if p == 0 || k == 0 {
            // No pose coordinates (e.g. a single pose): nothing to factor, the fit is the mean.
            let (u, s, v) = (
                DMatrix::zeros(p, 0),
                DVector::zeros(0),
                DMatrix::zeros(k, 0),
            );
            return Self {
                z_mean,
                y_mean,
                fitted_intercept,
                u,
                s,
                v,
                y_centred: y,
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
            z_mean,
            y_mean,
            fitted_intercept,
            u,
            s,
            v,
            y_centred: y,
        }
    }

    /// Numerical rank r of the centred inputs: 0 means the outputs cannot depend on the pose.
    pub fn rank(&self) -> usize {
        self.s.len()
    }

    /// Ridge solution at `alpha` (α = 0 is the minimum-norm least-squares solution).
    pub fn solve(&self, alpha: f64) -> RidgeSolution {
        let filter = self.s.map(|s| s / (s * s + alpha * alpha));
        let mut uty = self.u.tr_mul(&self.y_centred);
        for (mut row, f) in uty.row_iter_mut().zip(filter.iter()) {
            row *= *f;
        }
        let coefficients = &self.v * uty;
        let intercept = &self.y_mean - coefficients.tr_mul(&self.z_mean);
        RidgeSolution {
            intercept,
            coefficients,
        }
    }

    /// Chooses α minimising the leave-segment-out error over contiguous runs of `segment`
    /// poses (1 = leave-one-out): a 60-point log grid relative to `s_max`, then golden-section
    /// search on log α around the best grid point.
    pub fn select_alpha(&self, segment: usize) -> Result<AlphaSelection, FitError> {
        let p = self.u.nrows();
        let segment = segment.max(1);
        // Rank 0: no pose dependence to regularise; the fit is the mean whatever α.
        let Some(&s_max) = self.s.as_slice().first() else {
            return Ok(AlphaSelection {
                alpha: 0.0,
                curve: Vec::new(),
            });
        };
        // Holding out every pose leaves nothing to fit on.
        if segment >= p {
            return Err(FitError::SegmentTooLong { segment, poses: p });
        }
        let cv = GramCv::new(self, segment);
        let log_lo = (GRID_LOW * s_max).ln();
        let step = ((GRID_HIGH * s_max).ln() - log_lo) / (GRID_POINTS - 1) as f64;
        let mut curve: Vec<CvPoint> = (0..GRID_POINTS)
            .map(|i| cv.evaluate((log_lo + step * i as f64).exp()))
            .collect();
        let best = argmin(&curve).ok_or(FitError::NoFiniteCvError)?;
        // Golden-section search on log α inside the neighbouring grid points.
        let inv_phi = (5f64.sqrt() - 1.0) / 2.0;
        let (mut a, mut b) = (
            log_lo + step * best.saturating_sub(1) as f64,
            log_lo + step * (best + 1).min(GRID_POINTS - 1) as f64,
        );
        let mut x1 = b - inv_phi * (b - a);
        let mut x2 = a + inv_phi * (b - a);
        let (mut f1, mut f2) = (cv.evaluate(x1.exp()), cv.evaluate(x2.exp()));
        curve.extend([f1, f2]);
        while b - a > REFINE_LOG_WIDTH {
            if f1.cv_error <= f2.cv_error {
                (b, x2, f2) = (x2, x1, f1);
                x1 = b - inv_phi * (b - a);
                f1 = cv.evaluate(x1.exp());
                curve.push(f1);
            } else {
                (a, x1, f1) = (x1, x2, f2);
                x2 = a + inv_phi * (b - a);
                f2 = cv.evaluate(x2.exp());
                curve.push(f2);
            }
        }
        curve.sort_by(|l, r| l.alpha.total_cmp(&r.alpha));
        let alpha = curve[argmin(&curve).expect("the grid had a finite point")].alpha;
        Ok(AlphaSelection { alpha, curve })
    }

    /// Held-out and in-sample error at one α (see [`CvPoint`]); `segment` as in
    /// [`Self::select_alpha`].
    pub fn cv_point(&self, alpha: f64, segment: usize) -> CvPoint {
        GramCv::new(self, segment.max(1)).evaluate(alpha)
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

/// Everything cross validation needs, independent of α: the output Gram and its projections.
struct GramCv<'a> {
    problem: &'a RidgeProblem,
    segment: usize,
    /// `K = Y_c Y_cᵀ`, `p × p`.
    k: DMatrix<f64>,
    /// `K' = Uᵀ K`, `r × p`.
    ku: DMatrix<f64>,
    /// `M = Uᵀ K U`, `r × r`.
    m: DMatrix<f64>,
    /// `p·q`, the error normalisation.
    entries: f64,
}

impl<'a> GramCv<'a> {
    fn new(problem: &'a RidgeProblem, segment: usize) -> Self {
        let y = &problem.y_centred;
        let (p, q) = y.shape();
        let starts: Vec<usize> = (0..q).step_by(GRAM_COLUMNS_PER_BLOCK).collect();
        let parts: Vec<DMatrix<f64>> = starts
            .par_iter()
            .map(|&c| {
                let block = y.columns(c, GRAM_COLUMNS_PER_BLOCK.min(q - c));
                block * block.transpose()
            })
            .collect();
        let k = parts
            .into_iter()
            .fold(DMatrix::zeros(p, p), |acc, part| acc + part);
        let ku = problem.u.tr_mul(&k);
        let m = &ku * &problem.u;
        Self {
            problem,
            segment,
            k,
            ku,
            m,
            entries: (p * q.max(1)) as f64,
        }
    }

    fn evaluate(&self, alpha: f64) -> CvPoint {
        let (u, s) = (&self.problem.u, &self.problem.s);
        let p = u.nrows();
        let f = s.map(|s| s * s / (s * s + alpha * alpha));
        let mut uf = u.clone();
        for (mut col, fk) in uf.column_iter_mut().zip(f.iter()) {
            col *= *fk;
        }
        let (mut cv, mut train) = (0.0, 0.0);
        for start in (0..p).step_by(self.segment) {
            let len = self.segment.min(p - start);
            let (u_s, uf_s) = (u.rows(start, len), uf.rows(start, len));
            // Residual Gram of the segment: [(I − H) K (I − H)]_SS with H = 11ᵀ/p + U F Uᵀ
            // (H = U F Uᵀ when anchored); the 11ᵀ/p part vanishes against the centred K.
            let cross = uf_s * self.ku.columns(start, len);
            let g = self.k.view((start, start), (len, len)) - &cross - cross.transpose()
                + uf_s * &self.m * uf_s.transpose();
            let mean_part = if self.problem.fitted_intercept {
                1.0 / p as f64
            } else {
                0.0
            };
            let i_minus_h = DMatrix::identity(len, len)
                - DMatrix::from_element(len, len, mean_part)
                - uf_s * u_s.transpose();
            train += g.trace();
            cv += match i_minus_h.cholesky() {
                // e_S = (I − H_SS)⁻¹ r_S, so Σ‖e_S‖² = tr((I − H_SS)⁻¹ G (I − H_SS)⁻¹).
                Some(chol) => chol.solve(&chol.solve(&g).transpose()).trace(),
                None => f64::INFINITY,
            };
        }
        // Cancellation in the Gram expansion can leave tiny negative values.
        CvPoint {
            alpha,
            cv_error: cv.max(0.0) / self.entries,
            train_error: train.max(0.0) / self.entries,
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
        let ridge = RidgeProblem::new(&z, y.clone());
        for alpha in [1e-3, 0.05, 0.4, 3.0] {
            let closed = ridge.cv_point(alpha, 1).cv_error * (17 * 6) as f64;
            let brute = brute_force_cv(&z, &y, alpha, 1);
            assert!(
                (closed - brute).abs() <= 1e-9 * brute,
                "α = {alpha}: {closed} vs {brute}"
            );
        }
    }

    #[test]
    fn closed_form_loso_equals_refits() {
        let (z, y) = problem(23, 5, 4, 7);
        let ridge = RidgeProblem::new(&z, y.clone());
        for segment in [2, 5, 7] {
            for alpha in [1e-2, 0.3, 2.0] {
                let closed = ridge.cv_point(alpha, segment).cv_error * (23 * 4) as f64;
                let brute = brute_force_cv(&z, &y, alpha, segment);
                assert!(
                    (closed - brute).abs() <= 1e-9 * brute,
                    "L = {segment}, α = {alpha}: {closed} vs {brute}"
                );
            }
        }
    }

    #[test]
    fn train_error_is_the_in_sample_residual() {
        let (z, y) = problem(12, 3, 5, 3);
        let ridge = RidgeProblem::new(&z, y.clone());
        let alpha = 0.2;
        let (b, x) = normal_equations(&z, &y, alpha);
        let fitted = DMatrix::from_fn(12, 5, |_, j| b[j]) + &z * x;
        let direct = (&y - fitted).norm_squared() / 60.0;
        let closed = ridge.cv_point(alpha, 3).train_error;
        assert!((closed - direct).abs() <= 1e-9 * direct);
    }

    #[test]
    fn solution_matches_normal_equations_and_zero_alpha_is_least_squares() {
        let (z, y) = problem(15, 4, 3, 11);
        let ridge = RidgeProblem::new(&z, y.clone());
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
        let ridge = RidgeProblem::new(&z, y.clone());
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
        let ridge = RidgeProblem::new(&z, y.clone());
        let s = ridge.solve(1e12);
        let mean = DVector::from_fn(4, |j, _| y.column(j).mean());
        assert!((&s.intercept - &mean).amax() <= 1e-12 * mean.amax());
        assert!(s.coefficients.amax() <= 1e-20);
    }

    #[test]
    fn selection_minimises_the_curve() {
        let (z, y) = problem(40, 5, 8, 21);
        let ridge = RidgeProblem::new(&z, y);
        let selection = ridge.select_alpha(4).unwrap();
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
                ridge.cv_point(selection.alpha * factor, 4).cv_error
                    >= best.cv_error * (1.0 - 1e-12)
            );
        }
        assert_eq!(
            ridge.select_alpha(40),
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
        let ridge = RidgeProblem::anchored(&z, y.clone(), z0.clone(), y0.clone());
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
        let s = RidgeProblem::anchored(&z, y, z0, y0.clone()).solve(1e150);
        assert_eq!(s.intercept, y0);
        assert!(s.coefficients.amax() <= 1e-140);
    }

    #[test]
    fn anchored_closed_form_cv_equals_refits() {
        let (z, y) = problem(19, 4, 5, 41);
        let (z0, y0) = anchor(4, 5);
        let ridge = RidgeProblem::anchored(&z, y.clone(), z0.clone(), y0.clone());
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
                let closed = ridge.cv_point(alpha, segment).cv_error * (19 * 5) as f64;
                assert!(
                    (closed - brute).abs() <= 1e-9 * brute,
                    "L = {segment}, α = {alpha}: {closed} vs {brute}"
                );
            }
        }
    }
}
