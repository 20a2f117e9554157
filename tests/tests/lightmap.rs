//! SH light maps in the core: composition is linear in the lighting, gives the closed-form
//! irradiance of an unoccluded texel, equals the pose model's shading when the maps are its
//! transfer, and its per-texel light and rig paths equal their definitions computed by hand;
//! hostile inputs are refused with their errors. The texel-atlas section round-trips through
//! both readers and refuses what is malformed.

use std::f32::consts::PI;

use aprt_core::format::read_header;
use aprt_core::{
    Dim, DirectionalLight, Error, Input, IrradianceRig, Light, LightError, LightMap, LitWeights,
    MAX_ORDER, Model, Placement, PointLight, PoseWeights, SectionKind, SphereLight, StreamedModel,
    clamped_cosine, irradiance_sh,
};
use aprt_tests::edit::{reseal, with_header};
use aprt_tests::samples::{SAMPLE_ATLAS, SAMPLE_ATLAS_UVS, sample_blobs, sample_rig};
use aprt_tests::{Streamed, axis_angle, noise};
use proptest::prelude::*;

fn rgb(values: &[f64]) -> Vec<[f32; 3]> {
    values
        .chunks_exact(3)
        .map(|c| [c[0] as f32, c[1] as f32, c[2] as f32])
        .collect()
}

fn floats(values: &[f64]) -> Vec<f32> {
    values.iter().map(|&x| x as f32).collect()
}

/// `|a − b| ≤ tol · scale` per channel.
fn close(a: [f32; 3], b: [f32; 3], scale: f32, tol: f32) -> bool {
    a.iter()
        .zip(b)
        .all(|(x, y)| (x - y).abs() <= tol * scale.max(1e-6))
}

/// The unshadowed clamped-cosine transfer about `normal`, `texels` times over.
fn unoccluded(order: usize, normal: [f32; 3], texels: usize) -> Vec<f32> {
    let mut t = vec![0.0f32; order * order];
    clamped_cosine(order, normal, &mut t).unwrap();
    t.repeat(texels)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]

    /// `compose(a L1 + b L2) = a compose(L1) + b compose(L2)`, to f32 rounding of the sum of
    /// the terms' magnitudes, for every order and chunk size.
    #[test]
    fn composition_is_linear_in_the_lighting(
        order in 1usize..=MAX_ORDER,
        texels in 1usize..24,
        seed in 1u64..10_000,
        a in -4.0f32..4.0,
        b in -4.0f32..4.0,
    ) {
        let map = LightMap::new(order).unwrap();
        let n2 = order * order;
        let maps = floats(&noise(seed, texels * n2));
        let (l1, l2) = (rgb(&noise(seed + 1, 3 * n2)), rgb(&noise(seed + 2, 3 * n2)));
        let mixed: Vec<[f32; 3]> = l1
            .iter()
            .zip(&l2)
            .map(|(x, y)| std::array::from_fn(|k| a * x[k] + b * y[k]))
            .collect();
        let compose = |l: &[[f32; 3]]| {
            let mut out = vec![[0.0f32; 3]; texels];
            map.compose(&maps, l, &mut out).unwrap();
            out
        };
        let (o1, o2, om) = (compose(&l1), compose(&l2), compose(&mixed));
        for t in 0..texels {
            let tt = &maps[t * n2..(t + 1) * n2];
            let scale: f32 = (0..n2)
                .map(|c| tt[c].abs() * (a.abs() * l1[c][0].abs().max(l1[c][1].abs()).max(l1[c][2].abs())
                    + b.abs() * l2[c][0].abs().max(l2[c][1].abs()).max(l2[c][2].abs())))
                .sum();
            let want: [f32; 3] = std::array::from_fn(|k| a * o1[t][k] + b * o2[t][k]);
            prop_assert!(close(om[t], want, scale, 1e-5), "{:?} vs {:?}", om[t], want);
        }
    }
}

