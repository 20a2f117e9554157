//! Keyframe curves and glTF's three interpolation modes, independent of how the keys were
//! read, so they can be checked against hand-computed values.
//!
//! Follows glTF 2.0 §3.11 and Appendix C: before the first key the first value holds, after
//! the last key the last value holds; STEP holds each key's value until the next key; LINEAR
//! lerps vectors and slerps rotations the short way round; CUBICSPLINE is the cubic Hermite
//! spline through the values with the file's in/out tangents scaled by the key interval, and a
//! rotation is renormalised afterwards (the spline of unit quaternions is not unit).

use glam::{DQuat, DVec3};

/// How values between keys are found (glTF `sampler.interpolation`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    /// The previous key's value.
    Step,
    /// Straight line between keys (slerp for rotations).
    Linear,
    /// Cubic Hermite spline; each key stores in-tangent, value, out-tangent.
    CubicSpline,
}

/// A value a curve interpolates: translations and scales (vectors) or rotations.
pub trait Keyframe:
    Copy + std::ops::Add<Output = Self> + std::ops::Mul<f64, Output = Self>
{
    /// LINEAR interpolation from `a` (u = 0) to `b` (u = 1).
    fn linear(a: Self, b: Self, u: f64) -> Self;
    /// Brings a cubic-spline result back to a valid value.
    fn finish(self) -> Self;
}

impl Keyframe for DVec3 {
    fn linear(a: Self, b: Self, u: f64) -> Self {
        a.lerp(b, u)
    }
    fn finish(self) -> Self {
        self
    }
}

impl Keyframe for DQuat {
    /// Slerp the short way round (glam flips `b` when `a·b < 0`), as glTF requires.
    fn linear(a: Self, b: Self, u: f64) -> Self {
        a.slerp(b, u)
    }
    fn finish(self) -> Self {
        self.normalize()
    }
}

/// Why keys do not form a curve.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CurveError {
    /// No keys at all.
    #[error("the sampler has no keyframes")]
    Empty,
    /// The output count does not match the input count (×3 for CUBICSPLINE).
    #[error("{times} key times need {expected} output values, got {got}")]
    OutputCount {
        /// Key times.
        times: usize,
        /// Values needed.
        expected: usize,
        /// Values given.
        got: usize,
    },
    /// Key times must be finite and strictly increasing.
    #[error("key time {index} ({time}) is not finite or not after the previous key")]
    Times {
        /// Index of the offending key.
        index: usize,
        /// Its time.
        time: f64,
    },
}

/// Keys and their interpolation. For CUBICSPLINE `values` holds `[in-tangent, value,
/// out-tangent]` per key, as glTF stores them.
#[derive(Clone, Debug, PartialEq)]
pub struct Curve<T> {
    times: Vec<f64>,
    values: Vec<T>,
    interpolation: Interpolation,
}

impl<T: Keyframe> Curve<T> {
    /// Validates and stores the keys.
    pub fn new(
        times: Vec<f64>,
        values: Vec<T>,
        interpolation: Interpolation,
    ) -> Result<Self, CurveError> {
        if times.is_empty() {
            return Err(CurveError::Empty);
        }
        let per_key = if interpolation == Interpolation::CubicSpline {
            3
        } else {
            1
        };
        if values.len() != per_key * times.len() {
            return Err(CurveError::OutputCount {
                times: times.len(),
                expected: per_key * times.len(),
                got: values.len(),
            });
        }
        for (index, &time) in times.iter().enumerate() {
            if !time.is_finite() || (index > 0 && time <= times[index - 1]) {
                return Err(CurveError::Times { index, time });
            }
        }
        Ok(Curve {
            times,
            values,
            interpolation,
        })
    }

    /// Time of the last key.
    pub fn end(&self) -> f64 {
        self.times[self.times.len() - 1]
    }

