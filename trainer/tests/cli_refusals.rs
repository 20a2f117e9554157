//! The CLI findings of issue 43, through the real `aprt` binary: a closed standard output ends
//! every command quietly, names from files reach the terminal escaped and cut to one short
//! line, flags that cannot apply are refused rather than ignored, and each refusal names the
//! file, flag or key at fault.

use std::path::Path;
use std::process::{Command, Stdio};

use aprt_core::SectionKind;
use aprt_core::format::{Header, PREAMBLE_LEN, crc32};

use crate::run::{self, refuse, succeed};

fn s(path: &Path) -> &str {
    path.to_str().unwrap()
}

/// The OBJ sequence of `fixtures/malformed/ok` (three poses) and its angles.
fn fixture_sequence() -> (String, String) {
    let ok = concat!(env!("CARGO_MANIFEST_DIR"), "/../fixtures/malformed/ok");
    (format!("{ok}/seq"), format!("{ok}/angles.csv"))
}

/// `blob` with the bytes of its `kind` section changed by `edit` (which may resize it when it
/// is the last section), its checksums made valid again (the section's, and the header's that
/// holds it).
fn edited(blob: &[u8], kind: SectionKind, edit: impl FnOnce(&mut Vec<u8>)) -> Vec<u8> {
    let header_len = u32::from_le_bytes(blob[12..16].try_into().unwrap()) as usize;
    let mut header: Header =
        postcard::from_bytes(&blob[PREAMBLE_LEN..PREAMBLE_LEN + header_len]).unwrap();
    let first = header.sections.iter().map(|e| e.offset).min().unwrap() as usize;
    let entry = header
        .sections
        .iter_mut()
        .find(|e| e.kind == kind.tag())
        .unwrap();
    let (at, len) = (entry.offset as usize, entry.len as usize);
    let mut section = blob[at..at + len].to_vec();
    edit(&mut section);
    assert!(
        section.len() == len || at + len == blob.len(),
        "only the last section may change its length"
    );
    (entry.len, entry.crc32) = (section.len() as u64, crc32(&section));
    let bytes = postcard::to_allocvec(&header).unwrap();
    assert!(
        PREAMBLE_LEN + bytes.len() <= first,
        "the header outgrew its room"
    );
    let mut out = blob[..at].to_vec();
    out[PREAMBLE_LEN..first].fill(0);
    out[PREAMBLE_LEN..PREAMBLE_LEN + bytes.len()].copy_from_slice(&bytes);
    out[12..16].copy_from_slice(&(bytes.len() as u32).to_le_bytes());
    out[16..20].copy_from_slice(&crc32(&bytes).to_le_bytes());
    out.extend(section);
    out.extend(&blob[at + len..]);
    out
}

/// Runs `aprt args` with its standard output a pipe nobody reads (closed before it starts) and
/// asserts it ends quietly: no panic, no backtrace, no error line, not exit code 101.
fn ends_quietly_without_a_reader(args: &[&str]) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_aprt"))
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !stderr.contains("panicked") && !stderr.contains("aprt:"),
        "{args:?}:\n{stderr}"
    );
    assert_ne!(out.status.code(), Some(101), "{args:?}:\n{stderr}");
}

/// A closed standard output (`aprt inspect m.aprt | head -c 0`) once panicked in `println!`
/// with exit code 101 and a backtrace; every command that prints ends quietly now.
#[test]
fn a_closed_standard_output_ends_every_command_quietly() {
    let dir = tempfile::tempdir().unwrap();
    let (seq, csv) = fixture_sequence();
    let shlm = dir.path().join("seq.shlm");
    succeed(&[
        "lightmap",
        "bake",
        "--obj-seq",
        &seq,
        "--angles",
        &csv,
        "--resolution",
        "16",
        "--order",
        "2",
        "--rays",
        "8",
        "-o",
        s(&shlm),
    ]);
    let model = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../fixtures/golden/v1-world.aprt"
    );
    let lights = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../fixtures/lights/three-lights.toml"
    );
    let mesh = format!("{seq}/pose_0.obj");
    let at = ["--at", "0,0,0", "--normal", "0,1,0"];
    let rig = [
        "irradiance-rig",
        &mesh,
        "--lights",
        lights,
        "--rig",
        "constant",
    ];
    for args in [
        &["inspect", model][..],
        &["inspect", model, "--json"],
        &["lightmap", "inspect", s(&shlm)],
        &["lightmap", "inspect", s(&shlm), "--json"],
        &rig,
        &[&rig[..], &["--json"]].concat(),
        &[&["light", "irradiance", lights], &at[..]].concat(),
        &[&["light", "irradiance", lights, "--json"], &at[..]].concat(),
    ] {
        ends_quietly_without_a_reader(args);
    }
}

