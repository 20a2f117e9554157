//! Character sources through the real `aprt` binary on the real assets in `shared/assets`:
//! a glTF clip and a BVH file trained, inspected, evaluated on their own and on other clips
//! (retargeted by joint name for BVH), checked against `simulate`'s ground truth, and the
//! mistakes a user makes with a source (unknown clip, missing file, bad rate, out-of-range
//! frames, another mannequin, `--angles` for a bone-frame model) refused with one clear line.
//!
//! Everything is small (order 2, 16 rays, a few frames) so the file runs in seconds.

use crate::common;
use crate::run;

use std::path::{Path, PathBuf};

use run::{aprt, read_npy, refuse, succeed};

/// Cheap bake settings shared by `train` and `simulate`, so the model and the truth agree.
const BAKE: &[&str] = &["--order", "2", "--rays", "16"];

fn s(path: &Path) -> &str {
    path.to_str().unwrap()
}

/// Shape of a finite .npy.
fn finite_npy(path: &Path) -> (Vec<usize>, Vec<f32>) {
    let (shape, data) = read_npy(path);
    if let Some(i) = data.iter().position(|x| !x.is_finite()) {
        panic!("{}: value {i} is {}", path.display(), data[i]);
    }
    (shape, data)
}

/// ‖a − b‖ / ‖b‖ over every value.
fn relative_error(a: &[f32], b: &[f32]) -> f64 {
    assert_eq!(a.len(), b.len());
    let (mut diff, mut norm) = (0.0f64, 0.0f64);
    for (&x, &y) in a.iter().zip(b) {
        diff += (f64::from(x) - f64::from(y)).powi(2);
        norm += f64::from(y).powi(2);
    }
    (diff / norm).sqrt()
}

fn inspect(model: &Path) -> serde_json::Value {
    serde_json::from_slice(&succeed(&["inspect", s(model), "--json"])).unwrap()
}

fn angle_names(info: &serde_json::Value) -> Vec<String> {
    info["angle_names"]
        .as_array()
        .expect("angle_names is an array")
        .iter()
        .map(|n| n.as_str().unwrap().to_owned())
        .collect()
}

fn asset(dir: &Path, kind: &str, file: &str) -> PathBuf {
    dir.join(kind).join(file)
}