    /// The values at the keys (without CUBICSPLINE tangents).
    pub fn key_values(&self) -> impl Iterator<Item = T> + '_ {
        (0..self.times.len()).map(|k| self.value(k))
    }

    fn value(&self, key: usize) -> T {
        match self.interpolation {
            Interpolation::CubicSpline => self.values[3 * key + 1],
            _ => self.values[key],
        }
    }

    /// The curve at time `t`, held constant outside the keys.
    pub fn sample(&self, t: f64) -> T {
        let last = self.times.len() - 1;
        if t <= self.times[0] {
            return self.value(0);
        }
        if t >= self.times[last] {
            return self.value(last);
        }
        // The key interval [k, k+1] that holds t: times[k] <= t < times[k+1].
        let k = self.times.partition_point(|&key| key <= t) - 1;
        let dt = self.times[k + 1] - self.times[k];
        let u = (t - self.times[k]) / dt;
        match self.interpolation {
            Interpolation::Step => self.value(k),
            Interpolation::Linear => T::linear(self.value(k), self.value(k + 1), u),
            Interpolation::CubicSpline => {
                let (u2, u3) = (u * u, u * u * u);
                let out_tangent = self.values[3 * k + 2];
                let in_tangent = self.values[3 * (k + 1)];
                (self.value(k) * (2.0 * u3 - 3.0 * u2 + 1.0)
                    + out_tangent * (dt * (u3 - 2.0 * u2 + u))
                    + self.value(k + 1) * (-2.0 * u3 + 3.0 * u2)
                    + in_tangent * (dt * (u3 - u2)))
                    .finish()
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f64) -> DVec3 {
        DVec3::new(x, -2.0 * x, 0.5)
    }

    fn close(a: DVec3, b: DVec3) -> bool {
        (a - b).length() < 1e-12
    }

    #[test]
    fn step_holds_each_key_until_the_next() {
        let c = Curve::new(
            vec![0.0, 1.0, 3.0],
            vec![v(1.0), v(2.0), v(5.0)],
            Interpolation::Step,
        )
        .unwrap();
        assert!(close(c.sample(-1.0), v(1.0)));
        assert!(close(c.sample(0.999), v(1.0)));
        assert!(close(c.sample(1.0), v(2.0)));
        assert!(close(c.sample(2.9), v(2.0)));
        assert!(close(c.sample(3.0), v(5.0)));
        assert!(close(c.sample(10.0), v(5.0)));
    }

    #[test]
    fn linear_lerps_vectors_and_clamps_outside() {
        let c = Curve::new(vec![1.0, 3.0], vec![v(2.0), v(6.0)], Interpolation::Linear).unwrap();
        assert!(close(c.sample(0.0), v(2.0)));
        // u = 0.25 → 2 + 0.25·4 = 3.
        assert!(close(c.sample(1.5), v(3.0)));
        assert!(close(c.sample(4.0), v(6.0)));
        assert_eq!(c.end(), 3.0);
    }

    #[test]
    fn linear_slerps_rotations_the_short_way() {
        let a = DQuat::from_rotation_z(0.2);
        // The same 1.0 rad rotation stored with the opposite sign: the short way is 0.8 rad.
        let b = -DQuat::from_rotation_z(1.0);
        let c = Curve::new(vec![0.0, 1.0], vec![a, b], Interpolation::Linear).unwrap();
        let mid = c.sample(0.5);
        let expect = DQuat::from_rotation_z(0.6);
        assert!((mid - expect).length().min((mid + expect).length()) < 1e-12);
    }

    #[test]
    fn cubic_spline_matches_the_hermite_basis_by_hand() {
        // Keys at t = 0 (value 0, out-tangent 1) and t = 2 (value 1, in-tangent 3), one
        // component. At u = 0.5 (t = 1): h00 = 0.5, h10 = 0.125, h01 = 0.5, h11 = −0.125, and
        // tangents scale by dt = 2: 0.5·0 + 0.125·2·1 + 0.5·1 − 0.125·2·3 = 0.
        // At u = 0.25 (t = 0.5): h10 = 0.140625, h01 = 0.15625, h11 = −0.046875:
        // 0.140625·2 + 0.15625 − 0.046875·6 = 0.15625.
        let x = |a: f64| DVec3::new(a, 0.0, 0.0);
        let c = Curve::new(
            vec![0.0, 2.0],
            vec![x(9.0), x(0.0), x(1.0), x(3.0), x(1.0), x(9.0)],
            Interpolation::CubicSpline,
        )
        .unwrap();
        assert!(close(c.sample(1.0), x(0.0)), "{:?}", c.sample(1.0));
        assert!(close(c.sample(0.5), x(0.15625)), "{:?}", c.sample(0.5));
        assert!(close(c.sample(-1.0), x(0.0)));
        assert!(close(c.sample(2.0), x(1.0)));
        assert_eq!(c.key_values().collect::<Vec<_>>(), vec![x(0.0), x(1.0)]);
    }

    #[test]
    fn cubic_spline_rotations_are_renormalised() {
        // Zero tangents: the Hermite blend of two unit quaternions at u = 0.5 is their average,
        // which is shorter than 1; the curve must return it normalised.
        let (a, b) = (DQuat::IDENTITY, DQuat::from_rotation_x(1.0));
        let z = DQuat::from_xyzw(0.0, 0.0, 0.0, 0.0);
        let c = Curve::new(
            vec![0.0, 1.0],
            vec![z, a, z, z, b, z],
            Interpolation::CubicSpline,
        )
        .unwrap();
        let mid = c.sample(0.5);
        assert!((mid.length() - 1.0).abs() < 1e-15);
        assert!((mid - DQuat::from_rotation_x(0.5)).length() < 1e-12);
    }

    #[test]
    fn malformed_keys_are_refused() {
        assert_eq!(
            Curve::<DVec3>::new(vec![], vec![], Interpolation::Linear),
            Err(CurveError::Empty)
        );
        assert_eq!(
            Curve::new(vec![0.0, 1.0], vec![v(0.0); 2], Interpolation::CubicSpline),
            Err(CurveError::OutputCount {
                times: 2,
                expected: 6,
                got: 2
            })
        );
        assert_eq!(
            Curve::new(vec![0.0, 0.0], vec![v(0.0); 2], Interpolation::Step),
            Err(CurveError::Times {
                index: 1,
                time: 0.0
            })
        );
        assert!(Curve::new(vec![f64::NAN], vec![v(0.0)], Interpolation::Step).is_err());
    }
}
