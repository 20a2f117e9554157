//! Rotating one SH vector per vertex cheaply: `R = Rz(α) Ry(β) Rz(γ)` (ZYZ Euler angles) with
//! `Ry(β) = Rx(−90°) Rz(β) Rx(90°)`. A rotation about z turns each `(cos mφ, sin mφ)`
//! coefficient pair by `mθ` (O(n²)), and the two quarter turns about x are fixed matrices built
//! once per bake, so a vertex costs two block products and three plane rotations instead of
//! building its own Ivanic–Ruedenberg matrix (about 65k instructions at order 6).

use aprt_core::rotate::ShRotationMatrix;
use aprt_core::sh::{self, ShError};
use glam::DVec3;

/// Rotations of SH vectors of one order by any rotation.
pub(crate) struct EulerRotation {
    order: usize,
    /// `D(Rx(90°))`.
    quarter: ShRotationMatrix,
    /// `D(Rx(−90°))`.
    quarter_back: ShRotationMatrix,
}

/// The ZYZ Euler angles `(α, β, γ)` of the rotation with columns `x, y, z`. `β` comes from
/// `atan2(sin β, cos β)`, which stays accurate near the poles where `acos` does not. Where
/// `sin β` is below 1e-7 only `α ± γ` is well defined: `γ = 0` then, and treating `β` as
/// exactly 0 or π moves nothing by more than 1e-7 rad.
fn zyz(x: DVec3, y: DVec3, z: DVec3) -> (f64, f64, f64) {
    let sin_beta = z.x.hypot(z.y);
    let beta = sin_beta.atan2(z.z);
    if sin_beta > 1e-7 {
        (z.y.atan2(z.x), beta, y.z.atan2(-x.z))
    } else {
        ((-y.x).atan2(y.y), beta, 0.0)
    }
}

impl EulerRotation {
    pub fn new(order: usize) -> Result<EulerRotation, ShError> {
        let quarter = [[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]];
        let quarter_back = [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]];
        Ok(EulerRotation {
            order,
            quarter: ShRotationMatrix::new(order, &quarter)?,
            quarter_back: ShRotationMatrix::new(order, &quarter_back)?,
        })
    }

    /// `v` rotated by the rotation whose columns are `frame` (taking `f(ω)` to `f(Rᵀω)`, as
    /// [`ShRotationMatrix`]), in place; `v` holds at least `order²` values.
    pub fn apply(&self, frame: &[DVec3; 3], v: &mut [f32]) -> Result<(), ShError> {
        let (alpha, beta, gamma) = zyz(frame[0], frame[1], frame[2]);
        let mut tmp = [0.0f32; sh::MAX_COEFFS];
        self.turn_z(gamma, v);
        self.quarter.apply(v, &mut tmp)?;
        self.turn_z(beta, &mut tmp);
        self.quarter_back.apply(&tmp, v)?;
        self.turn_z(alpha, v);
        Ok(())
    }

    /// Rotation about z by `theta`: `f(φ) → f(φ − θ)`.
    fn turn_z(&self, theta: f64, v: &mut [f32]) {
        let (s1, c1) = theta.sin_cos();
        let (mut s, mut c) = (0.0f64, 1.0f64);
        for m in 1..self.order {
            (s, c) = (s * c1 + c * s1, c * c1 - s * s1);
            let (sf, cf) = (s as f32, c as f32);
            for l in m..self.order {
                let (a, b) = (sh::index(l, m as i32), sh::index(l, -(m as i32)));
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
    use glam::DQuat;

    #[test]
    fn equals_the_ivanic_ruedenberg_matrix_for_any_rotation() {
        let order = 6;
        let euler = EulerRotation::new(order).unwrap();
        let input: Vec<f32> = (0..36)
            .map(|i| ((i * 37 % 11) as f32 - 5.0) / 7.0)
            .collect();
        let mut quats: Vec<DQuat> = (0..200)
            .map(|i| {
                let f = i as f64;
                DQuat::from_xyzw(
                    (f * 0.71).sin(),
                    (f * 1.37).cos(),
                    (f * 2.11).sin(),
                    (f * 0.53).cos() + 0.1,
                )
                .normalize()
            })
            .collect();
        // The degenerate ones: identity, z only, a half turn about x (β = π), and near them.
        quats.push(DQuat::IDENTITY);
        quats.push(DQuat::from_rotation_z(1.3));
        quats.push(DQuat::from_rotation_x(std::f64::consts::PI));
        quats.push(DQuat::from_rotation_x(1e-12) * DQuat::from_rotation_z(0.4));
        quats.push(DQuat::from_rotation_y(std::f64::consts::PI - 1e-10));
        for q in quats {
            let frame = [q * DVec3::X, q * DVec3::Y, q * DVec3::Z];
            let r = std::array::from_fn(|row| frame.map(|axis| axis[row] as f32));
            let mut want = [0.0f32; 36];
            ShRotationMatrix::new(order, &r)
                .unwrap()
                .apply(&input, &mut want)
                .unwrap();
            let mut got = input.clone();
            euler.apply(&frame, &mut got).unwrap();
            for (g, w) in got.iter().zip(&want) {
                assert!((g - w).abs() < 2e-5, "{q:?}: {got:?} vs {want:?}");
            }
        }
    }
}
