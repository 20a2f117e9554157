//! `aprt train --sample-poses N`: extra training poses sampled within the range each pose
//! entry takes over the training clips. Each sampled pose starts from a training frame chosen
//! at random and re-draws 1 to 3 joints chosen at random (a rotation-vector joint's three
//! entries `<joint>.x/.y/.z` together; any other entry, such as a built-in character's
//! `l_elbow_flex`, is a joint of its own), each entry uniformly within the `[min, max]` it
//! takes over the training frames, narrowed to the rig's joint limits where it has them
//! ([`super::Rig::joint_limits`]).
//!
//! The same sampler makes the validation poses of `aprt train --validation-poses N`
//! ([`validation_clip`]): with its own seed, so they are never the training poses
//! `--sample-poses` adds, and each entry's range widened by [`VALIDATION_MARGIN`] of itself on
//! each side before the joint limits narrow it, since the novel poses a model is chosen for lie
//! beyond the training range.

use super::Clip;

/// The clip part the sampled poses form in the training set, so held-out segments never
/// straddle them.
pub const SAMPLED_CLIP: &str = "sampled";

/// The seed of every sampling: the same training frames give the same poses, so a resumed bake
/// finds the very poses its checkpoint holds.
pub const SEED: u64 = 0x5a4d_504c_4550_4f53;

/// The clip the validation poses form among the validation clips (`aprt train
/// --validation-poses`, after any `--validate` clip): never trained on, only used to choose
/// the model by.
pub const VALIDATION_CLIP: &str = "validation poses";

/// The seed of the validation poses: another than [`SEED`], so that a validation pose never
/// equals a training pose of `--sample-poses` (the same frames with the same seed and no
/// margin would re-draw the same joints), and fixed, so a resumed bake finds the very
/// validation poses its checkpoint holds.
pub const VALIDATION_SEED: u64 = 0x5641_4c49_4450_4f53;

/// How far beyond the training range the validation poses re-draw an entry, as a fraction of
/// that range on each side: `[min − m·(max − min), max + m·(max − min)]`, then narrowed to the
/// joint limits where the rig has them. The novel poses a model is chosen for lie beyond the
/// poses it was trained on, and a validation set drawn within the training range alone asks
/// only how well the model interpolates; 15 % reaches past it without leaving the motion's
/// character (a sampled pose still keeps every joint but 1 to 3 of a training frame).
pub const VALIDATION_MARGIN: f64 = 0.15;

/// The validation poses `aprt train`, `aprt results` and `aprt demo` sample and bake when no
/// count is given (`--validation-poses`). On CesiumMan, RiggedSimple and the Fox, 0, 16 and
/// 64 chose models of equal test error (docs/results/models.md); 64 costs 2 to 32 s of
/// bake (13 % of the demo's) and halves the standard error of a tie against 16.
pub const DEFAULT_VALIDATION_POSES: usize = 64;

/// Most joints one sampled pose re-draws.
const MAX_REDRAWN: usize = 3;

/// xorshift64* (Vigna 2016). The trainer depends on no random-number crate (only `proptest`,
/// for tests), and a sampler of a few hundred poses needs no more than this: fixed, portable
/// and bit-identical across platforms and versions, which a resume relies on.
struct XorShift(u64);

impl XorShift {
    fn new(seed: u64) -> Self {
        // Never zero: xorshift's one fixed point.
        XorShift(seed | 1)
    }

    fn next(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.0 = x;
        x.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }

