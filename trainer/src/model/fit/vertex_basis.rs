//! The shared vertex basis Π_v: k_v orthonormal vectors over vertices, learned from all
//! `p·n²` rows `b_i^c ∈ R^v` (transfer of SH coefficient c in pose i).
//!
//! The SVD is **uncentred**. The runtime reconstructs transfer as `Σ_k w_k U_k` with no vertex
//! mean term (see [`crate::model`]), so the basis must itself span the mean transfer, which is
//! by far the largest component of PRT data (every coefficient row shares the character's
//! self-occlusion). Centring would spend no vector on it and the model could not reproduce it.
//! The intercept of the ridge then lives in basis coordinates like every other weight.

use aprt_core::MAX_COEF_DIMS;
use nalgebra::DMatrix;
use rayon::prelude::*;

use super::dims::{self, Dims};
use super::rsvd::{RowOperator, SketchOptions, randomized_svd};

/// Oversampling of the sketch beyond the wanted dimension (HMT recommend 5–10).
const OVERSAMPLE: usize = 10;
/// Power iterations: enough for the slowly decaying tail of PRT spectra.
const POWER_ITERATIONS: usize = 2;
/// First sketch width when the dimension is chosen by energy fraction; doubled until the
/// fraction is reached inside the trusted (non-oversampled) part of the spectrum.
const INITIAL_WIDTH: usize = 32;
/// Fixed seed: the basis is a deterministic function of the data.
const SEED: u64 = 0x5eed_0a9e_7001;
/// Poses per gemm block: big enough for an efficient product, small enough to stay in cache
/// (8 poses · 36 coefficients · 12k vertices · 8 bytes ≈ 28 MB).
const POSES_PER_BLOCK: usize = 8;
/// Fixed number of contiguous groups a reduction is split into. Each group sums its blocks
/// in order and the groups are summed in order, so `Rᵀ Y` does not depend on the thread
/// count or on work stealing.
const REDUCTION_GROUPS: usize = 16;

/// The row matrix R (`p·n² × v`, row `i·n² + c` = coefficient c of pose i over vertices) read
/// straight from the f32 vertex-major transfer, a block of poses at a time.
pub struct PoseRows<'a> {
    transfers: Vec<&'a [f32]>,
    coefs: usize,
    vertices: usize,
}

impl<'a> PoseRows<'a> {
    /// `transfers[i]` is pose i's `v × n²` vertex-major transfer (`[j·n² + c]`); every entry
    /// must have length `vertices · coefs`: [`crate::model::fit::fit`] validates this, direct callers
    /// must too (a shorter array makes the products panic on a slice bound).
    pub fn new(transfers: &'a [Vec<f32>], coefs: usize, vertices: usize) -> Self {
        Self::from_slices(
            transfers.iter().map(Vec::as_slice).collect(),
            coefs,
            vertices,
        )
    }

    /// The rows of poses given as slices, same contract as [`Self::new`].
    pub fn from_slices(transfers: Vec<&'a [f32]>, coefs: usize, vertices: usize) -> Self {
        Self {
            transfers,
            coefs,
            vertices,
        }
    }

    /// Rows of the poses `first..first + count` as an f64 `(count·n²) × v` matrix. A vertex-major
    /// pose array is exactly the column-major layout of its `n² × v` block, so a block of poses
    /// is built column by column from contiguous slices.
    fn block(&self, first: usize, count: usize) -> DMatrix<f64> {
        let n2 = self.coefs;
        let mut data = Vec::with_capacity(count * n2 * self.vertices);
        for j in 0..self.vertices {
            for pose in &self.transfers[first..first + count] {
                data.extend(pose[j * n2..(j + 1) * n2].iter().map(|&x| f64::from(x)));
            }
        }
        DMatrix::from_vec(count * n2, self.vertices, data)
    }

