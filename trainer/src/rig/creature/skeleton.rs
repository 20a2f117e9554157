//! The creature's skeleton: joints in the bind pose and the named joint angles that drive
//! them (posed by the shared forward kinematics of [`crate::rig::procedural`]).
//!
//! Frame: z up, feet on z = 0, the long axis along y: the creature faces −y (as the human
//! does), its head at −y and its tail tip at +y, so its left is +x. Joint frames are
//! world-aligned in the bind pose, so every joint angle is a rotation about a fixed
//! bind-space axis, applied at its joint.
//!
//! Two chains leave the pelvis: the spine forward (spine, chest, two neck joints, head) and the
//! tail backward (six joints). Four legs hang below, each a hip and a knee (a fore leg's hip
//! and knee are its shoulder and elbow).

use glam::DVec3;

use crate::rig::procedural::{Dof, Skeleton, dof};

/// Joint indices, named so the body and clip tables read as anatomy.
pub(crate) mod joint {
    pub const PELVIS: usize = 0;
    pub const SPINE: usize = 1;
    pub const CHEST: usize = 2;
    pub const NECK_1: usize = 3;
    pub const NECK_2: usize = 4;
    pub const HEAD: usize = 5;
    /// The first of the tail's `TAIL_JOINTS` joints, base to tip.
    pub const TAIL: usize = 6;
    pub const TAIL_JOINTS: usize = 6;
    /// Hips and knees of the four legs, in [`super::LEGS`] order.
    pub const LEG_HIP: [usize; 4] = [12, 14, 16, 18];
    pub const LEG_KNEE: [usize; 4] = [13, 15, 17, 19];
    pub const COUNT: usize = 20;
}

/// Height of the back in the bind pose, metres (the torso's axis).
pub(crate) const BACK_Z: f64 = 0.86;
/// Hip height of every leg; knees halfway to the ground.
pub(crate) const HIP_Z: f64 = 0.74;
pub(crate) const KNEE_Z: f64 = 0.38;
/// The neck's line: from its base, rising toward −y.
pub(crate) const NECK_BASE: DVec3 = DVec3::new(0.0, -0.62, 0.95);
pub(crate) const NECK_DIRECTION: DVec3 = DVec3::new(0.0, -0.92, 0.40);
/// Spacing of the neck joints along that line (neck 1, neck 2, head).
pub(crate) const NECK_STEP: f64 = 0.27;
/// The tail's line: from its base, falling gently toward +y.
pub(crate) const TAIL_BASE: DVec3 = DVec3::new(0.0, 0.72, BACK_Z);
pub(crate) const TAIL_DIRECTION: DVec3 = DVec3::new(0.0, 1.0, -0.16);
/// Spacing of the tail joints along that line; the tip is `TAIL_LENGTH` from the base.
pub(crate) const TAIL_STEP: f64 = 0.3;
pub(crate) const TAIL_LENGTH: f64 = 2.05;

