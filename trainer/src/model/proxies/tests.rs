use std::f64::consts::PI;
use std::path::PathBuf;

use glam::DVec3;

use super::*;
use crate::rig::Rig;
use crate::rig::bone_frames::dominant_bones;
use crate::rig::character::Character;
use crate::rig::gltf::GltfRig;

/// A closed surface of revolution around the x axis through `centre`: `profile` lists
/// `(x, radius)` from one pole (radius 0) to the other, `segments` vertices per ring. Its
/// triangles face outwards (checked by the signed volume).
fn revolve(profile: &[(f64, f64)], segments: usize, centre: DVec3) -> Mesh {
    let mut positions = Vec::new();
    let mut rings = Vec::new();
    for &(x, r) in profile {
        let first = positions.len() as u32;
        let count = if r == 0.0 { 1 } else { segments };
        for j in 0..count {
            let phi = 2.0 * PI * j as f64 / segments as f64;
            let p = centre + DVec3::new(x, r * phi.cos(), r * phi.sin());
            positions.push(p.as_vec3().to_array());
        }
        rings.push((first, count as u32));
    }
    let mut triangles = Vec::new();
    for w in rings.windows(2) {
        let ((a, na), (b, nb)) = (w[0], w[1]);
        for j in 0..segments as u32 {
            let k = (j + 1) % segments as u32;
            let at = |first: u32, n: u32, j: u32| first + if n == 1 { 0 } else { j };
            let (a0, a1, b0, b1) = (at(a, na, j), at(a, na, k), at(b, nb, j), at(b, nb, k));
            if na > 1 {
                triangles.push([a0, a1, b1]);
            }
            if nb > 1 {
                triangles.push([a0, b1, b0]);
            }
        }
    }
    let mesh = Mesh::with_area_weighted_normals(positions, triangles);
    assert!(signed_volume(&mesh) > 0.0, "the test mesh faces inwards");
    mesh
}

/// The enclosed volume of a closed, outward-facing mesh (divergence theorem).
fn signed_volume(mesh: &Mesh) -> f64 {
    let p = |i: u32| DVec3::from(mesh.positions[i as usize].map(f64::from));
    mesh.triangles
        .iter()
        .map(|t| p(t[0]).dot(p(t[1]).cross(p(t[2]))) / 6.0)
        .sum()
}

fn sphere(radius: f64, centre: DVec3) -> Mesh {
    let stacks = 32;
    let profile: Vec<(f64, f64)> = (0..=stacks)
        .map(|i| {
            let theta = PI * i as f64 / stacks as f64;
            let (x, r) = (-radius * theta.cos(), radius * theta.sin());
            (x, if i == 0 || i == stacks { 0.0 } else { r })
        })
        .collect();
    revolve(&profile, 48, centre)
}

/// A capsule along x: a cylinder of `length` between two hemispheres of `radius`.
fn capsule(radius: f64, length: f64, centre: DVec3) -> Mesh {
    let cap = 12;
    let mut profile = Vec::new();
    for i in 0..=cap {
        let theta = 0.5 * PI * i as f64 / cap as f64;
        let r = if i == 0 { 0.0 } else { radius * theta.sin() };
        profile.push((-0.5 * length - radius * theta.cos(), r));
    }
    for i in 1..20 {
        profile.push((-0.5 * length + length * i as f64 / 20.0, radius));
    }
    for i in (0..=cap).rev() {
        let theta = 0.5 * PI * i as f64 / cap as f64;
        let r = if i == 0 { 0.0 } else { radius * theta.sin() };
        profile.push((0.5 * length + radius * theta.cos(), r));
    }
    revolve(&profile, 32, centre)
}

