use super::*;
use crate::rig::mesh::Mesh;
use crate::rig::procedural::checks::assert_parts_closed_and_outward;
use crate::rig::{PoseError, Rig, RigError};

fn character() -> Character {
    Character::builtin()
}

#[test]
fn character_builds_bit_identically() {
    let (a, b) = (character(), character());
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
    let frame = &a.training_clip().frames[100];
    assert_eq!(bits(&a.pose(frame).unwrap()), bits(&b.pose(frame).unwrap()));
}

#[test]
fn character_sizes_are_in_range() {
    let c = character();
    let v = c.bind_mesh().vertex_count();
    assert!((10_000..=25_000).contains(&v), "{v} vertices");
    assert!(c.pose_len() >= 20);
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

#[test]
fn character_stands_on_the_ground_facing_minus_y() {
    let c = character();
    let p = &c.bind_mesh().positions;
    let min_z = p.iter().map(|p| p[2]).fold(f32::INFINITY, f32::min);
    let max_z = p.iter().map(|p| p[2]).fold(f32::NEG_INFINITY, f32::max);
    assert!(min_z.abs() < 0.01, "feet at z = {min_z}");
    assert!((1.7..2.1).contains(&max_z), "top of the hat at z = {max_z}");
    // Below the hat, the nose and the toes are the frontmost points: they are at negative y.
    let body = || p.iter().filter(|p| p[2] < 1.75).map(|p| p[1]);
    let min_y = body().fold(f32::INFINITY, f32::min);
    let max_y = body().fold(f32::NEG_INFINITY, f32::max);
    assert!(min_y < -0.15 && max_y < 0.12, "front {min_y}, back {max_y}");
    // The hat brim reaches past the shoulders, so it shadows them.
    let brim = p
        .iter()
        .filter(|p| p[2] > 1.7)
        .map(|p| p[0].abs())
        .fold(0.0, f32::max);
    assert!(brim > 0.3, "brim radius {brim}");
}

#[test]
fn character_weights_are_normalised_and_blend_across_joints() {
    let c = character();
    let skin = c.skin();
    let mut blended = 0;
    for v in 0..skin.vertex_count() {
        let sum: f32 = skin.influences(v).map(|(_, w)| w).sum();
        assert!((sum - 1.0).abs() < 1e-5, "vertex {v} weights sum to {sum}");
        assert!(skin.influences(v).all(|(_, w)| w > 0.0));
        blended += usize::from(skin.influences(v).filter(|&(_, w)| w >= 0.2).count() >= 2);
    }
    // Blend regions are ±3–8 cm around each joint: a substantial share of the surface.
    let share = blended as f64 / skin.vertex_count() as f64;
    assert!(
        share > 0.1,
        "only {share:.3} of vertices blend two joints at ≥ 0.2"
    );
    assert_eq!(skin.joint_count(), skeleton::joint::COUNT);
}

/// The height mannequins scale the head and hat by is the built-in character's: soles on
/// z = 0, the head's top at `CROWN`.
#[test]
fn the_crown_is_the_top_of_the_head() {
    let c = character();
    let mesh = c.bind_mesh();
    let z = |part: &str| -> (f32, f32) {
        let (_, range) = c.parts().find(|(n, _)| *n == part).unwrap();
        let zs = mesh.triangles[range].iter().flatten();
        zs.map(|&i| mesh.positions[i as usize][2])
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), z| {
                (lo.min(z), hi.max(z))
            })
    };
    assert!((z("head").1 as f64 - body::CROWN).abs() < 1e-6);
    assert_eq!(z("l_foot").0, 0.0);
}

#[test]
fn character_parts_are_closed_and_face_outward() {
    let c = character();
    let mesh = c.bind_mesh();
    assert_parts_closed_and_outward(mesh, c.parts());
    // Vertex normals agree with the outward faces around them.
    for t in &mesh.triangles {
        let [a, b, cc] = t.map(|i| glam::Vec3::from(mesh.positions[i as usize]));
        let face = (b - a).cross(cc - a);
        let n: glam::Vec3 = t
            .iter()
            .map(|&i| glam::Vec3::from(mesh.normals[i as usize]))
            .sum();
        assert!(
            face.dot(n) >= 0.0,
            "triangle {t:?} faces against its vertex normals"
        );
    }
}

#[test]
fn character_rest_pose_is_the_bind_mesh() {
    let c = character();
    let posed = c.pose(&c.rest_pose()).unwrap();
    let bind = c.bind_mesh();
    for (p, q) in posed
        .positions
        .iter()
        .zip(&bind.positions)
        .chain(posed.normals.iter().zip(&bind.normals))
    {
        assert!(
            (glam::Vec3::from(*p) - glam::Vec3::from(*q)).length() < 1e-5,
            "{p:?} vs {q:?}"
        );
    }
    assert_eq!(posed.triangles, bind.triangles);
}

