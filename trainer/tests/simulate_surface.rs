//! `aprt simulate --surface N` through the real binary: the truth at N points spread over the
//! surface, the points themselves (`--points`), and a bake farm's shards resuming to the bytes
//! of one run; the surface-only flags refused without `--surface`.

use std::path::Path;

use run::{read_npy, refuse, succeed, tiny_character};

use crate::run;

/// Frames of the clip.
const FRAMES: usize = 6;

/// Points asked for: not a multiple of the triangle count, so the largest-remainder rounding
/// is exercised.
const POINTS: usize = 301;

fn path(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// `aprt simulate --surface` of the small character in `dir`, cheaply baked, writing `npy`,
/// then `extra`.
fn simulate(npy: &Path, extra: &[&str]) -> Vec<String> {
    let bvh = tiny_character(npy.parent().unwrap(), FRAMES);
    let mut args: Vec<String> = [
        "simulate",
        "--bvh",
        &bvh,
        "--order",
        "2",
        "--rays",
        "16",
        "--surface",
        &POINTS.to_string(),
        "--npy",
        path(npy),
    ]
    .map(str::to_owned)
    .to_vec();
    args.extend(extra.iter().map(|s| s.to_string()));
    args
}

/// The .npy holds (frames, N, n²) finite values; the points file (N, 5) holds whole triangle
/// indices, barycentric coordinates in [0, 1] summing to one and area weights summing to one;
/// the checkpoint is gone once both are written.
#[test]
fn surface_points_bake_into_frames_by_points_and_the_points_are_written() {
    let dir = tempfile::tempdir().unwrap();
    let npy = dir.path().join("truth.npy");
    let points = dir.path().join("points.npy");
    succeed(&simulate(&npy, &["--points", path(&points)]));
    let (shape, data) = read_npy(&npy);
    assert_eq!(shape, [FRAMES, POINTS, 4]);
    assert!(data.iter().all(|x| x.is_finite()));
    // Band 0 of an unoccluded point is √π / 2 and occlusion only lowers it.
    let dc_max = std::f32::consts::PI.sqrt() / 2.0 + 1e-3;
    assert!(data.chunks_exact(4).all(|t| (0.0..=dc_max).contains(&t[0])));
    let (shape, table) = read_npy(&points);
    assert_eq!(shape, [POINTS, 5]);
    let mut total = 0.0f64;
    for row in table.chunks_exact(5) {
        assert_eq!(row[0], row[0].round(), "{row:?}");
        assert!(row[0] >= 0.0, "{row:?}");
        assert!(row[1..4].iter().all(|b| (0.0..=1.0).contains(b)), "{row:?}");
        assert!(
            (row[1..4].iter().sum::<f32>() - 1.0).abs() < 1e-5,
            "{row:?}"
        );
        assert!(row[4] > 0.0, "{row:?}");
        total += f64::from(row[4]);
    }
    assert!((total - 1.0).abs() < 1e-4, "weights sum to {total}");
    assert!(!dir.path().join("truth.npy.bake").exists());
    // The per-vertex bake of the same clip: the vertices, not the points.
    let vertices = dir.path().join("vertices.npy");
    let mut args = simulate(&vertices, &[]);
    let at = args.iter().position(|a| a == "--surface").unwrap();
    args.drain(at..at + 2);
    succeed(&args);
    let (shape, _) = read_npy(&vertices);
    assert_eq!((shape[0], shape[2]), (FRAMES, 4));
    assert_ne!(shape[1], POINTS);
}

/// Two shards into one checkpoint, then `--resume`: the same bytes as one unsharded run; the
/// shards write no output, the final run reads every frame back and removes the checkpoint.
#[test]
fn two_shards_and_a_resume_give_the_bytes_of_one_run() {
    let dir = tempfile::tempdir().unwrap();
    let reference = dir.path().join("reference.npy");
    let reference_points = dir.path().join("reference-points.npy");
    succeed(&simulate(
        &reference,
        &["--points", path(&reference_points)],
    ));
    let npy = dir.path().join("sharded.npy");
    let points = dir.path().join("points.npy");
    let ck = dir.path().join("ck");
    for shard in ["0/2", "1/2"] {
        let args = simulate(
            &npy,
            &[
                "--points",
                path(&points),
                "--checkpoint",
                path(&ck),
                "--shard",
                shard,
            ],
        );
        let out = run::aprt(&args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{args:?}:\n{err}");
        assert!(
            err.contains(&format!("shard {shard} baked 3 of its 3 frames")),
            "{err}"
        );
        assert!(!npy.exists() && !points.exists(), "a shard wrote an output");
    }
    let args = simulate(
        &npy,
        &[
            "--points",
            path(&points),
            "--checkpoint",
            path(&ck),
            "--resume",
        ],
    );
    let out = run::aprt(&args);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{args:?}:\n{err}");
    assert!(
        err.contains(&format!("resumed {FRAMES} of {FRAMES} poses")),
        "{err}"
    );
    assert!(std::fs::read(&npy).unwrap() == std::fs::read(&reference).unwrap());
    assert!(std::fs::read(&points).unwrap() == std::fs::read(&reference_points).unwrap());
    assert!(!ck.exists(), "checkpoint left after the .npy was written");
}

/// A checkpoint of other points (another N) is not resumed; without --resume an existing one
/// is refused rather than overwritten.
#[test]
fn a_checkpoint_of_other_points_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let npy = dir.path().join("truth.npy");
    let ck = dir.path().join("ck");
    succeed(&simulate(
        &npy,
        &["--checkpoint", path(&ck), "--shard", "0/2"],
    ));
    let mut other = simulate(&npy, &["--checkpoint", path(&ck), "--resume"]);
    let at = other.iter().position(|a| a == "--surface").unwrap();
    other[at + 1] = "300".to_owned();
    refuse(
        &other,
        &["baked points", "301 surface points", "300 surface points"],
    );
    refuse(
        &simulate(&npy, &["--checkpoint", path(&ck)]),
        &["pass --resume to continue it"],
    );
    assert!(!npy.exists());
}

/// The surface-only flags without --surface, and --surface 0, are refused naming the flag,
/// before anything is written.
#[test]
fn surface_flags_are_refused_without_surface() {
    let dir = tempfile::tempdir().unwrap();
    let npy = dir.path().join("truth.npy");
    let points = dir.path().join("points.npy");
    let mut without = simulate(&npy, &["--points", path(&points)]);
    let at = without.iter().position(|a| a == "--surface").unwrap();
    without.drain(at..at + 2);
    refuse(&without, &["--points applies to --surface only"]);
    let mut shard = without.clone();
    shard.truncate(shard.len() - 2);
    shard.extend(["--shard".to_owned(), "0/2".to_owned()]);
    refuse(&shard, &["--shard applies to --surface only"]);
    // Refused by the argument parser, whose error quotes the flag.
    let mut zero = simulate(&npy, &[]);
    zero[at + 1] = "0".to_owned();
    let out = run::aprt(&zero);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{err}");
    assert!(
        err.contains("invalid value '0' for '--surface <N>'") && err.contains("1 or more"),
        "{err}"
    );
    refuse(
        &simulate(&npy, &["--points", path(&npy)]),
        &["--npy", "--points", "are the same path"],
    );
    assert!(!npy.exists() && !points.exists());
}
