//! Issue 46's flat quad: a large square (two triangles, four vertices) under a small square
//! occluder hovering over its middle. The shadow falls inside the two triangles, far from
//! every vertex, so the vertex method, interpolating four unshadowed corners, misses it
//! whole; a light map holds it in its texels. Each method's surface error is checked against
//! the closed form of the occluder's form factor at the points, and the baked truth at the
//! points (the same simulator as the vertices) against the same closed form.
//!
//! At SH order 1 the transfer is band 0 alone: a point of the quad sees the sky except the
//! occluder, so `T00 = Y00 · π · (1 − F)` with `F` the form factor from the point (normal +z)
//! to the occluder, a rectangle parallel to the quad, in closed form (Howell's catalogue,
//! differential area to a parallel rectangle with a corner above it, summed with signs over
//! the four corners). Under a uniform sky of radiance 1 an unoccluded point is white (255 grey
//! levels) and a point's shading error is 255 times its error in `F`.

use aprt_trainer::bake::checkpoint::BakeTarget;
use aprt_trainer::bake::{BakeSettings, ORIGIN_OFFSET, PatternRotation, bake_points, bake_pose};
use aprt_trainer::progress::Silent;
use aprt_trainer::rig::mesh::Mesh;
use aprt_trainer::rig::uv::{Atlas, UvLayout};
use aprt_trainer::surface::error::{Accuracy, ErrorSum};
use aprt_trainer::surface::{SurfacePoints, SurfaceTarget};

/// Half the quad's side.
const L: f64 = 10.0;
/// Half the occluder's side.
const A: f64 = 1.0;
/// The occluder's height above the quad.
const H: f64 = 1.0;
/// Rays per point and per texel.
const RAYS: usize = 2048;
/// Surface points over the quad.
const POINTS: usize = 4096;
/// Light-map texels a side: the quad spans [`QUAD_TEXELS`] of them, 0.21 units each.
const RESOLUTION: usize = 128;
/// Texels the quad spans a side, from texel [`QUAD_START`]; the occluder's island lies 8
/// texels beyond (more than the `2·GUTTER + 1` that keep islands apart).
const QUAD_TEXELS: f64 = 96.0;
const QUAD_START: f64 = 4.0;

/// The quad in z = 0 (normal +z), then the occluder at height [`H`] facing it (the tracer's
/// rays stop at either side of a triangle). Triangles 0 and 1 are the quad's.
fn scene() -> Mesh {
    let (l, a, h) = (L as f32, A as f32, H as f32);
    Mesh::with_area_weighted_normals(
        vec![
            [-l, -l, 0.0],
            [l, -l, 0.0],
            [l, l, 0.0],
            [-l, l, 0.0],
            [-a, -a, h],
            [a, -a, h],
            [a, a, h],
            [-a, a, h],
        ],
        vec![[0, 1, 2], [0, 2, 3], [4, 6, 5], [4, 7, 6]],
    )
}

/// The quad alone, whose triangles are the scene's first two: points spread on it lie on the
/// quad only and name the scene's triangles.
fn quad() -> Mesh {
    let mut mesh = scene();
    mesh.positions.truncate(4);
    mesh.normals.truncate(4);
    mesh.triangles.truncate(2);
    mesh
}

/// The quad over most of the unit square, the occluder's island in the far corner.
fn layout(mesh: &Mesh) -> UvLayout {
    let r = RESOLUTION as f32;
    let (start, span) = (QUAD_START as f32 / r, QUAD_TEXELS as f32 / r);
    let quad_uv = |p: [f32; 3]| {
        let l = L as f32;
        [0, 1].map(|k| start + (p[k] + l) / (2.0 * l) * span)
    };
    let occluder_uv = |p: [f32; 3]| {
        let a = A as f32;
        [0, 1].map(|k| (108.0 + (p[k] + a) / (2.0 * a) * 16.0) / r)
    };
    UvLayout {
        corners: mesh
            .triangles
            .iter()
            .enumerate()
            .map(|(t, tri)| {
                tri.map(|v| mesh.positions[v as usize])
                    .map(|p| if t < 2 { quad_uv(p) } else { occluder_uv(p) })
            })
            .collect(),
    }
}