/// `train` on the Fox's Survey at 5 fps: the default model and the full unregularised one;
/// `inspect` shows the pose-entry names and 1728 vertices; `eval` on Survey and on Walk gives
/// finite world-frame transfer of the right shape; against `simulate`, the full linear model
/// reproduces its training frames and the default one is close.
#[test]
fn gltf_clip_trains_evaluates_and_matches_simulate() {
    let Some(dir) = common::assets("gltf_clip_trains_evaluates_and_matches_simulate") else {
        return;
    };
    let work = tempfile::tempdir().unwrap();
    let fox = asset(&dir, "gltf", "Fox.gltf");
    let clip = |name: &'static str| ["--gltf", s(&fox), "--clip", name, "--fps", "5"];
    let model = work.path().join("fox.aprt");
    let full = work.path().join("fox-full.aprt");
    succeed(&[&["train"], &clip("Survey")[..], BAKE, &["-o", s(&model)]].concat());
    succeed(
        &[
            &["train"],
            &clip("Survey")[..],
            BAKE,
            &["--full", "--paper", "--alpha", "0", "-o", s(&full)],
        ]
        .concat(),
    );
    assert!(
        !work.path().join("fox.aprt.bake").exists(),
        "the checkpoint is removed once the model is written"
    );

    let info = inspect(&model);
    assert_eq!(info["vertices"], 1728);
    assert_eq!(info["order"], 2);
    let names = angle_names(&info);
    assert!(!names.is_empty());
    assert_eq!(names.len() as u64, info["joints"].as_u64().unwrap());
    assert!(
        names
            .iter()
            .all(|n| n.ends_with(".x") || n.ends_with(".y") || n.ends_with(".z")),
        "{names:?}"
    );
    assert_eq!(angle_names(&inspect(&full)), names);

    let truth = work.path().join("truth.npy");
    succeed(
        &[
            &["simulate"],
            &clip("Survey")[..],
            BAKE,
            &["--npy", s(&truth)],
        ]
        .concat(),
    );
    let (truth_shape, truth) = finite_npy(&truth);
    let frames = truth_shape[0];
    assert!((10..=40).contains(&frames), "{truth_shape:?}");
    assert_eq!(truth_shape, [frames, 1728, 4]);

    let mut predictions = Vec::new();
    for (name, m) in [("default", &model), ("full", &full)] {
        let npy = work.path().join(format!("{name}-survey.npy"));
        succeed(&[&["eval", s(m)], &clip("Survey")[..], &["--npy", s(&npy)]].concat());
        let (shape, data) = finite_npy(&npy);
        assert_eq!(shape, truth_shape, "{name}");
        predictions.push(relative_error(&data, &truth));
    }
    let [default_error, full_error] = predictions[..] else {
        unreachable!()
    };
    eprintln!("relative error on Survey: default {default_error:.2e}, full {full_error:.2e}");
    assert!(
        full_error < 1e-3,
        "the full unregularised model reproduces its training frames: {full_error}"
    );
    // A model predicting zeros scores 1.0; the regularised default measured 2.0e-2.
    assert!(
        default_error.is_finite() && default_error < 0.1,
        "{default_error}"
    );

    // Another clip of the same character: mapped onto the model by name.
    let walk = work.path().join("walk.npy");
    succeed(
        &[
            &["eval", s(&model)],
            &clip("Walk")[..],
            &["--npy", s(&walk)],
        ]
        .concat(),
    );
    let (shape, _) = finite_npy(&walk);
    assert_eq!(shape[1..], [1728, 4]);
    assert!(shape[0] > 1, "{shape:?}");

    // A bone-frame model needs the bones' rotations: --angles alone is refused, even with a
    // table of exactly the model's entries.
    let csv = work.path().join("angles.csv");
    let zeros = vec!["0"; names.len()].join(",");
    std::fs::write(&csv, format!("{}\n{zeros}\n", names.join(","))).unwrap();
    let out = work.path().join("angles.npy");
    refuse(
        &["eval", s(&model), "--angles", s(&csv), "--npy", s(&out)],
        &["fox.aprt", "bone frames", "--angles"],
    );
    assert!(!out.exists());

    // Another character does not fit the model.
    let simple = asset(&dir, "gltf", "RiggedSimple.gltf");
    refuse(
        &[
            "eval",
            s(&model),
            "--gltf",
            s(&simple),
            "--clip",
            "animation0",
            "--npy",
            s(&out),
        ],
        &["fox.aprt"],
    );
    assert!(!out.exists());
}

/// The smallest rig (96 vertices, 2 joints): its one clip trains, inspects and evaluates.
#[test]
fn small_gltf_rig_trains_and_evaluates() {
    let Some(dir) = common::assets("small_gltf_rig_trains_and_evaluates") else {
        return;
    };
    let work = tempfile::tempdir().unwrap();
    let simple = asset(&dir, "gltf", "RiggedSimple.gltf");
    let clip = ["--gltf", s(&simple), "--clip", "animation0", "--fps", "10"];
    let model = work.path().join("simple.aprt");
    succeed(&[&["train"], &clip[..], BAKE, &["-o", s(&model)]].concat());
    let info = inspect(&model);
    assert_eq!(info["vertices"], 96);
    let names = angle_names(&info);
    assert!(!names.is_empty() && names.len() <= 6, "{names:?}");

    let (npy, truth) = (work.path().join("p.npy"), work.path().join("t.npy"));
    succeed(&[&["eval", s(&model)], &clip[..], &["--npy", s(&npy)]].concat());
    succeed(&[&["simulate"], &clip[..], BAKE, &["--npy", s(&truth)]].concat());
    let (shape, predicted) = finite_npy(&npy);
    let (truth_shape, truth) = finite_npy(&truth);
    assert_eq!(shape, truth_shape);
    assert_eq!(shape[1..], [96, 4]);
    let error = relative_error(&predicted, &truth);
    // On its own training frames (zeros would score 1.0; measured 6.8e-3).
    assert!(error < 0.1, "{error}");
}

