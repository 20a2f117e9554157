//! Reading a light map back at the mesh's vertices, so it compares with per-vertex transfer
//! (`aprt simulate`) value for value.

use super::atlas::sample_bilinear;

/// Each vertex's transfer from the map (`resolution`² texels, `n2` values each, texel-major):
/// the bilinear sample at the vertex's UV, averaged over its UVs where it sits on a seam.
/// Vertices with no UV (in no triangle) get zeros.
pub fn at_vertices(map: &[f32], resolution: usize, n2: usize, uvs: &[Vec<[f32; 2]>]) -> Vec<f32> {
    let mut out = vec![0.0f32; uvs.len() * n2];
    let mut sample = vec![0.0f32; n2];
    for (vertex, at) in out.chunks_exact_mut(n2).zip(uvs) {
        for &uv in at {
            sample_bilinear(map, resolution, n2, uv, &mut sample);
            for (o, s) in vertex.iter_mut().zip(&sample) {
                *o += s / at.len() as f32;
            }
        }
    }
    out
}
