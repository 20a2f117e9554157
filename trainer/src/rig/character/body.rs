//! The built-in character's surface: closed lathes (see [`crate::rig::lathe`]) per body part,
//! each with smooth skinning weights that blend across the joints it spans. Neighbouring parts
//! use the same joint positions and half-widths, so where they overlap they deform alike.
//!
//! The head, nose and hat are also lent to the motion-capture mannequin (scaled to its skeleton), so both
//! characters wear the same brim, the large occluder PRT must capture.

use glam::DVec3;

use super::skeleton::{FOREARM, UPPER_ARM, joint, left_arm_direction};
use crate::rig::lathe::{Body, Lathe, Part, band, capsule_profile, smooth_profile};
use crate::rig::procedural::Skeleton;

/// Target spacing between rings along a profile, in metres. Chosen so the character lands near
/// 12k vertices while the elbow and knee blend regions (±5–6 cm) still span five or more rings,
/// which is what keeps them smooth when bent under linear blend skinning (the ±3 cm wrist
/// region gets three).
pub(crate) const RING_STEP: f64 = 0.02;

/// Centre of the head ellipsoid in the bind pose, metres.
pub(crate) const HEAD_CENTRE: DVec3 = DVec3::new(0.0, -0.01, 1.70);
/// Half-height of the head ellipsoid, metres.
const HEAD_HALF_HEIGHT: f64 = 0.125;
/// The character's height, sole (z = 0) to crown, without the hat: what a mannequin's head
/// and hat are scaled against.
pub(crate) const CROWN: f64 = HEAD_CENTRE.z + HEAD_HALF_HEIGHT;
/// Base of the nose (it points along −y, the way the character faces).
pub(crate) const NOSE_ORIGIN: DVec3 = DVec3::new(0.0, -0.115, 1.69);
/// Centre of the hat's brim underside; the brim sits at about the head's brow.
pub(crate) const HAT_ORIGIN: DVec3 = DVec3::new(0.0, -0.01, 1.755);

/// The head: an ellipsoid (radius 0.095 m across, 0.125 m up, 0.11 m front to back) around
/// `centre`, z up, every size multiplied by `scale`, rigid on `joint`.
pub(crate) fn head(centre: DVec3, scale: f64, joint: usize) -> Part {
    Part {
        lathe: Lathe {
            origin: centre,
            axis: DVec3::Z,
            side: DVec3::X,
            scale: (1.0, 1.16),
            segments: 36,
            profile: capsule_profile(
                RING_STEP * scale,
                0.0,
                (0.095 * scale, HEAD_HALF_HEIGHT * scale),
                (0.095 * scale, HEAD_HALF_HEIGHT * scale),
            ),
        },
        base: joint,
        bands: vec![],
    }
}

/// The nose, from `origin` along −y: small, but it makes the facing direction obvious in every
/// picture. Sizes multiplied by `scale`; rigid on `joint`.
pub(crate) fn nose(origin: DVec3, scale: f64, joint: usize) -> Part {
    Part {
        lathe: Lathe {
            origin,
            axis: -DVec3::Y,
            side: DVec3::X,
            scale: (0.8, 1.0),
            segments: 12,
            profile: capsule_profile(
                RING_STEP * scale,
                0.0,
                (0.022 * scale, 0.022 * scale),
                (0.022 * scale, 0.03 * scale),
            ),
        },
        base: joint,
        bands: vec![],
    }
}

/// A wide-brimmed hat whose brim underside is centred on `origin` (z up): brim radius
/// 0.33 m × `scale`, beyond the shoulders, rigid on `joint`. The large moving occluder that
/// makes shadows depend strongly on head pose.
pub(crate) fn hat(origin: DVec3, scale: f64, joint: usize) -> Part {
    let outline = [
        (0.0, 0.0),
        (0.0, 0.115),
        (0.004, 0.14),
        (0.0, 0.3),
        (0.006, 0.325),
        (0.018, 0.33),
        (0.026, 0.31),
        (0.03, 0.16),
        (0.045, 0.126),
        (0.16, 0.118),
        (0.19, 0.11),
        (0.2, 0.07),
        (0.2, 0.0),
    ]
    .map(|(axial, radius)| (axial * scale, radius * scale));
    Part {
        lathe: Lathe {
            origin,
            axis: DVec3::Z,
            side: DVec3::X,
            scale: (1.0, 1.0),
            segments: 56,
            profile: smooth_profile(RING_STEP * scale, &outline),
        },
        base: joint,
        bands: vec![],
    }
}

