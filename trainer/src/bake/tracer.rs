//! Ray queries against one posed mesh: shadow (any-hit) and closest-hit with barycentrics.
//!
//! The default hierarchy is this crate's four-wide BVH (the `wide` module), built from obvhs'
//! binary BVH, whose shadow rays walk it in packets of one vertex's rays; the one-ray walk and
//! obvhs' own two hierarchies stay selectable so their speed can be measured on real scenes
//! (see `benches/bake.rs`). A brute-force loop over every triangle is the reference
//! the hierarchies must agree with and the baseline the benchmark reports the speed-up against.
//! All use the same ray–triangle test (obvhs' Möller–Trumbore), so on the same ray they take
//! the same decision.

use glam::{DVec3, Vec3A};
use obvhs::{
    BvhBuildParams,
    bvh2::{Bvh2, builder::build_bvh2_from_tris},
    cwbvh::{CwBvh, builder::build_cwbvh_from_tris},
    ray::{Ray, RayHit},
    triangle::Triangle,
};
use std::time::Duration;

pub(crate) use super::wide::TraversalStack;
use super::wide::{Bvh4, PACKET, Packet, octant_of};

/// Which acceleration structure answers the bake's ray queries.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Accel {
    /// A four-wide BVH with exact `f32` boxes collapsed from obvhs' binary BVH and traversed by
    /// this crate one ray at a time (see the `wide` module): the default until
    /// [`Accel::Bvh4Packet`], kept selectable as the benchmark's "before". On the 11.5k-vertex
    /// benchmark scene (`benches/bake.rs`, 500 rays, order 6) it took 1.60 CPU seconds per
    /// pose against 2.73 for [`Accel::CwBvh`] and 2.57 for [`Accel::Bvh2`] in the same run,
    /// build included, with bit-identical transfer.
    Bvh4,
    /// The [`Accel::Bvh4`] hierarchy, its shadow rays walking it in packets of up to 16 rays
    /// of one vertex that point in similar directions (see the `wide::packet` module);
    /// closest-hit rays (the bounce passes) still walk one at a time. The default: in
    /// `cargo bench -p aprt-trainer --bench bake`, alternating five timed bakes with
    /// [`Accel::Bvh4`] on 2 shared cores, the median pair gave 1.38× the rays per second on the
    /// benchmark scene (best bakes 6.62 against 4.49 Mrays/s) and 1.34× on the demo's bake of
    /// the built-in human (128 rays, order 6, four poses: 6.76 against 4.97 Mrays/s), with
    /// bit-identical transfer; earlier runs 1.36–1.39× and 1.28–1.31×.
    #[default]
    Bvh4Packet,
    /// obvhs' compressed 8-wide BVH (the previous default), kept selectable so the choice stays
    /// measurable: its 8-bit child boxes cost more to decompress than the extra node visits of
    /// the four-wide tree.
    CwBvh,
    /// obvhs' binary BVH, kept selectable so the choice stays measurable.
    Bvh2,
    /// Every ray against every triangle: `O(triangles)` per ray. The reference and the
    /// benchmark baseline, not for production bakes.
    BruteForce,
}

/// The closest front-facing-or-not surface a ray hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Hit {
    /// Index of the hit triangle in the input mesh.
    pub triangle: u32,
    /// Barycentric weights of the triangle's three vertices at the hit point (sum to 1).
    pub bary: [f32; 3],
    /// Whether the ray arrived on the side the triangle's winding (counter-clockwise) faces,
    /// the same orientation the area-weighted vertex normals use.
    pub front_facing: bool,
}

enum Structure {
    Wide(Bvh4),
    /// The same tree, shadow rays walking it in packets.
    WidePackets(Bvh4),
    Cw(CwBvh),
    Bvh2(Bvh2),
    /// Also used when no triangle has area: nothing to build a hierarchy over.
    BruteForce,
}

/// The triangles of one mesh in the order the hierarchy wants them, with their source ids.
pub(crate) struct Tracer {
    tris: Vec<Triangle>,
    source: Vec<u32>,
    structure: Structure,
}

