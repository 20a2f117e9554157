//! The creature's surface: closed lathes (see [`crate::rig::lathe`]) for the torso, the neck,
//! the head, the tail and each leg's thigh, shin and foot, with smooth skinning weights that
//! blend across the joints each part spans. Parts overlap where they meet (the neck and tail
//! start inside the torso, the thighs inside its flanks) and use the same joint positions and
//! half-widths there, so they deform alike.

use glam::DVec3;

use super::skeleton::{
    HIP_Z, KNEE_Z, LEGS, Leg, NECK_DIRECTION, NECK_STEP, TAIL_BASE, TAIL_DIRECTION, TAIL_LENGTH,
    TAIL_STEP, joint,
};
use crate::rig::lathe::{Body, Lathe, Part, band, capsule_profile, smooth_profile};
use crate::rig::procedural::Skeleton;

/// Target spacing between rings along a profile, in metres. Chosen so the creature lands
/// near 8k vertices while the knee blend regions (±7 cm) span five rings and each tail
/// joint's (±14 cm) nine, which keeps bends and curls smooth under linear blend skinning.
pub(crate) const RING_STEP: f64 = 0.03;

/// Blend half-width around each tail joint: nearly half the joint spacing, so the tail bends
/// everywhere along its length (a curl, not a chain of rigid links).
const TAIL_BLEND: f64 = 0.14;
/// Where the torso's axis starts (its rear pole, inside the tail's base); it runs along −y.
const TORSO_ORIGIN: DVec3 = DVec3::new(0.0, 0.85, super::skeleton::BACK_Z);

/// The assembled surface and the name of each part, in mesh order.
pub(crate) fn build(skeleton: &Skeleton) -> (Body, Vec<&'static str>) {
    let (names, parts): (Vec<_>, Vec<_>) = parts(skeleton).into_iter().unzip();
    (crate::rig::lathe::build(parts), names)
}

/// Every part, in a fixed order (the vertex order of the mesh): torso, neck, head, tail, then
/// each leg's thigh, shin and foot in [`LEGS`] order.
fn parts(skeleton: &Skeleton) -> Vec<(&'static str, Part)> {
    let mut parts = vec![
        ("torso", torso(skeleton)),
        ("neck", neck()),
        ("head", head(skeleton)),
        ("tail", tail()),
    ];
    for (i, leg) in LEGS.iter().enumerate() {
        parts.extend(self::leg(leg, i));
    }
    parts
}

/// Position along the torso's axis of a bind-space point.
fn torso_axial(p: DVec3) -> f64 {
    TORSO_ORIGIN.y - p.y
}

/// The torso, rump to chest, one surface so the back bends smoothly: an ellipse a little
/// narrower than tall, widest at the belly. Its rear end belongs to the tail's first joint and
/// its front end blends into the neck's, as those parts do where they overlap it.
fn torso(skeleton: &Skeleton) -> Part {
    use joint::*;
    let at = |j: usize| torso_axial(skeleton.bind[j]);
    Part {
        lathe: Lathe {
            origin: TORSO_ORIGIN,
            axis: DVec3::NEG_Y,
            side: DVec3::X,
            scale: (0.85, 1.0),
            segments: 32,
            profile: smooth_profile(
                RING_STEP,
                &[
                    (0.0, 0.0),
                    (0.03, 0.12),
                    (0.12, 0.2),
                    (0.3, 0.27),
                    (0.55, 0.31),
                    (0.8, 0.32),
                    (1.05, 0.3),
                    (1.25, 0.26),
                    (1.42, 0.18),
                    (1.52, 0.09),
                    (1.55, 0.0),
                ],
            ),
        },
        base: TAIL,
        bands: vec![
            band(at(TAIL), TAIL_BLEND, PELVIS),
            band(at(SPINE), 0.15, SPINE),
            band(at(CHEST), 0.12, CHEST),
            band(at(NECK_1), 0.1, NECK_1),
        ],
    }
}

/// The neck, from inside the chest up to inside the head, thinning toward the head.
fn neck() -> Part {
    use joint::*;
    Part {
        lathe: Lathe {
            origin: super::skeleton::NECK_BASE,
            axis: NECK_DIRECTION.normalize(),
            side: DVec3::X,
            scale: (0.85, 1.0),
            segments: 28,
            profile: smooth_profile(
                RING_STEP,
                &[
                    (-0.25, 0.0),
                    (-0.22, 0.12),
                    (-0.12, 0.17),
                    (0.1, 0.14),
                    (0.35, 0.11),
                    (0.54, 0.1),
                    (0.64, 0.08),
                    (0.68, 0.0),
                ],
            ),
        },
        base: CHEST,
        bands: vec![
            band(0.0, 0.1, NECK_1),
            band(NECK_STEP, 0.1, NECK_2),
            band(2.0 * NECK_STEP, 0.08, HEAD),
        ],
    }
}

