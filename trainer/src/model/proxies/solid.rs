//! The volume a proxy fit is measured against: which points of space lie inside the closed
//! bind mesh, and which bone's part each belongs to (the bone of its nearest vertex), sampled
//! by a deterministic quasi-random point set.

use glam::{DVec3, Vec3A};
use rayon::prelude::*;

use crate::bake::tracer::{Accel, Tracer, TraversalStack, ray};

/// The `i`-th point (from 0) of the Halton sequence in bases 2, 3 and 5, in the unit cube.
/// Index 0 is skipped (it is the cube's corner), so point `i` is Halton's `i + 1`.
pub(super) fn halton(i: u64) -> DVec3 {
    DVec3::new(
        radical_inverse(i + 1, 2),
        radical_inverse(i + 1, 3),
        radical_inverse(i + 1, 5),
    )
}

/// Van der Corput's radical inverse of `i` in `base`: its digits mirrored after the point.
fn radical_inverse(mut i: u64, base: u64) -> f64 {
    let (mut value, mut scale) = (0.0, 1.0 / base as f64);
    while i > 0 {
        value += (i % base) as f64 * scale;
        i /= base;
        scale /= base as f64;
    }
    value
}

/// `count` quasi-random points in the box `[lo, hi]`: the Halton points `first..first + count`.
pub(super) fn box_points(lo: DVec3, hi: DVec3, first: u64, count: usize) -> Vec<DVec3> {
    (0..count as u64)
        .map(|i| lo + (hi - lo) * halton(first + i))
        .collect()
}

/// Points per leaf of the [`Nearest`] tree: below this a linear scan beats descending.
const LEAF: usize = 8;

/// Nearest-vertex queries over a fixed point set: a k-d tree stored as a permutation of the
/// points, each range split at its median along its box's widest axis. Ties between vertices
/// at the same distance go to the lower index, so the answer does not depend on the tree.
pub(super) struct Nearest {
    points: Vec<DVec3>,
    /// Point indices; the median of every range of more than [`LEAF`] is its split.
    order: Vec<u32>,
    /// Split axis of the range whose median sits at this position of `order`.
    axis: Vec<u8>,
}

impl Nearest {
    pub(super) fn new(points: Vec<DVec3>) -> Self {
        let mut tree = Nearest {
            order: (0..points.len() as u32).collect(),
            axis: vec![0; points.len()],
            points,
        };
        tree.build(0, tree.points.len());
        tree
    }

    fn build(&mut self, lo: usize, hi: usize) {
        if hi - lo <= LEAF {
            return;
        }
        let (mut min, mut max) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
        for &i in &self.order[lo..hi] {
            min = min.min(self.points[i as usize]);
            max = max.max(self.points[i as usize]);
        }
        let extent = max - min;
        let axis = if extent.x >= extent.y && extent.x >= extent.z {
            0
        } else if extent.y >= extent.z {
            1
        } else {
            2
        };
        let mid = lo + (hi - lo) / 2;
        let points = &self.points;
        self.order[lo..hi].select_nth_unstable_by(mid - lo, |&a, &b| {
            points[a as usize][axis]
                .total_cmp(&points[b as usize][axis])
                .then(a.cmp(&b))
        });
        self.axis[mid] = axis as u8;
        self.build(lo, mid);
        self.build(mid + 1, hi);
    }

    /// Index of the point nearest to `p` (the lowest index among equals); `None` when empty.
    pub(super) fn nearest(&self, p: DVec3) -> Option<usize> {
        let mut best = (f64::INFINITY, u32::MAX);
        self.search(p, 0, self.points.len(), &mut best);
        (best.1 != u32::MAX).then_some(best.1 as usize)
    }

    fn consider(&self, p: DVec3, i: u32, best: &mut (f64, u32)) {
        let d = p.distance_squared(self.points[i as usize]);
        if (d, i) < *best {
            *best = (d, i);
        }
    }

    fn search(&self, p: DVec3, lo: usize, hi: usize, best: &mut (f64, u32)) {
        if hi - lo <= LEAF {
            for &i in &self.order[lo..hi] {
                self.consider(p, i, best);
            }
            return;
        }
        let mid = lo + (hi - lo) / 2;
        let split = self.order[mid];
        self.consider(p, split, best);
        let axis = self.axis[mid] as usize;
        let diff = p[axis] - self.points[split as usize][axis];
        let (near, far) = if diff < 0.0 {
            ((lo, mid), (mid + 1, hi))
        } else {
            ((mid + 1, hi), (lo, mid))
        };
        self.search(p, near.0, near.1, best);
        // `<=`: a vertex on the far side at exactly the best distance may have a lower index.
        if diff * diff <= best.0 {
            self.search(p, far.0, far.1, best);
        }
    }
}

/// Rays cast per inside test, in the fixed directions of [`DIRECTIONS`]: a majority of three
/// outvotes one ray that slips through a hole or grazes a silhouette edge.
const DIRECTIONS: [[f32; 3]; 3] = [
    // Unit vectors far from the axes and from each other, so no ray runs along the lathe
    // rings and seams of the built-in character or the axis-aligned edges of a test mesh.
    [0.539_564_9, 0.312_790_3, 0.781_745_6],
    [-0.727_659_1, 0.618_470_3, 0.296_711_4],
    [0.171_541_3, -0.879_228_6, 0.444_483_4],
];

