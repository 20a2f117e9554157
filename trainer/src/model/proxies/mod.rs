//! Occluder proxies (issue 29): per bone, a few spheres standing in for the part of the body
//! the bone drives most, so the runtime can shadow a vertex by the parts of *other* bones in
//! poses no training pose showed. Each sphere moves with its bone's skinning matrix (posed
//! centre = `M_b · centre`); the runtime maths is aprt-core's, this module only fits them.
//!
//! # What a part is
//! Bone `b`'s part is the set of points inside the closed bind mesh whose nearest vertex is
//! dominated by `b` ([`BoneFrames::vertex_bone`]). Parts tile the mesh's volume, so the
//! spheres of different bones compete for no volume, and a part's surface is exactly the
//! skin that moves (mostly) with its bone.
//!
//! # How the spheres are fitted
//! For each bone with at least [`MIN_VERTICES`] vertices, Halton points fill the box of its
//! vertices until [`PART_SAMPLES`] of them lie in its part (grown by a tenth of its largest side and half the mean edge
//! length, so the part's whole volume is in it), and each is labelled in or out of the part.
//! Then for each `k` up to [`VOLUME_PER_BONE`] (or [`ProxyOptions::max_per_bone`] if smaller):
//!
//! 1. **centres**: k-means over the part's *interior* samples (farthest-point start, a fixed
//!    number of Lloyd steps), so the `k` centres tile the part's volume: along a limb they line
//!    up on its axis, on a head they sit at its middle. A part with too few interior samples
//!    (an open or paper-thin surface) clusters its vertices instead.
//! 2. **radii**: fitted so that the union of the spheres best matches the part's volume. Each
//!    radius in turn is the exact minimiser of the number of misfit samples (in the union but
//!    not the part, or the reverse) given the other spheres, a few rounds of this coordinate
//!    descent. Why not the mean distance of the cluster to its centre or axis: that measures
//!    the part's surface, which is right for a sphere but too large for a limb's cluster
//!    (whose ends stick out) and too small for a hat's crown; the volume criterion is the
//!    quantity the runtime needs (how much of the sky a part hides) and is what is reported,
//!    so fitting it directly leaves nothing to tune.
//!
//! **How many spheres**: every eligible part gets one; then spheres are added one at a time
//! to the part whose misfit volume the extra sphere reduces most, as long as it reduces it by
//! at least [`MIN_GAIN`] of that part's volume, up to [`VOLUME_PER_BONE`] per part and
//! `max_total` in all. So compact parts (a head) keep one sphere, elongated ones (a limb) get
//! more, and when the budget runs out it is the small parts that get fewer. When there are
//! more eligible parts than `max_total`, the smallest parts get none.
//!
//! # Covering the surface
//! What the runtime needs is the shadow a part casts, its silhouette seen from the vertices it
//! shades, not its volume; a thin wide part (the built-in hat's brim, 3 cm thick and 0.33 m in
//! radius) holds too little volume to earn a sphere by volume. So after the volume fit, a
//! vertex of a part lying more than a tolerance outside every sphere of its bone is
//! *uncovered* (the tolerance: [`COVER_TOLERANCE`] of the part's size, its vertices' extent
//! along their principal axis). The uncovered vertices are clustered by the same
//! deterministic k-means, and each cluster gets a sphere at its centroid whose radius is its
//! RMS distance to the centroid (its extent across the surface, so a ring of them hides
//! about the brim's area seen from below), capped at the bone's largest sphere and never
//! below the tolerance; the smallest `k` that covers every clustered vertex is taken. This
//! repeats until the part is covered or the budgets run out: `max_per_bone` in all per part
//! (spheres the volume fit did not use), `max_total` in all; when the total binds, the
//! largest uncovered areas (by the vertices' share of the surface) are covered first. Only
//! parts the volume fit gave spheres are covered. The report gives each part's coverage, the
//! share of its vertices within the tolerance of one of its spheres.
//!
//! # The volume error
//! Reported on a second, independent set of Halton points per part, drawn the same way (not the
//! points the radii were fitted on, so the figure is not flattered by the fit), over the box of
//! the part and its spheres: `|union △ part| / |part|`. The overall figure divides the summed
//! misfit volumes by the summed part volumes, and counts every part without proxies (too few
//! vertices, or left out by `max_total`) as missed entirely.
//!
//! # Inside the mesh
//! By the winding number along rays from the point, through the bake's BVH tracer
//! (`bake/tracer.rs`): its closest-hit query, repeated just past each hit, crosses every
//! surface on the ray in `O(log t)` each, where a parity count over all triangles would cost
//! `O(t)` per point (the built-in character has 14k triangles and a fit asks for about 10⁵
//! points). The signed count keeps points where two closed parts overlap inside; a majority of
//! three rays in fixed skew directions outvotes one that leaks through a hole of a mesh that is
//! not quite closed (the glTF characters) or grazes an edge. Zero-area triangles are left out
//! of the tracer, so they change nothing.
//!
//! # Measured (default options, this module's tests)
//!
//! | character | bones | with proxies | spheres | volume error | covered | fit |
//! | --- | --- | --- | --- | --- | --- | --- |
//! | built-in human | 17 | 16 | 64 | 69.0 % | 99.1 % | 0.6 s before the coverage |
//! | CesiumMan | 19 | 19 | 64 | 43.1 % | 99.9 % | |
//! | Fox | 24 | 19 | 60 | 47.7 % | 99.2 % | |
//! | a ball (test mesh) | 1 | 1 | 1 | 1.8 % | 100 % | |
//! | a capsule 5 × as long as thick | 1 | 1 | 4 | 32.1 % | 100 % | |
//! | a disc 10 × as wide as thick | 1 | 1 | 6 | 191.5 % | 100 % | |
//!
//! (Before the surface coverage: 55 spheres and 42.1 % on the built-in human, 60 and 31.8 %
//! on CesiumMan, 54 and 38.0 % on the Fox.) Limbs end at 18–45 % with four spheres: a union
//! of spheres is a string of beads, short of a cylinder between them and past it at their
//! middles, which is what capsules would fix. The built-in head's part (head, nose and hat)
//! gets one sphere by volume (radius 0.135 m over the head and the hat's crown; the brim is
//! too thin to pass [`MIN_GAIN`]) and then a ring of five on the brim's outer half (radii
//! 0.10–0.11 m, centres 0.27 m from the head's axis, in the brim's mid-plane), which covers
//! the brim but overshoots its thickness: that part's volume error goes from 62 % to 153 %,
//! the body's from 42 % to 69 %. The volume error says how much sky the proxies hide that the
//! body does not; coverage says whether every piece of skin that casts a shadow has a sphere.
//! A flat proxy (a disc or an oblate ellipsoid) would have both.
//!
//! # Determinism
//! Every step is a fixed sequence (Halton points, farthest-point starts with ties to the lowest
//! index, fixed iteration counts, sorted sweeps, stable sorts of the coverage's proposals); the only parallel loop labels each sample on
//! its own. Same input, same bytes.