/// The assembled surface and the name of each part, in mesh order.
pub(crate) fn build(skeleton: &Skeleton) -> (Body, Vec<&'static str>) {
    let (names, parts): (Vec<_>, Vec<_>) = parts(skeleton).into_iter().unzip();
    (crate::rig::lathe::build(parts), names)
}

/// Every part of the character, in a fixed order (the vertex order of the mesh): the trunk and
/// head, the left arm, the right arm, the left leg, the right leg.
fn parts(skeleton: &Skeleton) -> Vec<(&'static str, Part)> {
    use joint::*;
    let mut parts = trunk(skeleton);
    for (side, shoulder, elbow, wrist) in [
        (1.0, L_SHOULDER, L_ELBOW, L_WRIST),
        (-1.0, R_SHOULDER, R_ELBOW, R_WRIST),
    ] {
        parts.extend(arm(skeleton, side, shoulder, elbow, wrist));
    }
    for (side, hip, knee, ankle) in [
        (1.0, L_HIP, L_KNEE, L_ANKLE),
        (-1.0, R_HIP, R_KNEE, R_ANKLE),
    ] {
        parts.extend(leg(skeleton, side, hip, knee, ankle));
    }
    parts
}

/// Torso, neck, head, nose and hat.
fn trunk(skeleton: &Skeleton) -> Vec<(&'static str, Part)> {
    use joint::*;
    let j = |i: usize| skeleton.bind[i];
    let (x, z) = (DVec3::X, DVec3::Z);
    vec![
        (
            "torso",
            Part {
                // One surface from crotch to the base of the neck, so the waist bends smoothly;
                // axial coordinate is world height.
                lathe: Lathe {
                    origin: DVec3::ZERO,
                    axis: z,
                    side: x,
                    scale: (1.0, 0.62),
                    segments: 40,
                    profile: smooth_profile(
                        RING_STEP,
                        &[
                            (0.855, 0.0),
                            (0.86, 0.07),
                            (0.885, 0.13),
                            (0.93, 0.16),
                            (0.99, 0.165),
                            (1.06, 0.15),
                            (1.12, 0.138),
                            (1.2, 0.145),
                            (1.3, 0.165),
                            (1.38, 0.18),
                            (1.43, 0.175),
                            (1.48, 0.14),
                            (1.515, 0.08),
                            (1.525, 0.0),
                        ],
                    ),
                },
                base: PELVIS,
                bands: vec![band(j(SPINE).z, 0.06, SPINE), band(j(CHEST).z, 0.08, CHEST)],
            },
        ),
        (
            "neck",
            Part {
                lathe: Lathe {
                    origin: DVec3::new(0.0, 0.0, 1.45),
                    axis: z,
                    side: x,
                    scale: (1.0, 1.0),
                    segments: 24,
                    profile: capsule_profile(RING_STEP, 0.2, (0.052, 0.052), (0.048, 0.048)),
                },
                base: CHEST,
                bands: vec![
                    band(j(NECK).z - 1.45, 0.035, NECK),
                    band(j(HEAD).z - 1.45, 0.035, HEAD),
                ],
            },
        ),
        ("head", head(HEAD_CENTRE, 1.0, HEAD)),
        ("nose", nose(NOSE_ORIGIN, 1.0, HEAD)),
        ("hat", hat(HAT_ORIGIN, 1.0, HEAD)),
    ]
}

