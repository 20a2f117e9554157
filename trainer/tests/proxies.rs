//! Occluder proxies through the binary: `--proxies on` writes them into the blob (a required
//! section aprt-core reads), `--proxies none` leaves them out, the selection says what they
//! did, and `aprt eval` subtracts their occlusion on the clip's posed meshes.

use aprt_core::Model;
use run::{aprt, read_npy, succeed};

use crate::run;

#[test]
fn proxies_are_written_when_asked_and_evaluated_on_the_clip() {
    let dir = tempfile::tempdir().unwrap();
    let path = |name: &str| dir.path().join(name).to_str().unwrap().to_owned();
    let source = ["--builtin", "--clip", "wave", "--order", "2", "--rays", "4"];
    let train = |proxies: &str, model: &str| {
        let args = [
            &["train"][..],
            &source,
            &["--proxies", proxies, "-o", model],
        ]
        .concat();
        let out = aprt(&args);
        assert!(out.status.success(), "{args:?}");
        String::from_utf8(out.stderr).unwrap()
    };
    let (with, without) = (path("with.aprt"), path("without.aprt"));
    let printed = train("on", &with);
    assert!(
        printed.contains("occluder proxies:") && printed.contains("kept"),
        "the selection says what the proxies did:\n{printed}"
    );
    train("none", &without);
    let has = |file: &str| {
        let blob = std::fs::read(file).unwrap();
        Model::parse(&blob).unwrap().info().has_proxies()
    };
    assert!(has(&with) && !has(&without));
    let npy = path("eval.npy");
    let args = [&["eval", &with][..], &source[..3], &["--npy", &npy]].concat();
    succeed(&args);
    let (shape, values) = read_npy(std::path::Path::new(&npy));
    assert_eq!(shape[2], 4);
    assert!(values.iter().all(|x| x.is_finite()));
}

/// RiggedSimple with every vertex weighted to joint 0 alone, as `.gltf` + `.bin` in `dir`:
/// its joint 1 weights nothing, as the end joints of many exports.
fn weighted_to_joint_0(assets: &std::path::Path, dir: &std::path::Path) -> String {
    let text = std::fs::read_to_string(assets.join("gltf/RiggedSimple.gltf")).unwrap();
    let mut gltf: serde_json::Value = serde_json::from_str(&text).unwrap();
    let vertices = gltf["accessors"][1]["count"].as_u64().unwrap() as usize;
    let joints = vec![0u8; vertices * 8]; // VEC4 of u16
    let weights: Vec<u8> = (0..vertices)
        .flat_map(|_| [1.0f32, 0.0, 0.0, 0.0])
        .flat_map(f32::to_le_bytes)
        .collect();
    std::fs::write(dir.join("joint0.bin"), [&joints[..], &weights].concat()).unwrap();
    let buffers = gltf["buffers"].as_array_mut().unwrap();
    buffers
        .push(serde_json::json!({"uri": "joint0.bin", "byteLength": joints.len() + weights.len()}));
    let buffer = buffers.len() - 1;
    let views = gltf["bufferViews"].as_array_mut().unwrap();
    views.push(serde_json::json!({"buffer": buffer, "byteOffset": 0, "byteLength": joints.len()}));
    views.push(serde_json::json!({"buffer": buffer, "byteOffset": joints.len(), "byteLength": weights.len()}));
    let view = views.len() - 2;
    let primitive = gltf["meshes"][0]["primitives"][0]["attributes"].clone();
    for (attribute, view, value) in [("JOINTS_0", view, 0), ("WEIGHTS_0", view + 1, 1)] {
        let accessor = &mut gltf["accessors"][primitive[attribute].as_u64().unwrap() as usize];
        accessor["bufferView"] = view.into();
        accessor["byteOffset"] = 0.into();
        accessor["min"] = serde_json::json!([0, 0, 0, 0]);
        accessor["max"] = serde_json::json!([value, 0, 0, 0]);
    }
    let path = dir.join("joint0.gltf");
    std::fs::write(&path, gltf.to_string()).unwrap();
    path.to_str().unwrap().to_owned()
}

/// A character whose last joint weights no vertex trains by default, with proxies, and
/// evaluates: the proxies are posed by the model's bones (the joints up to the last weighted
/// one), not by every joint of the skin.
#[test]
fn a_character_with_an_unweighted_end_joint_trains_with_proxies() {
    let Some(assets) = crate::common::assets("a_character_with_an_unweighted_end_joint") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let gltf = weighted_to_joint_0(&assets, dir.path());
    let source = ["--gltf", &gltf, "--clip", "animation0"];
    let cheap = ["--order", "2", "--rays", "4"];
    for proxies in ["auto", "on"] {
        let model = dir.path().join(format!("{proxies}.aprt"));
        let model = model.to_str().unwrap();
        let args = [
            &["train"][..],
            &source,
            &cheap,
            &["--proxies", proxies, "-o", model],
        ];
        succeed(&args.concat());
        let blob = std::fs::read(model).unwrap();
        let info = *Model::parse(&blob).unwrap().info();
        assert_eq!(info.bones(), 1, "{proxies}");
        if proxies == "on" {
            assert!(info.has_proxies());
            let npy = dir.path().join("eval.npy");
            let npy = npy.to_str().unwrap();
            succeed(&[&["eval", model][..], &source, &["--npy", npy]].concat());
            assert!(
                read_npy(std::path::Path::new(npy))
                    .1
                    .iter()
                    .all(|x| x.is_finite())
            );
        }
    }
}
