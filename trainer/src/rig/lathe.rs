//! Closed surfaces of revolution ("lathes") with smooth skinning weights along their axis: the
//! geometry the built-in character and the motion-capture mannequin are both made of, so both deform the
//! same way across joints.
//!
//! Every part is one closed surface (two poles joined by rings), so each edge is shared by
//! exactly two triangles and triangles wind counter-clockwise seen from outside. Parts overlap
//! at the joints instead of being stitched: the overlap hides the seam when a joint bends, and
//! keeps every part simple to build and to check.
//!
//! Weights are a function of a vertex's bind position along its part's axis: a part names the
//! joint for its first segment and, at each joint it crosses, the joint that takes over, with a
//! blend half-width. Across a joint the weight moves from one joint to the next along a
//! smoothstep, 50/50 at the joint itself. Neighbouring parts that use the same joint positions
//! and half-widths deform alike where they overlap.
//!
//! Profiles are sampled at a caller-given ring `step` (a length in the mesh's units), so one
//! builder serves a character in metres and a skeleton in a motion-capture file's units.
//!
//! **UV layout** (for SH light maps; [`Body::uv_layout`]). Each part is one rectangular chart,
//! cut along the seam at angle 0:
//!
//! - `u` goes around, `s / segments` at segment `s`; the triangles that close the ring use
//!   `u = 1` at the seam rather than 0, which is why UVs are per triangle corner;
//! - `v` goes along the profile, from 0 at the first pole to 1 at the last, in proportion to
//!   arc length along the profile (axial position against the mean of the two radii);
//! - a pole's corner in each fan triangle sits at the middle of its segment,
//!   `u = (s + ½) / segments`, so the fan is a row of separate triangles (a sawtooth), each
//!   with its own area, instead of collapsing to a point;
//! - charts are `mean ring circumference × profile length` in the mesh's units (the ring
//!   polygons' perimeters averaged over the rings), and all share one scale to UV, so texel
//!   density is uniform over the body; [`crate::rig::uv::shelf_pack`] places them in
//!   `[0,1]²`, [`crate::rig::uv::pack::CHART_PADDING`] apart (`2·GUTTER + 2` texels at
//!   256²), so that no chart's gutter reaches another's texels.
//!
//! The stretch of a chart is that of a cylinder's unrolling: exact along the shaft of a
//! capsule, and squeezed around towards the poles, where rings are shorter than the mean.

use std::ops::Range;

use glam::{DVec2, DVec3};

use crate::rig::uv::{UvLayout, shelf_pack};

/// The joint that takes over at axial position `at` along a part, blending over `±half_width`.
pub(crate) struct Band {
    pub at: f64,
    pub half_width: f64,
    pub joint: usize,
}

/// A closed surface of revolution around `axis` through `origin`. `profile` lists
/// `(axial, radius)` from the first pole to the last, clockwise in the (axial, radius) plane so
/// that the surface faces outward; the first and last radii are ignored (they are the poles).
/// Cross-sections are ellipses: radius × `scale.0` along `side`, × `scale.1` along
/// `axis × side`. `axis` and `side` are unit length and perpendicular.
pub(crate) struct Lathe {
    pub origin: DVec3,
    pub axis: DVec3,
    pub side: DVec3,
    pub scale: (f64, f64),
    pub segments: usize,
    pub profile: Vec<(f64, f64)>,
}

/// One body part: its surface and how it is weighted.
pub(crate) struct Part {
    pub lathe: Lathe,
    /// Joint that owns the part before its first band.
    pub base: usize,
    pub bands: Vec<Band>,
}

/// The assembled bind-pose surface: positions, triangles, per-vertex influences, the
/// triangle range of each part, in the order the parts were given (for per-part closedness
/// checks), and the UV charts (see the module docs).
// Nominally `pub` (the module is crate-private) because `procedural::Spec` names it.
pub struct Body {
    pub positions: Vec<[f32; 3]>,
    pub triangles: Vec<[u32; 3]>,
    pub influences: Vec<Vec<(u32, f32)>>,
    pub parts: Vec<Range<usize>>,
    /// Each triangle's corner UVs within its part's chart, in `[0,1]²`.
    pub chart_uvs: Vec<[[f64; 2]; 3]>,
    /// Each part's chart size, `[mean circumference, profile length]` in the mesh's units.
    pub chart_sizes: Vec<[f64; 2]>,
}

