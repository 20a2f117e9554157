//! The built-in character's surface: closed surfaces of revolution ("lathes") per body part,
//! each with smooth skinning weights that blend across the joints it spans.
//!
//! Every part is one closed surface (two poles joined by rings), so each edge is shared by
//! exactly two triangles and triangles wind counter-clockwise seen from outside. Parts overlap
//! at the joints instead of being stitched: the overlap hides the seam when a joint bends, and
//! keeps every part simple to build and to check.
//!
//! Weights are a function of a vertex's bind position along its part's axis: a part names the
//! joint for its first segment and, at each joint it crosses, the joint that takes over, with a
//! blend half-width. Across a joint the weight moves from one joint to the next along a
//! smoothstep, 50/50 at the joint itself. Neighbouring parts use the same joint positions and
//! half-widths, so where they overlap they deform alike.

use std::ops::Range;

use glam::DVec3;

use super::skeleton::{FOREARM, Skeleton, UPPER_ARM, joint, left_arm_direction};

/// Target spacing between rings along a profile, in metres. Chosen so the character lands near
/// 12k vertices while the elbow and knee blend regions (±5–6 cm) still span five or more rings,
/// which is what keeps them smooth when bent under linear blend skinning (the ±3 cm wrist
/// region gets three).
const RING_STEP: f64 = 0.02;

/// The joint that takes over at axial position `at` along a part, blending over `±half_width`.
struct Band {
    at: f64,
    half_width: f64,
    joint: usize,
}

/// A closed surface of revolution around `axis` through `origin`. `profile` lists
/// `(axial, radius)` from the first pole to the last, clockwise in the (axial, radius) plane so
/// that the surface faces outward; the first and last radii are ignored (they are the poles).
/// Cross-sections are ellipses: radius × `scale.0` along `side`, × `scale.1` along
/// `axis × side`.
struct Lathe {
    origin: DVec3,
    axis: DVec3,
    side: DVec3,
    scale: (f64, f64),
    segments: usize,
    profile: Vec<(f64, f64)>,
}

/// One body part: its surface and how it is weighted.
struct Part {
    name: &'static str,
    lathe: Lathe,
    /// Joint that owns the part before its first band.
    base: usize,
    bands: Vec<Band>,
}

