//! The UV atlas: which surface point every texel stands for.
//!
//! A light map stores transfer per texel of the character's UV layout (*Real-time Rendering of
//! Dynamic Objects in Dynamic, Low-frequency Lighting Environments*, Xu, Pattanaik and
//! Hughes). This module turns a layout ([`UvLayout`], UVs per triangle corner) into an
//! [`Atlas`]: the surface samples each texel is baked from, and how per-sample values become a
//! full map ([`Atlas::gather`]) that bilinear sampling ([`sample_bilinear`]) can read at any
//! vertex without picking up empty texels.
//!
//! **Convention** (glTF's): `u` right, `v` down, texel row 0 at `v = 0`. At resolution `R`,
//! texel `(x, y)` covers `u ∈ [x/R, (x+1)/R]`, `v ∈ [y/R, (y+1)/R]`, its centre is
//! `((x+½)/R, (y+½)/R)` and its index `y·R + x`.
//!
//! **Coverage** (`raster.rs`):
//! - a texel is covered by every triangle whose UV triangle contains its centre, edges
//!   included (within a hundredth of a texel width), with one sample per such
//!   triangle at the centre's barycentric coordinates: a centre on an edge shared by two
//!   triangles gets both, and the map holds their mean, as the paper does for shared edges;
//! - *conservative* coverage: a texel that a triangle overlaps (with positive area) but whose
//!   centre lies in no triangle gets one sample, at the closest point to its centre of the
//!   overlapping triangle whose closest point is nearest (ties to the lower triangle index).
//!   Triangles smaller than a texel therefore still get texels, and every texel an island
//!   touches holds a value of that island's own surface, not an extrapolation;
//! - degenerate UV triangles (no area, to f32 precision) cover nothing.
//!
//! **Gutters** (`dilate.rs`): bilinear sampling at a point on an island's edge reads the 2×2
//! texels around it, some of which no triangle touches. [`Atlas::gather`] fills [`GUTTER`]
//! rings of texels around the covered ones, ring by ring, each texel the mean of its already
//! filled 8-neighbours. Charts at least `2·GUTTER + 1` texels apart never mix: each island's
//! rings stay on its side of the gap (see [`GUTTER`]).

mod dilate;
pub mod generate;
pub mod pack;
mod raster;
mod sample;
mod surface;
pub use surface::point_on;

#[cfg(test)]
mod tests;

use glam::DVec2;

use crate::rig::mesh::Mesh;

pub use pack::{Placement, shelf_pack};
pub use sample::{sample_bilinear, sample_bilinear_by};

/// Rings of texels filled around the covered ones. One ring is what bilinear sampling needs at
/// full resolution: a point on an island's edge lies in a covered texel (coverage is
/// conservative), and its 2×2 footprint reaches at most one texel beyond. The second ring
/// keeps the same footprint filled in the first mip level (2×2 box filtered) and under the
/// half-texel shifts a block codec or a resampling may introduce. More would only widen the
/// padding charts need (`2·GUTTER + 1` texels, so that neither island's rings reach the
/// other's texels).
pub const GUTTER: usize = 2;

/// The largest resolution [`Atlas::build`] accepts: 8192² texels (64 M, the texture size
/// engines can be relied on to sample), far beyond any character's needs.
pub const MAX_RESOLUTION: usize = 8192;

/// A character's UVs, per triangle corner so that seams and wrap-around charts (where one
/// vertex has two UVs) are representable: one entry per triangle of the bind mesh, in `[0,1]²`
/// with glTF's convention (see the module docs). The atlas does not wrap: a corner outside
/// `[0,1]²` (glTF allows them, for repeating textures) covers only the texels its triangle
/// reaches inside the square.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct UvLayout {
    /// The UVs of each triangle's three corners, in the triangle's corner order.
    pub corners: Vec<[[f32; 2]; 3]>,
}

impl UvLayout {
    /// CRC-32 of every corner's UV: what a `.shlm` records of the atlas it was baked on, and
    /// a checkpoint of the texels it bakes, so maps are never read or resumed on other UVs.
    pub fn fingerprint(&self) -> u32 {
        let mut h = crc32fast::Hasher::new();
        for uv in self.corners.iter().flatten().flatten() {
            h.update(&uv.to_le_bytes());
        }
        h.finalize()
    }