/// A flat cylinder across the x axis (a disc in the plane `x = centre.x`): `radius`, `thickness`,
/// its faces in rings a tenth of the radius apart and its rim in four.
fn disc(radius: f64, thickness: f64, centre: DVec3) -> Mesh {
    let h = 0.5 * thickness;
    let mut profile: Vec<(f64, f64)> = (0..10).map(|i| (-h, radius * i as f64 / 10.0)).collect();
    profile.extend((0..=4).map(|i| (-h + thickness * i as f64 / 4.0, radius)));
    profile.extend((0..10).rev().map(|i| (h, radius * i as f64 / 10.0)));
    revolve(&profile, 48, centre)
}

/// Several meshes as one, each driven by its own bone (`bone i` for mesh `i`).
fn join(meshes: &[Mesh]) -> (Mesh, BoneFrames) {
    let (mut positions, mut triangles, mut vertex_bone) = (Vec::new(), Vec::new(), Vec::new());
    for (b, m) in meshes.iter().enumerate() {
        let base = positions.len() as u32;
        positions.extend_from_slice(&m.positions);
        triangles.extend(m.triangles.iter().map(|t| t.map(|i| i + base)));
        vertex_bone.extend(std::iter::repeat_n(b as u16, m.vertex_count()));
    }
    let bones = BoneFrames {
        count: meshes.len(),
        vertex_bone,
    };
    (
        Mesh::with_area_weighted_normals(positions, triangles),
        bones,
    )
}

fn one_bone(mesh: &Mesh) -> BoneFrames {
    BoneFrames {
        count: 1,
        vertex_bone: vec![0; mesh.vertex_count()],
    }
}

/// The fit's table: one row per bone with proxies, then the totals.
fn table(name: &str, fit: &ProxyFit, bone_count: usize) -> String {
    let mut s = format!(
        "{name}: {bone_count} bones, {} with proxies, {} spheres, volume error {:.1} % ({:.1} % of the volume on bones without proxies), surface covered {:.1} %\n",
        fit.bones.len(),
        fit.proxies.len(),
        100.0 * fit.volume_error,
        100.0 * fit.uncovered,
        100.0 * fit.covered
    );
    s += "  bone  vertices  spheres  volume error  covered\n";
    for b in &fit.bones {
        s += &format!(
            "  {:>4}  {:>8}  {:>7}  {:>10.1} %  {:>5.1} %\n",
            b.bone,
            b.vertices,
            b.spheres,
            100.0 * b.volume_error,
            100.0 * b.covered
        );
    }
    s
}

/// A closed sphere mesh on one bone: one proxy, at the centre, of the sphere's radius (less
/// the polyhedron's shortfall, a fraction of a per cent at 48 × 32).
#[test]
fn a_sphere_gets_one_proxy_of_its_size() {
    let (radius, centre) = (0.5, DVec3::new(1.0, -2.0, 3.0));
    let mesh = sphere(radius, centre);
    let fit = fit_proxies(&mesh, &one_bone(&mesh), &ProxyOptions::default()).unwrap();
    println!("{}", table("sphere", &fit, 1));
    assert_eq!(fit.proxies.len(), 1, "{fit:?}");
    let p = fit.proxies[0];
    assert_eq!(p.bone, 0);
    assert!(
        DVec3::from(p.centre).distance(centre) < 0.02 * radius,
        "centre {:?}",
        p.centre
    );
    assert!(
        (p.radius - radius).abs() < 0.03 * radius,
        "radius {}",
        p.radius
    );
    assert!(fit.bones[0].volume_error < 0.1, "{:?}", fit.bones);
    let truth = 4.0 / 3.0 * PI * radius.powi(3);
    assert!(
        (fit.bones[0].volume - truth).abs() < 0.05 * truth,
        "{:?} against {truth}",
        fit.bones[0]
    );
    assert_eq!(fit.neighbours, vec![Vec::<u16>::new()]);
    assert_eq!(fit.uncovered, 0.0);
}

