//! The checked-in header, `include/aprt.h`, equals what the `cbindgen` command (version
//! [`CBINDGEN`], which `.ci/run` installs) generates from the sources, so the C ABI and its
//! header never drift. `APRT_BLESS=1` rewrites it. The command, not the `cbindgen` library:
//! the library and its `syn` with every feature, built at `opt-level = 3`, added a fifth to
//! the README's test build. Without the command the test says why it skips; with
//! `$APRT_REQUIRE_CBINDGEN` (set by `.ci/run`) it fails instead.

use std::path::Path;
use std::process::Command;

/// The cbindgen the header was generated with: another version may format it otherwise.
const CBINDGEN: &str = "0.29.4";

/// Why the header cannot be generated here, if it cannot.
fn missing_cbindgen() -> Option<String> {
    let out = Command::new("cbindgen").arg("--version").output();
    let version = match out {
        Ok(out) if out.status.success() => String::from_utf8_lossy(&out.stdout).into_owned(),
        _ => return Some("no `cbindgen` command".into()),
    };
    (!version.split_whitespace().any(|w| w == CBINDGEN)).then(|| {
        format!(
            "`cbindgen --version` says {:?}, not {CBINDGEN}",
            version.trim()
        )
    })
}

#[test]
fn header_matches_the_sources() {
    if let Some(why) = missing_cbindgen() {
        assert!(
            std::env::var_os("APRT_REQUIRE_CBINDGEN").is_none(),
            "the header check is required (APRT_REQUIRE_CBINDGEN) but {why}"
        );
        // Written to the stream itself: the harness hides a passing test's `eprintln!`.
        let line = format!(
            "skipped the header check: {why} (`cargo install cbindgen --version {CBINDGEN} \
             --locked`)\n"
        );
        std::io::Write::write_all(&mut std::io::stderr(), line.as_bytes()).unwrap();
        return;
    }
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = Command::new("cbindgen")
        .current_dir(dir)
        .args([
            "--config",
            "cbindgen.toml",
            "--crate",
            "aprt-capi",
            "--quiet",
        ])
        .output()
        .expect("run cbindgen");
    assert!(
        out.status.success(),
        "cbindgen failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let generated = String::from_utf8(out.stdout).expect("the header is UTF-8");
    let path = dir.join("include/aprt.h");
    if std::env::var_os("APRT_BLESS").is_some() {
        std::fs::write(&path, &generated).expect("write include/aprt.h");
        return;
    }
    let checked_in = std::fs::read_to_string(&path).unwrap_or_default();
    if checked_in != generated {
        let line = checked_in
            .lines()
            .zip(generated.lines())
            .position(|(a, b)| a != b)
            .unwrap_or(checked_in.lines().count().min(generated.lines().count()));
        panic!(
            "capi/include/aprt.h differs from what cbindgen generates (first at line {}); \
             regenerate it with `APRT_BLESS=1 cargo test --release -p aprt-capi --test \
             integration header::` and commit it",
            line + 1
        );
    }
}