/// The crate's transfer of an unoccluded texel facing +z is the clamped cosine's band norms
/// (`t_00 = √π/2`, `t_10 = √(π/3)`, `t_20 = √(5π)/8`, 0 for m ≠ 0), and uniform radiance `c`
/// (`L_00 = 2√π c`) composes to the irradiance `π c`, the shade convention's scale. A
/// directional light composes to what `irradiance_sh` gives the same normal.
#[test]
fn an_unoccluded_texel_composes_to_its_irradiance() {
    let mut t = [0.0f32; 36];
    clamped_cosine(MAX_ORDER, [0.0, 0.0, 1.0], &mut t).unwrap();
    let bands = [PI.sqrt() / 2.0, (PI / 3.0).sqrt(), (5.0 * PI).sqrt() / 8.0];
    for (l, want) in bands.into_iter().enumerate() {
        assert!(
            (t[l * l + l] - want).abs() < 1e-6,
            "band {l}: {}",
            t[l * l + l]
        );
    }
    for (c, &x) in t.iter().enumerate() {
        let zonal = (0..MAX_ORDER).any(|l| c == l * l + l);
        assert!(zonal || x.abs() < 1e-7, "t_{c} = {x}");
    }
    let c = [1.0f32, 0.25, 3.0];
    for order in 1..=MAX_ORDER {
        let map = LightMap::new(order).unwrap();
        let n2 = order * order;
        let mut uniform = vec![[0.0f32; 3]; n2];
        uniform[0] = c.map(|x| 2.0 * PI.sqrt() * x);
        let normals = [[0.0, 0.0, 1.0], [0.3, -0.8, 0.1], [0.0, 0.0, -1.0]];
        let maps: Vec<f32> = normals
            .iter()
            .flat_map(|&n| unoccluded(order, n, 1))
            .collect();
        let mut out = [[0.0f32; 3]; 3];
        map.compose(&maps, &uniform, &mut out).unwrap();
        for o in out {
            assert!(
                close(o, c.map(|x| PI * x), PI * 3.0, 1e-6),
                "order {order}: {o:?}"
            );
        }
        let sun = Light::Directional(DirectionalLight {
            direction: [0.4, 0.2, 1.0],
            irradiance: c,
        });
        let mut sh = vec![[0.0f32; 3]; n2];
        sun.add_radiance_sh(order, [0.0; 3], &mut sh).unwrap();
        map.compose(&maps, &sh, &mut out).unwrap();
        for (o, n) in out.iter().zip(normals) {
            let want = irradiance_sh(order, &sh, n).unwrap();
            assert!(
                close(*o, want, 3.0, 1e-5),
                "order {order}: {o:?} vs {want:?}"
            );
        }
    }
}

/// A light map that is a world-frame model's transfer composes, under grey lighting, to the
/// model's own shading: the same scale, any chunking, resident or streamed transfer.
#[test]
fn composing_a_models_transfer_equals_its_shading() {
    let mut checked = 0;
    for (name, blob) in sample_blobs() {
        let model = Model::parse(&blob).unwrap();
        let info = *model.info();
        if info.bones() > 0 {
            continue;
        }
        let (n2, v) = (info.coeffs(), info.vertices());
        let lighting = floats(&noise(7, n2));
        let (mut pose, mut lit) = (PoseWeights::new(), LitWeights::new());
        let angles = floats(&noise(8, info.pose_len()));
        model.set_pose(&angles, &mut pose).unwrap();
        model.light(&pose, &lighting, &[], &mut lit).unwrap();
        let mut shading = vec![0.0f32; v];
        model.shade(&lit, 0, &mut shading).unwrap();
        let mut transfer = vec![0.0f32; v * n2];
        let mut scratch = vec![0u8; info.scratch_bytes()];
        let mut streamed = StreamedModel::open(Streamed::new(&blob), &mut scratch).unwrap();
        streamed.transfer(&pose, 0, &mut transfer).unwrap();

        let map = LightMap::new(info.order()).unwrap();
        let grey: Vec<[f32; 3]> = lighting.iter().map(|&l| [l; 3]).collect();
        let mut whole = vec![[0.0f32; 3]; v];
        map.compose(&transfer, &grey, &mut whole).unwrap();
        for j in 0..v {
            let t = &transfer[j * n2..(j + 1) * n2];
            let scale: f32 = t.iter().zip(&lighting).map(|(a, b)| (a * b).abs()).sum();
            assert!(
                close(whole[j], [shading[j]; 3], scale, 1e-4),
                "{name}, vertex {j}: {:?} vs {}",
                whole[j],
                shading[j]
            );
        }
        for chunk in [1, 3, 8] {
            let mut pieces = vec![[0.0f32; 3]; v];
            for (t, out) in transfer.chunks(chunk * n2).zip(pieces.chunks_mut(chunk)) {
                map.compose(t, &grey, out).unwrap();
            }
            assert_eq!(pieces, whole, "{name}, chunks of {chunk}");
        }
        checked += 1;
    }
    assert!(checked >= 3, "{checked} world-frame samples");
}

