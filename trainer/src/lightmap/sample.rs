//! Reading a light map back at the mesh's vertices, so it compares with per-vertex transfer
//! (`aprt simulate`) value for value.

use crate::rig::Rig;
use crate::rig::uv::{UvLayout, sample_bilinear, sample_bilinear_by};

/// Every map of `maps` (`resolution`² texels × `n2`, laid out by `layout`) read at every
/// vertex of `rig`'s bind mesh ([`at_vertices`] at the vertex's UVs in `layout`): what
/// `aprt lightmap eval` writes.
pub fn maps_at_vertices(
    rig: &dyn Rig,
    layout: &UvLayout,
    maps: &[Vec<f32>],
    resolution: usize,
    n2: usize,
) -> Vec<Vec<f32>> {
    let bind = rig.bind_mesh();
    let uvs = layout.vertex_uvs(&bind.triangles, bind.vertex_count());
    maps.iter()
        .map(|m| at_vertices(m, resolution, n2, &uvs))
        .collect()
}

/// Each vertex's transfer from the map (`resolution`² texels, `n2` values each, texel-major):
/// the bilinear sample at the vertex's UV, averaged over its UVs where it sits on a seam.
/// Vertices with no UV (in no triangle) get zeros.
pub fn at_vertices(map: &[f32], resolution: usize, n2: usize, uvs: &[Vec<[f32; 2]>]) -> Vec<f32> {
    sample_vertices(n2, uvs, |uv, out| {
        sample_bilinear(map, resolution, n2, uv, out);
    })
}

/// [`at_vertices`] of a map held as its filled texels only: `rows` (`n2` values per texel of
/// `texels`, ascending texel indices), zero elsewhere. Reads a frame without its `R²` map.
pub fn rows_at_vertices(
    rows: &[f32],
    texels: &[usize],
    resolution: usize,
    n2: usize,
    uvs: &[Vec<[f32; 2]>],
) -> Vec<f32> {
    let texel = |t: usize| {
        let row = texels.binary_search(&t).ok()?;
        rows.get(row * n2..(row + 1) * n2)
    };
    sample_vertices(n2, uvs, |uv, out| {
        sample_bilinear_by(resolution, uv, texel, out);
    })
}

/// Each vertex's mean of `sample` at its UVs (`n2` values), zeros for a vertex without one.
fn sample_vertices(
    n2: usize,
    uvs: &[Vec<[f32; 2]>],
    mut sample: impl FnMut([f32; 2], &mut [f32]),
) -> Vec<f32> {
    let mut out = vec![0.0f32; uvs.len() * n2];
    let mut value = vec![0.0f32; n2];
    for (vertex, at) in out.chunks_exact_mut(n2).zip(uvs) {
        for &uv in at {
            sample(uv, &mut value);
            for (o, s) in vertex.iter_mut().zip(&value) {
                *o += s / at.len() as f32;
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A map linear in u and v (values at texel centres) reads back exactly at any UV inside
    /// the centres' hull: bilinear filtering reproduces linear fields. A vertex on a seam
    /// (two UVs) takes the mean; a vertex in no triangle gets zeros.
    #[test]
    fn linear_maps_read_back_exactly_and_seams_average() {
        let r = 8;
        let map: Vec<f32> = (0..r * r)
            .flat_map(|t| {
                let (x, y) = ((t % r) as f32 + 0.5, (t / r) as f32 + 0.5);
                [x / r as f32, 2.0 * y / r as f32]
            })
            .collect();
        let uvs = vec![vec![[0.3, 0.4]], vec![[0.25, 0.5], [0.75, 0.5]], vec![]];
        let out = at_vertices(&map, r, 2, &uvs);
        let close = |a: f32, b: f32| (a - b).abs() < 1e-6;
        assert!(close(out[0], 0.3) && close(out[1], 0.8), "{out:?}");
        assert!(close(out[2], 0.5) && close(out[3], 1.0), "{out:?}");
        assert_eq!(&out[4..], &[0.0, 0.0]);
    }

    /// A map held as its filled texels reads back as the dense map with zeros elsewhere.
    #[test]
    fn rows_read_back_as_their_dense_map() {
        let (r, n2) = (6, 2);
        let texels: Vec<usize> = (0..r * r).filter(|t| t % 3 != 0).collect();
        let rows: Vec<f32> = texels
            .iter()
            .flat_map(|&t| [t as f32, -(t as f32)])
            .collect();
        let mut map = vec![0.0f32; r * r * n2];
        for (i, &t) in texels.iter().enumerate() {
            map[t * n2..][..n2].copy_from_slice(&rows[i * n2..][..n2]);
        }
        let uvs = vec![vec![[0.31, 0.47]], vec![[0.0, 1.0], [0.9, 0.05]], vec![]];
        assert_eq!(
            rows_at_vertices(&rows, &texels, r, n2, &uvs),
            at_vertices(&map, r, n2, &uvs)
        );
    }
}
