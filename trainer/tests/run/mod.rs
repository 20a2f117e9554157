//! Running the real `aprt` binary from the integration tests.

// Each test binary includes this module and uses a different part of it.
#![allow(dead_code)]

use std::ffi::OsStr;
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
