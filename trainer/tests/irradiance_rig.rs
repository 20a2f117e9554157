//! `aprt rig` and `aprt train --rig` through the real binary: the report's keys and what must
//! hold of them (a directional light is carried by any rig at no cost, a near light goes per
//! vertex, a far one into the rig), and a trained model that carries its rig.

use std::path::Path;

use run::{aprt, refuse, succeed};

use crate::run;

fn json(args: &[&str]) -> serde_json::Value {
    serde_json::from_slice(&succeed(args)).unwrap()
}

fn lights_file(dir: &Path, text: &str) -> String {
    let path = dir.join("lights.toml");
    std::fs::write(&path, text).unwrap();
    path.to_str().unwrap().to_owned()
}

/// A 4 × 1 × 0.5 box, elongated like the creature, each face a grid of 16 × 16 quads, as an
/// OBJ (the errors are measured at vertices, so the faces need some).
fn box_obj(dir: &Path) -> String {
    const N: usize = 16;
    let size = [4.0f32, 1.0, 0.5];
    let mut obj = String::new();
    let mut next = 1;
    for axis in 0..3 {
        for side in [0.0f32, 1.0] {
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            for i in 0..=N {
                for j in 0..=N {
                    let mut p = [0.0f32; 3];
                    p[axis] = side * size[axis];
                    p[u] = i as f32 / N as f32 * size[u];
                    p[v] = j as f32 / N as f32 * size[v];
                    obj += &format!("v {} {} {}\n", p[0], p[1], p[2]);
                }
            }
            for i in 0..N {
                for j in 0..N {
                    let at = |i: usize, j: usize| next + i * (N + 1) + j;
                    let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
                    // Outward: counter-clockwise seen from outside.
                    if side == 1.0 {
                        obj += &format!("f {a} {b} {c}\nf {a} {c} {d}\n");
                    } else {
                        obj += &format!("f {a} {c} {b}\nf {a} {d} {c}\n");
                    }
                }
            }
            next += (N + 1) * (N + 1);
        }
    }
    let path = dir.join("box.obj");
    std::fs::write(&path, obj).unwrap();
    path.to_str().unwrap().to_owned()
}

#[test]
fn rig_report_on_a_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = box_obj(dir.path());
    let lights = lights_file(
        dir.path(),
        r#"
[[light]]
kind = "directional"
direction = [0.2, 0.3, 1.0]
irradiance = [1.0, 0.5, 0.25]
[[light]]
kind = "sphere"
position = [4.3, 0.5, 0.25]
radius = 0.05
radiance = [40.0, 40.0, 40.0]
[[light]]
kind = "point"
position = [2.0, 0.5, 400.0]
intensity = [5.0, 5.0, 5.0]
"#,
    );
    for rig in [
        "constant",
        "gradient",
        "lattice:4x2x2",
        "mixed:x=lattice3,y=gradient,z=constant",
    ] {
        let v = json(&[
            "irradiance-rig",
            &mesh,
            "--lights",
            &lights,
            "--rig",
            rig,
            "--json",
        ]);
        assert_eq!(v["rig"], rig);
        let ls = v["lights"].as_array().unwrap();
        assert_eq!(ls.len(), 3);
        assert_eq!(ls[0]["mode"], "rig", "{rig}: directional");
        assert_eq!(ls[0]["transition_distance"], 0.0);
        assert_eq!(
            ls[1]["mode"], "analytic",
            "{rig}: a bright light 0.3 from the end"
        );
        assert_eq!(ls[2]["mode"], "rig", "{rig}: a point light 400 away");
        let t = ls[1]["transition_distance"].as_f64().unwrap();
        assert!(t > ls[1]["distance"].as_f64().unwrap(), "{rig}: {t}");
        for key in ["error_grey", "error_grey_all_rig", "error_grey_per_vertex"] {
            let (mean, max) = (
                v[key]["mean"].as_f64().unwrap(),
                v[key]["max"].as_f64().unwrap(),
            );
            assert!(
                mean.is_finite() && max.is_finite() && mean <= max,
                "{rig} {key}"
            );
        }
        // The near light per vertex: the choice costs little over the SH floor, while carrying
        // it in the rig would cost much more.
        let chosen = v["error_grey"]["max"].as_f64().unwrap();
        let floor = v["error_grey_per_vertex"]["max"].as_f64().unwrap();
        let all_rig = v["error_grey_all_rig"]["max"].as_f64().unwrap();
        assert!(
            chosen <= floor + 2.0,
            "{rig}: {chosen} against floor {floor}"
        );
        assert!(all_rig > chosen + 10.0, "{rig}: all in rig {all_rig}");
        assert!(v["sh_vectors"].as_u64().unwrap() >= 1);
        assert!(v["us_per_frame"]["total"].as_f64().unwrap() > 0.0);
    }
}

#[test]
fn rig_refusals_name_what_is_wrong() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = box_obj(dir.path());
    let lights = lights_file(
        dir.path(),
        "[[light]]\nkind = \"point\"\nposition = [0.0, 0.0, 3.0]\nintensity = [1.0, 1.0, 1.0]\n",
    );
    // Clap refuses a kind that does not parse, with the kind's own message.
    let out = aprt(&["rig", &mesh, "--lights", &lights, "--rig", "lattice:2x2"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && stderr.contains("\"2x2\" is not NXxNYxNZ"),
        "{stderr}"
    );
    refuse(
        &[
            "rig",
            &mesh,
            "--lights",
            &lights,
            "--rig",
            "gradient",
            "--builtin",
        ],
        &["not both"],
    );
    refuse(
        &[
            "rig",
            "--builtin",
            "--clip",
            "walk",
            "--frame",
            "9999",
            "--lights",
            &lights,
            "--rig",
            "gradient",
        ],
        &["--frame 9999"],
    );
    refuse(
        &[
            "rig",
            &mesh,
            "--lights",
            &lights,
            "--rig",
            "gradient",
            "--target-error",
            "0",
        ],
        &["--target-error"],
    );
}

#[test]
fn a_trained_model_carries_its_rig() {
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("m.aprt");
    let model = model.to_str().unwrap();
    succeed(&[
        "train",
        "--builtin",
        "--clip",
        "walk",
        "--rays",
        "8",
        "--order",
        "2",
        "--rig",
        "mixed:x=constant,y=gradient,z=lattice3",
        "-o",
        model,
    ]);
    let v = json(&["inspect", model, "--json"]);
    let rig = &v["irradiance_rig"];
    assert_eq!(rig["kind"], "mixed:x=constant,y=gradient,z=lattice3");
    assert_eq!(rig["sh_vectors"], 6);
    assert!(rig["samples"].as_u64().unwrap() >= 64);
    let sections: Vec<&str> = v["sections"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["kind"].as_str().unwrap())
        .collect();
    assert!(sections.contains(&"IrradianceRig"), "{sections:?}");
}
