//! Every malformed input in `fixtures/malformed/` through the real `aprt` binary: a non-zero
//! exit, no panic, exactly one message that names the file and the line, row or item and the
//! problem, and nothing left in the output directory (no output, no temporary, no checkpoint).
//!
//! The table is the place to add inputs: one row per fixture and command, with the fragments
//! the message must contain. `{fx}` is `fixtures/malformed`, `{out}` a fresh empty output
//! directory, `{model}` a model trained from `{fx}/ok`.

use run::{aprt, succeed};
use std::path::{Path, PathBuf};

use crate::run;

/// One malformed input, the command that reads it, and what its message must say.
struct Case {
    args: &'static [&'static str],
    expect: &'static [&'static str],
}

const fn case(args: &'static [&'static str], expect: &'static [&'static str]) -> Case {
    Case { args, expect }
}

/// Cheap bake settings: the malformed input must be refused before they matter.
const TRAIN: &[&str] = &["train", "--order", "1", "--rays", "4", "-o", "{out}/m.aprt"];

const CASES: &[Case] = &[
    // OBJ statements, read by `train` (one frame) and by `transfer`.
    case(
        &["--obj-seq", "{fx}/obj-nan", "--angles", "{fx}/ok/one.csv"],
        &["obj-nan/pose_0.obj:2", "\"nan\" is not finite"],
    ),
    case(
        &["--obj-seq", "{fx}/obj-inf", "--angles", "{fx}/ok/one.csv"],
        &["obj-inf/pose_0.obj:3", "\"inf\" is not finite"],
    ),
    case(
        &[
            "--obj-seq",
            "{fx}/obj-f32-overflow",
            "--angles",
            "{fx}/ok/one.csv",
        ],
        &["obj-f32-overflow/pose_0.obj:2", "\"1e39\" is not finite"],
    ),
    case(
        &[
            "--obj-seq",
            "{fx}/obj-missing-vertex",
            "--angles",
            "{fx}/ok/one.csv",
        ],
        &["obj-missing-vertex/pose_0.obj:5", "vertex 9", "only 3"],
    ),
    case(
        &[
            "--obj-seq",
            "{fx}/obj-missing-normal",
            "--angles",
            "{fx}/ok/one.csv",
        ],
        &["obj-missing-normal/pose_0.obj:5", "normal 2"],
    ),
    case(
        &[
            "--obj-seq",
            "{fx}/obj-zero-index",
            "--angles",
            "{fx}/ok/one.csv",
        ],
        &["obj-zero-index/pose_0.obj:4", "index 0"],
    ),
    case(
        &[
            "--obj-seq",
            "{fx}/obj-two-corners",
            "--angles",
            "{fx}/ok/one.csv",
        ],
        &[
            "obj-two-corners/pose_0.obj:4",
            "at least 3 corners, found 2",
        ],
    ),
    case(
        &[
            "--obj-seq",
            "{fx}/obj-bad-number",
            "--angles",
            "{fx}/ok/one.csv",
        ],
        &["obj-bad-number/pose_0.obj:2", "malformed number \"0,5\""],
    ),
    case(
        &["--obj-seq", "{fx}/obj-empty", "--angles", "{fx}/ok/one.csv"],
        &["obj-empty/pose_0.obj", "no vertices"],
    ),
    case(
        &[
            "--obj-seq",
            "{fx}/obj-no-faces",
            "--angles",
            "{fx}/ok/one.csv",
        ],
        &["obj-no-faces/pose_0.obj", "no faces"],
    ),
    case(
        &[
            "--obj-seq",
            "{fx}/obj-huge-extent",
            "--angles",
            "{fx}/ok/one.csv",
        ],
        &["obj-huge-extent/pose_0.obj", "extent", "f32"],
    ),
    case(
        &[
            "transfer",
            "{fx}/obj-nan/pose_0.obj",
            "--npy",
            "{out}/t.npy",
        ],
        &["obj-nan/pose_0.obj:2", "not finite"],
    ),
    case(
        &[
            "transfer",
            "{fx}/obj-huge-extent/pose_0.obj",
            "--npy",
            "{out}/t.npy",
        ],
        &["obj-huge-extent/pose_0.obj", "extent"],
    ),
    // Sequences.
    case(
        &[
            "--obj-seq",
            "{fx}/seq-vertex-count",
            "--angles",
            "{fx}/csv/two-rows.csv",
        ],
        &[
            "seq-vertex-count/pose_1.obj",
            "8 vertices",
            "pose_0.obj has 7",
        ],
    ),
    case(
        &[
            "--obj-seq",
            "{fx}/seq-no-obj",
            "--angles",
            "{fx}/ok/one.csv",
        ],
        &["seq-no-obj", "no .obj files"],
    ),
    case(
        &[
            "--obj-seq",
            "{fx}/missing-dir",
            "--angles",
            "{fx}/ok/one.csv",
        ],
        &["missing-dir", "cannot read directory"],
    ),
    // Angle tables.
    case(
        &[
            "--obj-seq",
            "{fx}/ok/seq",
            "--angles",
            "{fx}/csv/two-rows.csv",
        ],
        &["two-rows.csv has 2 rows", "3 OBJ files"],
    ),
    case(
        &[
            "--obj-seq",
            "{fx}/ok/seq",
            "--angles",
            "{fx}/csv/non-numeric.csv",
        ],
        &["non-numeric.csv: row 3, column 2", "'abc' is not a number"],
    ),
    case(
        &["--obj-seq", "{fx}/ok/seq", "--angles", "{fx}/csv/nan.csv"],
        &["nan.csv: row 4, column 1", "not finite"],
    ),
    case(
        &[
            "--obj-seq",
            "{fx}/ok/seq",
            "--angles",
            "{fx}/csv/overflow.csv",
        ],
        &["overflow.csv: row 3, column 2", "'1e400' is not finite"],
    ),
    // Regression: nalgebra's SVD panicked on the overflowing squares of 1e308.
    case(
        &["--obj-seq", "{fx}/ok/seq", "--angles", "{fx}/csv/huge.csv"],
        &["huge.csv: row 2, column 1", "'1e308' is beyond ±3.4e38"],
    ),
    case(
        &[
            "--obj-seq",
            "{fx}/ok/seq",
            "--angles",
            "{fx}/csv/ragged.csv",
        ],
        &["ragged.csv: row 3 has 1 values, row 2 has 2"],
    ),
    case(
        &[
            "--obj-seq",
            "{fx}/ok/seq",
            "--angles",
            "{fx}/csv/header-only.csv",
        ],
        &["header-only.csv", "no rows"],
    ),
    case(
        &[
            "eval",
            "{model}",
            "--angles",
            "{fx}/csv/three-columns.csv",
            "--npy",
            "{out}/p.npy",
        ],
        &["three-columns.csv: row 2 has 3 angles, the model takes 2"],
    ),
    case(
        &[
            "eval",
            "{model}",
            "--angles",
            "{fx}/csv/ragged.csv",
            "--npy",
            "{out}/p.npy",
        ],
        &["ragged.csv: row 3 has 1 angles"],
    ),
    // glTF characters.
    case(
        &["--gltf", "{fx}/gltf/no-skin.gltf", "--clip", "animation0"],
        &[
            "gltf/no-skin.gltf",
            "without a skin",
            "no node has both a mesh and a skin",
        ],
    ),
    // BVH motion.
    case(
        &["--bvh", "{fx}/bvh/channel-names.bvh"],
        &["bvh/channel-names.bvh:9", "\"Xposition\""],
    ),
    case(
        &["--bvh", "{fx}/bvh/frame-values.bvh"],
        &[
            "bvh/frame-values.bvh:20",
            "frame 1 has 8 values, expected 9",
        ],
    ),
    case(
        &["--bvh", "{fx}/bvh/non-numeric.bvh"],
        &["bvh/non-numeric.bvh:21", "\"abc\" is not a number"],
    ),
    case(
        &["--bvh", "{fx}/bvh/frame-count.bvh"],
        &[
            "bvh/frame-count.bvh:21",
            "Frames: says 5 but the file has 3 frame lines",
        ],
    ),
    case(
        &["--bvh", "{fx}/bvh/frame-count-extra.bvh"],
        &[
            "bvh/frame-count-extra.bvh:21",
            "Frames: says 2 but the file has 3 frame lines",
        ],
    ),
    case(
        &[
            "simulate",
            "--bvh",
            "{fx}/bvh/non-numeric.bvh",
            "--npy",
            "{out}/t.npy",
        ],
        &["bvh/non-numeric.bvh:21", "\"abc\" is not a number"],
    ),
    case(
        &[
            "simulate",
            "--bvh",
            "{fx}/bvh/ok.bvh",
            "--mannequin",
            "{fx}/bvh/frame-values.bvh",
            "--npy",
            "{out}/t.npy",
        ],
        &["bvh/frame-values.bvh:20", "frame 1 has 8 values"],
    ),
    case(
        &[
            "simulate",
            "--bvh",
            "{fx}/bvh/frame-count.bvh",
            "--mannequin",
            "{fx}/bvh/ok.bvh",
            "--npy",
            "{out}/t.npy",
        ],
        &["bvh/frame-count.bvh", "Frames: says 5"],
    ),
    // Models.
    case(
        &["inspect", "{fx}/not-a-model.aprt"],
        &["not-a-model.aprt", "invalid model"],
    ),
    case(
        &[
            "eval",
            "{fx}/not-a-model.aprt",
            "--angles",
            "{fx}/ok/angles.csv",
            "--npy",
            "{out}/p.npy",
        ],
        &["not-a-model.aprt", "invalid model"],
    ),
];

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../fixtures/malformed")
}

