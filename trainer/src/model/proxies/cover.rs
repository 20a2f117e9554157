//! Covering a part's surface: after the volume fit, spheres on the patches of a part's skin
//! that no sphere reaches, so a thin wide part (a hat's brim) casts its shadow even though it
//! holds too little volume to earn a sphere by volume.

use glam::DVec3;

use super::spheres::kmeans;

/// A vertex is covered when it lies within this share of its part's size (its vertices' extent
/// along their principal axis: a limb's length, a brim's diameter) of one of its bone's spheres.
///
/// What it trades: a larger tolerance buys fewer, fatter spheres (every coverage sphere is at
/// least this large), a smaller one more spheres and less overshoot. The shading the proxies
/// feed is order-3 SH, whose narrowest lobe is about 60° wide; a receiver not next to the part
/// (neighbours are left to the learnt model) is at least about the part's size away, so a
/// silhouette off by 15 % of that size moves the shadow's edge by under 9°, a seventh of what
/// the SH can resolve. On the built-in hat it is 0.1 m: the head's sphere then reaches the
/// brim's inner half and a ring of spheres its outer half.
pub const COVER_TOLERANCE: f64 = 0.15;

/// One part's skin, as the coverage sees it.
pub(super) struct Surface<'a> {
    /// The part's vertices.
    pub vertices: &'a [DVec3],
    /// The area each stands for (a third of its triangles').
    pub areas: &'a [f64],
    /// How far outside a sphere a vertex still counts as covered.
    pub tolerance: f64,
}

impl Surface<'_> {
    /// Whether `v` is within the tolerance of one of `spheres`.
    fn covers(&self, spheres: &[(DVec3, f64)], v: DVec3) -> bool {
        spheres
            .iter()
            .any(|&(c, r)| v.distance(c) <= r + self.tolerance)
    }

    /// The share of the vertices within the tolerance of one of `spheres` (1 for no vertices).
    pub fn covered(&self, spheres: &[(DVec3, f64)]) -> f64 {
        let n = self
            .vertices
            .iter()
            .filter(|&&v| self.covers(spheres, v))
            .count();
        if self.vertices.is_empty() {
            1.0
        } else {
            n as f64 / self.vertices.len() as f64
        }
    }
}

/// A sphere proposed for an uncovered patch, and the patch's area.
struct Patch {
    centre: DVec3,
    radius: f64,
    area: f64,
}

/// Spheres for the uncovered vertices of `surface` given its `spheres`, at most `room` of them:
/// for `k = 1, 2, …` the uncovered vertices are split by k-means (see [`kmeans`]) and each
/// cluster gets a sphere at its centroid, of radius its RMS distance to the centroid (its
/// extent across the surface) but no more than `cap` and no less than the tolerance. The first
/// `k` whose spheres leave no vertex of their clusters uncovered is taken; when none does, the
/// `k` leaving fewest uncovered (the smallest on ties).
///
/// Why the cap: a ring's centroid is its middle, not on it, and a sphere of the ring's RMS
/// radius around a whole brim (or half of one) covers its vertices, but as a ball the size of
/// the hat. Capped (at the bone's largest sphere, or the tolerance if larger), such a sphere
/// misses the ring, so the split goes on until the clusters are patches no larger than the
/// part's bulk: on the built-in hat, five arcs of the brim's outer half.
fn patches(surface: &Surface, spheres: &[(DVec3, f64)], room: usize, cap: f64) -> Vec<Patch> {
    let (points, areas): (Vec<DVec3>, Vec<f64>) = surface
        .vertices
        .iter()
        .zip(surface.areas)
        .filter(|&(&v, _)| !surface.covers(spheres, v))
        .map(|(&v, &a)| (v, a))
        .unzip();
    let tolerance = surface.tolerance;
    let mut best: Option<(usize, Vec<Patch>)> = None;
    for k in 1..=room.min(points.len()) {
        let (centres, cluster) = kmeans(&points, k);
        // (squared distances, members, area) per cluster.
        let mut sums = vec![(0.0, 0usize, 0.0); k];
        for ((p, &c), &a) in points.iter().zip(&cluster).zip(&areas) {
            sums[c].0 += p.distance_squared(centres[c]);
            sums[c].1 += 1;
            sums[c].2 += a;
        }
        let radii: Vec<f64> = sums
            .iter()
            .map(|&(d2, n, _)| (d2 / n.max(1) as f64).sqrt().min(cap).max(tolerance))
            .collect();
        let missed = points
            .iter()
            .zip(&cluster)
            .filter(|&(p, &c)| p.distance(centres[c]) > radii[c] + tolerance)
            .count();
        let patches: Vec<Patch> = (0..k)
            .filter(|&c| sums[c].1 > 0)
            .map(|c| Patch {
                centre: centres[c],
                radius: radii[c],
                area: sums[c].2,
            })
            .collect();
        if missed == 0 {
            return patches;
        }
        if best.as_ref().is_none_or(|b| missed < b.0) {
            best = Some((missed, patches));
        }
    }
    best.map(|b| b.1).unwrap_or_default()
}

/// Adds spheres to `spheres` (per part, as `(centre, radius)`) until every vertex of every part
/// is covered or the budgets run out: `room[i]` more for part `i`, `budget` in all. In rounds:
/// each part with room and uncovered vertices proposes its patches (see [`patches`]); they are
/// taken largest area first (then by part, then in k-means order), so when the total budget
/// binds it is the largest uncovered areas that get covered. Each round covers at least one
/// vertex per sphere it adds (a cluster has a member within its RMS distance of its centroid),
/// so the rounds end.
pub(super) fn cover(
    surfaces: &[Surface],
    spheres: &mut [Vec<(DVec3, f64)>],
    room: &mut [usize],
    mut budget: usize,
) {
    while budget > 0 {
        let mut proposed: Vec<(usize, Patch)> = Vec::new();
        for (i, surface) in surfaces.iter().enumerate() {
            if room[i] == 0 {
                continue;
            }
            let cap = spheres[i]
                .iter()
                .map(|s| s.1)
                .fold(surface.tolerance, f64::max);
            proposed.extend(
                patches(surface, &spheres[i], room[i], cap)
                    .into_iter()
                    .map(|p| (i, p)),
            );
        }
        if proposed.is_empty() {
            break;
        }
        // Stable: equal areas keep part and k-means order.
        proposed.sort_by(|a, b| b.1.area.total_cmp(&a.1.area));
        for (i, patch) in proposed {
            if budget == 0 {
                break;
            }
            if room[i] > 0 {
                spheres[i].push((patch.centre, patch.radius));
                room[i] -= 1;
                budget -= 1;
            }
        }
    }
}
