//! The mannequin's surface, derived from the skeleton alone: a tapered capsule around every
//! bone, the built-in character's head, nose and hat scaled to the skeleton, all with the
//! built-in character's smooth weights across joints (see [`crate::rig::lathe`]).
//!
//! Proportions are fractions of the skeleton's rest height `H`:
//!
//! - **Bones.** A bone runs from a joint to a child joint or End Site and is driven by the
//!   joint at its start. Zero-length bones (a zero OFFSET, such as CMU's `LHipJoint` or
//!   `LeftShoulder`, which sit on their parent) get no surface; the bones that start there
//!   blend upstream to the parent joint, the nearest joint that carries them.
//! - **Radius** follows the pipe model (Leonardo's rule for trees): a bone's cross-section is
//!   proportional to the total bone length it carries, `r = PIPE · √(H · L)` with `L` the
//!   bone's length plus every bone below it. Limbs therefore thin toward the hands and feet
//!   and the spine, which carries the arms and head, is thickest, without naming any joint.
//!   `PIPE` makes a CMU thigh 4.7 % of `H` thick, as the built-in character's (8.5 cm of
//!   1.8 m). A floor of `MIN_RADIUS · H` keeps fingers and toes from becoming wires: they
//!   read as mitten-like hands and feet. A bone tapers to the radius of the thickest bone
//!   continuing from its end (never widening), or to `TIP` of its radius at an End Site.
//! - **Blending.** Around each joint the weight moves from the upstream joint to the joint
//!   along a smoothstep over ± `BLEND` × the thickest radius there, as the built-in
//!   character's elbows and knees do, capped at half the shortest bone at that joint so the
//!   bands of one bone never overlap.
//! - **Head.** The bone ending highest in the rest pose (the head's End Site) is replaced by
//!   the built-in character's head and nose, scaled by `H / CROWN` (the built-in character's
//!   height) and centred on the bone's middle, rigid on the bone's joint; the hat sits on it
//!   likewise.
//! - **Sampling.** Rings every `COARSER` × the built-in character's `RING_STEP`, scaled the
//!   same way, and `AROUND` ring spacings of circumference per segment (about 10k vertices
//!   for a CMU skeleton, with the hat).

use glam::{DQuat, DVec3};

use crate::rig::character::body::{
    CROWN, HAT_ORIGIN, HEAD_CENTRE, NOSE_ORIGIN, RING_STEP, hat, head, nose,
};
use crate::rig::lathe::{self, Band, Lathe, Part, band, capsule_profile, capsule_vertices};
use crate::rig::mocap::{Joint, Mocap};

/// Most vertices a mannequin's bones may have: the most a model may have
/// (`aprt_core::MAX_VERTICES`). A CMU skeleton gives about 10k.
pub(super) const MAX_VERTICES: usize = aprt_core::MAX_VERTICES;

/// Pipe-model constant (see the module docs).
const PIPE: f64 = 0.057;
/// Thinnest bone radius, as a fraction of the height.
const MIN_RADIUS: f64 = 0.018;
/// End radius of a bone that ends in an End Site, as a fraction of its start radius.
const TIP: f64 = 0.8;
/// Blend half-width around a joint, in radii of the thickest bone there.
const BLEND: f64 = 1.0;
/// Ring spacing along the bones relative to the built-in character's (both as fractions of
/// the height): coarser, because a capsule has no detail to resolve, yet still four or more
/// rings across each joint's blend region, which keeps bends smooth.
const COARSER: f64 = 1.5;
/// Spacing around a bone, in ring spacings along it (the built-in limbs have about 0.6).
const AROUND: f64 = 0.8;
/// Lengths below this fraction of the height are zero-length bones.
const ZERO_LENGTH: f64 = 1e-6;

/// The mannequin's surface: the lathe body, one name per part, and the height it is
/// proportioned by.
pub(super) struct Built {
    pub body: lathe::Body,
    pub names: Vec<String>,
    pub height: f64,
}

/// Why a skeleton gives no surface.
pub(super) enum Refusal {
    /// No bone has a nonzero length.
    NoBones,
    /// The bones' capsules would have this many vertices, more than [`MAX_VERTICES`] (bones
    /// very long for the skeleton's height, which sets the ring spacing).
    TooManyVertices(usize),
}

