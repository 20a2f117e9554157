//! Rotation vectors (the log map of unit quaternions) and back: the three numbers per joint
//! that make up the pose vector of a glTF rig or a motion-capture mannequin.
//!
//! A rotation vector `r = θ·axis` is linear enough in the joint motion for the pose-driven
//! linear model (a hinge moves one component, small rotations add), has no redundant fourth
//! number and is zero at the rest pose. Both maps are exact to rounding everywhere, including
//! the identity (series instead of `0/0`) and half turns (angle `π`, where the quaternion's
//! `w` is 0).

use glam::{DQuat, DVec3};

/// Below this `|v|` (the sine of half the angle), `atan2(|v|, w)/|v|` is replaced by `1/w`:
/// the dropped term is `|v|²/3`, below 1e-24, far under f64 resolution.
const SMALL_SIN: f64 = 1e-12;

/// Below this angle, `sin(θ/2)/θ` is replaced by its series `1/2 − θ²/48`; the next term is
/// `θ⁴/3840`, below 1e-27.
const SMALL_ANGLE: f64 = 1e-6;

/// The rotation vector of `q` (unit or not; only its direction matters): angle in `[0, π]`
/// times the unit axis. `q` and `−q` give the same vector, because the sign is chosen so that
/// `w ≥ 0` (the shorter way round). At exactly `π`, the axis keeps the sign `q` had.
pub fn log(q: DQuat) -> DVec3 {
    let q = if q.w < 0.0 { -q } else { q };
    let v = q.xyz();
    let s = v.length();
    if s < SMALL_SIN {
        // w ≈ |q| here; q may be unnormalised, so divide by it rather than assume 1.
        v * (2.0 / q.w)
    } else {
        v * (2.0 * s.atan2(q.w) / s)
    }
}

/// The unit quaternion of rotation vector `r` (rotation by `|r|` about `r/|r|`); the inverse
/// of [`log`] for `|r| ≤ π`.
pub fn exp(r: DVec3) -> DQuat {
    let angle = r.length();
    let (sin_half_over_angle, cos_half) = if angle < SMALL_ANGLE {
        (0.5 - angle * angle / 48.0, 1.0 - angle * angle / 8.0)
    } else {
        let (s, c) = (0.5 * angle).sin_cos();
        (s / angle, c)
    };
    let v = r * sin_half_over_angle;
    DQuat::from_xyzw(v.x, v.y, v.z, cos_half)
}

/// Of the rotation vectors equal to `v` as rotations (`v̂ (|v| + 2πk)`), the one nearest
/// `previous`: applied frame by frame, it keeps a clip's pose vectors continuous where a joint
/// turns through a half turn and [`log`] jumps to the other side.
fn nearest_turn(v: DVec3, previous: DVec3) -> DVec3 {
    let angle = v.length();
    if angle == 0.0 {
        return v;
    }
    let axis = v / angle;
    let k = ((axis.dot(previous) - angle) / std::f64::consts::TAU).round();
    if k == 0.0 {
        v
    } else {
        axis * (angle + std::f64::consts::TAU * k)
    }
}

