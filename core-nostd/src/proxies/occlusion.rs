//! One vertex's occlusion by the proxies that may touch it (see the module above).

use core::f32::consts::PI;

use super::frame::{ProxyFrame, unit};
use crate::light::sphere_irradiance;
use crate::math;
use crate::rotation::Rotation;
use crate::sh::{MAX_COEFFS, MAX_ORDER, clamped_cosine, eval_basis};

/// The zonal bands of the cosine-weighted cap, `2π ∫_{cos α}^1 t P_l(t) dt`, relative to band
/// 0 (`π sin²α`): with `c = cos α` they are `sin²α · q_l(c)`, `q = [1/2, (1 + c + c²)/(3(1 + c)),
/// (3c² + 1)/8, c³/2, (35c⁴ − 10c² − 1)/48, c³(9c² − 5)/8]`, factored so that no band cancels
/// for small caps (all tend to `sin²α / 2`). For a cap about the normal they are its exact
/// projection; tilted, the cosine is taken as its value along the axis (module doc).
fn cosine_cap_bands(d: f32, r: f32) -> ([f32; MAX_ORDER], f32) {
    // `cos α = √((d − r)/d · (1 + r/d))`, exact as `d → r` (as `sphere_light_bands`).
    let c = math::sqrt(((d - r) / d * (1.0 + r / d)).max(0.0));
    let (c2, c3) = (c * c, c * c * c);
    let bands = [
        1.0,
        2.0 * (1.0 + c + c2) / (3.0 * (1.0 + c)),
        (3.0 * c2 + 1.0) / 4.0,
        c3,
        (35.0 * c2 * c2 - 10.0 * c2 - 1.0) / 24.0,
        c3 * (9.0 * c2 - 5.0) / 4.0,
    ];
    (bands, c)
}

/// `Rᵀ v`: a world direction in a bone's frame.
fn to_bone(r: &Rotation, v: [f32; 3]) -> [f32; 3] {
    [0, 1, 2].map(|k| r[0][k] * v[0] + r[1][k] * v[1] + r[2][k] * v[2])
}

