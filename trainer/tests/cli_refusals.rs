//! The CLI findings of issue 43, through the real `aprt` binary: a closed standard output ends
//! every command quietly, names from files reach the terminal escaped and cut to one short
//! line, flags that cannot apply are refused rather than ignored, and each refusal names the
//! file, flag or key at fault.

use std::path::Path;
use std::process::{Command, Stdio};

use aprt_core::SectionKind;
use aprt_core::format::{Header, PREAMBLE_LEN, crc32};

use crate::run::{refuse, succeed};

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
/// escaped and cut now, as every reader's quotes are.
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
}
