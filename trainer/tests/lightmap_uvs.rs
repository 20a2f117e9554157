//! Generated light-map UVs on the real Fox (faceted: every edge splits its normals) and
//! CesiumMan (smooth), checked without the generator's own bookkeeping: charts found from the
//! UVs alone, hard edges from the geometry, coverage from the rasteriser, transfer from
//! `bake_points`.

use std::collections::HashMap;

use aprt_trainer::bake::checkpoint::OnExisting;
use aprt_trainer::bake::{BakeSettings, PatternRotation, bake_points};
use aprt_trainer::lightmap::bake::{CheckpointSettings, bake_light_maps};
use aprt_trainer::lightmap::layout::{AtlasSpec, LightMapUvs};
use aprt_trainer::rig::uv::generate::{
    DEFAULT_HARD_ANGLE_DEG, DEFAULT_MARGIN_TEXELS, UnwrapSettings, charts, generate_layout,
};
use aprt_trainer::rig::uv::{Atlas, GUTTER, UvLayout, sample_bilinear};
use aprt_trainer::{Clip, GltfRig, Mesh, Rig, Silent};
use glam::{DVec2, DVec3, Vec3};

use crate::common;

const RESOLUTION: usize = 256;

/// One side of an edge: a triangle and the two of its corners the edge joins.
type Side = (usize, [usize; 2]);

/// Every edge two triangles share (matched by position), as `(triangle, its two corner
/// indices)` on each side, with whether it is hard: the faces fold by more than the default
/// hard angle, or the two sides give an end of the edge different normals.
fn neighbours(mesh: &Mesh) -> Vec<(Side, Side, bool)> {
    let key = |t: usize, k: usize| mesh.positions[mesh.triangles[t][k] as usize].map(f32::to_bits);
    let mut sides: HashMap<_, Vec<Side>> = HashMap::new();
    for t in 0..mesh.triangles.len() {
        for k in 0..3 {
            let (a, b) = (k, (k + 1) % 3);
            let side = if key(t, a) < key(t, b) {
                [a, b]
            } else {
                [b, a]
            };
            sides
                .entry((key(t, side[0]), key(t, side[1])))
                .or_default()
                .push((t, side));
        }
    }
    let normal = |t: usize| {
        let p = mesh.triangles[t].map(|v| Vec3::from(mesh.positions[v as usize]).as_dvec3());
        (p[1] - p[0]).cross(p[2] - p[0]).normalize()
    };
    let cos_hard = f64::from(DEFAULT_HARD_ANGLE_DEG).to_radians().cos();
    let vertex_normal =
        |t: usize, k: usize| Vec3::from(mesh.normals[mesh.triangles[t][k] as usize]);
    sides
        .values()
        .filter_map(|s| match s.as_slice() {
            &[(s, e), (t, f)] => {
                let split =
                    (0..2).any(|i| vertex_normal(s, e[i]).dot(vertex_normal(t, f[i])) < 0.9999);
                Some(((s, e), (t, f), split || normal(s).dot(normal(t)) < cos_hard))
            }
            _ => None,
        })
        .collect()
}

fn load(file: &str) -> Option<GltfRig> {
    let assets = common::assets(&format!("light-map UVs on {file}"))?;
    Some(GltfRig::load(&assets.join("gltf").join(file), 30.0).unwrap())
}

