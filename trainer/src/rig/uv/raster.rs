//! Rasterising UV triangles into texel samples: centre coverage with shared edges, and
//! conservative coverage for the texels a triangle overlaps without containing their centre
//! (see the module docs of [`super`]). Geometry is in texel units (`uv · R`), in f64.

use glam::DVec2;
use rayon::prelude::*;

use super::TexelSample;
use crate::rig::mesh::is_flat;

/// How far outside a triangle (in texel widths) a texel centre may lie and still count as on
/// its edge: f32 UVs of a shared edge rounded differently in each triangle, or a centre
/// meant to lie exactly on an edge, land within about 1e-7 of a UV of each other, that is
/// 1e-3 texels at 8192², well inside this.
pub(super) const EDGE_TOLERANCE: f64 = 1e-2;

/// The samples of every texel, sorted by texel then triangle, and how many texels have a
/// centre strictly inside two or more triangles.
pub(super) struct Coverage {
    pub samples: Vec<TexelSample>,
    pub overlapping: usize,
}

/// How a triangle reaches a texel.
#[derive(Clone, Copy)]
enum Hit {
    /// The centre is in the triangle (edges included); `strict` when it is farther than
    /// [`EDGE_TOLERANCE`] from every edge.
    Centre { strict: bool },
    /// The triangle overlaps the texel, its closest point `distance2` (squared texels) from
    /// the centre.
    Near { distance2: f64 },
}

struct Candidate {
    sample: TexelSample,
    hit: Hit,
}

/// Rasterises the triangles' `corners` (finite UVs, checked by the caller) at `resolution`².
pub(super) fn rasterise(corners: &[[[f32; 2]; 3]], resolution: usize) -> Coverage {
    let mut candidates: Vec<Candidate> = corners
        .par_iter()
        .enumerate()
        .flat_map_iter(|(t, c)| {
            let scaled = c.map(|uv| DVec2::from(uv.map(f64::from)) * resolution as f64);
            UvTriangle::new(scaled)
                .map(|tri| tri.candidates(t as u32, resolution))
                .unwrap_or_default()
        })
        .collect();
    candidates.par_sort_unstable_by_key(|c| (c.sample.texel, c.sample.triangle));
    let mut samples = Vec::with_capacity(candidates.len());
    let mut overlapping = 0;
    for group in candidates.chunk_by(|a, b| a.sample.texel == b.sample.texel) {
        let centres = group.iter().filter_map(|c| match c.hit {
            Hit::Centre { strict } => Some((c.sample, strict)),
            Hit::Near { .. } => None,
        });
        let before = samples.len();
        let mut strict_count = 0;
        for (sample, strict) in centres {
            samples.push(sample);
            strict_count += usize::from(strict);
        }
        overlapping += usize::from(strict_count >= 2);
        if samples.len() > before {
            continue;
        }
        // Conservative coverage: the nearest closest point (ties to the lower triangle, the
        // group being sorted by triangle and `min_by` keeping the first minimum).
        let nearest = group
            .iter()
            .filter_map(|c| match c.hit {
                Hit::Near { distance2 } => Some((distance2, c.sample)),
                Hit::Centre { .. } => None,
            })
            .min_by(|a, b| a.0.total_cmp(&b.0));
        samples.extend(nearest.map(|(_, s)| s));
    }
    Coverage {
        samples,
        overlapping,
    }
}

/// Whether a UV triangle has no area to f32 precision ([`is_flat`]): it covers no texel.
pub(super) fn is_flat_uv(v: [DVec2; 3]) -> bool {
    let twice_area = (v[1] - v[0]).perp_dot(v[2] - v[0]);
    let edges = [
        v[0].distance(v[1]),
        v[1].distance(v[2]),
        v[2].distance(v[0]),
    ];
    is_flat(twice_area, edges)
}

/// A UV triangle in texel units with a nonzero area.
struct UvTriangle {
    v: [DVec2; 3],
    /// Twice the signed area.
    twice_area: f64,
}

impl UvTriangle {
    /// `None` for a degenerate triangle: the sine of every angle at most four f32 epsilons
    /// (the test [`crate::rig::mesh::Mesh::degenerate_triangles`] makes in 3D), so f32 UVs of
    /// three corners on a line cover nothing whatever their rounding.
    fn new(v: [DVec2; 3]) -> Option<UvTriangle> {
        let twice_area = (v[1] - v[0]).perp_dot(v[2] - v[0]);
        (!is_flat_uv(v) && twice_area.is_finite()).then_some(UvTriangle { v, twice_area })
    }

