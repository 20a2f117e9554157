//! Values and files that once gave a wrong result with exit 0 (issue 30), through the real
//! `aprt` binary: each is now refused with one `aprt:` line naming the file, the item and what
//! is wrong, before any work, with no panic and every input byte for byte as it was.

use crate::run;

use std::path::{Path, PathBuf};

use run::{refuse, tiny_character};

/// A scene for the small character in `dir`, saved as `name`, ending with `lighting` (lines
/// of TOML after `[effects] rays`).
fn scene(dir: &Path, name: &str, lighting: &str) -> PathBuf {
    tiny_character(dir, 12);
    let text = format!(
        "[source]\nbvh = \"character.bvh\"\ntrain = [\"0..8\"]\ntest = [\"8..12\"]\n\
         [effects]\nrays = 8\n{lighting}"
    );
    let file = dir.join(name);
    std::fs::write(&file, text).unwrap();
    file
}

/// A directional light of unit irradiance, the lighting of scenes whose lighting is not the
/// point.
const LIGHT: &str =
    "[[light]]\nkind = \"directional\"\ndirection = [0, 1, 0]\nirradiance = [1, 1, 1]\n";

fn s(path: &Path) -> &str {
    path.to_str().unwrap()
}

/// Every file under `dir` with its bytes, sorted by path.
fn snapshot(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut files = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else {
                files.push((path.clone(), std::fs::read(&path).unwrap()));
            }
        }
    }
    files.sort();
    files
}

/// Refuses `args` (see [`refuse`]) and asserts nothing under `dir` changed.
fn refuse_untouched(dir: &Path, args: &[&str], fragments: &[&str]) -> String {
    let before = snapshot(dir);
    let line = refuse(args, fragments);
    assert_eq!(before, snapshot(dir), "{args:?} changed its inputs");
    line
}

/// `aprt report DIR/report.md --out DIR` once overwrote the scene it was reading: the guard
/// compared the directory with the inputs, not the files written into it. Also a directory
/// that does not exist yet but would hold the scene once created (`DIR/new/..`), and an output
/// directory inside an input directory.
#[test]
fn a_file_written_into_an_output_directory_is_never_an_input() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let file = scene(d, "report.md", LIGHT);
    for out in [d.to_path_buf(), d.join("new/..")] {
        refuse_untouched(
            d,
            &["report", s(&file), "--out", s(&out)],
            &[
                "--out",
                "writes",
                "report.md",
                "the scene file",
                "would destroy the input",
            ],
        );
    }
    refuse_untouched(
        d,
        &["results", "--assets", s(d), "--out", s(&d.join("docs"))],
        &["--out", "inside the assets directory"],
    );
}

/// A float32 `.npy` of `shape` with `values` and `header` edited by `edit` (which keeps its
/// length, so the length field holds), written at `path`.
fn npy(path: &Path, values: &[f32], edit: (&str, &str)) {
    let header = format!(
        "{{'descr': '<f4', 'fortran_order': False, 'shape': ({},), }}",
        values.len()
    );
    assert!(header.contains(edit.0), "{}", edit.0);
    let header = header.replacen(edit.0, &format!("{:<w$}", edit.1, w = edit.0.len()), 1);
    let padded = format!("{header:<w$}\n", w = 64 - 10 - 1);
    let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
    bytes.extend_from_slice(&(padded.len() as u16).to_le_bytes());
    bytes.extend_from_slice(padded.as_bytes());
    values
        .iter()
        .for_each(|v| bytes.extend_from_slice(&v.to_le_bytes()));
    std::fs::write(path, bytes).unwrap();
}

