//! The clip machinery of the built-in characters: a training clip that sweeps the whole pose
//! space by a deterministic random walk, and scripted clips written as functions of time.

use super::JointAngle;
use crate::rig::Clip;

/// Frame rate of every built-in clip.
pub(crate) const FPS: f64 = 30.0;
/// Training clip length: about the number of poses the paper bakes, at 30 fps (8.3 s).
const TRAINING_FRAMES: usize = 250;
/// Fraction of each angle's half-range the training clip uses, so it never touches a limit
/// exactly (limits are where linear skinning looks worst and are rarely held in real motion).
const TRAINING_REACH: f64 = 0.95;

/// splitmix64: a tiny, well-mixed generator so the clip is identical on every platform and
/// does not depend on a random-number crate's version.
pub(crate) struct SplitMix(pub(crate) u64);

impl SplitMix {
    /// The next value, uniform in [0, 1).
    pub(crate) fn next_unit(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// The clip "training" (250 frames at 30 fps), from the generator seeded with `seed`: every
/// angle follows its own smooth random walk through key values: keys every 12–20 frames (a
/// different period per angle), each a step of at most ±40 % of the range from the last, kept
/// within `TRAINING_REACH` of the limits, joined by cosine ease (C¹, as smooth as keyframed
/// animation).
///
/// Why not sums of slow sinusoids: motion band-limited to B Hz over T seconds spans only about
/// 2·B·T dimensions, so 250 frames of 0.1–0.5 Hz waves left the human's pose matrix with about
/// ten significant singular values out of 23; the fit then never saw the other directions and
/// novel poses along them were extrapolated wildly. Independent key schedules per angle make
/// the training poses span every dimension.
pub(crate) fn training(angles: &[JointAngle], seed: u64) -> Clip {
    let mut rng = SplitMix(seed);
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
pub(crate) fn scripted(
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
pub(crate) fn index_of(angles: &[JointAngle], name: &str) -> usize {
    angles
        .iter()
        .position(|a| a.name == name)
        .unwrap_or_else(|| panic!("a built-in clip names unknown angle {name}"))
}

/// 0 → 1 with zero slope at both ends, over `[start, end]` seconds.
pub(crate) fn ease(t: f64, start: f64, end: f64) -> f64 {
    let x = ((t - start) / (end - start)).clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}