impl Tracer {
    /// Builds the structure over the non-degenerate triangles. Triangles with exactly zero area
    /// cannot occlude anything and would only cost traversal time, so they are left out; the
    /// caller has already checked that every index is in range and every position finite.
    pub fn new(positions: &[[f32; 3]], triangles: &[[u32; 3]], accel: Accel) -> Self {
        let mut tris = Vec::with_capacity(triangles.len());
        let mut source = Vec::with_capacity(triangles.len());
        for (i, t) in triangles.iter().enumerate() {
            let [a, b, c] = t.map(|k| DVec3::from(positions[k as usize].map(f64::from)));
            if (b - a).cross(c - a) != DVec3::ZERO {
                let [v0, v1, v2] = t.map(|k| Vec3A::from(positions[k as usize]));
                tris.push(Triangle { v0, v1, v2 });
                source.push(i as u32);
            }
        }
        if tris.is_empty() {
            return Tracer {
                tris,
                source,
                structure: Structure::BruteForce,
            };
        }
        let mut build_time = Duration::ZERO;
        let (structure, order) = match accel {
            Accel::Bvh4 | Accel::Bvh4Packet => {
                // One triangle per leaf: on the benchmark scene the default leaves of up to
                // eight triangles cost 17–24% more traversal instructions (callgrind) for a
                // build saving of 2% of the pose.
                let params = BvhBuildParams {
                    max_prims_per_leaf: 1,
                    ..BvhBuildParams::medium_build()
                };
                let bvh = build_bvh2_from_tris(&tris, params, &mut build_time);
                reorder(&mut tris, &mut source, &bvh.primitive_indices);
                let wide = Bvh4::new(&bvh, &tris);
                let structure = if accel == Accel::Bvh4 {
                    Structure::Wide(wide)
                } else {
                    Structure::WidePackets(wide)
                };
                (structure, None)
            }
            Accel::CwBvh => {
                let bvh =
                    build_cwbvh_from_tris(&tris, BvhBuildParams::medium_build(), &mut build_time);
                let order = bvh.primitive_indices.clone();
                (Structure::Cw(bvh), Some(order))
            }
            Accel::Bvh2 => {
                let bvh =
                    build_bvh2_from_tris(&tris, BvhBuildParams::medium_build(), &mut build_time);
                let order = bvh.primitive_indices.clone();
                (Structure::Bvh2(bvh), Some(order))
            }
            Accel::BruteForce => (Structure::BruteForce, None),
        };
        if let Some(order) = order {
            reorder(&mut tris, &mut source, &order);
        }
        Tracer {
            tris,
            source,
            structure,
        }
    }

    /// Whether anything lies on the ray within `[tmin, tmax]`; stops at the first hit.
    pub fn occluded(&self, ray: Ray, stack: &mut TraversalStack) -> bool {
        let tris = &self.tris;
        let test = |r: &Ray, id: usize| tris[id].intersect(r);
        match &self.structure {
            Structure::Wide(bvh) | Structure::WidePackets(bvh) => bvh.occluded(tris, &ray, stack),
            Structure::Cw(bvh) => !bvh.ray_traverse_miss(ray, test),
            Structure::Bvh2(bvh) => !bvh.ray_traverse_miss(ray, test),
            Structure::BruteForce => tris.iter().any(|t| t.intersect(&ray) < f32::INFINITY),
        }
    }

    /// For every `i`, whether anything lies on the ray from `origin` along `dirs[i]` within
    /// `[t_min, ∞)`, written to `blocked[i]`: what [`Tracer::occluded`] answers for
    /// `ray(origin, dirs[i], t_min, ∞)`. `order` lists the indices of `dirs` so that neighbours
    /// point in similar directions; with [`Accel::Bvh4Packet`] consecutive entries of one
    /// direction octant share a packet, the other structures trace ray by ray.
    pub fn occluded_from(
        &self,
        origin: Vec3A,
        (dirs, order): (&[Vec3A], &[u32]),
        t_min: f32,
        blocked: &mut [bool],
        stack: &mut TraversalStack,
    ) {
        let Structure::WidePackets(bvh) = &self.structure else {
            for (b, &d) in blocked.iter_mut().zip(dirs) {
                *b = self.occluded(ray(origin, d, t_min, f32::INFINITY), stack);
            }
            return;
        };
        // Rays waiting for a full packet, one bucket per octant.
        let mut buckets = [[0u32; PACKET]; 8];
        let mut counts = [0usize; 8];
        let mut trace = |bucket: &[u32], stack: &mut TraversalStack| {
            let packet_dirs: [Vec3A; PACKET] = std::array::from_fn(|r| {
                dirs[bucket[r.min(bucket.len() - 1)] as usize] + Vec3A::ZERO
            });
            let packet = Packet::new(origin, &packet_dirs[..bucket.len()], t_min, f32::INFINITY);
            let mask = bvh.occluded_packet(&self.tris, &packet, stack);
            for (r, &i) in bucket.iter().enumerate() {
                blocked[i as usize] = mask >> r & 1 != 0;
            }
        };
        for &i in order {
            let o = usize::from(octant_of(dirs[i as usize]));
            buckets[o][counts[o]] = i;
            counts[o] += 1;
            if counts[o] == PACKET {
                trace(&buckets[o], stack);
                counts[o] = 0;
            }
        }
        for (bucket, &count) in buckets.iter().zip(&counts) {
            if count > 0 {
                trace(&bucket[..count], stack);
            }
        }
    }

