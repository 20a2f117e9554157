use glam::Vec3;

use super::*;
use crate::rig::Rig;
use crate::rig::mesh::Mesh;
use crate::rig::procedural::checks::{self, Region, assert_parts_closed_and_outward};

fn creature() -> Creature {
    Creature::builtin()
}

#[test]
fn creature_charts_are_packed_apart() {
    let c = creature();
    checks::assert_charts_apart(&c, c.parts());
}

#[test]
fn creature_builds_bit_identically() {
    checks::assert_builds_bit_identically::<Lizard>();
}

/// Lowest and highest corner of the mesh's bounding box.
fn bounds(mesh: &Mesh) -> (Vec3, Vec3) {
    mesh.positions.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), &p| (lo.min(Vec3::from(p)), hi.max(Vec3::from(p))),
    )
}

#[test]
fn creature_sizes_and_names() {
    let c = creature();
    let v = c.bind_mesh().vertex_count();
    assert!((5_000..=10_000).contains(&v), "{v} vertices");
    assert_eq!(c.pose_len(), 34);
    checks::assert_angles_are_unique_and_within_limits(&c);
    let names = c.angle_names();
    for expected in [
        "neck_1_pitch",
        "head_yaw",
        "tail_1_yaw",
        "tail_6_pitch",
        "hr_knee_bend",
    ] {
        assert!(names.iter().any(|n| n == expected), "{expected} missing");
    }
    assert!(c.joint_angles().iter().all(|a| a.rest == 0.0));
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
    let share = checks::blended_share(&c);
    assert!(
        share > 0.15,
        "only {share:.3} of vertices blend two joints at ≥ 0.2"
    );
    // Every tail joint owns some of the tail.
    let skin = c.skin();
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
    checks::assert_rest_pose_is_the_bind_mesh(&creature());
}

#[test]
fn creature_pose_rejects_bad_input() {
    checks::assert_pose_rejects_bad_input(&creature(), 14, f64::INFINITY);
}

#[test]
fn creature_angle_signs_match_the_documented_conventions() {
    // The creature faces −y and its left is +x.
    let tail_tip: Region = |p| p[1] > 2.4;
    let head: Region = |p| p[1] < -1.2;
    let fl_foot: Region = |p| p[0] > 0.0 && p[1] < 0.0 && p[2] < 0.1;
    let hl_foot: Region = |p| p[0] > 0.0 && p[1] > 0.0 && p[2] < 0.1;
    let cases = [
        ("tail_1_yaw", 0.4, tail_tip, Vec3::X),
        ("tail_3_pitch", 0.3, tail_tip, Vec3::Z),
        ("neck_1_pitch", 0.4, head, Vec3::Z),
        ("neck_1_yaw", 0.4, head, Vec3::X),
        ("spine_yaw", 0.25, head, Vec3::X),
        ("fl_hip_swing", 0.5, fl_foot, Vec3::NEG_Y),
        ("hl_knee_bend", 1.0, hl_foot, Vec3::Y),
        ("hl_hip_splay", 0.4, hl_foot, Vec3::X),
    ];
    checks::assert_angles_move_as_documented(&creature(), &cases, 0.05);
}

#[test]
fn creature_clips_are_named_smooth_and_inside_the_limits() {
    checks::assert_clips_are_named_smooth_and_inside_the_limits(
        &creature(),
        &["training", "prowl", "lash", "crouch"],
        60..251,
    );
}

#[test]
fn creature_novel_and_validation_clips_are_not_training_poses() {
    checks::assert_novel_and_validation_clips_are_not_training_poses(&creature());
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
