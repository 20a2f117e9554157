//! The SH rotation matrix of one rotation by the Ivanic–Ruedenberg recurrences. It is built
//! at compile time for the two quarter turns about x that [`ShRotation`](super::ShRotation)
//! composes every rotation from.

use crate::math;
#[cfg(test)]
use crate::sh::coeff_count;
use crate::sh::{MAX_ORDER, ShError};

/// Block-diagonal SH rotation matrix for one rotation, built by the Ivanic–Ruedenberg
/// recurrences (J. Phys. Chem. 1996, with the 1998 errata) from the 3×3 matrix: O(n³) work.
#[derive(Clone, Debug)]
pub(crate) struct ShRotationMatrix {
    #[cfg_attr(not(test), allow(dead_code))]
    order: usize,
    /// Band `l` occupies `blocks[offset(l)..][..(2l+1)²]`, row-major, rows and columns
    /// indexed by `m + l`.
    blocks: [f32; BLOCK_LEN],
}

/// Σ_{l<6} (2l + 1)² entries.
const BLOCK_LEN: usize = 1 + 9 + 25 + 49 + 81 + 121;

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
                let u = math::const_sqrt(((l + m) * (l - m)) as f64 / denom);
                let v = 0.5
                    * math::const_sqrt((1.0 + d) * ((l + am - 1) * (l + am)) as f64 / denom)
                    * (1.0 - 2.0 * d);
                let w =
                    -0.5 * math::const_sqrt(((l - am - 1) * (l - am)) as f64 / denom) * (1.0 - d);
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
    /// The rotation taking `f(ω)` to `f(rᵀω)` (as [`ShRotation::apply`](super::ShRotation::apply))
    /// for `order` ≤ 6; `r` is row-major. A `const fn` (plain `while` loops), so fixed
    /// rotations can be tables built at compile time.
    pub(crate) const fn new(order: usize, r: &[[f32; 3]; 3]) -> Result<ShRotationMatrix, ShError> {
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
    #[cfg(test)]
    pub(crate) fn apply(&self, input: &[f32], output: &mut [f32]) -> Result<(), ShError> {
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
mod tests {
    use super::*;
    use crate::sh::{MAX_COEFFS, project_directional};

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

    fn times(r: &[[f32; 3]; 3], d: [f32; 3]) -> [f32; 3] {
        core::array::from_fn(|i| r[i][0] * d[0] + r[i][1] * d[1] + r[i][2] * d[2])
    }

    /// Rotating the projection of a direction gives the projection of the rotated direction,
    /// `M(R) y(d) = y(R d)`: an identity of the basis alone. Holding for 48 directions, more
    /// than the 2l + 1 that span each band, it pins every entry of the matrix.
    #[test]
    fn rotates_the_projection_of_every_direction_like_the_direction() {
        let rotations = [
            [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            axis_angle([0.0, 0.0, 1.0], 0.7),
            [[0.36, 0.48, -0.8], [-0.8, 0.6, 0.0], [0.48, 0.64, 0.6]],
            axis_angle([0.3, -0.5, 0.8], 1.1),
            axis_angle([1.0, 0.0, 0.0], core::f32::consts::PI),
        ];
        // A spiral of directions over the whole sphere, poles included.
        let directions: [[f32; 3]; 48] = core::array::from_fn(|i| {
            let z = 1.0 - 2.0 * i as f32 / 47.0;
            let s = math::sqrt((1.0 - z * z).max(0.0));
            let phi = 2.399_963 * i as f32;
            [s * math::cos(phi), s * math::sin(phi), z]
        });
        for order in 1..=MAX_ORDER {
            for r in &rotations {
                let m = ShRotationMatrix::new(order, r).unwrap();
                for d in directions {
                    let (mut y, mut want, mut got) =
                        ([0.0f32; MAX_COEFFS], [0.0; MAX_COEFFS], [0.0; MAX_COEFFS]);
                    project_directional(order, d, 1.0, &mut y).unwrap();
                    project_directional(order, times(r, d), 1.0, &mut want).unwrap();
                    m.apply(&y, &mut got).unwrap();
                    for c in 0..coeff_count(order) {
                        assert!(
                            math::abs(got[c] - want[c]) < 2e-5,
                            "order {order}, {r:?}, {d:?}, c {c}: {} vs {}",
                            got[c],
                            want[c]
                        );
                    }
                }
            }
        }
    }

    /// A rotation mixes coefficients only within a band and is orthogonal there, so each
    /// band's energy `Σ_m x_lm²` is unchanged.
    #[test]
    fn preserves_each_bands_energy() {
        let x: [f32; MAX_COEFFS] = core::array::from_fn(|i| math::sin(i as f32 * 1.3 + 0.2));
        for k in 0..50 {
            let f = k as f32;
            let r = axis_angle(
                [
                    math::sin(f * 0.71),
                    math::cos(f * 1.37),
                    math::sin(f * 2.11) + 0.1,
                ],
                0.3 + f * 0.12,
            );
            let mut y = [0.0f32; MAX_COEFFS];
            ShRotationMatrix::new(MAX_ORDER, &r)
                .unwrap()
                .apply(&x, &mut y)
                .unwrap();
            for l in 0..MAX_ORDER {
                let band = |v: &[f32]| {
                    v[l * l..(l + 1) * (l + 1)]
                        .iter()
                        .map(|a| a * a)
                        .sum::<f32>()
                };
                assert!(
                    math::abs(band(&x) - band(&y)) < 1e-4 * band(&x).max(1.0),
                    "rotation {k}, band {l}"
                );
            }
        }
    }

    #[test]
    fn refuses_bad_orders_and_short_slices() {
        let id = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        assert!(ShRotationMatrix::new(0, &id).is_err() && ShRotationMatrix::new(7, &id).is_err());
        let m = ShRotationMatrix::new(3, &id).unwrap();
        assert_eq!(
            m.apply(&[0.0; 8], &mut [0.0; 9]),
            Err(ShError::OutputTooSmall)
        );
        assert_eq!(
            m.apply(&[0.0; 9], &mut [0.0; 8]),
            Err(ShError::OutputTooSmall)
        );
    }
}