/// A bone with a surface: from `start` to `end` (mesh frame), driven by `joint`; `child` is
/// the joint at its end, `None` for an End Site.
struct Bone {
    joint: usize,
    child: Option<usize>,
    start: DVec3,
    end: DVec3,
    radius: f64,
}

impl Bone {
    fn length(&self) -> f64 {
        self.start.distance(self.end)
    }
}

/// Builds the surface for `mocap` whose rest joint positions (file frame) are `rest`;
/// `to_mesh` turns file axes into mesh axes. Refused if no bone has a nonzero length, or if
/// the bones would have more than [`MAX_VERTICES`] vertices (counted before any is made).
pub(super) fn build(
    mocap: &Mocap,
    rest: &[DVec3],
    to_mesh: DQuat,
    with_hat: bool,
) -> Result<Built, Refusal> {
    let joints = mocap.joints();
    let at: Vec<DVec3> = rest.iter().map(|&p| to_mesh * p).collect();
    let height = rest_height(mocap, &at, to_mesh).ok_or(Refusal::NoBones)?;
    let eps = ZERO_LENGTH * height;
    let mut bones = bones(mocap, &at, to_mesh, eps);
    pipe_radii(&mut bones, joints, &at, height, eps);
    let scale = height / CROWN;
    let step = COARSER * RING_STEP * scale;
    let head_bone = bones
        .iter()
        .enumerate()
        .max_by(|(_, a), (_, b)| a.end.z.total_cmp(&b.end.z))
        .map(|(i, _)| i)
        .ok_or(Refusal::NoBones)?;
    let shaped: Vec<(&Bone, Shape)> = bones
        .iter()
        .enumerate()
        .filter(|&(i, _)| i != head_bone)
        .map(|(_, bone)| (bone, shape(bone, &bones, step)))
        .collect();
    let vertices = shaped
        .iter()
        .map(|(bone, s)| s.vertices(bone, step))
        .fold(0usize, usize::saturating_add);
    if vertices > MAX_VERTICES {
        return Err(Refusal::TooManyVertices(vertices));
    }

    let mut parts: Vec<(String, Part)> = shaped
        .into_iter()
        .map(|(bone, shape)| bone_part(bone, shape, joints, step))
        .collect();
    let bone = &bones[head_bone];
    let centre = 0.5 * (bone.start + bone.end);
    let from_head = |p: DVec3| centre + (p - HEAD_CENTRE) * scale;
    parts.push(("head".into(), head(centre, scale, bone.joint)));
    parts.push((
        "nose".into(),
        nose(from_head(NOSE_ORIGIN), scale, bone.joint),
    ));
    if with_hat {
        parts.push(("hat".into(), hat(from_head(HAT_ORIGIN), scale, bone.joint)));
    }
    let (names, parts): (Vec<String>, Vec<Part>) = parts.into_iter().unzip();
    Ok(Built {
        body: lathe::build(parts),
        names,
        height,
    })
}

/// The skeleton's rest height along the mesh's up axis, lowest to highest joint or End Site
/// (`at`: the joints' rest positions in the mesh frame); `None` if it is not a positive number.
fn rest_height(mocap: &Mocap, at: &[DVec3], to_mesh: DQuat) -> Option<f64> {
    // Every bone end, zero-length ones included.
    let mut points: Vec<DVec3> = at.to_vec();
    for (j, joint) in mocap.joints().iter().enumerate() {
        for &e in &joint.end_sites {
            points.push(at[j] + to_mesh * e);
        }
    }
    let (low, high) = points
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| {
            (l.min(p.z), h.max(p.z))
        });
    let height = high - low;
    (height > 0.0 && height.is_finite()).then_some(height)
}

/// The bones longer than `eps`, to each child joint and to each End Site, in file order, with
/// no radius yet.
fn bones(mocap: &Mocap, at: &[DVec3], to_mesh: DQuat, eps: f64) -> Vec<Bone> {
    let mut bones: Vec<Bone> = Vec::new();
    for (c, joint) in mocap.joints().iter().enumerate() {
        if let Some(j) = joint.parent {
            bones.push(Bone {
                joint: j,
                child: Some(c),
                start: at[j],
                end: at[c],
                radius: 0.0,
            });
        }
        for &e in &joint.end_sites {
            bones.push(Bone {
                joint: c,
                child: None,
                start: at[c],
                end: at[c] + to_mesh * e,
                radius: 0.0,
            });
        }
    }
    bones.retain(|b| b.length() > eps);
    bones
}

