//! Randomized truncated SVD (Halko, Martinsson & Tropp 2011, algorithms 4.4 and 5.1).
//!
//! The vertex basis needs the leading right singular vectors of a `p·n² × v` matrix (9000 ×
//! 11 500 for the paper's character). A dense SVD of that costs O(m·n·min(m, n)) and, in
//! nalgebra, minutes; a Gaussian sketch with a few power iterations gets the leading k vectors
//! in a handful of passes over the data, each pass a matrix product that parallelises. The
//! matrix is only touched through [`RowOperator`], so callers never have to build it in f64.

use nalgebra::DMatrix;

/// A real `m × n` matrix seen only through products with thin matrices.
pub trait RowOperator: Sync {
    /// m.
    fn nrows(&self) -> usize;
    /// n.
    fn ncols(&self) -> usize;
    /// `R X` for an `n × l` matrix `X`.
    fn mul(&self, x: &DMatrix<f64>) -> DMatrix<f64>;
    /// `Rᵀ Y` for an `m × l` matrix `Y`.
    fn tr_mul(&self, y: &DMatrix<f64>) -> DMatrix<f64>;
    /// `‖R‖_F²`, the total energy variance fractions refer to.
    fn frobenius_sq(&self) -> f64;
}

impl RowOperator for DMatrix<f64> {
    fn nrows(&self) -> usize {
        self.nrows()
    }
    fn ncols(&self) -> usize {
        self.ncols()
    }
    fn mul(&self, x: &DMatrix<f64>) -> DMatrix<f64> {
        self * x
    }
    fn tr_mul(&self, y: &DMatrix<f64>) -> DMatrix<f64> {
        DMatrix::tr_mul(self, y)
    }
    fn frobenius_sq(&self) -> f64 {
        self.norm_squared()
    }
}

/// Leading singular values and right singular vectors.
#[derive(Clone, Debug)]
pub struct TruncatedSvd {
    /// Singular values, descending.
    pub singular_values: Vec<f64>,
    /// Right singular vectors as columns, `n × l`.
    pub right: DMatrix<f64>,
}

/// Sketch parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SketchOptions {
    /// Number of vectors to sketch (target rank plus oversampling); clamped to `min(m, n)`.
    pub width: usize,
    /// Power (subspace) iterations. Each one sharpens the spectral decay seen by the sketch
    /// from `σ_j` to `σ_j^(2q+1)`, which matters for PRT data whose spectrum decays slowly
    /// after the first few components.
    pub power_iterations: usize,
    /// Seed of the Gaussian test matrix: same seed, same basis, whatever the thread count.
    pub seed: u64,
}

/// Randomized SVD of `op`: range finder with re-orthonormalised power iterations, then an
/// exact SVD of the small projected matrix.
///
/// With `width = min(m, n)` the sketch spans the whole range and the result is an exact SVD
/// up to rounding.
pub fn randomized_svd(op: &impl RowOperator, options: SketchOptions) -> TruncatedSvd {
    let (m, n) = (op.nrows(), op.ncols());
    let l = options.width.min(m).min(n);
    if l == 0 {
        return TruncatedSvd {
            singular_values: Vec::new(),
            right: DMatrix::zeros(n, 0),
        };
    }
    let omega = gaussian_matrix(n, l, options.seed);
    // Re-orthonormalising after every product keeps the small singular directions from being
    // swamped in floating point by the large ones (HMT algorithm 4.4).
    let mut q = orthonormal(op.mul(&omega));
    for _ in 0..options.power_iterations {
        let w = orthonormal(op.tr_mul(&q));
        q = orthonormal(op.mul(&w));
    }
    // B = Qᵀ R is l × n. Factor Bᵀ = Q₂ R₂ (n × l, l × l), so B = R₂ᵀ Q₂ᵀ and with the small
    // SVD R₂ᵀ = U_b S V_bᵀ the right singular vectors of B (≈ those of R) are Q₂ V_b.
    let qr = op.tr_mul(&q).qr();
    let (q2, r2) = (qr.q(), qr.r());
    let svd = r2.transpose().svd(false, true);
    let v_b = svd.v_t.expect("SVD computed with V").transpose();
    TruncatedSvd {
        singular_values: svd.singular_values.iter().copied().collect(),
        right: q2 * v_b,
    }
}