/// Upper arm, forearm and hand of one side (`side` +1 left, −1 right).
fn arm(
    skeleton: &Skeleton,
    side: f64,
    shoulder: usize,
    elbow: usize,
    wrist: usize,
) -> Vec<(&'static str, Part)> {
    use joint::*;
    let j = |i: usize| skeleton.bind[i];
    let y = DVec3::Y;
    let mut parts = Vec::with_capacity(3);
    let d = left_arm_direction() * DVec3::new(side, 1.0, 1.0);
    let arm = |name, origin, length, start, end, base, bands, segments, scale| {
        (
            name,
            Part {
                lathe: Lathe {
                    origin,
                    axis: d,
                    side: y,
                    scale,
                    segments,
                    profile: capsule_profile(RING_STEP, length, start, end),
                },
                base,
                bands,
            },
        )
    };
    parts.push(arm(
        if side > 0.0 {
            "l_upper_arm"
        } else {
            "r_upper_arm"
        },
        j(shoulder),
        UPPER_ARM,
        (0.056, 0.056),
        (0.043, 0.043),
        CHEST,
        vec![band(0.0, 0.05, shoulder), band(UPPER_ARM, 0.05, elbow)],
        28,
        (1.0, 1.0),
    ));
    parts.push(arm(
        if side > 0.0 { "l_forearm" } else { "r_forearm" },
        j(elbow),
        FOREARM,
        (0.043, 0.043),
        (0.031, 0.031),
        shoulder,
        vec![band(0.0, 0.05, elbow), band(FOREARM, 0.03, wrist)],
        24,
        (1.0, 1.0),
    ));
    // Flattened across the palm, which faces down and in toward the body.
    parts.push(arm(
        if side > 0.0 { "l_hand" } else { "r_hand" },
        j(wrist),
        0.09,
        (0.032, 0.032),
        (0.034, 0.045),
        elbow,
        vec![band(0.0, 0.03, wrist)],
        20,
        (1.3, 0.62),
    ));
    parts
}

/// Thigh, shin and foot of one side (`side` +1 left, −1 right).
fn leg(
    skeleton: &Skeleton,
    side: f64,
    hip: usize,
    knee: usize,
    ankle: usize,
) -> Vec<(&'static str, Part)> {
    use joint::*;
    let j = |i: usize| skeleton.bind[i];
    let (x, y, z) = (DVec3::X, DVec3::Y, DVec3::Z);
    let mut parts = Vec::with_capacity(3);
    let left = side > 0.0;
    let thigh = j(hip).z - j(knee).z;
    let shin = j(knee).z - j(ankle).z;
    let leg = |name, origin, length, start, end, base, bands, segments| {
        (
            name,
            Part {
                lathe: Lathe {
                    origin,
                    axis: -z,
                    side: x,
                    scale: (1.0, 1.0),
                    segments,
                    profile: capsule_profile(RING_STEP, length, start, end),
                },
                base,
                bands,
            },
        )
    };
    parts.push(leg(
        if left { "l_thigh" } else { "r_thigh" },
        j(hip),
        thigh,
        (0.085, 0.085),
        (0.056, 0.056),
        PELVIS,
        vec![band(0.0, 0.07, hip), band(thigh, 0.06, knee)],
        32,
    ));
    parts.push(leg(
        if left { "l_shin" } else { "r_shin" },
        j(knee),
        shin,
        (0.054, 0.054),
        (0.036, 0.036),
        hip,
        vec![band(0.0, 0.06, knee), band(shin, 0.04, ankle)],
        28,
    ));
    parts.push((
        if left { "l_foot" } else { "r_foot" },
        Part {
            // Heel to toe along −y, sole on z = 0; rigid on the ankle, while the shin's lower
            // end blends into the ankle above it.
            lathe: Lathe {
                origin: DVec3::new(side * 0.09, 0.045, 0.045),
                axis: -y,
                side: x,
                scale: (1.0, 1.0),
                segments: 24,
                profile: capsule_profile(RING_STEP, 0.17, (0.04, 0.03), (0.045, 0.05)),
            },
            base: ankle,
            bands: vec![],
        },
    ));
    parts
}
