//! Rotating SH vectors cheaply: `R = Rz(α) Ry(β) Rz(γ)` (ZYZ Euler angles) with
//! `Ry(β) = Rx(−90°) Rz(β) Rx(90°)`. A rotation about z turns each `(cos mφ, sin mφ)`
//! coefficient pair by `mθ` (O(n²)), and the two quarter turns about x are fixed
//! [`ShRotationMatrix`]es computed at compile time and split into parity blocks, so a rotation
//! costs two sparse block products and three plane rotations instead of building its own
//! Ivanic–Ruedenberg matrix (about 65k instructions at order 6), and no set-up. Used for the
//! bake's per-vertex frames and the runtime's per-bone lighting.

mod recurrence;

use crate::math;
use crate::sh::{MAX_COEFFS, MAX_ORDER, ShError, coeff_count, index};
use recurrence::ShRotationMatrix;

/// A 3×3 rotation matrix, row-major (`r[row][column]`): `r · v` rotates the column vector `v`.
pub type Rotation = [[f32; 3]; 3];

/// The rotation that turns nothing.
pub(crate) const IDENTITY: Rotation = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// Whether `r` is a proper rotation within `tol`: its columns unit and orthogonal, and its
/// determinant positive. Guards callers that pass a blended (non-orthogonal) skinning matrix
/// or a mirrored one (determinant −1), whose SH rotation is not the one built here.
pub(crate) fn is_rotation(r: &Rotation, tol: f32) -> bool {
    let col = |j: usize| [r[0][j], r[1][j], r[2][j]];
    let dot = |a: [f32; 3], b: [f32; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let orthonormal = (0..3).all(|i| {
        (0..3).all(|j| math::abs(dot(col(i), col(j)) - if i == j { 1.0 } else { 0.0 }) <= tol)
    });
    let [a, b, c] = [col(0), col(1), col(2)];
    let cross = [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ];
    orthonormal && dot(cross, c) > 0.0
}

/// `D(Rx(90°))` for every band, built at compile time.
static QUARTER: ParityBlocks = ParityBlocks::of(&quarter_turn(1.0));
/// `D(Rx(−90°))`.
static QUARTER_BACK: ParityBlocks = ParityBlocks::of(&quarter_turn(-1.0));

/// The SH rotation of a quarter turn about x, `sign` giving its direction.
const fn quarter_turn(sign: f32) -> ShRotationMatrix {
    match ShRotationMatrix::new(
        MAX_ORDER,
        &[[1.0, 0.0, 0.0], [0.0, 0.0, -sign], [0.0, sign, 0.0]],
    ) {
        Ok(m) => m,
        Err(_) => panic!("MAX_ORDER is a valid order"),
    }
}

/// Widest band, `2·MAX_ORDER − 1` coefficients.
const MAX_BAND: usize = 2 * MAX_ORDER - 1;

/// Parity of the real SH `Y_lm` under the reflection `x → −x` (`φ → π − φ`): `cos mφ` gets
/// `(−1)^m`, `sin |m|φ` gets `−(−1)^|m|`. 0 for even, 1 for odd.
const fn x_parity(m: i32) -> usize {
    if m >= 0 {
        (m % 2) as usize
    } else {
        ((-m + 1) % 2) as usize
    }
}

/// A rotation about x as two dense blocks per band. It commutes with the reflection
/// `x → −x`, so it maps each band's even coefficients (`l + 1` of them) among themselves and
/// its odd ones (`l`) likewise: 146 products at order 6 instead of 286 for the whole bands.
struct ParityBlocks {
    /// Band `l`'s coefficients `m + l`, even ones first.
    members: [[usize; MAX_BAND]; MAX_ORDER],
    /// Band by band: the even block, then the odd one, row-major in `members` order.
    values: [f32; PARITY_VALUES],
}

/// Σ_{l<MAX_ORDER} (l + 1)² + l²: an even and an odd block per band.
const PARITY_VALUES: usize = {
    let (mut l, mut total) = (0, 0);
    while l < MAX_ORDER {
        total += (l + 1) * (l + 1) + l * l;
        l += 1;
    }
    total
};

impl ParityBlocks {
    /// The blocks of `matrix`, which must commute with `x → −x` (a rotation about x): its
    /// entries between coefficients of different parity are zero and are left out.
    const fn of(matrix: &ShRotationMatrix) -> ParityBlocks {
        let mut blocks = ParityBlocks {
            members: [[0; MAX_BAND]; MAX_ORDER],
            values: [0.0; PARITY_VALUES],
        };
        let (mut l, mut at) = (0, 0);
        while l < MAX_ORDER {
            let li = l as i32;
            // Even members in 0..=l, odd ones after them.
            let (mut even, mut odd, mut m) = (0, l + 1, -li);
            while m <= li {
                let slot = if x_parity(m) == 0 {
                    &mut even
                } else {
                    &mut odd
                };
                blocks.members[l][*slot] = (m + li) as usize;
                *slot += 1;
                m += 1;
            }
            let mut k = 0;
            while k < (l + 1) * (l + 1) + l * l {
                // Row and column of entry k within the even block, then the odd one.
                let (start, len, k_in) = if k < (l + 1) * (l + 1) {
                    (0, l + 1, k)
                } else {
                    (l + 1, l, k - (l + 1) * (l + 1))
                };
                let row = blocks.members[l][start + k_in / len] as i32 - li;
                let column = blocks.members[l][start + k_in % len] as i32 - li;
                blocks.values[at] = matrix.get(li, row, column);
                at += 1;
                k += 1;
            }
            l += 1;
        }
        blocks
    }

    /// `output = D · input` on the first `order` bands (both at least `order²` long). Each
    /// band's blocks have sizes fixed at compile time, so the products unroll completely.
    fn apply(&self, order: usize, input: &[f32], output: &mut [f32]) {
        let mut values = &self.values[..];
        for (l, members) in self.members.iter().enumerate().take(order) {
            let band = &input[l * l..][..2 * l + 1];
            let out = &mut output[l * l..][..2 * l + 1];
            values = match l {
                0 => band_blocks::<1, 0>(members, values, band, out),
                1 => band_blocks::<2, 1>(members, values, band, out),
                2 => band_blocks::<3, 2>(members, values, band, out),
                3 => band_blocks::<4, 3>(members, values, band, out),
                4 => band_blocks::<5, 4>(members, values, band, out),
                _ => band_blocks::<6, 5>(members, values, band, out),
            };
        }
    }
}

/// One band's even (`E` coefficients) and odd (`O`) blocks; returns the values after them.
#[inline(always)]
fn band_blocks<'a, const E: usize, const O: usize>(
    members: &[usize; MAX_BAND],
    values: &'a [f32],
    band: &[f32],
    out: &mut [f32],
) -> &'a [f32] {
    let values = block::<E>(&members[..E], values, band, out);
    if O == 0 {
        return values; // band 0 has no odd coefficient
    }
    block::<O>(&members[E..E + O], values, band, out)
}