/// The form factor from a differential area at the origin (normal +z) to the rectangle
/// `[0, x] × [0, y]` at height `h`, signed: odd in `x` and in `y`, so that rectangles with no
/// corner above the point are sums and differences of four of these.
fn corner_form_factor(x: f64, y: f64, h: f64) -> f64 {
    let (a, b) = (x / h, y / h);
    let (ra, rb) = ((1.0 + a * a).sqrt(), (1.0 + b * b).sqrt());
    (a / ra * (b / ra).atan() + b / rb * (a / rb).atan()) / std::f64::consts::TAU
}

/// The occluder's form factor seen from `(x, y)` on the quad, whose rays leave from `h` below
/// it (the bake lifts each ray's origin off the surface).
fn form_factor(x: f64, y: f64, h: f64) -> f64 {
    let (x0, x1, y0, y1) = (-A - x, A - x, -A - y, A - y);
    corner_form_factor(x1, y1, h) - corner_form_factor(x0, y1, h) - corner_form_factor(x1, y0, h)
        + corner_form_factor(x0, y0, h)
}

/// Band 0 of a point's transfer when it misses a fraction `f` of the cosine-weighted sky.
fn transfer_00(f: f64) -> f64 {
    std::f64::consts::PI.sqrt() / 2.0 * (1.0 - f)
}

/// The fraction of the cosine-weighted sky a band-0 transfer stands for as occluded.
fn occluded(t00: f32) -> f64 {
    1.0 - f64::from(t00) / transfer_00(0.0)
}

/// How far a bake's occluded fraction may stray from the exact `f`. The bake estimates `f`
/// from [`RAYS`] cosine-weighted low-discrepancy directions: stratified sampling, whose
/// variance is never above that of as many independent rays, the binomial `f(1 − f)/N`.
/// Five of those standard deviations, plus one ray for where `f` is so small that a single
/// ray is a large part of it.
fn monte_carlo_bound(f: f64) -> f64 {
    let n = RAYS as f64;
    5.0 * (f * (1.0 - f) / n).sqrt() + 1.0 / n
}

/// A bilinear read of a C² field on a grid of spacing `d` strays from it by at most
/// `d²/8 · (max |∂²/∂x²| + max |∂²/∂y²|)`. The form factor's second derivatives, by central
/// differences on a grid over the occluder's neighbourhood (beyond, `F` falls as `1/r⁴` and
/// bends less), with a 10 % margin for the grid missing the peak.
fn bilinear_bound(d: f64, h: f64) -> f64 {
    let e = 1e-3;
    let mut fxx = 0.0f64;
    for i in -400..=400 {
        for j in -400..=400 {
            let (x, y) = (f64::from(i) * 0.01, f64::from(j) * 0.01);
            let f = form_factor(x, y, h);
            let xx = (form_factor(x + e, y, h) - 2.0 * f + form_factor(x - e, y, h)) / (e * e);
            fxx = fxx.max(xx.abs());
        }
    }
    // By the occluder's symmetry under swapping x and y, max |F_yy| = max |F_xx|.
    d * d / 8.0 * 2.0 * fxx * 1.1
}

/// `pred` (band 0 at each point) against `truth` under the uniform white sky, each point
/// weighted by its area.
fn accuracy(pred: &[f32], truth: &[f32], weights: &[f64]) -> Accuracy {
    // A sky of radiance 1 is 2√π in band 0 (∫ Y00 over the sphere): irradiance π unoccluded.
    let sky = [2.0 * std::f32::consts::PI.sqrt()];
    let mut sum = ErrorSum::new(&sky);
    sum.add(pred, 1, truth, Some(weights));
    sum.finish()
}

/// `|a − b| ≤ bound` for the RMS grey levels and relative transfer errors of two comparisons
/// whose predictions or truths differ by `shift`, by Minkowski's inequality: an RMS moves by
/// at most the RMS of what was added, and a relative error `‖p − t‖ / ‖t‖` by at most
/// `ε (1 + e)` where `ε` is the relative size of the change and `e` the error itself.
fn agree(measured: Accuracy, expected: Accuracy, shifts: &[Accuracy], what: &str) {
    let grey: f64 = shifts.iter().map(|s| s.grey_rms).sum();
    let relative: f64 = shifts.iter().map(|s| s.transfer_error).sum();
    assert!(
        (measured.grey_rms - expected.grey_rms).abs() <= grey + 1e-6,
        "{what}: {} grey levels RMS, the closed form {} (within {grey})",
        measured.grey_rms,
        expected.grey_rms
    );
    // The second-order term covers the truth's norm changing under the shift.
    let bound = relative * (1.0 + expected.transfer_error) + relative * relative + 1e-6;
    assert!(
        (measured.transfer_error - expected.transfer_error).abs() <= bound,
        "{what}: transfer error {}, the closed form {} (within {bound})",
        measured.transfer_error,
        expected.transfer_error
    );
}

