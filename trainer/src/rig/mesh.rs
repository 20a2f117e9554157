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

    /// How many triangles have no area: a repeated corner, or three corners on one line up to
    /// f32 precision (the sine of every angle at most four f32 epsilons, that is twice the area
    /// at most that times the product of the two shorter edges). Such a triangle casts no
    /// shadow and adds nothing to the area-weighted normals. A thin triangle is not one: the
    /// test is the angles, not the size. Triangles naming a vertex that does not exist are not
    /// counted (the bake refuses them).
    pub fn degenerate_triangles(&self) -> usize {
        (0..self.triangles.len())
            .filter(|&t| self.is_degenerate(t))
            .count()
    }

    /// Whether triangle `t` has no area, as [`Mesh::degenerate_triangles`] counts them.
    pub fn is_degenerate(&self, t: usize) -> bool {
        let corner = |i: u32| {
            self.positions
                .get(i as usize)
                .map(|&p| glam::Vec3::from(p).as_dvec3())
        };
        let t = self.triangles[t];
        let (Some(a), Some(b), Some(c)) = (corner(t[0]), corner(t[1]), corner(t[2])) else {
            return false;
        };
        let twice_area = (b - a).cross(c - a).length();
        is_flat(
            twice_area,
            [(b - a).length(), (c - a).length(), (c - b).length()],
        )
    }
}

/// Whether a triangle of `twice_area` and these `edges` has no area to f32 precision: the sine
/// of every angle at most four f32 epsilons, that is twice the area at most that times the
/// product of the two shorter edges.
pub(crate) fn is_flat(twice_area: f64, mut edges: [f64; 3]) -> bool {
    edges.sort_by(f64::total_cmp);
    twice_area.abs() <= 4.0 * f64::from(f32::EPSILON) * edges[0] * edges[1]
}

/// The note for `mesh` (called `name` in it) when it has degenerate triangles
/// ([`Mesh::degenerate_triangles`]); `None` when it has none.
pub fn degenerate_note(name: &str, mesh: &Mesh) -> Option<String> {
    let count = mesh.degenerate_triangles();
    (count > 0).then(|| {
        format!(
            "note: {name}: {count} of {} triangles have zero area (a repeated corner or three corners on a line); they cast no shadow and add nothing to the vertex normals",
            mesh.triangles.len()
        )
    })
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

    /// Triangles with a repeated corner, collinear corners (exactly, and as f32 rounds them),
    /// and three that are thin or huge but real: a sliver 1e-4 high, a right angle with a leg
    /// of 1e30 (`obj-huge-extent`), and corners collinear in decimal that f32 rounds apart far
    /// from the origin.
    #[test]
    fn zero_area_triangles_are_counted() {
        // Corners 0–3 in the xy plane, 4 and 5 on the line through 0 and (1, 2, 3), 6–8 far
        // out, 9 a sliver's apex 1e-4 above the x axis, 10 at 1e30 on it.
        #[rustfmt::skip]
        let flat: [f32; 33] = [
            0.0, 0.0, 0.0,  1.0, 0.0, 0.0,  0.0, 1.0, 0.0,  2.0, 0.0, 0.0,  0.1, 0.2, 0.3,
            0.2, 0.4, 0.6,  1000.1, 1000.2, 1000.3,  1000.2, 1000.4, 1000.6,
            1000.3, 1000.6, 1000.9,  1.0, 1e-4, 0.0,  1e30, 0.0, 0.0,
        ];
        let positions: Vec<[f32; 3]> = flat.chunks(3).map(|c| [c[0], c[1], c[2]]).collect();
        let count = |triangles: Vec<[u32; 3]>| {
            Mesh::with_area_weighted_normals(positions.clone(), triangles).degenerate_triangles()
        };
        assert_eq!(count(vec![[0, 1, 2]]), 0);
        assert_eq!(count(vec![[0, 0, 2]]), 1, "repeated corner");
        assert_eq!(count(vec![[0, 1, 3]]), 1, "collinear");
        assert_eq!(count(vec![[0, 4, 5]]), 1, "collinear in f32");
        assert_eq!(count(vec![[0, 3, 9]]), 0, "a sliver 1e-4 high is real");
        assert_eq!(count(vec![[0, 10, 2]]), 0, "a huge right angle is real");
        assert_eq!(count(vec![[6, 7, 8]]), 0, "rounded apart in f32");
        assert_eq!(count(vec![[0, 1, 2], [0, 0, 0], [1, 3, 0]]), 2);
        let mesh = Mesh::with_area_weighted_normals(positions.clone(), vec![[0, 1, 2], [0, 1, 3]]);
        let note = degenerate_note("m.obj", &mesh).unwrap();
        assert!(
            note.contains("m.obj: 1 of 2 triangles have zero area"),
            "{note}"
        );
        assert_eq!(
            degenerate_note(
                "m.obj",
                &Mesh::with_area_weighted_normals(positions, vec![[0, 1, 2]])
            ),
            None
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
