//! The real `aprt` binary, end to end: train from an OBJ sequence, inspect, evaluate, and the
//! same numbers through `aprt-core` from a slice and streamed with a tiny buffer; bad input
//! fails with a message naming the file and leaves no output behind.

use std::path::{Path, PathBuf};

use aprt_core::{Model, PoseWeights, StreamedModel};
use run::{aprt, read_npy, refuse, succeed, tiny_character};

use crate::run;

/// `aprt train` on an OBJ sequence and an angles file, with extra model options.
fn train(seq: &Path, angles: &Path, model: &Path, options: &[&str]) -> Vec<String> {
    let paths = [seq, angles, model].map(|p| p.to_str().unwrap());
    let args = [
        "train",
        "--obj-seq",
        paths[0],
        "--angles",
        paths[1],
        "-o",
        paths[2],
    ];
    args.iter().chain(options).map(|s| s.to_string()).collect()
}

/// A floor quad and a box "arm" hinged above it, rotated by `angle` about the y axis: the
/// arm's shadow on the floor moves with the angle.
fn scene_obj(angle: f64) -> String {
    let mut s = String::from("v -2 -2 0\nv 2 -2 0\nv 2 2 0\nv -2 2 0\n");
    let (sn, cs) = angle.sin_cos();
    for &(x, y, z) in &[
        (0.0, -0.3, -0.1),
        (1.5, -0.3, -0.1),
        (1.5, 0.3, -0.1),
        (0.0, 0.3, -0.1),
        (0.0, -0.3, 0.1),
        (1.5, -0.3, 0.1),
        (1.5, 0.3, 0.1),
        (0.0, 0.3, 0.1),
    ] {
        let (rx, rz) = (x * cs + z * sn, -x * sn + z * cs + 1.0);
        s.push_str(&format!("v {rx} {y} {rz}\n"));
    }
    s.push_str("f 1 2 3\nf 1 3 4\n");
    for f in [
        [5, 8, 7, 6],
        [9, 10, 11, 12],
        [5, 6, 10, 9],
        [6, 7, 11, 10],
        [7, 8, 12, 11],
        [8, 5, 9, 12],
    ] {
        s.push_str(&format!("f {} {} {} {}\n", f[0], f[1], f[2], f[3]));
    }
    s
}

fn setup(dir: &Path, poses: usize) -> (PathBuf, PathBuf) {
    let seq = dir.join("seq");
    std::fs::create_dir_all(&seq).unwrap();
    let mut csv = String::from("arm,unused\n");
    for i in 0..poses {
        let angle = -0.8 + 1.6 * i as f64 / (poses - 1) as f64;
        std::fs::write(seq.join(format!("pose_{i:03}.obj")), scene_obj(angle)).unwrap();
        csv.push_str(&format!("{angle},0.5\n"));
    }
    let angles = dir.join("angles.csv");
    std::fs::write(&angles, csv).unwrap();
    (seq, angles)
}