/// On both characters: no chart crosses a hard edge (its two sides have their own UVs, but
/// where a crease ends inside smooth surface); every UV lies in the square; no texel is
/// covered by two charts; covered texels of different charts are at least `2·GUTTER + 1`
/// texels apart (so their gutters never meet); and the 2×2 footprint of every vertex's UV
/// holds only its own chart's values.
#[test]
fn charts_respect_hard_edges_and_their_margins() {
    for file in ["Fox.gltf", "CesiumMan.gltf"] {
        let Some(rig) = load(file) else {
            return;
        };
        let mesh = rig.bind_mesh();
        let layout =
            generate_layout(mesh, rig.uv_layout(), &UnwrapSettings::at(RESOLUTION)).unwrap();
        assert_eq!(layout.outside_unit_square(), None);
        let pairs = neighbours(mesh);
        let hard = pairs.iter().filter(|p| p.2).count();
        assert!(hard > 0, "{file}: no hard edge found");
        let uv = |(t, e): Side| e.map(|k| layout.corners[t][k].map(f32::to_bits));
        let weld = |(t, e): Side| {
            e.map(|k| mesh.positions[mesh.triangles[t][k] as usize].map(f32::to_bits))
        };
        let mut hard_degree: HashMap<[u32; 3], usize> = HashMap::new();
        for &(s, _, _) in pairs.iter().filter(|p| p.2) {
            weld(s)
                .iter()
                .for_each(|&v| *hard_degree.entry(v).or_default() += 1);
        }
        for &(s, t, hard) in &pairs {
            // A crease that ends inside smooth surface (an end of hard degree 1) cannot be
            // cut without cutting smooth surface: it may stay joined at its ends.
            let open = || weld(s).iter().any(|v| hard_degree.get(v) == Some(&1));
            assert!(
                !hard || uv(s) != uv(t) || open(),
                "{file}: triangles {} and {} share the UVs of a hard edge",
                s.0,
                t.0
            );
        }
        let chart = charts(mesh, &layout);
        let atlas = Atlas::build(&layout, &mesh.triangles, RESOLUTION).unwrap();
        let owner = texel_owners(&atlas, &chart, file);
        let reach = (2 * GUTTER) as i64;
        for (&texel, &c) in &owner {
            let (x, y) = ((texel % RESOLUTION) as i64, (texel / RESOLUTION) as i64);
            for (dx, dy) in (-reach..=reach).flat_map(|dx| (-reach..=reach).map(move |dy| (dx, dy)))
            {
                let (u, v) = (x + dx, y + dy);
                let near = (u >= 0 && v >= 0 && u < RESOLUTION as i64 && v < RESOLUTION as i64)
                    .then(|| owner.get(&(v as usize * RESOLUTION + u as usize)))
                    .flatten();
                assert!(
                    near.is_none_or(|&d| d == c),
                    "{file}: texels {texel} and ({u}, {v})"
                );
            }
        }
        footprints_hold_their_chart(&layout, &atlas, &chart, file);
    }
}

/// Each covered texel's chart; a texel covered by two charts fails the test.
fn texel_owners(atlas: &Atlas, chart: &[usize], file: &str) -> HashMap<usize, usize> {
    let mut owner = HashMap::new();
    for s in atlas.samples() {
        let c = chart[s.triangle as usize];
        let previous = owner.insert(s.texel as usize, c);
        assert!(
            previous.is_none_or(|p| p == c),
            "{file}: texel {} in two charts",
            s.texel
        );
    }
    owner
}

/// Gathers each sample's chart id into a map and reads it at every corner's UV: each of the
/// four texels bilinear filtering reads there holds exactly the corner's chart id (integers
/// stay exact through the gutters' means), so no value of another chart, and no empty texel,
/// reaches a vertex.
fn footprints_hold_their_chart(layout: &UvLayout, atlas: &Atlas, chart: &[usize], file: &str) {
    let ids: Vec<f32> = atlas
        .samples()
        .iter()
        .map(|s| chart[s.triangle as usize] as f32 + 1.0)
        .collect();
    let map = atlas.gather(&ids, 1);
    let r = RESOLUTION;
    for (t, corners) in layout.corners.iter().enumerate() {
        for uv in corners {
            let axis = |c: f32| {
                let x = (f64::from(c) * r as f64 - 0.5).clamp(0.0, (r - 1) as f64);
                let i = x.floor() as usize;
                [i, (i + 1).min(r - 1)]
            };
            let (xs, ys) = (axis(uv[0]), axis(uv[1]));
            for (x, y) in xs.iter().flat_map(|&x| ys.iter().map(move |&y| (x, y))) {
                assert_eq!(
                    map[y * r + x],
                    chart[t] as f32 + 1.0,
                    "{file}: triangle {t} at {uv:?}, texel ({x}, {y})"
                );
            }
        }
    }
}