/// A model's pose-entry names once reached the terminal raw through `inspect` and the error of
/// a clip that does not fit: an escape sequence recoloured it, a carriage return and a
/// right-to-left mark rewrote the line, and a 60,000-character name gave a 60 KB line. They are
/// escaped and cut now, as every reader's quotes are (a BVH joint name's too).
#[test]
fn a_blobs_names_reach_the_terminal_escaped_and_short() {
    let dir = tempfile::tempdir().unwrap();
    let golden = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../fixtures/golden/v1-world.aprt"
    );
    let hostile = [
        "\u{1b}[31mhip.x",
        "hip\ry",
        "\u{202e}hip.z",
        &"k".repeat(60_000),
    ];
    let blob = edited(
        &std::fs::read(golden).unwrap(),
        SectionKind::AngleNames,
        |names| {
            *names = hostile
                .iter()
                .flat_map(|n| [n.as_bytes(), b"\n"].concat())
                .collect();
        },
    );
    let model = dir.path().join("names.aprt");
    std::fs::write(&model, blob).unwrap();
    let clean = |what: &str, text: &str| {
        assert!(
            !text.contains(['\u{1b}', '\r', '\u{202e}']),
            "{what}: raw control characters in {text:?}"
        );
        assert!(text.lines().all(|l| l.len() < 400), "{what}: a long line");
    };
    let listed = String::from_utf8(succeed(&["inspect", s(&model)])).unwrap();
    clean("inspect", &listed);
    assert!(
        listed.contains("\\u{1b}[31mhip.x hip\\ry \\u{202e}hip.z kkk"),
        "{listed}"
    );
    let npy = dir.path().join("out.npy");
    let line = refuse(
        &[
            "eval",
            s(&model),
            "--builtin",
            "--clip",
            "wave",
            "--npy",
            s(&npy),
        ],
        &["names.aprt", "does not fit", "hip.x"],
    );
    clean("eval", &line);

    // A BVH joint name of 60,000 characters with an escape sequence, declared twice.
    let name = format!("\u{1b}[31m{}", "j".repeat(60_000));
    let joint = format!(
        "JOINT {name}\n{{\nOFFSET 0 1 0\nCHANNELS 3 Zrotation Xrotation Yrotation\nEnd Site\n{{\nOFFSET 0 1 0\n}}\n}}\n"
    );
    let bvh = dir.path().join("names.bvh");
    std::fs::write(
        &bvh,
        format!(
            "HIERARCHY\nROOT hips\n{{\nOFFSET 0 0 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n{joint}{joint}}}\nMOTION\nFrames: 1\nFrame Time: 0.1\n0 0 0 0 0 0 0 0 0\n"
        ),
    )
    .unwrap();
    let line = refuse(
        &["simulate", "--bvh", s(&bvh), "--npy", s(&npy)],
        &["names.bvh", "used twice", "\\u{1b}[31mjjj"],
    );
    clean("simulate", &line);
}

/// Flags that cannot apply were once ignored without a word: `--proxies on` wrote a model
/// without proxies for a world-frame model, an OBJ sequence (by flag or scene) or a light-map
/// model; `--confine` and `--report` without `--scene` trained as if absent (clap drops their
/// `requires` once a source flag is given); `eval` read nothing of an `--obj-seq` folder, even
/// one that does not exist. Each is refused now, naming the flags at fault.
#[test]
fn flags_that_cannot_apply_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (seq, csv) = fixture_sequence();
    let model = dir.path().join("m.aprt");
    let o = ["-o", s(&model)];
    let wave = ["--builtin", "--clip", "wave", "--rays", "8"];
    let on = ["--proxies", "on"];
    let scene = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../fixtures/scenes/obj-sequence.toml"
    );
    for (args, fragments) in [
        (
            [&["train", "--world-frame"], &wave[..], &on, &o].concat(),
            &["--proxies on", "--world-frame"][..],
        ),
        (
            [&["train", "--obj-seq", &seq, "--angles", &csv], &on[..], &o].concat(),
            &["--proxies on", "--obj-seq", "ok/seq", "no bones"],
        ),
        (
            [&["train", "--scene", scene], &on[..], &o].concat(),
            &["--proxies on", "obj-sequence.toml", "[source] obj_seq"],
        ),
        (
            [&["lightmap", "train"], &wave[..], &on, &o].concat(),
            &["--proxies on", "light-map"],
        ),
        (
            [&["train", "--confine"], &wave[..], &o].concat(),
            &["--confine", "--scene"],
        ),
        (
            [&["train", "--report", "r.json"], &wave[..], &o].concat(),
            &["--report", "--scene"],
        ),
    ] {
        refuse(&args, fragments);
    }
    let golden = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../fixtures/golden/v1-world.aprt"
    );
    let angles = dir.path().join("a.csv");
    std::fs::write(&angles, "0,0,0,0\n0.1,0.2,0.3,0.4\n").unwrap();
    let npy = dir.path().join("e.npy");
    let missing = dir.path().join("no-such-folder");
    refuse(
        &[
            "eval",
            golden,
            "--obj-seq",
            s(&missing),
            "--angles",
            s(&angles),
            "--npy",
            s(&npy),
        ],
        &["--obj-seq", "no-such-folder"],
    );
    assert!(!model.exists() && !npy.exists());
}