/// Zero-area triangles (a repeated corner, three corners on a line) are left out of the
/// inside test and add no neighbours: the sphere's proxy is still right.
#[test]
fn degenerate_triangles_change_nothing_that_matters() {
    let (radius, centre) = (0.5, DVec3::ZERO);
    let mut mesh = sphere(radius, centre);
    let n = mesh.vertex_count() as u32;
    mesh.positions
        .extend_from_slice(&[[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.2, 0.0, 0.0]]);
    mesh.triangles
        .extend_from_slice(&[[0, 0, 1], [n, n + 1, n + 2], [5, 5, 5]]);
    let fit = fit_proxies(&mesh, &one_bone(&mesh), &ProxyOptions::default()).unwrap();
    assert_eq!(fit.proxies.len(), 1, "{fit:?}");
    assert!(DVec3::from(fit.proxies[0].centre).length() < 0.02 * radius);
    assert!((fit.proxies[0].radius - radius).abs() < 0.03 * radius);
}

/// A capsule five times as long as it is thick: several spheres, on its axis, in order along
/// it, about as thick as the capsule.
#[test]
fn a_capsule_gets_spheres_along_its_axis() {
    let (radius, length, centre) = (0.1, 0.8, DVec3::new(0.0, 1.0, 0.5));
    let mesh = capsule(radius, length, centre);
    let fit = fit_proxies(&mesh, &one_bone(&mesh), &ProxyOptions::default()).unwrap();
    println!("{}", table("capsule", &fit, 1));
    for p in &fit.proxies {
        println!("  {:?} r {:.4}", p.centre, p.radius);
    }
    assert!(fit.proxies.len() >= 3, "{fit:?}");
    let c: Vec<DVec3> = fit
        .proxies
        .iter()
        .map(|p| DVec3::from(p.centre) - centre)
        .collect();
    for (p, c) in fit.proxies.iter().zip(&c) {
        assert!(c.y.hypot(c.z) < 0.1 * radius, "off the axis: {c}");
        assert!(
            p.radius > 0.8 * radius && p.radius < 1.5 * radius,
            "radius {} for a capsule of {radius}",
            p.radius
        );
    }
    assert!(c.windows(2).all(|w| w[0].x < w[1].x), "not in order: {c:?}");
    assert!(c[0].x < -0.25 && c[c.len() - 1].x > 0.25, "{c:?}");
    // A union of spheres is a string of beads: four of them leave a third of a cylinder's
    // volume in misfit (the waists between them and the bulges beyond the wall).
    assert!(fit.volume_error < 0.4, "{fit:?}");
}

/// A capsule cut in two at its middle (the two halves share the triangles across the cut) and
/// two separate spheres: the halves are neighbours, the spheres are not, and a bone with no
/// vertices has none.
#[test]
fn neighbours_are_parts_that_share_triangles() {
    let mesh = capsule(0.1, 0.8, DVec3::ZERO);
    let bones = BoneFrames {
        count: 3,
        vertex_bone: mesh
            .positions
            .iter()
            .map(|p| u16::from(p[0] > 0.0))
            .collect(),
    };
    let fit = fit_proxies(&mesh, &bones, &ProxyOptions::default()).unwrap();
    assert_eq!(fit.neighbours, vec![vec![1], vec![0], vec![]]);
    assert!(fit.proxies.iter().any(|p| p.bone == 0) && fit.proxies.iter().any(|p| p.bone == 1));
    assert!(fit.proxies.windows(2).all(|w| w[0].bone <= w[1].bone));

    let (mesh, bones) = join(&[
        sphere(0.2, DVec3::ZERO),
        sphere(0.2, DVec3::new(1.0, 0.0, 0.0)),
    ]);
    let fit = fit_proxies(&mesh, &bones, &ProxyOptions::default()).unwrap();
    assert_eq!(fit.neighbours, vec![Vec::<u16>::new(), vec![]]);
    assert_eq!(fit.proxies.len(), 2);
}

