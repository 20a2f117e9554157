use super::error::ErrorSum;
use super::*;
use crate::progress::Silent;

/// Two triangles side by side in z = 0, areas 1 and 3.
fn two_triangles() -> Mesh {
    Mesh::with_area_weighted_normals(
        vec![
            [0.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [6.0, 0.0, 0.0],
            [2.0, 1.5, 0.0],
        ],
        vec![[0, 1, 2], [1, 3, 4]],
    )
}

/// Each triangle gets its share of the count by area, every point lies inside its triangle,
/// the weights are the area each point stands for and sum to one, and the same mesh and
/// count give the same points.
#[test]
fn points_spread_by_area_inside_their_triangles() {
    let mesh = two_triangles();
    let spread = SurfacePoints::spread(&mesh, 8).unwrap();
    let on = |t: u32| spread.points.iter().filter(|p| p.triangle == t).count();
    assert_eq!((on(0), on(1)), (2, 6));
    for p in &spread.points {
        assert!(p.bary.iter().all(|&b| b > 0.0), "{p:?}");
        assert!((p.bary.iter().sum::<f32>() - 1.0).abs() < 1e-6, "{p:?}");
        assert!((p.weight - 0.125).abs() < 1e-12, "{p:?}");
    }
    assert_eq!(spread, SurfacePoints::spread(&mesh, 8).unwrap());
    // Rounding: 7 points are 1.75 and 5.25 by area; the larger remainder takes the spare one.
    let seven = SurfacePoints::spread(&mesh, 7).unwrap();
    let on = |t: u32| seven.points.iter().filter(|p| p.triangle == t).count();
    assert_eq!((on(0), on(1)), (2, 5));
    let total: f64 = seven.points.iter().map(|p| p.weight).sum();
    assert!((total - 1.0).abs() < 1e-12);
}

/// With fewer points than triangles, the triangles left without a point leave their area to
/// those that got one: the weights still sum to one, each in proportion to its triangle's
/// area (a bug once: they summed to the share of the surface the points' triangles cover).
#[test]
fn weights_sum_to_one_with_fewer_points_than_triangles() {
    // A fan of 10 triangles of areas 1..=10 (55 in all) around the origin.
    let mut positions = vec![[0.0f32, 0.0, 0.0]];
    let mut triangles = Vec::new();
    for t in 0..10u32 {
        positions.push([0.0, 0.0, 0.0]);
        positions.push([0.0, 0.0, 0.0]);
        let area = (t + 1) as f32;
        let (i, j) = (2 * t + 1, 2 * t + 2);
        positions[i as usize] = [10.0 * t as f32, 1.0, 0.0];
        positions[j as usize] = [10.0 * t as f32 + 2.0 * area, 1.0, 0.0];
        triangles.push([0, i, j]);
    }
    let mesh = Mesh::with_area_weighted_normals(positions, triangles);
    let spread = SurfacePoints::spread(&mesh, 3).unwrap();
    assert_eq!(spread.len(), 3);
    let total: f64 = spread.points.iter().map(|p| p.weight).sum();
    assert!((total - 1.0).abs() < 1e-12, "{spread:?}");
    // Shares 30/55, 27/55 and 24/55 of 3 points: the three largest triangles, one each.
    let on: Vec<u32> = spread.points.iter().map(|p| p.triangle).collect();
    assert_eq!(on, [7, 8, 9]);
    let w = |i: usize| spread.points[i].weight;
    assert!((w(0) / w(2) - 0.8).abs() < 1e-12 && (w(1) / w(2) - 0.9).abs() < 1e-12);
}

/// A triangle with no area (or a non-finite one) gets no point; a mesh with no area and a
/// count of zero are refused.
#[test]
fn degenerate_surfaces_get_no_points() {
    let mut mesh = two_triangles();
    mesh.triangles.push([0, 1, 3]); // collinear corners
    mesh.positions.push([f32::NAN, 0.0, 0.0]);
    mesh.normals.push([0.0, 0.0, 1.0]);
    mesh.triangles.push([0, 1, 5]);
    let spread = SurfacePoints::spread(&mesh, 100).unwrap();
    assert_eq!(spread.len(), 100);
    assert!(spread.points.iter().all(|p| p.triangle < 2));
    assert_eq!(SurfacePoints::spread(&mesh, 0), Err(SpreadError::NoPoints));
    let flat = Mesh::with_area_weighted_normals(
        vec![[0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]],
        vec![[0, 1, 2]],
    );
    assert_eq!(SurfacePoints::spread(&flat, 4), Err(SpreadError::NoArea));
}

/// Within a triangle the points fill it evenly: with 400 points, each quarter of the
/// triangle (its midpoint subdivision) holds a quarter of them, within 2 %.
#[test]
fn points_fill_each_triangle_evenly() {
    let mesh = Mesh::with_area_weighted_normals(
        vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        vec![[0, 1, 2]],
    );
    let spread = SurfacePoints::spread(&mesh, 400).unwrap();
    let mut quarters = [0usize; 4];
    for p in &spread.points {
        let [a, b, c] = p.bary;
        let q = if a > 0.5 {
            0
        } else if b > 0.5 {
            1
        } else if c > 0.5 {
            2
        } else {
            3
        };
        quarters[q] += 1;
    }
    for q in quarters {
        assert!((q as i64 - 100).abs() <= 8, "{quarters:?}");
    }
}

/// Values linear over the surface interpolate exactly at every point, and a light map linear
/// in UV reads back exactly at every point's UV: the two ways an engine shows a method.
#[test]
fn linear_fields_interpolate_exactly_at_the_points() {
    let mesh = two_triangles();
    let spread = SurfacePoints::spread(&mesh, 50).unwrap();
    let values: Vec<f32> = mesh
        .positions
        .iter()
        .flat_map(|p| [p[0], 2.0 * p[1] + 1.0])
        .collect();
    let at = spread.from_vertices(&values, 2, &mesh.triangles);
    let (positions, normals) = spread.on(&mesh);
    for ((v, p), n) in at.chunks_exact(2).zip(&positions).zip(&normals) {
        assert!((v[0] - p[0]).abs() < 1e-5 && (v[1] - (2.0 * p[1] + 1.0)).abs() < 1e-5);
        assert_eq!(*n, [0.0, 0.0, 1.0]);
    }
    // UVs: x / 8 + 1/16 and y / 4 + 1/4 keep every point inside the texel centres' hull.
    let layout = UvLayout {
        corners: mesh
            .triangles
            .iter()
            .map(|t| {
                t.map(|v| mesh.positions[v as usize])
                    .map(|p| [p[0] / 8.0 + 0.0625, p[1] / 4.0 + 0.25])
            })
            .collect(),
    };
    let r = 16;
    let map: Vec<f32> = (0..r * r)
        .flat_map(|t| {
            [
                ((t % r) as f32 + 0.5) / r as f32,
                ((t / r) as f32 + 0.5) / r as f32,
            ]
        })
        .collect();
    let uvs = spread.uvs(&layout);
    let read = SurfacePoints::from_map(&map, r, 2, &uvs);
    for (v, uv) in read.chunks_exact(2).zip(&uvs) {
        assert!(
            (v[0] - uv[0]).abs() < 1e-5 && (v[1] - uv[1]).abs() < 1e-5,
            "{v:?} {uv:?}"
        );
    }
}

/// On a lone flat surface nothing occludes: every point's baked transfer is the clamped
/// cosine lobe about the normal in closed form (its band-0 coefficient √π / 2, band 1
/// √(π/3) along the normal), within the Monte Carlo error of 1024 rays.
#[test]
fn unoccluded_points_bake_the_clamped_cosine_lobe() {
    let mesh = two_triangles();
    let spread = SurfacePoints::spread(&mesh, 20).unwrap();
    let settings = BakeSettings {
        order: 2,
        rays: 1024,
        ..BakeSettings::default()
    };
    let baked = SurfaceTarget(&spread)
        .bake(&mesh, &settings, &Silent)
        .unwrap();
    let mut lobe = [0.0f32; 4];
    aprt_core::clamped_cosine(2, [0.0, 0.0, 1.0], &mut lobe).unwrap();
    assert!((lobe[0] - std::f32::consts::PI.sqrt() / 2.0).abs() < 1e-6);
    for point in baked.chunks_exact(4) {
        for (b, l) in point.iter().zip(lobe) {
            assert!((b - l).abs() < 0.02, "{point:?} against {lobe:?}");
        }
    }
}

/// The error sums: relative transfer error and grey levels against values worked by hand,
/// points weighted by their area, and bands a prediction leaves out counted as error.
#[test]
fn errors_are_weighted_by_area_and_count_missing_bands() {
    let lighting = [1.0f32, 0.0, 0.0, 0.0];
    let truth = [2.0f32, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0];
    // Point 0 off by 1 in band 0 (one grey unit of irradiance), point 1 exact in band 0.
    let pred = [3.0f32, 1.0];
    let mut sum = ErrorSum::new(&lighting);
    sum.add(&pred, 1, &truth, Some(&[0.75, 0.25]));
    let got = sum.finish();
    let grey = crate::lighting::GREY_PER_IRRADIANCE;
    // diff: point 0 misses 1 in band 0 and 1 in band 3 (left out), weighted 0.75.
    let expected = ((0.75f64 * 2.0) / (0.75 * 5.0 + 0.25 * 1.0)).sqrt();
    assert!((got.transfer_error - expected).abs() < 1e-12, "{got:?}");
    assert!(
        (got.grey_rms - (0.75f64).sqrt() * grey).abs() < 1e-9,
        "{got:?}"
    );
    assert!((got.grey_max - grey).abs() < 1e-9);
    let mut unweighted = ErrorSum::new(&lighting);
    unweighted.add(&pred, 1, &truth, None);
    assert!((unweighted.finish().grey_rms - (0.5f64).sqrt() * grey).abs() < 1e-9);
}
