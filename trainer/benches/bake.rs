//! Bake throughput on an 11.5k-vertex occluding scene (the size of the paper's Master Pai):
//! four subdivided icospheres resting on a subdivided ground plane, deterministic.
//!
//! Bakes one pose at 500 directions and SH order 6 on all cores, alternating the one-ray BVH4
//! walk (before) with the packet walk (after) and printing both rays per second and their
//! ratio; then obvhs' hierarchies, and the same estimator with a brute-force ray–triangle loop
//! on a vertex subset, extrapolated to the whole pose, whose transfer every hierarchy must
//! equal bit for bit. Last, the same before/after on the demo's bake (the built-in human, four
//! poses). Run with `cargo bench -p aprt-trainer --bench bake`.

use aprt_trainer::{Accel, BakeSettings, Character, Mesh, Rig, bake_pose_with, bake_vertices};
use std::collections::HashMap;
use std::time::Instant;

/// An icosphere subdivided `levels` times (10·4^levels + 2 vertices), indexed, outward winding.
fn icosphere(centre: [f32; 3], radius: f32, levels: u32) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    let g = (1.0 + 5f32.sqrt()) / 2.0;
    let mut pos: Vec<[f32; 3]> = vec![
        [-1.0, g, 0.0],
        [1.0, g, 0.0],
        [-1.0, -g, 0.0],
        [1.0, -g, 0.0],
        [0.0, -1.0, g],
        [0.0, 1.0, g],
        [0.0, -1.0, -g],
        [0.0, 1.0, -g],
        [g, 0.0, -1.0],
        [g, 0.0, 1.0],
        [-g, 0.0, -1.0],
        [-g, 0.0, 1.0],
    ];
    let mut tris: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..levels {
        let mut midpoints: HashMap<(u32, u32), u32> = HashMap::new();
        let mut mid = |a: u32, b: u32, pos: &mut Vec<[f32; 3]>| {
            *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
                let (p, q) = (pos[a as usize], pos[b as usize]);
                pos.push([
                    (p[0] + q[0]) / 2.0,
                    (p[1] + q[1]) / 2.0,
                    (p[2] + q[2]) / 2.0,
                ]);
                pos.len() as u32 - 1
            })
        };
        tris = tris
            .iter()
            .flat_map(|&[a, b, c]| {
                let (ab, bc, ca) = (
                    mid(a, b, &mut pos),
                    mid(b, c, &mut pos),
                    mid(c, a, &mut pos),
                );
                [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
            })
            .collect();
    }
    let pos = pos
        .iter()
        .map(|p| {
            let l = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
            [0, 1, 2].map(|k| centre[k] + radius * p[k] / l)
        })
        .collect();
    (pos, tris)
}

/// An `n × n`-vertex ground plane at z = 0 spanning `[−half, half]²`, facing +z.
fn ground(half: f32, n: u32) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    let at = |i: u32| -half + 2.0 * half * i as f32 / (n - 1) as f32;
    let pos = (0..n)
        .flat_map(|j| (0..n).map(move |i| [at(i), at(j), 0.0]))
        .collect();
    let tris = (0..n - 1)
        .flat_map(|j| {
            (0..n - 1).flat_map(move |i| {
                let a = j * n + i;
                [[a, a + 1, a + n + 1], [a, a + n + 1, a + n]]
            })
        })
        .collect();
    (pos, tris)
}

fn scene() -> Mesh {
    let parts = [
        icosphere([-0.55, -0.55, 0.5], 0.5, 4),
        icosphere([0.55, -0.5, 0.45], 0.45, 4),
        icosphere([-0.45, 0.6, 0.55], 0.55, 4),
        icosphere([0.5, 0.5, 1.0], 0.4, 4),
        ground(2.0, 36),
    ];
    let (mut positions, mut triangles) = (Vec::new(), Vec::new());
    for (p, t) in parts {
        let base = positions.len() as u32;
        positions.extend(p);
        triangles.extend(t.into_iter().map(|t| t.map(|i| i + base)));
    }
    Mesh::with_area_weighted_normals(positions, triangles)
}

