//! Light-map UVs made for lighting rather than painting: charts cut at hard edges, flattened
//! with low distortion and packed at uniform texel density with a margin, by the `uvunwrap`
//! crate (xatlas-style segmentation, LSCM + ARAP, shape packing). What this module adds is
//! the choice of cuts, because a light map cannot hold a discontinuity inside a chart:
//!
//! - where the mesh splits its shading normals along an edge (a faceted character such as the
//!   Fox splits every edge), the baked transfer jumps across the edge, so it is always cut;
//!   `uvunwrap` itself would ignore such splits on a mostly flat-shaded mesh and merge the
//!   faces into charts;
//! - where the surface folds by more than the hard angle between the two faces' normals, it is
//!   cut even if the normals are shared (as Unity's "Generate Lightmap UVs" does, whose
//!   default, 88°, is ours).

use std::collections::HashMap;

use glam::Vec3;

use super::{GUTTER, UvLayout};
use crate::rig::mesh::Mesh;

/// The hard angle engines default to (Unity's "Generate Lightmap UVs"): an edge between faces
/// whose normals are further apart than this is a chart boundary (but where a crease ends
/// inside smooth surface, which no cut can separate without cutting the smooth surface too).
pub const DEFAULT_HARD_ANGLE_DEG: f32 = 88.0;

/// The margin that keeps charts from mixing: `uvunwrap` leaves twice the margin in empty
/// texels between two charts' (conservatively rasterised) texels, so each chart's [`GUTTER`]
/// rings of dilated texels stay on its side of the gap (tested on the real characters).
pub const DEFAULT_MARGIN_TEXELS: u32 = GUTTER as u32;

/// Shading normals closer than this (cosine of about 0.8°) are the same normal: exporters
/// round normals, and a smooth mesh's welded copies may differ in the last bits.
const SAME_NORMAL_COS: f32 = 0.9999;

/// How a light-map atlas is generated.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UnwrapSettings {
    /// Atlas width and height in texels: the packing's page.
    pub resolution: usize,
    /// Faces folding by more than this many degrees are cut apart.
    pub hard_angle_deg: f32,
    /// Empty texels around each chart (charts are twice this apart).
    pub margin_texels: u32,
}

impl UnwrapSettings {
    /// The defaults at `resolution`.
    pub fn at(resolution: usize) -> Self {
        UnwrapSettings {
            resolution,
            hard_angle_deg: DEFAULT_HARD_ANGLE_DEG,
            margin_texels: DEFAULT_MARGIN_TEXELS,
        }
    }
}

/// Why a light-map atlas could not be generated.
#[derive(Debug, thiserror::Error)]
pub enum UnwrapError {
    /// The settings are outside what the packer accepts.
    #[error("{0}")]
    Settings(String),
    /// The unwrapper refused the mesh.
    #[error("uvunwrap: {0}")]
    Unwrap(#[from] uvunwrap::Error),
    /// The charts need more than one page at this resolution and margin.
    #[error(
        "the {charts} charts do not fit one {resolution}x{resolution} atlas with a margin of {margin} texels: raise --resolution"
    )]
    TooManyCharts {
        /// Charts generated.
        charts: u32,
        /// The page size.
        resolution: usize,
        /// The margin.
        margin: u32,
    },
}

