//! Rotation of SH vectors by exact quadrature.
//!
//! Rotating `f` by `R` gives `f'(ω) = f(Rᵀω)`, so `f'_c = ∫ y_c(ω) f(Rᵀω) dω`. For order n the
//! integrand is a polynomial of degree ≤ 2n − 2 on the sphere, which a product rule of n
//! Gauss–Legendre nodes in cos θ and 2n − 1 uniform nodes in φ integrates exactly: no rotation
//! recurrences and no sign conventions beyond the basis itself: the reference the faster
//! rotations are checked against. [`ShRotationMatrix`] builds the matrix of one rotation by
//! recurrences; the per-bone and per-vertex rotations use [`crate::euler`], which needs only
//! two such matrices.

use crate::math;
use crate::sh::{MAX_COEFFS, MAX_ORDER, ShError, coeff_count, eval_basis};

/// Most quadrature directions: n (2n − 1) at n = [`MAX_ORDER`].
const MAX_NODES: usize = MAX_ORDER * (2 * MAX_ORDER - 1);

/// Precomputed quadrature for one order (about 10 KiB); build once, rotate many times.
#[derive(Clone, Debug)]
pub struct ShRotation {
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
        let mut t = libm::cos(core::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5));
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
            if libm::fabs(step) < 1e-15 {
                break;
            }
        }
        nodes[i] = t;
    }
}

