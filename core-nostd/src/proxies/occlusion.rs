//! One vertex's occlusion by the proxies that may touch it (see the module above).

use core::f32::consts::PI;

use super::frame::{ProxyFrame, unit};
use crate::blob::format::VERTEX_BLOCK;
use crate::light::sphere_irradiance;
use crate::math;
use crate::rotation::Rotation;
use crate::sh::{
    DirectionLanes, MAX_COEFFS, MAX_ORDER, clamped_cosine, eval_basis, eval_basis_lanes, normalise,
};

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

/// One sphere's occlusion seen from a vertex, all but its SH basis.
enum Cap {
    /// The sphere does not reach the vertex (or fades out).
    Miss,
    /// The vertex is inside the sphere: every direction is blocked, the whole lobe goes.
    Inside,
    /// The cap of form factor `f` whose bands `f · ratio[l]` are taken about `axis` (in the
    /// frame the sum is in; not normalised).
    Tilted {
        f: f32,
        axis: [f32; 3],
        ratio: [f32; MAX_ORDER],
    },
}

/// The cap of one sphere seen from `position` (normal `normal`, unit), in the frame of
/// `rotation` when given, world otherwise.
fn cap(
    (centre, radius, reach2): ([f32; 3], f32, f32),
    (position, normal): ([f32; 3], [f32; 3]),
    rotation: Option<&Rotation>,
    cull: f32,
) -> Cap {
    let v = [0, 1, 2].map(|k| centre[k] - position[k]);
    let d2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
    if d2 >= reach2 {
        return Cap::Miss;
    }
    if d2 <= radius * radius {
        return Cap::Inside;
    }
    let s2 = radius * radius / d2;
    let weight = fade(s2, cull);
    if weight == 0.0 {
        return Cap::Miss;
    }
    let d = math::sqrt(d2);
    let axis = v.map(|x| x / d);
    let cos_beta = dot(axis, normal);
    let f = weight * sphere_irradiance(radius, d, cos_beta);
    if f <= 0.0 {
        return Cap::Miss;
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
    let axis = rotation.map_or(centre_of_weight, |r| to_bone(r, centre_of_weight));
    Cap::Tilted { f, axis, ratio }
}

/// Adds the whole cosine lobe about `normal` (a vertex inside a sphere) to `sum` and returns
/// its form factor, π (0 when the normal has no direction).
fn add_inside(
    order: usize,
    normal: [f32; 3],
    rotation: Option<&Rotation>,
    sum: &mut [f32; MAX_COEFFS],
) -> f32 {
    let n2 = order * order;
    let mut y = [0.0f32; MAX_COEFFS];
    let normal = rotation.map_or(normal, |r| to_bone(r, normal));
    if clamped_cosine(order, normal, &mut y[..n2]).is_err() {
        return 0.0;
    }
    for (s, y) in sum[..n2].iter_mut().zip(&y) {
        *s += y;
    }
    PI
}

/// Adds a tilted cap's bands, `f · ratio[l] · y_lm`, to `sum` (`y` its basis at the unit axis).
#[inline(always)]
fn add_bands(
    order: usize,
    f: f32,
    ratio: &[f32; MAX_ORDER],
    y: impl Fn(usize) -> f32,
    sum: &mut [f32; MAX_COEFFS],
) {
    for (l, ratio) in ratio.iter().enumerate().take(order) {
        let weight = f * ratio;
        let band = l * l..(l + 1) * (l + 1);
        for (c, s) in band.clone().zip(&mut sum[band]) {
            *s += weight * y(c);
        }
    }
}

/// Adds one sphere's occlusion seen from a vertex to `sum` (`order²` values) and returns its
/// form factor `F` (0 when it does not reach the vertex).
fn add_cap(
    order: usize,
    sphere: ([f32; 3], f32, f32),
    (position, normal): ([f32; 3], [f32; 3]),
    rotation: Option<&Rotation>,
    cull: f32,
    sum: &mut [f32; MAX_COEFFS],
) -> f32 {
    match cap(sphere, (position, normal), rotation, cull) {
        Cap::Miss => 0.0,
        Cap::Inside => add_inside(order, normal, rotation, sum),
        Cap::Tilted { f, axis, ratio } => {
            let n2 = order * order;
            let mut y = [0.0f32; MAX_COEFFS];
            if eval_basis(order, axis, &mut y[..n2]).is_err() {
                return 0.0;
            }
            add_bands(order, f, &ratio, |c| y[c], sum);
            f
        }
    }
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
    let mut sum = [0.0f32; MAX_COEFFS];
    let mut union = Union::NONE;
    while mask != 0 {
        let i = mask.trailing_zeros() as usize;
        mask &= mask - 1;
        let f = add_cap(
            order,
            frame.sphere(i),
            (position, normal),
            rotation,
            frame.cull,
            &mut sum,
        );
        union.add(f);
    }
    union.finish(&sum, &mut out[..order * order])
}

/// [`vertex_occlusion`] of the eight vertices of a block at once, with the same bits: lane `l`
/// has `masks[l]`, `vertices[l]` and `rotations[l]`, and its occlusion goes to `out[l]` where
/// the returned bits have `1 << l`. Each proxy's caps have their SH bases evaluated for the
/// eight lanes together ([`eval_basis_lanes`]); each lane sums its caps in the same order.
pub(crate) fn block_occlusion(
    frame: &ProxyFrame,
    order: usize,
    mut masks: [u64; VERTEX_BLOCK],
    vertices: [([f32; 3], [f32; 3]); VERTEX_BLOCK],
    rotations: [Option<&Rotation>; VERTEX_BLOCK],
    out: &mut [[f32; MAX_COEFFS]; VERTEX_BLOCK],
) -> u8 {
    let mut normals = [[0.0f32; 3]; VERTEX_BLOCK];
    for ((mask, n), &(position, normal)) in masks.iter_mut().zip(&mut normals).zip(&vertices) {
        *mask = within_reach(frame, *mask, position);
        match unit(normal).filter(|_| *mask != 0) {
            Some(unit) => *n = unit,
            None => *mask = 0,
        }
    }
    let mut sums = [[0.0f32; MAX_COEFFS]; VERTEX_BLOCK];
    let mut unions = [Union::NONE; VERTEX_BLOCK];
    let mut y = [[0.0f32; VERTEX_BLOCK]; MAX_COEFFS];
    let mut proxies = masks.iter().fold(0, |all, m| all | m);
    while proxies != 0 {
        let i = proxies.trailing_zeros() as usize;
        proxies &= proxies - 1;
        let mut axes: DirectionLanes = [
            [0.0; VERTEX_BLOCK],
            [0.0; VERTEX_BLOCK],
            [1.0; VERTEX_BLOCK],
        ];
        let mut tilted = [None; VERTEX_BLOCK];
        for l in (0..VERTEX_BLOCK).filter(|&l| masks[l] & (1 << i) != 0) {
            let (vertex, rotation) = ((vertices[l].0, normals[l]), rotations[l]);
            let f = match cap(frame.sphere(i), vertex, rotation, frame.cull) {
                Cap::Miss => 0.0,
                Cap::Inside => add_inside(order, normals[l], rotation, &mut sums[l]),
                // As `eval_basis` would refuse it: the cap adds nothing.
                Cap::Tilted { f, axis, ratio } => match normalise(axis) {
                    Err(_) => 0.0,
                    Ok(unit) => {
                        (0..3).for_each(|k| axes[k][l] = unit[k]);
                        tilted[l] = Some((f, ratio));
                        continue;
                    }
                },
            };
            unions[l].add(f);
        }
        if tilted.iter().any(Option::is_some) {
            eval_basis_lanes(order, axes, &mut y);
            for (l, cap) in tilted.iter().enumerate() {
                if let Some((f, ratio)) = cap {
                    add_bands(order, *f, ratio, |c| y[c][l], &mut sums[l]);
                    unions[l].add(*f);
                }
            }
        }
    }
    let mut reached = 0;
    for (l, ((union, sum), out)) in unions.iter().zip(&sums).zip(out).enumerate() {
        if masks[l] != 0 && union.finish(sum, &mut out[..order * order]) {
            reached |= 1 << l;
        }
    }
    reached
}

/// The union of a vertex's caps: their form factors' sum and the share of the lobe none of
/// them blocks.
#[derive(Clone, Copy)]
struct Union {
    total: f32,
    visible: f32,
}

impl Union {
    const NONE: Union = Union {
        total: 0.0,
        visible: 1.0,
    };

    fn add(&mut self, f: f32) {
        self.total += f;
        self.visible *= (1.0 - f / PI).max(0.0);
    }

    /// Writes the caps' summed occlusion `sum`, scaled to their union, into `out` (n² values)
    /// and returns true, or returns false when no cap reached the vertex.
    fn finish(self, sum: &[f32; MAX_COEFFS], out: &mut [f32]) -> bool {
        if self.total.is_nan() || self.total <= 0.0 {
            return false;
        }
        // The caps overlap: their union blocks `π (1 − Π (1 − F_i/π))` of the lobe, not `Σ F_i`.
        let scale = PI * (1.0 - self.visible) / self.total;
        for (o, s) in out.iter_mut().zip(sum) {
            *o = s * scale;
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::{block_occlusion, vertex_occlusion};
    use crate::blob::format::VERTEX_BLOCK;
    use crate::proxies::ProxyFrame;
    use crate::rotation::Rotation;
    use crate::sh::MAX_COEFFS;
    use crate::test_values::weight;

    /// Three values of the shared test sequence from `i`, times `scale`.
    fn vec(i: usize, scale: f32) -> [f32; 3] {
        [0, 1, 2].map(|k| scale * weight(i + k))
    }

    /// A rotation about z by `angle`.
    fn turn(angle: f32) -> Rotation {
        let (s, c) = (libm::sinf(angle), libm::cosf(angle));
        [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
    }

    /// The block kernel gives every lane `vertex_occlusion`'s bits and reach, at every order:
    /// 24 proxies, blocks whose lanes have partial masks, zero normals, vertices inside a
    /// sphere, lanes without proxies, and bone rotations or none.
    #[test]
    fn blocks_give_each_vertex_its_own_bits() {
        // A fresh stretch of the test sequence for each value drawn.
        let mut next = 0;
        let mut draw = |scale: f32| {
            next += 3;
            vec(next, scale)
        };
        let mut frame = ProxyFrame::new();
        frame.cull = 0.05;
        for i in 0..24 {
            frame.centres[i] = draw(1.2);
            frame.radii[i] = 0.05 + 0.25 * (draw(1.0)[0] + 0.85);
            frame.reach2[i] = frame.radii[i] * frame.radii[i] / frame.cull;
        }
        let rotations = [turn(0.3), turn(-1.2)];
        let mut lanes_reached = 0;
        for order in 1..=6 {
            for block in 0..40 {
                let masks: [u64; VERTEX_BLOCK] = core::array::from_fn(|l| match (block + l) % 5 {
                    0 => 0,
                    1 => (1 << 24) - 1,
                    _ => (draw(1.0)[0].to_bits() as u64) & ((1 << 24) - 1),
                });
                let vertices: [([f32; 3], [f32; 3]); VERTEX_BLOCK] = core::array::from_fn(|l| {
                    let position = match l {
                        3 => frame.centres[block % 24], // inside a sphere
                        _ => draw(1.4),
                    };
                    let normal = if (block + l) % 7 == 0 {
                        [0.0; 3]
                    } else {
                        draw(1.0)
                    };
                    (position, normal)
                });
                let lane_rotations: [Option<&Rotation>; VERTEX_BLOCK] =
                    core::array::from_fn(|l| (block % 3 != 0).then_some(&rotations[l % 2]));
                let mut out = [[0.0f32; MAX_COEFFS]; VERTEX_BLOCK];
                let reached =
                    block_occlusion(&frame, order, masks, vertices, lane_rotations, &mut out);
                for l in 0..VERTEX_BLOCK {
                    let mut alone = [0.0f32; MAX_COEFFS];
                    let hit = vertex_occlusion(
                        &frame,
                        order,
                        masks[l],
                        vertices[l],
                        lane_rotations[l],
                        &mut alone,
                    );
                    assert_eq!(
                        reached & (1 << l) != 0,
                        hit,
                        "order {order}, block {block}, lane {l}"
                    );
                    if hit {
                        lanes_reached += 1;
                        let n2 = order * order;
                        let same = out[l][..n2]
                            .iter()
                            .zip(&alone[..n2])
                            .all(|(a, b)| a.to_bits() == b.to_bits());
                        assert!(
                            same,
                            "order {order}, block {block}, lane {l}: {:?} against {:?}",
                            &out[l][..n2],
                            &alone[..n2]
                        );
                    }
                }
            }
        }
        // The cases reach: most lanes with proxies meet a cap.
        assert!(lanes_reached > 6 * 40 * 3, "{lanes_reached}");
    }
}