    /// The closest surface on the ray, with barycentrics for interpolating vertex data.
    pub fn closest(&self, ray: Ray, stack: &mut TraversalStack) -> Option<Hit> {
        let tris = &self.tris;
        let test = |r: &Ray, id: usize| tris[id].intersect(r);
        let mut hit = RayHit::none();
        let found = match &self.structure {
            Structure::Wide(bvh) | Structure::WidePackets(bvh) => {
                bvh.closest(tris, ray, &mut hit, stack)
            }
            Structure::Cw(bvh) => bvh.ray_traverse(ray, &mut hit, test),
            Structure::Bvh2(bvh) => bvh.ray_traverse(ray, &mut hit, test),
            Structure::BruteForce => {
                for (id, t) in tris.iter().enumerate() {
                    let d = t.intersect(&Ray {
                        tmax: hit.t.min(ray.tmax),
                        ..ray
                    });
                    if d < hit.t {
                        hit.t = d;
                        hit.primitive_id = id as u32;
                    }
                }
                hit.t < ray.tmax
            }
        };
        if !found {
            return None;
        }
        let tri = &tris[hit.primitive_id as usize];
        let point = ray.origin.as_dvec3() + ray.direction.as_dvec3() * f64::from(hit.t);
        let [v0, v1, v2] = [tri.v0, tri.v1, tri.v2].map(|v| v.as_dvec3());
        let normal = (v1 - v0).cross(v2 - v0);
        Some(Hit {
            triangle: self.source[hit.primitive_id as usize],
            bary: barycentric(point, v0, v1, v2, normal),
            front_facing: normal.dot(ray.direction.as_dvec3()) < 0.0,
        })
    }
}

/// Lays the triangles (and their source ids) out in the order the leaves reference them: one
/// indirection less per intersection test.
fn reorder(tris: &mut Vec<Triangle>, source: &mut Vec<u32>, order: &[u32]) {
    *tris = order.iter().map(|&k| tris[k as usize]).collect();
    *source = order.iter().map(|&k| source[k as usize]).collect();
}

/// A ray for [`Tracer`] queries. Signed zeros in the direction are turned into +0: obvhs'
/// intersection test treats a −0 barycentric as outside, and an axis-aligned direction such
/// as (−0, −0, −1) produces exactly such values, so it would pass straight through triangles.
pub(crate) fn ray(origin: Vec3A, direction: Vec3A, t_min: f32, t_max: f32) -> Ray {
    Ray::new(origin, direction + Vec3A::ZERO, t_min, t_max)
}