/// Six capsules of growing size: the budget caps the total, the per-bone cap holds, and when
/// the budget is smaller than the parts, the smallest parts go without.
#[test]
fn the_budgets_hold_and_small_parts_give_way() {
    let meshes: Vec<Mesh> = (0..6)
        .map(|i| {
            let s = 1.0 + 0.2 * i as f64;
            capsule(0.05 * s, 0.4 * s, DVec3::new(i as f64, 0.0, 0.0))
        })
        .collect();
    let (mesh, bones) = join(&meshes);
    let free = fit_proxies(&mesh, &bones, &ProxyOptions::default()).unwrap();
    assert!(free.proxies.len() > 8, "{}", free.proxies.len());
    for (max_per_bone, max_total) in [(4, 8), (2, 64), (3, 6)] {
        let options = ProxyOptions {
            max_per_bone,
            max_total,
        };
        let fit = fit_proxies(&mesh, &bones, &options).unwrap();
        assert!(fit.proxies.len() <= max_total, "{options:?}: {fit:?}");
        assert!(fit.bones.iter().all(|b| b.spheres <= max_per_bone));
        assert_eq!(fit.bones.len(), 6, "{options:?}: every part gets one");
    }
    let fit = fit_proxies(
        &mesh,
        &bones,
        &ProxyOptions {
            max_per_bone: 4,
            max_total: 4,
        },
    )
    .unwrap();
    let kept: Vec<u16> = fit.bones.iter().map(|b| b.bone).collect();
    assert_eq!(kept, vec![2, 3, 4, 5], "the largest four");
    assert!(fit.uncovered > 0.0 && fit.volume_error >= fit.uncovered);
    let none = fit_proxies(
        &mesh,
        &bones,
        &ProxyOptions {
            max_per_bone: 4,
            max_total: 0,
        },
    )
    .unwrap();
    assert!(none.proxies.is_empty() && none.bones.is_empty());
    assert_eq!(none.volume_error, 1.0);
}

/// A disc ten times as wide (in radius) as it is thick, the shape of a hat's brim: it holds
/// too little volume for spheres to earn their place by volume, so coverage puts a set of
/// spheres over it, all centred in its plane, within the tolerance of nine tenths of its
/// vertices.
#[test]
fn a_thin_disc_gets_spheres_in_its_plane_that_cover_it() {
    let (radius, thickness, centre) = (0.3, 0.03, DVec3::new(0.2, -0.1, 1.0));
    let mesh = disc(radius, thickness, centre);
    let fit = fit_proxies(&mesh, &one_bone(&mesh), &ProxyOptions::default()).unwrap();
    println!("{}", table("disc", &fit, 1));
    for p in &fit.proxies {
        println!("  {:.4?} r {:.4}", p.centre, p.radius);
    }
    assert!(fit.proxies.len() >= 3, "{fit:?}");
    assert!(fit.bones[0].covered >= 0.9, "{:?}", fit.bones);
    assert_eq!(fit.covered, fit.bones[0].covered);
    for p in &fit.proxies {
        let off = DVec3::from(p.centre) - centre;
        assert!(off.x.abs() <= 0.5 * thickness, "out of the plane: {off}");
        assert!(off.y.hypot(off.z) < radius, "off the disc: {off}");
    }
    // Spread over the disc, not heaped at its middle.
    assert!(
        fit.proxies
            .iter()
            .any(|p| (DVec3::from(p.centre) - centre).length() > 0.5 * radius),
        "{:?}",
        fit.proxies
    );
}

/// Bones with fewer than [`MIN_VERTICES`] vertices get no sphere.
#[test]
fn a_bone_with_few_vertices_gets_none() {
    let mesh = capsule(0.1, 0.8, DVec3::ZERO);
    // The pole at +x and its first ring's first few vertices on bone 1.
    let mut vertex_bone = vec![0u16; mesh.vertex_count()];
    let tip = mesh.vertex_count() - 1;
    for v in [tip, tip - 1, tip - 2] {
        vertex_bone[v] = 1;
    }
    let bones = BoneFrames {
        count: 2,
        vertex_bone,
    };
    let fit = fit_proxies(&mesh, &bones, &ProxyOptions::default()).unwrap();
    assert!(fit.proxies.iter().all(|p| p.bone == 0));
    assert!(
        fit.uncovered > 0.0 && fit.uncovered < 0.01,
        "{}",
        fit.uncovered
    );
}

