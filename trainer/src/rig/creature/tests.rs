use glam::Vec3;

use super::*;
use crate::rig::character::CharacterError;
use crate::rig::mesh::Mesh;
use crate::rig::procedural::checks::assert_parts_closed_and_outward;
use crate::rig::{PoseError, Rig, RigError};

fn creature() -> Creature {
    Creature::builtin()
}

/// Lowest and highest corner of the mesh's bounding box.
fn bounds(mesh: &Mesh) -> (Vec3, Vec3) {
    mesh.positions.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), &p| (lo.min(Vec3::from(p)), hi.max(Vec3::from(p))),
    )
}

fn angle(c: &Creature, name: &str) -> usize {
    c.angle_names().iter().position(|n| n == name).unwrap()
}

#[test]
fn creature_builds_bit_identically() {
    let (a, b) = (creature(), creature());
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
    assert_eq!(a.clip("lash").unwrap(), b.clip("lash").unwrap());
    let frame = &a.training_clip().frames[100];
    assert_eq!(bits(&a.pose(frame).unwrap()), bits(&b.pose(frame).unwrap()));
}

#[test]
fn creature_sizes_and_names() {
    let c = creature();
    let v = c.bind_mesh().vertex_count();
    assert!((5_000..=10_000).contains(&v), "{v} vertices");
    assert_eq!(c.pose_len(), 34);
    let names = c.angle_names();
    let mut unique = names.clone();
    unique.sort_unstable();
    unique.dedup();
    assert_eq!(unique.len(), names.len(), "angle names are unique");
    for expected in [
        "neck_1_pitch",
        "head_yaw",
        "tail_1_yaw",
        "tail_6_pitch",
        "hr_knee_bend",
    ] {
        assert!(names.iter().any(|n| n == expected), "{expected} missing");
    }
    for a in c.joint_angles() {
        assert!(
            a.min < a.max && a.rest == 0.0 && a.min <= 0.0 && 0.0 <= a.max,
            "{a:?}"
        );
    }
    assert_eq!(c.limits().len(), c.pose_len());
    assert_eq!(c.skin().joint_count(), skeleton::joint::COUNT);
}

#[test]
fn creature_is_long_along_y_stands_on_the_ground_and_faces_minus_y() {
    let c = creature();
    let (lo, hi) = bounds(c.bind_mesh());
    let size = hi - lo;
    eprintln!("bounding box {lo} .. {hi}, size {size}");
    assert!(lo.z.abs() < 0.01, "feet at z = {}", lo.z);
    assert!((3.8..4.5).contains(&size.y), "length {}", size.y);
    assert!((1.1..1.4).contains(&size.z), "height {}", size.z);
    assert!(size.y >= 2.5 * size.x && size.y >= 2.5 * size.z, "{size}");
    assert!(
        (lo.x + hi.x).abs() < 1e-6,
        "left-right symmetric: {lo} .. {hi}"
    );
    // The head is the front (−y) and highest part; the tail reaches far behind (+y).
    let highest = c
        .bind_mesh()
        .positions
        .iter()
        .max_by(|a, b| a[2].total_cmp(&b[2]))
        .unwrap();
    assert!(highest[1] < -0.9, "highest point at {highest:?}");
    assert!(hi.y > 2.5 && lo.y < -1.3, "{lo} .. {hi}");
}

#[test]
fn creature_parts_are_closed_and_face_outward() {
    let c = creature();
    let mesh = c.bind_mesh();
    assert_parts_closed_and_outward(mesh, c.parts());
    assert_eq!(c.parts().count(), 4 + 3 * 4);
}

#[test]
fn creature_weights_are_partitions_of_unity_that_blend_along_the_tail() {
    let c = creature();
    let skin = c.skin();
    let mut blended = 0;
    for v in 0..skin.vertex_count() {
        let sum: f32 = skin.influences(v).map(|(_, w)| w).sum();
        assert!((sum - 1.0).abs() < 1e-5, "vertex {v} weights sum to {sum}");
        assert!(skin.influences(v).all(|(_, w)| w > 0.0));
        blended += usize::from(skin.influences(v).filter(|&(_, w)| w >= 0.2).count() >= 2);
    }
    let share = blended as f64 / skin.vertex_count() as f64;
    assert!(
        share > 0.15,
        "only {share:.3} of vertices blend two joints at ≥ 0.2"
    );
    // Every tail joint owns some of the tail.
    let (_, tail) = c.parts().find(|(n, _)| *n == "tail").unwrap();
    let tail_vertices: Vec<usize> = c.bind_mesh().triangles[tail]
        .iter()
        .flatten()
        .map(|&i| i as usize)
        .collect();
    for k in 0..skeleton::joint::TAIL_JOINTS {
        let joint = (skeleton::joint::TAIL + k) as u32;
        assert!(
            tail_vertices
                .iter()
                .any(|&v| skin.influences(v).any(|(j, w)| j == joint && w > 0.9)),
            "tail joint {k} owns no vertex"
        );
    }
}

