//! The local model's storage: its per-vertex map (each vertex on the entries near it, see
//! [`super::local`]) written in the runtime's layout through a vertex basis, and what that
//! basis's truncation costs, so that it is scored like the shared candidates.

use nalgebra::{DMatrix, DVector};

use super::assemble::beside;
use super::local::LocalFit;
use super::vertex_basis::{Deflated, PoseRows, field_basis, fit_vertex_basis};
use super::{Anchor, Dims};

/// The local model in the runtime's layout: its per-vertex map stored through a vertex basis
/// of k_v vectors (the anchor's n² fields exactly, the rest the leading components of the
/// map itself), with what that truncation costs on the scored and the training poses.
pub(super) struct LocalModel {
    /// `v × k_v`: the anchor's fields, then the map's leading components.
    pub basis: DMatrix<f64>,
    /// Captured energy of the map's components.
    pub energies: Vec<f64>,
    /// `n² × (1 + a) × k_v` in the runtime's layout, the anchor's coordinates as intercept.
    pub weights: Vec<f64>,
    /// Truncation error per transfer value on the scored poses.
    pub outside_scored: f64,
    /// The same pose by pose.
    pub outside_rows: Vec<f64>,
    /// The same on the training poses.
    pub outside_train: f64,
}

impl LocalModel {
    /// Stores `fitted` (anchored at `anchor`) through `kv` basis vectors; `scored` are the
    /// pose sets the candidates are scored on, with what each of their poses weighs.
    pub fn new(
        fitted: &LocalFit,
        anchor: Anchor<'_>,
        n2: usize,
        kv: usize,
        angles: &DMatrix<f64>,
        scored: &[(&DMatrix<f64>, f64)],
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
        // Per pose, ‖Δaᵀ E‖² = Δaᵀ (EᵀE) Δa per transfer value; the mean over a set's poses.
        let outside_rows = |sets: &[(&DMatrix<f64>, f64)]| -> Vec<f64> {
            let values = (vertices * n2).max(1) as f64;
            sets.iter()
                .flat_map(|&(m, weight)| {
                    let d = offsets(m);
                    (0..d.nrows())
                        .map(|i| {
                            let e = (d.row(i) * &missed * d.row(i).transpose())[(0, 0)];
                            weight * e / values
                        })
                        .collect::<Vec<f64>>()
                })
                .collect()
        };
        let outside = |sets: &[(&DMatrix<f64>, f64)]| {
            let rows = outside_rows(sets);
            rows.iter().sum::<f64>() / rows.len().max(1) as f64
        };
        Self {
            outside_scored: outside(scored),
            outside_rows: outside_rows(scored),
            outside_train: outside(&[(angles, 1.0)]),
            basis,
            energies: residual.energies,
            weights,
        }
    }
}
