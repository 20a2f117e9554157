//! Generated light-map UVs on closed forms: a cube's faces, seams where normals split, the
//! settings refused.

use super::*;
use crate::rig::uv::{Atlas, UvLayout};

/// A unit cube of 8 shared corners (smooth, averaged normals: only the hard angle can cut
/// it), or of 24 corners with each face's own normal (split normals).
fn cube(split: bool) -> Mesh {
    let corner = |i: usize| [(i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32];
    // Each face's four corners, counter-clockwise seen from outside.
    let faces = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    if !split {
        let triangles = faces
            .iter()
            .flat_map(|f| [[f[0], f[1], f[2]], [f[0], f[2], f[3]]])
            .collect();
        return Mesh::with_area_weighted_normals((0..8).map(corner).collect(), triangles);
    }
    let positions: Vec<[f32; 3]> = faces
        .iter()
        .flatten()
        .map(|&i| corner(i as usize))
        .collect();
    let triangles = (0..6u32)
        .flat_map(|f| [[4 * f, 4 * f + 1, 4 * f + 2], [4 * f, 4 * f + 2, 4 * f + 3]])
        .collect();
    Mesh::with_area_weighted_normals(positions, triangles)
}

/// The face (0..6) of each of the cube's triangles.
fn face(t: usize) -> usize {
    t / 2
}

/// Whichever way the cube's normals are stored, and whether or not it comes with a texture
/// whose one island wraps all six faces, its twelve folds of 90° are hard edges at the
/// default hard angle (88°), no chart holds two faces, and the charts are laid out without
/// overlap inside the square. At a hard angle above 90° nothing forces a smooth cube apart.
#[test]
fn a_cube_is_cut_into_one_chart_a_face_or_more() {
    for (split, textured) in [(false, false), (true, false), (false, true)] {
        let mesh = cube(split);
        let texture = textured.then(|| {
            let uvs: Vec<[f32; 2]> = mesh
                .positions
                .iter()
                .map(|p| [(p[0] + 0.5 * p[2]) / 1.5, (p[1] + 0.25 * p[2]) / 1.25])
                .collect();
            UvLayout::from_vertex_uvs(&uvs, &mesh.triangles)
        });
        let seams = hard_edges(&mesh, DEFAULT_HARD_ANGLE_DEG);
        assert_eq!(
            seams.iter().flatten().filter(|&&s| s).count(),
            24,
            "split {split}"
        );
        let layout = generate_layout(&mesh, texture.as_ref(), &UnwrapSettings::at(64)).unwrap();
        let chart = charts(&mesh, &layout);
        for s in 0..12 {
            for t in 0..12 {
                assert!(
                    face(s) == face(t) || chart[s] != chart[t],
                    "split {split}: {s} {t}"
                );
            }
        }
        let count = chart.iter().collect::<std::collections::HashSet<_>>().len();
        assert!(count >= 6, "split {split}: {count} charts");
        assert_eq!(layout.outside_unit_square(), None);
        let atlas = Atlas::build(&layout, &mesh.triangles, 64).unwrap();
        assert_eq!(atlas.overlapping_texels(), 0);
    }
    let smooth = hard_edges(&cube(false), 95.0);
    assert!(smooth.iter().flatten().all(|&s| !s));
    let split = hard_edges(&cube(true), 95.0);
    assert_eq!(split.iter().flatten().filter(|&&s| s).count(), 24);
}

/// Coplanar triangles sharing their normals stay together: a flat square split into two
/// triangles has no hard edge and unwraps into one chart.
#[test]
fn a_flat_square_is_one_chart() {
    let mesh = Mesh::with_area_weighted_normals(
        vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ],
        vec![[0, 1, 2], [0, 2, 3]],
    );
    assert!(
        hard_edges(&mesh, DEFAULT_HARD_ANGLE_DEG)
            .iter()
            .flatten()
            .all(|&s| !s)
    );
    let layout = generate_layout(&mesh, None, &UnwrapSettings::at(32)).unwrap();
    let chart = charts(&mesh, &layout);
    assert_eq!(chart[0], chart[1]);
}

/// A hard angle outside (0, 180) degrees, or a margin that leaves no room, is refused naming
/// the flag; so is an atlas too small for the charts and their margins.
#[test]
fn bad_settings_and_crowded_atlases_are_refused() {
    let mesh = cube(true);
    for (hard_angle_deg, margin_texels, resolution, flag) in [
        (0.0, 3, 64, "--hard-angle"),
        (f32::NAN, 3, 64, "--hard-angle"),
        (180.0, 3, 64, "--hard-angle"),
        (88.0, 40, 64, "--margin"),
        (88.0, 3, 8, "--resolution"),
    ] {
        let settings = UnwrapSettings {
            resolution,
            hard_angle_deg,
            margin_texels,
        };
        let err = generate_layout(&mesh, None, &settings)
            .unwrap_err()
            .to_string();
        assert!(err.contains(flag), "{err}");
    }
}