impl ShRotation {
    /// Builds the quadrature for `order` (1..=6).
    pub fn new(order: usize) -> Result<ShRotation, ShError> {
        if order == 0 || order > MAX_ORDER {
            return Err(ShError::BadOrder);
        }
        let mut r = ShRotation {
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
            let s = libm::sqrt((1.0 - t[a] * t[a]).max(0.0));
            for b in 0..n_phi {
                let i = a * n_phi + b;
                let phi = 2.0 * core::f64::consts::PI * (b as f64 + 0.5) / n_phi as f64;
                r.dirs[i] = [
                    (s * libm::cos(phi)) as f32,
                    (s * libm::sin(phi)) as f32,
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

/// The angle-preserving part is all a rotation needs; this guards callers that pass a
/// blended (non-orthogonal) matrix by checking its columns are unit and orthogonal to `tol`.
pub fn is_rotation(r: &[[f32; 3]; 3], tol: f32) -> bool {
    let col = |j: usize| [r[0][j], r[1][j], r[2][j]];
    let dot = |a: [f32; 3], b: [f32; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    (0..3).all(|i| {
        (0..3).all(|j| math::abs(dot(col(i), col(j)) - if i == j { 1.0 } else { 0.0 }) <= tol)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sh::project_directional;

    fn axis_angle(axis: [f32; 3], angle: f32) -> [[f32; 3]; 3] {
        let n = math::sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
        let [x, y, z] = [axis[0] / n, axis[1] / n, axis[2] / n];
        let (s, c) = (math::sin(angle), math::cos(angle));
        let t = 1.0 - c;
        [
            [t * x * x + c, t * x * y - s * z, t * x * z + s * y],
            [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
            [t * x * z - s * y, t * y * z + s * x, t * z * z + c],
        ]
    }

    fn apply(r: &[[f32; 3]; 3], d: [f32; 3]) -> [f32; 3] {
        core::array::from_fn(|i| r[i][0] * d[0] + r[i][1] * d[1] + r[i][2] * d[2])
    }

    #[test]
    fn gauss_legendre_integrates_polynomials_exactly() {
        for n in 1..=MAX_ORDER {
            let (mut x, mut w) = ([0.0f64; MAX_ORDER], [0.0f64; MAX_ORDER]);
            gauss_legendre(n, &mut x, &mut w);
            for degree in 0..2 * n {
                let integral: f64 = (0..n).map(|i| w[i] * libm::pow(x[i], degree as f64)).sum();
                let expect = if degree % 2 == 1 {
                    0.0
                } else {
                    2.0 / (degree as f64 + 1.0)
                };
                assert!(
                    libm::fabs(integral - expect) < 1e-13,
                    "n {n}, degree {degree}: {integral}"
                );
            }
        }
    }

    /// Rotating the projection of a direction gives the projection of the rotated direction,
    /// `rotate(y(d)) = y(R d)`: an identity independent of the quadrature.
    #[test]
    fn rotation_moves_a_projected_direction() {
        let r = axis_angle([0.3, -0.5, 0.8], 1.1);
        assert!(is_rotation(&r, 1e-6));
        for order in 1..=MAX_ORDER {
            let rot = ShRotation::new(order).unwrap();
            for d in [[0.0, 0.0, 1.0], [0.2, 0.9, -0.3], [-1.0, 0.0, 0.0]] {
                let (mut src, mut expect, mut got) = ([0.0f32; 36], [0.0f32; 36], [0.0f32; 36]);
                project_directional(order, d, 1.0, &mut src).unwrap();
                project_directional(order, apply(&r, d), 1.0, &mut expect).unwrap();
                rot.rotate(&r, &src, &mut got).unwrap();
                for c in 0..order * order {
                    assert!(
                        math::abs(got[c] - expect[c]) < 2e-5,
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
        assert!(ShRotation::new(0).is_err() && ShRotation::new(7).is_err());
        let rot = ShRotation::new(3).unwrap();
        let id = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        assert_eq!(
            rot.rotate(&id, &[0.0; 8], &mut [0.0; 9]),
            Err(ShError::OutputTooSmall)
        );
    }
}

/// Block-diagonal SH rotation matrix for one rotation, built by the Ivanic–Ruedenberg
/// recurrences (J. Phys. Chem. 1996, with the 1998 errata) from the 3×3 matrix: O(n³) work
/// instead of O(n³)·quadrature nodes. Checked against the exact quadrature [`ShRotation`] in
/// the tests.
#[derive(Clone, Debug)]
pub struct ShRotationMatrix {
    order: usize,
    /// Band `l` occupies `blocks[offset(l)..][..(2l+1)²]`, row-major, rows and columns
    /// indexed by `m + l`.
    blocks: [f32; BLOCK_LEN],
}

/// Σ_{l<6} (2l + 1)² entries.
const BLOCK_LEN: usize = 1 + 9 + 25 + 49 + 81 + 121;

/// `sqrt` for compile-time tables (Newton's method; `f64::sqrt` is not `const`).
const fn const_sqrt(x: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    let mut g = if x > 1.0 { x } else { 1.0 };
    let mut i = 0;
    while i < 64 {
        g = 0.5 * (g + x / g);
        i += 1;
    }
    g
}

/// The recurrence's `(u, v, w)` coefficients for every `(l, m, n)`, laid out like the blocks:
/// they depend only on the indices, so they are computed at compile time and the per-rotation
/// work is multiply-adds only.
const UVW: [[f32; 3]; BLOCK_LEN] = {
    let mut t = [[0.0f32; 3]; BLOCK_LEN];
    let mut l = 2i32;
    while l < MAX_ORDER as i32 {
        let mut m = -l;
        while m <= l {
            let mut n = -l;
            while n <= l {
                let d = if m == 0 { 1.0 } else { 0.0 };
                let denom = if n == l || n == -l {
                    (2 * l * (2 * l - 1)) as f64
                } else {
                    ((l + n) * (l - n)) as f64
                };
                let am = if m < 0 { -m } else { m };
                let u = const_sqrt(((l + m) * (l - m)) as f64 / denom);
                let v = 0.5
                    * const_sqrt((1.0 + d) * ((l + am - 1) * (l + am)) as f64 / denom)
                    * (1.0 - 2.0 * d);
                let w = -0.5 * const_sqrt(((l - am - 1) * (l - am)) as f64 / denom) * (1.0 - d);
                let i = block_offset(l as usize) + ((m + l) * (2 * l + 1) + (n + l)) as usize;
                t[i] = [u as f32, v as f32, w as f32];
                n += 1;
            }
            m += 1;
        }
        l += 1;
    }
    t
};

const fn block_offset(l: usize) -> usize {
    // Σ_{k<l} (2k+1)² = l(2l−1)(2l+1)/3
    if l == 0 {
        0
    } else {
        l * (2 * l - 1) * (2 * l + 1) / 3
    }
}

impl ShRotationMatrix {
    /// The rotation taking `f(ω)` to `f(rᵀω)` (as [`ShRotation::rotate`]) for `order` ≤ 6;
    /// `r` is row-major. A `const fn` (plain `while` loops), so fixed rotations can be
    /// tables built at compile time.
    pub const fn new(order: usize, r: &[[f32; 3]; 3]) -> Result<ShRotationMatrix, ShError> {
        if order == 0 || order > MAX_ORDER {
            return Err(ShError::BadOrder);
        }
        let mut m = ShRotationMatrix {
            order,
            blocks: [0.0; BLOCK_LEN],
        };
        m.blocks[0] = 1.0;
        // Band 1 in the basis order (y, z, x) of m = −1, 0, 1.
        let axis = [1usize, 2, 0];
        let mut i = 0;
        while order > 1 && i < 9 {
            m.blocks[block_offset(1) + i] = r[axis[i / 3]][axis[i % 3]];
            i += 1;
        }
        let mut l = 2;
        while l < order {
            let (li, w) = (l as i32, 2 * l + 1);
            let mut k = 0;
            while k < w * w {
                let (mm, n) = ((k / w) as i32 - li, (k % w) as i32 - li);
                m.blocks[block_offset(l) + k] = m.recurrence(li, mm, n);
                k += 1;
            }
            l += 1;
        }
        Ok(m)
    }

    /// Entry `(a, b)` of band `l`, both in `−l..=l`.
    pub(crate) const fn get(&self, l: i32, a: i32, b: i32) -> f32 {
        let w = (2 * l + 1) as usize;
        self.blocks[block_offset(l as usize) + (a + l) as usize * w + (b + l) as usize]
    }

    /// The `P` term of the recurrence: band-1 row `i` times band `l − 1`.
    const fn p(&self, i: i32, a: i32, b: i32, l: i32) -> f32 {
        if b == l {
            self.get(1, i, 1) * self.get(l - 1, a, l - 1)
                - self.get(1, i, -1) * self.get(l - 1, a, -l + 1)
        } else if b == -l {
            self.get(1, i, 1) * self.get(l - 1, a, -l + 1)
                + self.get(1, i, -1) * self.get(l - 1, a, l - 1)
        } else {
            self.get(1, i, 0) * self.get(l - 1, a, b)
        }
    }

    const fn recurrence(&self, l: i32, m: i32, n: i32) -> f32 {
        let [u, v, w] = UVW[block_offset(l as usize) + ((m + l) * (2 * l + 1) + (n + l)) as usize];
        let big_u = if u != 0.0 { self.p(0, m, n, l) } else { 0.0 };
        let big_v = if v == 0.0 {
            0.0
        } else if m == 0 {
            self.p(1, 1, n, l) + self.p(-1, -1, n, l)
        } else if m > 0 {
            let (k, keep) = if m == 1 {
                (core::f32::consts::SQRT_2, 0.0)
            } else {
                (1.0, 1.0)
            };
            self.p(1, m - 1, n, l) * k - self.p(-1, -m + 1, n, l) * keep
        } else {
            let (k, keep) = if m == -1 {
                (core::f32::consts::SQRT_2, 0.0)
            } else {
                (1.0, 1.0)
            };
            self.p(1, m + 1, n, l) * keep + self.p(-1, -m - 1, n, l) * k
        };
        let big_w = if w == 0.0 {
            0.0
        } else if m > 0 {
            self.p(1, m + 1, n, l) + self.p(-1, -m - 1, n, l)
        } else {
            self.p(1, m - 1, n, l) - self.p(-1, -m + 1, n, l)
        };
        u * big_u + v * big_v + w * big_w
    }

    /// Writes `input` rotated to `output` (both at least `order²` values).
    pub fn apply(&self, input: &[f32], output: &mut [f32]) -> Result<(), ShError> {
        let n2 = coeff_count(self.order);
        if input.len() < n2 || output.len() < n2 {
            return Err(ShError::OutputTooSmall);
        }
        for l in 0..self.order {
            let (w, base) = (2 * l + 1, l * l);
            let block = &self.blocks[block_offset(l)..][..w * w];
            for (i, row) in block.chunks_exact(w).enumerate() {
                output[base + i] = row
                    .iter()
                    .zip(&input[base..base + w])
                    .map(|(a, b)| a * b)
                    .sum();
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod recurrence_tests {
    use super::*;

    /// The recurrence agrees with the exact quadrature for every order and several rotations.
    #[test]
    fn matches_quadrature_rotation() {
        let rotations: [[[f32; 3]; 3]; 3] = [
            [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            {
                let (s, c) = (math::sin(0.7), math::cos(0.7));
                [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
            },
            [[0.36, 0.48, -0.8], [-0.8, 0.6, 0.0], [0.48, 0.64, 0.6]],
        ];
        let input: [f32; 36] = core::array::from_fn(|i| math::sin(i as f32 * 1.3 + 0.2));
        for order in 1..=MAX_ORDER {
            let exact = ShRotation::new(order).unwrap();
            for r in &rotations {
                let (mut a, mut b) = ([0.0f32; 36], [0.0f32; 36]);
                exact.rotate(r, &input, &mut a).unwrap();
                ShRotationMatrix::new(order, r)
                    .unwrap()
                    .apply(&input, &mut b)
                    .unwrap();
                for c in 0..order * order {
                    assert!(
                        math::abs(a[c] - b[c]) < 1e-4,
                        "order {order}, c {c}: {} vs {}",
                        a[c],
                        b[c]
                    );
                }
            }
        }
    }
}