    fn blocks(&self) -> Vec<(usize, usize)> {
        let p = self.transfers.len();
        (0..p)
            .step_by(POSES_PER_BLOCK)
            .map(|s| (s, POSES_PER_BLOCK.min(p - s)))
            .collect()
    }
}

impl RowOperator for PoseRows<'_> {
    fn nrows(&self) -> usize {
        self.transfers.len() * self.coefs
    }

    fn ncols(&self) -> usize {
        self.vertices
    }

    fn mul(&self, x: &DMatrix<f64>) -> DMatrix<f64> {
        let parts: Vec<DMatrix<f64>> = self
            .blocks()
            .into_par_iter()
            .map(|(first, count)| self.block(first, count) * x)
            .collect();
        let mut out = DMatrix::zeros(self.nrows(), x.ncols());
        for ((first, _), part) in self.blocks().into_iter().zip(parts) {
            out.rows_mut(first * self.coefs, part.nrows())
                .copy_from(&part);
        }
        out
    }

    fn tr_mul(&self, y: &DMatrix<f64>) -> DMatrix<f64> {
        let blocks = self.blocks();
        let per_group = blocks.len().div_ceil(REDUCTION_GROUPS).max(1);
        let partials: Vec<DMatrix<f64>> = blocks
            .par_chunks(per_group)
            .map(|group| {
                let mut acc = DMatrix::zeros(self.vertices, y.ncols());
                for &(first, count) in group {
                    let rows = y.rows(first * self.coefs, count * self.coefs);
                    acc += self.block(first, count).tr_mul(&rows);
                }
                acc
            })
            .collect();
        partials
            .into_iter()
            .fold(DMatrix::zeros(self.vertices, y.ncols()), |acc, p| acc + p)
    }

    fn frobenius_sq(&self) -> f64 {
        self.transfers
            .par_iter()
            .map(|t| t.iter().map(|&x| f64::from(x).powi(2)).sum::<f64>())
            .collect::<Vec<_>>()
            .iter()
            .sum()
    }
}

/// The fitted vertex basis and its spectrum.
#[derive(Clone, Debug)]
pub struct VertexBasisFit {
    /// `v × k_v`, orthonormal columns.
    pub basis: DMatrix<f64>,
    /// Captured energy `σ_k²` of the leading computed components (at least k_v of them),
    /// descending.
    pub energies: Vec<f64>,
    /// `‖R‖_F²`: the total the energies are fractions of.
    pub total_energy: f64,
}

/// Learns the basis by randomized SVD; `dims` is a count, an energy fraction of `‖R‖_F²`, or
/// all components up to the numerical rank. The rank is judged at f32 precision, the
/// precision transfer is baked and stored in.
///
/// An energy fraction or all keeps at most [`MAX_COEF_DIMS`] vectors, the most the runtime
/// holds, as on the pose side; an explicit count is kept as asked (the writer then says it is
/// too many). Real transfer spectra decay slowly (the built-in character keeps 94 % at
/// k_v = 22), and chasing 99.9 % would grow the sketch to thousands of columns for a model no
/// engine can load.
pub fn fit_vertex_basis(rows: &impl RowOperator, dims: Dims) -> VertexBasisFit {
    let max_width = rows.nrows().min(rows.ncols());
    let cap = dims.cap(MAX_COEF_DIMS).min(max_width);
    let total_energy = rows.frobenius_sq();
    let mut width = match dims {
        Dims::Count(k) => k + OVERSAMPLE,
        Dims::Variance(_) => INITIAL_WIDTH + OVERSAMPLE,
        Dims::All | Dims::Auto => cap + OVERSAMPLE,
    }
    .min(max_width);
    loop {
        let svd = randomized_svd(
            rows,
            SketchOptions {
                width,
                power_iterations: POWER_ITERATIONS,
                seed: SEED,
            },
        );
        let exact = width == max_width;
        let trusted = if exact {
            width
        } else {
            width.saturating_sub(OVERSAMPLE)
        };
        let energies: Vec<f64> = svd.singular_values[..trusted]
            .iter()
            .map(|s| s * s)
            .collect();
        let found_rank = dims::numerical_rank(
            &svd.singular_values,
            rows.nrows(),
            rows.ncols(),
            f32::EPSILON.into(),
        );
        // A rank below the sketch width is the true rank; otherwise it is only bounded by the shape.
        let rank = if exact || found_rank < width {
            found_rank
        } else {
            max_width
        };
        let capped = trusted >= cap;
        let chosen = dims::choose(dims, &energies, total_energy, rank);
        if let Some(keep) = chosen
            .map(|k| if capped { k.min(cap) } else { k })
            .or(capped.then_some(cap))
        {
            return VertexBasisFit {
                basis: svd.right.columns(0, keep).into_owned(),
                energies,
                total_energy,
            };
        }
        width = (2 * width).min(max_width).min(cap + OVERSAMPLE);
    }
}

