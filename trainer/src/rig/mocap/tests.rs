use std::path::Path;

use glam::{DMat3, DVec3};

use super::*;

/// Three joints: a root with six channels (ZXY rotations), a chest rotating XYZ with an End
/// Site, and an arm with a position channel of its own. 13 channels.
const SMALL: &str = "HIERARCHY
ROOT Hips
{
  OFFSET 0 1 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT Chest
  {
    OFFSET 0 5 0
    CHANNELS 3 Xrotation Yrotation Zrotation
    End Site
    {
      OFFSET 0 2 0
    }
  }
  JOINT Left Arm
  {
    OFFSET 3 0 0
    CHANNELS 4 Xposition Zrotation Xrotation Yrotation
    End Site
    {
      OFFSET 1 0 0
    }
  }
}
MOTION
Frames: 2
Frame Time: 0.5
1 2 3  0 0 0  0 0 0  0 0 0 0
10 20 30  90 90 90  90 90 90  0.5 90 0 0
";

fn parse(text: &str) -> Result<Mocap, MocapError> {
    Mocap::parse(text, Path::new("test.bvh"))
}

fn err(text: &str) -> String {
    parse(text).unwrap_err().to_string()
}

/// Rotation matrices written out entry by entry (column vectors, right-handed), independent
/// of glam's constructors.
fn rx(deg: f64) -> DMat3 {
    let (s, c) = deg.to_radians().sin_cos();
    DMat3::from_cols_array(&[1.0, 0.0, 0.0, 0.0, c, s, 0.0, -s, c])
}
fn ry(deg: f64) -> DMat3 {
    let (s, c) = deg.to_radians().sin_cos();
    DMat3::from_cols_array(&[c, 0.0, -s, 0.0, 1.0, 0.0, s, 0.0, c])
}
fn rz(deg: f64) -> DMat3 {
    let (s, c) = deg.to_radians().sin_cos();
    DMat3::from_cols_array(&[c, s, 0.0, -s, c, 0.0, 0.0, 0.0, 1.0])
}

fn assert_mat(a: DMat3, b: DMat3) {
    assert!(a.abs_diff_eq(b, 1e-12), "{a} vs {b}");
}

/// A file saved with a UTF-8 byte-order mark. Expected: read as without it (it was refused,
/// glued to `HIERARCHY`).
#[test]
fn a_byte_order_mark_is_skipped() {
    assert_eq!(
        parse(&format!("\u{feff}{SMALL}")).unwrap(),
        parse(SMALL).unwrap()
    );
}

#[test]
fn hierarchy_channels_and_frames_are_read() {
    let mocap = parse(SMALL).unwrap();
    let names: Vec<_> = mocap.joints().iter().map(|j| j.name.as_str()).collect();
    assert_eq!(names, ["Hips", "Chest", "Left Arm"]);
    let [hips, chest, arm] = [0, 1, 2].map(|i| &mocap.joints()[i]);
    assert_eq!(
        (hips.parent, chest.parent, arm.parent),
        (None, Some(0), Some(0))
    );
    assert_eq!(chest.offset, DVec3::new(0.0, 5.0, 0.0));
    assert_eq!(chest.end_sites, [DVec3::new(0.0, 2.0, 0.0)]);
    assert_eq!(arm.end_sites, [DVec3::X]);
    assert_eq!(
        (hips.first_channel, chest.first_channel, arm.first_channel),
        (0, 6, 9)
    );
    assert_eq!(
        arm.channels,
        [
            Channel::Xposition,
            Channel::Zrotation,
            Channel::Xrotation,
            Channel::Yrotation
        ]
    );
    assert!(arm.translates() && arm.rotates() && !chest.translates());
    assert_eq!(mocap.frame_count(), 2);
    assert_eq!(mocap.fps(), 2.0);
    assert_eq!(mocap.frame(1)[9], 0.5);
    assert_eq!(mocap.joint_index("Left Arm"), Some(2));
    assert_eq!(
        mocap.rest_positions(),
        [
            DVec3::Y,
            DVec3::new(0.0, 6.0, 0.0),
            DVec3::new(3.0, 1.0, 0.0)
        ]
    );
}