/// Makes a clip's rotation vectors continuous: frame by frame, each 3-number vector at
/// `joints` (indices of triples) becomes, of the vectors `v̂ (|v| + 2πk)` equal to it as
/// rotations, the one nearest the same joint in the frame before.
pub fn continue_turns(frames: &mut [Vec<f64>], joints: impl Iterator<Item = usize> + Clone) {
    for f in 1..frames.len() {
        let (done, rest) = frames.split_at_mut(f);
        let (previous, pose) = (&done[f - 1], &mut rest[0]);
        for i in joints.clone() {
            let v = DVec3::from_slice(&pose[3 * i..]);
            let u = DVec3::from_slice(&previous[3 * i..]);
            nearest_turn(v, u).write_to_slice(&mut pose[3 * i..]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// Same rotation: q and −q are equal rotations.
    fn same_rotation(a: DQuat, b: DQuat) -> f64 {
        (a - b).length().min((a + b).length())
    }

    #[test]
    fn round_trips_across_the_range_of_angles() {
        // Labelled hard cases: the identity (0/0 in the closed form), angles where the series
        // switch happens, a generic angle, and half turns where w vanishes and the vector is
        // only defined up to sign.
        let axis = DVec3::new(0.3, -0.8, 0.52).normalize();
        let cases = [
            ("identity", 0.0),
            ("tiny, series branch", 1e-9),
            ("just below the series switch", 0.9e-6),
            ("just above the series switch", 1.1e-6),
            ("generic", 1.234),
            ("near a half turn", PI - 1e-9),
            ("half turn", PI),
        ];
        for (label, angle) in cases {
            let q = DQuat::from_axis_angle(axis, angle);
            let r = log(q);
            assert!(
                (r - axis * angle).length() <= 1e-14 * (1.0 + angle),
                "{label}: log gave {r:?}, expected {:?}",
                axis * angle
            );
            let back = exp(r);
            assert!(
                same_rotation(back, q) <= 1e-15,
                "{label}: exp(log(q)) = {back:?}, q = {q:?}"
            );
            assert!((back.length() - 1.0).abs() <= 1e-15, "{label}: not unit");
        }
    }

    #[test]
    fn both_signs_of_a_quaternion_give_the_same_vector() {
        let q = DQuat::from_axis_angle(DVec3::Z, 2.5);
        assert!((log(q) - log(-q)).length() < 1e-15);
        // Beyond π the shorter way round is taken: a 3π/2 turn is a −π/2 turn.
        let long = DQuat::from_axis_angle(DVec3::X, 1.5 * PI);
        assert!((log(long) - DVec3::new(-0.5 * PI, 0.0, 0.0)).length() < 1e-14);
    }

    #[test]
    fn exp_matches_the_axis_angle_constructor() {
        for r in [
            DVec3::new(0.1, 0.2, -0.3),
            DVec3::new(-2.0, 1.0, 0.5),
            DVec3::new(1e-8, 0.0, -2e-8),
        ] {
            let expect = DQuat::from_scaled_axis(r);
            assert!(same_rotation(exp(r), expect) < 1e-15, "{r:?}");
        }
    }

    /// A turn past π about y: the log flips to the other side, the unwrapped vector continues
    /// it; whole turns back are unwrapped too, and a vector nearest itself is left alone.
    #[test]
    fn nearest_turn_continues_through_half_turns() {
        let raw = log(DQuat::from_rotation_y(3.2));
        assert!(raw.y < 0.0);
        let continued = nearest_turn(raw, DVec3::new(0.0, 3.1, 0.0));
        assert!((continued.y - 3.2).abs() < 1e-12, "{continued}");
        let back = nearest_turn(DVec3::new(0.0, 0.5, 0.0), DVec3::new(0.0, -5.9, 0.0));
        assert!((back.y - (0.5 - 2.0 * PI)).abs() < 1e-12, "{back}");
        assert_eq!(nearest_turn(raw, raw), raw);
        assert_eq!(nearest_turn(DVec3::ZERO, DVec3::X), DVec3::ZERO);
        // Frame 1 continues frame 0, frame 2 continues the continued frame 1.
        let mut frames = vec![
            vec![9.0, 9.0, 9.0, 0.0, 3.1, 0.0],
            vec![0.0, 0.0, 0.0, raw.x, raw.y, raw.z],
            vec![0.0, 0.0, 0.0, raw.x, raw.y, raw.z],
        ];
        continue_turns(&mut frames, 1..2);
        assert_eq!(frames[1][..3], [0.0; 3], "joint 0 was not asked for");
        assert!((frames[1][4] - 3.2).abs() < 1e-12, "{frames:?}");
        assert!((frames[2][4] - 3.2).abs() < 1e-12, "{frames:?}");
    }
}