    /// Uniform in `[0, 1)` (53 bits).
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in `0..n` (`n > 0`; the bias of the modulo is below 2⁻⁴⁰ for any n here).
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

/// The joints of a pose vector: indices of entries grouped by name, `<joint>.x/.y/.z` as one.
fn joints(names: &[String]) -> Vec<Vec<usize>> {
    let mut joints: Vec<(String, Vec<usize>)> = Vec::new();
    for (i, name) in names.iter().enumerate() {
        let stem = [".x", ".y", ".z"]
            .iter()
            .find_map(|s| name.strip_suffix(s))
            .unwrap_or(name);
        match joints.iter_mut().find(|(j, _)| j == stem) {
            Some((_, entries)) => entries.push(i),
            None => joints.push((stem.to_owned(), vec![i])),
        }
    }
    joints.into_iter().map(|(_, e)| e).collect()
}

/// `n` poses sampled from `frames` (the training frames, entries named `names`) with `seed`;
/// each entry is re-drawn within the range it takes over `frames` widened by `margin` of
/// itself on each side (0: the seen range), narrowed by `limits`, one `(min, max)` per entry,
/// where given. Joints that never move in `frames` are never re-drawn. Empty when `n` is 0 or
/// there are no frames.
pub fn sample_poses(
    names: &[String],
    frames: &[Vec<f64>],
    limits: Option<&[(f64, f64)]>,
    n: usize,
    seed: u64,
    margin: f64,
) -> Vec<Vec<f64>> {
    sample(names, frames, limits, n, seed, margin)
        .into_iter()
        .map(|s| s.pose)
        .collect()
}

/// The `n` validation poses of `frames` ([`VALIDATION_SEED`], [`VALIDATION_MARGIN`]; see
/// [`sample_poses`]).
pub fn validation_poses(
    names: &[String],
    frames: &[Vec<f64>],
    limits: Option<&[(f64, f64)]>,
    n: usize,
) -> Vec<Vec<f64>> {
    sample_poses(names, frames, limits, n, VALIDATION_SEED, VALIDATION_MARGIN)
}

/// One sampled pose and how it was made (the tests check the pose against the rest).
#[cfg_attr(
    not(test),
    expect(dead_code, reason = "base and redrawn are read by the tests only")
)]
struct Sampled {
    /// The training frame it starts from.
    base: usize,
    /// The joints re-drawn (entry indices of each).
    redrawn: Vec<Vec<usize>>,
    pose: Vec<f64>,
}

/// [`sample_poses`], keeping each pose's base frame and re-drawn joints.
fn sample(
    names: &[String],
    frames: &[Vec<f64>],
    limits: Option<&[(f64, f64)]>,
    n: usize,
    seed: u64,
    margin: f64,
) -> Vec<Sampled> {
    if n == 0 || frames.is_empty() {
        return Vec::new();
    }
    let ranges: Vec<(f64, f64)> = (0..names.len())
        .map(|e| {
            let (lo, hi) = frames
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |r, f| {
                    (r.0.min(f[e]), r.1.max(f[e]))
                });
            // Widened only for a margin, so that margin 0 is bit for bit the seen range.
            let (wlo, whi) = if margin > 0.0 {
                let w = margin * (hi - lo);
                (lo - w, hi + w)
            } else {
                (lo, hi)
            };
            match limits.and_then(|l| l.get(e)) {
                Some(&(min, max)) if wlo.max(min) <= whi.min(max) => (wlo.max(min), whi.min(max)),
                _ => (lo, hi),
            }
        })
        .collect();
    let moving: Vec<Vec<usize>> = joints(names)
        .into_iter()
        .filter(|j| j.iter().any(|&e| ranges[e].0 < ranges[e].1))
        .collect();
    let mut rng = XorShift::new(seed);
    (0..n)
        .map(|_| {
            let base = rng.below(frames.len());
            let mut pose = frames[base].clone();
            let mut pool: Vec<usize> = (0..moving.len()).collect();
            let k = (1 + rng.below(MAX_REDRAWN)).min(pool.len());
            let mut redrawn = Vec::with_capacity(k);
            for _ in 0..k {
                let joint = pool.swap_remove(rng.below(pool.len()));
                for &e in &moving[joint] {
                    let (lo, hi) = ranges[e];
                    pose[e] = (lo + rng.unit() * (hi - lo)).clamp(lo, hi);
                }
                redrawn.push(moving[joint].clone());
            }
            Sampled {
                base,
                redrawn,
                pose,
            }
        })
        .collect()
}

/// The clip of `n` poses sampled from `clips`' frames (see [`sample_poses`]), named
/// [`SAMPLED_CLIP`], at the first clip's rate; None when `n` is 0.
pub fn sampled_clip(
    names: &[String],
    clips: &[Clip],
    limits: Option<&[(f64, f64)]>,
    n: usize,
) -> Option<Clip> {
    clip_of(clips, SAMPLED_CLIP, |frames| {
        sample_poses(names, frames, limits, n, SEED, 0.0)
    })
}

/// The clip of `n` validation poses sampled from `clips`' frames (see [`validation_poses`]),
/// named [`VALIDATION_CLIP`], at the first clip's rate; None when `n` is 0. Never trained on:
/// it joins the validation clips.
pub fn validation_clip(
    names: &[String],
    clips: &[Clip],
    limits: Option<&[(f64, f64)]>,
    n: usize,
) -> Option<Clip> {
    clip_of(clips, VALIDATION_CLIP, |frames| {
        validation_poses(names, frames, limits, n)
    })
}