/// Generates a light-map layout for `mesh` (the bind mesh): one UV per triangle corner, in the
/// atlas's convention ([`super`]), every chart inside the `resolution`² square.
///
/// With the character's texture layout `texture` (one entry per triangle, every UV finite),
/// its islands are kept as charts, cut at the hard edges, and repacked at uniform density
/// (islands that overlap themselves or flip are unwrapped anew): an artist's islands follow
/// the character's seams and are already flat. Without one, the mesh is unwrapped from
/// scratch. On CesiumMan at 256² the repacked islands read back within 4.4 % of per-vertex
/// transfer where a fresh unwrap (35 charts) gives 6.0 %; on the Fox the two are alike
/// (9.7 % and 9.4 %), its charts being its faces either way (docs/results/lightmaps).
pub fn generate_layout(
    mesh: &Mesh,
    texture: Option<&UvLayout>,
    settings: &UnwrapSettings,
) -> Result<UvLayout, UnwrapError> {
    check_settings(settings)?;
    let seams = hard_edges(mesh, settings.hard_angle_deg);
    let usable = texture.filter(|t| {
        t.corners.len() == mesh.triangles.len()
            && t.corners.iter().flatten().flatten().all(|x| x.is_finite())
    });
    // Either way the only cuts `uvunwrap` makes are ours and the islands': it would cut
    // wherever the mesh splits a vertex otherwise, which on CesiumMan makes 343 small charts
    // whose margins fill two thirds of the atlas. With a texture, every corner is its own
    // vertex carrying its UV (corners at one position with one UV are joined again); without,
    // corners at one position are one vertex.
    let (positions, indices, existing): (Vec<[f32; 3]>, Vec<u32>, _) = match usable {
        Some(layout) => {
            let corners: Vec<[f32; 3]> = mesh
                .triangles
                .iter()
                .flatten()
                .map(|&v| mesh.positions[v as usize])
                .collect();
            let uvs: Vec<[f32; 2]> = layout.corners.iter().flatten().copied().collect();
            (
                corners,
                (0..3 * mesh.triangles.len() as u32).collect(),
                Some(uvs),
            )
        }
        None => {
            let (welded, positions) = weld(mesh);
            let indices = mesh
                .triangles
                .iter()
                .flatten()
                .map(|&v| welded[v as usize])
                .collect();
            (positions, indices, None)
        }
    };
    let input = uvunwrap::MeshInput {
        seams: Some(&seams),
        existing_uvs: existing.as_deref(),
        ..uvunwrap::MeshInput::new(&positions, &indices)
    };
    let options = uvunwrap::Options {
        density: uvunwrap::Density::Auto {
            page_size: settings.resolution as u32,
        },
        padding: settings.margin_texels,
        ..uvunwrap::Options::default()
    };
    let atlas = uvunwrap::generate(&[input], &options)?;
    if atlas.page_count > 1 {
        return Err(UnwrapError::TooManyCharts {
            charts: atlas.chart_count,
            resolution: settings.resolution,
            margin: settings.margin_texels,
        });
    }
    // The page is cropped to the rows it uses and `v` spans the cropped height: rescale it to
    // the square the rest of the atlas code works in.
    let r = settings.resolution as f32;
    let scale = [atlas.width as f32 / r, atlas.height as f32 / r];
    let out = &atlas.meshes[0];
    let corners = out
        .indices
        .chunks_exact(3)
        .map(|t| {
            [0, 1, 2].map(|k| {
                let uv = out.vertices[t[k] as usize].uv;
                [uv[0] * scale[0], uv[1] * scale[1]]
            })
        })
        .collect();
    Ok(UvLayout { corners })
}

/// Refuses settings the packer would panic or loop on, naming the flag.
fn check_settings(settings: &UnwrapSettings) -> Result<(), UnwrapError> {
    let bad = |s: String| Err(UnwrapError::Settings(s));
    if !(settings.hard_angle_deg > 0.0 && settings.hard_angle_deg < 180.0) {
        return bad(format!(
            "--hard-angle {} is not between 0 and 180 degrees",
            settings.hard_angle_deg
        ));
    }
    if 2 * settings.margin_texels as usize + 1 >= settings.resolution {
        return bad(format!(
            "--margin {} leaves no room in a {}x{} atlas",
            settings.margin_texels, settings.resolution, settings.resolution
        ));
    }
    Ok(())
}