#[test]
fn train_inspect_eval_and_stream_agree() {
    let dir = tempfile::tempdir().unwrap();
    let (seq, angles) = setup(dir.path(), 9);
    let model_path = dir.path().join("m.aprt");
    succeed(&train(
        &seq,
        &angles,
        &model_path,
        &["--order", "3", "--rays", "64", "--coef-dims", "6"],
    ));

    let out = aprt(&["inspect", model_path.to_str().unwrap(), "--json"]);
    assert!(out.status.success());
    let info: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(info["order"], 3);
    assert_eq!(info["vertices"], 12);
    assert_eq!(info["joints"], 2);
    assert!(
        info["pose_dims"].as_u64().unwrap() <= 1,
        "the constant column carries no variance"
    );
    // The default features are the angles.
    assert_eq!(info["features"], 2);
    assert!(info["coef_dims"].as_u64().unwrap() <= 6);
    assert_eq!(
        info["bytes"].as_u64().unwrap() as usize,
        std::fs::metadata(&model_path).unwrap().len() as usize
    );

    let npy = dir.path().join("pred.npy");
    let out = aprt(&[
        "eval",
        model_path.to_str().unwrap(),
        "--angles",
        angles.to_str().unwrap(),
        "--npy",
        npy.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let (shape, predicted) = read_npy(&npy);
    assert_eq!(shape, [9, 12, 9]);

    // The core from a slice and streamed through a buffer of one block: the same bits.
    let blob = std::fs::read(&model_path).unwrap();
    let model = Model::parse(&blob).unwrap();
    // What inspect says an engine must provide is what the core asks for.
    let core = model.info();
    assert_eq!(info["scratch_bytes"], core.scratch_bytes());
    assert_eq!(info["pose_weights"], core.pose_weights_len());
    assert_eq!(info["lit_weights"], core.lit_weights_len());
    assert_eq!(
        info["bones"], 0,
        "an OBJ sequence trains a world-frame model"
    );
    let mut scratch = vec![0u8; model.info().scratch_bytes()];
    // A slice as a BlobSource copies on every read, as flash or a file would.
    let mut streamed = StreamedModel::open(&blob[..], &mut scratch).unwrap();
    let csv = std::fs::read_to_string(&angles).unwrap();
    for (p, line) in csv.lines().skip(1).enumerate() {
        let a: Vec<f32> = line
            .split(',')
            .map(|x| x.parse::<f64>().unwrap() as f32)
            .collect();
        let (mut pose, mut t_slice, mut t_stream) = (
            PoseWeights::new(),
            vec![0.0f32; 12 * 9],
            vec![0.0f32; 12 * 9],
        );
        model.set_pose(&a, &mut pose).unwrap();
        model.transfer(&pose, 0, &mut t_slice).unwrap();
        streamed.set_pose(&a, &mut pose).unwrap();
        streamed.transfer(&pose, 0, &mut t_stream).unwrap();
        assert_eq!(t_slice, t_stream);
        assert_eq!(&predicted[p * 108..(p + 1) * 108], &t_slice[..]);
    }

    // The floor under the arm is shadowed, and the fit follows the truth at a training pose.
    let truth = dir.path().join("truth.npy");
    let out = aprt(&[
        "transfer",
        seq.join("pose_004.obj").to_str().unwrap(),
        "--order",
        "3",
        "--rays",
        "64",
        "--npy",
        truth.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let (shape, truth) = read_npy(&truth);
    assert_eq!(shape, [12, 9]);
    let err: f32 = truth
        .iter()
        .zip(&predicted[4 * 108..5 * 108])
        .map(|(a, b)| (a - b).powi(2))
        .sum::<f32>()
        .sqrt();
    let norm: f32 = truth.iter().map(|a| a * a).sum::<f32>().sqrt();
    assert!(err < 0.2 * norm, "relative error {}", err / norm);
}

#[test]
fn bad_input_fails_clearly_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let (seq, angles) = setup(dir.path(), 4);
    let model_path = dir.path().join("m.aprt");
    let train = |angles: &Path| train(&seq, angles, &model_path, &["--order", "2", "--rays", "16"]);
    let check = |args: Vec<String>, needle: &str| {
        refuse(&args, &[needle]);
        assert!(!model_path.exists(), "partial output left behind");
    };
    let short = dir.path().join("short.csv");
    std::fs::write(&short, "0.1,0.5\n0.2,0.5\n").unwrap();
    check(train(&short), "2 rows of angles but");
    let bad_cell = dir.path().join("bad.csv");
    std::fs::write(&bad_cell, "0.1,0.5\n0.2,x\n0.3,0.5\n0.4,0.5\n").unwrap();
    check(
        train(&bad_cell),
        "bad.csv: row 2, column 2: 'x' is not a number",
    );
    std::fs::write(seq.join("pose_002.obj"), "v 0 0 0\nv 1 0 0\nf 1 2 7\n").unwrap();
    check(train(&angles), "pose_002.obj");
    let missing = dir.path().join("missing.aprt");
    refuse(&["inspect", missing.to_str().unwrap()], &["missing.aprt"]);
    std::fs::write(&model_path, b"APRTMDL\0garbage").unwrap();
    refuse(
        &["inspect", model_path.to_str().unwrap()],
        &["invalid model"],
    );
}

#[test]
fn builtin_creature_simulates_and_character_is_refused_without_builtin() {
    let dir = tempfile::tempdir().unwrap();
    let npy = dir.path().join("lash.npy");
    let npy_arg = npy.to_str().unwrap();
    succeed(&[
        "simulate",
        "--builtin",
        "--character",
        "creature",
        "--clip",
        "lash",
        "--rays",
        "16",
        "--order",
        "2",
        "--npy",
        npy_arg,
    ]);
    let (shape, data) = read_npy(&npy);
    assert_eq!(shape.len(), 3);
    assert_eq!((shape[0], shape[2]), (90, 4), "{shape:?}");
    assert!((5_000..=10_000).contains(&shape[1]), "{shape:?}");
    assert!(data.iter().all(|x| x.is_finite()));

    // The creature's clips are its own, and --character needs --builtin.
    let refused = dir.path().join("refused.npy");
    let refused_arg = refused.to_str().unwrap();
    let creature = ["simulate", "--builtin", "--character", "creature"];
    refuse(
        &[&creature[..], &["--clip", "wave", "--npy", refused_arg]].concat(),
        &["wave", "training, prowl, lash, crouch"],
    );
    refuse(
        &[
            "simulate",
            "--obj-seq",
            dir.path().join("seq").to_str().unwrap(),
            "--character",
            "creature",
            "--npy",
            refused_arg,
        ],
        &["--character", "--builtin only", "--obj-seq"],
    );
    assert!(!refused.exists());
}

#[test]
fn sample_poses_adds_that_many_training_poses_and_a_bound_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let model = |name: &str| dir.path().join(name).to_str().unwrap().to_owned();
    let base = [
        "train",
        "--builtin",
        "--character",
        "creature",
        "--clip",
        "lash",
        "--rays",
        "16",
        "--order",
        "2",
    ];
    let poses = |extra: &[&str], out: &str| -> usize {
        let o = model(out);
        let out = aprt(&[&base[..], extra, &["-o", &o]].concat());
        let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
        assert!(out.status.success(), "{stderr}");
        let line = stderr
            .lines()
            .find(|l| l.starts_with("wrote "))
            .unwrap_or_else(|| panic!("no `wrote` line in\n{stderr}"));
        line.split(": ")
            .nth(1)
            .unwrap()
            .split(' ')
            .next()
            .unwrap()
            .parse()
            .unwrap()
    };
    let without = poses(&[], "a.aprt");
    let with = poses(&["--sample-poses", "8"], "b.aprt");
    assert_eq!(with, without + 8);
    let refused = model("c.aprt");
    refuse(
        &[&base[..], &["--sample-poses", "10001", "-o", &refused]].concat(),
        &["--sample-poses 10001", "10000"],
    );
    assert!(!Path::new(&refused).exists());
}

/// `--validation-poses N` samples N poses from a character's training frames and bakes them
/// with the training frames, saying what they cost, but never trains on them: the model's
/// poses stay the clip's. 0 bakes exactly what was baked before they existed. An OBJ
/// sequence, which has no joints to sample, takes none by default and refuses a count naming
/// the flag; a count past one run's frames is refused.
#[test]
fn validation_poses_are_baked_but_never_trained_on_and_an_obj_sequence_refuses_them() {
    const FRAMES: usize = 8;
    let dir = tempfile::tempdir().unwrap();
    let bvh = tiny_character(dir.path(), FRAMES);
    let model = |name: &str| dir.path().join(name).to_str().unwrap().to_owned();
    let base = [
        "train",
        "--bvh",
        &bvh,
        "--order",
        "2",
        "--rays",
        "16",
        "--coef-dims",
        "4",
    ];
    let run = |extra: &[&str], out: &str| -> (String, String, Vec<u8>) {
        let o = model(out);
        let out = aprt(&[&base[..], extra, &["-o", &o]].concat());
        let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
        assert!(out.status.success(), "{extra:?}: {stderr}");
        let wrote = stderr
            .lines()
            .find(|l| l.starts_with("wrote "))
            .unwrap_or_else(|| panic!("no `wrote` line in\n{stderr}"))
            .to_owned();
        (stderr, wrote, std::fs::read(o).unwrap())
    };
    // The clip's frames and the rest pose, as before: nothing else baked, nothing said.
    let (none, wrote, bytes) = run(&["--validation-poses", "0"], "none.aprt");
    let baked = |n: usize| format!("baked {n} poses; fitting the model");
    assert!(none.contains(&baked(FRAMES + 1)), "{none}");
    assert!(!none.contains("validation pose"), "{none}");
    assert!(wrote.contains(&format!(": {FRAMES} poses,")), "{wrote}");
    assert_eq!(run(&["--validation-poses", "0"], "again.aprt").2, bytes);
    // Eight more baked, none trained on.
    let (eight, wrote, _) = run(&["--validation-poses", "8"], "eight.aprt");
    assert!(eight.contains(&baked(FRAMES + 8 + 1)), "{eight}");
    assert!(wrote.contains(&format!(": {FRAMES} poses,")), "{wrote}");
    assert!(
        wrote.contains(", 8 validation poses baked in ") && wrote.ends_with(" s"),
        "{wrote}"
    );
    // The default: 64 of them.
    let (default, wrote, _) = run(&[], "default.aprt");
    assert!(default.contains(&baked(FRAMES + 64 + 1)), "{default}");
    assert!(wrote.contains(", 64 validation poses baked in "), "{wrote}");
    let refused = model("refused.aprt");
    refuse(
        &[&base[..], &["--validation-poses", "10001", "-o", &refused]].concat(),
        &["--validation-poses 10001", "10000"],
    );
    // An OBJ sequence: none by default, a count refused before anything is baked.
    let (seq, angles) = setup(dir.path(), 5);
    let obj = dir.path().join("obj.aprt");
    let cheap = ["--order", "2", "--rays", "16"];
    refuse(
        &train(
            &seq,
            &angles,
            &obj,
            &[&cheap[..], &["--validation-poses", "4"]].concat(),
        ),
        &["--validation-poses 4", "--obj-seq"],
    );
    assert!(!obj.exists() && !Path::new(&refused).exists());
    assert!(!dir.path().join("obj.aprt.bake").exists());
    let out = aprt(&train(&seq, &angles, &obj, &cheap));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains(&baked(5)), "{stderr}");
    assert!(!stderr.contains("validation pose"), "{stderr}");
    succeed(&train(
        &seq,
        &angles,
        &dir.path().join("obj0.aprt"),
        &[&cheap[..], &["--validation-poses", "0"]].concat(),
    ));
}

/// An OBJ sequence of `poses` files of 7 vertices (a floor triangle under two moving ones)
/// and its angles file, in `dir`.
fn tiny_sequence(dir: &Path, poses: usize) -> (PathBuf, PathBuf) {
    let seq = dir.join(format!("seq{poses}"));
    std::fs::create_dir_all(&seq).unwrap();
    let mut csv = String::from("a,b\n");
    for i in 0..poses {
        let t = std::f64::consts::TAU * i as f64 / poses as f64;
        let (a, b) = (t.sin(), (3.0 * t).cos());
        let (c, s) = (0.5 * a.cos(), 0.5 * a.sin());
        let obj = format!(
            "v -2 -2 0\nv 2 -2 0\nv 0 2 0\nv {c} {s} 1\nv {} {} 1\nv {} 0.2 1.2\nv 0 0 0.8\n\
             f 1 2 3\nf 4 5 6\nf 4 6 7\nf 5 7 6\n",
            -c,
            -s,
            0.3 * b
        );
        std::fs::write(seq.join(format!("p{i:05}.obj")), obj).unwrap();
        csv.push_str(&format!("{a},{b}\n"));
    }
    let angles = dir.join(format!("angles{poses}.csv"));
    std::fs::write(&angles, csv).unwrap();
    (seq, angles)
}

/// What follows the bake grows linearly with the poses: 4× the poses of a 7-vertex sequence
/// adds at most [`BYTES_PER_POSE`] a pose to the peak memory. The model selection held the
/// poses' `p × p` output Gram (twice) and solved each held-out run's `p/10 × p/10` system at
/// every α: 4,000 poses took 79 s and 269 MB, 10,000 ran past 10 minutes after their bake.
/// Now 1,600 poses add about 4 MB to 400's (10,000: 31 s, 55 MB, the bake's checkpoint files
/// most of it); the quadratic code added 40 MB. Progress is said after the bake.
#[cfg(unix)]
#[test]
fn a_long_sequence_fits_in_memory_linear_in_its_poses() {
    const BYTES_PER_POSE: f64 = 8192.0;
    let dir = tempfile::tempdir().unwrap();
    let peak = |poses: usize| {
        let (seq, angles) = tiny_sequence(dir.path(), poses);
        let model = dir.path().join(format!("m{poses}.aprt"));
        let args = train(&seq, &angles, &model, &["--order", "2", "--rays", "4"]);
        let usage = run::measured(&args, std::time::Duration::from_secs(600));
        assert_eq!(usage.code, 0, "{args:?}:\n{}", usage.stderr);
        assert!(
            usage
                .stderr
                .contains(&format!("baked {poses} poses; fitting the model")),
            "no progress after the bake:\n{}",
            usage.stderr
        );
        usage.rss_mb
    };
    let (small, large) = (peak(400), peak(1600));
    let per_pose = (large - small) * 1024.0 * 1024.0 / 1200.0;
    assert!(
        per_pose < BYTES_PER_POSE,
        "400 poses peaked at {small:.1} MB, 1600 at {large:.1} MB: {per_pose:.0} bytes a pose"
    );
}