/// `shlm eval --against`: a Fortran-order or big-endian header once passed a substring search
/// and was read scrambled, a NaN in the truth printed "NaN%", and `--against` naming the
/// `--npy` about to be written compared the output with itself ("0.00 %"). Each is refused
/// before the light maps are read (the light-map file here is not even one).
#[test]
fn a_truth_array_that_is_not_plain_finite_float32_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let bvh = tiny_character(d, 4);
    let maps = d.join("maps.shlm");
    std::fs::write(&maps, "not read").unwrap();
    let truth = d.join("truth.npy");
    let out = d.join("out.npy");
    let eval = |against: &Path, npy: &Path, fragments: &[&str]| {
        refuse_untouched(
            d,
            &[
                "shlm",
                "eval",
                s(&maps),
                "--npy",
                s(npy),
                "--against",
                s(against),
                "--bvh",
                &bvh,
            ],
            fragments,
        );
    };
    for (edit, what) in [
        (
            ("False", "True"),
            "'fortran_order' is True: only C-order arrays are read",
        ),
        (
            ("'<f4'", "'>f4'"),
            "'descr' is '>f4': only '<f4' (little-endian float32)",
        ),
        (("'descr'", "'dtype'"), "unknown key 'dtype'"),
    ] {
        npy(&truth, &[1.0, 2.0], edit);
        eval(&truth, &out, &["--against", "truth.npy", "header", what]);
    }
    npy(&truth, &[1.0, f32::NAN, 3.0], ("", ""));
    eval(
        &truth,
        &out,
        &[
            "--against",
            "truth.npy",
            "value 1 (index [1]) is NaN",
            "finite",
        ],
    );
    let fresh = d.join("fresh.npy");
    eval(
        &fresh,
        &d.join("x/../fresh.npy"),
        &["--npy", "that is --against", "fresh.npy"],
    );
    assert!(!out.exists() && !fresh.exists());
}

/// Runs `aprt train --scene` on a scene ending with `lighting` and asserts it is refused with
/// `fragments`, before any model is written.
fn train_refused(lighting: &str, fragments: &[&str]) {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let file = scene(d, "scene.toml", lighting);
    let model = d.join("m.aprt");
    let mut expect = vec!["scene.toml"];
    expect.extend_from_slice(fragments);
    refuse_untouched(d, &["train", "--scene", s(&file), "-o", s(&model)], &expect);
    assert!(!model.exists());
}

/// Lighting finite as the TOML's f64 but infinite as the f32 it is computed in, and an
/// error target that becomes infinity, are refused naming the key; so is a light whose
/// irradiance is finite but whose grey levels are not (the order once chosen on `null`s).
#[test]
fn values_beyond_f32_are_refused_naming_the_key() {
    train_refused(
        "[environment]\nsh = [[1e300, 1, 1]]\n",
        &["[environment] sh", "`sh[0]` holds 1e300", "finite f32"],
    );
    train_refused(
        &format!("error_target = 1e300\n{LIGHT}"),
        &[
            "[effects] error_target",
            "1e300",
            "positive number of grey levels",
        ],
    );
    train_refused(
        "[[light]]\nkind = \"sphere\"\nposition = [0, 1, 0]\nradius = 0.1\nradiance = [1, 1e300, 1]\n",
        &["light 1 (sphere)", "`radiance` holds 1e300", "finite f32"],
    );
    train_refused(
        "[[light]]\nkind = \"directional\"\ndirection = [0, 1, 0]\nirradiance = [3e38, 3e38, 3e38]\n",
        &["lighting:", "bind-pose vertex", "too bright for f32"],
    );
    let dir = tempfile::tempdir().unwrap();
    let lights = dir.path().join("lights.toml");
    std::fs::write(
        &lights,
        "[[light]]\nkind = \"directional\"\ndirection = [0, 1, 0]\nirradiance = [3e38, 3e38, 3e38]\n",
    )
    .unwrap();
    refuse_untouched(
        dir.path(),
        &[
            "light",
            "irradiance",
            s(&lights),
            "--at",
            "0,0,0",
            "--normal",
            "0,1,0",
            "--json",
        ],
        &[
            "lights.toml",
            "grey levels",
            "beyond f32",
            "scale the lights down",
        ],
    );
}

/// A negative band-0 environment and `light = []` are refused naming the key.
#[test]
fn a_negative_environment_and_an_empty_light_list_are_refused() {
    train_refused(
        "[environment]\nsh = [[-1, 0.5, 0.5]]\n",
        &[
            "[environment] sh",
            "`sh[0]` (band 0) holds -1",
            "must not be negative",
        ],
    );
    let dir = tempfile::tempdir().unwrap();
    // `light` is a top-level key, so it comes before the tables.
    let empty = dir.path().join("empty.toml");
    let text = std::fs::read_to_string(scene(dir.path(), "x.toml", LIGHT)).unwrap();
    let text = text.replace(LIGHT, "[environment]\nsh = [[1, 1, 1]]\n");
    std::fs::write(&empty, format!("light = []\n{text}")).unwrap();
    let model = dir.path().join("m.aprt");
    refuse_untouched(
        dir.path(),
        &["train", "--scene", s(&empty), "-o", s(&model)],
        &["empty.toml: light:", "`light = []` lists no lights"],
    );
    let lights = dir.path().join("lights.toml");
    std::fs::write(&lights, "light = []\n").unwrap();
    refuse_untouched(
        dir.path(),
        &[
            "light",
            "irradiance",
            s(&lights),
            "--at",
            "0,0,0",
            "--normal",
            "0,1,0",
        ],
        &["lights.toml", "`light = []` lists no lights"],
    );
}

