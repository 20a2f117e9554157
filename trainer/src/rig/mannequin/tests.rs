use std::path::Path;

use glam::{DVec3, Vec3};

use super::*;

const ZYX: &str = "CHANNELS 3 Zrotation Yrotation Xrotation";

/// A small figure: a zero-length hip joint (as in CMU files) above a two-bone leg, and a
/// spine with a head: 6 joints, 21 channels, three frames; frame 2 bends the knee 90°.
fn figure() -> String {
    format!(
        "HIERARCHY
ROOT Hips
{{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation
  JOINT LHipJoint
  {{
    OFFSET 0 0 0
    {ZYX}
    JOINT LeftUpLeg
    {{
      OFFSET 1 -1 0
      {ZYX}
      JOINT LeftLeg
      {{
        OFFSET 0 -7 0
        {ZYX}
        End Site
        {{
          OFFSET 0 -7 0
        }}
      }}
    }}
  }}
  JOINT Spine
  {{
    OFFSET 0 3 0
    {ZYX}
    JOINT Head
    {{
      OFFSET 0 4 0
      {ZYX}
      End Site
      {{
        OFFSET 0 2 0
      }}
    }}
  }}
}}
MOTION
Frames: 3
Frame Time: 0.1
0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0
5 1 2 10 20 30 0 0 0 -10 0 5 0 0 0 0 15 0 0 0 0
5 1 2 0 0 0 0 0 0 0 0 0 90 0 0 0 0 0 0 0 0
"
    )
}

fn rig(options: &MocapOptions) -> MocapRig {
    let mocap = Mocap::parse(&figure(), Path::new("figure.bvh")).unwrap();
    MocapRig::from_mocap(mocap, "figure", options).unwrap()
}

#[test]
fn mannequin_charts_are_packed_apart() {
    for hat in [true, false] {
        let r = rig(&MocapOptions {
            hat,
            ..MocapOptions::default()
        });
        crate::rig::procedural::checks::assert_charts_apart(&r, r.parts());
    }
}

#[test]
fn pose_vector_lists_every_rotating_joint_and_root_translation_on_request() {
    let plain = rig(&MocapOptions::default());
    let names = plain.angle_names();
    assert_eq!(names.len(), 18);
    assert_eq!(&names[..4], ["Hips.x", "Hips.y", "Hips.z", "LHipJoint.x"]);
    let moving = rig(&MocapOptions {
        root_translation: true,
        ..MocapOptions::default()
    });
    assert_eq!(
        &moving.angle_names()[..4],
        ["Hips.tx", "Hips.ty", "Hips.tz", "Hips.x"]
    );
    assert_eq!(&moving.frame_pose(1)[..3], [5.0, 1.0, 2.0]);
    // Rest pose: identity skinning matrices, so the bind mesh.
    for m in plain.joint_matrices(&[0.0; 18]).unwrap() {
        assert!(m.abs_diff_eq(Mat4::IDENTITY, 1e-6));
    }
    // A 90° knee (LeftLeg Zrotation) is the rotation vector (0, 0, π/2).
    let knee = plain.frame_pose(2);
    assert!(
        DVec3::from_slice(&knee[9..12])
            .abs_diff_eq(DVec3::new(0.0, 0.0, std::f64::consts::FRAC_PI_2), 1e-12)
    );
}

#[test]
fn pose_errors_name_the_entry() {
    let r = rig(&MocapOptions::default());
    assert_eq!(
        r.joint_matrices(&[0.0; 3]).unwrap_err().to_string(),
        "a pose needs 18 values, got 3"
    );
    let mut pose = vec![0.0; 18];
    pose[10] = f64::NAN;
    assert_eq!(
        r.joint_matrices(&pose).unwrap_err().to_string(),
        "pose value 10 (LeftLeg.y) is NaN, not a finite number"
    );
    assert_eq!(
        r.clip("walk").unwrap_err().to_string(),
        "no clip named \"walk\"; available: figure"
    );
    let mocap = Mocap::parse(&figure(), Path::new("figure.bvh")).unwrap();
    let err = MocapRig::from_mocap(
        mocap,
        "figure",
        &MocapOptions {
            fps: Some(0.0),
            ..MocapOptions::default()
        },
    )
    .unwrap_err();
    assert_eq!(
        err.to_string(),
        "frame rate 0 is not a positive finite number"
    );
    // A finite but absurd rate is refused before anything is allocated.
    let fast = rig(&MocapOptions {
        fps: Some(1e12),
        ..MocapOptions::default()
    });
    assert!(
        matches!(
            fast.clip("figure"),
            Err(e) if e.to_string().contains("frames, more than the 10000 one run bakes or evaluates")
        ),
        "an unbounded resampling must be refused"
    );
}