mod cover;
mod solid;
mod spheres;
#[cfg(test)]
mod tests;

use std::collections::BTreeSet;

use glam::DVec3;
use nalgebra::{Matrix3, SymmetricEigen};

use crate::rig::bone_frames::BoneFrames;
use crate::rig::mesh::Mesh;
use cover::Surface;
use solid::{Solid, box_points};
use spheres::{Spheres, ball_radius, fit_radii, kmeans};

pub use cover::COVER_TOLERANCE;

/// One sphere: its bone (skin joint index, as [`BoneFrames::vertex_bone`] uses), its centre in
/// the bind pose (model space) and radius.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Proxy {
    /// The skin joint whose skinning matrix moves the sphere.
    pub bone: u16,
    /// Centre in the bind pose, in the mesh's model space.
    pub centre: [f64; 3],
    /// Radius, in the mesh's units. Always positive.
    pub radius: f64,
}

/// How many spheres a fit may use.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ProxyOptions {
    /// At most this many spheres per bone (default 8): at most [`VOLUME_PER_BONE`] from the
    /// volume fit, the rest to cover a thin part's surface.
    pub max_per_bone: usize,
    /// At most this many spheres in all (default 64).
    pub max_total: usize,
}

impl Default for ProxyOptions {
    fn default() -> Self {
        ProxyOptions {
            max_per_bone: 8,
            max_total: 64,
        }
    }
}