fn lights() -> [Light; 3] {
    [
        Light::Sphere(SphereLight {
            position: [0.5, 1.0, 0.2],
            radius: 0.3,
            radiance: [4.0, 2.0, 1.0],
        }),
        Light::Point(PointLight {
            position: [-1.0, 0.0, 0.5],
            intensity: [1.0, 3.0, 2.0],
        }),
        Light::Directional(DirectionalLight {
            direction: [0.0, -1.0, 1.0],
            irradiance: [0.5; 3],
        }),
    ]
}

/// Texel positions: scattered points, one inside the sphere light and one on the point light.
fn positions(texels: usize) -> Vec<[f32; 3]> {
    let mut p = rgb(&noise(11, 3 * texels));
    p[1] = [0.5, 1.1, 0.2];
    p[2] = [-1.0, 0.0, 0.5];
    p
}

/// `compose_lights` is `compose` of each texel's own lighting, the environment plus every
/// light's `add_radiance_sh` at its position (a texel on a point light inside its sphere),
/// bit for bit.
#[test]
fn per_texel_lights_equal_their_definition() {
    let texels = 9;
    for order in [1, 3, 6] {
        let map = LightMap::new(order).unwrap();
        let n2 = order * order;
        let maps = floats(&noise(12, texels * n2));
        let p = positions(texels);
        let lights = lights();
        for environment in [vec![], rgb(&noise(13, 3 * n2))] {
            let mut out = vec![[0.0f32; 3]; texels];
            map.compose_lights(&maps, &p, &lights, &environment, &mut out)
                .unwrap();
            for t in 0..texels {
                let mut l = match environment.is_empty() {
                    true => vec![[0.0f32; 3]; n2],
                    false => environment.clone(),
                };
                for light in &lights {
                    light.add_radiance_sh(order, p[t], &mut l).unwrap();
                }
                let mut want = [[0.0f32; 3]];
                map.compose(&maps[t * n2..(t + 1) * n2], &l, &mut want)
                    .unwrap();
                assert_eq!(out[t], want[0], "order {order}, texel {t}");
            }
        }
    }
}

/// `compose_rig` is `compose` of the rig's lighting at each texel (`lighting_at`), bit for
/// bit, with the character placed away from the world's origin.
#[test]
fn rig_lit_texels_equal_their_definition() {
    let bytes = sample_rig();
    let rig = IrradianceRig::parse(&bytes).unwrap();
    let place = Placement {
        rotation: axis_angle([0.0, 0.0, 1.0], 0.7),
        translation: [2.0, -1.0, 0.5],
    };
    let texels = 12;
    for order in [2, 4] {
        let map = LightMap::new(order).unwrap();
        let n2 = order * order;
        let mut vectors = vec![[0.0f32; 3]; rig.vectors() * n2];
        let env = rgb(&noise(14, 3 * n2));
        rig.vectors_from_lights(order, &place, &lights(), &env, &mut vectors)
            .unwrap();
        let maps = floats(&noise(15, texels * n2));
        let p: Vec<[f32; 3]> = rgb(&noise(16, 3 * texels))
            .into_iter()
            .map(|q| place.to_world(q))
            .collect();
        let mut out = vec![[0.0f32; 3]; texels];
        map.compose_rig(&maps, &rig, &vectors, &place, &p, &mut out)
            .unwrap();
        for t in 0..texels {
            let mut l = vec![[0.0f32; 3]; n2];
            rig.lighting_at(&vectors, &place, p[t], &mut l);
            let mut want = [[0.0f32; 3]];
            map.compose(&maps[t * n2..(t + 1) * n2], &l, &mut want)
                .unwrap();
            assert_eq!(out[t], want[0], "order {order}, texel {t}");
        }
    }
}

