//! The surface point and normal each texel sample stands for on a posed mesh.

use glam::DVec3;
use rayon::prelude::*;

use super::TexelSample;
use crate::rig::mesh::Mesh;

/// Positions and unit normals of `samples` on `mesh` (whose triangles they index):
/// barycentric interpolation in f64, normals renormalised, the face normal where the
/// interpolated one vanishes (opposite normals on a fold) and `+z` where the face has no area
/// either, as [`crate::rig::mesh::area_weighted_normals`] does for a vertex.
/// Below this length an interpolated normal (of unit corner normals, so at most 1 long) has
/// no direction worth trusting.
const VANISHED: f64 = 1e-6;

pub(super) fn surface(samples: &[TexelSample], mesh: &Mesh) -> (Vec<[f32; 3]>, Vec<[f32; 3]>) {
    samples
        .par_iter()
        .map(|s| point_on(mesh, s.triangle, s.bary))
        .unzip()
}

/// The position and unit normal at barycentric coordinates `bary` of triangle `triangle` of
/// `mesh`, as [`Atlas::surface`](super::Atlas::surface) gives a texel sample's (and
/// [`crate::surface`] a surface point's).
pub fn point_on(mesh: &Mesh, triangle: u32, bary: [f32; 3]) -> ([f32; 3], [f32; 3]) {
    let t = mesh.triangles[triangle as usize];
    let corner = |data: &[[f32; 3]], k: usize| glam::Vec3::from(data[t[k] as usize]).as_dvec3();
    let blend = |data: &[[f32; 3]]| {
        (0..3).fold(DVec3::ZERO, |sum, k| {
            sum + corner(data, k) * f64::from(bary[k])
        })
    };
    let position = blend(&mesh.positions);
    let blended = blend(&mesh.normals);
    let normal = if blended.length() > VANISHED {
        blended.normalize()
    } else {
        let p = |k| corner(&mesh.positions, k);
        (p(1) - p(0))
            .cross(p(2) - p(0))
            .try_normalize()
            .unwrap_or(DVec3::Z)
    };
    (position.as_vec3().to_array(), normal.as_vec3().to_array())
}
