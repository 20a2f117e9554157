//! The atlas against closed forms: affine quads, a faceted cylinder's normals, shared edges,
//! mirrored UVs, islands that must not bleed, and the inputs that must not panic.

use glam::{DVec2, DVec3};

use super::*;
use crate::rig::mesh::Mesh;

/// The UV of every sample (barycentric interpolation of its triangle's corners).
fn sample_uv(layout: &UvLayout, s: &TexelSample) -> DVec2 {
    let c = layout.corners[s.triangle as usize];
    (0..3).fold(DVec2::ZERO, |sum, k| {
        sum + DVec2::from(c[k].map(f64::from)) * f64::from(s.bary[k])
    })
}

fn centre(texel: u32, resolution: usize) -> DVec2 {
    let r = resolution as u32;
    DVec2::new(f64::from(texel % r) + 0.5, f64::from(texel / r) + 0.5) / resolution as f64
}

#[test]
fn quad_samples_are_the_affine_image_of_texel_centres() {
    // Positions (x, y, 0) for xy in the unit square; UV = M·xy + t.
    let xy = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
    let (m, t) = (
        glam::DMat2::from_cols_array(&[0.6, 0.1, -0.15, 0.7]),
        DVec2::new(0.25, 0.12),
    );
    let uvs: Vec<[f32; 2]> = xy
        .iter()
        .map(|&p| (m * DVec2::from(p) + t).as_vec2().to_array())
        .collect();
    let triangles = [[0, 1, 2], [0, 2, 3]];
    let positions: Vec<[f32; 3]> = xy.iter().map(|p| [p[0] as f32, p[1] as f32, 0.0]).collect();
    let mesh = Mesh::with_area_weighted_normals(positions, triangles.to_vec());
    let layout = UvLayout::from_vertex_uvs(&uvs, &triangles);
    let atlas = Atlas::build(&layout, &triangles, 64).unwrap();
    let (points, normals) = atlas.surface(&mesh);
    let inverse = m.inverse();
    let mut centred = 0;
    for ((s, p), n) in atlas.samples().iter().zip(&points).zip(&normals) {
        assert_eq!(*n, [0.0, 0.0, 1.0]);
        let expect = inverse * (centre(s.texel, 64) - t);
        let inside = expect.min_element() >= 0.0 && expect.max_element() <= 1.0;
        let got = glam::Vec3::from(*p).as_dvec3();
        if inside {
            centred += 1;
            assert!(
                got.truncate().distance(expect) < 1e-5 && got.z == 0.0,
                "texel {}: {got} vs {expect}",
                s.texel
            );
        } else {
            // Conservative coverage: a point of the quad, on its boundary.
            let e = got.truncate();
            assert!(
                e.min_element() > -1e-6 && e.max_element() < 1.0 + 1e-6,
                "{e}"
            );
            assert!(e.min_element().abs() < 1e-6 || (e.max_element() - 1.0).abs() < 1e-6);
        }
    }
    // The quad's UV area is det M = 0.435 of the map.
    let area = m.determinant() * 64.0 * 64.0;
    assert!(
        (f64::from(centred) - area).abs() < 0.1 * area,
        "{centred} vs {area}"
    );
    assert_eq!(atlas.overlapping_texels(), 0);
}

