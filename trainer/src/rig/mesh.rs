//! The triangle mesh every stage passes around: one posed frame of a character.

/// A triangle mesh with one normal per vertex. Vertex order is meaningful: it is the order of
/// the input file's vertices and of every per-vertex output.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<[f32; 3]>,
    /// Unit vertex normals, one per position.
    pub normals: Vec<[f32; 3]>,
    /// Triangles as indices into `positions`.
    pub triangles: Vec<[u32; 3]>,
}

impl Mesh {
    /// Builds a mesh whose normals are the area-weighted average of the adjacent face normals.
    pub fn with_area_weighted_normals(positions: Vec<[f32; 3]>, triangles: Vec<[u32; 3]>) -> Self {
        let normals = area_weighted_normals(&positions, &triangles);
        Mesh {
            positions,
            normals,
            triangles,
        }
    }

    /// Number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }
}

/// Area-weighted vertex normals: the sum of the (unnormalised) cross products of the adjacent
/// triangles, whose length is twice the area, then normalised. Vertices with no area around
/// them (isolated, or only degenerate triangles) get +z rather than NaN.
pub fn area_weighted_normals(positions: &[[f32; 3]], triangles: &[[u32; 3]]) -> Vec<[f32; 3]> {
    let mut sum = vec![glam::DVec3::ZERO; positions.len()];
    let p = |i: u32| glam::Vec3::from(positions[i as usize]).as_dvec3();
    for t in triangles {
        let n = (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0]));
        for &i in t {
            sum[i as usize] += n;
        }
    }
    sum.into_iter()
        .map(|n| {
            let n = n.normalize_or_zero();
            if n == glam::DVec3::ZERO {
                [0.0, 0.0, 1.0]
            } else {
                n.as_vec3().to_array()
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normals_weight_faces_by_area() {
        // A big triangle in the xy plane and a small one in the xz plane share vertex 0.
        let positions = vec![
            [0.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [0.0, 2.0, 0.0],
            [0.0, 0.0, 0.1],
            [0.1, 0.0, 0.0],
        ];
        let n = area_weighted_normals(&positions, &[[0, 1, 2], [0, 3, 4]]);
        let expect = glam::Vec3::new(0.0, 4.0 * 0.0 + 0.01, 4.0).normalize();
        assert!(
            (glam::Vec3::from(n[0]) - expect).length() < 1e-6,
            "{:?}",
            n[0]
        );
    }

    #[test]
    fn degenerate_and_isolated_vertices_get_a_unit_normal() {
        let positions = vec![[0.0; 3], [0.0; 3], [0.0; 3], [5.0, 5.0, 5.0]];
        let n = area_weighted_normals(&positions, &[[0, 1, 2]]);
        for v in n {
            assert!((glam::Vec3::from(v).length() - 1.0).abs() < 1e-6);
        }
    }
}
