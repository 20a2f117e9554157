//! Animation clips for the built-in character: a training clip that sweeps the whole pose
//! space, and novel test clips with motions the training clip never performs.

use super::JointAngle;
use crate::rig::Clip;

/// Frame rate of every built-in clip.
const FPS: f64 = 30.0;
/// Training clip length: about the number of poses the paper bakes, at 30 fps (8.3 s).
const TRAINING_FRAMES: usize = 250;
/// Fraction of each angle's half-range the training clip uses, so it never touches a limit
/// exactly (limits are where linear skinning looks worst and are rarely held in real motion).
const TRAINING_REACH: f64 = 0.95;

/// splitmix64: a tiny, well-mixed generator so the clip is identical on every platform and
/// does not depend on a random-number crate's version.
struct SplitMix(u64);

impl SplitMix {
    fn next_unit(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Every angle follows its own smooth random walk through key values: keys every 12–20
/// frames (a different period per angle), each a step of at most ±40 % of the range from the
/// last, kept within `TRAINING_REACH` of the limits, joined by cosine ease (C¹, as smooth as
/// keyframed animation).
///
/// Why not sums of slow sinusoids: motion band-limited to B Hz over T seconds spans only about
/// 2·B·T dimensions, so 250 frames of 0.1–0.5 Hz waves left the pose matrix with about ten
/// significant singular values out of 23; the fit then never saw the other directions and
/// novel poses along them were extrapolated wildly. Independent key schedules per angle make
/// the training poses span all 23 dimensions.
pub(crate) fn training(angles: &[JointAngle]) -> Clip {
    let mut rng = SplitMix(0x0A9B_7C0D_E5F1_2345);
    let tracks: Vec<Vec<f64>> = angles
        .iter()
        .map(|angle| {
            let period = 12 + (rng.next_unit() * 9.0) as usize;
            let (mid, half) = (0.5 * (angle.min + angle.max), 0.5 * (angle.max - angle.min));
            let (lo, hi) = (mid - TRAINING_REACH * half, mid + TRAINING_REACH * half);
            let mut key = mid + (2.0 * rng.next_unit() - 1.0) * TRAINING_REACH * half;
            let mut keys = vec![key];
            while (keys.len() - 1) * period < TRAINING_FRAMES + period {
                key = (key + (2.0 * rng.next_unit() - 1.0) * 0.8 * half).clamp(lo, hi);
                keys.push(key);
            }
            (0..TRAINING_FRAMES)
                .map(|f| {
                    let (k, s) = (f / period, (f % period) as f64 / period as f64);
                    let ease = 0.5 - 0.5 * (std::f64::consts::PI * s).cos();
                    keys[k] + (keys[k + 1] - keys[k]) * ease
                })
                .collect()
        })
        .collect();
    let frames = (0..TRAINING_FRAMES)
        .map(|f| tracks.iter().map(|track| track[f]).collect())
        .collect();
    Clip {
        name: "training".into(),
        fps: FPS,
        frames,
    }
}

/// Builds a clip of `frames` frames whose poses start at rest and are then adjusted by `pose`,
/// which receives the time in seconds and a setter by angle name.
fn scripted(
    angles: &[JointAngle],
    name: &str,
    frames: usize,
    pose: impl Fn(f64, &mut dyn FnMut(&str, f64)),
) -> Clip {
    let frames = (0..frames)
        .map(|f| {
            let mut frame: Vec<f64> = angles.iter().map(|a| a.rest).collect();
            pose(f as f64 / FPS, &mut |angle_name, value| {
                frame[index_of(angles, angle_name)] = value;
            });
            frame
        })
        .collect();
    Clip {
        name: name.into(),
        fps: FPS,
        frames,
    }
}

/// Index of the angle called `name`. The scripted clips only name built-in angles, and the
/// clip tests run every script, so a typo fails those tests rather than a caller.
fn index_of(angles: &[JointAngle], name: &str) -> usize {
    angles
        .iter()
        .position(|a| a.name == name)
        .unwrap_or_else(|| panic!("a built-in clip names unknown angle {name}"))
}

/// 0 → 1 with zero slope at both ends, over `[start, end]` seconds.
fn ease(t: f64, start: f64, end: f64) -> f64 {
    let x = ((t - start) / (end - start)).clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

/// Raises the right arm high and waves the forearm at 1.5 Hz while the head turns toward it.
/// Training never holds one arm high while the other rests, nor oscillates this fast.
fn wave(angles: &[JointAngle]) -> Clip {
    let abduct_rest = angles[index_of(angles, "r_shoulder_abduct")].rest;
    scripted(angles, "wave", 90, |t, set| {
        let up = ease(t, 0.0, 0.7);
        let w = std::f64::consts::TAU * 1.5 * t;
        set("r_shoulder_abduct", abduct_rest + (1.95 - abduct_rest) * up);
        set("r_shoulder_flex", 0.45 * up);
        set("r_elbow_flex", up * (0.8 + 0.45 * w.sin()));
        set("r_wrist_flex", up * 0.3 * (w + 0.5).sin());
        set("neck_twist", -0.35 * up);
        set("head_flex", -0.12 * up);
        set("chest_twist", -0.15 * up);
        set("spine_lean", 0.08 * up);
    })
}

/// Three strides of a walk in place (1.07 s cycle): legs and arms swing in opposition, the
/// chest counter-rotates, arms hang near the body.
fn walk(angles: &[JointAngle]) -> Clip {
    scripted(angles, "walk", 96, |t, set| {
        let w = std::f64::consts::TAU * t / 1.07;
        for (side, sign) in [("l", 1.0), ("r", -1.0)] {
            let phase = if sign > 0.0 {
                0.0
            } else {
                std::f64::consts::PI
            };
            set(&format!("{side}_hip_flex"), 0.1 + 0.45 * (w + phase).sin());
            set(
                &format!("{side}_knee_flex"),
                0.45 + 0.4 * (w + phase + 1.3).sin(),
            );
            set(
                &format!("{side}_ankle_flex"),
                0.15 * (w + phase + 2.0).sin(),
            );
            set(&format!("{side}_shoulder_flex"), -0.35 * (w + phase).sin());
            set(&format!("{side}_shoulder_abduct"), 0.2);
            set(
                &format!("{side}_elbow_flex"),
                0.3 + 0.15 * (w + phase + 0.4).sin(),
            );
        }
        set("chest_twist", 0.12 * w.sin());
        set("spine_flex", 0.05);
        set("spine_lean", 0.03 * (2.0 * w).sin());
    })
}

/// Bends forward and reaches down and ahead with the left arm, bending the knees, then holds.
/// (Shoulder flex is relative to the chest, so it must exceed the 0.75 rad forward bend for
/// the arm to point ahead of vertical.)
fn reach(angles: &[JointAngle]) -> Clip {
    let abduct_rest = angles[index_of(angles, "l_shoulder_abduct")].rest;
    scripted(angles, "reach", 72, |t, set| {
        let e = ease(t, 0.0, 1.8);
        set("spine_flex", 0.45 * e);
        set("chest_flex", 0.3 * e);
        set("l_shoulder_flex", 1.5 * e);
        set("l_shoulder_abduct", abduct_rest + (0.35 - abduct_rest) * e);
        set("l_elbow_flex", 0.25 * e);
        set("r_shoulder_flex", -0.2 * e);
        set("head_flex", -0.2 * e);
        set("neck_twist", 0.2 * e);
        set("l_hip_flex", 0.3 * e);
        set("r_hip_flex", 0.3 * e);
        set("l_knee_flex", 0.35 * e);
        set("r_knee_flex", 0.35 * e);
    })
}

/// Stretches: both arms out to the sides while the chest twists, then a squat with the arms
/// forward and the head down. The validation clip: held out of training to choose the model
/// by (`--validate stretch`), never a test clip.
pub(crate) fn stretch(angles: &[JointAngle]) -> Clip {
    let rest = |name: &str| angles[index_of(angles, name)].rest;
    let abduct_rest = [rest("l_shoulder_abduct"), rest("r_shoulder_abduct")];
    scripted(angles, "stretch", 96, |t, set| {
        let out = ease(t, 0.0, 0.6) * (1.0 - ease(t, 1.6, 2.0));
        let squat = ease(t, 1.8, 2.6);
        let twist = 0.45 * (std::f64::consts::TAU * 0.6 * t).sin() * out;
        for (side, abduct_rest) in ["l", "r"].into_iter().zip(abduct_rest) {
            let joint = |name: &str| format!("{side}_{name}");
            set(
                &joint("shoulder_abduct"),
                abduct_rest + (1.45 - abduct_rest) * out,
            );
            set(&joint("shoulder_flex"), 1.2 * squat);
            set(&joint("elbow_flex"), 0.2 * out + 0.4 * squat);
            set(&joint("hip_flex"), 1.0 * squat);
            set(&joint("knee_flex"), 1.4 * squat);
            set(&joint("ankle_flex"), 0.35 * squat);
        }
        set("chest_twist", twist);
        set("spine_lean", 0.1 * twist);
        set("spine_flex", 0.25 * squat);
        set("neck_flex", 0.3 * squat);
    })
}

/// The novel test clips, in a fixed order.
pub(crate) fn novel(angles: &[JointAngle]) -> Vec<Clip> {
    vec![wave(angles), walk(angles), reach(angles)]
}