#[test]
fn cylinder_normals_follow_the_closed_form_of_interpolated_radial_normals() {
    let n = 7usize;
    let step = std::f64::consts::TAU / n as f64;
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    for h in [0.0, 1.0] {
        for s in 0..n {
            let a = step * s as f64;
            positions.push([a.cos() as f32, a.sin() as f32, h as f32]);
            normals.push([a.cos() as f32, a.sin() as f32, 0.0]);
        }
    }
    let mut triangles = Vec::new();
    let mut corners = Vec::new();
    for s in 0..n {
        let s1 = (s + 1) % n;
        let (u0, u1) = (s as f32 / n as f32, (s + 1) as f32 / n as f32);
        let (b0, b1, t0, t1) = (s as u32, s1 as u32, (n + s) as u32, (n + s1) as u32);
        triangles.push([b0, b1, t1]);
        corners.push([[u0, 0.0], [u1, 0.0], [u1, 1.0]]);
        triangles.push([b0, t1, t0]);
        corners.push([[u0, 0.0], [u1, 1.0], [u0, 1.0]]);
    }
    let mesh = Mesh {
        positions,
        normals,
        triangles: triangles.clone(),
    };
    let layout = UvLayout { corners };
    let atlas = Atlas::build(&layout, &triangles, 96).unwrap();
    let (points, normals) = atlas.surface(&mesh);
    for ((s, p), nrm) in atlas.samples().iter().zip(&points).zip(&normals) {
        let uv = sample_uv(&layout, s);
        let segment = (s.triangle / 2) as f64;
        let t = uv.x * n as f64 - segment;
        let (a0, a1) = (step * segment, step * (segment + 1.0));
        let facet = DVec3::new(a0.cos(), a0.sin(), 0.0) * (1.0 - t)
            + DVec3::new(a1.cos(), a1.sin(), 0.0) * t
            + DVec3::Z * uv.y;
        let angle = a0 + (t * step.sin()).atan2((1.0 - t) + t * step.cos());
        let radial = DVec3::new(angle.cos(), angle.sin(), 0.0);
        let got_p = glam::Vec3::from(*p).as_dvec3();
        let got_n = glam::Vec3::from(*nrm).as_dvec3();
        assert!(got_p.distance(facet) < 1e-5, "{got_p} vs {facet}");
        assert!(got_n.distance(radial) < 1e-5, "{got_n} vs {radial}");
    }
    // The whole map is the cylinder: every texel covered, none twice strictly.
    assert!(atlas.filled().iter().all(|&f| f));
    assert_eq!(atlas.overlapping_texels(), 0);
}