/// One leg: its side (+1 left, −1 right), where its hip is, and the names of its angles and
/// parts.
pub(crate) struct Leg {
    pub side: f64,
    pub hip: DVec3,
    /// Whether it is a hind leg (its knee bends forward, its foot swings back).
    pub hind: bool,
    /// Hip swing, hip splay, knee bend.
    pub angles: [&'static str; 3],
    /// Thigh, shin, foot.
    pub parts: [&'static str; 3],
}

/// The legs: fore left, fore right, hind left, hind right.
pub(crate) const LEGS: [Leg; 4] = [
    Leg {
        side: 1.0,
        hip: DVec3::new(0.2, -0.36, HIP_Z),
        hind: false,
        angles: ["fl_hip_swing", "fl_hip_splay", "fl_knee_bend"],
        parts: ["fl_thigh", "fl_shin", "fl_foot"],
    },
    Leg {
        side: -1.0,
        hip: DVec3::new(-0.2, -0.36, HIP_Z),
        hind: false,
        angles: ["fr_hip_swing", "fr_hip_splay", "fr_knee_bend"],
        parts: ["fr_thigh", "fr_shin", "fr_foot"],
    },
    Leg {
        side: 1.0,
        hip: DVec3::new(0.23, 0.42, HIP_Z),
        hind: true,
        angles: ["hl_hip_swing", "hl_hip_splay", "hl_knee_bend"],
        parts: ["hl_thigh", "hl_shin", "hl_foot"],
    },
    Leg {
        side: -1.0,
        hip: DVec3::new(-0.23, 0.42, HIP_Z),
        hind: true,
        angles: ["hr_hip_swing", "hr_hip_splay", "hr_knee_bend"],
        parts: ["hr_thigh", "hr_shin", "hr_foot"],
    },
];

/// Bind position of neck joint `k` (0 neck 1, 1 neck 2, 2 head).
pub(crate) fn neck_joint(k: usize) -> DVec3 {
    NECK_BASE + NECK_DIRECTION.normalize() * (NECK_STEP * k as f64)
}

/// Bind position of tail joint `k` (0 at the base).
pub(crate) fn tail_joint(k: usize) -> DVec3 {
    TAIL_BASE + TAIL_DIRECTION.normalize() * (TAIL_STEP * k as f64)
}

/// Bind-pose joint positions and parents (parents precede children).
pub(crate) fn skeleton() -> Skeleton {
    use joint::*;
    let mut skeleton = Skeleton::with_joints(COUNT);
    skeleton.set(PELVIS, None, DVec3::new(0.0, 0.42, BACK_Z));
    skeleton.set(SPINE, Some(PELVIS), DVec3::new(0.0, 0.0, BACK_Z));
    skeleton.set(CHEST, Some(SPINE), DVec3::new(0.0, -0.35, BACK_Z));
    skeleton.set(NECK_1, Some(CHEST), neck_joint(0));
    skeleton.set(NECK_2, Some(NECK_1), neck_joint(1));
    skeleton.set(HEAD, Some(NECK_2), neck_joint(2));
    for k in 0..TAIL_JOINTS {
        let parent = if k == 0 { PELVIS } else { TAIL + k - 1 };
        skeleton.set(TAIL + k, Some(parent), tail_joint(k));
    }
    for (i, leg) in LEGS.iter().enumerate() {
        let parent = if leg.hind { PELVIS } else { CHEST };
        skeleton.set(LEG_HIP[i], Some(parent), leg.hip);
        skeleton.set(
            LEG_KNEE[i],
            Some(LEG_HIP[i]),
            DVec3::new(leg.hip.x, leg.hip.y, KNEE_Z),
        );
    }
    skeleton
}

/// Names of the tail's angles, base to tip: `tail_1_pitch`, `tail_1_yaw`, … `tail_6_yaw`.
const TAIL_NAMES: [[&str; 2]; joint::TAIL_JOINTS] = [
    ["tail_1_pitch", "tail_1_yaw"],
    ["tail_2_pitch", "tail_2_yaw"],
    ["tail_3_pitch", "tail_3_yaw"],
    ["tail_4_pitch", "tail_4_yaw"],
    ["tail_5_pitch", "tail_5_yaw"],
    ["tail_6_pitch", "tail_6_yaw"],
];

/// The joint angles, in the order poses list them (34: 4 of the back, 6 of the neck and head,
/// 12 of the tail, 3 per leg), all 0 at rest.
///
/// Sign conventions (the creature faces −y, its left is +x): `*_pitch` positive lifts the
/// chain's far end (the chest, the head, the tail's tip); `*_yaw` positive swings the far end
/// toward the creature's left; `*_hip_swing` positive swings the foot forward (−y);
/// `*_hip_splay` positive moves the foot away from the midline; `*_knee_bend` positive folds
/// the leg (a hind foot moves back, a fore foot forward).
pub(crate) fn dofs() -> Vec<Dof> {
    use joint::*;
    let (x, y, z) = (DVec3::X, DVec3::Y, DVec3::Z);
    // The spine chain points −y: lifting its far end is a turn about −x, and swinging it to
    // +x a turn about +z; the tail points +y, so the reverse.
    let mut dofs = vec![
        dof("spine_pitch", SPINE, -x, 0.0, -0.25, 0.3),
        dof("spine_yaw", SPINE, z, 0.0, -0.3, 0.3),
        dof("chest_pitch", CHEST, -x, 0.0, -0.25, 0.3),
        dof("chest_yaw", CHEST, z, 0.0, -0.3, 0.3),
        dof("neck_1_pitch", NECK_1, -x, 0.0, -0.6, 0.5),
        dof("neck_1_yaw", NECK_1, z, 0.0, -0.6, 0.6),
        dof("neck_2_pitch", NECK_2, -x, 0.0, -0.5, 0.5),
        dof("neck_2_yaw", NECK_2, z, 0.0, -0.6, 0.6),
        dof("head_pitch", HEAD, -x, 0.0, -0.5, 0.5),
        dof("head_yaw", HEAD, z, 0.0, -0.5, 0.5),
    ];
    for (k, [pitch, yaw]) in TAIL_NAMES.into_iter().enumerate() {
        dofs.push(dof(pitch, TAIL + k, x, 0.0, -0.3, 0.4));
        dofs.push(dof(yaw, TAIL + k, -z, 0.0, -0.6, 0.6));
    }
    for (i, leg) in LEGS.iter().enumerate() {
        let [swing, splay, bend] = leg.angles;
        // The foot hangs along −z: forward (−y) is a turn about −x, outward a turn about −y
        // on the left (+x) and +y on the right; a hind knee folds the foot back (about +x).
        let fold = if leg.hind { x } else { -x };
        dofs.push(dof(swing, LEG_HIP[i], -x, 0.0, -0.7, 0.7));
        dofs.push(dof(splay, LEG_HIP[i], -y * leg.side, 0.0, -0.2, 0.5));
        dofs.push(dof(bend, LEG_KNEE[i], fold, 0.0, 0.0, 1.4));
    }
    dofs
}
