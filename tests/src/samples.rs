//! Small valid blobs, one per kind of model (stored or identity basis, world or bone frame,
//! f32, f16 or scaled bytes, angles or cosine features): the starting points of the mutation tests and the seeds of the fuzz corpus
//! (`cargo run -p aprt-tests --release --example write_corpus` writes `fuzz/corpus/`).

use aprt_core::{AxisKind, RigLayout, RigShape};
use aprt_trainer::model::occluders::{BoneBound, ProxySection, Sphere};
use aprt_trainer::{
    BoneFrames, Extras, LinearModel, Precision, TexelAtlasExtra, encode_model, encode_model_with,
    encode_model_with_rig,
};

use crate::{random_model, with_cosines};

fn with_bones(mut m: LinearModel, count: usize) -> LinearModel {
    m.bones = Some(BoneFrames {
        count,
        vertex_bone: (0..m.vertices)
            .map(|j| (j * 5 / 3 % count) as u16)
            .collect(),
    });
    m
}

/// `(name, model, precision)` of each sample.
pub fn sample_models() -> Vec<(&'static str, LinearModel, Precision)> {
    vec![
        (
            "stored-f32",
            random_model(2, 9, 3, 2, Some(3)),
            Precision::F32,
        ),
        (
            "identity-f16",
            random_model(1, 5, 2, 1, None),
            Precision::F16,
        ),
        (
            "bones-stored-f16",
            with_bones(random_model(3, 11, 4, 0, Some(2)), 3),
            Precision::F16,
        ),
        (
            "bones-identity-f32",
            with_bones(random_model(2, 8, 1, 1, None), 2),
            Precision::F32,
        ),
        (
            "cosines-stored-f32",
            with_cosines(random_model(2, 7, 3, 2, Some(2)), &[true, false, true]),
            Precision::F32,
        ),
        (
            "stored-i8",
            random_model(2, 13, 3, 2, Some(3)),
            Precision::I8,
        ),
        (
            "bones-identity-i8",
            with_bones(random_model(2, 9, 2, 1, None), 3),
            Precision::I8,
        ),
    ]
}

/// A small mixed irradiance rig's bytes: a 2-node lattice along x, linear along y, over five
/// samples, with an error table.
pub fn sample_rig() -> Vec<u8> {
    let samples = [
        [0.0, 0.0, 0.0],
        [1.0, 0.2, 0.0],
        [-1.0, 0.1, 0.3],
        [0.5, -0.5, 0.1],
        [0.0, 0.4, -0.2],
    ];
    let shape = RigShape::Product([AxisKind::Lattice(2), AxisKind::Linear, AxisKind::Constant]);
    let matrix: Vec<f32> = (0..shape.vectors() * samples.len())
        .map(|i| ((i * 7 % 5) as f32 - 2.0) * 0.25)
        .collect();
    let layout = RigLayout {
        shape,
        centre: [0.0, 0.0, 0.0],
        half: [1.0, 0.5, 0.3],
        radius: 1.2,
        table: &[[1.1, 30.0], [3.0, 4.0], [9.0, 0.4]],
        samples: &samples,
        matrix: &matrix,
    };
    let mut bytes = vec![0u8; layout.len()];
    layout.write(&mut bytes).expect("sized for the layout");
    bytes
}

/// The texel atlas of [`sample_atlas_model`]: a 5 × 5 map, its rows on texels with gaps
/// between them (the first and last texel included).
pub const SAMPLE_ATLAS: (u32, [u32; 7]) = (5, [0, 3, 4, 11, 12, 20, 24]);

/// The light-map UVs of [`SAMPLE_ATLAS`]'s mesh: three triangles' corners, on the map's
/// edges and inside it.
pub const SAMPLE_ATLAS_UVS: [[[f32; 2]; 3]; 3] = [
    [[0.0, 0.0], [0.6, 0.0], [0.0, 0.6]],
    [[0.6, 0.0], [0.6, 0.6], [0.0, 0.6]],
    [[0.7, 0.5], [1.0, 0.9], [0.8, 1.0]],
];

/// A light-map model (its rows are texels) for [`SAMPLE_ATLAS`].
pub fn sample_atlas_model() -> LinearModel {
    random_model(2, SAMPLE_ATLAS.1.len(), 2, 1, None)
}

/// A proxies section for a model of `bones` bones: a sphere on bone 0 and one on the last
/// bone, each ignored by its own bone, culled below a cap of `sin²α = 0.01`.
pub fn sample_proxies(bones: usize) -> Vec<u8> {
    let last = (bones - 1) as u16;
    let sphere = |bone, centre| Sphere {
        bone,
        centre,
        radius: 0.25,
    };
    let mut bounds = vec![
        BoneBound {
            centre: [0.0, 0.0, 0.0],
            radius: 1.0,
            ignored: 0,
        };
        bones
    ];
    bounds[0].ignored |= 1;
    bounds[bones - 1].ignored |= 2;
    ProxySection {
        spheres: vec![sphere(0, [0.0, 0.0, 0.5]), sphere(last, [0.3, -0.2, 0.4])],
        bones: bounds,
        cull: 0.01,
    }
    .to_bytes()
    .expect("the sample proxies are valid")
}

/// `(name, blob)` of each sample, a bone-frame model carrying an irradiance rig, one carrying
/// occluder proxies, and a light-map model carrying its texel atlas with corner UVs (last).
pub fn sample_blobs() -> Vec<(&'static str, Vec<u8>)> {
    let rigged = with_bones(random_model(2, 10, 3, 1, Some(2)), 2);
    let atlas = Extras {
        texel_atlas: Some(TexelAtlasExtra {
            resolution: SAMPLE_ATLAS.0,
            texels: &SAMPLE_ATLAS.1,
            corner_uvs: Some(&SAMPLE_ATLAS_UVS),
        }),
        ..Extras::default()
    };
    let occluded = LinearModel {
        proxies: Some(sample_proxies(2)),
        ..rigged.clone()
    };
    sample_models()
        .into_iter()
        .map(|(name, m, p)| (name, encode_model(&m, p).expect("samples are valid")))
        .chain([
            (
                "proxies-bones-f32",
                encode_model(&occluded, Precision::F32).expect("samples are valid"),
            ),
            (
                "rig-bones-f32",
                encode_model_with_rig(&rigged, Precision::F32, Some(&sample_rig()))
                    .expect("samples are valid"),
            ),
            (
                "atlas-identity-f32",
                encode_model_with(&sample_atlas_model(), Precision::F32, &atlas)
                    .expect("samples are valid"),
            ),
        ])
        .collect()
}