/// The clip `name` of the poses `sample` draws from all of `clips`' frames, at the first
/// clip's rate; None when it draws none.
fn clip_of(
    clips: &[Clip],
    name: &str,
    sample: impl FnOnce(&[Vec<f64>]) -> Vec<Vec<f64>>,
) -> Option<Clip> {
    let frames: Vec<Vec<f64>> = clips
        .iter()
        .flat_map(|c| c.frames.iter().cloned())
        .collect();
    let poses = sample(&frames);
    (!poses.is_empty()).then(|| Clip {
        name: name.to_owned(),
        fps: clips.first().map_or(30.0, |c| c.fps),
        frames: poses,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names() -> Vec<String> {
        ["a.x", "a.y", "a.z", "b.x", "b.y", "b.z", "elbow", "still"]
            .iter()
            .map(|s| s.to_string())
            .collect()
    }

    fn frames() -> Vec<Vec<f64>> {
        (0..20)
            .map(|f| {
                let t = f as f64;
                vec![
                    (t * 0.3).sin(),
                    0.1 * t,
                    -0.5,
                    (t * 0.7).cos() * 2.0,
                    0.0,
                    t * t * 0.01,
                    1.0 - 0.05 * t,
                    0.25,
                ]
            })
            .collect()
    }

    #[test]
    fn sampled_entries_lie_within_the_seen_range_and_the_rest_keep_a_base_frame() {
        let (names, frames) = (names(), frames());
        let poses = sample_poses(&names, &frames, None, 200, SEED, 0.0);
        assert_eq!(poses.len(), 200);
        let groups = joints(&names);
        assert_eq!(groups.len(), 4);
        for pose in &poses {
            for e in 0..names.len() {
                let lo = frames.iter().map(|f| f[e]).fold(f64::INFINITY, f64::min);
                let hi = frames
                    .iter()
                    .map(|f| f[e])
                    .fold(f64::NEG_INFINITY, f64::max);
                assert!((lo..=hi).contains(&pose[e]), "entry {e}: {}", pose[e]);
            }
            // Some training frame agrees with the pose on every joint not re-drawn, and
            // between 1 and 3 (moving) joints differ from it.
            let kept = |f: &Vec<f64>, j: &Vec<usize>| j.iter().all(|&e| f[e] == pose[e]);
            let best = frames
                .iter()
                .map(|f| groups.iter().filter(|j| !kept(f, j)).count())
                .min()
                .unwrap();
            assert!(best <= 3, "{best} joints differ from every frame");
            assert_eq!(pose[7], 0.25, "a joint that never moves is never re-drawn");
        }
    }

    #[test]
    fn joints_not_redrawn_keep_the_base_frame() {
        let (names, frames) = (names(), frames());
        let moving = 3; // a, b, elbow; "still" never moves
        for s in sample(&names, &frames, None, 200, SEED, 0.0) {
            assert!((1..=3).contains(&s.redrawn.len()));
            assert!(s.redrawn.iter().all(|j| !j.contains(&7)));
            for (e, v) in s.pose.iter().enumerate() {
                if !s.redrawn.iter().any(|j| j.contains(&e)) {
                    assert_eq!(*v, frames[s.base][e], "entry {e} not re-drawn changed");
                }
            }
            assert!(s.redrawn.len() <= moving);
        }
        // A single frame moves nothing, so nothing is re-drawn.
        let one = vec![frames[3].clone()];
        assert!(
            sample_poses(&names, &one, None, 10, SEED, 0.0)
                .iter()
                .all(|p| *p == one[0])
        );
    }

    #[test]
    fn the_same_seed_gives_the_same_poses_and_none_for_zero() {
        let (names, frames) = (names(), frames());
        let a = sample_poses(&names, &frames, None, 30, SEED, 0.0);
        let b = sample_poses(&names, &frames, None, 30, SEED, 0.0);
        assert_eq!(a, b);
        assert_ne!(a, sample_poses(&names, &frames, None, 30, SEED + 1, 0.0));
        assert!(sample_poses(&names, &frames, None, 0, SEED, 0.0).is_empty());
        let clips = [Clip {
            name: "t".into(),
            fps: 30.0,
            frames,
        }];
        assert!(sampled_clip(&names, &clips, None, 0).is_none());
        let clip = sampled_clip(&names, &clips, None, 8).unwrap();
        assert_eq!((clip.name.as_str(), clip.frames.len()), (SAMPLED_CLIP, 8));
    }

    #[test]
    fn limits_narrow_the_seen_range() {
        let (names, frames) = (names(), frames());
        let mut limits = vec![(-10.0, 10.0); names.len()];
        limits[6] = (0.5, 0.6); // elbow is seen over [0.05, 1.0]
        let poses = sample_poses(&names, &frames, Some(&limits), 300, SEED, 0.0);
        let drawn: Vec<f64> = poses
            .iter()
            .map(|p| p[6])
            .filter(|v| !frames.iter().any(|f| f[6] == *v))
            .collect();
        assert!(!drawn.is_empty());
        assert!(drawn.iter().all(|v| (0.5..=0.6).contains(v)));
    }

    /// Each entry's seen range over `frames`.
    fn seen(frames: &[Vec<f64>], e: usize) -> (f64, f64) {
        let lo = frames.iter().map(|f| f[e]).fold(f64::INFINITY, f64::min);
        let hi = frames
            .iter()
            .map(|f| f[e])
            .fold(f64::NEG_INFINITY, f64::max);
        (lo, hi)
    }

    #[test]
    fn validation_poses_lie_within_the_margin_and_the_limits_and_reach_beyond_training() {
        let (names, frames) = (names(), frames());
        let mut limits = vec![(-10.0, 10.0); names.len()];
        limits[6] = (0.0, 1.02); // elbow is seen over [0.05, 1.0]: the margin reaches past both
        let poses = validation_poses(&names, &frames, Some(&limits), 400);
        assert_eq!(poses.len(), 400);
        let mut beyond = 0;
        for pose in &poses {
            for (e, v) in pose.iter().enumerate() {
                let (lo, hi) = seen(&frames, e);
                let w = VALIDATION_MARGIN * (hi - lo);
                let (min, max) = limits[e];
                let (lo_m, hi_m) = ((lo - w).max(min), (hi + w).min(max));
                assert!(
                    (lo_m..=hi_m).contains(v),
                    "entry {e}: {v} not in [{lo_m}, {hi_m}]"
                );
                beyond += usize::from(*v < lo || *v > hi);
            }
            assert_eq!(pose[7], 0.25, "a joint that never moves is never re-drawn");
        }
        assert!(beyond > 0, "no validation pose left the training range");
        // The limit cuts the elbow's margin above, not below.
        let elbow: Vec<f64> = poses.iter().map(|p| p[6]).collect();
        assert!(elbow.iter().all(|v| *v <= 1.02));
        assert!(elbow.iter().any(|v| *v < 0.05));
        // Without limits, the full margin.
        for pose in validation_poses(&names, &frames, None, 200) {
            for (e, v) in pose.iter().enumerate() {
                let (lo, hi) = seen(&frames, e);
                let w = VALIDATION_MARGIN * (hi - lo);
                assert!((lo - w..=hi + w).contains(v), "entry {e}: {v}");
            }
        }
    }

    #[test]
    fn validation_poses_are_deterministic_differ_from_the_sampled_ones_and_none_for_zero() {
        let (names, frames) = (names(), frames());
        let a = validation_poses(&names, &frames, None, 50);
        assert_eq!(a, validation_poses(&names, &frames, None, 50));
        let sampled = sample_poses(&names, &frames, None, 50, SEED, 0.0);
        assert!(a.iter().all(|p| !sampled.contains(p)));
        assert!(validation_poses(&names, &frames, None, 0).is_empty());
        let clips = [Clip {
            name: "t".into(),
            fps: 24.0,
            frames,
        }];
        assert!(validation_clip(&names, &clips, None, 0).is_none());
        let clip = validation_clip(&names, &clips, None, 8).unwrap();
        assert_eq!(
            (clip.name.as_str(), clip.frames.len()),
            (VALIDATION_CLIP, 8)
        );
        assert_eq!(clip.fps, 24.0);
        assert_eq!(clip.frames[..], a[..8]);
        let train = sampled_clip(&names, &clips, None, 8).unwrap();
        assert!(clip.frames.iter().all(|p| !train.frames.contains(p)));
    }

    #[test]
    fn margin_zero_is_the_seen_range() {
        let (names, frames) = (names(), frames());
        let a = sample_poses(&names, &frames, None, 50, VALIDATION_SEED, 0.0);
        for pose in &a {
            for (e, v) in pose.iter().enumerate() {
                let (lo, hi) = seen(&frames, e);
                assert!((lo..=hi).contains(v));
            }
        }
    }
}