/// Rows with their component in a fixed orthonormal subspace `Q` (`v × m`) removed:
/// `R (I − Q Qᵀ)`. The basis of a prior-anchored model spans the prior's transfer exactly
/// (its n² coefficient fields, `Q`) and spends the rest of its vectors on what the poses add.
pub struct Deflated<'a, R> {
    rows: &'a R,
    q: &'a DMatrix<f64>,
}

impl<'a, R: RowOperator> Deflated<'a, R> {
    /// `rows` without their part in the span of `q`'s orthonormal columns.
    pub fn new(rows: &'a R, q: &'a DMatrix<f64>) -> Self {
        Self { rows, q }
    }
}

impl<R: RowOperator> RowOperator for Deflated<'_, R> {
    fn nrows(&self) -> usize {
        self.rows.nrows()
    }

    fn ncols(&self) -> usize {
        self.rows.ncols()
    }

    fn mul(&self, x: &DMatrix<f64>) -> DMatrix<f64> {
        self.rows.mul(&(x - self.q * self.q.tr_mul(x)))
    }

    fn tr_mul(&self, y: &DMatrix<f64>) -> DMatrix<f64> {
        let r = self.rows.tr_mul(y);
        &r - self.q * self.q.tr_mul(&r)
    }

    fn frobenius_sq(&self) -> f64 {
        (self.rows.frobenius_sq() - self.rows.mul(self.q).norm_squared()).max(0.0)
    }
}

/// An orthonormal basis of the n² coefficient fields of one pose's transfer (`v × n²`, each
/// column one coefficient over the vertices), cut at its numerical rank.
pub fn field_basis(transfer: &[f32], coefs: usize) -> DMatrix<f64> {
    let v = transfer.len() / coefs.max(1);
    let fields = DMatrix::from_fn(v, coefs, |j, c| f64::from(transfer[j * coefs + c]));
    let svd = fields.svd(true, false);
    let rank = dims::numerical_rank(
        svd.singular_values.as_slice(),
        v,
        coefs,
        f32::EPSILON.into(),
    );
    svd.u
        .expect("SVD computed with U")
        .columns(0, rank)
        .into_owned()
}

/// Basis coordinates of every row, arranged as ridge outputs: `p × (n²·k_v)`, entry
/// `[i][c·k_v + k] = U_kᵀ b_i^c`.
pub fn project_rows(rows: &PoseRows<'_>, basis: &DMatrix<f64>) -> DMatrix<f64> {
    let (p, n2, kv) = (rows.transfers.len(), rows.coefs, basis.ncols());
    let w = rows.mul(basis);
    DMatrix::from_fn(p, n2 * kv, |i, col| w[(i * n2 + col / kv, col % kv)])
}