/// A 2x1 Radiance file of texels `rgbe` (flat, uncompressed: rows narrower than 8 are) with
/// `header` (lines, each ending in a newline) after FORMAT.
fn hdr(path: &Path, header: &str, rgbe: [u8; 4]) {
    let mut bytes =
        format!("#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n{header}\n-Y 1 +X 2\n").into_bytes();
    bytes.extend_from_slice(&rgbe);
    bytes.extend_from_slice(&rgbe);
    std::fs::write(path, bytes).unwrap();
}

/// Band 0 of `aprt light env FILE --order 1 --json`.
fn band0(file: &Path) -> f64 {
    let out = run::succeed(&["light", "env", s(file), "--order", "1", "--json"]);
    let json: serde_json::Value = serde_json::from_slice(&out).unwrap();
    json["coefficients"][0][0].as_f64().unwrap()
}

/// Radiance's `EXPOSURE=` is honoured (radiance is the stored value divided by it), a
/// non-positive one is refused, and texels whose projection overflows f32 are refused naming
/// the file and the brightest texel.
#[test]
fn radiance_exposure_is_honoured_and_overflow_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let one = [128, 128, 128, 129]; // 1.0 in RGBE
    let (plain, exposed) = (d.join("plain.hdr"), d.join("exposed.hdr"));
    hdr(&plain, "", one);
    hdr(&exposed, "EXPOSURE=2\nEXPOSURE=2\n", one);
    let (a, b) = (band0(&plain), band0(&exposed));
    assert!((a - 4.0 * b).abs() < 1e-5 * a, "{a} vs {b}");
    let zero = d.join("zero.hdr");
    hdr(&zero, "EXPOSURE=0\n", one);
    refuse_untouched(
        d,
        &["light", "env", s(&zero), "--order", "1"],
        &["zero.hdr", "EXPOSURE is 0", "positive"],
    );
    let bright = d.join("bright.hdr");
    hdr(&bright, "", [255, 255, 255, 255]);
    refuse_untouched(
        d,
        &["light", "env", s(&bright), "--order", "1"],
        &[
            "bright.hdr",
            "SH coefficient 0",
            "beyond f32",
            "brightest texel (0, 0)",
        ],
    );
}

/// OpenEXR texels of 3.4e38 are finite in f32, but the projection's sums over a row of them
/// are not: refused naming the file, the coefficient and a brightest texel; an infinite texel
/// is refused by position before any sum.
#[test]
fn exr_texels_that_overflow_f32_are_refused() {
    use image::{ImageEncoder, codecs::openexr::OpenExrEncoder};
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let exr = |name: &str, texel: f32| {
        let mut texels = vec![1.0f32; 4 * 2 * 3];
        texels[3 * 4..].fill(texel);
        let path = d.join(name);
        let file = std::io::BufWriter::new(std::fs::File::create(&path).unwrap());
        OpenExrEncoder::new(file)
            .write_image(
                &native_bytes(&texels),
                4,
                2,
                image::ExtendedColorType::Rgb32F,
            )
            .unwrap();
        path
    };
    let bright = exr("bright.exr", 3.4e38);
    refuse_untouched(
        d,
        &["light", "env", s(&bright), "--order", "1"],
        &[
            "bright.exr",
            "SH coefficient 0",
            "beyond f32",
            "brightest texel (",
        ],
    );
    let infinite = exr("infinite.exr", f32::INFINITY);
    refuse_untouched(
        d,
        &["light", "env", s(&infinite), "--order", "1"],
        &["infinite.exr", "(0, 1)"],
    );
}

/// The bytes of `values`, native order, as the encoder takes them.
fn native_bytes(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_ne_bytes()).collect()
}