/// A case's full command line: rows starting with a flag are `train` runs.
fn command_line(case: &Case, out: &Path, model: &Path) -> Vec<String> {
    let fill = |s: &str| {
        s.replace("{fx}", fixtures().to_str().unwrap())
            .replace("{out}", out.to_str().unwrap())
            .replace("{model}", model.to_str().unwrap())
    };
    let train = case.args[0].starts_with("--");
    let prefix: &[&str] = if train { TRAIN } else { &[] };
    prefix.iter().chain(case.args).map(|s| fill(s)).collect()
}

#[test]
fn every_malformed_input_is_refused_clearly_and_leaves_nothing() {
    let work = tempfile::tempdir().unwrap();
    // The baseline trains: the failures below come from the malformations alone.
    let model = work.path().join("ok.aprt");
    let ok = Case {
        args: &["--obj-seq", "{fx}/ok/seq", "--angles", "{fx}/ok/angles.csv"],
        expect: &[],
    };
    let mut args = command_line(&ok, work.path(), &model);
    let o = args.iter().position(|a| a == "-o").unwrap();
    args[o + 1] = model.to_str().unwrap().to_owned();
    succeed(&args);

    let mut failures = Vec::new();
    for (i, case) in CASES.iter().enumerate() {
        let out_dir = work.path().join(format!("out-{i}"));
        std::fs::create_dir(&out_dir).unwrap();
        let args = command_line(case, &out_dir, &model);
        let out = aprt(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        let left: Vec<_> = std::fs::read_dir(&out_dir)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        let mut problems = Vec::new();
        if out.status.success() {
            problems.push("exit status 0".to_owned());
        }
        if stderr.contains("panicked") {
            problems.push("panicked".to_owned());
        }
        if !(stderr.starts_with("aprt: ") && stderr.lines().count() == 1) {
            problems.push("not exactly one `aprt: ` line".to_owned());
        }
        for fragment in case.expect {
            if !stderr.contains(fragment) {
                problems.push(format!("missing {fragment:?}"));
            }
        }
        if !left.is_empty() {
            problems.push(format!("left behind {left:?}"));
        }
        if !problems.is_empty() {
            failures.push(format!(
                "{:?}\n  {}\n  {}",
                &args,
                problems.join("; "),
                stderr.trim()
            ));
        }
    }
    assert!(failures.is_empty(), "\n{}", failures.join("\n"));
}

/// The BVH fixtures are `bvh/ok.bvh` with one thing broken: the baseline itself is accepted
/// (as its own mannequin and as the one another motion is retargeted onto).
#[test]
fn the_bvh_baseline_is_accepted() {
    let work = tempfile::tempdir().unwrap();
    let ok = fixtures().join("bvh/ok.bvh");
    let npy = work.path().join("t.npy");
    for mannequin in [&[][..], &["--mannequin", ok.to_str().unwrap()][..]] {
        let mut args: Vec<String> = ["simulate", "--order", "1", "--rays", "4", "--bvh"]
            .iter()
            .map(|s| (*s).to_owned())
            .collect();
        args.push(ok.to_str().unwrap().to_owned());
        args.extend(mannequin.iter().map(|s| (*s).to_owned()));
        args.extend(["--npy".to_owned(), npy.to_str().unwrap().to_owned()]);
        succeed(&args);
    }
}

/// `simulate` bakes an OBJ sequence without angles: it has no use for them.
#[test]
fn simulate_needs_no_angles() {
    let work = tempfile::tempdir().unwrap();
    let npy = work.path().join("t.npy");
    let seq = fixtures().join("ok/seq");
    let args: Vec<String> = ["simulate", "--order", "1", "--rays", "4", "--obj-seq"]
        .iter()
        .map(|s| (*s).to_owned())
        .chain([seq.to_str().unwrap().to_owned(), "--npy".to_owned()])
        .chain([npy.to_str().unwrap().to_owned()])
        .collect();
    succeed(&args);
    assert!(npy.exists());
}