/// The fit's report for one bone with proxies.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoneProxies {
    /// The skin joint.
    pub bone: u16,
    /// Vertices it dominates.
    pub vertices: usize,
    /// Spheres it got.
    pub spheres: usize,
    /// `|union △ part| / |part|`, on samples independent of the fit.
    pub volume_error: f64,
    /// The part's volume, in the mesh's units cubed (estimated on the same samples).
    pub volume: f64,
    /// The share of its vertices within the coverage tolerance ([`COVER_TOLERANCE`] of the
    /// part's size) of one of its spheres.
    pub covered: f64,
}

/// Occluder proxies fitted to a mesh's parts.
#[derive(Clone, Debug, PartialEq)]
pub struct ProxyFit {
    /// The spheres, ordered by bone, then along the bone (by their position on the principal
    /// axis of the bone's vertices).
    pub proxies: Vec<Proxy>,
    /// Per bone (index = bone, one entry per bone of the [`BoneFrames`]): the bones whose
    /// dominant vertices share a triangle with this bone's, sorted, without itself. The
    /// runtime leaves a vertex's own bone and these to the learnt model.
    pub neighbours: Vec<Vec<u16>>,
    /// Per bone with proxies, in bone order: the fit's report.
    pub bones: Vec<BoneProxies>,
    /// Over all parts: summed misfit volume over summed part volume, parts without proxies
    /// counted as missed entirely.
    pub volume_error: f64,
    /// The share of the parts' summed volume that belongs to bones without proxies.
    pub uncovered: f64,
    /// The share of all vertices within the coverage tolerance of one of their bone's spheres;
    /// vertices of bones without proxies count as uncovered.
    pub covered: f64,
}

/// Why proxies could not be fitted.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ProxyError {
    /// The mesh has no vertices.
    #[error("the mesh has no vertices to fit occluder proxies to")]
    NoVertices,
    /// The bone frames do not have one bone per vertex.
    #[error("the bone frames name a bone for {bones} vertices, the mesh has {vertices}")]
    VertexCount {
        /// Vertices in the mesh.
        vertices: usize,
        /// Entries of `vertex_bone`.
        bones: usize,
    },
    /// More bones than a `u16` bone index can name.
    #[error("{count} bones, more than the 65536 a proxy's bone index can name")]
    TooManyBones {
        /// The bone count given.
        count: usize,
    },
    /// A vertex position that is NaN or infinite.
    #[error("vertex {vertex} has a position that is not a finite number")]
    NonFinite {
        /// The vertex.
        vertex: usize,
    },
    /// A vertex whose bone is not one of the bones.
    #[error("vertex {vertex} is dominated by bone {bone}, but there are only {count} bones")]
    BoneOutOfRange {
        /// The vertex.
        vertex: usize,
        /// Its bone.
        bone: u16,
        /// The bone count.
        count: usize,
    },
    /// A triangle corner naming a vertex that does not exist.
    #[error("triangle {triangle} names vertex {index}, but the mesh has {vertices}")]
    TriangleIndex {
        /// The triangle.
        triangle: usize,
        /// The index it names.
        index: u32,
        /// Vertices in the mesh.
        vertices: usize,
    },
}

/// Bones dominating fewer vertices than this get no proxies: too few to tell a part's shape,
/// and a part that small (a finger's tip, a single ring of a tail) hides little sky.
pub const MIN_VERTICES: usize = 8;

/// Halton samples are drawn into a part's box in batches of this many...
pub const SAMPLE_BATCH: usize = 4096;

/// ...until this many fall in the part (or [`MAX_SAMPLES`] are drawn): the misfit of a part
/// is then counted on about a thousand samples of it whatever share of its box it fills (a
/// limb at 40° fills a tenth of its box, the hat's crown a sixteenth), so its sampling noise
/// is a few per cent and the same for every part.
pub const PART_SAMPLES: usize = 1024;

/// At most this many samples per part and set: a part too thin to catch [`PART_SAMPLES`]
/// (a sheet, or an open mesh's part) is measured on what it caught.
pub const MAX_SAMPLES: usize = 16 * SAMPLE_BATCH;

/// Where in the Halton sequence the report's samples start: past every fit sample, so the two
/// sets never share a point.
const REPORT_FIRST: u64 = MAX_SAMPLES as u64;

/// A sphere is added to a part only if it removes at least this share of the part's volume
/// from the misfit. Above the sampling noise of the misfit (a few per cent for a part of a few
/// hundred samples), so noise never buys a sphere; 5 % keeps a ball at one sphere and gives a
/// limb three or four.
pub const MIN_GAIN: f64 = 0.05;