/// Orthonormal basis of the column space (thin Householder QR).
fn orthonormal(y: DMatrix<f64>) -> DMatrix<f64> {
    y.qr().q()
}

/// Standard normal `rows × cols` matrix from SplitMix64 and Box–Muller: a fixed, portable
/// stream, so the sketch (and the basis) depend only on the seed.
fn gaussian_matrix(rows: usize, cols: usize, seed: u64) -> DMatrix<f64> {
    let mut state = seed;
    let mut next_unit = move || {
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        // In (0, 1]: never 0, so the logarithm below is finite.
        ((z >> 11) + 1) as f64 / (1u64 << 53) as f64
    };
    let mut values = Vec::with_capacity(rows * cols + 1);
    while values.len() < rows * cols {
        let (u1, u2) = (next_unit(), next_unit());
        let radius = (-2.0 * u1.ln()).sqrt();
        let angle = std::f64::consts::TAU * u2;
        values.push(radius * angle.cos());
        values.push(radius * angle.sin());
    }
    values.truncate(rows * cols);
    DMatrix::from_vec(rows, cols, values)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rank-8 matrix with singular values 100 … 1.2 (decaying) plus Gaussian noise of
    /// spectral norm about 1e-4 · (√m + √n).
    fn low_rank_plus_noise(m: usize, n: usize) -> DMatrix<f64> {
        let u = orthonormal(gaussian_matrix(m, 8, 11));
        let v = orthonormal(gaussian_matrix(n, 8, 12));
        let s = DMatrix::from_diagonal(&nalgebra::DVector::from_fn(8, |i, _| {
            100.0 * 0.53f64.powi(i as i32)
        }));
        &u * s * v.transpose() + gaussian_matrix(m, n, 13) * 1e-4
    }

    #[test]
    fn matches_exact_svd_on_low_rank_plus_noise() {
        let r = low_rank_plus_noise(180, 140);
        let exact = r.clone().svd(false, true);
        let v_exact = exact.v_t.unwrap().transpose();
        let opts = SketchOptions {
            width: 8 + 10,
            power_iterations: 2,
            seed: 5,
        };
        let approx = randomized_svd(&r, opts);
        // Gap σ₈/σ₉ ≈ 1.2 / 2.5e-3: with q = 2 the leading values are exact to far below the
        // noise level, so only rounding remains.
        for k in 0..8 {
            let (a, e) = (approx.singular_values[k], exact.singular_values[k]);
            assert!((a - e).abs() <= 1e-9 * e, "σ_{k}: {a} vs {e}");
        }
        // Subspace: the cosines of the principal angles between the leading 8-dim subspaces.
        let overlap = approx.right.columns(0, 8).transpose() * v_exact.columns(0, 8);
        let cosines = overlap.singular_values();
        assert!(cosines.iter().all(|&c| c > 1.0 - 1e-10), "{cosines}");
        // Orthonormal right vectors.
        let g = approx.right.transpose() * &approx.right;
        assert!((g - DMatrix::identity(18, 18)).amax() < 1e-12);
    }

    #[test]
    fn full_width_sketch_is_an_exact_svd() {
        let r = gaussian_matrix(30, 12, 3);
        let exact = r.singular_values();
        let approx = randomized_svd(
            &r,
            SketchOptions {
                width: 40,
                power_iterations: 0,
                seed: 9,
            },
        );
        assert_eq!(approx.singular_values.len(), 12);
        for (a, e) in approx.singular_values.iter().zip(exact.iter()) {
            assert!((a - e).abs() <= 1e-12 * exact[0]);
        }
    }

    #[test]
    fn gaussian_stream_has_unit_moments() {
        let g = gaussian_matrix(200, 100, 1);
        let mean = g.mean();
        let var = g.map(|x| (x - mean) * (x - mean)).mean();
        // 20 000 samples: standard errors 0.007 (mean) and 0.01 (variance); 5σ bounds.
        assert!(mean.abs() < 0.035, "{mean}");
        assert!((var - 1.0).abs() < 0.05, "{var}");
        assert_eq!(g, gaussian_matrix(200, 100, 1));
    }
}
