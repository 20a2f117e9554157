//! Assertions the built-in characters' tests share.

use std::ops::Range;

use crate::rig::mesh::Mesh;

/// Asserts that each of `parts` (name and triangle range of `mesh`) is closed and consistently
/// wound (each directed edge once, its reverse once), encloses a positive volume (faces
/// outward), and that together they cover every triangle.
pub(crate) fn assert_parts_closed_and_outward(
    mesh: &Mesh,
    parts: impl Iterator<Item = (&'static str, Range<usize>)>,
) {
    let mut covered = 0;
    for (name, range) in parts {
        let triangles = &mesh.triangles[range.clone()];
        let mut directed: std::collections::HashMap<(u32, u32), usize> = Default::default();
        for t in triangles {
            for k in 0..3 {
                *directed.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
            }
        }
        for (&(a, b), &count) in &directed {
            assert_eq!(count, 1, "{name}: edge {a}->{b} used {count} times");
            assert_eq!(
                directed.get(&(b, a)),
                Some(&1),
                "{name}: {a}->{b} has no twin"
            );
        }
        let volume: f64 = triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| glam::Vec3::from(mesh.positions[i as usize]).as_dvec3());
                a.dot(b.cross(c)) / 6.0
            })
            .sum();
        assert!(volume > 0.0, "{name}: signed volume {volume}");
        covered += range.len();
    }
    assert_eq!(covered, mesh.triangles.len());
}