/// The volume fit gives a part at most this many spheres (fewer if
/// [`ProxyOptions::max_per_bone`] is smaller); the rest of the per-bone budget is for covering
/// its surface. Past four beads a limb's misfit falls by little (its volume error is the
/// waists between beads, see the module's documentation), and sixteen limbs and trunk parts at
/// five or more would spend the whole default budget before a brim got any.
pub const VOLUME_PER_BONE: usize = 4;

/// Clustering a part's interior samples needs at least this many; fewer (an open or very thin
/// part) and its vertices are clustered instead.
const MIN_INTERIOR: usize = 32;

/// Fits occluder proxies to `mesh`, whose vertices `bones` assigns to bones (see the module's
/// documentation for the method). Refuses an empty mesh, non-finite positions, bone or vertex
/// indices out of range, and bone frames for another mesh; zero-area triangles are harmless.
pub fn fit_proxies(
    mesh: &Mesh,
    bones: &BoneFrames,
    options: &ProxyOptions,
) -> Result<ProxyFit, ProxyError> {
    check(mesh, bones)?;
    let neighbours = neighbours(mesh, bones);
    let solid = Solid::new(&mesh.positions, &mesh.triangles, &bones.vertex_bone);
    let margin = 0.5 * mean_edge(mesh);
    let areas = vertex_areas(mesh);
    let parts: Vec<Part> = (0..bones.count)
        .filter_map(|b| Part::sample(mesh, bones, &areas, b as u16, margin, &solid))
        .collect();
    let per_bone = options.max_per_bone.min(VOLUME_PER_BONE);
    let candidates: Vec<Vec<Spheres>> =
        parts.iter().map(|part| part.candidates(per_bone)).collect();
    let counts = allocate(&parts, &candidates, options.max_total);

    // The volume fit's spheres, then more where the parts' surfaces are still uncovered (only
    // on parts the volume fit gave spheres: the others are too small, or out of budget).
    let mut spheres: Vec<Vec<(DVec3, f64)>> = parts
        .iter()
        .zip(&candidates)
        .zip(&counts)
        .map(|((_, fits), &count)| match count {
            0 => Vec::new(),
            _ => fits[count - 1].nonzero(),
        })
        .collect();
    let mut room: Vec<usize> = spheres
        .iter()
        .map(|s| match s.len() {
            0 => 0,
            n => options.max_per_bone.saturating_sub(n),
        })
        .collect();
    let used: usize = spheres.iter().map(Vec::len).sum();
    let surfaces: Vec<Surface> = parts.iter().map(Part::surface).collect();
    cover::cover(
        &surfaces,
        &mut spheres,
        &mut room,
        options.max_total.saturating_sub(used),
    );

    let (mut proxies, mut reports) = (Vec::new(), Vec::new());
    let (mut missed, mut total, mut uncovered) = (0.0, 0.0, 0.0);
    let mut covered = 0.0;
    for ((part, surface), spheres) in parts.iter().zip(&surfaces).zip(&spheres) {
        if spheres.is_empty() {
            missed += part.volume();
            total += part.volume();
            uncovered += part.volume();
            continue;
        }
        let spheres = part.ordered(spheres);
        let mut report = part.report(&spheres, margin, &solid);
        let balls: Vec<(DVec3, f64)> = spheres
            .iter()
            .map(|p| (DVec3::from(p.centre), p.radius))
            .collect();
        report.covered = surface.covered(&balls);
        missed += report.volume_error * report.volume;
        total += report.volume;
        covered += report.covered * part.vertices.len() as f64;
        reports.push(report);
        proxies.extend(spheres);
    }
    let share = |x: f64| if total > 0.0 { x / total } else { 0.0 };
    Ok(ProxyFit {
        proxies,
        neighbours,
        bones: reports,
        volume_error: share(missed),
        uncovered: share(uncovered),
        covered: covered / mesh.vertex_count() as f64,
    })
}