    /// Barycentric coordinates of `p` and its signed distance (texels, positive inside) to
    /// the edge opposite each corner.
    fn locate(&self, p: DVec2) -> ([f64; 3], [f64; 3]) {
        let mut bary = [0.0; 3];
        let mut distance = [0.0; 3];
        for i in 0..3 {
            let (a, b) = (self.v[(i + 1) % 3], self.v[(i + 2) % 3]);
            bary[i] = (b - a).perp_dot(p - a) / self.twice_area;
            distance[i] = bary[i] * self.twice_area.abs() / a.distance(b);
        }
        (bary, distance)
    }

    /// Whether the triangle and the texel square around `centre` overlap with positive area
    /// (separating axes: the square's two, the triangle's three edge normals).
    fn overlaps_texel(&self, centre: DVec2) -> bool {
        let (lo, hi) = (centre - 0.5, centre + 0.5);
        let min = self.v[0].min(self.v[1]).min(self.v[2]);
        let max = self.v[0].max(self.v[1]).max(self.v[2]);
        if min.x >= hi.x || max.x <= lo.x || min.y >= hi.y || max.y <= lo.y {
            return false;
        }
        (0..3).all(|i| {
            let normal = (self.v[(i + 1) % 3] - self.v[i]).perp();
            let project = |p: DVec2| normal.dot(p);
            let tri = self.v.map(project);
            let (t_lo, t_hi) = (
                tri[0].min(tri[1]).min(tri[2]),
                tri[0].max(tri[1]).max(tri[2]),
            );
            let reach = 0.5 * (normal.x.abs() + normal.y.abs());
            let c = project(centre);
            t_hi > c - reach && c + reach > t_lo
        })
    }

    /// The point of the triangle closest to `p` (outside it) as barycentric coordinates, and
    /// its squared distance: the closest of the three edges' closest points.
    fn closest(&self, p: DVec2) -> ([f64; 3], f64) {
        (0..3)
            .map(|i| {
                let j = (i + 1) % 3;
                let edge = self.v[j] - self.v[i];
                let t = ((p - self.v[i]).dot(edge) / edge.length_squared()).clamp(0.0, 1.0);
                let mut bary = [0.0; 3];
                bary[i] = 1.0 - t;
                bary[j] = t;
                (bary, p.distance_squared(self.v[i] + edge * t))
            })
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .unwrap_or_else(|| unreachable!("three edges"))
    }

    /// A candidate sample for every texel of the bounding box the triangle reaches.
    fn candidates(&self, triangle: u32, resolution: usize) -> Vec<Candidate> {
        let r = resolution as f64;
        let min = self.v[0].min(self.v[1]).min(self.v[2]);
        let max = self.v[0].max(self.v[1]).max(self.v[2]);
        let range =
            |lo: f64, hi: f64| lo.floor().clamp(0.0, r) as usize..hi.ceil().clamp(0.0, r) as usize;
        let mut out = Vec::new();
        for y in range(min.y, max.y) {
            for x in range(min.x, max.x) {
                let centre = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
                let texel = (y * resolution + x) as u32;
                let (bary, distance) = self.locate(centre);
                let (bary, hit) = if distance.iter().all(|&d| d >= -EDGE_TOLERANCE) {
                    let strict = distance.iter().all(|&d| d > EDGE_TOLERANCE);
                    (clamp_bary(bary), Hit::Centre { strict })
                } else if self.overlaps_texel(centre) {
                    let (bary, distance2) = self.closest(centre);
                    (bary, Hit::Near { distance2 })
                } else {
                    continue;
                };
                out.push(Candidate {
                    sample: TexelSample {
                        texel,
                        triangle,
                        bary: bary.map(|b| b as f32),
                    },
                    hit,
                });
            }
        }
        out
    }
}

/// Barycentric coordinates of a point within the edge tolerance, moved onto the triangle.
fn clamp_bary(bary: [f64; 3]) -> [f64; 3] {
    let clamped = bary.map(|b| b.max(0.0));
    let sum: f64 = clamped.iter().sum();
    clamped.map(|b| b / sum)
}
