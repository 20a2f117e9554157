//! Rotation of SH vectors by exact quadrature: the independent reference the core's rotations
//! are checked against.
//!
//! Rotating `f` by `R` gives `f'(ω) = f(Rᵀω)`, so `f'_c = ∫ y_c(ω) f(Rᵀω) dω`. For order n the
//! integrand is a polynomial of degree ≤ 2n − 2 on the sphere, which a product rule of n
//! Gauss–Legendre nodes in cos θ and 2n − 1 uniform nodes in φ integrates exactly: no rotation
//! recurrences and no sign conventions beyond the basis itself. The core rotates by Euler
//! angles ([`aprt_core::ShRotation`]), built from two Ivanic–Ruedenberg matrices.

use aprt_core::{MAX_COEFFS, MAX_ORDER, ShError, coeff_count, eval_basis};

/// Most quadrature directions: n (2n − 1) at n = [`MAX_ORDER`].
const MAX_NODES: usize = MAX_ORDER * (2 * MAX_ORDER - 1);

/// Precomputed quadrature for one order (about 10 KiB); build once, rotate many times.
#[derive(Clone, Debug)]
pub struct QuadratureRotation {
    order: usize,
    nodes: usize,
    dirs: [[f32; 3]; MAX_NODES],
    /// `w_i y_c(ω_i)` at `[i * MAX_COEFFS + c]`.
    weighted: [f32; MAX_NODES * MAX_COEFFS],
}

/// Nodes and weights of the n-point Gauss–Legendre rule on [−1, 1] (into the first n slots of
/// `nodes` and `weights`), by
/// Newton's method on the Legendre recurrence, in f64.
pub fn gauss_legendre(n: usize, nodes: &mut [f64], weights: &mut [f64]) {
    for i in 0..n.min(nodes.len()).min(weights.len()) {
        let mut t = f64::cos(core::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5));
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0f64, t);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * t * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            let (p, dp) = if n == 1 {
                (t, 1.0)
            } else {
                (p1, n as f64 * (t * p1 - p0) / (t * t - 1.0))
            };
            let step = p / dp;
            t -= step;
            weights[i] = 2.0 / ((1.0 - t * t) * dp * dp);
            if f64::abs(step) < 1e-15 {
                break;
            }
        }
        nodes[i] = t;
    }
}

impl QuadratureRotation {
    /// Builds the quadrature for `order` (1..=6).
    pub fn new(order: usize) -> Result<QuadratureRotation, ShError> {
        if order == 0 || order > MAX_ORDER {
            return Err(ShError::BadOrder);
        }
        let mut r = QuadratureRotation {
            order,
            nodes: order * (2 * order - 1),
            dirs: [[0.0; 3]; MAX_NODES],
            weighted: [0.0; MAX_NODES * MAX_COEFFS],
        };
        let (mut t, mut w) = ([0.0f64; MAX_ORDER], [0.0f64; MAX_ORDER]);
        gauss_legendre(order, &mut t, &mut w);
        let n_phi = 2 * order - 1;
        let mut y = [0.0f32; MAX_COEFFS];
        for a in 0..order {
            let s = f64::sqrt((1.0 - t[a] * t[a]).max(0.0));
            for b in 0..n_phi {
                let i = a * n_phi + b;
                let phi = 2.0 * core::f64::consts::PI * (b as f64 + 0.5) / n_phi as f64;
                r.dirs[i] = [
                    (s * f64::cos(phi)) as f32,
                    (s * f64::sin(phi)) as f32,
                    t[a] as f32,
                ];
                eval_basis(order, r.dirs[i], &mut y)?;
                let dw = (w[a] * 2.0 * core::f64::consts::PI / n_phi as f64) as f32;
                for (o, yc) in r.weighted[i * MAX_COEFFS..][..coeff_count(order)]
                    .iter_mut()
                    .zip(&y)
                {
                    *o = dw * yc;
                }
            }
        }
        Ok(r)
    }

    /// The order this quadrature rotates.
    pub fn order(&self) -> usize {
        self.order
    }

