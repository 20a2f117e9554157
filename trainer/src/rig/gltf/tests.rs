//! Small glTF documents built in code: a two-joint skin with known answers, written as
//! `.gltf` with an embedded buffer, `.gltf` with an external buffer and `.glb`.

use std::f64::consts::FRAC_PI_2;
use std::path::{Path, PathBuf};

use glam::{DMat4, DQuat, DVec3, Vec3};
use serde_json::{Value, json};

use super::*;

/// A document under construction: JSON plus one binary buffer, one buffer view per accessor.
struct Doc {
    json: Value,
    bin: Vec<u8>,
}

impl Doc {
    /// Appends `values` (f32 or u16 by `component`) as a new accessor; returns its index.
    fn accessor(&mut self, kind: &str, component: u32, values: &[f64], extra: Value) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let offset = self.bin.len();
        for &v in values {
            match component {
                5126 => self.bin.extend((v as f32).to_le_bytes()),
                5123 => self.bin.extend((v as u16).to_le_bytes()),
                _ => unreachable!(),
            }
        }
        let width = match kind {
            "SCALAR" => 1,
            "VEC2" => 2,
            "VEC3" => 3,
            "VEC4" => 4,
            "MAT4" => 16,
            _ => unreachable!(),
        };
        let views = self.json["bufferViews"].as_array_mut().unwrap();
        views.push(
            json!({"buffer": 0, "byteOffset": offset, "byteLength": self.bin.len() - offset}),
        );
        let mut accessor = json!({
            "bufferView": views.len() - 1, "componentType": component,
            "count": values.len() / width, "type": kind
        });
        if let Value::Object(extra) = extra {
            accessor.as_object_mut().unwrap().extend(extra);
        }
        let accessors = self.json["accessors"].as_array_mut().unwrap();
        accessors.push(accessor);
        accessors.len() - 1
    }

    fn f32s(&mut self, kind: &str, values: &[f64]) -> usize {
        self.accessor(kind, 5126, values, Value::Null)
    }

    /// Writes the document in one of three forms and returns the path to load.
    fn write(&self, dir: &Path, form: Form) -> PathBuf {
        let mut json = self.json.clone();
        json["buffers"] = json!([{"byteLength": self.bin.len()}]);
        match form {
            Form::Embedded => {
                json["buffers"][0]["uri"] =
                    format!("data:application/octet-stream;base64,{}", base64(&self.bin)).into();
                let path = dir.join("embedded.gltf");
                std::fs::write(&path, json.to_string()).unwrap();
                path
            }
            Form::External => {
                // Percent-encoded, as URIs are: the file is "external data.bin".
                json["buffers"][0]["uri"] = "external%20data.bin".into();
                std::fs::write(dir.join("external data.bin"), &self.bin).unwrap();
                let path = dir.join("external.gltf");
                std::fs::write(&path, json.to_string()).unwrap();
                path
            }
            Form::Glb => {
                let mut text = json.to_string().into_bytes();
                while !text.len().is_multiple_of(4) {
                    text.push(b' ');
                }
                let mut bin = self.bin.clone();
                while !bin.len().is_multiple_of(4) {
                    bin.push(0);
                }
                let total = 12 + 8 + text.len() + 8 + bin.len();
                let mut glb = Vec::new();
                glb.extend(b"glTF");
                glb.extend(2u32.to_le_bytes());
                glb.extend((total as u32).to_le_bytes());
                glb.extend((text.len() as u32).to_le_bytes());
                glb.extend(b"JSON");
                glb.extend(text);
                glb.extend((bin.len() as u32).to_le_bytes());
                glb.extend(b"BIN\0");
                glb.extend(bin);
                let path = dir.join("binary.glb");
                std::fs::write(&path, glb).unwrap();
                path
            }
        }
    }
}

#[derive(Clone, Copy, Debug)]
enum Form {
    Embedded,
    External,
    Glb,
}

fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            *chunk.get(1).unwrap_or(&0),
            *chunk.get(2).unwrap_or(&0),
        ];
        let n = u32::from(b[0]) << 16 | u32::from(b[1]) << 8 | u32::from(b[2]);
        for i in 0..4 {
            if i <= chunk.len() {
                out.push(ALPHABET[(n >> (18 - 6 * i) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// Rest rotation of the tip joint: a quarter turn about z, so its local x is the mesh's y
/// and the pose-vector convention (joint frame vs parent frame) is visible.
fn tip_rest() -> DQuat {
    DQuat::from_rotation_z(FRAC_PI_2)
}

/// Two joints, `base` at the origin and `tip` at z = 1 (rest rotation [`tip_rest`]), under a
/// Y-up → Z-up root like CesiumMan's; the mesh node sits beside the skeleton under the same
/// root. Four vertices in the xz plane: v0, v1 on `base`, v2 on `tip`, v3 half and half
/// through a second influence set (weights 0.3 + 0.3, normalised to 0.5 each).
/// Animations on `tip` rotate from rest to `rest · Rx(1)` over 1 s: "linear", "step",
/// "cubic" (zero tangents); "long" is linear over 1.1 s and also moves `base` (held).
fn two_joint_doc() -> Doc {
    let root = DQuat::from_rotation_x(-FRAC_PI_2);
    let mut doc = Doc {
        json: json!({
            "asset": {"version": "2.0"},
            "scene": 0,
            "scenes": [{"nodes": [0]}],
            "nodes": [
                {"name": "root", "rotation": root.to_array(), "children": [1, 2]},
                {"name": "body", "mesh": 0, "skin": 0},
                {"name": "base", "children": [3]},
                {"name": "tip", "translation": [0.0, 0.0, 1.0], "rotation": tip_rest().to_array()}
            ],
            "bufferViews": [],
            "accessors": [],
        }),
        bin: Vec::new(),
    };
    let positions = doc.accessor(
        "VEC3",
        5126,
        &[0., 0., 0., 1., 0., 0., 0., 0., 2., 1., 0., 2.],
        json!({"min": [0.0, 0.0, 0.0], "max": [1.0, 0.0, 2.0]}),
    );
    let normals = doc.f32s("VEC3", &[0., 2., 0.].repeat(4));
    let joints0 = doc.accessor(
        "VEC4",
        5123,
        &[
            0., 0., 0., 0., 0., 0., 0., 0., 1., 0., 0., 0., 1., 0., 0., 0.,
        ],
        Value::Null,
    );
    let weights0 = doc.f32s(
        "VEC4",
        &[
            1., 0., 0., 0., 1., 0., 0., 0., 1., 0., 0., 0., 0.3, 0., 0., 0.,
        ],
    );
    let joints1 = doc.accessor("VEC4", 5123, &[0.; 16], Value::Null);
    let weights1 = doc.f32s(
        "VEC4",
        &[
            0., 0., 0., 0., 0., 0., 0., 0., 0., 0., 0., 0., 0.3, 0., 0., 0.,
        ],
    );
    let indices = doc.accessor("SCALAR", 5123, &[0., 1., 2., 1., 3., 2.], Value::Null);
    // inverse(world_bind(joint)) · world(mesh node): the root cancels.
    let tip_bind = DMat4::from_rotation_translation(tip_rest(), DVec3::Z);
    let ibm: Vec<f64> = [DMat4::IDENTITY, tip_bind.inverse()]
        .iter()
        .flat_map(|m| m.to_cols_array())
        .collect();
    let ibm = doc.f32s("MAT4", &ibm);
    let second = json!({"min": [0.0], "max": [1.0]});
    let times = doc.accessor("SCALAR", 5126, &[0.0, 1.0], second);
    let long_times = doc.accessor(
        "SCALAR",
        5126,
        &[0.0, 1.1],
        json!({"min": [0.0], "max": [1.1]}),
    );
    let end = tip_rest() * DQuat::from_rotation_x(1.0);
    let rotations: Vec<f64> = [tip_rest(), end]
        .iter()
        .flat_map(|q| q.to_array())
        .collect();
    let rotations = doc.f32s("VEC4", &rotations);
    let zero = [0.0; 4];
    let cubic: Vec<f64> = [
        zero,
        tip_rest().to_array(),
        zero,
        zero,
        end.to_array(),
        zero,
    ]
    .concat();
    let cubic = doc.f32s("VEC4", &cubic);
    let moves = doc.f32s("VEC3", &[0., 0., 0., 0.5, 0., 0.]);
    doc.json["meshes"] = json!([{"primitives": [{
        "attributes": {
            "POSITION": positions, "NORMAL": normals,
            "JOINTS_0": joints0, "WEIGHTS_0": weights0,
            "JOINTS_1": joints1, "WEIGHTS_1": weights1
        },
        "indices": indices
    }]}]);
    doc.json["skins"] = json!([{"joints": [2, 3], "inverseBindMatrices": ibm}]);
    let animation = |name: &str, interpolation: &str, output: usize| {
        json!({
            "name": name,
            "channels": [{"sampler": 0, "target": {"node": 3, "path": "rotation"}}],
            "samplers": [{"input": times, "output": output, "interpolation": interpolation}]
        })
    };
    doc.json["animations"] = json!([
        animation("linear", "LINEAR", rotations),
        animation("step", "STEP", rotations),
        animation("cubic", "CUBICSPLINE", cubic),
        {
            "name": "long",
            "channels": [
                {"sampler": 0, "target": {"node": 3, "path": "rotation"}},
                {"sampler": 1, "target": {"node": 2, "path": "translation"}}
            ],
            "samplers": [
                {"input": long_times, "output": rotations},
                {"input": long_times, "output": moves}
            ]
        }
    ]);
    doc
}

fn load(doc: &Doc, form: Form) -> (tempfile::TempDir, Result<GltfRig, GltfError>) {
    let dir = tempfile::tempdir().unwrap();
    let path = doc.write(dir.path(), form);
    let rig = GltfRig::load(&path, 4.0);
    (dir, rig)
}

fn close(a: [f32; 3], b: [f32; 3]) -> bool {
    (Vec3::from(a) - Vec3::from(b)).length() < 1e-5
}

#[test]
fn the_rest_pose_gives_back_the_stored_mesh() {
    let (_dir, rig) = load(&two_joint_doc(), Form::Embedded);
    let rig = rig.unwrap();
    assert_eq!(rig.joint_names(), ["base", "tip"]);
    assert_eq!(rig.angle_names()[3..], ["tip.x", "tip.y", "tip.z"]);
    let bind = rig.bind_mesh();
    assert_eq!(bind.triangles, vec![[0, 1, 2], [1, 3, 2]]);
    assert_eq!(
        bind.normals,
        vec![[0.0, 1.0, 0.0]; 4],
        "normals are renormalised"
    );
    let posed = rig.pose(&[0.0; 6]).unwrap();
    for (p, b) in posed.positions.iter().zip(&bind.positions) {
        assert!(close(*p, *b), "{p:?} vs {b:?}");
    }
    // Both influence sets are read and normalised.
    assert_eq!(
        rig.skin().influences(3).collect::<Vec<_>>(),
        vec![(1, 0.5), (0, 0.5)]
    );
    // The root turns the file's Z-up data into glTF's Y-up world: world +Y is +Z here.
    assert!((rig.up() - Vec3::Z).length() < 1e-6);
}

#[test]
fn pose_rotations_are_about_the_joints_own_rest_axes() {
    let (_dir, rig) = load(&two_joint_doc(), Form::Embedded);
    let rig = rig.unwrap();
    // A quarter turn about the tip's local x, which its rest rotation points along mesh y:
    // Ry(90°) maps the tip's offsets (0,0,1) → (1,0,0) and (1,0,1) → (1,0,−1). v2 is on the
    // tip; v3 averages tip (1,0,0) and base (1,0,2).
    let posed = rig.pose(&[0.0, 0.0, 0.0, FRAC_PI_2, 0.0, 0.0]).unwrap();
    let expect = [[0., 0., 0.], [1., 0., 0.], [1., 0., 1.], [1., 0., 1.]];
    for (p, e) in posed.positions.iter().zip(expect) {
        assert!(close(*p, e), "{:?} vs {expect:?}", posed.positions);
    }
}

#[test]
fn clips_follow_each_interpolation_mode() {
    let (_dir, rig) = load(&two_joint_doc(), Form::Embedded);
    let rig = rig.unwrap();
    assert_eq!(rig.clip_names(), ["linear", "step", "cubic", "long"]);
    // 4 fps over 1 s: t = 0, 0.25, 0.5, 0.75, 1, the last included. The tip turns about its
    // local x from 0 to 1 rad; the base never moves.
    let tip_x = |name: &str| -> Vec<f64> {
        let clip = rig.clip(name).unwrap();
        assert_eq!(clip.fps, 4.0);
        for f in &clip.frames {
            assert!(
                f[..3].iter().chain(&f[4..]).all(|v| v.abs() < 1e-6),
                "{f:?}"
            );
        }
        clip.frames.iter().map(|f| f[3]).collect()
    };
    let within = |got: Vec<f64>, expect: &[f64]| {
        assert_eq!(got.len(), expect.len());
        for (g, e) in got.iter().zip(expect) {
            assert!((g - e).abs() < 1e-6, "{got:?} vs {expect:?}");
        }
    };
    within(tip_x("linear"), &[0.0, 0.25, 0.5, 0.75, 1.0]);
    within(tip_x("step"), &[0.0, 0.0, 0.0, 0.0, 1.0]);
    // Zero tangents: the relative rotation is normalize(h00·1 + h01·Rx(1)), whose angle is
    // 2·atan2(h01·sin ½, h00 + h01·cos ½) with h01 = 3u² − 2u³.
    let cubic: Vec<f64> = [0.0, 0.25, 0.5, 0.75, 1.0]
        .iter()
        .map(|&u: &f64| {
            let h01 = 3.0 * u * u - 2.0 * u * u * u;
            2.0 * (h01 * 0.5f64.sin()).atan2(1.0 - h01 + h01 * 0.5f64.cos())
        })
        .collect();
    within(tip_x("cubic"), &cubic);
    // 1.1 s at 4 fps: five whole frames and a last one clamped to the end.
    within(
        tip_x("long"),
        &[0.0, 0.25 / 1.1, 0.5 / 1.1, 0.75 / 1.1, 1.0 / 1.1, 1.0],
    );
}

#[test]
fn the_pose_vector_reproduces_rotations_and_held_channels_are_reported() {
    let (_dir, rig) = load(&two_joint_doc(), Form::Embedded);
    let rig = rig.unwrap();
    for name in ["linear", "cubic"] {
        let clip = rig.clip(name).unwrap();
        for (i, pose) in clip.frames.iter().enumerate() {
            let from_pose = rig.joint_matrices(pose).unwrap();
            let animated = rig.animated_joint_matrices(name, i).unwrap();
            for (a, b) in from_pose.iter().zip(&animated) {
                assert!(a.abs_diff_eq(*b, 1e-6), "{name} frame {i}: {a:?} vs {b:?}");
            }
        }
    }
    // "long" also slides the base (the skeleton root) along x: held at rest, reported, and
    // the difference it makes is a rigid translation.
    assert_eq!(
        rig.held_channels(),
        [HeldChannel {
            animation: "long".into(),
            node: 2,
            node_name: "base".into(),
            property: "translation",
            max_deviation: 0.5,
        }]
    );
    assert_eq!(
        rig.held_channels()[0].to_string(),
        "clip long: the translation of node 2 (base) is animated, up to 0.500 units from rest, \
         and held at rest: the pose vector carries joint rotations only"
    );
    let last = rig.clip("long").unwrap().frames.len() - 1;
    let pose = &rig.clip("long").unwrap().frames[last];
    let animated = rig.animated_joint_matrices("long", last).unwrap();
    for (a, b) in rig.joint_matrices(pose).unwrap().iter().zip(&animated) {
        let shift = glam::Mat4::from_translation(Vec3::new(0.5, 0.0, 0.0));
        assert!((shift * *a).abs_diff_eq(*b, 1e-6));
    }
    assert!(matches!(
        rig.animated_joint_matrices("long", last + 1),
        Err(GltfError::Frames { .. })
    ));
}

#[test]
fn embedded_external_and_binary_buffers_load_the_same_rig() {
    let doc = two_joint_doc();
    let (_a, embedded) = load(&doc, Form::Embedded);
    let embedded = embedded.unwrap();
    for form in [Form::External, Form::Glb] {
        let (_dir, other) = load(&doc, form);
        let other = other.unwrap();
        assert_eq!(other.bind_mesh(), embedded.bind_mesh(), "{form:?}");
        assert_eq!(other.skin(), embedded.skin(), "{form:?}");
        let pose = [0.1, -0.2, 0.3, 0.4, 0.5, -0.6];
        assert_eq!(
            other.joint_matrices(&pose).unwrap(),
            embedded.joint_matrices(&pose).unwrap()
        );
        for name in embedded.clip_names() {
            assert_eq!(other.clip(&name).unwrap(), embedded.clip(&name).unwrap());
        }
    }
}

#[test]
fn errors_name_the_file_and_the_item() {
    let message = |doc: &Doc| {
        let (_dir, rig) = load(doc, Form::Embedded);
        rig.unwrap_err().to_string()
    };
    let mut unskinned = two_joint_doc();
    unskinned.json["nodes"][1]
        .as_object_mut()
        .unwrap()
        .remove("skin");
    let text = message(&unskinned);
    assert!(
        text.contains("embedded.gltf") && text.contains("without a skin"),
        "{text}"
    );

    let mut points = two_joint_doc();
    points.json["meshes"][0]["primitives"][0]["mode"] = 0.into();
    let text = message(&points);
    assert!(
        text.contains("mesh 0 primitive 0") && text.contains("Points"),
        "{text}"
    );

    let mut stray = two_joint_doc();
    stray.json["skins"][0]["joints"] = json!([2]);
    stray.json["nodes"][2]["children"] = json!([]);
    let text = message(&stray);
    assert!(
        text.contains("JOINTS_0 of vertex 2 names joint 1"),
        "{text}"
    );

    let (dir, _) = load(&two_joint_doc(), Form::External);
    std::fs::remove_file(dir.path().join("external data.bin")).unwrap();
    let text = GltfRig::load(&dir.path().join("external.gltf"), 30.0)
        .unwrap_err()
        .to_string();
    assert!(
        text.contains("external.gltf: buffer 0: ")
            && text.contains("external data.bin: cannot read this glTF buffer: No such file"),
        "{text}"
    );
    let source = std::error::Error::source(
        &GltfRig::load(&dir.path().join("external.gltf"), 30.0).unwrap_err(),
    )
    .map(ToString::to_string);
    assert!(source.is_some_and(|s| s.contains("No such file")));

    let (_dir, rig) = load(&two_joint_doc(), Form::Embedded);
    let rig = rig.unwrap();
    let text = rig.clip("run").unwrap_err().to_string();
    assert!(text.contains("linear, step, cubic, long"), "{text}");
    let err = rig
        .joint_matrices(&[0.0, 0.0, 0.0, 0.0, f64::NAN, 0.0])
        .unwrap_err();
    let text = format!("{:#}", anyhow::Error::from(err));
    assert!(
        text.ends_with("embedded.gltf: pose value 4 (tip.y) is NaN, not a finite number"),
        "{text}"
    );
    assert!(rig.joint_matrices(&[0.0; 5]).is_err());
    assert!(matches!(
        GltfRig::load(Path::new("x.gltf"), 0.0),
        Err(GltfError::Fps { .. })
    ));
}

/// A joint turning on past a half turn: the log map alone would jump from +π to −π, so the
/// clip unwraps each rotation vector to the turn nearest the previous frame's, and the pose
/// vector still reproduces the animation.
#[test]
fn clips_unwrap_rotations_through_half_turns() {
    let mut doc = two_joint_doc();
    let times = doc.accessor(
        "SCALAR",
        5126,
        &[0.0, 0.5, 1.0],
        json!({"min": [0.0], "max": [1.0]}),
    );
    let keys: Vec<f64> = [0.0, 2.0, 4.0]
        .iter()
        .flat_map(|&a| (tip_rest() * DQuat::from_rotation_x(a)).to_array())
        .collect();
    let keys = doc.f32s("VEC4", &keys);
    doc.json["animations"].as_array_mut().unwrap().push(json!({
        "name": "spin",
        "channels": [{"sampler": 0, "target": {"node": 3, "path": "rotation"}}],
        "samplers": [{"input": times, "output": keys}]
    }));
    let (_dir, rig) = load(&doc, Form::Embedded);
    let rig = rig.unwrap();
    let clip = rig.clip("spin").unwrap();
    let tip_x: Vec<f64> = clip.frames.iter().map(|f| f[3]).collect();
    assert_eq!(tip_x.len(), 5, "{tip_x:?}");
    for (got, expect) in tip_x.iter().zip([0.0, 1.0, 2.0, 3.0, 4.0]) {
        assert!((got - expect).abs() < 1e-5, "{tip_x:?}");
    }
    for (i, pose) in clip.frames.iter().enumerate() {
        let animated = rig.animated_joint_matrices("spin", i).unwrap();
        for (a, b) in rig.joint_matrices(pose).unwrap().iter().zip(&animated) {
            assert!(a.abs_diff_eq(*b, 1e-5), "frame {i}: {a:?} vs {b:?}");
        }
    }
}

/// The same document from bytes: embedded and binary forms load as from the file; an external
/// buffer is refused, as there is no directory to read it from.
#[test]
fn from_slice_reads_embedded_and_binary_documents_and_refuses_external_buffers() {
    let doc = two_joint_doc();
    for form in [Form::Embedded, Form::Glb, Form::External] {
        let dir = tempfile::tempdir().unwrap();
        let path = doc.write(dir.path(), form);
        let bytes = std::fs::read(&path).unwrap();
        let from_bytes = GltfRig::from_slice(&bytes, Path::new("memory.gltf"), 4.0);
        match form {
            Form::External => {
                let text = from_bytes.unwrap_err().to_string();
                assert!(
                    text.starts_with("memory.gltf: buffer 0: names the external file"),
                    "{text}"
                );
            }
            _ => {
                let (from_file, rig) = (GltfRig::load(&path, 4.0).unwrap(), from_bytes.unwrap());
                assert_eq!(rig.bind_mesh(), from_file.bind_mesh(), "{form:?}");
                assert_eq!(
                    rig.clip("linear").unwrap(),
                    from_file.clip("linear").unwrap()
                );
            }
        }
    }
}

/// Adds `TEXCOORD_0` (`kind` of `component`, `extra` accessor properties) to the primitive.
fn with_uvs(kind: &str, component: u32, values: &[f64], extra: Value) -> Doc {
    let mut doc = two_joint_doc();
    let uvs = doc.accessor(kind, component, values, extra);
    doc.json["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = uvs.into();
    doc
}

#[test]
fn texcoord_0_gives_the_uv_layout_per_corner() {
    let (_dir, rig) = load(&two_joint_doc(), Form::Embedded);
    assert!(
        rig.unwrap().uv_layout().is_none(),
        "no TEXCOORD_0, no layout"
    );
    // Normalized UNSIGNED_SHORT: 65535 is 1.
    let doc = with_uvs(
        "VEC2",
        5123,
        &[0., 0., 65535., 0., 0., 65535., 65535., 65535.],
        json!({"normalized": true}),
    );
    let (_dir, rig) = load(&doc, Form::Embedded);
    let rig = rig.unwrap();
    let layout = rig.uv_layout().unwrap();
    assert_eq!(
        layout.corners,
        [
            [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]],
            [[1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]
        ]
    );
    let uvs = layout.vertex_uvs(&rig.bind_mesh().triangles, 4);
    assert_eq!(uvs[3], [[1.0, 1.0]]);
}

#[test]
fn texcoord_0_of_the_wrong_type_or_count_is_refused() {
    let cases = [
        with_uvs("VEC3", 5126, &[0.0; 12], Value::Null),
        with_uvs("VEC2", 5123, &[0.0; 8], Value::Null),
        with_uvs("VEC2", 5126, &[0.0; 6], Value::Null),
    ];
    for (doc, expect) in cases.iter().zip(["VEC3", "UNSIGNED_SHORT", "3 elements"]) {
        let (_dir, rig) = load(doc, Form::Embedded);
        let message = rig.unwrap_err().to_string();
        assert!(
            message.contains("TEXCOORD_0") && message.contains(expect),
            "{message}"
        );
    }
}
