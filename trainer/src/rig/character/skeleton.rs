//! The built-in character's skeleton: joints in the bind pose, the named joint angles that
//! drive them (posed by the shared forward kinematics of [`crate::rig::procedural`]).
//!
//! Frame: z up, feet on z = 0, the character faces −y, so its left is +x. Joint frames are
//! world-aligned in the bind pose (an A-pose, arms 40° below horizontal), so every joint angle
//! is a rotation about a fixed bind-space axis, applied at its joint.

use glam::DVec3;

use crate::rig::procedural::{Dof, Skeleton, dof};

/// Joint indices, named so the body and clip tables read as anatomy.
pub(crate) mod joint {
    pub const PELVIS: usize = 0;
    pub const SPINE: usize = 1;
    pub const CHEST: usize = 2;
    pub const NECK: usize = 3;
    pub const HEAD: usize = 4;
    pub const L_SHOULDER: usize = 5;
    pub const L_ELBOW: usize = 6;
    pub const L_WRIST: usize = 7;
    pub const R_SHOULDER: usize = 8;
    pub const R_ELBOW: usize = 9;
    pub const R_WRIST: usize = 10;
    pub const L_HIP: usize = 11;
    pub const L_KNEE: usize = 12;
    pub const L_ANKLE: usize = 13;
    pub const R_HIP: usize = 14;
    pub const R_KNEE: usize = 15;
    pub const R_ANKLE: usize = 16;
    pub const COUNT: usize = 17;
}

/// Arm droop below horizontal in the bind pose. An A-pose rather than a T-pose keeps the
/// shoulders' rest shape natural and puts the training range of abduction around the middle.
const ARM_DROOP: f64 = 40.0 * std::f64::consts::PI / 180.0;
/// Lateral offset of the shoulder and hip joints from the midline.
const SHOULDER_X: f64 = 0.19;
const HIP_X: f64 = 0.09;
/// Bone lengths in metres, roughly a 1.8 m adult.
pub(crate) const UPPER_ARM: f64 = 0.29;
pub(crate) const FOREARM: f64 = 0.26;

/// Unit direction of the left arm in the bind pose (mirror x for the right).
pub(crate) fn left_arm_direction() -> DVec3 {
    DVec3::new(ARM_DROOP.cos(), 0.0, -ARM_DROOP.sin())
}

/// Bind-pose joint positions and parents (parents precede children).
pub(crate) fn skeleton() -> Skeleton {
    use joint::*;
    let mut skeleton = Skeleton::with_joints(COUNT);
    skeleton.set(PELVIS, None, DVec3::new(0.0, 0.0, 0.98));
    skeleton.set(SPINE, Some(PELVIS), DVec3::new(0.0, 0.0, 1.10));
    skeleton.set(CHEST, Some(SPINE), DVec3::new(0.0, 0.0, 1.30));
    skeleton.set(NECK, Some(CHEST), DVec3::new(0.0, 0.0, 1.50));
    skeleton.set(HEAD, Some(NECK), DVec3::new(0.0, 0.0, 1.60));
    for (side, shoulder, elbow, wrist) in [
        (1.0, L_SHOULDER, L_ELBOW, L_WRIST),
        (-1.0, R_SHOULDER, R_ELBOW, R_WRIST),
    ] {
        let d = left_arm_direction() * DVec3::new(side, 1.0, 1.0);
        let s = DVec3::new(side * SHOULDER_X, 0.0, 1.43);
        skeleton.set(shoulder, Some(CHEST), s);
        skeleton.set(elbow, Some(shoulder), s + d * UPPER_ARM);
        skeleton.set(wrist, Some(elbow), s + d * (UPPER_ARM + FOREARM));
    }
    for (side, hip, knee, ankle) in [
        (1.0, L_HIP, L_KNEE, L_ANKLE),
        (-1.0, R_HIP, R_KNEE, R_ANKLE),
    ] {
        skeleton.set(hip, Some(PELVIS), DVec3::new(side * HIP_X, 0.0, 0.93));
        skeleton.set(knee, Some(hip), DVec3::new(side * HIP_X, 0.0, 0.50));
        skeleton.set(ankle, Some(knee), DVec3::new(side * HIP_X, 0.0, 0.08));
    }
    skeleton
}

/// The joint angles, in the order poses list them. Within a joint, earlier angles are applied
/// after later ones (`R = R_first · R_second`), so e.g. the shoulder abducts in the bind plane
/// and then swings that plane forward.
///
/// Sign conventions (character faces −y): `*_flex` positive bends forward (knees: shin back,
/// ankles: toes up), `*_lean` positive leans to the character's left, `*_twist` positive turns
/// the front toward the character's left, `*_abduct` is the arm's or leg's angle away from the
/// body, with the arm hanging straight down at 0.
pub(crate) fn dofs() -> Vec<Dof> {
    use joint::*;
    let x = DVec3::X;
    let y = DVec3::Y;
    let z = DVec3::Z;
    let forward = DVec3::NEG_Y;
    let arm_rest = std::f64::consts::FRAC_PI_2 - ARM_DROOP;
    let left_arm = left_arm_direction();
    let right_arm = left_arm * DVec3::new(-1.0, 1.0, 1.0);
    vec![
        dof("spine_flex", SPINE, x, 0.0, -0.35, 0.6),
        dof("spine_lean", SPINE, y, 0.0, -0.35, 0.35),
        dof("chest_flex", CHEST, x, 0.0, -0.3, 0.45),
        dof("chest_twist", CHEST, z, 0.0, -0.6, 0.6),
        dof("neck_flex", NECK, x, 0.0, -0.5, 0.6),
        dof("neck_twist", NECK, z, 0.0, -0.9, 0.9),
        dof("head_flex", HEAD, x, 0.0, -0.4, 0.4),
        dof("l_shoulder_flex", L_SHOULDER, -x, 0.0, -0.6, 1.6),
        dof("l_shoulder_abduct", L_SHOULDER, -y, arm_rest, 0.1, 2.4),
        dof(
            "l_elbow_flex",
            L_ELBOW,
            left_arm.cross(forward),
            0.0,
            0.0,
            2.3,
        ),
        dof(
            "l_wrist_flex",
            L_WRIST,
            left_arm.cross(forward),
            0.0,
            -0.7,
            0.7,
        ),
        dof("r_shoulder_flex", R_SHOULDER, -x, 0.0, -0.6, 1.6),
        dof("r_shoulder_abduct", R_SHOULDER, y, arm_rest, 0.1, 2.4),
        dof(
            "r_elbow_flex",
            R_ELBOW,
            right_arm.cross(forward),
            0.0,
            0.0,
            2.3,
        ),
        dof(
            "r_wrist_flex",
            R_WRIST,
            right_arm.cross(forward),
            0.0,
            -0.7,
            0.7,
        ),
        dof("l_hip_flex", L_HIP, -x, 0.0, -0.5, 1.6),
        dof("l_hip_abduct", L_HIP, -y, 0.0, -0.3, 0.7),
        dof("l_knee_flex", L_KNEE, x, 0.0, 0.0, 2.2),
        dof("l_ankle_flex", L_ANKLE, -x, 0.0, -0.6, 0.4),
        dof("r_hip_flex", R_HIP, -x, 0.0, -0.5, 1.6),
        dof("r_hip_abduct", R_HIP, y, 0.0, -0.3, 0.7),
        dof("r_knee_flex", R_KNEE, x, 0.0, 0.0, 2.2),
        dof("r_ankle_flex", R_ANKLE, -x, 0.0, -0.6, 0.4),
    ]
}