#[test]
fn rotations_compose_in_the_listed_order() {
    // Arbitrary angles, so that no order coincides with another.
    let text = SMALL.replace(
        "10 20 30  90 90 90  90 90 90",
        "10 20 30  30 -50 70  -20 65 110",
    );
    let mocap = parse(&text).unwrap();
    let frame = mocap.frame(1);
    // Hips lists Z X Y: R = Rz · Rx · Ry.
    let (hips, t) = mocap.joints()[0].local(frame);
    assert_mat(DMat3::from_quat(hips), rz(30.0) * rx(-50.0) * ry(70.0));
    assert_eq!(t, DVec3::new(10.0, 21.0, 30.0));
    // Chest lists X Y Z: R = Rx · Ry · Rz.
    let (chest, _) = mocap.joints()[1].local(frame);
    assert_mat(DMat3::from_quat(chest), rx(-20.0) * ry(65.0) * rz(110.0));

    // At 90° about every axis the orders are easy to follow by hand: Z X Y sends x to −x
    // (Ry: x→−z, Rx: −z→y, Rz: y→−x), X Y Z sends x to z (Rz: x→y, Ry keeps y, Rx: y→z).
    let mocap = parse(SMALL).unwrap();
    let (hips, _) = mocap.joints()[0].local(mocap.frame(1));
    let (chest, _) = mocap.joints()[1].local(mocap.frame(1));
    assert!((hips * DVec3::X).abs_diff_eq(-DVec3::X, 1e-12));
    assert!((chest * DVec3::X).abs_diff_eq(DVec3::Z, 1e-12));
}

#[test]
fn forward_kinematics_chains_parent_transforms_and_position_channels() {
    let mocap = parse(SMALL).unwrap();
    let world = mocap.world_transforms(mocap.frame(0));
    // Frame 0 translates the root only.
    assert_eq!(world[0].translation, DVec3::new(1.0, 3.0, 3.0));
    assert_eq!(world[1].translation, DVec3::new(1.0, 8.0, 3.0));
    let frame = mocap.frame(1);
    let world = mocap.world_transforms(frame);
    let root = rz(90.0) * rx(90.0) * ry(90.0);
    // The arm's own Xposition (0.5) adds to its offset in the parent's frame.
    let arm = DVec3::new(10.0, 21.0, 30.0) + root * DVec3::new(3.5, 0.0, 0.0);
    assert!(world[2].translation.abs_diff_eq(arm, 1e-12));
    assert!(
        world[2].matrix3.abs_diff_eq(root * rz(90.0), 1e-12),
        "rotations accumulate down the chain"
    );
}

#[test]
fn mixed_line_endings_and_any_whitespace_are_accepted() {
    let crlf = SMALL.replace('\n', "\r\n");
    // Mixed: every other line LF, tabs and runs of spaces between tokens.
    let mixed: String = SMALL
        .split('\n')
        .enumerate()
        .map(|(i, l)| {
            format!(
                "{}{}",
                l.replace(' ', " \t "),
                if i % 2 == 0 { "\r\n" } else { "\n" }
            )
        })
        .collect();
    let reference = parse(SMALL).unwrap();
    assert_eq!(parse(&crlf).unwrap(), reference);
    let mixed = parse(&mixed).unwrap();
    assert_eq!(mixed.frame(1), reference.frame(1));
    assert_eq!(mixed.joints()[2].name, "Left \t Arm".replace(" \t ", " "));
}