impl Body {
    /// The charts packed into one layout (see the module docs); `None` only if they do not
    /// fit ([`shelf_pack`]: more than about 1,600 parts).
    pub fn uv_layout(&self) -> Option<UvLayout> {
        let placement = shelf_pack(&self.chart_sizes)?;
        let mut corners = Vec::with_capacity(self.chart_uvs.len());
        for ((range, size), offset) in self
            .parts
            .iter()
            .zip(&self.chart_sizes)
            .zip(&placement.offsets)
        {
            let extent = [0, 1].map(|k| placement.scale * size[k]);
            corners.extend(
                self.chart_uvs[range.clone()]
                    .iter()
                    .map(|c| c.map(|uv| [0, 1].map(|k| (offset[k] + extent[k] * uv[k]) as f32))),
            );
        }
        Some(UvLayout { corners })
    }
}

/// Emits `parts` in order: the vertex and triangle order of the mesh.
pub(crate) fn build(parts: impl IntoIterator<Item = Part>) -> Body {
    let mut body = Body {
        positions: Vec::new(),
        triangles: Vec::new(),
        influences: Vec::new(),
        parts: Vec::new(),
        chart_uvs: Vec::new(),
        chart_sizes: Vec::new(),
    };
    for part in parts {
        let first_triangle = body.triangles.len();
        emit(&part, &mut body);
        body.chart_sizes.push(chart_size(&part.lathe));
        body.parts.push(first_triangle..body.triangles.len());
    }
    body
}

pub(crate) fn band(at: f64, half_width: f64, joint: usize) -> Band {
    Band {
        at,
        half_width,
        joint,
    }
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
        _ => unreachable!("every profile has two poles and at least one ring"),
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
    let v = profile_fractions(lathe);
    let u = |s: u32| f64::from(s) / f64::from(n);
    let pole_u = |s: u32| (f64::from(s) + 0.5) / f64::from(n);
    let last = rings.len() - 1;
    for s in 0..n {
        body.triangles.push([base, ring(0, s + 1), ring(0, s)]);
        body.chart_uvs
            .push([[pole_u(s), 0.0], [u(s + 1), v[1]], [u(s), v[1]]]);
        for i in 0..rings.len() - 1 {
            let (a, b, c, d) = (
                ring(i, s),
                ring(i, s + 1),
                ring(i + 1, s + 1),
                ring(i + 1, s),
            );
            let (va, vc) = (v[i + 1], v[i + 2]);
            body.triangles.push([a, b, c]);
            body.chart_uvs
                .push([[u(s), va], [u(s + 1), va], [u(s + 1), vc]]);
            body.triangles.push([a, c, d]);
            body.chart_uvs
                .push([[u(s), va], [u(s + 1), vc], [u(s), vc]]);
        }
        body.triangles
            .push([last_pole, ring(last, s), ring(last, s + 1)]);
        body.chart_uvs.push([
            [pole_u(s), 1.0],
            [u(s), v[last + 1]],
            [u(s + 1), v[last + 1]],
        ]);
    }
}

/// The profile in the (axial, mean radius) plane, where arc length is measured for the
/// chart's `v` (the mean of the cross-section's two radii stands for the ellipse).
fn meridian(lathe: &Lathe) -> Vec<DVec2> {
    let mean_scale = 0.5 * (lathe.scale.0 + lathe.scale.1);
    let last = lathe.profile.len() - 1;
    (lathe.profile.iter().enumerate())
        .map(|(k, &(axial, radius))| {
            // The poles are on the axis whatever radius the profile lists there.
            let r = if k == 0 || k == last { 0.0 } else { radius };
            DVec2::new(axial, r * mean_scale)
        })
        .collect()
}

/// Each profile point's arc length from the first pole, as a fraction of the whole (0 at the
/// first pole, 1 at the last; evenly spaced if the profile has no length).
fn profile_fractions(lathe: &Lathe) -> Vec<f64> {
    let points = meridian(lathe);
    let mut along = vec![0.0];
    for pair in points.windows(2) {
        along.push(along[along.len() - 1] + pair[0].distance(pair[1]));
    }
    let total = along[along.len() - 1];
    let count = (along.len() - 1) as f64;
    (along.iter().enumerate())
        .map(|(k, &a)| {
            if total > 0.0 {
                a / total
            } else {
                k as f64 / count
            }
        })
        .collect()
}