/// Mistakes with a glTF source: each refused with one line that says what is wrong.
#[test]
fn gltf_source_mistakes_are_refused_clearly() {
    let Some(dir) = common::assets("gltf_source_mistakes_are_refused_clearly") else {
        return;
    };
    let work = tempfile::tempdir().unwrap();
    let fox = asset(&dir, "gltf", "Fox.gltf");
    let out = work.path().join("out.npy");
    let model = work.path().join("m.aprt");
    let simulate = |source: &[&str], fragments: &[&str]| {
        refuse(
            &[&["simulate"], source, BAKE, &["--npy", s(&out)]].concat(),
            fragments,
        );
        assert!(!out.exists());
    };
    let train = |source: &[&str], fragments: &[&str]| {
        refuse(
            &[&["train"], source, BAKE, &["-o", s(&model)]].concat(),
            fragments,
        );
        assert!(!model.exists());
        assert!(!work.path().join("m.aprt.bake").exists());
    };

    let available = ["Fox.gltf", "Survey", "Walk", "Run"];
    train(
        &["--gltf", s(&fox), "--clip", "Dance"],
        &[&["\"Dance\""][..], &available].concat(),
    );
    simulate(&["--gltf", s(&fox), "--clip", "Dance"], &available);
    train(&["--gltf", s(&fox)], &["--clip", "Survey, Walk, Run"]);

    let missing = work.path().join("no-such-character.gltf");
    train(
        &["--gltf", s(&missing), "--clip", "Survey"],
        &["no-such-character.gltf"],
    );
    simulate(
        &["--gltf", s(&missing), "--clip", "Survey"],
        &["no-such-character.gltf"],
    );
    // A file next to the real ones: the message lists what the directory holds.
    let typo = fox.with_file_name("Foxy.gltf");
    train(
        &["--gltf", s(&typo), "--clip", "Survey"],
        &["Foxy.gltf: no such file", "CesiumMan.gltf", "Fox.gltf"],
    );

    // `--fps -5` with a space too: a negative rate reaches the check rather than being taken
    // for an unknown flag `-5`.
    for fps in [
        ["--fps", "0"],
        ["--fps", "-5"],
        ["--fps", "NaN"],
        ["--fps", "inf"],
    ] {
        train(
            &[&["--gltf", s(&fox), "--clip", "Survey"][..], &fps].concat(),
            &["frame rate", fps[1], "not a positive finite number"],
        );
    }
    // Not a number at all: clap's own message, naming the option.
    let out = aprt(&[
        "train",
        "--gltf",
        s(&fox),
        "--clip",
        "Survey",
        "--fps",
        "fast",
        "-o",
        s(&model),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        stderr.contains("'fast'") && stderr.contains("--fps"),
        "{stderr}"
    );
}

/// `train` on 40 frames of the CMU walk resampled to 30 fps (10 poses); `eval` on subject 01's
/// motion retargeted onto the walk's mannequin; the mistakes refused clearly.
#[test]
fn bvh_trains_retargets_and_refuses_mismatches() {
    let Some(dir) = common::assets("bvh_trains_retargets_and_refuses_mismatches") else {
        return;
    };
    let work = tempfile::tempdir().unwrap();
    let walk = asset(&dir, "bvh", "cmu_walk_delfem2.bvh");
    let subject = asset(&dir, "bvh", "cmu_01_01.bvh");
    let training = ["--bvh", s(&walk), "--frames", "0..40", "--fps", "30"];
    let model = work.path().join("walk.aprt");
    succeed(&[&["train"], &training[..], BAKE, &["-o", s(&model)]].concat());

    let truth = work.path().join("truth.npy");
    succeed(&[&["simulate"], &training[..], BAKE, &["--npy", s(&truth)]].concat());
    let (truth_shape, truth) = finite_npy(&truth);
    assert_eq!(truth_shape[0], 10, "frames 0, 4, ..., 36");
    let vertices = truth_shape[1];
    assert_eq!(truth_shape[2], 4);

    let info = inspect(&model);
    assert_eq!(info["vertices"].as_u64(), Some(vertices as u64));
    let names = angle_names(&info);
    assert!(names.iter().any(|n| n.starts_with("LeftLeg.")), "{names:?}");

    let own = work.path().join("own.npy");
    succeed(&[&["eval", s(&model)], &training[..], &["--npy", s(&own)]].concat());
    let (shape, predicted) = finite_npy(&own);
    assert_eq!(shape, truth_shape);
    let error = relative_error(&predicted, &truth);
    // On its own training frames (zeros would score 1.0; measured 2.3e-2).
    assert!(error < 0.1, "{error}");

    // Another subject's motion on the training mannequin: retargeted by joint name.
    let retargeted = work.path().join("retargeted.npy");
    let out = aprt(&[
        "eval",
        s(&model),
        "--bvh",
        s(&subject),
        "--mannequin",
        s(&walk),
        "--frames",
        "0..8",
        "--npy",
        s(&retargeted),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let (shape, _) = finite_npy(&retargeted);
    assert_eq!(shape, [8, vertices, 4]);

    // The other subject's own mannequin is another skeleton: the walk's hand joints, which
    // the model takes, are not in it.
    let refused = work.path().join("refused.npy");
    refuse(
        &[
            "eval",
            s(&model),
            "--bvh",
            s(&subject),
            "--frames",
            "0..8",
            "--npy",
            s(&refused),
        ],
        &["walk.aprt does not fit this character", "LeftHandIndex1.x"],
    );
    // The same skeleton without its hat is another mesh.
    let vertex_count = format!("walk.aprt has {vertices} vertices, the character has");
    refuse(
        &[
            "eval",
            s(&model),
            "--bvh",
            s(&walk),
            "--no-hat",
            "--frames",
            "0..4",
            "--npy",
            s(&refused),
        ],
        &[&vertex_count],
    );
    assert!(!refused.exists());

    // Frames past the end say how many there are.
    refuse(
        &[
            "simulate",
            "--bvh",
            s(&walk),
            "--frames",
            "300..400",
            "--npy",
            s(&refused),
        ],
        &["300..400", "344 frames"],
    );
    refuse(
        &[
            "eval",
            s(&model),
            "--bvh",
            s(&walk),
            "--frames",
            "300..400",
            "--npy",
            s(&refused),
        ],
        &["300..400", "344 frames"],
    );
    refuse(
        &[
            "eval",
            s(&model),
            "--bvh",
            s(&subject),
            "--mannequin",
            s(&walk),
            "--frames",
            "2700..2800",
            "--npy",
            s(&refused),
        ],
        &["2700..2800", "2752 frames"],
    );
    for fps in ["0", "-30"] {
        refuse(
            &[
                "simulate",
                "--bvh",
                s(&walk),
                "--fps",
                fps,
                "--npy",
                s(&refused),
            ],
            &["frame rate", fps, "not a positive finite number"],
        );
    }
    refuse(
        &[
            "simulate",
            "--bvh",
            s(&work.path().join("missing.bvh")),
            "--npy",
            s(&refused),
        ],
        &["missing.bvh"],
    );
    assert!(!refused.exists());
}

/// Training and simulating on several clips: repeated `--clip` simulates the clips' frames in
/// order (exactly the separate simulations, stacked); `train` on two of the Fox's clips with
/// the third held out (`--validate`) selects the model on it and says so; a BVH file's frame
/// ranges and another BVH file's motion serve the same way; the mistakes refused clearly.
/// Writes the first `frames` frames of the BVH file `from` to `to`.
fn first_frames(from: &Path, frames: usize, to: &Path) {
    let text = std::fs::read_to_string(from).unwrap();
    let (hierarchy, motion) = text.split_once("MOTION").unwrap();
    let mut lines = motion.lines().skip_while(|l| !l.starts_with("Frame Time"));
    let frame_time = lines.next().unwrap();
    let kept: Vec<&str> = lines.take(frames).collect();
    assert_eq!(kept.len(), frames, "{} is shorter", from.display());
    let motion = format!(
        "MOTION\nFrames: {frames}\n{frame_time}\n{}\n",
        kept.join("\n")
    );
    std::fs::write(to, hierarchy.to_owned() + &motion).unwrap();
}

#[test]
fn several_clips_train_and_validate() {
    let Some(dir) = common::assets("several_clips_train_and_validate") else {
        return;
    };
    let work = tempfile::tempdir().unwrap();
    let fox = asset(&dir, "gltf", "Fox.gltf");
    let fox_args = ["--gltf", s(&fox), "--fps", "2"];
    let simulate = |clips: &[&str], name: &str| {
        let npy = work.path().join(name);
        let named: Vec<&str> = clips.iter().flat_map(|c| ["--clip", *c]).collect();
        succeed(
            &[
                &["simulate"],
                &fox_args[..],
                &named,
                BAKE,
                &["--npy", s(&npy)],
            ]
            .concat(),
        );
        finite_npy(&npy)
    };
    let (walk_shape, walk) = simulate(&["Walk"], "walk.npy");
    let (run_shape, run) = simulate(&["Run"], "run.npy");
    let (both_shape, both) = simulate(&["Walk", "Run"], "both.npy");
    assert_eq!(both_shape[0], walk_shape[0] + run_shape[0]);
    assert_eq!(both, [walk, run].concat(), "the clips' frames, in order");

    let model = work.path().join("fox.aprt");
    let stderr = |out: std::process::Output| String::from_utf8_lossy(&out.stderr).into_owned();
    // The --validate clip and 8 validation poses choose, and the printout names both, what
    // each alone would choose, and how the choice was made.
    let clips = [
        "--clip",
        "Walk",
        "--clip",
        "Run",
        "--validate",
        "Survey",
        "--validation-poses",
        "8",
    ];
    let out = aprt(&[&["train"], &fox_args[..], &clips, BAKE, &["-o", s(&model)]].concat());
    let text = stderr(out);
    for expected in [
        "model selection (validation on \"Survey\" (",
        " poses) and \"validation poses\" (8 poses)): ",
        "\"Survey\" alone would choose",
        "\"validation poses\" alone would choose",
        "  candidates: ",
        "standard error",
        "(the rule: ",
    ] {
        assert!(text.contains(expected), "{expected}: {text}");
    }
    let poses = format!("{} poses", both_shape[0]);
    assert!(
        text.contains(&poses),
        "trained on Walk and Run only: {text}"
    );
    let eval = work.path().join("eval.npy");
    succeed(
        &[
            &["eval", s(&model)],
            &fox_args[..],
            &["--clip", "Survey", "--npy", s(&eval)],
        ]
        .concat(),
    );
    finite_npy(&eval);

    let walk_bvh = asset(&dir, "bvh", "cmu_walk_delfem2.bvh");
    // Another subject's first two seconds: at 10 fps, 20 validation poses, not the 229 of
    // the whole 23-second take, which made this test take 17 s.
    let subject = work.path().join("cmu_01_01_first_240.bvh");
    first_frames(&asset(&dir, "bvh", "cmu_01_01.bvh"), 240, &subject);
    let bvh = ["--bvh", s(&walk_bvh), "--fps", "10"];
    let ranges = ["--frames", "0..60", "--frames", "120..180"];
    let model = work.path().join("walk.aprt");
    for validate in ["200..260", s(&subject)] {
        let args = [
            &["train"],
            &bvh[..],
            &ranges,
            &["--validate", validate, "--validation-poses", "0"],
            BAKE,
        ];
        let out = aprt(&[&args.concat()[..], &["-o", s(&model)]].concat());
        let text = stderr(out);
        // One set, the clip (named by its file or range), and no validation poses.
        assert!(
            text.contains("model selection (validation on \"") && !text.contains(") and \""),
            "{validate}: {text}"
        );
        // 60 frames at 120 fps are 5 poses at 10 fps; two ranges, 10.
        assert!(text.contains(": 10 poses,"), "{validate}: {text}");
    }

    let refused = work.path().join("refused.aprt");
    let two_files = ["--bvh", s(&walk_bvh), "--bvh", s(&subject)];
    let three = ["--frames", "0..4", "--frames", "0..4", "--frames", "0..4"];
    let args = [
        &["train"],
        &two_files[..],
        &three,
        BAKE,
        &["-o", s(&refused)],
    ]
    .concat();
    refuse(&args, &["3 --frames ranges for 2 --bvh files"]);
    let args = [
        &[
            "train",
            "--builtin",
            "--clip",
            "wave",
            "--validate",
            "dance",
        ],
        BAKE,
    ]
    .concat();
    refuse(
        &[&args[..], &["-o", s(&refused)]].concat(),
        &["--validate", "dance", "reach"],
    );
    assert!(!refused.exists());
}

/// `aprt results --study` runs a subset of the studies for experiments; an unknown one is
/// refused before any bake, naming the flag and the studies there are.
#[test]
fn results_refuses_a_study_it_does_not_have() {
    let Some(dir) = common::assets("results_refuses_a_study_it_does_not_have") else {
        return;
    };
    let out = tempfile::tempdir().unwrap();
    let assets = dir.to_str().unwrap();
    let args = [
        "results", "--assets", assets, "--study", "fox", "--study", "cat",
    ];
    refuse(
        &[&args[..], &["--out", out.path().to_str().unwrap()]].concat(),
        &[
            "--study \"cat\"",
            "cesiumman, riggedfigure, riggedsimple, fox, cmu",
        ],
    );
    assert!(std::fs::read_dir(out.path()).unwrap().next().is_none());
}
