//! Where the real third-party assets live, for the tests that read them.

use std::path::PathBuf;

/// `$APRT_ASSETS`, or `shared/assets` beside the repository. `None`, after printing a line
/// saying which test skipped and why, when they are not there; a panic instead when
/// `$APRT_REQUIRE_ASSETS` is set (as `.ci/run` does), so CI cannot pass by skipping.
pub fn assets(test: &str) -> Option<PathBuf> {
    let dir = std::env::var_os("APRT_ASSETS").map_or_else(
        || PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/assets"),
        PathBuf::from,
    );
    if dir.join("gltf").is_dir() && dir.join("bvh").is_dir() {
        Some(dir)
    } else if std::env::var_os("APRT_REQUIRE_ASSETS").is_some() {
        panic!("{test}: assets not found at {}", dir.display());
    } else {
        eprintln!(
            "skipped {test}: assets not found at {} (set APRT_ASSETS)",
            dir.display()
        );
        None
    }
}