/// At most this many surfaces are counted along one ray: a bound on the work, far above the
/// depth complexity of a character (a ray through the built-in character crosses at most a
/// dozen surfaces).
const MAX_CROSSINGS: usize = 512;

/// The closed bind mesh as a solid, with each point's part.
pub(super) struct Solid<'a> {
    positions: &'a [[f32; 3]],
    triangles: &'a [[u32; 3]],
    vertex_bone: &'a [u16],
    tracer: Tracer,
    nearest: Nearest,
    /// How far past a hit the next search along the ray starts: 10⁻⁶ of the mesh's box
    /// diagonal, far above the rounding of a hit's distance and far below any wall's
    /// thickness, so every surface is counted once.
    step: f64,
}

impl<'a> Solid<'a> {
    /// The solid of a mesh whose indices and positions are checked (in range, finite).
    pub(super) fn new(
        positions: &'a [[f32; 3]],
        triangles: &'a [[u32; 3]],
        vertex_bone: &'a [u16],
    ) -> Self {
        let points: Vec<DVec3> = positions
            .iter()
            .map(|p| DVec3::from(p.map(f64::from)))
            .collect();
        let (min, max) = points
            .iter()
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &p| {
                (lo.min(p), hi.max(p))
            });
        Solid {
            positions,
            triangles,
            vertex_bone,
            tracer: Tracer::new(positions, triangles, Accel::default()),
            nearest: Nearest::new(points),
            step: 1e-6 * (max - min).length().max(f64::MIN_POSITIVE),
        }
    }

    /// For each of `points`, whether it lies in `bone`'s part: inside the mesh, with its
    /// nearest vertex dominated by `bone`. The nearest vertex is looked up first; only points
    /// that pass are traced. Each point's answer is its own, so the parallel loop gives the
    /// same result on any number of threads.
    pub(super) fn in_part(&self, bone: u16, points: &[DVec3]) -> Vec<bool> {
        points
            .par_iter()
            .map_init(TraversalStack::default, |stack, &p| {
                self.nearest
                    .nearest(p)
                    .is_some_and(|v| self.vertex_bone[v] == bone)
                    && self.inside(p, stack)
            })
            .collect()
    }

    /// Whether `p` is inside the mesh: the winding number along each ray (surfaces left from
    /// their back side minus surfaces entered from their front) is positive for at least two
    /// of the three rays. The signed count, unlike parity, keeps a point inside two closed
    /// parts that overlap (an arm sunk into the torso) inside.
    fn inside(&self, p: DVec3, stack: &mut TraversalStack) -> bool {
        let mut votes = 0;
        for (k, d) in DIRECTIONS.iter().enumerate() {
            votes += usize::from(self.winding(p, Vec3A::from(*d), stack) > 0);
            // Decided once two agree, or once the last ray cannot change the outcome.
            if votes == 2 || votes + (DIRECTIONS.len() - 1 - k) < 2 {
                break;
            }
        }
        votes >= 2
    }

    /// The winding number of the surface around `p`, counted along the ray from `p` in
    /// `direction`.
    fn winding(&self, p: DVec3, direction: Vec3A, stack: &mut TraversalStack) -> i32 {
        let origin = p.as_vec3a();
        let (o, d) = (origin.as_dvec3(), direction.as_dvec3());
        let (mut t_min, mut winding) = (0.0f64, 0);
        for _ in 0..MAX_CROSSINGS {
            let Some(hit) = self
                .tracer
                .closest(ray(origin, direction, t_min as f32, f32::INFINITY), stack)
            else {
                break;
            };
            winding += if hit.front_facing { -1 } else { 1 };
            let corners = self.triangles[hit.triangle as usize]
                .map(|i| DVec3::from(self.positions[i as usize].map(f64::from)));
            let point = corners
                .iter()
                .zip(hit.bary)
                .map(|(&c, w)| c * f64::from(w))
                .sum::<DVec3>();
            t_min = (point - o).dot(d).max(t_min) + self.step;
        }
        winding
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_agrees_with_a_scan_and_breaks_ties_by_index() {
        // A grid with repeated points (ties) and a Halton cloud of queries around it.
        let mut points: Vec<DVec3> = (0..200).map(|i| halton(i) * 2.0 - 1.0).collect();
        points.extend_from_within(..20);
        let tree = Nearest::new(points.clone());
        for q in box_points(DVec3::splat(-1.5), DVec3::splat(1.5), 1000, 500) {
            let scan = (0..points.len())
                .min_by(|&a, &b| {
                    q.distance_squared(points[a])
                        .total_cmp(&q.distance_squared(points[b]))
                        .then(a.cmp(&b))
                })
                .unwrap();
            assert_eq!(tree.nearest(q), Some(scan), "query {q}");
        }
        assert_eq!(Nearest::new(Vec::new()).nearest(DVec3::ZERO), None);
    }

    #[test]
    fn halton_points_fill_the_cube_evenly() {
        let n = 4096;
        let inside = (0..n)
            .filter(|&i| halton(i).distance(DVec3::splat(0.5)) <= 0.5)
            .count();
        let ball = std::f64::consts::PI / 6.0;
        assert!(
            (inside as f64 / n as f64 - ball).abs() < 0.01,
            "{inside} of {n} in the ball, expected {ball}"
        );
    }
}
