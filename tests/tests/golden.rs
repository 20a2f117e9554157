//! Golden blobs: small models of each frame, checked into `fixtures/golden/`, that every later
//! reader must keep reading the same way (the format's compatibility promise) and that the
//! core's documentation examples run on. `cargo test -p aprt-tests --release --test golden --
//! --ignored` writes them again from the models below.

use std::path::PathBuf;

use aprt_core::{Frame, Model};
use aprt_tests::decode::decode;
use aprt_tests::harness::{Probe, exercise};
use aprt_tests::random_model;
use aprt_trainer::model::occluders::{BoneBound, ProxySection, Sphere};
use aprt_trainer::{BoneFrames, Extras, LinearModel, Precision, encode_model_with};

fn golden_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../fixtures/golden")
}

/// A golden blob: its file name, model, precision and texel atlas (resolution, texels).
type Golden = (
    &'static str,
    LinearModel,
    Precision,
    Option<(u32, Vec<u32>)>,
);

/// The blob's bytes as the writer writes them today.
fn encode((_, model, precision, atlas): &Golden) -> Vec<u8> {
    let extras = Extras {
        texel_atlas: atlas.as_ref().map(|(r, texels)| (*r, &texels[..])),
        ..Extras::default()
    };
    encode_model_with(model, *precision, &extras).unwrap()
}

/// Each golden blob: a world-frame and a bone-frame model, a light-map model (its rows are
/// texels of an 8 × 8 map) with its texel atlas, and a bone-frame model with occluder
/// proxies (two spheres on bone 0, which bone 0 ignores).
fn golden_models() -> Vec<Golden> {
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
    let texels = (0..12).map(|j| 9 + 4 * j).collect();
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
        ("v1-atlas.aprt", lightmap, Precision::F32, Some((8, texels))),
        ("v1-proxies.aprt", occluded, Precision::F32, None),
    ]
}

#[test]
#[ignore = "writes fixtures/golden; run when the golden models change"]
fn write_golden_blobs() {
    for golden in golden_models() {
        std::fs::write(golden_dir().join(golden.0), encode(&golden)).unwrap();
    }
}

/// Each checked-in blob reads with the dimensions and names it was written with, evaluates
/// like the f64 reference of what it stores (resident and streamed, through the fuzz
/// harness), and is what the writer writes today.
#[test]
fn golden_blobs_read_as_written() {
    for golden in golden_models() {
        let (name, model, _, atlas) = &golden;
        let path = golden_dir().join(name);
        let blob = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let core = Model::parse(&blob).unwrap_or_else(|e| panic!("{name}: {e}"));
        let info = core.info();
        assert_eq!(
            (
                info.order(),
                info.vertices(),
                info.pose_len(),
                info.pose_dims()
            ),
            (
                model.order,
                model.vertices,
                model.pose_len,
                model.pose_dims()
            ),
            "{name}"
        );
        assert_eq!(info.coef_dims(), model.coef_dims(), "{name}");
        let bones = model.bones.as_ref().map_or(0, |b| b.count);
        assert_eq!(info.bones(), bones, "{name}");
        assert_eq!(info.frame() == Frame::World, bones == 0, "{name}");
        assert!(
            core.angle_names()
                .iter()
                .eq(model.angle_names.iter().map(String::as_str))
        );
        let stored = decode(&blob).unwrap();
        assert_eq!(stored.angle_names, model.angle_names, "{name}");
        let read = core.texel_atlas().map(|a| {
            let texels = (0..a.rows()).map(|j| a.texel(j).unwrap()).collect();
            (a.resolution(), texels)
        });
        assert_eq!(read, *atlas, "{name}: texel atlas");
        assert_eq!(
            info.has_proxies(),
            model.proxies.is_some(),
            "{name}: proxies"
        );
        assert_eq!(stored.proxies, model.proxies, "{name}: proxies");
        exercise(&blob, &Probe::GENTLE).unwrap();
        assert!(
            encode(&golden) == blob,
            "{name}: the writer's bytes changed; if that is intended, keep this blob as a \
             compatibility fixture and write the new one under a new name"
        );
    }
}