/// `out[members] = M · band[members]` for the `N × N` block `M` at the start of `values`;
/// returns the values after it.
#[inline(always)]
fn block<'a, const N: usize>(
    members: &[usize],
    values: &'a [f32],
    band: &[f32],
    out: &mut [f32],
) -> &'a [f32] {
    let gathered: [f32; N] = core::array::from_fn(|i| band[members[i]]);
    let (rows, rest) = values.split_at(N * N);
    for (&m, row) in members.iter().zip(rows.as_chunks::<N>().0) {
        out[m] = (0..N).map(|c| row[c] * gathered[c]).sum();
    }
    rest
}

/// Rotations of SH vectors of one order by any rotation, by ZYZ Euler angles: what the
/// runtime does to the lighting of each bone, and the trainer to each vertex's transfer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ShRotation {
    order: usize,
}

/// The ZYZ Euler angles `(α, β, γ)` of the row-major rotation `r`. `β` comes from
/// `atan2(sin β, cos β)`, which stays accurate near the poles where `acos` does not. Where
/// `sin β` is below 1e-7 only `α ± γ` is well defined: `γ = 0` then, and treating `β` as
/// exactly 0 or π moves nothing by more than 1e-7 rad.
fn zyz(r: &[[f64; 3]; 3]) -> (f64, f64, f64) {
    let sin_beta = math::hypot_f64(r[0][2], r[1][2]);
    let beta = math::atan2_f64(sin_beta, r[2][2]);
    if sin_beta > 1e-7 {
        (
            math::atan2_f64(r[1][2], r[0][2]),
            beta,
            math::atan2_f64(r[2][1], -r[2][0]),
        )
    } else {
        (math::atan2_f64(-r[0][1], r[1][1]), beta, 0.0)
    }
}