    /// Writes `input` rotated by the rotation matrix `r` (row-major, `r[row][col]`) to
    /// `output`: `output(ω) = input(rᵀω)`. Both slices hold at least `order²` values.
    pub fn rotate(
        &self,
        r: &[[f32; 3]; 3],
        input: &[f32],
        output: &mut [f32],
    ) -> Result<(), ShError> {
        let n2 = coeff_count(self.order);
        if input.len() < n2 || output.len() < n2 {
            return Err(ShError::OutputTooSmall);
        }
        let mut acc = [0.0f32; MAX_COEFFS];
        let mut y = [0.0f32; MAX_COEFFS];
        for (d, w) in self.dirs[..self.nodes]
            .iter()
            .zip(self.weighted.chunks_exact(MAX_COEFFS))
        {
            // rᵀ d: column j of r dotted with d.
            let rd = core::array::from_fn(|j| r[0][j] * d[0] + r[1][j] * d[1] + r[2][j] * d[2]);
            eval_basis(self.order, rd, &mut y)?;
            let value: f32 = input[..n2].iter().zip(&y).map(|(a, b)| a * b).sum();
            for (a, wc) in acc[..n2].iter_mut().zip(w) {
                *a += value * wc;
            }
        }
        output[..n2].copy_from_slice(&acc[..n2]);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use aprt_core::project_directional;

    #[test]
    fn gauss_legendre_integrates_polynomials_exactly() {
        for n in 1..=MAX_ORDER {
            let (mut x, mut w) = ([0.0f64; MAX_ORDER], [0.0f64; MAX_ORDER]);
            gauss_legendre(n, &mut x, &mut w);
            for degree in 0..2 * n {
                let integral: f64 = (0..n).map(|i| w[i] * f64::powf(x[i], degree as f64)).sum();
                let expect = if degree % 2 == 1 {
                    0.0
                } else {
                    2.0 / (degree as f64 + 1.0)
                };
                assert!(
                    f64::abs(integral - expect) < 1e-13,
                    "n {n}, degree {degree}: {integral}"
                );
            }
        }
    }

    /// Rotating the projection of a direction gives the projection of the rotated direction,
    /// `rotate(y(d)) = y(R d)`: an identity independent of the quadrature.
    #[test]
    fn rotation_moves_a_projected_direction() {
        // A generic rotation (rows orthonormal, determinant 1).
        let r = [[0.36, 0.48, -0.8], [-0.8, 0.6, 0.0], [0.48, 0.64, 0.6]];
        let times =
            |d: [f32; 3]| std::array::from_fn(|i| r[i][0] * d[0] + r[i][1] * d[1] + r[i][2] * d[2]);
        for order in 1..=MAX_ORDER {
            let rot = QuadratureRotation::new(order).unwrap();
            for d in [[0.0, 0.0, 1.0], [0.2, 0.9, -0.3], [-1.0, 0.0, 0.0]] {
                let (mut src, mut expect, mut got) = ([0.0f32; 36], [0.0f32; 36], [0.0f32; 36]);
                project_directional(order, d, 1.0, &mut src).unwrap();
                project_directional(order, times(d), 1.0, &mut expect).unwrap();
                rot.rotate(&r, &src, &mut got).unwrap();
                for c in 0..order * order {
                    assert!(
                        f32::abs(got[c] - expect[c]) < 2e-5,
                        "order {order}, c {c}: {} vs {}",
                        got[c],
                        expect[c]
                    );
                }
            }
        }
    }

    #[test]
    fn rejects_bad_order_and_short_slices() {
        assert!(QuadratureRotation::new(0).is_err() && QuadratureRotation::new(7).is_err());
        let rot = QuadratureRotation::new(3).unwrap();
        let id = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        assert_eq!(
            rot.rotate(&id, &[0.0; 8], &mut [0.0; 9]),
            Err(ShError::OutputTooSmall)
        );
    }

    /// Orthonormality by a product Gauss–Legendre (θ) × uniform (φ) quadrature, exact for
    /// band-limited integrands of this degree.
    #[test]
    fn orthonormal_by_quadrature() {
        const NT: usize = 24;
        const NP: usize = 48;
        let (mut nodes, mut weights) = ([0.0f64; NT], [0.0f64; NT]);
        gauss_legendre(NT, &mut nodes, &mut weights);
        let mut gram = [[0.0f64; MAX_COEFFS]; MAX_COEFFS];
        let mut y = [0.0f32; MAX_COEFFS];
        for (t, w) in nodes.iter().zip(weights) {
            for j in 0..NP {
                let phi = 2.0 * std::f64::consts::PI * j as f64 / NP as f64;
                let s = (1.0 - t * t).sqrt();
                eval_basis(
                    MAX_ORDER,
                    [(s * phi.cos()) as f32, (s * phi.sin()) as f32, *t as f32],
                    &mut y,
                )
                .unwrap();
                let dw = w * 2.0 * std::f64::consts::PI / NP as f64;
                for (row, ya) in gram.iter_mut().zip(&y) {
                    for (g, yb) in row.iter_mut().zip(&y) {
                        *g += dw * *ya as f64 * *yb as f64;
                    }
                }
            }
        }
        for (a, row) in gram.iter().enumerate() {
            for (b, g) in row.iter().enumerate() {
                let expect = if a == b { 1.0 } else { 0.0 };
                assert!((g - expect).abs() < 2e-5, "<y{a}, y{b}> = {g}");
            }
        }
    }

    /// The core's Euler-angle rotation agrees with the exact quadrature for every order and
    /// several rotations (the identity, a turn about z, and a generic one).
    #[test]
    fn the_cores_rotation_matches_the_quadrature() {
        let rotations: [[[f32; 3]; 3]; 3] = [
            [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            {
                let (s, c) = 0.7f32.sin_cos();
                [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
            },
            [[0.36, 0.48, -0.8], [-0.8, 0.6, 0.0], [0.48, 0.64, 0.6]],
        ];
        let input: [f32; 36] = std::array::from_fn(|i| (i as f32 * 1.3 + 0.2).sin());
        for order in 1..=MAX_ORDER {
            let exact = QuadratureRotation::new(order).unwrap();
            for r in &rotations {
                let mut a = [0.0f32; 36];
                exact.rotate(r, &input, &mut a).unwrap();
                let mut b = input;
                let r64 = r.map(|row| row.map(f64::from));
                aprt_core::ShRotation::new(order)
                    .unwrap()
                    .apply(&r64, &mut b)
                    .unwrap();
                for c in 0..order * order {
                    assert!(
                        (a[c] - b[c]).abs() < 1e-4,
                        "order {order}, c {c}: {} vs {}",
                        a[c],
                        b[c]
                    );
                }
            }
        }
    }
}
