//! Truth on the whole surface, not only at the vertices: points spread over the character's
//! surface by area, baked by the vertex bake's own simulator ([`crate::bake::bake_points`]:
//! the same rays, bounces and order), and every method read at those points as an engine
//! shows it — per-vertex values interpolated across each triangle as a GPU interpolates
//! varyings, a light map filtered bilinearly at the point's light-map UV. A shadow that falls
//! inside a large triangle is in the truth here and in a light map's texels, but not between
//! the vertices that bound it; the vertex error never sees it, the surface error does.
//!
//! The points are placed once on the bind mesh (triangle and barycentric coordinates) and
//! ride the skin: on every posed mesh a point is the same blend of its triangle's corners, so
//! a point's truth, its interpolated vertex values and its light-map texels all refer to one
//! place on the character.

pub mod error;

use crate::bake::checkpoint::BakeTarget;
use crate::bake::{BakeError, BakeSettings, PatternRotation, bake_points};
use crate::progress::BakeProgress;
use crate::rig::mesh::Mesh;
use crate::rig::uv::{UvLayout, point_on, sample_bilinear_by};

/// Surface points `aprt report` measures at unless told otherwise: about five per vertex of
/// the Fox, so each of its faces holds several.
pub const DEFAULT_SURFACE_POINTS: u64 = 8192;

/// One point of the surface: where it lies on the mesh and the share of the surface's area it
/// stands for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    /// Triangle index in the mesh.
    pub triangle: u32,
    /// Barycentric coordinates in that triangle (non-negative, summing to one).
    pub bary: [f32; 3],
    /// Its triangle's share of the bind surface's area, split evenly between the triangle's
    /// points: the weights sum to one. Triangles too small to get a point (fewer points than
    /// triangles) leave their area to those that did, so the weights still sum to one.
    pub weight: f64,
}

/// Points spread over a mesh by area ([`SurfacePoints::spread`]).
#[derive(Clone, Debug, PartialEq)]
pub struct SurfacePoints {
    /// The points, triangle by triangle in ascending triangle order.
    pub points: Vec<SurfacePoint>,
    /// Triangles of the mesh the points were spread on.
    pub triangles: usize,
}

/// Why points cannot be spread over a mesh.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SpreadError {
    /// No point asked for.
    #[error("0 surface points asked for: give one at least")]
    NoPoints,
    /// The mesh has no triangle with a finite, positive area.
    #[error("the mesh has no triangle with a finite, positive area to spread points over")]
    NoArea,
}

/// The plastic number's powers' inverses: the R2 low-discrepancy sequence (Roberts, 2018)
/// steps by these, which spreads any count of points evenly over the unit square.
const R2: [f64; 2] = [0.754_877_666_246_692_7, 0.569_840_290_998_053_2];

