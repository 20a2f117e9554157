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