/// The head: a flattened, tapering capsule from the back of the skull to the snout, pointing
/// forward (−y) and a little down, rigid on the head joint. The snout shows the facing
/// direction in every picture.
fn head(skeleton: &Skeleton) -> Part {
    Part {
        lathe: Lathe {
            origin: skeleton.bind[joint::HEAD],
            axis: DVec3::new(0.0, -1.0, -0.25).normalize(),
            side: DVec3::X,
            scale: (0.9, 0.85),
            segments: 28,
            profile: capsule_profile(RING_STEP, 0.3, (0.12, 0.13), (0.06, 0.08)),
        },
        base: joint::HEAD,
        bands: vec![],
    }
}

/// The tail, from inside the rump to a thin tip `TAIL_LENGTH` behind its base: flattened side
/// to side, blending across every tail joint.
fn tail() -> Part {
    use joint::*;
    Part {
        lathe: Lathe {
            origin: TAIL_BASE,
            axis: TAIL_DIRECTION.normalize(),
            side: DVec3::X,
            scale: (0.8, 1.0),
            segments: 24,
            profile: smooth_profile(
                RING_STEP,
                &[
                    (-0.22, 0.0),
                    (-0.19, 0.12),
                    (-0.1, 0.19),
                    (0.1, 0.2),
                    (0.5, 0.15),
                    (0.9, 0.11),
                    (1.3, 0.075),
                    (1.65, 0.045),
                    (1.9, 0.022),
                    (TAIL_LENGTH - 0.02, 0.01),
                    (TAIL_LENGTH, 0.0),
                ],
            ),
        },
        base: PELVIS,
        bands: (0..TAIL_JOINTS)
            .map(|k| band(TAIL_STEP * k as f64, TAIL_BLEND, TAIL + k))
            .collect(),
    }
}

/// Thigh, shin and foot of leg `i`. Hind legs are thicker and longer-footed than fore legs.
fn leg(leg: &Leg, i: usize) -> Vec<(&'static str, Part)> {
    let (hip, knee) = (joint::LEG_HIP[i], joint::LEG_KNEE[i]);
    let body = if leg.hind {
        joint::PELVIS
    } else {
        joint::CHEST
    };
    let names = leg.parts;
    let (thick, foot_length) = if leg.hind { (1.2, 0.18) } else { (0.95, 0.13) };
    let knee_at = DVec3::new(leg.hip.x, leg.hip.y, KNEE_Z);
    let ankle_z = 0.06;
    let down = |origin, length, start: f64, end: f64, segments| Lathe {
        origin,
        axis: DVec3::NEG_Z,
        side: DVec3::X,
        scale: (1.0, 1.0),
        segments,
        profile: capsule_profile(RING_STEP, length, (start, start), (end, end)),
    };
    vec![
        (
            names[0],
            Part {
                lathe: down(leg.hip, HIP_Z - KNEE_Z, 0.11 * thick, 0.07 * thick, 18),
                base: body,
                bands: vec![band(0.0, 0.1, hip), band(HIP_Z - KNEE_Z, 0.07, knee)],
            },
        ),
        (
            names[1],
            Part {
                lathe: down(knee_at, KNEE_Z - ankle_z, 0.068 * thick, 0.05 * thick, 16),
                base: hip,
                bands: vec![band(0.0, 0.07, knee)],
            },
        ),
        (
            names[2],
            Part {
                // Heel to toe along −y, sole on z = 0, rigid on the knee (the legs have no
                // ankle joint).
                lathe: Lathe {
                    origin: DVec3::new(leg.hip.x, leg.hip.y + 0.06, 0.05),
                    axis: DVec3::NEG_Y,
                    side: DVec3::X,
                    scale: (1.0, 0.9),
                    segments: 14,
                    profile: capsule_profile(RING_STEP, foot_length, (0.05, 0.04), (0.055, 0.06)),
                },
                base: knee,
                bands: vec![],
            },
        ),
    ]
}