/// Raw transfer as ridge outputs for the identity basis: `p × (n²·v)`, entry
/// `[i][c·v + j] = t_i[j·n² + c]`.
pub fn raw_rows(rows: &PoseRows<'_>) -> DMatrix<f64> {
    let (p, n2, v) = (rows.transfers.len(), rows.coefs, rows.vertices);
    DMatrix::from_fn(p, n2 * v, |i, col| {
        f64::from(rows.transfers[i][(col % v) * n2 + col / v])
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 21 poses (blocks of 8, 8, 5), 4 coefficients, 7 vertices, distinct values.
    fn sample() -> (Vec<Vec<f32>>, DMatrix<f64>) {
        let (p, n2, v) = (21, 4, 7);
        let transfers: Vec<Vec<f32>> = (0..p)
            .map(|i| {
                (0..v * n2)
                    .map(|idx| (i * 1000 + idx) as f32 * 0.25 - 300.0)
                    .collect()
            })
            .collect();
        // Dense R: row i·n² + c, column j holds t_i[j·n² + c].
        let dense = DMatrix::from_fn(p * n2, v, |r, j| {
            f64::from(transfers[r / n2][j * n2 + r % n2])
        });
        (transfers, dense)
    }

    #[test]
    fn pose_rows_products_match_the_dense_row_matrix() {
        let (transfers, dense) = sample();
        let rows = PoseRows::new(&transfers, 4, 7);
        assert_eq!((rows.nrows(), rows.ncols()), dense.shape());
        let x = DMatrix::from_fn(7, 3, |i, j| (i as f64 - 2.0) * (j as f64 + 0.5));
        let y = DMatrix::from_fn(84, 3, |i, j| ((i * 7 + j) % 11) as f64 - 5.0);
        assert!((rows.mul(&x) - &dense * &x).amax() <= 1e-9);
        assert!((rows.tr_mul(&y) - dense.tr_mul(&y)).amax() <= 1e-9);
        assert!((rows.frobenius_sq() - dense.norm_squared()).abs() <= 1e-12 * dense.norm_squared());
    }

    #[test]
    fn outputs_are_laid_out_coefficient_major() {
        let (transfers, dense) = sample();
        let rows = PoseRows::new(&transfers, 4, 7);
        let raw = raw_rows(&rows);
        assert_eq!(raw.shape(), (21, 28));
        // [i][c·v + j] = t_i[j·n² + c]
        assert_eq!(raw[(3, 2 * 7 + 5)], f64::from(transfers[3][5 * 4 + 2]));
        let basis = DMatrix::<f64>::identity(7, 7).columns(0, 2).into_owned();
        let projected = project_rows(&rows, &basis);
        assert_eq!(projected.shape(), (21, 8));
        // [i][c·k_v + k] = U_kᵀ b_i^c, here the k-th vertex value.
        assert_eq!(projected[(9, 3 * 2 + 1)], dense[(9 * 4 + 3, 1)]);
    }

    #[test]
    fn basis_spans_the_uncentred_rows() {
        // Every row is a multiple of one positive vector: centred PCA would see only the
        // variation of the multiples, the uncentred basis must return that vector itself.
        let shape: Vec<f64> = (0..30)
            .map(|j| 1.0 + (j as f64 * 0.3).sin().abs())
            .collect();
        let transfers: Vec<Vec<f32>> = (0..6)
            .map(|i| {
                (0..30 * 4)
                    .map(|idx| (shape[idx / 4] * (1.0 + 0.1 * (i * 4 + idx % 4) as f64)) as f32)
                    .collect()
            })
            .collect();
        let rows = PoseRows::new(&transfers, 4, 30);
        let fit = fit_vertex_basis(&rows, Dims::Variance(0.999_999));
        assert_eq!(fit.basis.ncols(), 1);
        let u = fit.basis.column(0);
        let s = nalgebra::DVector::from_vec(shape.clone()).normalize();
        assert!(1.0 - u.dot(&s).abs() < 1e-12);
        assert!((fit.energies[0] - fit.total_energy).abs() < 1e-6 * fit.total_energy);
    }
}