impl SurfacePoints {
    /// `count` points over the triangles of `bind`, stratified by area: each triangle gets its
    /// share of `count` by its area (the largest remainders round, lower triangle index first
    /// on ties), and its points lie along the R2 sequence folded into the triangle, so they
    /// are evenly spread inside it. Deterministic: the same mesh and count give the same
    /// points. Triangles without a finite, positive area get none.
    pub fn spread(bind: &Mesh, count: usize) -> Result<SurfacePoints, SpreadError> {
        if count == 0 {
            return Err(SpreadError::NoPoints);
        }
        let areas: Vec<f64> = (0..bind.triangles.len())
            .map(|t| triangle_area(bind, t))
            .collect();
        let total: f64 = areas.iter().sum();
        if !(total.is_finite() && total > 0.0) {
            return Err(SpreadError::NoArea);
        }
        let shares: Vec<f64> = areas.iter().map(|a| a / total * count as f64).collect();
        let mut counts: Vec<usize> = shares.iter().map(|s| s.floor() as usize).collect();
        let mut by_remainder: Vec<usize> = (0..shares.len()).collect();
        by_remainder.sort_by(|&a, &b| {
            let rem = |t: usize| shares[t] - shares[t].floor();
            rem(b).total_cmp(&rem(a)).then(a.cmp(&b))
        });
        let missing = count - counts.iter().sum::<usize>();
        for &t in by_remainder.iter().take(missing) {
            counts[t] += 1;
        }
        // Zero-area triangles never get a point (their remainder is 0), so this is positive.
        let represented: f64 = areas
            .iter()
            .zip(&counts)
            .map(|(&a, &n)| if n > 0 { a } else { 0.0 })
            .sum();
        let mut points = Vec::with_capacity(count);
        for (t, &n) in counts.iter().enumerate() {
            let weight = areas[t] / represented / n.max(1) as f64;
            points.extend((0..n).map(|i| SurfacePoint {
                triangle: t as u32,
                bary: r2_barycentric(i),
                weight,
            }));
        }
        Ok(SurfacePoints {
            points,
            triangles: bind.triangles.len(),
        })
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// CRC-32 of every point's triangle and coordinates: what a checkpoint records, so a
    /// resume at other points is refused.
    pub fn fingerprint(&self) -> u32 {
        let mut h = crc32fast::Hasher::new();
        for p in &self.points {
            h.update(&p.triangle.to_le_bytes());
            for b in p.bary {
                h.update(&b.to_le_bytes());
            }
        }
        h.finalize()
    }

    /// Each point's position and unit normal on posed `mesh` (the bind mesh's triangles):
    /// its triangle's corners and vertex normals blended, as a light map's texels are.
    pub fn on(&self, mesh: &Mesh) -> (Vec<[f32; 3]>, Vec<[f32; 3]>) {
        self.points
            .iter()
            .map(|p| point_on(mesh, p.triangle, p.bary))
            .unzip()
    }

    /// Per-vertex values (`n2` per vertex of the mesh `triangles` index) interpolated at
    /// every point, `n2` each: the barycentric blend of its triangle's corners in f32, what a
    /// GPU's varyings give the fragment there.
    pub fn from_vertices(&self, values: &[f32], n2: usize, triangles: &[[u32; 3]]) -> Vec<f32> {
        let mut out = Vec::with_capacity(self.len() * n2);
        for p in &self.points {
            let corners = triangles[p.triangle as usize].map(|v| &values[v as usize * n2..][..n2]);
            out.extend((0..n2).map(|c| {
                p.bary[0] * corners[0][c] + p.bary[1] * corners[1][c] + p.bary[2] * corners[2][c]
            }));
        }
        out
    }

    /// Each point's light-map UV in `layout` (one entry per triangle): its triangle's corner
    /// UVs blended by its barycentric coordinates.
    pub fn uvs(&self, layout: &UvLayout) -> Vec<[f32; 2]> {
        self.points
            .iter()
            .map(|p| {
                let c = layout.corners[p.triangle as usize];
                let b = p.bary;
                [0, 1].map(|k| b[0] * c[0][k] + b[1] * c[1][k] + b[2] * c[2][k])
            })
            .collect()
    }

    /// A light map held as its filled texels (`rows`, `n2` values per texel of `texels`,
    /// ascending texel indices, zero elsewhere; `resolution`² texels) read bilinearly at every
    /// point's UV (`uvs`, from [`SurfacePoints::uvs`]): what a renderer's filtered fetch gives.
    pub fn from_map_rows(
        rows: &[f32],
        texels: &[usize],
        resolution: usize,
        n2: usize,
        uvs: &[[f32; 2]],
    ) -> Vec<f32> {
        let texel = |t: usize| {
            let row = texels.binary_search(&t).ok()?;
            rows.get(row * n2..(row + 1) * n2)
        };
        let mut out = vec![0.0f32; uvs.len() * n2];
        for (value, &uv) in out.chunks_exact_mut(n2.max(1)).zip(uvs) {
            sample_bilinear_by(resolution, uv, texel, value);
        }
        out
    }

    /// A full map (`resolution`² texels × `n2`, texel-major) read bilinearly at every point.
    pub fn from_map(map: &[f32], resolution: usize, n2: usize, uvs: &[[f32; 2]]) -> Vec<f32> {
        let texels: Vec<usize> = (0..resolution * resolution).collect();
        SurfacePoints::from_map_rows(map, &texels, resolution, n2, uvs)
    }
}

/// The `i`-th point of the R2 sequence folded into a triangle (a point beyond the diagonal
/// of the unit square mirrors back), as barycentric coordinates.
fn r2_barycentric(i: usize) -> [f32; 3] {
    let n = (i + 1) as f64;
    let [mut u, mut v] = R2.map(|a| (0.5 + a * n).fract());
    if u + v > 1.0 {
        (u, v) = (1.0 - u, 1.0 - v);
    }
    [(1.0 - u - v) as f32, u as f32, v as f32]
}

/// Area of triangle `t` of `mesh` in f64; 0 for one whose area is not finite.
fn triangle_area(mesh: &Mesh, t: usize) -> f64 {
    let p = mesh.triangles[t].map(|v| glam::Vec3::from(mesh.positions[v as usize]).as_dvec3());
    let area = 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length();
    if area.is_finite() { area } else { 0.0 }
}

/// The surface points of every pose, as a checkpoint bakes them: each point's transfer on the
/// posed mesh from [`bake_points`], with each point's own turn of the ray pattern as each
/// vertex has in the vertex bake.
pub struct SurfaceTarget<'a>(pub &'a SurfacePoints);

impl BakeTarget for SurfaceTarget<'_> {
    fn describe(&self) -> String {
        format!(
            "{} surface points spread by area (CRC {:08x})",
            self.0.len(),
            self.0.fingerprint()
        )
    }

    fn points(&self, _mesh: &Mesh) -> usize {
        self.0.len()
    }

    fn bake(
        &self,
        mesh: &Mesh,
        settings: &BakeSettings,
        progress: &dyn BakeProgress,
    ) -> Result<Vec<f32>, BakeError> {
        let (positions, normals) = self.0.on(mesh);
        bake_points(
            mesh,
            (&positions, &normals),
            PatternRotation::PerPoint,
            settings,
            progress,
        )
    }
}

/// The transfer at `points` on every mesh of `meshes` (posed from the bind mesh they were
/// spread on), `order²` values per point, one vector per mesh: [`SurfaceTarget`] pose by pose.
pub fn bake_surface(
    points: &SurfacePoints,
    meshes: &[Mesh],
    settings: &BakeSettings,
) -> Result<Vec<Vec<f32>>, BakeError> {
    let target = SurfaceTarget(points);
    meshes
        .iter()
        .map(|mesh| target.bake(mesh, settings, &crate::progress::Silent))
        .collect()
}

#[cfg(test)]
mod tests;