/// A part's chart size in the mesh's units: the mean perimeter of its ring polygons around,
/// the profile's arc length along.
fn chart_size(lathe: &Lathe) -> [f64; 2] {
    let points = meridian(lathe);
    let length: f64 = points.windows(2).map(|p| p[0].distance(p[1])).sum();
    let n = lathe.segments;
    let ellipse = |s: usize| {
        let theta = std::f64::consts::TAU * s as f64 / n as f64;
        DVec2::new(lathe.scale.0 * theta.cos(), lathe.scale.1 * theta.sin())
    };
    // The perimeter of a ring of radius r is r times that of the unit ring.
    let unit: f64 = (0..n).map(|s| ellipse(s).distance(ellipse(s + 1))).sum();
    let rings = &lathe.profile[1..lathe.profile.len() - 1];
    let mean_radius = rings.iter().map(|&(_, r)| r.abs()).sum::<f64>() / rings.len() as f64;
    [unit * mean_radius, length]
}

/// Number of samples to cover `length` at `step`, at least one.
fn samples(length: f64, step: f64) -> usize {
    ((length / step).ceil() as usize).max(1)
}

/// Profile of a tapered capsule of axial length `length` with elliptical end caps: radius
/// `r0 → r1` along the shaft, caps reaching `h0` before the start and `h1` past the end,
/// rings about every `step`. With `length == 0` it is an ellipsoid.
pub(crate) fn capsule_profile(
    step: f64,
    length: f64,
    (r0, h0): (f64, f64),
    (r1, h1): (f64, f64),
) -> Vec<(f64, f64)> {
    let quarter = std::f64::consts::FRAC_PI_2;
    let (n0, shaft, n1) = capsule_samples(step, length, (r0, h0), (r1, h1));
    let mut out = Vec::new();
    for k in 0..n0 {
        let phi = quarter * k as f64 / n0 as f64;
        out.push((-h0 * phi.cos(), r0 * phi.sin()));
    }
    for k in 0..=shaft {
        let t = if shaft == 0 {
            0.0
        } else {
            k as f64 / shaft as f64
        };
        out.push((length * t, r0 + (r1 - r0) * t));
    }
    for k in (0..n1).rev() {
        let phi = quarter * k as f64 / n1 as f64;
        out.push((length + h1 * phi.cos(), r1 * phi.sin()));
    }
    out
}

/// Samples of [`capsule_profile`]'s first cap, shaft (one fewer than its points) and last cap.
fn capsule_samples(
    step: f64,
    length: f64,
    (r0, h0): (f64, f64),
    (r1, h1): (f64, f64),
) -> (usize, usize, usize) {
    let quarter = std::f64::consts::FRAC_PI_2;
    let cap_samples = |r: f64, h: f64| samples(quarter * r.max(h), step);
    let shaft = if length > 0.0 {
        samples(length, step)
    } else {
        0
    };
    (cap_samples(r0, h0), shaft, cap_samples(r1, h1))
}

/// Vertices of a lathe of `segments` around [`capsule_profile`] of these arguments, counted
/// without building it (saturating, for sizes no mesh could have): two poles and a ring per
/// profile point in between.
pub(crate) fn capsule_vertices(
    segments: usize,
    step: f64,
    length: f64,
    start: (f64, f64),
    end: (f64, f64),
) -> usize {
    let (n0, shaft, n1) = capsule_samples(step, length, start, end);
    let points = n0
        .saturating_add(shaft)
        .saturating_add(1)
        .saturating_add(n1);
    (points - 2).saturating_mul(segments).saturating_add(2)
}

/// A smooth profile through `points` (centripetal Catmull–Rom, which neither overshoots nor
/// loops at tight corners such as a hat's brim), sampled about every `step` of chord length.
pub(crate) fn smooth_profile(step: f64, points: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let p = |i: isize| -> DVec2 {
        let last = points.len() as isize - 1;
        let at = |j: isize| DVec2::from(points[j as usize]);
        match i {
            i if i < 0 => 2.0 * at(0) - at(1),
            i if i > last => 2.0 * at(last) - at(last - 1),
            i => at(i),
        }
    };
    let mut out = vec![points[0]];
    for seg in 0..points.len() as isize - 1 {
        let [p0, p1, p2, p3] = [p(seg - 1), p(seg), p(seg + 1), p(seg + 2)];
        let knot = |a: DVec2, b: DVec2| a.distance(b).sqrt().max(1e-9);
        let (t0, t1) = (0.0, knot(p0, p1));
        let t2 = t1 + knot(p1, p2);
        let t3 = t2 + knot(p2, p3);
        let n = samples(p1.distance(p2), step);
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