#[test]
fn centres_on_a_shared_edge_take_both_triangles_and_their_mean() {
    // The diagonal u = v passes through the centres of the texels (k, k).
    let corners = vec![
        [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]],
        [[0.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
    ];
    let triangles = [[0, 1, 2], [0, 2, 3]];
    let atlas = Atlas::build(&UvLayout { corners }, &triangles, 4).unwrap();
    let doubled: Vec<u32> = atlas
        .samples()
        .chunk_by(|a, b| a.texel == b.texel)
        .filter(|g| g.len() == 2)
        .map(|g| g[0].texel)
        .collect();
    assert_eq!(doubled, [0, 5, 10, 15]);
    assert_eq!(atlas.samples().len(), 16 + 4);
    assert_eq!(atlas.overlapping_texels(), 0);
    let values: Vec<f32> = atlas
        .samples()
        .iter()
        .flat_map(|s| {
            let v = if s.triangle == 0 { 1.0 } else { 3.0 };
            [v, -v]
        })
        .collect();
    let map = atlas.gather(&values, 2);
    for texel in 0..16 {
        let (x, y) = (texel % 4, texel / 4);
        let expect = match x.cmp(&y) {
            std::cmp::Ordering::Equal => 2.0,
            std::cmp::Ordering::Greater => 1.0,
            std::cmp::Ordering::Less => 3.0,
        };
        assert_eq!(map[2 * texel..2 * texel + 2], [expect, -expect], "{texel}");
    }
}

#[test]
fn mirrored_uvs_are_counted_as_overlapping() {
    let uv = [[0.1, 0.1], [0.9, 0.2], [0.3, 0.8]];
    let mirrored = [uv[0], uv[2], uv[1]];
    let triangles = [[0, 1, 2], [3, 4, 5]];
    let layout = UvLayout {
        corners: vec![uv, mirrored],
    };
    let atlas = Atlas::build(&layout, &triangles, 32).unwrap();
    let single = Atlas::build(&UvLayout { corners: vec![uv] }, &triangles[..1], 32).unwrap();
    let inside = single
        .samples()
        .iter()
        .filter(|s| s.bary.iter().all(|&b| b > 0.01))
        .count();
    assert!(inside > 100);
    assert!(atlas.overlapping_texels() >= inside);
    assert!(atlas.overlapping_texels() <= single.samples().len());
    assert_eq!(single.overlapping_texels(), 0);
}

/// Two rectangular islands `2·GUTTER + 1` texels apart, each made of two triangles.
fn two_islands(resolution: usize) -> (UvLayout, Vec<[u32; 3]>, [[f32; 4]; 2]) {
    let gap = (2 * GUTTER + 1) as f32 / resolution as f32;
    let a = [0.1003, 0.1207, 0.4011, 0.8702];
    let b = [a[2] + gap, 0.2113, 0.9071, 0.9309];
    let rect = |[u0, v0, u1, v1]: [f32; 4]| {
        [
            [[u0, v0], [u1, v0], [u1, v1]],
            [[u0, v0], [u1, v1], [u0, v1]],
        ]
    };
    let corners = [rect(a), rect(b)].concat();
    let triangles = (0..4u32).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect();
    (UvLayout { corners }, triangles, [a, b])
}

#[test]
fn islands_with_the_documented_padding_do_not_bleed() {
    for resolution in [32, 64, 100] {
        let (layout, triangles, rects) = two_islands(resolution);
        let atlas = Atlas::build(&layout, &triangles, resolution).unwrap();
        let values: Vec<f32> = atlas
            .samples()
            .iter()
            .map(|s| if s.triangle < 2 { 1.0 } else { -1.0 })
            .collect();
        let map = atlas.gather(&values, 1);
        for (rect, expect) in rects.iter().zip([1.0, -1.0]) {
            let steps = 40;
            for i in 0..=steps {
                for j in 0..=steps {
                    let f = |k: usize| k as f32 / steps as f32;
                    let uv = [
                        rect[0] + (rect[2] - rect[0]) * f(i),
                        rect[1] + (rect[3] - rect[1]) * f(j),
                    ];
                    let mut out = [0.0];
                    sample_bilinear(&map, resolution, 1, uv, &mut out);
                    assert_eq!(out[0], expect, "R {resolution} at {uv:?}");
                }
            }
        }
    }
}

#[test]
fn gutters_reach_guttter_rings_and_no_further() {
    let r = 16;
    let c = 7.3 / r as f32;
    let d = 0.2 / r as f32;
    // A triangle inside one texel, away from its centre: conservative coverage alone.
    let corners = vec![[[c, c], [c + d, c], [c, c + d]]];
    let atlas = Atlas::build(&UvLayout { corners }, &[[0, 1, 2]], r).unwrap();
    assert_eq!(atlas.samples().len(), 1);
    let s = atlas.samples()[0];
    assert_eq!(s.texel, 7 * 16 + 7);
    assert!((s.bary.iter().sum::<f32>() - 1.0).abs() < 1e-6);
    let filled = atlas.filled();
    let side = 2 * GUTTER + 1;
    assert_eq!(filled.iter().filter(|&&f| f).count(), side * side);
    let map = atlas.gather(&[0.5, 2.0], 2);
    for (t, &f) in filled.iter().enumerate() {
        let expect = if f { [0.5, 2.0] } else { [0.0, 0.0] };
        assert_eq!(map[2 * t..2 * t + 2], expect, "{t}");
    }
}

#[test]
fn a_tiny_triangle_over_a_centre_gets_it() {
    let r = 8;
    let c = 3.5 / r as f32;
    let e = 0.05 / r as f32;
    let corners = vec![[[c - e, c - e], [c + e, c - e], [c, c + e]]];
    let atlas = Atlas::build(&UvLayout { corners }, &[[0, 1, 2]], r).unwrap();
    assert_eq!(atlas.samples().len(), 1);
    assert_eq!(atlas.samples()[0].texel, 3 * 8 + 3);
    assert!(atlas.samples()[0].bary.iter().all(|&b| b > 0.1));
}

#[test]
fn bad_inputs_are_errors_or_cover_nothing() {
    let tri = [[0u32, 1, 2]];
    let good = UvLayout {
        corners: vec![[[0.1, 0.1], [0.9, 0.1], [0.5, 0.9]]],
    };
    for resolution in [0, MAX_RESOLUTION + 1] {
        assert_eq!(
            Atlas::build(&good, &tri, resolution).unwrap_err(),
            AtlasError::Resolution { resolution }
        );
    }
    assert!(matches!(
        Atlas::build(&good, &[[0, 1, 2], [0, 2, 1]], 8),
        Err(AtlasError::LayoutLength {
            corners: 1,
            triangles: 2
        })
    ));
    let nan = UvLayout {
        corners: vec![
            [[0.1, 0.1], [0.9, 0.1], [0.5, 0.9]],
            [[0.1, 0.1], [f32::NAN, 0.1], [0.5, 0.9]],
        ],
    };
    let err = Atlas::build(&nan, &[[0, 1, 2], [0, 1, 2]], 8).unwrap_err();
    assert!(matches!(
        err,
        AtlasError::NonFinite {
            triangle: 1,
            corner: 1,
            ..
        }
    ));
    assert!(err.to_string().contains("triangle 1"), "{err}");
    // A corner naming a vertex without a UV.
    let missing = UvLayout::from_vertex_uvs(&[[0.0, 0.0]; 2], &tri);
    assert!(matches!(
        Atlas::build(&missing, &tri, 8),
        Err(AtlasError::NonFinite {
            triangle: 0,
            corner: 2,
            ..
        })
    ));
    // Degenerate (collinear, repeated corner), far outside the map, and huge: no panic.
    let odd = UvLayout {
        corners: vec![
            [[0.1, 0.1], [0.5, 0.5], [0.9, 0.9]],
            [[0.3, 0.3], [0.3, 0.3], [0.6, 0.2]],
            [[5.0, 5.0], [6.0, 5.0], [5.0, 6.0]],
            [[-1e30, -1e30], [1e30, -1e30], [0.0, 1e30]],
        ],
    };
    let tris = [[0, 1, 2]; 4];
    let atlas = Atlas::build(&odd, &tris, 16).unwrap();
    assert!(atlas.samples().iter().all(|s| s.triangle == 3));
    assert_eq!(atlas.samples().len(), 256);
}

#[test]
fn vertex_uvs_list_every_distinct_uv_of_a_seam_vertex() {
    let triangles = [[0, 1, 2], [0, 2, 3], [0, 3, 1]];
    let layout = UvLayout {
        corners: vec![
            [[0.0, 0.0], [0.5, 0.0], [0.5, 0.5]],
            [[0.0, 0.0], [0.5, 0.5], [0.0, 0.5]],
            [[1.0, 0.0], [0.0, 0.5], [0.5, 0.0]],
        ],
    };
    let uvs = layout.vertex_uvs(&triangles, 5);
    assert_eq!(uvs[0], [[0.0, 0.0], [1.0, 0.0]]);
    assert_eq!(uvs[1], [[0.5, 0.0]]);
    assert_eq!(uvs[3], [[0.0, 0.5]]);
    assert!(uvs[4].is_empty());
    assert_eq!(
        UvLayout::from_vertex_uvs(&[[0.25, 0.75]], &[[0, 0, 0]]).corners,
        [[[0.25, 0.75]; 3]]
    );
}

#[test]
fn bilinear_interpolates_between_centres_and_clamps_at_the_edge() {
    // 2×2 map, values 0 1 / 2 3.
    let map = [0.0, 1.0, 2.0, 3.0];
    let at = |u: f32, v: f32| {
        let mut out = [0.0];
        sample_bilinear(&map, 2, 1, [u, v], &mut out);
        out[0]
    };
    assert_eq!(at(0.25, 0.25), 0.0);
    assert_eq!(at(0.75, 0.25), 1.0);
    assert_eq!(at(0.25, 0.75), 2.0);
    assert_eq!(at(0.5, 0.5), 1.5);
    assert_eq!(at(0.0, 0.0), 0.0);
    assert_eq!(at(1.0, 1.0), 3.0);
    assert_eq!(at(-4.0, 9.0), 2.0);
    assert_eq!(at(f32::NAN, 0.25), 0.0);
}

#[test]
fn packed_charts_keep_their_padding_inside_the_square() {
    let sizes = [
        [0.5, 0.3],
        [0.2, 0.9],
        [1.5, 0.1],
        [0.0, 0.0],
        [0.3, 0.3],
        [0.05, 0.4],
    ];
    let p = shelf_pack(&sizes).unwrap();
    assert!(p.scale > 0.3, "{}", p.scale);
    let rect = |i: usize| {
        let [x, y] = p.offsets[i];
        [x, y, x + p.scale * sizes[i][0], y + p.scale * sizes[i][1]]
    };
    for i in 0..sizes.len() {
        let a = rect(i);
        assert!(
            a[0] >= 0.0 && a[1] >= 0.0 && a[2] <= 1.0 && a[3] <= 1.0,
            "{a:?}"
        );
        for j in 0..i {
            let b = rect(j);
            let apart = a[0] >= b[2] + pack::CHART_PADDING - 1e-12
                || b[0] >= a[2] + pack::CHART_PADDING - 1e-12
                || a[1] >= b[3] + pack::CHART_PADDING - 1e-12
                || b[1] >= a[3] + pack::CHART_PADDING - 1e-12;
            assert!(apart, "{i} {a:?} and {j} {b:?}");
        }
    }
    assert!(shelf_pack(&[[f64::NAN, 1.0]]).is_none());
    assert!(shelf_pack(&vec![[1.0, 1.0]; 5000]).is_none());
    assert_eq!(shelf_pack(&[]).unwrap().offsets, Vec::<[f64; 2]>::new());
}