/// The quad's points and the truth there.
struct Truth {
    mesh: Mesh,
    settings: BakeSettings,
    /// The occluder's height above where the rays leave the quad.
    h: f64,
    points: SurfacePoints,
    weights: Vec<f64>,
    positions: Vec<[f32; 3]>,
    /// Band 0 at each point in closed form.
    closed: Vec<f32>,
    /// Band 0 at each point, baked as `aprt simulate --surface` bakes it.
    baked: Vec<f32>,
}

/// [`POINTS`] points over the quad, baked in the whole scene, and the closed form there; the
/// bake is checked against the closed form point by point, within its Monte Carlo error.
fn truth() -> Truth {
    let mesh = scene();
    let settings = BakeSettings {
        order: 1,
        rays: RAYS,
        bounces: 0,
        ..BakeSettings::default()
    };
    // Rays leave ORIGIN_OFFSET of the bounding box's diagonal above the quad.
    let diagonal = (8.0 * L * L + H * H).sqrt();
    let h = H - ORIGIN_OFFSET * diagonal;
    let points = SurfacePoints::spread(&quad(), POINTS).unwrap();
    let weights: Vec<f64> = points.points.iter().map(|p| p.weight).collect();
    let (positions, _) = points.on(&mesh);
    let closed: Vec<f32> = positions
        .iter()
        .map(|p| transfer_00(form_factor(f64::from(p[0]), f64::from(p[1]), h)) as f32)
        .collect();
    let baked = SurfaceTarget(&points)
        .bake(&mesh, &settings, &Silent)
        .unwrap();
    for ((t, c), p) in baked.iter().zip(&closed).zip(&positions) {
        let (ft, fc) = (occluded(*t), occluded(*c));
        assert!(
            (ft - fc).abs() <= monte_carlo_bound(fc),
            "at {p:?} the bake misses {ft} of the sky, the closed form {fc}"
        );
    }
    Truth {
        mesh,
        settings,
        h,
        points,
        weights,
        positions,
        closed,
        baked,
    }
}

/// The four corners baked as the vertex bake bakes them (each checked against the closed
/// form: the occluder is a speck from there), interpolated at the points.
fn vertex_method(truth: &Truth) -> Vec<f32> {
    let vertices = bake_pose(&truth.mesh, &truth.settings).unwrap();
    for (v, p) in vertices.iter().zip(&truth.mesh.positions).take(4) {
        let f = form_factor(f64::from(p[0]), f64::from(p[1]), truth.h);
        assert!(
            (occluded(*v) - f).abs() <= monte_carlo_bound(f),
            "{p:?}: {v}"
        );
    }
    truth
        .points
        .from_vertices(&vertices, 1, &truth.mesh.triangles)
}

/// A light map read at the points: the baked one, and the same map holding the closed form
/// at the quad's texels instead (the occluder's island kept as baked).
struct LightMapReads {
    baked: Vec<f32>,
    closed: Vec<f32>,
    /// The largest Monte Carlo error of a quad texel, as a fraction of the sky.
    texel_noise: f64,
}

