//! Running the real `aprt` binary from the integration tests.

// Each test binary includes this module and uses a different part of it.
#![allow(dead_code)]

use std::ffi::OsStr;
use std::path::Path;
use std::process::{Command, Output};

/// Runs `aprt` with `args`.
pub fn aprt<S: AsRef<OsStr>>(args: &[S]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_aprt"))
        .args(args)
        .output()
        .expect("run aprt")
}

/// Runs `aprt` and asserts success; returns its stdout.
pub fn succeed<S: AsRef<OsStr> + std::fmt::Debug>(args: &[S]) -> Vec<u8> {
    let out = aprt(args);
    assert!(
        out.status.success(),
        "{args:?} failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    out.stdout
}

/// Runs `aprt`, asserts it fails with exactly one `aprt: ` line and no panic, and that the
/// line contains every fragment; returns the line.
pub fn refuse<S: AsRef<OsStr> + std::fmt::Debug>(args: &[S], fragments: &[&str]) -> String {
    let out = aprt(args);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!out.status.success(), "{args:?} succeeded:\n{stderr}");
    the_one_error(args, &stderr, fragments)
}

/// Asserts that a failed run's `stderr` holds no panic and exactly one `aprt: ` line, holding
/// every fragment; returns the line.
pub fn the_one_error<S: std::fmt::Debug>(args: &[S], stderr: &str, fragments: &[&str]) -> String {
    assert!(!stderr.contains("panicked"), "{args:?} panicked:\n{stderr}");
    let errors: Vec<&str> = stderr.lines().filter(|l| l.starts_with("aprt: ")).collect();
    assert_eq!(
        errors.len(),
        1,
        "{args:?}: not one `aprt: ` line:\n{stderr}"
    );
    for fragment in fragments {
        assert!(
            errors[0].contains(fragment),
            "{args:?}: {fragment:?} missing from\n{stderr}"
        );
    }
    errors[0].to_owned()
}

/// A float32 .npy: its shape and data.
pub fn read_npy(path: &Path) -> (Vec<usize>, Vec<f32>) {
    let bytes = std::fs::read(path).unwrap();
    assert_eq!(&bytes[..6], b"\x93NUMPY");
    let header_len = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    let header = std::str::from_utf8(&bytes[10..10 + header_len]).unwrap();
    assert!(header.contains("'descr': '<f4'"), "{header}");
    let shape = header
        .split_once("'shape': (")
        .and_then(|(_, rest)| rest.split_once(')'))
        .unwrap_or_else(|| panic!("no shape in {header}"))
        .0
        .split(',')
        .filter(|d| !d.trim().is_empty())
        .map(|d| d.trim().parse().unwrap())
        .collect::<Vec<usize>>();
    let data: Vec<f32> = bytes[10 + header_len..]
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes(b.try_into().unwrap()))
        .collect();
    assert_eq!(data.len(), shape.iter().product::<usize>(), "{header}");
    (shape, data)
}

/// A small character, so that every test bakes in a second: a BVH clip of `frames` frames
/// of a four-joint skeleton (a spine and arm bending, a leg swinging), which `aprt` dresses
/// as a mannequin with UVs. Written into `dir` unless it is there (runs that may be reading
/// it must not see it rewritten); returns its path.
pub fn tiny_character(dir: &Path, frames: usize) -> String {
    let bvh = dir.join("character.bvh");
    if bvh.exists() {
        return bvh.to_str().unwrap().to_owned();
    }
    let mut text = String::from(
        "HIERARCHY\nROOT hips\n{\nOFFSET 0 0 0\nCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n",
    );
    let joint = |name: &str, offset: &str, end: &str| {
        format!(
            "JOINT {name}\n{{\nOFFSET {offset}\nCHANNELS 3 Zrotation Xrotation Yrotation\n{end}"
        )
    };
    text += &joint("spine", "0 10 0", "");
    text += &joint("arm", "0 10 0", "End Site\n{\nOFFSET 0 10 0\n}\n}\n}\n");
    text += &joint("leg", "5 -10 0", "End Site\n{\nOFFSET 0 -10 0\n}\n}\n}\n");
    text += &format!("MOTION\nFrames: {frames}\nFrame Time: 0.0333333\n");
    for f in 0..frames {
        let (a, b, c) = (10.0 * f as f64, 20.0 * (f as f64).sin(), -7.0 * f as f64);
        let channels = [
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
            0.3 * a,
            b,
            0.0,
            a,
            c,
            0.5 * b,
            c,
            0.0,
            b,
        ];
        let row: Vec<String> = channels.iter().map(f64::to_string).collect();
        text += &(row.join(" ") + "\n");
    }
    std::fs::write(&bvh, text).unwrap();
    bvh.to_str().unwrap().to_owned()
}

/// What one run of `aprt` used, as `aprt-measure` read it.
#[derive(Debug)]
pub struct Usage {
    /// Peak resident memory, in MB.
    pub rss_mb: f64,
    /// User plus system CPU time, all threads, in seconds.
    pub cpu_s: f64,
    /// Whether it ran past its time limit and was killed.
    pub timed_out: bool,
    pub code: i32,
    pub stderr: String,
}

/// Runs `aprt args` through `aprt-measure` (the only child of its own process, so that
/// `getrusage` counts it alone), killed past `timeout`; returns what it used.
pub fn measured(args: &[String], timeout: std::time::Duration) -> Usage {
    let out = Command::new(env!("CARGO_BIN_EXE_aprt-measure"))
        .arg(timeout.as_secs_f64().to_string())
        .arg(env!("CARGO_BIN_EXE_aprt"))
        .args(args)
        .output()
        .expect("run aprt-measure");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    let line = stdout
        .lines()
        .find_map(|l| l.strip_prefix("measured "))
        .unwrap_or_else(|| panic!("{args:?}: no measurement in\n{stdout}\n{stderr}"));
    let field = |name: &str| {
        line.split(' ')
            .find_map(|kv| kv.strip_prefix(name)?.strip_prefix('='))
            .unwrap_or_else(|| panic!("no {name} in {line}"))
    };
    Usage {
        rss_mb: field("max_rss_kb").parse::<f64>().unwrap() / 1024.0,
        cpu_s: field("cpu_s").parse().unwrap(),
        timed_out: field("timed_out") == "true",
        code: field("code").parse().unwrap(),
        stderr,
    }
}