/// The fade of a cap of `sin²α = s2` kept from `cull`: 0 below it, 1 from twice it, a
/// smoothstep between, so that a sphere entering a vertex's reach never pops.
fn fade(s2: f32, cull: f32) -> f32 {
    if cull <= 0.0 {
        return 1.0;
    }
    let t = ((s2 - cull) / cull).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Adds one sphere's occlusion seen from `position` (normal `normal`, unit) to `sum`
/// (`order²` values, in the frame of `rotation` when given, world otherwise) and returns its
/// form factor `F` (0 when it does not reach the vertex).
fn add_cap(
    order: usize,
    (centre, radius, reach2): ([f32; 3], f32, f32),
    (position, normal): ([f32; 3], [f32; 3]),
    rotation: Option<&Rotation>,
    cull: f32,
    sum: &mut [f32; MAX_COEFFS],
) -> f32 {
    let v = [0, 1, 2].map(|k| centre[k] - position[k]);
    let d2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
    if d2 >= reach2 {
        return 0.0;
    }
    let n2 = order * order;
    let frame = |w: [f32; 3]| rotation.map_or(w, |r| to_bone(r, w));
    let mut y = [0.0f32; MAX_COEFFS];
    if d2 <= radius * radius {
        // Inside: every direction is blocked, the whole lobe goes.
        if clamped_cosine(order, frame(normal), &mut y[..n2]).is_err() {
            return 0.0;
        }
        for (s, y) in sum[..n2].iter_mut().zip(&y) {
            *s += y;
        }
        return PI;
    }
    let s2 = radius * radius / d2;
    let weight = fade(s2, cull);
    if weight == 0.0 {
        return 0.0;
    }
    let d = math::sqrt(d2);
    let axis = v.map(|x| x / d);
    let cos_beta = dot(axis, normal);
    let f = weight * sphere_irradiance(radius, d, cos_beta);
    if f <= 0.0 {
        return 0.0;
    }
    let (ratio, cos_alpha) = cosine_cap_bands(d, radius);
    // The cosine's tilt across the cap, `(n⊥·ω) 1_cap`, is the derivative as the axis turns
    // towards n⊥ of the zonal `max(a·ω − cos α, 0)`, whose band 0 is `π (1 − cos α)²`. To
    // first order it moves the cap's centre of weight towards the normal: the bands are taken
    // about `a + π (1 − cos α)² n⊥ k / F` instead of `a` (`k` the share of the cap the horizon
    // keeps, so the shift vanishes with the cap). Exact in band 0; the other bands are off by
    // the second order of the shift, a few percent for a cap of 40° tilted 40°.
    let unclipped = PI * s2 * cos_beta * weight;
    let kept = (unclipped / f).clamp(0.0, 1.0);
    let shift = kept * weight * PI * (1.0 - cos_alpha) * (1.0 - cos_alpha) / f;
    let centre_of_weight = [0, 1, 2].map(|k| axis[k] + shift * (normal[k] - cos_beta * axis[k]));
    if eval_basis(order, frame(centre_of_weight), &mut y[..n2]).is_err() {
        return 0.0;
    }
    for (l, ratio) in ratio.iter().enumerate().take(order) {
        let weight = f * ratio;
        for c in l * l..(l + 1) * (l + 1) {
            sum[c] += weight * y[c];
        }
    }
    f
}

fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The proxies of `mask` whose reach holds `position`: one distance each, before the normal
/// is even normalised, since most vertices of a block in reach are out of every cap's.
fn within_reach(frame: &ProxyFrame, mut mask: u64, position: [f32; 3]) -> u64 {
    let mut reached = 0;
    while mask != 0 {
        let i = mask.trailing_zeros() as usize;
        mask &= mask - 1;
        let c = frame.centres[i];
        let v = [c[0] - position[0], c[1] - position[1], c[2] - position[2]];
        if v[0] * v[0] + v[1] * v[1] + v[2] * v[2] < frame.reach2[i] {
            reached |= 1 << i;
        }
    }
    reached
}

/// The occlusion `D` of one vertex at `position` with `normal` (any length) by the proxies of
/// `mask` (those `frame` lets touch the vertex's bone, and its block), into `out` (`order²`
/// values, in the frame of `rotation` when given: the vertex's bone frame; world otherwise).
/// Returns whether any proxy reached it (`out` is untouched otherwise). A zero or non-finite
/// normal sees nothing.
pub(crate) fn vertex_occlusion(
    frame: &ProxyFrame,
    order: usize,
    mask: u64,
    (position, normal): ([f32; 3], [f32; 3]),
    rotation: Option<&Rotation>,
    out: &mut [f32],
) -> bool {
    let mut mask = within_reach(frame, mask, position);
    let Some(normal) = unit(normal).filter(|_| mask != 0) else {
        return false;
    };
    let n2 = order * order;
    let mut sum = [0.0f32; MAX_COEFFS];
    let (mut total, mut visible) = (0.0f32, 1.0f32);
    while mask != 0 {
        let i = mask.trailing_zeros() as usize;
        mask &= mask - 1;
        let sphere = (frame.centres[i], frame.radii[i], frame.reach2[i]);
        let f = add_cap(
            order,
            sphere,
            (position, normal),
            rotation,
            frame.cull,
            &mut sum,
        );
        total += f;
        visible *= (1.0 - f / PI).max(0.0);
    }
    if total.is_nan() || total <= 0.0 {
        return false;
    }
    let out = &mut out[..n2];
    // The caps overlap: their union blocks `π (1 − Π (1 − F_i/π))` of the lobe, not `Σ F_i`.
    let scale = PI * (1.0 - visible) / total;
    for (o, s) in out.iter_mut().zip(&sum) {
        *o = s * scale;
    }
    true
}