    /// The first corner whose UV is not in `[0, 1]²` (or is NaN), as (triangle, corner, the
    /// offending coordinate): what a light-map atlas, stored or generated, must never have.
    pub fn outside_unit_square(&self) -> Option<(usize, usize, f32)> {
        self.corners.iter().enumerate().find_map(|(t, corners)| {
            corners.iter().enumerate().find_map(|(k, uv)| {
                uv.iter()
                    .find(|x| !(0.0..=1.0).contains(*x))
                    .map(|&x| (t, k, x))
            })
        })
    }

    /// The first triangle of `mesh` that has area while its UVs have none (to f32 precision,
    /// as the rasteriser tests): no texel stands for its surface.
    pub fn first_flat_triangle(&self, mesh: &Mesh) -> Option<usize> {
        let flat =
            |c: &[[f32; 2]; 3]| raster::is_flat_uv(c.map(|uv| DVec2::from(uv.map(f64::from))));
        (0..self.corners.len().min(mesh.triangles.len()))
            .find(|&t| flat(&self.corners[t]) && !mesh.is_degenerate(t))
    }

    /// The layout of a mesh with one UV per vertex (as glTF stores them). A corner naming a
    /// vertex without a UV gets NaN, which [`Atlas::build`] refuses, naming the triangle.
    pub fn from_vertex_uvs(uvs: &[[f32; 2]], triangles: &[[u32; 3]]) -> UvLayout {
        let uv = |i: u32| uvs.get(i as usize).copied().unwrap_or([f32::NAN; 2]);
        UvLayout {
            corners: triangles.iter().map(|t| t.map(uv)).collect(),
        }
    }

    /// Every distinct UV at which each of `vertex_count` vertices appears (several on a seam),
    /// in order of first appearance, for sampling a map at the vertices. Corners naming a
    /// vertex at or past `vertex_count`, or past the end of the layout, are ignored.
    pub fn vertex_uvs(&self, triangles: &[[u32; 3]], vertex_count: usize) -> Vec<Vec<[f32; 2]>> {
        let mut out = vec![Vec::new(); vertex_count];
        for (t, corners) in triangles.iter().zip(&self.corners) {
            for (&v, &uv) in t.iter().zip(corners) {
                let Some(list) = out.get_mut(v as usize) else {
                    continue;
                };
                let bits = uv.map(f32::to_bits);
                if !list.iter().any(|o: &[f32; 2]| o.map(f32::to_bits) == bits) {
                    list.push(uv);
                }
            }
        }
        out
    }
}

/// One surface point a texel is baked from: triangle `triangle` of the mesh at barycentric
/// coordinates `bary` (non-negative, summing to one, weighting the triangle's corners in
/// order).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TexelSample {
    /// Texel index `y·R + x`.
    pub texel: u32,
    /// Triangle index in the mesh.
    pub triangle: u32,
    /// Barycentric coordinates of the point in the triangle.
    pub bary: [f32; 3],
}

/// Why an atlas cannot be built.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum AtlasError {
    /// A resolution of zero texels or more than [`MAX_RESOLUTION`].
    #[error("atlas resolution {resolution} is not between 1 and {MAX_RESOLUTION}")]
    Resolution {
        /// The resolution asked for.
        resolution: usize,
    },
    /// Not one UV triple per triangle.
    #[error("the UV layout has {corners} triangles but the mesh has {triangles}")]
    LayoutLength {
        /// Triangles in the layout.
        corners: usize,
        /// Triangles in the mesh.
        triangles: usize,
    },
    /// A UV that is NaN or infinite (or names a vertex that has no UV).
    #[error("triangle {triangle} corner {corner} has UV {uv:?}, not a finite point")]
    NonFinite {
        /// The triangle.
        triangle: usize,
        /// Its corner (0, 1 or 2).
        corner: usize,
        /// The UV.
        uv: [f32; 2],
    },
}

