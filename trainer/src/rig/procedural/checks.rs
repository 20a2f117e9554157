//! Assertions the built-in characters' tests share: what every [`BuiltinRig`] must satisfy,
//! written once; each character's tests add its own sizes, names and thresholds.

use std::ops::Range;

use glam::Vec3;

use super::{BuiltinRig, CharacterError, Spec};
use crate::rig::mesh::Mesh;
use crate::rig::{Clip, PoseError, Rig, RigError};

/// Asserts that each of `parts` (name and triangle range of `mesh`) is closed and consistently
/// wound (each directed edge once, its reverse once), encloses a positive volume (faces
/// outward), and that together they cover every triangle.
pub(crate) fn assert_parts_closed_and_outward(
    mesh: &Mesh,
    parts: impl Iterator<Item = (&'static str, Range<usize>)>,
) {
    let mut covered = 0;
    for (name, range) in parts {
        let triangles = &mesh.triangles[range.clone()];
        let mut directed: std::collections::HashMap<(u32, u32), usize> = Default::default();
        for t in triangles {
            for k in 0..3 {
                *directed.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
            }
        }
        for (&(a, b), &count) in &directed {
            assert_eq!(count, 1, "{name}: edge {a}->{b} used {count} times");
            assert_eq!(
                directed.get(&(b, a)),
                Some(&1),
                "{name}: {a}->{b} has no twin"
            );
        }
        let volume: f64 = triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| glam::Vec3::from(mesh.positions[i as usize]).as_dvec3());
                a.dot(b.cross(c)) / 6.0
            })
            .sum();
        assert!(volume > 0.0, "{name}: signed volume {volume}");
        covered += range.len();
    }
    assert_eq!(covered, mesh.triangles.len());
}

/// Asserts that two builds give bit-identical bind meshes, skins and clips, and pose a training
/// frame bit-identically.
pub(crate) fn assert_builds_bit_identically<S: Spec>() {
    let (a, b) = (BuiltinRig::<S>::builtin(), BuiltinRig::<S>::builtin());
    let bits = |m: &Mesh| -> Vec<u32> {
        m.positions
            .iter()
            .chain(&m.normals)
            .flatten()
            .map(|v| v.to_bits())
            .collect()
    };
    assert_eq!(bits(a.bind_mesh()), bits(b.bind_mesh()));
    assert_eq!(a.bind_mesh().triangles, b.bind_mesh().triangles);
    assert_eq!(a.skin(), b.skin());
    for name in a.clip_names() {
        assert_eq!(a.clip(&name).unwrap(), b.clip(&name).unwrap());
    }
    let frame = &a.training_clip().frames[100];
    assert_eq!(bits(&a.pose(frame).unwrap()), bits(&b.pose(frame).unwrap()));
}

/// Asserts that the angle names are unique, each angle's rest lies within its limits, and
/// [`BuiltinRig::limits`] lists them all.
pub(crate) fn assert_angles_are_unique_and_within_limits<S: Spec>(c: &BuiltinRig<S>) {
    let names = c.angle_names();
    let mut unique = names.clone();
    unique.sort_unstable();
    unique.dedup();
    assert_eq!(unique.len(), names.len(), "angle names are unique");
    for a in c.joint_angles() {
        assert!(a.min < a.max && (a.min..=a.max).contains(&a.rest), "{a:?}");
    }
    assert_eq!(c.limits().len(), c.pose_len());
}

/// Asserts that every vertex's weights are positive and sum to 1, and returns the share of
/// vertices that blend two joints at ≥ 0.2 each.
pub(crate) fn blended_share<S: Spec>(c: &BuiltinRig<S>) -> f64 {
    let skin = c.skin();
    let mut blended = 0;
    for v in 0..skin.vertex_count() {
        let sum: f32 = skin.influences(v).map(|(_, w)| w).sum();
        assert!((sum - 1.0).abs() < 1e-5, "vertex {v} weights sum to {sum}");
        assert!(skin.influences(v).all(|(_, w)| w > 0.0));
        blended += usize::from(skin.influences(v).filter(|&(_, w)| w >= 0.2).count() >= 2);
    }
    blended as f64 / skin.vertex_count() as f64
}

