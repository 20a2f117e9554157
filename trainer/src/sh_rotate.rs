//! Rotation of SH vectors by exact quadrature, for the skinning baseline (transfer baked in
//! the bind pose, rotated with each vertex's skinning rotation).
//!
//! Rotating `t` by `R` gives `t'(ω) = t(Rᵀω)`, so `t'_c = ∫ y_c(ω) t(Rᵀω) dω`. For order n the
//! integrand is a polynomial of degree ≤ 2n − 2 on the sphere, which a product rule of n
//! Gauss–Legendre nodes in cos θ and 2n − 1 uniform nodes in φ integrates exactly: no
//! rotation recurrences, no sign conventions beyond the basis itself.

use aprt_core::sh::{MAX_COEFFS, coeff_count, eval_basis};
use glam::{DMat3, DVec3};

/// Precomputed quadrature for one SH order.
#[derive(Clone, Debug)]
pub struct ShRotator {
    order: usize,
    /// Quadrature directions.
    dirs: Vec<DVec3>,
    /// Quadrature weight times basis: `weighted[i * n² + c] = w_i y_c(ω_i)`.
    weighted: Vec<f64>,
}

/// Nodes and weights of the n-point Gauss–Legendre rule on [−1, 1], by Newton's method on
/// the Legendre recurrence.
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    let (mut nodes, mut weights) = (vec![0.0; n], vec![0.0; n]);
    for i in 0..n {
        let mut t = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
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
            if step.abs() < 1e-15 {
                break;
            }
        }
        nodes[i] = t;
    }
    (nodes, weights)
}

impl ShRotator {
    /// Builds the quadrature for `order` (1..=6).
    pub fn new(order: usize) -> ShRotator {
        let n2 = coeff_count(order);
        let (nodes, gl_weights) = gauss_legendre(order);
        let n_phi = 2 * order - 1;
        let mut dirs = Vec::new();
        let mut weighted = Vec::new();
        let mut y = [0.0f32; MAX_COEFFS];
        for (t, w) in nodes.iter().zip(&gl_weights) {
            let s = (1.0 - t * t).sqrt();
            for j in 0..n_phi {
                let phi = 2.0 * std::f64::consts::PI * (j as f64 + 0.5) / n_phi as f64;
                let d = DVec3::new(s * phi.cos(), s * phi.sin(), *t);
                eval_basis(order, d.as_vec3().to_array(), &mut y)
                    .expect("unit direction, valid order");
                let dw = w * 2.0 * std::f64::consts::PI / n_phi as f64;
                weighted.extend(y[..n2].iter().map(|&yc| dw * yc as f64));
                dirs.push(d);
            }
        }
        ShRotator {
            order,
            dirs,
            weighted,
        }
    }

    /// Writes `t` rotated by `r` (a rotation matrix) to `out`: `out(ω) = t(rᵀω)`.
    pub fn rotate(&self, r: DMat3, t: &[f32], out: &mut [f32]) {
        let n2 = coeff_count(self.order);
        let mut y = [0.0f32; MAX_COEFFS];
        let mut acc = [0.0f64; MAX_COEFFS];
        let rt = r.transpose();
        for (d, w) in self.dirs.iter().zip(self.weighted.chunks_exact(n2)) {
            eval_basis(self.order, (rt * *d).as_vec3().to_array(), &mut y)
                .expect("unit direction, valid order");
            let value: f64 = t[..n2]
                .iter()
                .zip(&y)
                .map(|(a, b)| *a as f64 * *b as f64)
                .sum();
            for (a, wc) in acc.iter_mut().zip(w) {
                *a += value * wc;
            }
        }
        for (o, a) in out[..n2].iter_mut().zip(acc) {
            *o = a as f32;
        }
    }
}

/// The rotation nearest to `m` (polar decomposition by Newton iteration `Q ← (Q + Q⁻ᵀ)/2`),
/// for the blended, slightly non-orthogonal matrices of linear blend skinning.
pub fn nearest_rotation(m: DMat3) -> DMat3 {
    let mut q = m;
    for _ in 0..20 {
        let det = q.determinant();
        if !det.is_finite() || det.abs() < 1e-12 {
            return DMat3::IDENTITY;
        }
        let next = (q + q.inverse().transpose()) * 0.5;
        let change = (next - q)
            .to_cols_array()
            .iter()
            .map(|x| x.abs())
            .fold(0.0, f64::max);
        q = next;
        if change < 1e-12 {
            break;
        }
    }
    q
}

#[cfg(test)]
mod tests {
    use super::*;
    use aprt_core::sh::project_directional;

    #[test]
    fn gauss_legendre_integrates_polynomials_exactly() {
        for n in 1..=8 {
            let (x, w) = gauss_legendre(n);
            for degree in 0..2 * n {
                let integral: f64 = x
                    .iter()
                    .zip(&w)
                    .map(|(x, w)| w * x.powi(degree as i32))
                    .sum();
                let expect = if degree % 2 == 1 {
                    0.0
                } else {
                    2.0 / (degree as f64 + 1.0)
                };
                assert!(
                    (integral - expect).abs() < 1e-13,
                    "n {n}, degree {degree}: {integral}"
                );
            }
        }
    }

    /// Rotating the projection of a direction must give the projection of the rotated
    /// direction: `rotate(y(d)) = y(R d)`, an identity independent of the quadrature.
    #[test]
    fn rotation_moves_a_projected_direction() {
        let r = DMat3::from_axis_angle(DVec3::new(0.3, -0.5, 0.8).normalize(), 1.1)
            * DMat3::from_axis_angle(DVec3::X, -0.4);
        for order in 1..=6 {
            let rot = ShRotator::new(order);
            for d in [DVec3::Z, DVec3::new(0.2, 0.9, -0.3).normalize(), -DVec3::X] {
                let mut src = [0.0f32; 36];
                let mut expect = [0.0f32; 36];
                let mut got = [0.0f32; 36];
                project_directional(order, d.as_vec3().to_array(), 1.0, &mut src).unwrap();
                project_directional(order, (r * d).as_vec3().to_array(), 1.0, &mut expect).unwrap();
                rot.rotate(r, &src, &mut got);
                for c in 0..order * order {
                    assert!(
                        (got[c] - expect[c]).abs() < 2e-5,
                        "order {order}, c {c}: {} vs {}",
                        got[c],
                        expect[c]
                    );
                }
            }
        }
    }

    #[test]
    fn nearest_rotation_recovers_a_rotation_from_a_blend() {
        let a = DMat3::from_axis_angle(DVec3::Y, 0.3);
        let b = DMat3::from_axis_angle(DVec3::Y, 0.7);
        let q = nearest_rotation(a * 0.5 + b * 0.5);
        let expect = DMat3::from_axis_angle(DVec3::Y, 0.5);
        assert!((q - expect).to_cols_array().iter().all(|x| x.abs() < 1e-9));
        assert_eq!(nearest_rotation(DMat3::ZERO), DMat3::IDENTITY);
    }
}