impl ShRotation {
    /// Rotations of order-`order` vectors (1..=6).
    pub fn new(order: usize) -> Result<ShRotation, ShError> {
        if order == 0 || order > MAX_ORDER {
            return Err(ShError::BadOrder);
        }
        Ok(ShRotation { order })
    }

    /// Rotations of a validated order (1..=[`MAX_ORDER`]).
    pub(crate) const fn of_order(order: usize) -> ShRotation {
        ShRotation { order }
    }

    /// The SH order of the vectors it rotates.
    pub fn order(&self) -> usize {
        self.order
    }

    /// `v` rotated by the row-major rotation `r`, in place: the function `f(ω)` it holds
    /// becomes `f(rᵀω)`, so a lobe around direction `d` moves to `r d`. `v` holds at least
    /// `order²` values; values past them are left alone.
    ///
    /// ```
    /// use aprt_core::{ShRotation, clamped_cosine};
    ///
    /// // A quarter turn about x takes +z to −y.
    /// let quarter = [[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]];
    /// let (mut up, mut back) = ([0.0; 9], [0.0; 9]);
    /// clamped_cosine(3, [0.0, 0.0, 1.0], &mut up)?;
    /// clamped_cosine(3, [0.0, -1.0, 0.0], &mut back)?;
    /// ShRotation::new(3)?.apply(&quarter, &mut up)?;
    /// assert!(up.iter().zip(back).all(|(a, b)| (a - b).abs() < 1e-5));
    /// # Ok::<(), aprt_core::ShError>(())
    /// ```
    pub fn apply(&self, r: &[[f64; 3]; 3], v: &mut [f32]) -> Result<(), ShError> {
        if v.len() < coeff_count(self.order) {
            return Err(ShError::OutputTooSmall);
        }
        self.rotate_slice(r, v);
        Ok(())
    }

    /// [`ShRotation::apply`] of a whole SH vector, which cannot be too short.
    pub(crate) fn rotate(&self, r: &[[f64; 3]; 3], v: &mut [f32; MAX_COEFFS]) {
        self.rotate_slice(r, v);
    }

    /// [`ShRotation::apply`] without the length check: `v` holds at least `order²` values.
    fn rotate_slice(&self, r: &[[f64; 3]; 3], v: &mut [f32]) {
        let (alpha, beta, gamma) = zyz(r);
        let mut tmp = [0.0f32; MAX_COEFFS];
        self.turn_z(gamma, v);
        QUARTER.apply(self.order, v, &mut tmp);
        self.turn_z(beta, &mut tmp);
        QUARTER_BACK.apply(self.order, &tmp, v);
        self.turn_z(alpha, v);
    }