/// Asserts that posing the rest pose gives back the bind mesh.
pub(crate) fn assert_rest_pose_is_the_bind_mesh<S: Spec>(c: &BuiltinRig<S>) {
    let posed = c.pose(&c.rest_pose()).unwrap();
    let bind = c.bind_mesh();
    for (p, q) in posed
        .positions
        .iter()
        .zip(&bind.positions)
        .chain(posed.normals.iter().zip(&bind.normals))
    {
        assert!(
            (Vec3::from(*p) - Vec3::from(*q)).length() < 1e-5,
            "{p:?} vs {q:?}"
        );
    }
    assert_eq!(posed.triangles, bind.triangles);
}

/// Asserts that a short pose, and one whose angle `bad` is `value` (not finite), are refused
/// with the built-in characters' error.
pub(crate) fn assert_pose_rejects_bad_input<S: Spec>(c: &BuiltinRig<S>, bad: usize, value: f64) {
    let Err(RigError::Character(err)) = c.joint_matrices(&[0.0; 3]) else {
        panic!("a short pose must be a built-in character's error");
    };
    assert_eq!(
        err,
        CharacterError::Pose(PoseError::Length {
            expected: c.pose_len(),
            got: 3
        })
    );
    let mut angles = c.rest_pose();
    angles[bad] = value;
    assert!(matches!(
        c.joint_matrices(&angles),
        Err(RigError::Character(CharacterError::Pose(
            PoseError::NonFinite { index, .. }
        ))) if index == bad
    ));
}

/// Asserts that every clip is named as [`Rig::clip_names`] says (`names`, which an unknown
/// clip's error lists), runs at 30 fps inside the limits, moves no angle faster than 6 rad/s
/// (0.2 rad per frame, about a brisk hand wave, the fastest motion here), and that the training
/// clip has 250 frames and each other clip a number in `frames`.
pub(crate) fn assert_clips_are_named_smooth_and_inside_the_limits<S: Spec>(
    c: &BuiltinRig<S>,
    names: &[&str],
    frames: Range<usize>,
) {
    assert_eq!(c.clip_names(), names);
    let err = c.clip("dance").unwrap_err().to_string();
    assert!(
        err.contains("dance") && err.contains(&names.join(", ")),
        "{err}"
    );
    let training = c.clip("training").unwrap();
    assert_eq!(training.frames.len(), 250);
    let others = c.novel_clips().into_iter().chain([c.validation_clip()]);
    for clip in std::iter::once(training).chain(others) {
        if clip.name != "training" {
            assert!(
                frames.contains(&clip.frames.len()),
                "{}: {} frames",
                clip.name,
                clip.frames.len()
            );
        }
        assert_eq!(clip.fps, 30.0);
        for (f, frame) in clip.frames.iter().enumerate() {
            assert_eq!(frame.len(), c.pose_len());
            for (value, a) in frame.iter().zip(c.joint_angles()) {
                assert!(
                    (a.min..=a.max).contains(value),
                    "{} frame {f}: {} = {value}",
                    clip.name,
                    a.name
                );
            }
        }
        for pair in clip.frames.windows(2) {
            let step = pair[0]
                .iter()
                .zip(&pair[1])
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            assert!(step < 0.2, "{}: step {step}", clip.name);
        }
    }
}

/// Smallest Euclidean distance (radians, over all angles) from `frame` to a training frame.
fn nearest_training_distance(training: &Clip, frame: &[f64]) -> f64 {
    training
        .frames
        .iter()
        .map(|t| {
            t.iter()
                .zip(frame)
                .map(|(a, b)| (a - b) * (a - b))
                .sum::<f64>()
                .sqrt()
        })
        .fold(f64::INFINITY, f64::min)
}