/// The Fox baked through `bake_light_maps` on generated UVs and read at texel centres (where
/// bilinear filtering returns the texel) matches `bake_points` at the surface point the
/// texel centre maps to, found here from the UV triangle by barycentric coordinates.
#[test]
fn a_fox_light_map_at_texel_centres_matches_bake_points_there() {
    let Some(rig) = load("Fox.gltf") else {
        return;
    };
    let settings = BakeSettings {
        order: 2,
        rays: 64,
        bounces: 0,
        albedo: 0.0,
        shadows: true,
    };
    let clip = Clip {
        name: "bind".into(),
        fps: 30.0,
        frames: vec![vec![0.0; rig.angle_names().len()]],
    };
    let dir = tempfile::tempdir().unwrap();
    let spec = AtlasSpec {
        resolution: RESOLUTION,
        uvs: LightMapUvs::Generate {
            hard_angle_deg: DEFAULT_HARD_ANGLE_DEG,
            margin_texels: DEFAULT_MARGIN_TEXELS,
        },
    };
    let checkpoint = CheckpointSettings {
        dir: &dir.path().join("ck"),
        existing: OnExisting::Refuse,
    };
    let baked = bake_light_maps(
        &rig,
        "the Fox",
        &clip,
        spec,
        &settings,
        &checkpoint,
        &Silent,
    )
    .unwrap();
    let mesh = rig.pose(&clip.frames[0]).unwrap();
    let (texels, points, normals) = interior_centres(&mesh, &baked.layout);
    assert!(
        texels.len() > 2_000,
        "{} interior texel centres",
        texels.len()
    );
    let expect = bake_points(
        &mesh,
        (&points, &normals),
        PatternRotation::Shared,
        &settings,
        &Silent,
    )
    .unwrap();
    let map = &baked.sequence.frames[0];
    let (mut err, mut norm, mut off) = (0.0f64, 0.0f64, 0);
    for (i, &(x, y)) in texels.iter().enumerate() {
        let uv = [
            (x as f32 + 0.5) / RESOLUTION as f32,
            (y as f32 + 0.5) / RESOLUTION as f32,
        ];
        let mut got = [0.0f32; 4];
        sample_bilinear(map, RESOLUTION, 4, uv, &mut got);
        let want = &expect[4 * i..][..4];
        let d: f64 = got
            .iter()
            .zip(want)
            .map(|(a, b)| f64::from(a - b).powi(2))
            .sum();
        err += d;
        norm += want.iter().map(|b| f64::from(*b).powi(2)).sum::<f64>();
        off += usize::from(d.sqrt() > 1e-4);
    }
    let relative = (err / norm).sqrt();
    assert!(relative < 1e-3, "relative difference {relative}");
    assert!(
        off * 200 < texels.len(),
        "{off} of {} texels differ",
        texels.len()
    );
}

/// Texel centres lying well inside exactly one triangle (barycentric coordinates all above
/// 0.02, in no other triangle), with the posed surface point and interpolated normal there.
#[allow(clippy::type_complexity)]
fn interior_centres(
    mesh: &Mesh,
    layout: &UvLayout,
) -> (Vec<(usize, usize)>, Vec<[f32; 3]>, Vec<[f32; 3]>) {
    let r = RESOLUTION as f64;
    let mut found: HashMap<(usize, usize), Option<(usize, [f64; 3])>> = HashMap::new();
    for (t, c) in layout.corners.iter().enumerate() {
        let uv = c.map(|p| DVec2::new(f64::from(p[0]), f64::from(p[1])) * r);
        let lo = uv[0].min(uv[1]).min(uv[2]).floor().max(DVec2::ZERO);
        let hi = uv[0]
            .max(uv[1])
            .max(uv[2])
            .ceil()
            .min(DVec2::splat(r - 1.0));
        let area = (uv[1] - uv[0]).perp_dot(uv[2] - uv[0]);
        if area.abs() < 1e-9 {
            continue;
        }
        for y in lo.y as usize..=hi.y as usize {
            for x in lo.x as usize..=hi.x as usize {
                let p = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
                let b1 = (p - uv[0]).perp_dot(uv[2] - uv[0]) / area;
                let b2 = (uv[1] - uv[0]).perp_dot(p - uv[0]) / area;
                let bary = [1.0 - b1 - b2, b1, b2];
                if bary.iter().all(|&b| b > -1e-9) {
                    let entry = found.entry((x, y)).or_insert(None);
                    *entry = if bary.iter().all(|&b| b > 0.02) && entry.is_none() {
                        Some((t, bary))
                    } else {
                        None
                    };
                }
            }
        }
    }
    let mut texels = Vec::new();
    let (mut points, mut normals) = (Vec::new(), Vec::new());
    let mut kept: Vec<_> = found
        .into_iter()
        .filter_map(|(k, v)| v.map(|v| (k, v)))
        .collect();
    kept.sort_by_key(|&((x, y), _)| (y, x));
    for ((x, y), (t, bary)) in kept {
        let tri = mesh.triangles[t];
        let blend = |data: &[[f32; 3]]| {
            (0..3).fold(DVec3::ZERO, |s, k| {
                s + Vec3::from(data[tri[k] as usize]).as_dvec3() * bary[k]
            })
        };
        texels.push((x, y));
        points.push(blend(&mesh.positions).as_vec3().to_array());
        normals.push(blend(&mesh.normals).normalize().as_vec3().to_array());
    }
    (texels, points, normals)
}