/// The typed refusals of [`fit_proxies`], in the order they are listed there.
fn check(mesh: &Mesh, bones: &BoneFrames) -> Result<(), ProxyError> {
    let vertices = mesh.vertex_count();
    if vertices == 0 {
        return Err(ProxyError::NoVertices);
    }
    if bones.vertex_bone.len() != vertices {
        return Err(ProxyError::VertexCount {
            vertices,
            bones: bones.vertex_bone.len(),
        });
    }
    if bones.count > usize::from(u16::MAX) + 1 {
        return Err(ProxyError::TooManyBones { count: bones.count });
    }
    if let Some(vertex) = mesh
        .positions
        .iter()
        .position(|p| p.iter().any(|x| !x.is_finite()))
    {
        return Err(ProxyError::NonFinite { vertex });
    }
    if let Some((vertex, &bone)) = bones
        .vertex_bone
        .iter()
        .enumerate()
        .find(|&(_, &b)| usize::from(b) >= bones.count)
    {
        return Err(ProxyError::BoneOutOfRange {
            vertex,
            bone,
            count: bones.count,
        });
    }
    for (triangle, t) in mesh.triangles.iter().enumerate() {
        if let Some(&index) = t.iter().find(|&&i| i as usize >= vertices) {
            return Err(ProxyError::TriangleIndex {
                triangle,
                index,
                vertices,
            });
        }
    }
    Ok(())
}

/// Per bone, the other bones whose vertices share a triangle with its own.
fn neighbours(mesh: &Mesh, bones: &BoneFrames) -> Vec<Vec<u16>> {
    let mut sets = vec![BTreeSet::new(); bones.count];
    for t in &mesh.triangles {
        let b = t.map(|i| bones.vertex_bone[i as usize]);
        for (x, y) in [(b[0], b[1]), (b[1], b[2]), (b[2], b[0])] {
            if x != y {
                sets[usize::from(x)].insert(y);
                sets[usize::from(y)].insert(x);
            }
        }
    }
    sets.into_iter().map(|s| s.into_iter().collect()).collect()
}

/// The mean length of the triangles' edges (0 without triangles): how far a part's volume
/// reaches past its outermost vertices is about half of it.
fn mean_edge(mesh: &Mesh) -> f64 {
    let p = |i: u32| DVec3::from(mesh.positions[i as usize].map(f64::from));
    let sum: f64 = mesh
        .triangles
        .iter()
        .map(|t| p(t[0]).distance(p(t[1])) + p(t[1]).distance(p(t[2])) + p(t[2]).distance(p(t[0])))
        .sum();
    sum / (3 * mesh.triangles.len()).max(1) as f64
}

/// Per vertex, a third of the area of its triangles: the share of the surface it stands for.
fn vertex_areas(mesh: &Mesh) -> Vec<f64> {
    let p = |i: u32| DVec3::from(mesh.positions[i as usize].map(f64::from));
    let mut areas = vec![0.0; mesh.vertex_count()];
    for t in &mesh.triangles {
        let area = 0.5 * (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0])).length();
        for &i in t {
            areas[i as usize] += area / 3.0;
        }
    }
    areas
}

/// The smallest and largest corner of `points`' box.
fn bounds(points: impl IntoIterator<Item = DVec3>) -> (DVec3, DVec3) {
    points
        .into_iter()
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p), hi.max(p))
        })
}

/// One bone's part, sampled for the fit.
struct Part {
    bone: u16,
    vertices: Vec<DVec3>,
    /// The area each vertex stands for.
    areas: Vec<f64>,
    /// The principal axis of the vertices, and their extent along it (the part's size).
    axis: DVec3,
    size: f64,
    /// The fit's samples and whether each is in the part.
    samples: Vec<DVec3>,
    in_part: Vec<bool>,
    /// Volume of the box the samples fill, per sample.
    cell: f64,
}