/// Asserts that ≥ 90% of each novel and validation clip's frames are farther than 1 rad (over
/// all angles) from every training frame: a pose that close would test interpolation between
/// neighbours, not generalisation.
pub(crate) fn assert_novel_and_validation_clips_are_not_training_poses<S: Spec>(c: &BuiltinRig<S>) {
    let training = c.training_clip();
    for clip in c.novel_clips().into_iter().chain([c.validation_clip()]) {
        let distances: Vec<f64> = clip
            .frames
            .iter()
            .map(|f| nearest_training_distance(&training, f))
            .collect();
        let far = distances.iter().filter(|&&d| d > 1.0).count();
        let min = distances.iter().copied().fold(f64::INFINITY, f64::min);
        eprintln!(
            "{}: min distance {min:.3}, {far}/{} frames beyond 1 rad",
            clip.name,
            distances.len()
        );
        assert!(
            far as f64 >= 0.9 * distances.len() as f64,
            "{}: {far}/{} far frames",
            clip.name,
            distances.len()
        );
    }
}

/// Which bind vertices a sign-convention case watches.
pub(crate) type Region = fn(&[f32; 3]) -> bool;

/// Asserts, for each `(angle, value, region, direction)`, that setting the angle to the value
/// moves the region's bind vertices on average along `direction` (within 60°), by more than
/// `min_move` metres.
pub(crate) fn assert_angles_move_as_documented<S: Spec>(
    c: &BuiltinRig<S>,
    cases: &[(&str, f64, Region, Vec3)],
    min_move: f32,
) {
    let bind = c.bind_mesh();
    for &(name, value, region, direction) in cases {
        let mut angles = c.rest_pose();
        angles[c.angle_names().iter().position(|n| n == name).unwrap()] = value;
        let posed = c.pose(&angles).unwrap();
        let (sum, count) = bind
            .positions
            .iter()
            .zip(&posed.positions)
            .filter(|(p, _)| region(p))
            .fold((Vec3::ZERO, 0), |(s, n), (p, q)| {
                (s + Vec3::from(*q) - Vec3::from(*p), n + 1)
            });
        assert!(count > 0, "{name}: empty region");
        let mean = sum / count as f32;
        assert!(
            mean.dot(direction) > 0.5 * mean.length() && mean.length() > min_move,
            "{name}: moved {mean}"
        );
    }
}

/// Asserts that `rig` lays out each of `parts` (name and triangle range of its bind mesh) as a
/// chart of its own: a UV for every corner, inside `[0,1]²`; no texel centre strictly inside
/// two triangles at 256²; and, with every sample holding its part's number, bilinear sampling
/// of the gathered map at every corner returns exactly that number, so the padding keeps each
/// chart's gutters clear of its neighbours'.
pub(crate) fn assert_charts_apart<'a>(
    rig: &dyn Rig,
    parts: impl Iterator<Item = (&'a str, Range<usize>)>,
) {
    use crate::rig::uv::{Atlas, sample_bilinear};
    let triangles = &rig.bind_mesh().triangles;
    let layout = rig.uv_layout().expect("a lathe body has a UV layout");
    assert_eq!(layout.corners.len(), triangles.len());
    for (t, c) in layout.corners.iter().enumerate() {
        assert!(
            c.iter().flatten().all(|x| (0.0..=1.0).contains(x)),
            "triangle {t}: {c:?}"
        );
    }
    let mut part_of = vec![usize::MAX; triangles.len()];
    let mut names = Vec::new();
    for (k, (name, range)) in parts.enumerate() {
        part_of[range].fill(k);
        names.push(name);
    }
    assert!(part_of.iter().all(|&k| k != usize::MAX));
    let resolution = 256;
    let atlas = Atlas::build(layout, triangles, resolution).unwrap();
    assert_eq!(atlas.overlapping_texels(), 0);
    let values: Vec<f32> = (atlas.samples().iter())
        .map(|s| part_of[s.triangle as usize] as f32)
        .collect();
    let map = atlas.gather(&values, 1);
    for (t, corners) in layout.corners.iter().enumerate() {
        for &uv in corners {
            let mut out = [0.0];
            sample_bilinear(&map, resolution, 1, uv, &mut out);
            let part = part_of[t];
            assert_eq!(
                out[0], part as f32,
                "triangle {t} of {} at {uv:?}",
                names[part]
            );
        }
    }
}