/// Bad orders, lengths, chunk sizes, non-finite maps, lighting and positions, bad lights and
/// rig vectors: each its error, and nothing written.
#[test]
fn hostile_inputs_are_refused_and_write_nothing() {
    for order in [0, MAX_ORDER + 1, usize::MAX] {
        assert_eq!(
            LightMap::new(order),
            Err(Error::BadDimension {
                what: Dim::Order,
                value: order as u64
            })
        );
    }
    let map = LightMap::new(2).unwrap();
    let maps = floats(&noise(17, 3 * 4));
    let light = rgb(&noise(18, 12));
    let p = positions(3);
    let bytes = sample_rig();
    let rig = IrradianceRig::parse(&bytes).unwrap();
    let vectors = rgb(&noise(19, 3 * 4 * rig.vectors()));
    let id = Placement::IDENTITY;
    let lights = lights();
    let sentinel = [[7.0f32; 3]; 3];
    let mut out = sentinel;
    let wrong = |what, expected, found| {
        Err(Error::WrongLength {
            what,
            expected,
            found,
        })
    };
    // Chunks that do not match: maps, positions, lighting.
    assert_eq!(
        map.compose(&maps[1..], &light, &mut out),
        wrong(Input::LightMap, 12, 11)
    );
    assert_eq!(
        map.compose(&maps, &light, &mut out[..2]),
        wrong(Input::LightMap, 8, 12)
    );
    assert_eq!(
        map.compose(&maps, &light[..3], &mut out),
        wrong(Input::Lighting, 4, 3)
    );
    assert_eq!(
        map.compose_lights(&maps, &p[..2], &lights, &[], &mut out),
        wrong(Input::Positions, 3, 2)
    );
    assert_eq!(
        map.compose_lights(&maps, &p, &lights, &light[..1], &mut out),
        wrong(Input::Lighting, 4, 1)
    );
    assert_eq!(
        map.compose_rig(&maps, &rig, &vectors[4..], &id, &p, &mut out),
        wrong(Input::RigVectors, vectors.len(), vectors.len() - 4)
    );
    assert_eq!(
        map.compose_rig(&maps, &rig, &vectors, &id, &p[1..], &mut out),
        wrong(Input::Positions, 3, 2)
    );
    // Non-finite values, each named by its index.
    let mut nan_maps = maps.clone();
    nan_maps[9] = f32::INFINITY;
    assert_eq!(
        map.compose(&nan_maps, &light, &mut out),
        Err(Error::NonFiniteLightMap { texel: 2 })
    );
    let mut nan_light = light.clone();
    nan_light[3][1] = f32::NAN;
    assert_eq!(
        map.compose(&maps, &nan_light, &mut out),
        Err(Error::NonFiniteLighting { index: 3 })
    );
    assert_eq!(
        map.compose_lights(&maps, &p, &lights, &nan_light, &mut out),
        Err(Error::NonFiniteLighting { index: 3 })
    );
    let mut nan_p = p.clone();
    nan_p[1][2] = f32::NAN;
    assert_eq!(
        map.compose_lights(&maps, &nan_p, &lights, &[], &mut out),
        Err(Error::NonFinitePosition { index: 1 })
    );
    assert_eq!(
        map.compose_rig(&maps, &rig, &vectors, &id, &nan_p, &mut out),
        Err(Error::NonFinitePosition { index: 1 })
    );
    let mut nan_vectors = vectors.clone();
    nan_vectors[5][0] = f32::NEG_INFINITY;
    assert_eq!(
        map.compose_rig(&maps, &rig, &nan_vectors, &id, &p, &mut out),
        Err(Error::NonFiniteLighting { index: 5 })
    );
    // A placement that takes finite positions out of f32 in the rig's frame.
    let far = Placement {
        translation: [-3e38, 0.0, 0.0],
        ..id
    };
    let big = [[3e38f32, 0.0, 0.0]; 3];
    assert_eq!(
        map.compose_rig(&maps, &rig, &vectors, &far, &big, &mut out),
        Err(Error::NonFinitePosition { index: 0 })
    );
    let mut bad = lights;
    bad[1] = Light::Sphere(SphereLight {
        position: [0.0; 3],
        radius: -1.0,
        radiance: [1.0; 3],
    });
    assert_eq!(
        map.compose_lights(&maps, &p, &bad, &[], &mut out),
        Err(Error::BadLight {
            index: 1,
            reason: LightError::BadRadius
        })
    );
    assert_eq!(out, sentinel, "nothing written on an error");
    // An empty chunk is valid and writes nothing.
    map.compose(&[], &light, &mut []).unwrap();
    map.compose_lights(&[], &[], &lights, &[], &mut []).unwrap();
    map.compose_rig(&[], &rig, &vectors, &id, &[], &mut [])
        .unwrap();
}

