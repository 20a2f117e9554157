//! Nothing lost: `aprt train` killed mid-bake and rerun with `--resume` writes the same model
//! bytes as an uninterrupted run; a resume with other settings, or a rerun without `--resume`,
//! is refused and leaves the checkpoint intact.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

const POSES: usize = 16;

/// A 24 × 24-quad floor under a box "arm" rotated by `angle` about the y axis: 637 vertices,
/// enough work per pose (at 1024 rays) that the run can be killed between two poses.
fn scene_obj(angle: f64) -> String {
    let n = 24;
    let mut s = String::new();
    for i in 0..=n {
        for j in 0..=n {
            let (x, y) = (
                -2.0 + 4.0 * i as f64 / n as f64,
                -2.0 + 4.0 * j as f64 / n as f64,
            );
            s.push_str(&format!("v {x} {y} 0\n"));
        }
    }
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
    let at = |i: usize, j: usize| i * (n + 1) + j + 1;
    for i in 0..n {
        for j in 0..n {
            let [a, b, c, d] = [at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)];
            s.push_str(&format!("f {a} {b} {c} {d}\n"));
        }
    }
    let o = (n + 1) * (n + 1);
    for f in [
        [1, 4, 3, 2],
        [5, 6, 7, 8],
        [1, 2, 6, 5],
        [2, 3, 7, 6],
        [3, 4, 8, 7],
        [4, 1, 5, 8],
    ] {
        s.push_str(&format!(
            "f {} {} {} {}\n",
            f[0] + o,
            f[1] + o,
            f[2] + o,
            f[3] + o
        ));
    }
    s
}

fn setup(dir: &Path) -> (PathBuf, PathBuf) {
    let seq = dir.join("seq");
    std::fs::create_dir_all(&seq).unwrap();
    let mut csv = String::from("arm,wrist\n");
    for i in 0..POSES {
        let angle = -0.8 + 1.6 * i as f64 / (POSES - 1) as f64;
        std::fs::write(seq.join(format!("pose_{i:03}.obj")), scene_obj(angle)).unwrap();
        csv.push_str(&format!("{angle},{}\n", (3.0 * angle).sin()));
    }
    let angles = dir.join("angles.csv");
    std::fs::write(&angles, csv).unwrap();
    (seq, angles)
}

fn train_command(seq: &Path, angles: &Path, model: &Path, rays: &str, extra: &[&str]) -> Command {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_aprt"));
    cmd.arg("train")
        .arg("--obj-seq")
        .arg(seq)
        .arg("--angles")
        .arg(angles)
        .arg("-o")
        .arg(model)
        .args(["--order", "2", "--rays", rays, "--coef-dims", "4"])
        .args(extra);
    cmd
}

fn run(mut cmd: Command) -> Output {
    cmd.output().expect("run aprt")
}

fn pose_files(dir: &Path) -> usize {
    std::fs::read_dir(dir).map_or(0, |entries| {
        entries
            .filter(|e| {
                e.as_ref()
                    .is_ok_and(|e| e.file_name().to_string_lossy().starts_with("pose-"))
            })
            .count()
    })
}

#[test]
fn killed_bake_resumes_to_the_same_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let (seq, angles) = setup(dir.path());

    // Uninterrupted reference; its default checkpoint (MODEL.bake) is gone afterwards.
    let reference = dir.path().join("reference.aprt");
    let out = run(train_command(&seq, &angles, &reference, "1024", &[]));
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(!dir.path().join("reference.aprt.bake").exists());
    let reference = std::fs::read(&reference).unwrap();

    // Interrupted: killed once at least one pose is checkpointed.
    let model = dir.path().join("model.aprt");
    let ck = dir.path().join("ck");
    let ck_arg = ["--checkpoint", ck.to_str().unwrap()];
    let mut child = train_command(&seq, &angles, &model, "1024", &ck_arg)
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while pose_files(&ck) == 0 {
        assert!(
            child.try_wait().unwrap().is_none(),
            "finished before a pose was seen: make the scene bigger"
        );
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "no pose checkpointed"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let stored = pose_files(&ck);
    assert!(!model.exists(), "a killed run wrote the model");
    assert!(
        (1..POSES).contains(&stored),
        "{stored} poses stored: the kill came too late to test anything"
    );

    // Without --resume the checkpoint is neither overwritten nor ignored.
    let out = run(train_command(&seq, &angles, &model, "1024", &ck_arg));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("pass --resume"),
        "{err}"
    );
    // Other bake settings are refused, naming the setting.
    let resume: Vec<&str> = ck_arg.iter().copied().chain(["--resume"]).collect();
    let out = run(train_command(&seq, &angles, &model, "512", &resume));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("rays (checkpoint: 1024, now: 512)"),
        "{err}"
    );
    assert!(!model.exists());
    assert_eq!(
        pose_files(&ck),
        stored,
        "a refused resume touched the checkpoint"
    );

    // The resume finishes the bake: the same bytes, and the checkpoint is gone.
    let out = run(train_command(&seq, &angles, &model, "1024", &resume));
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // The stored poses were loaded, not baked again (equal bytes alone would not show it).
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains(&format!("resumed {stored} of {POSES} poses")),
        "{err}"
    );
    assert!(
        std::fs::read(&model).unwrap() == reference,
        "resumed model differs from the uninterrupted one"
    );
    assert!(!ck.exists(), "checkpoint left after success");
}