#[test]
fn character_angles_move_the_expected_side() {
    // Bending the left elbow moves the left hand (+x) and leaves the right hand alone.
    let c = character();
    let mut angles = c.rest_pose();
    let elbow = c
        .angle_names()
        .iter()
        .position(|n| *n == "l_elbow_flex")
        .unwrap();
    angles[elbow] = 1.5;
    let posed = c.pose(&angles).unwrap();
    let bind = c.bind_mesh();
    let moved = |side: f32| {
        bind.positions
            .iter()
            .zip(&posed.positions)
            .filter(|(p, _)| p[0] * side > 0.6)
            .map(|(p, q)| (glam::Vec3::from(*p) - glam::Vec3::from(*q)).length())
            .fold(0.0, f32::max)
    };
    assert!(moved(1.0) > 0.2, "left hand moved {}", moved(1.0));
    assert_eq!(moved(-1.0), 0.0);
    // Forward is −y: the left hand swings to negative y.
    let hand_y = bind
        .positions
        .iter()
        .zip(&posed.positions)
        .filter(|(p, _)| p[0] > 0.6)
        .map(|(_, q)| q[1]);
    assert!(hand_y.fold(f32::INFINITY, f32::min) < -0.2);
    for n in &posed.normals {
        assert!((glam::Vec3::from(*n).length() - 1.0).abs() < 1e-5);
    }
}

#[test]
fn character_pose_rejects_bad_input() {
    let c = character();
    let Err(RigError::Character(err)) = c.joint_matrices(&[0.0; 3]) else {
        panic!("a short pose must be the character's error");
    };
    assert_eq!(
        err,
        CharacterError::Pose(PoseError::Length {
            expected: c.pose_len(),
            got: 3
        })
    );
    let mut angles = c.rest_pose();
    angles[4] = f64::NAN;
    assert!(matches!(
        c.joint_matrices(&angles),
        Err(RigError::Character(CharacterError::Pose(
            PoseError::NonFinite { index: 4, .. }
        )))
    ));
}

#[test]
fn character_clips_are_named_smooth_and_inside_the_limits() {
    let c = character();
    assert_eq!(
        c.clip_names(),
        ["training", "wave", "walk", "reach", "stretch"]
    );
    let err = c.clip("dance").unwrap_err().to_string();
    assert!(
        err.contains("dance") && err.contains("training, wave, walk, reach, stretch"),
        "{err}"
    );
    let training = c.clip("training").unwrap();
    assert_eq!(training.frames.len(), 250);
    let others = c.novel_clips().into_iter().chain([c.validation_clip()]);
    for clip in std::iter::once(training).chain(others) {
        if clip.name != "training" {
            assert!(
                (60..=120).contains(&clip.frames.len()),
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
        // Smooth like animation: no angle moves faster than 6 rad/s (0.2 rad per frame), about
        // the speed of a brisk hand wave, the fastest motion here.
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

#[test]
fn character_novel_and_validation_clips_are_not_training_poses() {
    // Threshold 1 rad over all 23 angles (e.g. 0.2 rad on each of 23): a pose that close to a
    // training frame would test interpolation between neighbours, not generalisation.
    // ≥ 90% of each novel clip must be farther (measured: every frame is, the closest at
    // 1.5 rad, in walk).
    let c = character();
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

#[test]
fn character_angle_signs_match_the_documented_conventions() {
    // (angle, value, which bind vertices to watch, direction they must move). The character
    // faces −y and its left is +x.
    type Region = fn(&[f32; 3]) -> bool;
    let left_hand: Region = |p| p[0] > 0.55;
    let right_hand: Region = |p| p[0] < -0.55;
    let left_foot: Region = |p| p[0] > 0.0 && p[2] < 0.1;
    let head: Region = |p| p[2] > 1.6 && p[0].abs() < 0.1 && p[1].abs() < 0.1;
    let nose: Region = |p| p[1] < -0.11 && (1.65..1.73).contains(&p[2]);
    let cases: [(&str, f64, Region, glam::Vec3); 7] = [
        ("l_shoulder_flex", 1.2, left_hand, glam::Vec3::NEG_Y),
        ("r_shoulder_abduct", 2.2, right_hand, glam::Vec3::Z),
        ("l_knee_flex", 1.2, left_foot, glam::Vec3::Y),
        (
            "l_ankle_flex",
            0.4,
            |p| p[0] > 0.0 && p[1] < -0.1 && p[2] < 0.1,
            glam::Vec3::Z,
        ),
        ("spine_flex", 0.5, head, glam::Vec3::NEG_Y),
        ("spine_lean", 0.3, head, glam::Vec3::X),
        ("neck_twist", 0.6, nose, glam::Vec3::X),
    ];
    let c = character();
    let bind = c.bind_mesh();
    for (name, value, region, direction) in cases {
        let mut angles = c.rest_pose();
        angles[c.angle_names().iter().position(|n| *n == name).unwrap()] = value;
        let posed = c.pose(&angles).unwrap();
        let (sum, count) = bind
            .positions
            .iter()
            .zip(&posed.positions)
            .filter(|(p, _)| region(p))
            .fold((glam::Vec3::ZERO, 0), |(s, n), (p, q)| {
                (s + glam::Vec3::from(*q) - glam::Vec3::from(*p), n + 1)
            });
        assert!(count > 0, "{name}: empty region");
        let mean = sum / count as f32;
        assert!(
            mean.dot(direction) > 0.5 * mean.length() && mean.length() > 0.02,
            "{name}: moved {mean}"
        );
    }
}