/// The assembled bind-pose surface: positions, triangles, per-vertex influences, and which
/// triangles belong to which part (for per-part closedness checks).
pub(crate) struct Body {
    pub positions: Vec<[f32; 3]>,
    pub triangles: Vec<[u32; 3]>,
    pub influences: Vec<Vec<(u32, f32)>>,
    pub parts: Vec<(&'static str, Range<usize>)>,
}

pub(crate) fn build(skeleton: &Skeleton) -> Body {
    let mut body = Body {
        positions: Vec::new(),
        triangles: Vec::new(),
        influences: Vec::new(),
        parts: Vec::new(),
    };
    for part in parts(skeleton) {
        let first_triangle = body.triangles.len();
        emit(&part, &mut body);
        body.parts
            .push((part.name, first_triangle..body.triangles.len()));
    }
    body
}

fn smoothstep_blend(x: f64, half_width: f64) -> f64 {
    let t = ((x + half_width) / (2.0 * half_width)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Weights of a point at axial position `u`: a telescoping partition of unity
/// (`c_0 = 1`, `c_k` = smoothstep past band k, `w_k = c_k − c_{k+1}`), so weights are
/// non-negative when bands do not overlap and always sum to 1.
fn weights(part: &Part, u: f64) -> Vec<(u32, f32)> {
    let mut out = Vec::with_capacity(2);
    let joints = std::iter::once(part.base).chain(part.bands.iter().map(|b| b.joint));
    let mut coverage = part
        .bands
        .iter()
        .map(|b| smoothstep_blend(u - b.at, b.half_width));
    let mut current = 1.0;
    for joint in joints {
        let next = coverage.next().unwrap_or(0.0);
        let w = current - next;
        if w > 0.0 {
            out.push((joint as u32, w as f32));
        }
        current = next;
    }
    out
}

fn emit(part: &Part, body: &mut Body) {
    let lathe = &part.lathe;
    let other = lathe.axis.cross(lathe.side);
    let base = body.positions.len() as u32;
    let push = |p: DVec3, body: &mut Body| {
        body.positions.push(p.as_vec3().to_array());
        body.influences
            .push(weights(part, (p - lathe.origin).dot(lathe.axis)));
    };
    let (first, rings, last) = match lathe.profile.as_slice() {
        [first, rings @ .., last] if !rings.is_empty() => (first, rings, last),
        _ => unreachable!("every built-in profile has two poles and at least one ring"),
    };
    push(lathe.origin + lathe.axis * first.0, body);
    for &(axial, radius) in rings {
        for s in 0..lathe.segments {
            let theta = std::f64::consts::TAU * s as f64 / lathe.segments as f64;
            let offset = lathe.side * (radius * lathe.scale.0 * theta.cos())
                + other * (radius * lathe.scale.1 * theta.sin());
            push(lathe.origin + lathe.axis * axial + offset, body);
        }
    }
    push(lathe.origin + lathe.axis * last.0, body);

    let n = lathe.segments as u32;
    let ring = |i: usize, s: u32| base + 1 + i as u32 * n + s % n;
    let last_pole = base + 1 + rings.len() as u32 * n;
    for s in 0..n {
        body.triangles.push([base, ring(0, s + 1), ring(0, s)]);
        for i in 0..rings.len() - 1 {
            let (a, b, c, d) = (
                ring(i, s),
                ring(i, s + 1),
                ring(i + 1, s + 1),
                ring(i + 1, s),
            );
            body.triangles.push([a, b, c]);
            body.triangles.push([a, c, d]);
        }
        body.triangles.push([
            last_pole,
            ring(rings.len() - 1, s),
            ring(rings.len() - 1, s + 1),
        ]);
    }
}

/// Number of samples to cover `length` at `RING_STEP`, at least one.
fn samples(length: f64) -> usize {
    ((length / RING_STEP).ceil() as usize).max(1)
}

/// Profile of a tapered capsule of axial length `length` with elliptical end caps: radius
/// `r0 → r1` along the shaft, caps reaching `h0` before the start and `h1` past the end.
/// With `length == 0` it is an ellipsoid.
fn capsule_profile(length: f64, (r0, h0): (f64, f64), (r1, h1): (f64, f64)) -> Vec<(f64, f64)> {
    let quarter = std::f64::consts::FRAC_PI_2;
    let cap_samples = |r: f64, h: f64| samples(quarter * r.max(h));
    let mut out = Vec::new();
    let n0 = cap_samples(r0, h0);
    for k in 0..n0 {
        let phi = quarter * k as f64 / n0 as f64;
        out.push((-h0 * phi.cos(), r0 * phi.sin()));
    }
    let shaft = if length > 0.0 { samples(length) } else { 0 };
    for k in 0..=shaft {
        let t = if shaft == 0 {
            0.0
        } else {
            k as f64 / shaft as f64
        };
        out.push((length * t, r0 + (r1 - r0) * t));
    }
    let n1 = cap_samples(r1, h1);
    for k in (0..n1).rev() {
        let phi = quarter * k as f64 / n1 as f64;
        out.push((length + h1 * phi.cos(), r1 * phi.sin()));
    }
    out
}

/// A smooth profile through `points` (centripetal Catmull–Rom, which neither overshoots nor
/// loops at the hat's tight brim corners), sampled about every `RING_STEP` of chord length.
fn smooth_profile(points: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let p = |i: isize| -> glam::DVec2 {
        let last = points.len() as isize - 1;
        let at = |j: isize| glam::DVec2::from(points[j as usize]);
        match i {
            i if i < 0 => 2.0 * at(0) - at(1),
            i if i > last => 2.0 * at(last) - at(last - 1),
            i => at(i),
        }
    };
    let mut out = vec![points[0]];
    for seg in 0..points.len() as isize - 1 {
        let [p0, p1, p2, p3] = [p(seg - 1), p(seg), p(seg + 1), p(seg + 2)];
        let knot = |a: glam::DVec2, b: glam::DVec2| a.distance(b).sqrt().max(1e-9);
        let (t0, t1) = (0.0, knot(p0, p1));
        let t2 = t1 + knot(p1, p2);
        let t3 = t2 + knot(p2, p3);
        let n = samples(p1.distance(p2));
        for k in 1..=n {
            let t = t1 + (t2 - t1) * k as f64 / n as f64;
            let a1 = p0 * ((t1 - t) / (t1 - t0)) + p1 * ((t - t0) / (t1 - t0));
            let a2 = p1 * ((t2 - t) / (t2 - t1)) + p2 * ((t - t1) / (t2 - t1));
            let a3 = p2 * ((t3 - t) / (t3 - t2)) + p3 * ((t - t2) / (t3 - t2));
            let b1 = a1 * ((t2 - t) / (t2 - t0)) + a2 * ((t - t0) / (t2 - t0));
            let b2 = a2 * ((t3 - t) / (t3 - t1)) + a3 * ((t - t1) / (t3 - t1));
            let c = b1 * ((t2 - t) / (t2 - t1)) + b2 * ((t - t1) / (t2 - t1));
            out.push(c.into());
        }
    }
    out
}

fn band(at: f64, half_width: f64, joint: usize) -> Band {
    Band {
        at,
        half_width,
        joint,
    }
}

/// Every part of the character, in a fixed order (the vertex order of the mesh).
fn parts(skeleton: &Skeleton) -> Vec<Part> {
    use joint::*;
    let j = |i: usize| skeleton.bind[i];
    let (x, y, z) = (DVec3::X, DVec3::Y, DVec3::Z);
    let mut parts = vec![
        Part {
            name: "torso",
            // One surface from crotch to the base of the neck, so the waist bends smoothly;
            // axial coordinate is world height.
            lathe: Lathe {
                origin: DVec3::ZERO,
                axis: z,
                side: x,
                scale: (1.0, 0.62),
                segments: 40,
                profile: smooth_profile(&[
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
                ]),
            },
            base: PELVIS,
            bands: vec![band(j(SPINE).z, 0.06, SPINE), band(j(CHEST).z, 0.08, CHEST)],
        },
        Part {
            name: "neck",
            lathe: Lathe {
                origin: DVec3::new(0.0, 0.0, 1.45),
                axis: z,
                side: x,
                scale: (1.0, 1.0),
                segments: 24,
                profile: capsule_profile(0.2, (0.052, 0.052), (0.048, 0.048)),
            },
            base: CHEST,
            bands: vec![
                band(j(NECK).z - 1.45, 0.035, NECK),
                band(j(HEAD).z - 1.45, 0.035, HEAD),
            ],
        },
        Part {
            name: "head",
            lathe: Lathe {
                origin: DVec3::new(0.0, -0.01, 1.70),
                axis: z,
                side: x,
                scale: (1.0, 1.16),
                segments: 36,
                profile: capsule_profile(0.0, (0.095, 0.125), (0.095, 0.125)),
            },
            base: HEAD,
            bands: vec![],
        },
        Part {
            name: "nose",
            // Small, but it makes the facing direction obvious in every picture.
            lathe: Lathe {
                origin: DVec3::new(0.0, -0.115, 1.69),
                axis: -y,
                side: x,
                scale: (0.8, 1.0),
                segments: 12,
                profile: capsule_profile(0.0, (0.022, 0.022), (0.022, 0.03)),
            },
            base: HEAD,
            bands: vec![],
        },
        Part {
            name: "hat",
            // A wide brim (radius 0.33 m, beyond the shoulders) rigid on the head: the large
            // moving occluder that makes shadows depend strongly on head pose.
            lathe: Lathe {
                origin: DVec3::new(0.0, -0.01, 1.755),
                axis: z,
                side: x,
                scale: (1.0, 1.0),
                segments: 56,
                profile: smooth_profile(&[
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
                ]),
            },
            base: HEAD,
            bands: vec![],
        },
    ];
    for (side, shoulder, elbow, wrist) in [
        (1.0, L_SHOULDER, L_ELBOW, L_WRIST),
        (-1.0, R_SHOULDER, R_ELBOW, R_WRIST),
    ] {
        let d = left_arm_direction() * DVec3::new(side, 1.0, 1.0);
        let arm = |name, origin, length, start, end, base, bands, segments, scale| Part {
            name,
            lathe: Lathe {
                origin,
                axis: d,
                side: y,
                scale,
                segments,
                profile: capsule_profile(length, start, end),
            },
            base,
            bands,
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
    }
    for (side, hip, knee, ankle) in [
        (1.0, L_HIP, L_KNEE, L_ANKLE),
        (-1.0, R_HIP, R_KNEE, R_ANKLE),
    ] {
        let left = side > 0.0;
        let thigh = j(hip).z - j(knee).z;
        let shin = j(knee).z - j(ankle).z;
        let leg = |name, origin, length, start, end, base, bands, segments| Part {
            name,
            lathe: Lathe {
                origin,
                axis: -z,
                side: x,
                scale: (1.0, 1.0),
                segments,
                profile: capsule_profile(length, start, end),
            },
            base,
            bands,
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
        parts.push(Part {
            name: if left { "l_foot" } else { "r_foot" },
            // Heel to toe along −y, sole on z = 0; rigid on the ankle, while the shin's lower
            // end blends into the ankle above it.
            lathe: Lathe {
                origin: DVec3::new(side * 0.09, 0.045, 0.045),
                axis: -y,
                side: x,
                scale: (1.0, 1.0),
                segments: 24,
                profile: capsule_profile(0.17, (0.04, 0.03), (0.045, 0.05)),
            },
            base: ankle,
            bands: vec![],
        });
    }
    parts
}