/// The sample light-map model's atlas, corner UVs included, round-trips through both readers
/// and scatters each row to its texel.
#[test]
fn texel_atlas_round_trips() {
    let blob = atlas_blob();
    let model = Model::parse(&blob).unwrap();
    let atlas = model.texel_atlas().expect("the sample records its atlas");
    let (r, texels) = SAMPLE_ATLAS;
    assert_eq!((atlas.resolution(), atlas.rows()), (r, texels.len()));
    for (j, &t) in texels.iter().enumerate() {
        assert_eq!(atlas.texel(j), Ok(t));
    }
    let mut scratch = vec![0u8; model.info().scratch_bytes()];
    let mut streamed = StreamedModel::open(Streamed::new(&blob), &mut scratch).unwrap();
    let mut buf = vec![0u8; model.info().texel_atlas_bytes()];
    assert_eq!(
        buf.len(),
        4 * (1 + texels.len()) + 4 + 24 * SAMPLE_ATLAS_UVS.len()
    );
    assert_eq!(streamed.texel_atlas(&mut buf).unwrap(), Some(atlas));
    assert_eq!(atlas.triangles(), SAMPLE_ATLAS_UVS.len());
    for (t, uvs) in SAMPLE_ATLAS_UVS.iter().enumerate() {
        assert_eq!(atlas.corner_uvs(t), Ok(*uvs));
    }
    // Rows 2.. scattered in two chunks.
    let rows: Vec<[f32; 3]> = (0..texels.len()).map(|j| [j as f32; 3]).collect();
    let mut map = vec![[-1.0f32; 3]; (r * r) as usize];
    atlas.scatter(2, &rows[2..4], &mut map).unwrap();
    atlas.scatter(4, &rows[4..], &mut map).unwrap();
    for (t, texel) in map.iter().enumerate() {
        let want = match texels.iter().position(|&x| x as usize == t) {
            Some(j) if j >= 2 => [j as f32; 3],
            _ => [-1.0; 3],
        };
        assert_eq!(*texel, want, "texel {t}");
    }
    // Models without an atlas have none, in both faces.
    let plain = &sample_blobs()[0].1;
    let model = Model::parse(plain).unwrap();
    assert_eq!(model.texel_atlas(), None);
    let mut scratch = vec![0u8; model.info().scratch_bytes()];
    let mut streamed = StreamedModel::open(Streamed::new(plain), &mut scratch).unwrap();
    assert_eq!(streamed.texel_atlas(&mut []), Ok(None));
}