#[test]
fn errors_name_the_file_line_and_problem() {
    let cases: [(String, &str); 14] = [
        (
            SMALL.replace("0.5 90 0 0", "0.5 90 0"),
            "test.bvh:29: frame 1 has 12 values, expected 13 (one per channel)",
        ),
        (
            SMALL.replace("1 2 3  0 0 0", "1 2 3  0 0 0 7"),
            "test.bvh:28: frame 0 has 14 values, expected 13 (one per channel)",
        ),
        (
            SMALL.replace(
                "Xrotation Yrotation Zrotation",
                "Xrotation Yrotation Wrotation",
            ),
            "test.bvh:9: unknown channel \"Wrotation\" (expected Xposition, Yposition, \
             Zposition, Xrotation, Yrotation or Zrotation)",
        ),
        (
            SMALL.replace("0.5 90", "0.5 ninety"),
            "test.bvh:29: \"ninety\" is not a number",
        ),
        (
            SMALL.replace("0.5 90", "0.5 NaN"),
            "test.bvh:29: \"NaN\" is not a finite number",
        ),
        (
            SMALL.replace("OFFSET 0 5 0", "OFFSET 0 inf 0"),
            "test.bvh:8: \"inf\" is not a finite number",
        ),
        (
            SMALL[..SMALL.find("MOTION").unwrap()].to_owned(),
            "test.bvh:25: no MOTION section after the hierarchy",
        ),
        (
            SMALL.replace("Frames: 2", "Frames: 3"),
            "test.bvh:29: Frames: says 3 but the file has 2 frame lines",
        ),
        (
            SMALL.replace("Frames: 2", "Frames: 1"),
            "test.bvh:29: Frames: says 1 but the file has 2 frame lines",
        ),
        (
            SMALL.replacen("    }\n  }\n  JOINT", "    }\n  JOINT", 1),
            "test.bvh:3: the '{' of \"Hips\" on line 3 is never closed",
        ),
        (
            SMALL.replace("}\nMOTION", "}\n}\nMOTION"),
            "test.bvh:25: '}' closes nothing",
        ),
        (
            SMALL.replace("Left Arm", "Chest"),
            "test.bvh:15: joint name \"Chest\" is used twice (first on line 6)",
        ),
        (
            SMALL.replace("CHANNELS 3 X", "CHANNELS 7 X"),
            "test.bvh:9: CHANNELS must be followed by a count from 0 to 6, found \"7\"",
        ),
        (
            SMALL.replace("Frame Time: 0.5", "Frame Time: 0"),
            "test.bvh:27: Frame Time must be a positive number of seconds with a finite frame rate, \
             found 0.0",
        ),
    ];
    for (text, message) in cases {
        assert_eq!(err(&text), message);
    }
    assert_eq!(
        err(&SMALL.replace(
            "Xrotation Yrotation Zrotation",
            "Xrotation Yrotation Xrotation"
        )),
        "test.bvh:9: joint \"Chest\" lists Xrotation twice"
    );
    assert_eq!(
        err("HIERARCHY\nROOT A\n{\n  CHANNELS 0\n}\nMOTION\nFrames: 0\nFrame Time: 1\n"),
        "test.bvh:5: \"A\" has no OFFSET"
    );
    assert_eq!(
        err("HIERARCHY\nROOT A\n{\n  OFFSET 0 0\n"),
        "test.bvh:5: the file ends where an OFFSET coordinate should be"
    );
    assert!(matches!(
        Mocap::read(Path::new("/nonexistent/x.bvh")),
        Err(MocapError::Read(_))
    ));
}

#[test]
fn a_joint_without_channels_and_a_file_without_frames_are_valid() {
    let mocap = parse(
        "HIERARCHY\nROOT A\n{\n OFFSET 0 0 0\n JOINT B\n {\n  OFFSET 1 0 0\n }\n}\n\
         MOTION\nFrames: 0\nFrame Time: 0.1\n\n",
    )
    .unwrap();
    assert_eq!(mocap.frame_count(), 0);
    assert!(mocap.joints().iter().all(|j| j.channels.is_empty()));
}