#[test]
fn the_same_input_gives_the_same_bytes() {
    let mesh = capsule(0.1, 0.8, DVec3::new(0.3, 0.2, 0.1));
    let bones = BoneFrames {
        count: 2,
        vertex_bone: mesh
            .positions
            .iter()
            .map(|p| u16::from(p[0] > 0.2))
            .collect(),
    };
    let bytes = || {
        let fit = fit_proxies(&mesh, &bones, &ProxyOptions::default()).unwrap();
        let mut out = Vec::new();
        for p in &fit.proxies {
            out.extend(p.bone.to_le_bytes());
            for x in p.centre.into_iter().chain([p.radius]) {
                out.extend(x.to_bits().to_le_bytes());
            }
        }
        for b in &fit.bones {
            out.extend(b.volume_error.to_bits().to_le_bytes());
            out.extend(b.volume.to_bits().to_le_bytes());
            out.extend(b.covered.to_bits().to_le_bytes());
        }
        out.extend(fit.volume_error.to_bits().to_le_bytes());
        out
    };
    let first = bytes();
    assert!(first.len() > 8);
    assert_eq!(first, bytes());
}

/// Each bad input and the error naming it.
#[test]
fn degenerate_input_is_refused_with_what_is_wrong() {
    let mesh = sphere(0.5, DVec3::ZERO);
    let bones = one_bone(&mesh);
    let options = ProxyOptions::default();
    let fit = |mesh: &Mesh, bones: &BoneFrames| fit_proxies(mesh, bones, &options).unwrap_err();

    let empty = BoneFrames {
        count: 1,
        vertex_bone: vec![],
    };
    assert_eq!(fit(&Mesh::default(), &empty), ProxyError::NoVertices);

    let mut nan = mesh.clone();
    nan.positions[7][1] = f32::NAN;
    assert_eq!(fit(&nan, &bones), ProxyError::NonFinite { vertex: 7 });
    nan.positions[7][1] = f32::INFINITY;
    assert_eq!(fit(&nan, &bones), ProxyError::NonFinite { vertex: 7 });

    let mut wrong = bones.clone();
    wrong.vertex_bone[3] = 1;
    let e = fit(&mesh, &wrong);
    assert_eq!(
        e,
        ProxyError::BoneOutOfRange {
            vertex: 3,
            bone: 1,
            count: 1
        }
    );
    assert!(
        e.to_string().contains("vertex 3 is dominated by bone 1"),
        "{e}"
    );

    let short = BoneFrames {
        count: 1,
        vertex_bone: vec![0; 5],
    };
    assert_eq!(
        fit(&mesh, &short),
        ProxyError::VertexCount {
            vertices: mesh.vertex_count(),
            bones: 5
        }
    );

    let mut out = mesh.clone();
    let n = out.vertex_count() as u32;
    out.triangles[9][2] = n;
    assert_eq!(
        fit(&out, &bones),
        ProxyError::TriangleIndex {
            triangle: 9,
            index: n,
            vertices: n as usize
        }
    );

    let many = BoneFrames {
        count: 70_000,
        vertex_bone: bones.vertex_bone.clone(),
    };
    assert_eq!(
        fit(&mesh, &many),
        ProxyError::TooManyBones { count: 70_000 }
    );

    // Valid but empty of volume: a mesh with vertices and no triangles fits nothing.
    let points = Mesh {
        triangles: Vec::new(),
        ..mesh.clone()
    };
    let none = fit_proxies(&points, &bones, &options).unwrap();
    assert!(none.proxies.is_empty() && none.bones.is_empty());
    assert_eq!(none.volume_error, 0.0);
}