/// The texels baked as `aprt lightmap bake` bakes them (each checked against the closed
/// form), gathered into a map and read bilinearly at the points' UVs.
fn light_map(truth: &Truth) -> LightMapReads {
    let mesh = &truth.mesh;
    let layout = layout(mesh);
    let atlas = Atlas::build(&layout, &mesh.triangles, RESOLUTION).unwrap();
    let (positions, normals) = atlas.surface(mesh);
    let texels = bake_points(
        mesh,
        (&positions, &normals),
        PatternRotation::Shared,
        &truth.settings,
        &Silent,
    )
    .unwrap();
    let mut texel_noise = 0.0f64;
    let closed: Vec<f32> = atlas
        .samples()
        .iter()
        .zip(&positions)
        .zip(&texels)
        .map(|((sample, p), &baked)| {
            if sample.triangle >= 2 {
                return baked;
            }
            let f = form_factor(f64::from(p[0]), f64::from(p[1]), truth.h);
            let noise = (occluded(baked) - f).abs();
            assert!(noise <= monte_carlo_bound(f), "texel at {p:?}: {baked}");
            texel_noise = texel_noise.max(noise);
            transfer_00(f) as f32
        })
        .collect();
    let uvs = truth.points.uvs(&layout);
    let read =
        |values: &[f32]| SurfacePoints::from_map(&atlas.gather(values, 1), RESOLUTION, 1, &uvs);
    LightMapReads {
        baked: read(&texels),
        closed: read(&closed),
        texel_noise,
    }
}

/// The vertex method's surface error is the shadow it misses, as the closed form says; the
/// light map's is a small fraction of it, within its texels' Monte Carlo error and the blur
/// of bilinear filtering of the closed form; the baked truth at the points is the closed form
/// within its Monte Carlo error. Measured: the vertex method 12.73 grey levels RMS and 5.04 %
/// transfer error (closed form 12.72, 5.03 %), the 128² light map 0.15 and 0.06 %, the truth
/// 0.10 grey levels RMS from the closed form.
#[test]
fn the_vertices_miss_a_shadow_inside_a_quad_that_a_light_map_holds() {
    let truth = truth();
    let (closed, weights) = (&truth.closed, &truth.weights);
    let truth_noise = accuracy(&truth.baked, closed, weights);

    // The vertex method: four unshadowed corners, interpolated: the unshadowed quad.
    let by_vertices = vertex_method(&truth);
    let unshadowed = vec![transfer_00(0.0) as f32; truth.points.len()];
    let vertex = accuracy(&by_vertices, &truth.baked, weights);
    let vertex_closed = accuracy(&unshadowed, closed, weights);
    let corners_vs_unshadowed = accuracy(&by_vertices, &unshadowed, weights);
    agree(
        vertex,
        vertex_closed,
        &[truth_noise, corners_vs_unshadowed],
        "the vertex method",
    );

    // The light map. Bilinear weights sum to one: a read strays from the closed form by at
    // most the texels' largest Monte Carlo error plus the filter's blur of the closed form.
    let map = light_map(&truth);
    let blur = bilinear_bound(2.0 * L / QUAD_TEXELS, truth.h);
    for ((m, c), p) in map.baked.iter().zip(closed).zip(&truth.positions) {
        let (fm, fc) = (occluded(*m), occluded(*c));
        assert!(
            (fm - fc).abs() <= map.texel_noise + blur + 1e-6,
            "at {p:?} the light map misses {fm} of the sky, the closed form {fc}"
        );
    }
    let light_map = accuracy(&map.baked, &truth.baked, weights);
    let map_noise = accuracy(&map.baked, &map.closed, weights);
    let map_closed = accuracy(&map.closed, closed, weights);
    agree(
        light_map,
        map_closed,
        &[truth_noise, map_noise],
        "the light map",
    );

    eprintln!(
        "flat quad, {POINTS} points, {RAYS} rays, order 1, uniform sky: vertex method {:.2} grey RMS, transfer error {:.4} (closed form {:.2}, {:.4}); light map {RESOLUTION}² {:.2} grey RMS, transfer error {:.4} (closed form, filtered {:.2}, {:.4}); truth against the closed form {:.3} grey RMS; largest texel error {:.4} of the sky, filter bound {:.4}",
        vertex.grey_rms,
        vertex.transfer_error,
        vertex_closed.grey_rms,
        vertex_closed.transfer_error,
        light_map.grey_rms,
        light_map.transfer_error,
        map_closed.grey_rms,
        map_closed.transfer_error,
        truth_noise.grey_rms,
        map.texel_noise,
        blur
    );
    // The closed form over the quad (its RMS occluded fraction 0.0497): 12.7 grey levels RMS
    // and 5.0 % transfer error that the vertices cannot see.
    assert!(vertex_closed.grey_rms > 12.0 && vertex_closed.transfer_error > 0.045);
    assert!(light_map.grey_rms < vertex.grey_rms / 4.0);
    assert!(light_map.transfer_error < vertex.transfer_error / 4.0);
}