fn main() {
    let mesh = scene();
    let settings = BakeSettings {
        order: 6,
        rays: 500,
        bounces: 0,
        albedo: 0.0,
        shadows: true,
    };
    let v = mesh.vertex_count();
    println!(
        "scene: {v} vertices, {} triangles; {} rays per vertex, order {}; {} threads",
        mesh.triangles.len(),
        settings.rays,
        settings.order,
        rayon::current_num_threads()
    );
    let reference = before_and_after("scene", std::slice::from_ref(&mesh), &settings, 5);
    for (name, accel) in [("CWBVH", Accel::CwBvh), ("BVH2", Accel::Bvh2)] {
        let _ = bake_pose_with(&mesh, &settings, accel).expect("bake");
        let mut walls = Vec::new();
        for _ in 0..3 {
            let start = Instant::now();
            let t = bake_pose_with(&mesh, &settings, accel).expect("bake");
            walls.push(start.elapsed().as_secs_f64());
            assert_eq!(t, reference, "{name} and BVH4 bakes differ");
        }
        let (wall, median) = best_and_median(&mut walls);
        println!(
            "{name:>6}: {wall:.3} s per pose wall (median {median:.3}), {:.2} Mrays/s",
            (v * settings.rays) as f64 / wall / 1e6,
        );
    }
    let subset = 2000..2064;
    let start = Instant::now();
    let naive = bake_vertices(&mesh, &settings, Accel::BruteForce, subset.clone()).expect("bake");
    let wall = start.elapsed().as_secs_f64() * v as f64 / subset.len() as f64;
    println!(
        " naive: {wall:.1} s per pose wall, {:.4} Mrays/s (extrapolated from vertices {subset:?})",
        (v * settings.rays) as f64 / wall / 1e6,
    );
    assert_eq!(
        naive[..],
        reference[subset.start * 36..subset.end * 36],
        "naive and BVH bakes differ"
    );
    demo_bake();
}

/// The demo's own bake (`aprt demo`): the built-in human at the built-in scene's 128 rays and
/// the reference's SH order 6, four frames of its training clip.
fn demo_bake() {
    let human = Character::builtin();
    let clip = human.clip("training").expect("the built-in training clip");
    let step = (clip.frames.len() / 4).max(1);
    let meshes: Vec<Mesh> = clip
        .frames
        .iter()
        .step_by(step)
        .take(4)
        .map(|pose| human.pose(pose).expect("pose"))
        .collect();
    let settings = BakeSettings {
        order: 6,
        rays: 128,
        bounces: 0,
        albedo: 0.0,
        shadows: true,
    };
    println!(
        "demo: built-in human, {} vertices, {} triangles; {} poses of \"training\", {} rays, order {}",
        meshes[0].vertex_count(),
        meshes[0].triangles.len(),
        meshes.len(),
        settings.rays,
        settings.order
    );
    before_and_after("demo", &meshes, &settings, 5);
}

/// Bakes `meshes` with the old default hierarchy walk (`before`, [`Accel::Bvh4`]) and the
/// packet walk (`after`, [`Accel::Bvh4Packet`]), alternating the two `reps` times after one
/// warm-up each so that drift of the shared machine's speed hits both alike; prints the rays
/// per second of each (best and median) and their ratio, checks that both bake the same bits,
/// and returns the first mesh's transfer.
fn before_and_after(
    label: &str,
    meshes: &[Mesh],
    settings: &BakeSettings,
    reps: usize,
) -> Vec<f32> {
    let rays: usize = meshes
        .iter()
        .map(|m| m.vertex_count() * settings.rays)
        .sum();
    let accels = [
        ("before (BVH4, one ray at a time)", Accel::Bvh4),
        ("after (BVH4, packets)", Accel::Bvh4Packet),
    ];
    let bake = |accel| -> Vec<Vec<f32>> {
        meshes
            .iter()
            .map(|m| bake_pose_with(m, settings, accel).expect("bake"))
            .collect()
    };
    let reference = bake(Accel::Bvh4);
    assert_eq!(
        reference,
        bake(Accel::Bvh4Packet),
        "{label}: packet and one-ray bakes differ"
    );
    let mut walls = [Vec::new(), Vec::new()];
    let mut ratios = Vec::new();
    for _ in 0..reps {
        for (k, &(_, accel)) in accels.iter().enumerate() {
            let start = Instant::now();
            let _ = bake(accel);
            walls[k].push(start.elapsed().as_secs_f64());
        }
        let last = |k: usize| walls[k][walls[k].len() - 1];
        ratios.push(last(0) / last(1));
    }
    let mut best = [0.0; 2];
    for (k, (name, _)) in accels.iter().enumerate() {
        let (wall, median) = best_and_median(&mut walls[k]);
        best[k] = wall;
        println!(
            "{label}: {name:>33}: {:.3} s wall best (median {median:.3}), {:.2} Mrays/s best ({:.2} median)",
            wall,
            rays as f64 / wall / 1e6,
            rays as f64 / median / 1e6,
        );
    }
    let (_, median_ratio) = best_and_median(&mut ratios);
    println!(
        "{label}: after/before rays per second: {:.2}x (best against best), {median_ratio:.2}x (median of {reps} alternating pairs)",
        best[0] / best[1]
    );
    reference.into_iter().next().expect("one mesh at least")
}

/// The smallest and the median of `samples`.
fn best_and_median(samples: &mut [f64]) -> (f64, f64) {
    samples.sort_by(f64::total_cmp);
    (samples[0], samples[samples.len() / 2])
}
