//! Inputs that are not files, through the real `aprt` binary (issue 30): `/dev/zero` (read
//! until memory ran out) and a FIFO (blocked forever waiting for a writer) given as each kind
//! of input a command reads: a scene, a lights file, an environment map, a `.shlm` light map,
//! a model blob, a BVH clip, an angles CSV and an OBJ mesh. Each is refused at once, naming
//! the path, the kind of file and what is there instead; no command may hang.

use crate::run;

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Far longer than any refusal takes, far shorter than reading /dev/zero into 24 GB.
const DEADLINE: Duration = Duration::from_secs(20);

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../fixtures/malformed")
}

fn s(path: &Path) -> String {
    path.to_str().unwrap().to_owned()
}

/// Runs `aprt args`, killing it past [`DEADLINE`]; asserts it failed (not hung, not panicked)
/// with one `aprt:` line holding every fragment.
fn refused_in_time(args: &[String], fragments: &[&str]) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_aprt"))
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run aprt");
    let start = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if start.elapsed() > DEADLINE {
            child.kill().unwrap();
            child.wait().unwrap();
            panic!("{args:?} still running after {DEADLINE:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let mut stderr = String::new();
    std::io::Read::read_to_string(child.stderr.as_mut().unwrap(), &mut stderr).unwrap();
    assert!(!status.success(), "{args:?} succeeded:\n{stderr}");
    run::the_one_error(args, &stderr, fragments);
}

fn mkfifo(path: &Path) {
    let status = Command::new("mkfifo").arg(path).status().expect("mkfifo");
    assert!(status.success(), "mkfifo {}", path.display());
}

/// Each input kind: the file name it needs (its extension may choose the reader), the kind's
/// name in errors, and the command line reading it from `{}`.
fn cases(out: &Path) -> Vec<(&'static str, &'static str, Vec<String>)> {
    let io = fixtures().join("io");
    let npy = s(&out.join("out.npy"));
    let args = |list: &[&str]| list.iter().map(|a| a.to_string()).collect::<Vec<_>>();
    vec![
        (
            "scene.toml",
            "scene file",
            args(&["report", "{}", "--out", &s(&out.join("r"))]),
        ),
        (
            "lights.toml",
            "lights file",
            args(&[
                "light",
                "irradiance",
                "{}",
                "--at",
                "0,0,1",
                "--normal",
                "0,0,1",
            ]),
        ),
        (
            "sky.hdr",
            "environment map",
            args(&["light", "env", "{}", "--order", "3"]),
        ),
        (
            "sky.exr",
            "environment map",
            args(&["light", "env", "{}", "--order", "3"]),
        ),
        ("maps.shlm", "light map", args(&["shlm", "inspect", "{}"])),
        ("model.aprt", "model blob", args(&["inspect", "{}"])),
        (
            "motion.bvh",
            "BVH clip",
            args(&[
                "simulate", "--bvh", "{}", "--order", "1", "--rays", "4", "--npy", &npy,
            ]),
        ),
        (
            "angles.csv",
            "angles CSV",
            args(&[
                "train",
                "--obj-seq",
                &s(&io.join("bom/seq")),
                "--angles",
                "{}",
                "--order",
                "1",
                "--rays",
                "4",
                "-o",
                &s(&out.join("m.aprt")),
            ]),
        ),
        (
            "mesh.obj",
            "OBJ mesh",
            args(&["transfer", "{}", "--npy", &npy]),
        ),
    ]
}

#[test]
fn devices_and_fifos_are_refused_as_every_input_kind() {
    let dir = tempfile::tempdir().unwrap();
    for (name, kind, template) in cases(dir.path()) {
        let fifo_dir = dir.path().join("fifo");
        let zero_dir = dir.path().join("zero");
        std::fs::create_dir_all(&fifo_dir).unwrap();
        std::fs::create_dir_all(&zero_dir).unwrap();
        let fifo = fifo_dir.join(name);
        mkfifo(&fifo);
        // A symlink keeps the extension a reader may dispatch on.
        let zero = zero_dir.join(name);
        std::os::unix::fs::symlink("/dev/zero", &zero).unwrap();
        for (path, found) in [(&fifo, "a named pipe (FIFO)"), (&zero, "a device")] {
            let args: Vec<String> = template
                .iter()
                .map(|a| if a == "{}" { s(path) } else { a.clone() })
                .collect();
            let expected = format!("this {kind} is {found}, not a regular file");
            refused_in_time(&args, &[&s(path), &expected]);
        }
        std::fs::remove_file(&fifo).unwrap();
        std::fs::remove_file(&zero).unwrap();
    }
}