/// A UV layout rasterised at one resolution: the surface samples every texel is baked from,
/// and the gutter rings [`Atlas::gather`] fills. Texel `(x, y)` covers `u ∈ [x/R, (x+1)/R]`,
/// `v ∈ [y/R, (y+1)/R]`; its centre is `((x+½)/R, (y+½)/R)`; its index `y·R + x`.
#[derive(Clone, Debug)]
pub struct Atlas {
    resolution: usize,
    triangle_count: usize,
    samples: Vec<TexelSample>,
    overlapping: usize,
    rings: dilate::Rings,
}

impl Atlas {
    /// Rasterises `layout` (one entry per triangle of `triangles`) at `resolution`² texels.
    /// Costs O(triangles × texels in their UV bounding boxes), in parallel over triangles.
    pub fn build(
        layout: &UvLayout,
        triangles: &[[u32; 3]],
        resolution: usize,
    ) -> Result<Atlas, AtlasError> {
        if resolution == 0 || resolution > MAX_RESOLUTION {
            return Err(AtlasError::Resolution { resolution });
        }
        if layout.corners.len() != triangles.len() {
            return Err(AtlasError::LayoutLength {
                corners: layout.corners.len(),
                triangles: triangles.len(),
            });
        }
        for (triangle, corners) in layout.corners.iter().enumerate() {
            if let Some(corner) = corners
                .iter()
                .position(|c| !c.iter().all(|x| x.is_finite()))
            {
                return Err(AtlasError::NonFinite {
                    triangle,
                    corner,
                    uv: corners[corner],
                });
            }
        }
        let coverage = raster::rasterise(&layout.corners, resolution);
        let rings = dilate::Rings::around(&coverage.samples, resolution);
        Ok(Atlas {
            resolution,
            triangle_count: triangles.len(),
            samples: coverage.samples,
            overlapping: coverage.overlapping,
            rings,
        })
    }

    /// Texels per side.
    pub fn resolution(&self) -> usize {
        self.resolution
    }

    /// The surface samples, sorted by texel (then triangle); a texel may have several (a
    /// centre on a shared edge, or overlapping UVs).
    pub fn samples(&self) -> &[TexelSample] {
        &self.samples
    }

    /// One surface point and unit normal per sample on a posed `mesh` of the bind mesh's
    /// topology: barycentric interpolation of positions and of vertex normals, renormalised
    /// (the face normal where the interpolated one vanishes, `+z` where that does too).
    ///
    /// # Panics
    /// If `mesh` does not have the triangle count the atlas was built for, or its triangles
    /// name vertices it lacks: posed meshes come from the same rig as the layout.
    pub fn surface(&self, mesh: &Mesh) -> (Vec<[f32; 3]>, Vec<[f32; 3]>) {
        assert_eq!(
            mesh.triangles.len(),
            self.triangle_count,
            "the atlas was built for {} triangles, the mesh has {}",
            self.triangle_count,
            mesh.triangles.len()
        );
        surface::surface(&self.samples, mesh)
    }

    /// The full map from per-sample values (`n2` each, sample-major): `R²·n2` values,
    /// texel-major (`[texel·n2 + c]`), each covered texel the mean over its samples, then
    /// [`GUTTER`] rings dilated outward from the covered texels, zero beyond.
    ///
    /// # Panics
    /// If `values` does not hold `n2` values per sample.
    pub fn gather(&self, values: &[f32], n2: usize) -> Vec<f32> {
        assert_eq!(
            values.len(),
            self.samples.len() * n2,
            "gather takes {n2} values for each of {} samples",
            self.samples.len()
        );
        self.rings.gather(&self.samples, values, n2)
    }

    /// `R²` flags: the texels that hold a value after [`Atlas::gather`] (covered or dilated).
    pub fn filled(&self) -> Vec<bool> {
        self.rings.filled()
    }

    /// Texels whose centre lies strictly inside two or more triangles (mirrored or
    /// overlapping UVs): their value mixes unrelated surface points, which is worth reporting.
    pub fn overlapping_texels(&self) -> usize {
        self.overlapping
    }
}