/// The edges to cut, three flags per triangle (edge `k` runs from corner `k` to `k + 1`): an
/// edge shared by two triangles whose shading normals differ at either end, or whose faces
/// fold by more than `hard_angle_deg`. Corners are matched by position, so a mesh split for
/// its normals (or its texture's seams) still finds its neighbours.
pub fn hard_edges(mesh: &Mesh, hard_angle_deg: f32) -> Vec<[bool; 3]> {
    let cos_hard = hard_angle_deg.to_radians().cos();
    let (welded, _) = weld(mesh);
    let mut sides: HashMap<(u32, u32), Vec<(usize, usize)>> = HashMap::new();
    for (t, tri) in mesh.triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (welded[tri[k] as usize], welded[tri[(k + 1) % 3] as usize]);
            if a != b {
                sides.entry((a.min(b), a.max(b))).or_default().push((t, k));
            }
        }
    }
    let face_normal = |t: usize| {
        let p = mesh.triangles[t].map(|v| Vec3::from(mesh.positions[v as usize]));
        (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero()
    };
    let mut seams = vec![[false; 3]; mesh.triangles.len()];
    for shared in sides.values() {
        let &[(s, i), (t, j)] = shared.as_slice() else {
            continue;
        };
        let folds = face_normal(s).dot(face_normal(t)) < cos_hard;
        if folds || normals_split(mesh, (s, i), (t, j), &welded) {
            seams[s][i] = true;
            seams[t][j] = true;
        }
    }
    seams
}

/// Each vertex's index among the mesh's distinct positions (`-0.0` and `0.0` alike), and those
/// positions.
fn weld(mesh: &Mesh) -> (Vec<u32>, Vec<[f32; 3]>) {
    let mut ids: HashMap<[u32; 3], u32> = HashMap::new();
    let mut positions = Vec::new();
    let welded = mesh
        .positions
        .iter()
        .map(|p| {
            let key = p.map(|x| if x == 0.0 { 0 } else { x.to_bits() });
            *ids.entry(key).or_insert_with(|| {
                positions.push(*p);
                positions.len() as u32 - 1
            })
        })
        .collect();
    (welded, positions)
}

/// Whether the two triangles on an edge (`(triangle, edge)` each) give either of its ends
/// different shading normals.
fn normals_split(
    mesh: &Mesh,
    (s, i): (usize, usize),
    (t, j): (usize, usize),
    welded: &[u32],
) -> bool {
    let ends = |tri: usize, k: usize| {
        let v = mesh.triangles[tri];
        [v[k], v[(k + 1) % 3]]
    };
    let normal = |v: u32| Vec3::from(mesh.normals[v as usize]);
    ends(s, i).iter().any(|&a| {
        ends(t, j)
            .iter()
            .find(|&&b| welded[b as usize] == welded[a as usize])
            .is_some_and(|&b| normal(a).dot(normal(b)) < SAME_NORMAL_COS)
    })
}

/// The charts of `layout`: triangles joined where they share an edge (by position, as
/// [`hard_edges`] matches corners) with the same UVs on both sides; each triangle's chart id.
/// What a renderer sees as one island, found without the unwrapper's own bookkeeping.
pub fn charts(mesh: &Mesh, layout: &UvLayout) -> Vec<usize> {
    let key = |t: usize, k: usize| {
        let v = mesh.triangles[t][k % 3] as usize;
        (
            mesh.positions[v].map(f32::to_bits),
            layout.corners[t][k % 3].map(f32::to_bits),
        )
    };
    let mut edges: HashMap<_, Vec<usize>> = HashMap::new();
    for t in 0..mesh.triangles.len() {
        for k in 0..3 {
            let (a, b) = (key(t, k), key(t, k + 1));
            edges
                .entry(if a < b { (a, b) } else { (b, a) })
                .or_default()
                .push(t);
        }
    }
    let mut parent: Vec<usize> = (0..mesh.triangles.len()).collect();
    fn root(parent: &mut [usize], mut t: usize) -> usize {
        while parent[t] != t {
            parent[t] = parent[parent[t]];
            t = parent[t];
        }
        t
    }
    for shared in edges.values() {
        for pair in shared.windows(2) {
            let (a, b) = (root(&mut parent, pair[0]), root(&mut parent, pair[1]));
            parent[a.max(b)] = a.min(b);
        }
    }
    (0..parent.len()).map(|t| root(&mut parent, t)).collect()
}

#[cfg(test)]
mod tests;