#[test]
fn mannequin_skips_zero_length_bones_and_blends_across_joints() {
    let r = rig(&MocapOptions::default());
    let names: Vec<&str> = r.parts().map(|(n, _)| n).collect();
    assert_eq!(
        names,
        [
            "LHipJoint-LeftUpLeg",
            "LeftUpLeg-LeftLeg",
            "LeftLeg-end",
            "Hips-Spine",
            "Spine-Head",
            "head",
            "nose",
            "hat"
        ]
    );
    assert!((r.height() - 24.0).abs() < 1e-9, "height {}", r.height());
    let mesh = r.bind_mesh();
    let skin = r.skin();
    let mut two = 0;
    for v in 0..skin.vertex_count() {
        let sum: f32 = skin.influences(v).map(|(_, w)| w).sum();
        assert!((sum - 1.0).abs() < 1e-5);
        two += usize::from(skin.influences(v).count() >= 2);
        assert!((Vec3::from(mesh.normals[v]).length() - 1.0).abs() < 1e-5);
    }
    assert!(two * 10 > skin.vertex_count(), "{two} blended vertices");
    // The bone under the zero-length LHipJoint blends upstream into Hips (joint 0), the
    // joint LHipJoint sits on.
    let hip_bone = r.parts().next().unwrap().1;
    let touches_hips = mesh.triangles[hip_bone]
        .iter()
        .flatten()
        .any(|&v| skin.influences(v as usize).any(|(j, _)| j == 0));
    assert!(touches_hips);
    // Bending the knee moves the shin and leaves the head alone.
    let posed = r.pose(&r.frame_pose(2)).unwrap();
    let moved = |keep: fn(&[f32; 3]) -> bool| {
        mesh.positions
            .iter()
            .zip(&posed.positions)
            .filter(|(p, _)| keep(p))
            .map(|(p, q)| (Vec3::from(*p) - Vec3::from(*q)).length())
            .fold(0.0, f32::max)
    };
    assert!(moved(|p| p[2] < -12.0) > 3.0);
    assert_eq!(moved(|p| p[2] > 4.0), 0.0);

    let bare = rig(&MocapOptions {
        hat: false,
        ..MocapOptions::default()
    });
    assert!(bare.parts().all(|(n, _)| n != "hat"));
    assert!(bare.bind_mesh().vertex_count() < mesh.vertex_count());
}

#[test]
fn skeletons_without_bones_and_motions_without_shared_joints_are_refused() {
    let point = "HIERARCHY\nROOT A\n{\n OFFSET 0 0 0\n CHANNELS 3 Xrotation Yrotation Zrotation\n}\n\
                 MOTION\nFrames: 1\nFrame Time: 0.1\n0 0 0\n";
    let mocap = Mocap::parse(point, Path::new("point.bvh")).unwrap();
    assert_eq!(
        MocapRig::from_mocap(mocap.clone(), "point", &MocapOptions::default())
            .unwrap_err()
            .to_string(),
        "the skeleton of \"point\" has no bone of nonzero length"
    );
    let r = rig(&MocapOptions::default());
    assert_eq!(
        r.retarget(&mocap, "point", 0..1).unwrap_err().to_string(),
        "no joint of \"point\" has the name of a joint of this mannequin"
    );
}

/// A BVH skeleton: `joints` (name, parent, offset) with three rotation channels each, one
/// End Site on the last, and one frame of zeros.
fn skeleton_text(joints: &[(String, Option<usize>, [f64; 3])]) -> String {
    let mut text = String::from("HIERARCHY\n");
    let mut open: Vec<usize> = Vec::new();
    for (j, (name, parent, [x, y, z])) in joints.iter().enumerate() {
        while open.last().is_some_and(|&o| Some(o) != *parent) {
            text += "}\n";
            open.pop();
        }
        let kind = if parent.is_none() { "ROOT" } else { "JOINT" };
        text += &format!("{kind} {name}\n{{\nOFFSET {x} {y} {z}\n");
        text += "CHANNELS 3 Zrotation Xrotation Yrotation\n";
        open.push(j);
    }
    text += "End Site\n{\nOFFSET 0 1 0\n}\n";
    text += &"}\n".repeat(open.len());
    text += &format!(
        "MOTION\nFrames: 1\nFrame Time: 0.1\n{}\n",
        vec!["0"; 3 * joints.len()].join(" ")
    );
    text
}

#[test]
fn skeletons_a_model_cannot_hold_are_refused_before_any_surface_is_made() {
    let chain: Vec<_> = (0..=MAX_JOINTS)
        .map(|j| (format!("j{j}"), j.checked_sub(1), [0.0, 1.0, 0.0]))
        .collect();
    let mocap = Mocap::parse(&skeleton_text(&chain), Path::new("chain.bvh")).unwrap();
    let err = MocapRig::from_mocap(mocap, "chain", &MocapOptions::default()).unwrap_err();
    assert!(
        matches!(err, MocapRigError::TooManyJoints { joints: 257, .. }),
        "{err}"
    );
    // One bone 10⁵ units long under a skeleton 0.01 units tall: rings every 1.7e-4 units.
    let long = [
        ("root".to_owned(), None, [0.0; 3]),
        ("arm".to_owned(), Some(0), [1e5, 0.0, 0.0]),
    ];
    let text = skeleton_text(&long).replace("OFFSET 0 1 0", "OFFSET 0 0.01 0");
    let mocap = Mocap::parse(&text, Path::new("long.bvh")).unwrap();
    let err = MocapRig::from_mocap(mocap, "long", &MocapOptions::default()).unwrap_err();
    match err {
        MocapRigError::TooManyVertices { vertices, .. } => assert!(vertices > 1 << 30),
        other => panic!("{other}"),
    }
}