/// Gives every bone its pipe-model radius (see the module docs).
fn pipe_radii(bones: &mut [Bone], joints: &[Joint], at: &[DVec3], height: f64, eps: f64) {
    // Length carried below each joint, children before parents (reverse file order, as
    // parents precede children).
    let mut below = vec![0.0; joints.len()];
    for j in (0..joints.len()).rev() {
        below[j] += bones
            .iter()
            .filter(|b| b.joint == j)
            .map(|b| b.length() + b.child.map_or(0.0, |c| below[c]))
            .sum::<f64>();
        if let Some(p) = joints[j].parent {
            // Zero-length bones carry their child's load to the parent.
            if at[j].distance(at[p]) <= eps {
                below[p] += below[j];
            }
        }
    }
    for b in bones.iter_mut() {
        let carried = b.length() + b.child.map_or(0.0, |c| below[c]);
        b.radius = (PIPE * (height * carried).sqrt()).max(MIN_RADIUS * height);
    }
}

/// How a bone's capsule is shaped: radii at its ends, segments around it, and the bands that
/// blend it into the joints at its ends.
struct Shape {
    r0: f64,
    r1: f64,
    segments: usize,
    bands: Vec<Band>,
}

impl Shape {
    /// Vertices of the capsule around `bone` sampled every `step`.
    fn vertices(&self, bone: &Bone, step: f64) -> usize {
        let (r0, r1) = (self.r0, self.r1);
        capsule_vertices(self.segments, step, bone.length(), (r0, r0), (r1, r1))
    }
}

/// The shape of the tapered capsule around `bone`, sampled every `step`, blending into the
/// joints at its ends over the half-widths the bones there allow.
fn shape(bone: &Bone, bones: &[Bone], step: f64) -> Shape {
    let thickest_from = |j: usize| {
        bones
            .iter()
            .filter(|b| b.joint == j)
            .map(|b| b.radius)
            .fold(None, |m: Option<f64>, r| Some(m.map_or(r, |m| m.max(r))))
    };
    let half_width = |j: usize| {
        let touching = bones.iter().filter(|b| b.joint == j || b.child == Some(j));
        let (r, len) = touching.fold((0.0_f64, f64::INFINITY), |(r, len), b| {
            (r.max(b.radius), len.min(b.length()))
        });
        (BLEND * r).min(0.5 * len)
    };
    let r0 = bone.radius;
    let r1 = bone
        .child
        .and_then(thickest_from)
        .unwrap_or(TIP * r0)
        .min(r0);
    let mut bands: Vec<Band> = vec![band(0.0, half_width(bone.joint), bone.joint)];
    if let Some(c) = bone.child {
        bands.push(band(bone.length(), half_width(c), c));
    }
    // Multiples of 4 from 12 to 48, clamped before the cast so no radius overflows it.
    let quarters = ((std::f64::consts::TAU * r0 / (AROUND * step)) / 4.0).ceil();
    Shape {
        r0,
        r1,
        segments: (quarters.clamp(3.0, 12.0) as usize).max(3) * 4,
        bands,
    }
}

/// The capsule around `bone` of shape `shape`, sampled every `step`.
fn bone_part(bone: &Bone, shape: Shape, joints: &[Joint], step: f64) -> (String, Part) {
    let length = bone.length();
    let axis = (bone.end - bone.start) / length;
    let Shape {
        r0,
        r1,
        segments,
        bands,
    } = shape;
    (
        format!(
            "{}-{}",
            joints[bone.joint].name,
            bone.child.map_or("end", |c| joints[c].name.as_str())
        ),
        Part {
            lathe: Lathe {
                origin: bone.start,
                axis,
                side: axis.any_orthonormal_vector(),
                scale: (1.0, 1.0),
                segments,
                profile: capsule_profile(step, length, (r0, r0), (r1, r1)),
            },
            base: joints[bone.joint].parent.unwrap_or(bone.joint),
            bands,
        },
    )
}