/// The built-in character: the head (with its hat and nose), the arms and the torso get
/// proxies. Joint indices as in the character's skeleton (`rig/character/skeleton.rs`).
#[test]
fn the_builtin_character_gets_proxies_on_head_arms_and_torso() {
    let rig = Character::builtin();
    let bones = dominant_bones(&rig);
    let fit = fit_proxies(rig.bind_mesh(), &bones, &ProxyOptions::default()).unwrap();
    println!("{}", table("built-in character", &fit, bones.count));
    let has = |bone: u16| fit.proxies.iter().any(|p| p.bone == bone);
    const HEAD: u16 = 4;
    // The head's axis is vertical through its centre; the brim is 3 cm thick from z = 1.755.
    let from_axis = |p: &Proxy| (p.centre[0] - 0.0).hypot(p.centre[1] + 0.01);
    for p in fit.proxies.iter().filter(|p| p.bone == HEAD) {
        println!(
            "  head and hat: centre {:.3?}, radius {:.3}, {:.3} m from the head's axis",
            p.centre,
            p.radius,
            from_axis(p)
        );
    }
    assert!(
        fit.proxies
            .iter()
            .any(|p| p.bone == HEAD && from_axis(p) >= 0.2 && (p.centre[2] - 1.77).abs() < 0.05),
        "no sphere out on the brim"
    );
    assert!(fit.covered >= 0.9, "{}", fit.covered);
    const ARMS: [u16; 4] = [5, 6, 8, 9];
    const TORSO: [u16; 3] = [0, 1, 2];
    assert!(has(HEAD), "no proxy on the head and hat");
    assert!(ARMS.iter().all(|&b| has(b)), "an arm without proxies");
    assert!(TORSO.iter().any(|&b| has(b)), "no proxy on the torso");
    assert!(fit.proxies.len() <= 64);
    assert!(fit.proxies.iter().all(|p| p.radius > 0.0 && p.radius < 0.5));
    // The shoulders touch the chest, the head the neck: neighbours both ways.
    assert!(fit.neighbours[5].contains(&2) && fit.neighbours[2].contains(&5));
    assert!(
        !fit.neighbours[HEAD as usize].contains(&6),
        "head beside the elbow"
    );
    // Was `< 0.5` (42 %) before the surface coverage: the brim's five coverage spheres are
    // about 0.1 m in radius (the tolerance, their floor) on a brim 3 cm thick, so they add
    // about 0.02 m³ of sphere outside the part, near a third of the body's volume (69 % in
    // all). That overshoot is the price of the brim's shadow; the rest of the body is held to
    // the old bound.
    assert!(fit.volume_error < 0.75, "{}", fit.volume_error);
    let (missed, volume) = fit
        .bones
        .iter()
        .filter(|b| b.bone != HEAD)
        .fold((0.0, 0.0), |(m, v), b| {
            (m + b.volume_error * b.volume, v + b.volume)
        });
    assert!(missed / volume < 0.5, "{}", missed / volume);
}

/// The real assets, from `$APRT_ASSETS` or the repository's neighbour `shared/assets`.
fn assets() -> PathBuf {
    std::env::var_os("APRT_ASSETS").map_or_else(
        || PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/assets"),
        PathBuf::from,
    )
}

/// CesiumMan and the Fox, when the assets are there: proxies within the budgets, and their
/// tables.
#[test]
fn gltf_characters_get_proxies() {
    for file in ["CesiumMan.gltf", "Fox.gltf"] {
        let path = assets().join("gltf").join(file);
        if !path.exists() {
            println!(
                "skipped {file}: {} is absent (set APRT_ASSETS)",
                path.display()
            );
            continue;
        }
        let rig = GltfRig::load(&path, 30.0).unwrap();
        let bones = dominant_bones(&rig);
        let fit = fit_proxies(rig.bind_mesh(), &bones, &ProxyOptions::default()).unwrap();
        println!("{}", table(file, &fit, bones.count));
        let pairs: usize = fit.neighbours.iter().map(Vec::len).sum::<usize>() / 2;
        println!("  {pairs} neighbouring pairs of bones");
        assert!(!fit.proxies.is_empty() && fit.proxies.len() <= 64, "{file}");
        assert_eq!(fit.neighbours.len(), bones.count);
        assert!(fit.volume_error.is_finite());
    }
}
