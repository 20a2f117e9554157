//! The golden blobs of `fixtures/golden/`: the models they are written from, so the stable
//! test (`tests/tests/golden.rs`) checks every checked-in blob is what the writer writes
//! today, and `cargo run -p aprt-tests --release --example write_golden` writes them again
//! when the golden models change.

use std::path::PathBuf;

use aprt_trainer::model::occluders::{BoneBound, ProxySection, Sphere};
use aprt_trainer::{
    BoneFrames, Extras, LinearModel, Precision, TexelAtlasExtra, encode_model_with,
};

use crate::random_model;

/// Where the golden blobs are checked in.
pub fn golden_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../fixtures/golden")
}

/// A golden blob: its file name, model, precision and texel atlas.
pub type Golden = (&'static str, LinearModel, Precision, Option<GoldenAtlas>);

/// A golden texel atlas: resolution, texels, and corner UVs (none when empty).
pub type GoldenAtlas = (u32, Vec<u32>, Vec<[[f32; 2]; 3]>);

/// The blob's bytes as the writer writes them today.
pub fn encode((_, model, precision, atlas): &Golden) -> Vec<u8> {
    let extras = Extras {
        texel_atlas: atlas.as_ref().map(|(r, texels, uvs)| TexelAtlasExtra {
            resolution: *r,
            texels,
            corner_uvs: (!uvs.is_empty()).then_some(&uvs[..]),
        }),
        ..Extras::default()
    };
    encode_model_with(model, *precision, &extras).unwrap()
}

/// Each golden blob: a world-frame and a bone-frame model, a light-map model (its rows are
/// texels of an 8 × 8 map) with its texel atlas, without and with the corner UVs of its
/// mesh, and a bone-frame model with occluder proxies (two spheres on bone 0, which bone 0
/// ignores).
pub fn golden_models() -> Vec<Golden> {
    let names = |names: &[&str]| names.iter().map(|n| n.to_string()).collect();
    let mut world = random_model(3, 20, 4, 2, Some(3));
    world.angle_names = names(&["hip.x", "hip.y", "hip.z", "knee"]);
    let mut bones = random_model(3, 24, 5, 3, Some(4));
    bones.angle_names = names(&["neck.x", "neck.y", "neck.z", "l_elbow", "r_elbow"]);
    bones.bones = Some(BoneFrames {
        count: 3,
        vertex_bone: (0..24).map(|j| (j / 8) as u16).collect(),
    });
    let mut lightmap = random_model(2, 12, 3, 1, None);
    lightmap.angle_names = names(&["jaw", "brow.l", "brow.r"]);
    let texels: Vec<u32> = (0..12).map(|j| 9 + 4 * j).collect();
    let mut occluded = random_model(2, 16, 3, 3, Some(5));
    occluded.angle_names = names(&["shoulder.x", "shoulder.y", "elbow"]);
    occluded.bones = Some(BoneFrames {
        count: 2,
        vertex_bone: (0..16).map(|j| (j / 8) as u16).collect(),
    });
    let sphere = |centre, radius| Sphere {
        bone: 0,
        centre,
        radius,
    };
    occluded.proxies = Some(
        ProxySection {
            spheres: vec![sphere([0.0, 0.0, 1.0], 0.3), sphere([0.0, 0.4, 1.0], 0.2)],
            bones: vec![
                BoneBound {
                    centre: [0.0, 0.2, 1.0],
                    radius: 0.5,
                    ignored: 0b11,
                },
                BoneBound {
                    centre: [0.0, 0.0, 0.0],
                    radius: 0.3,
                    ignored: 0,
                },
            ],
            cull: 0.01,
        }
        .to_bytes()
        .unwrap(),
    );
    vec![
        ("v1-world.aprt", world, Precision::F32, None),
        ("v1-bones.aprt", bones, Precision::F16, None),
        (
            "v1-atlas.aprt",
            lightmap.clone(),
            Precision::F32,
            Some((8, texels.clone(), vec![])),
        ),
        (
            "v1-atlas-uvs.aprt",
            lightmap,
            Precision::F32,
            Some((8, texels, golden_corner_uvs())),
        ),
        ("v1-proxies.aprt", occluded, Precision::F32, None),
    ]
}

/// The light-map UVs of the golden light-map model's mesh: two islands of two triangles, one
/// a square at the map's corner, one inside.
fn golden_corner_uvs() -> Vec<[[f32; 2]; 3]> {
    vec![
        [[0.0, 0.0], [0.5, 0.0], [0.0, 0.5]],
        [[0.5, 0.0], [0.5, 0.5], [0.0, 0.5]],
        [[0.625, 0.5], [1.0, 0.5], [0.625, 1.0]],
        [[1.0, 0.5], [1.0, 1.0], [0.625, 1.0]],
    ]
}