fn atlas_blob() -> Vec<u8> {
    let (name, blob) = sample_blobs().pop().unwrap();
    assert_eq!(name, "atlas-identity-f32");
    blob
}

/// The atlas section's offset and length in `blob`.
fn atlas_span(blob: &[u8]) -> (usize, usize) {
    let e = read_header(blob)
        .unwrap()
        .sections
        .into_iter()
        .find(|e| SectionKind::from_tag(e.kind) == SectionKind::TexelAtlas)
        .unwrap();
    (e.offset as usize, e.len as usize)
}

/// What both readers make of a blob; they must agree.
fn open(blob: &[u8]) -> Result<(), Error> {
    let resident = Model::parse(blob).map(|_| ());
    let mut scratch = vec![0u8; 4096];
    let streamed = StreamedModel::open(Streamed::new(blob), &mut scratch).map(|_| ());
    assert_eq!(resident, streamed);
    resident
}

/// Resolution 0 or above 8192, indices that repeat, fall or reach R², and a section of
/// another row count: refused when the blob is opened, by both readers, checksums matching.
#[test]
fn malformed_atlases_are_refused_at_open() {
    let blob = atlas_blob();
    assert_eq!(open(&blob), Ok(()));
    let (offset, len) = atlas_span(&blob);
    let word = |i: usize, value: u32| {
        let mut b = blob.clone();
        b[offset + 4 * i..offset + 4 * i + 4].copy_from_slice(&value.to_le_bytes());
        reseal(&b)
    };
    let (r, texels) = SAMPLE_ATLAS;
    for (i, value) in [
        (0, 0),
        (0, 8193),
        (0, u32::MAX),
        (0, 4),         // R² = 16: the last index, 24, is out of range
        (2, texels[0]), // repeats row 0's texel
        (3, texels[1]), // below row 1's
        (7, r * r),     // the last row reaches R²
        (7, u32::MAX),
    ] {
        assert_eq!(
            open(&word(i, value)),
            Err(Error::BadTexelAtlas),
            "word {i} = {value}"
        );
    }
    // The largest resolution is valid.
    assert_eq!(open(&word(0, 8192)), Ok(()));
    for delta in [-4i64, 4, -(len as i64)] {
        let resized = with_header(&blob, |h| {
            let e = h.sections.iter_mut().find(|e| e.kind == 10).unwrap();
            e.len = (e.len as i64 + delta) as u64;
        })
        .unwrap();
        let result = open(&reseal(&resized));
        assert!(
            matches!(
                result,
                Err(Error::SectionLength {
                    section: SectionKind::TexelAtlas,
                    ..
                } | Error::SectionOutOfRange { .. }
                    | Error::TrailingBytes { .. })
            ),
            "{delta}: {result:?}"
        );
        // Cut into the corner UVs, the trailer's count gives the length; cut to nothing, the
        // length without a trailer.
        let expected = match delta {
            -4 => len,
            _ => 4 * (1 + texels.len()),
        };
        if delta < 0 {
            assert_eq!(
                result,
                Err(Error::SectionLength {
                    section: SectionKind::TexelAtlas,
                    expected: expected as u64,
                    found: (len as i64 + delta) as u64
                })
            );
        }
    }
    // Twice the section: a duplicate.
    let twice = with_header(&blob, |h| {
        let e = *h.sections.iter().find(|e| e.kind == 10).unwrap();
        h.sections.push(e).unwrap();
    })
    .unwrap();
    assert!(matches!(
        open(&twice),
        Err(Error::DuplicateSection { .. } | Error::SectionOverlap { .. })
    ));
    // A reader that predates the section skips it: as an unknown optional tag it is ignored.
    let renamed = with_header(&blob, |h| {
        h.sections.iter_mut().find(|e| e.kind == 10).unwrap().kind = 99;
    })
    .unwrap();
    assert_eq!(Model::parse(&renamed).unwrap().texel_atlas(), None);
}