impl Part {
    /// The part of `bone`, sampled; `None` for a bone that dominates no vertex.
    fn sample(
        mesh: &Mesh,
        bones: &BoneFrames,
        areas: &[f64],
        bone: u16,
        margin: f64,
        solid: &Solid,
    ) -> Option<Part> {
        let (vertices, areas): (Vec<DVec3>, Vec<f64>) = mesh
            .positions
            .iter()
            .zip(areas)
            .zip(&bones.vertex_bone)
            .filter(|&(_, &b)| b == bone)
            .map(|((p, &a), _)| (DVec3::from(p.map(f64::from)), a))
            .unzip();
        if vertices.is_empty() {
            return None;
        }
        let axis = principal_axis(&vertices);
        let (lo, hi) = vertices
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                (lo.min(v.dot(axis)), hi.max(v.dot(axis)))
            });
        let part_box = grown(bounds(vertices.iter().copied()), margin);
        let (samples, in_part, cell) = sample_part(solid, bone, part_box, 0);
        Some(Part {
            bone,
            vertices,
            areas,
            axis,
            size: hi - lo,
            samples,
            in_part,
            cell,
        })
    }

    /// The part's volume as the fit's samples estimate it.
    fn volume(&self) -> f64 {
        self.in_part.iter().filter(|&&x| x).count() as f64 * self.cell
    }

    /// Whether the part may get spheres.
    fn eligible(&self) -> bool {
        self.vertices.len() >= MIN_VERTICES && self.volume() > 0.0
    }

    /// The best `k` spheres for each `k` in `1..=max` (fewer when the part has fewer points to
    /// cluster); none for a part that may not get spheres.
    fn candidates(&self, max: usize) -> Vec<Spheres> {
        if !self.eligible() {
            return Vec::new();
        }
        let interior: Vec<DVec3> = self
            .samples
            .iter()
            .zip(&self.in_part)
            .filter(|&(_, &x)| x)
            .map(|(p, _)| *p)
            .collect();
        let points = if interior.len() >= MIN_INTERIOR {
            &interior
        } else {
            &self.vertices
        };
        let mut fits: Vec<Spheres> = Vec::new();
        for k in 1..=max.min(points.len()) {
            let (centres, cluster) = kmeans(points, k);
            let radii = ball_radius(points, &cluster, &centres);
            let mut fit = fit_radii(&self.samples, &self.in_part, &centres, radii);
            if let Some(grown) = fits.last().map(|previous| self.grow(previous))
                && grown.misfit < fit.misfit
            {
                fit = grown;
            }
            fits.push(fit);
        }
        fits
    }

    /// `previous` and one more sphere, centred where the most part is still uncovered (see
    /// [`grow`](spheres::grow)). Never worse than `previous`, so a part's misfit falls with
    /// its sphere count even where a fresh k-means lands badly (k-means does not know about
    /// the radii: on the built-in character's hat, two clusters split the brim and fit worse
    /// than one sphere).
    fn grow(&self, previous: &Spheres) -> Spheres {
        spheres::grow(&self.samples, &self.in_part, previous)
    }

    /// The part's skin, for the coverage: its vertices, their areas and the tolerance.
    fn surface(&self) -> Surface<'_> {
        Surface {
            vertices: &self.vertices,
            areas: &self.areas,
            tolerance: COVER_TOLERANCE * self.size,
        }
    }

    /// `spheres` as the part's proxies, ordered along the principal axis of its vertices.
    fn ordered(&self, spheres: &[(DVec3, f64)]) -> Vec<Proxy> {
        let mut spheres: Vec<(f64, Proxy)> = spheres
            .iter()
            .map(|&(c, r)| {
                let proxy = Proxy {
                    bone: self.bone,
                    centre: c.to_array(),
                    radius: r,
                };
                (c.dot(self.axis), proxy)
            })
            .collect();
        spheres.sort_by(|a, b| a.0.total_cmp(&b.0));
        spheres.into_iter().map(|(_, p)| p).collect()
    }

    /// The volume error of `spheres` on fresh samples over the box of the part and the spheres.
    fn report(&self, spheres: &[Proxy], margin: f64, solid: &Solid) -> BoneProxies {
        let centres: Vec<DVec3> = spheres.iter().map(|s| DVec3::from(s.centre)).collect();
        let radii: Vec<f64> = spheres.iter().map(|s| s.radius).collect();
        let part_box = grown(bounds(self.vertices.iter().copied()), margin);
        let (lo, hi) = spheres.iter().fold(part_box, |(lo, hi), s| {
            let c = DVec3::from(s.centre);
            (lo.min(c - s.radius), hi.max(c + s.radius))
        });
        let (samples, in_part, cell) = sample_part(solid, self.bone, (lo, hi), REPORT_FIRST);
        let part = in_part.iter().filter(|&&x| x).count();
        let misfit = spheres::misfit(&samples, &in_part, &centres, &radii);
        BoneProxies {
            bone: self.bone,
            vertices: self.vertices.len(),
            spheres: spheres.len(),
            volume_error: misfit as f64 / part.max(1) as f64,
            volume: part as f64 * cell,
            covered: 0.0,
        }
    }
}