/// `lightmap bake -o` once wrote its `.shlm` into the OBJ sequence folder it read (only
/// `--checkpoint` was guarded), which broke the next `train` on that folder: an output inside
/// an input directory is refused now, whatever it is called.
#[test]
fn no_output_lands_inside_the_obj_sequence_it_reads() {
    let dir = tempfile::tempdir().unwrap();
    let (fixture, csv) = fixture_sequence();
    let seq = dir.path().join("seq");
    std::fs::create_dir(&seq).unwrap();
    for entry in std::fs::read_dir(&fixture).unwrap() {
        let path = entry.unwrap().path();
        std::fs::copy(&path, seq.join(path.file_name().unwrap())).unwrap();
    }
    let checkpoint = dir.path().join("bake");
    for name in ["maps.shlm", "next.obj"] {
        let out = seq.join(name);
        refuse(
            &[
                "lightmap",
                "bake",
                "--obj-seq",
                s(&seq),
                "--angles",
                &csv,
                "--resolution",
                "16",
                "--rays",
                "8",
                "--checkpoint",
                s(&checkpoint),
                "-o",
                s(&out),
            ],
            &["-o", name, "inside the OBJ sequence directory"],
        );
    }
    assert_eq!(std::fs::read_dir(&seq).unwrap().count(), 3);
}

/// Runs `aprt args`, asserts clap refuses it (exit code 2, no panic) naming every fragment.
fn refused_by_clap(args: &[&str], fragments: &[&str]) {
    let out = run::aprt(args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{args:?}:\n{stderr}");
    assert!(!stderr.contains("panicked"), "{args:?}:\n{stderr}");
    for fragment in fragments {
        assert!(
            stderr.contains(fragment),
            "{args:?}: {fragment:?} missing from\n{stderr}"
        );
    }
}

/// Refusals that once blamed the wrong thing name the file, flag or key at fault now:
/// `--resolution 0` blamed `--margin`, `--rays 0` named no flag, an angles CSV of 600 columns
/// named no file (`lightmap train`) or the OBJ folder (`train`), `irradiance-rig --obj-seq`
/// asked for a mesh or a character, and `report --stride 1000000` blamed the character
/// (`demo --stride` named no flag).
#[test]
fn refusals_name_what_is_at_fault() {
    let dir = tempfile::tempdir().unwrap();
    let (seq, csv) = fixture_sequence();
    let out = dir.path().join("out");
    let o = ["-o", s(&out)];
    let source = ["--obj-seq", seq.as_str(), "--angles", csv.as_str()];
    for cmd in [&["lightmap", "bake"][..], &["lightmap", "train"]] {
        let args = [cmd, &source[..], &["--resolution", "0"], &o].concat();
        refused_by_clap(&args, &["--resolution", "0", "texels"]);
    }
    let rays = ["--rays", "0"];
    for args in [
        [&["train"][..], &source, &rays, &o].concat(),
        [&["lightmap", "bake"][..], &source, &rays, &o].concat(),
        [&["simulate", "--npy", s(&out)][..], &source, &rays].concat(),
    ] {
        refused_by_clap(&args, &["--rays", "0"]);
    }

    let wide = dir.path().join("wide.csv");
    let row = |r: usize| {
        (0..600)
            .map(|c| format!("0.{r}{c}"))
            .collect::<Vec<_>>()
            .join(",")
    };
    std::fs::write(&wide, format!("{}\n{}\n{}\n", row(1), row(2), row(3))).unwrap();
    for cmd in [&["train"][..], &["lightmap", "train"]] {
        let args = [cmd, &["--obj-seq", &seq, "--angles", s(&wide)], &o].concat();
        refuse(&args, &["wide.csv", "600 angles", "512"]);
    }

    let lights = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../fixtures/lights/three-lights.toml"
    );
    let rig = ["irradiance-rig", "--lights", lights, "--rig", "constant"];
    refuse(
        &[&rig[..], &source].concat(),
        &["--obj-seq", "ok/seq", "one mesh"],
    );
    let mesh = format!("{seq}/pose_0.obj");
    refuse(
        &[&rig[..], &[&mesh, "--frame", "2"]].concat(),
        &["--frame 2"],
    );

    let scene = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../fixtures/scenes/builtin.toml"
    );
    let line = refuse(
        &["report", scene, "--stride", "1000000", "--out", s(&out)],
        &["--stride 1000000", "training frames"],
    );
    assert!(!line.contains("character"), "{line}");
    refuse(
        &["demo", "--stride", "1000000", "--out", s(&out)],
        &["--stride 1000000", "training frames"],
    );
}