    /// Rotation about z by `theta`: `f(φ) → f(φ − θ)`.
    fn turn_z(&self, theta: f64, v: &mut [f32]) {
        let (s1, c1) = math::sin_cos_f64(theta);
        let (mut s, mut c) = (0.0f64, 1.0f64);
        for m in 1..self.order {
            (s, c) = (s * c1 + c * s1, c * c1 - s * s1);
            let (sf, cf) = (s as f32, c as f32);
            for l in m..self.order {
                let (a, b) = (index(l, m as i32), index(l, -(m as i32)));
                let (x, y) = (v[a], v[b]);
                v[a] = x * cf - y * sf;
                v[b] = x * sf + y * cf;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mirrored_and_scaled_matrices_are_not_rotations() {
        let r = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]];
        assert!(is_rotation(&r, 1e-3));
        // Any column negated, or all three: orthonormal, determinant −1.
        for column in 0..3 {
            let mut mirrored = r;
            for row in &mut mirrored {
                row[column] = -row[column];
            }
            assert!(!is_rotation(&mirrored, 1e-3), "{mirrored:?}");
        }
        let minus = r.map(|row| row.map(|x| -x));
        assert!(!is_rotation(&minus, 1e-3));
        let scaled = r.map(|row| row.map(|x| 1.01 * x));
        assert!(!is_rotation(&scaled, 1e-3));
    }

    /// The rotation by `angle` about the unit `axis` (Rodrigues), row-major.
    fn axis_angle(axis: [f64; 3], angle: f64) -> [[f64; 3]; 3] {
        let (s, c) = (libm::sin(angle), libm::cos(angle));
        let [x, y, z] = axis;
        [
            [
                c + x * x * (1.0 - c),
                x * y * (1.0 - c) - z * s,
                x * z * (1.0 - c) + y * s,
            ],
            [
                y * x * (1.0 - c) + z * s,
                c + y * y * (1.0 - c),
                y * z * (1.0 - c) - x * s,
            ],
            [
                z * x * (1.0 - c) - y * s,
                z * y * (1.0 - c) + x * s,
                c + z * z * (1.0 - c),
            ],
        ]
    }

    #[test]
    fn equals_the_ivanic_ruedenberg_matrix_for_any_rotation_and_order() {
        let input: [f32; 36] = core::array::from_fn(|i| ((i * 37 % 11) as f32 - 5.0) / 7.0);
        let pi = core::f64::consts::PI;
        // Generic rotations, then the degenerate ones: identity, z only, half turns about x and
        // y (β = π), and rotations within 1e-10 of them.
        let mut cases = [([0.0f64; 3], 0.0f64); 206];
        for (i, case) in cases.iter_mut().enumerate().take(200) {
            let f = i as f64;
            let axis = [
                libm::sin(f * 0.71),
                libm::cos(f * 1.37),
                libm::sin(f * 2.11) + 0.1,
            ];
            let len = libm::sqrt(axis.iter().map(|a| a * a).sum::<f64>());
            *case = (axis.map(|a| a / len), 0.3 + f * 0.029);
        }
        cases[200] = ([0.0, 0.0, 1.0], 0.0);
        cases[201] = ([0.0, 0.0, 1.0], 1.3);
        cases[202] = ([1.0, 0.0, 0.0], pi);
        cases[203] = ([0.0, 1.0, 0.0], pi - 1e-10);
        cases[204] = ([1.0, 0.0, 0.0], 1e-10);
        cases[205] = ([0.6, 0.0, 0.8], pi);
        for (order, (axis, angle)) in (1..=MAX_ORDER).flat_map(|n| cases.map(|c| (n, c))) {
            let n2 = coeff_count(order);
            let r = axis_angle(axis, angle);
            let r32 = r.map(|row| row.map(|x| x as f32));
            let mut want = [0.0f32; 36];
            ShRotationMatrix::new(order, &r32)
                .unwrap()
                .apply(&input, &mut want)
                .unwrap();
            let mut got = input;
            ShRotation::new(order).unwrap().apply(&r, &mut got).unwrap();
            for (g, w) in got[..n2].iter().zip(&want[..n2]) {
                assert!(
                    math::abs(g - w) < 2e-5,
                    "order {order}, {axis:?} {angle}: {got:?} vs {want:?}"
                );
            }
            // Coefficients past the order are left alone.
            assert_eq!(got[n2..], input[n2..]);
        }
    }

    /// The entries the parity blocks leave out are zero in the full quarter-turn matrices,
    /// and the blocks have the sizes `PARITY_VALUES` assumes.
    #[test]
    fn quarter_turns_do_not_mix_parities() {
        for sign in [1.0, -1.0] {
            let full = quarter_turn(sign);
            let mut largest = 0.0f32;
            for l in 0..MAX_ORDER {
                let w = 2 * l + 1;
                let evens = (0..w)
                    .filter(|&i| x_parity(i as i32 - l as i32) == 0)
                    .count();
                assert_eq!(evens, l + 1);
                for i in 0..w {
                    for j in 0..w {
                        let (pi, pj) =
                            (x_parity(i as i32 - l as i32), x_parity(j as i32 - l as i32));
                        if pi != pj {
                            largest = largest.max(math::abs(full.get(
                                l as i32,
                                i as i32 - l as i32,
                                j as i32 - l as i32,
                            )));
                        }
                    }
                }
            }
            assert!(largest < 1e-6, "{largest}");
        }
    }

    #[test]
    fn refuses_a_vector_shorter_than_the_order() {
        let euler = ShRotation::new(3).unwrap();
        let identity = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        assert_eq!(
            euler.apply(&identity, &mut [0.0; 8]),
            Err(ShError::OutputTooSmall)
        );
        // The identity goes through the two quarter turns: equal within f32 rounding.
        let mut v = [1.0f32; 9];
        euler.apply(&identity, &mut v).unwrap();
        assert!(v.iter().all(|x| math::abs(x - 1.0) < 1e-6), "{v:?}");
    }
}