/// Halton points in the box `lo..hi` from the sequence's point `first` on, in batches of
/// [`SAMPLE_BATCH`] until [`PART_SAMPLES`] lie in `bone`'s part or [`MAX_SAMPLES`] are drawn;
/// with whether each is in the part, and the box's volume per point.
fn sample_part(
    solid: &Solid,
    bone: u16,
    (lo, hi): (DVec3, DVec3),
    first: u64,
) -> (Vec<DVec3>, Vec<bool>, f64) {
    let (mut samples, mut in_part) = (Vec::new(), Vec::new());
    let mut inside = 0;
    while inside < PART_SAMPLES && samples.len() < MAX_SAMPLES {
        let batch = box_points(lo, hi, first + samples.len() as u64, SAMPLE_BATCH);
        let labels = solid.in_part(bone, &batch);
        inside += labels.iter().filter(|&&x| x).count();
        samples.extend(batch);
        in_part.extend(labels);
    }
    let cell = (hi - lo).element_product() / samples.len() as f64;
    (samples, in_part, cell)
}

/// A box grown by a tenth of its largest side and `margin` on every side.
fn grown((lo, hi): (DVec3, DVec3), margin: f64) -> (DVec3, DVec3) {
    let grow = 0.1 * (hi - lo).max_element() + margin;
    // A single vertex with no triangles: give the box some size so it has a volume at all.
    let grow = if grow > 0.0 { grow } else { 1e-3 };
    (lo - grow, hi + grow)
}

/// The unit direction of largest spread of `points`, its largest component made positive.
fn principal_axis(points: &[DVec3]) -> DVec3 {
    let mean = points.iter().sum::<DVec3>() / points.len().max(1) as f64;
    let mut cov = Matrix3::zeros();
    for p in points {
        let d = nalgebra::Vector3::new(p.x - mean.x, p.y - mean.y, p.z - mean.z);
        cov += d * d.transpose();
    }
    let eigen = SymmetricEigen::new(cov);
    let i = eigen.eigenvalues.imax();
    let v = eigen.eigenvectors.column(i);
    let axis = DVec3::new(v[0], v[1], v[2]);
    let largest = axis.abs().max_element();
    let sign = if [axis.x, axis.y, axis.z]
        .into_iter()
        .find(|x| x.abs() == largest)
        .is_some_and(|x| x < 0.0)
    {
        -1.0
    } else {
        1.0
    };
    axis * sign
}

/// Spheres per part (indexed like `parts`): one for each eligible part (the largest
/// `max_total` when there are more), then more, a step at a time, to the part that gains most
/// per added sphere: a step takes a part from `k` to any `k' > k` spheres within the budgets,
/// its gain per sphere `(misfit(k) − misfit(k')) / (k' − k)` in volume, and is taken only
/// when that is at least [`MIN_GAIN`] of the part's volume. Looking past `k + 1` lets a part
/// whose second sphere helps little but whose third helps much (a thigh: the second sphere's
/// best place is beside the first) still get both.
fn allocate(parts: &[Part], candidates: &[Vec<Spheres>], max_total: usize) -> Vec<usize> {
    let mut counts = vec![0; parts.len()];
    let mut eligible: Vec<usize> = (0..parts.len())
        .filter(|&i| !candidates[i].is_empty())
        .collect();
    // Largest parts first; the bone breaks ties.
    eligible.sort_by(|&a, &b| {
        parts[b]
            .volume()
            .total_cmp(&parts[a].volume())
            .then(parts[a].bone.cmp(&parts[b].bone))
    });
    eligible.truncate(max_total);
    for &i in &eligible {
        counts[i] = 1;
    }
    let mut budget = max_total - eligible.len();
    loop {
        // (part, new count, gain per sphere); the first best in `eligible` order wins ties.
        let mut best: Option<(usize, usize, f64)> = None;
        for &i in &eligible {
            let (fits, k, cell) = (&candidates[i], counts[i], parts[i].cell);
            for next in k + 1..=fits.len().min(k + budget) {
                let gain = (fits[k - 1].misfit as f64 - fits[next - 1].misfit as f64) * cell
                    / (next - k) as f64;
                if gain >= MIN_GAIN * parts[i].volume() && best.is_none_or(|b| gain > b.2) {
                    best = Some((i, next, gain));
                }
            }
        }
        let Some((i, next, _)) = best else { break };
        budget -= next - counts[i];
        counts[i] = next;
    }
    counts
}