#[test]
fn creature_rest_pose_is_the_bind_mesh() {
    let c = creature();
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

#[test]
fn creature_pose_rejects_bad_input() {
    let c = creature();
    let Err(RigError::Character(err)) = c.joint_matrices(&[0.0; 3]) else {
        panic!("a short pose must be a built-in character's error");
    };
    assert_eq!(
        err,
        CharacterError::Pose(PoseError::Length {
            expected: 34,
            got: 3
        })
    );
    let mut angles = c.rest_pose();
    angles[14] = f64::INFINITY;
    assert!(matches!(
        c.joint_matrices(&angles),
        Err(RigError::Character(CharacterError::Pose(
            PoseError::NonFinite { index: 14, .. }
        )))
    ));
}

#[test]
fn creature_angle_signs_match_the_documented_conventions() {
    // (angle, value, which bind vertices to watch, direction they must move). The creature
    // faces −y and its left is +x.
    type Region = fn(&[f32; 3]) -> bool;
    let tail_tip: Region = |p| p[1] > 2.4;
    let head: Region = |p| p[1] < -1.2;
    let fl_foot: Region = |p| p[0] > 0.0 && p[1] < 0.0 && p[2] < 0.1;
    let hl_foot: Region = |p| p[0] > 0.0 && p[1] > 0.0 && p[2] < 0.1;
    let cases: [(&str, f64, Region, Vec3); 8] = [
        ("tail_1_yaw", 0.4, tail_tip, Vec3::X),
        ("tail_3_pitch", 0.3, tail_tip, Vec3::Z),
        ("neck_1_pitch", 0.4, head, Vec3::Z),
        ("neck_1_yaw", 0.4, head, Vec3::X),
        ("spine_yaw", 0.25, head, Vec3::X),
        ("fl_hip_swing", 0.5, fl_foot, Vec3::NEG_Y),
        ("hl_knee_bend", 1.0, hl_foot, Vec3::Y),
        ("hl_hip_splay", 0.4, hl_foot, Vec3::X),
    ];
    let c = creature();
    let bind = c.bind_mesh();
    for (name, value, region, direction) in cases {
        let mut angles = c.rest_pose();
        angles[angle(&c, name)] = value;
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
            mean.dot(direction) > 0.5 * mean.length() && mean.length() > 0.05,
            "{name}: moved {mean}"
        );
    }
}

#[test]
fn creature_clips_are_named_smooth_and_inside_the_limits() {
    let c = creature();
    assert_eq!(c.clip_names(), ["training", "prowl", "lash", "crouch"]);
    let err = c.clip("dance").unwrap_err().to_string();
    assert!(err.contains("training, prowl, lash, crouch"), "{err}");
    let training = c.clip("training").unwrap();
    assert_eq!(training.frames.len(), 250);
    let others = c.novel_clips().into_iter().chain([c.validation_clip()]);
    for clip in std::iter::once(training).chain(others) {
        assert!((60..=250).contains(&clip.frames.len()), "{}", clip.name);
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

#[test]
fn creature_novel_and_validation_clips_are_not_training_poses() {
    // As the human's: ≥ 90 % of each clip's frames farther than 1 rad (over all angles) from
    // every training frame, so they test generalisation, not interpolation.
    let c = creature();
    let training = c.training_clip();
    for clip in c.novel_clips().into_iter().chain([c.validation_clip()]) {
        let far = clip
            .frames
            .iter()
            .filter(|f| {
                training.frames.iter().all(|t| {
                    let d2: f64 = t.iter().zip(f.iter()).map(|(a, b)| (a - b).powi(2)).sum();
                    d2 > 1.0
                })
            })
            .count();
        assert!(
            far as f64 >= 0.9 * clip.frames.len() as f64,
            "{}: {far}/{} far frames",
            clip.name,
            clip.frames.len()
        );
    }
}

#[test]
fn the_tail_tip_whips_and_curls_beside_the_body_in_lash() {
    let c = creature();
    let bind = c.bind_mesh();
    let tip: Vec<usize> = (0..bind.vertex_count())
        .filter(|&v| bind.positions[v][1] > 2.6)
        .collect();
    assert!(!tip.is_empty());
    let tip_at = |mesh: &Mesh| -> Vec3 {
        tip.iter()
            .map(|&v| Vec3::from(mesh.positions[v]))
            .sum::<Vec3>()
            / tip.len() as f32
    };
    let lash = c.clip("lash").unwrap();
    let tips: Vec<Vec3> = lash
        .frames
        .iter()
        .map(|f| tip_at(&c.pose(f).unwrap()))
        .collect();
    let (min_x, max_x) = tips
        .iter()
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p.x), hi.max(p.x))
        });
    // Whipping: the tip swings over a metre to either side.
    assert!(min_x < -1.0 && max_x > 1.0, "tip x in {min_x}..{max_x}");
    // Curled: at the end the tip has come forward, beside the body on its left, off the ground.
    let end = *tips.last().unwrap();
    assert!(
        end.x > 0.4 && end.y < 1.5 && end.z > 0.0,
        "tip ends at {end}"
    );
}