/// A `.shlm` stripped of its light-map UVs (a version 4 file whose UV fields say none) reads
/// as one baked on the character's texture UVs; with a character that has none, the refusal
/// blamed the character alone ("has no texture coordinates"). It names the file now.
#[test]
fn a_sequence_without_its_uvs_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let (seq, csv) = fixture_sequence();
    let shlm = dir.path().join("seq.shlm");
    let source = ["--obj-seq", seq.as_str(), "--angles", csv.as_str()];
    let bake = [
        "lightmap",
        "bake",
        "--resolution",
        "16",
        "--rays",
        "8",
        "-o",
        s(&shlm),
    ];
    succeed(&[&bake[..], &source].concat());
    let bytes = std::fs::read(&shlm).unwrap();
    let word = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()) as usize;
    assert!(word(56) > 0, "the bake stores its generated UVs");
    // The UV section follows the mask, positions and shared sections, which start at 64.
    let uvs = 64 + word(40) + word(44) + word(48);
    let mut stripped = [&bytes[..uvs], &bytes[uvs + word(60)..bytes.len() - 4]].concat();
    stripped[56..64].fill(0);
    let crc = crc32(&stripped);
    stripped.extend(crc.to_le_bytes());
    let bare = dir.path().join("bare.shlm");
    std::fs::write(&bare, stripped).unwrap();
    let npy = dir.path().join("out.npy");
    let line = refuse(
        &[
            &["lightmap", "eval", s(&bare), "--npy", s(&npy)][..],
            &source,
        ]
        .concat(),
        &["bare.shlm", "stores no light-map UVs"],
    );
    assert!(!npy.exists(), "{line}");
}

/// A light-map model of the fixture sequence with a gradient irradiance rig, in `dir`.
fn rigged_light_map_model(dir: &Path) -> std::path::PathBuf {
    let (seq, csv) = fixture_sequence();
    let model = dir.join("rigged.aprt");
    succeed(&[
        "lightmap",
        "train",
        "--obj-seq",
        &seq,
        "--angles",
        &csv,
        "--resolution",
        "16",
        "--order",
        "2",
        "--rays",
        "8",
        "--rig",
        "gradient",
        "-o",
        s(&model),
    ]);
    model
}

/// A light-map model whose irradiance rig holds 3e38 (finite, so the core's checks pass) once
/// passed `inspect` and then failed `compose` naming neither the file nor the rig (huge
/// weights: "lighting coefficient 0 is NaN or infinite"), or composed shading off by 10³⁸ (a
/// huge centre). Both commands refuse it now, naming the file and the rig.
#[test]
fn a_rig_of_huge_values_is_refused_by_inspect_as_by_compose() {
    let dir = tempfile::tempdir().unwrap();
    let blob = std::fs::read(rigged_light_map_model(dir.path())).unwrap();
    let (seq, csv) = fixture_sequence();
    let lights = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../fixtures/lights/three-lights.toml"
    );
    let png = dir.path().join("out.png");
    // Every weight of the fit matrix (after the prelude, the error table and the samples),
    // and the centre's x.
    let weights = |rig: &mut Vec<u8>| {
        let word = |at: usize| u32::from_le_bytes(rig[at..at + 4].try_into().unwrap()) as usize;
        44 + 8 * word(12) + 12 * word(4)..rig.len()
    };
    for (name, fragment, range) in [
        ("weights.aprt", "SH vector 0", None),
        ("centre.aprt", "centre", Some(16..20)),
    ] {
        let huge = edited(&blob, SectionKind::IrradianceRig, |rig| {
            for at in range.clone().unwrap_or_else(|| weights(rig)).step_by(4) {
                rig[at..at + 4].copy_from_slice(&3e38f32.to_le_bytes());
            }
        });
        let model = dir.path().join(name);
        std::fs::write(&model, huge).unwrap();
        let expected = [name, "irradiance rig", fragment];
        refuse(&["inspect", s(&model)], &expected);
        refuse(&["inspect", s(&model), "--json"], &expected);
        refuse(
            &[
                "lightmap",
                "compose",
                s(&model),
                "--obj-seq",
                &seq,
                "--angles",
                &csv,
                "--lights",
                lights,
                "--rays",
                "8",
                "--png",
                s(&png),
            ],
            &expected,
        );
        assert!(!png.exists());
    }
}