/// Barycentric weights of `p` (projected onto the triangle's plane) in f64, clamped to the
/// triangle: the intersection test accepts points up to rounding outside an edge, and a weight
/// of −1e-9 must not extrapolate vertex data.
fn barycentric(p: DVec3, v0: DVec3, v1: DVec3, v2: DVec3, normal: DVec3) -> [f32; 3] {
    let area2 = normal.length_squared();
    let w1 = (p - v0).cross(v2 - v0).dot(normal) / area2;
    let w2 = (v1 - v0).cross(p - v0).dot(normal) / area2;
    let w = [1.0 - w1 - w2, w1, w2].map(|x| x.clamp(0.0, 1.0));
    let sum: f64 = w.iter().sum();
    w.map(|x| (x / sum) as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad_scene() -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
        // A unit square at z = 1 (facing +z), plus a degenerate triangle.
        let p = vec![
            [0.0, 0.0, 1.0],
            [1.0, 0.0, 1.0],
            [1.0, 1.0, 1.0],
            [0.0, 1.0, 1.0],
            [5.0, 5.0, 5.0],
        ];
        (p, vec![[0, 1, 2], [0, 2, 3], [4, 4, 4]])
    }

    #[test]
    fn closest_hit_reports_source_triangle_barycentrics_and_facing() {
        let (p, t) = quad_scene();
        for accel in [
            Accel::Bvh4,
            Accel::Bvh4Packet,
            Accel::CwBvh,
            Accel::Bvh2,
            Accel::BruteForce,
        ] {
            let tracer = Tracer::new(&p, &t, accel);
            let mut stack = TraversalStack::default();
            let up = ray(Vec3A::new(0.75, 0.25, 0.0), Vec3A::Z, 0.0, f32::INFINITY);
            let hit = tracer.closest(up, &mut stack).expect("hits the square");
            assert_eq!(hit.triangle, 0);
            // p = 0.25·v0 + 0.5·v1 + 0.25·v2 for (0.75, 0.25).
            for (got, want) in hit.bary.iter().zip([0.25, 0.5, 0.25]) {
                assert!((got - want).abs() < 1e-6, "{accel:?} {:?}", hit.bary);
            }
            assert!(
                !hit.front_facing,
                "arrives from below, against the +z winding"
            );
            let down = ray(Vec3A::new(0.2, 0.7, 2.0), -Vec3A::Z, 0.0, f32::INFINITY);
            let hit = tracer.closest(down, &mut stack).expect("hits the square");
            assert_eq!(hit.triangle, 1);
            assert!(hit.front_facing);
            assert!(tracer.occluded(up, &mut stack) && tracer.occluded(down, &mut stack));
            let short = ray(Vec3A::new(0.5, 0.5, 0.0), Vec3A::Z, 0.0, 0.9);
            assert!(
                !tracer.occluded(short, &mut stack) && tracer.closest(short, &mut stack).is_none()
            );
            let away = ray(Vec3A::new(0.5, 0.5, 0.0), -Vec3A::Z, 0.0, f32::INFINITY);
            assert!(!tracer.occluded(away, &mut stack));
        }
    }

    #[test]
    fn packets_from_surface_points_agree_with_brute_force() {
        // Two crossed quads, a box over them and zero-area triangles (collinear and a point),
        // shot at from their vertices, an edge midpoint and a face point, in bundles big
        // enough for full packets in every octant and partial ones.
        let mut p = vec![
            [-1.0, -1.0, 0.0],
            [1.0, -1.0, 0.0],
            [1.0, 1.0, 0.0],
            [-1.0, 1.0, 0.0],
            [0.0, -1.0, -1.0],
            [0.0, 1.0, -1.0],
            [0.0, 1.0, 1.0],
            [0.0, -1.0, 1.0],
            [0.0, 0.0, 0.7],
            [0.5, 0.5, 0.7],
            [1.0, 1.0, 0.7],
        ];
        let mut t = vec![
            [0, 1, 2],
            [0, 2, 3],
            [4, 5, 6],
            [4, 6, 7],
            [8, 9, 10],
            [9, 9, 9],
        ];
        let lid = p.len() as u32;
        p.extend([
            [-0.3, -0.3, 0.4],
            [0.6, -0.3, 0.4],
            [0.6, 0.6, 0.4],
            [-0.3, 0.6, 0.4],
        ]);
        t.extend([[lid, lid + 1, lid + 2], [lid, lid + 2, lid + 3]]);
        let packets = Tracer::new(&p, &t, Accel::Bvh4Packet);
        let brute = Tracer::new(&p, &t, Accel::BruteForce);
        let pattern = crate::bake::directions::cosine_hammersley(300);
        let order = crate::bake::directions::coherent_order(&pattern);
        let mut stack = TraversalStack::default();
        let (mut fast, mut slow) = (vec![false; 600], vec![false; 600]);
        for origin in [
            [1.0, 1.0, 0.0],
            [0.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.3, -0.2, 0.0],
            [0.6, 0.6, 0.4],
        ] {
            // Both hemispheres: the pattern and its mirror, with the order kept.
            let dirs: Vec<Vec3A> = pattern
                .iter()
                .flat_map(|d| [d.as_vec3a(), glam::DVec3::new(d.y, d.z, -d.x).as_vec3a()])
                .collect();
            let order: Vec<u32> = order.iter().flat_map(|&i| [2 * i, 2 * i + 1]).collect();
            let origin = Vec3A::from(origin);
            packets.occluded_from(origin, (&dirs, &order), 1e-4, &mut fast, &mut stack);
            brute.occluded_from(origin, (&dirs, &order), 1e-4, &mut slow, &mut stack);
            assert_eq!(fast, slow, "from {origin:?}");
            let blocked = fast.iter().filter(|&&b| b).count();
            assert!(
                blocked > 0 && blocked < 600,
                "{blocked} of 600 blocked from {origin:?}"
            );
        }
    }

    #[test]
    fn only_degenerate_triangles_mean_nothing_occludes() {
        let p = vec![[0.0; 3], [1.0, 1.0, 1.0], [2.0, 2.0, 2.0]];
        let tracer = Tracer::new(&p, &[[0, 1, 2]], Accel::CwBvh);
        let mut stack = TraversalStack::default();
        let ray = ray(
            Vec3A::new(1.0, 0.0, 1.0),
            Vec3A::new(-1.0, 1.0, 0.0).normalize(),
            0.0,
            10.0,
        );
        assert!(!tracer.occluded(ray, &mut stack) && tracer.closest(ray, &mut stack).is_none());
    }
}
