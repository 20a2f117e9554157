//! Bake farms through the real binary: `aprt train --shard I/N` bakes one share of the frames
//! into the checkpoint, and `--resume` over the shards' merged checkpoint writes the same
//! model bytes as one unsharded run, whether the shards shared one directory (one after the
//! other, or all at once) or baked apart and were copied together. `shlm bake` does the same
//! for light maps; a bad spec and a shard with other bake settings are refused.

use std::path::Path;
use std::process::Output;

use run::{aprt, refuse, succeed, tiny_character};

use crate::run;

/// Frames of the clip: with the validation poses and the rest pose (bone-frame models are
/// anchored at it) the checkpoint holds [`POSES`].
const FRAMES: usize = 8;

/// Validation poses `aprt train` samples (`--validation-poses`): sampled alike by every shard
/// and the final run, checkpointed like the clip's frames.
const VALIDATION: usize = 3;

/// Poses of the checkpoint: the frames, the validation poses and the rest pose.
const POSES: usize = FRAMES + VALIDATION + 1;

fn path(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The small character of [`tiny_character`], [`FRAMES`] frames long, in `dir`.
fn character(dir: &Path) -> String {
    tiny_character(dir, FRAMES)
}

/// `aprt train` of the character in `dir`, cheaply baked, writing `model`, then `extra`.
fn train(model: &Path, extra: &[&str]) -> Vec<String> {
    let bvh = character(model.parent().unwrap());
    let mut args: Vec<String> = [
        "train",
        "--bvh",
        &bvh,
        "--order",
        "2",
        "--rays",
        "16",
        "--coef-dims",
        "4",
        "--validation-poses",
        &VALIDATION.to_string(),
        "-o",
        path(model),
    ]
    .map(str::to_owned)
    .to_vec();
    args.extend(extra.iter().map(|s| s.to_string()));
    args
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Runs `args`, asserting success; returns stderr.
fn succeed_noting(args: &[String]) -> String {
    let out = aprt(args);
    assert!(out.status.success(), "{args:?} failed:\n{}", stderr(&out));
    stderr(&out)
}

/// The unsharded model's bytes.
fn reference(dir: &Path) -> Vec<u8> {
    let model = dir.join("reference.aprt");
    succeed(&train(&model, &[]));
    std::fs::read(model).unwrap()
}

/// `--resume` over the checkpoint `ck` loads every frame, bakes none, writes `reference`'s
/// bytes and removes the checkpoint.
fn resume_matches(dir: &Path, ck: &Path, reference: &[u8]) {
    let model = dir.join("merged.aprt");
    let err = succeed_noting(&train(&model, &["--checkpoint", path(ck), "--resume"]));
    assert!(
        err.contains(&format!("resumed {POSES} of {POSES} poses")),
        "{err}"
    );
    // Read back, not baked: this run spent nothing on them.
    assert!(
        err.contains(&format!("{VALIDATION} validation poses baked in 0.0 s")),
        "{err}"
    );
    assert!(
        std::fs::read(&model).unwrap() == reference,
        "the model of the merged shards differs from the unsharded one"
    );
    assert!(!ck.exists(), "checkpoint left after the model was written");
}

#[test]
fn three_shards_in_one_checkpoint_resume_to_the_bytes_of_one_run() {
    let dir = tempfile::tempdir().unwrap();
    let reference = reference(dir.path());
    let ck = dir.path().join("ck");
    let model = dir.path().join("model.aprt");
    assert_eq!(POSES % 3, 0, "each shard holds a third");
    let share = POSES / 3;
    for i in 0..3 {
        let shard = format!("{i}/3");
        let stored = (i + 1) * share;
        let err = succeed_noting(&train(
            &model,
            &["--checkpoint", path(&ck), "--shard", &shard],
        ));
        assert!(
            err.contains(&format!(
                "shard {shard} baked {share} of its {share} frames (0 were already there); {stored} of {POSES} frames are now in"
            )),
            "{err}"
        );
        assert!(!model.exists(), "a shard wrote the model");
    }
    // A shard run again (a retried array task) bakes nothing.
    let err = succeed_noting(&train(
        &model,
        &["--checkpoint", path(&ck), "--shard", "1/3"],
    ));
    assert!(
        err.contains(&format!(
            "shard 1/3 baked 0 of its {share} frames ({share} were already there)"
        )),
        "{err}"
    );
    resume_matches(dir.path(), &ck, &reference);
}

#[test]
fn shards_baked_apart_and_copied_together_resume_to_the_bytes_of_one_run() {
    let dir = tempfile::tempdir().unwrap();
    let reference = reference(dir.path());
    let ck = dir.path().join("ck");
    std::fs::create_dir(&ck).unwrap();
    let mut manifests = Vec::new();
    for i in 0..3 {
        let own = dir.path().join(format!("ck{i}"));
        let model = dir.path().join(format!("model{i}.aprt"));
        let shard = format!("{i}/3");
        succeed(&train(
            &model,
            &["--checkpoint", path(&own), "--shard", &shard],
        ));
        // As `cp ck0/* ck1/* ck2/* ck/` would.
        for entry in std::fs::read_dir(&own).unwrap() {
            let entry = entry.unwrap().path();
            std::fs::copy(&entry, ck.join(entry.file_name().unwrap())).unwrap();
        }
        manifests.push(std::fs::read(own.join("manifest.json")).unwrap());
    }
    assert!(manifests.iter().all(|m| *m == manifests[0]));
    resume_matches(dir.path(), &ck, &reference);
}

#[test]
fn shards_started_at_once_share_one_checkpoint() {
    let dir = tempfile::tempdir().unwrap();
    let reference = reference(dir.path());
    let ck = dir.path().join("ck");
    let model = dir.path().join("model.aprt");
    let runs: Vec<Output> = std::thread::scope(|scope| {
        let shards: Vec<_> = (0..3)
            .map(|i| {
                let args = train(
                    &model,
                    &["--checkpoint", path(&ck), "--shard", &format!("{i}/3")],
                );
                scope.spawn(move || aprt(&args))
            })
            .collect();
        shards.into_iter().map(|s| s.join().unwrap()).collect()
    });
    for out in &runs {
        assert!(out.status.success(), "{}", stderr(out));
    }
    resume_matches(dir.path(), &ck, &reference);
}

#[test]
fn bad_specs_and_other_settings_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("model.aprt");
    let ck = dir.path().join("ck");
    // Refused by the argument parser, before anything is read or written.
    for (spec, says) in [
        (
            "3/3",
            "the index must be below the count (0-based: shards 0/3 to 2/3)",
        ),
        ("0/0", "the count must be at least 1"),
        ("1-3", "expected INDEX/COUNT"),
    ] {
        let out = aprt(&train(&model, &["--shard", spec]));
        let err = stderr(&out);
        let quoted = format!("invalid value '{spec}' for '--shard <I/N>': {says}");
        assert!(!out.status.success() && err.contains(&quoted), "{err}");
    }
    assert!(!dir.path().join("model.aprt.bake").exists());
    succeed(&train(
        &model,
        &["--checkpoint", path(&ck), "--shard", "0/2"],
    ));
    let mut other = train(&model, &["--checkpoint", path(&ck), "--shard", "1/2"]);
    let rays = other.iter().position(|a| a == "--rays").unwrap();
    other[rays + 1] = "32".to_owned();
    refuse(&other, &["rays (checkpoint: 16, now: 32)"]);
    let pose_files = std::fs::read_dir(&ck).unwrap().count() - 1;
    assert_eq!(
        pose_files,
        POSES.div_ceil(2),
        "the refused shard touched the checkpoint"
    );
}

/// `shlm bake` of the character in `dir` at a small atlas, writing `output`, then `extra`.
fn shlm_bake(output: &Path, extra: &[&str]) -> Vec<String> {
    let bvh = character(output.parent().unwrap());
    let mut args: Vec<String> = [
        "shlm",
        "bake",
        "--bvh",
        &bvh,
        "--resolution",
        "32",
        "--order",
        "2",
        "--rays",
        "16",
        "-o",
        path(output),
    ]
    .map(str::to_owned)
    .to_vec();
    args.extend(extra.iter().map(|s| s.to_string()));
    args
}

#[test]
fn sharded_light_maps_resume_to_the_bytes_of_one_bake() {
    let dir = tempfile::tempdir().unwrap();
    let reference = dir.path().join("reference.shlm");
    succeed(&shlm_bake(&reference, &[]));
    let output = dir.path().join("maps.shlm");
    let ck = dir.path().join("ck");
    for shard in ["0/3", "1/3", "2/3"] {
        let err = succeed_noting(&shlm_bake(
            &output,
            &["--checkpoint", path(&ck), "--shard", shard],
        ));
        assert!(err.contains(&format!("shard {shard} baked")), "{err}");
        assert!(!output.exists(), "a shard wrote the sequence");
    }
    let err = succeed_noting(&shlm_bake(
        &output,
        &["--checkpoint", path(&ck), "--resume"],
    ));
    assert!(
        err.contains(&format!("resumed {FRAMES} of {FRAMES} poses")),
        "{err}"
    );
    assert!(std::fs::read(&output).unwrap() == std::fs::read(&reference).unwrap());
    assert!(!ck.exists());
}
