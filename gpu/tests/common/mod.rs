//! The device for a test, or why there is none.

use aprt_gpu::Gpu;

/// The adapter `Gpu::new` finds, or `None` after saying on stderr why `test` is skipped; with
/// `$APRT_REQUIRE_GPU` set (as `.ci/run` does) a missing adapter fails the test instead, so
/// CI cannot pass by skipping. The adapter's name is printed either way, so a run's log says
/// what it ran on.
pub fn gpu_or_skip(test: &str) -> Option<Gpu> {
    // Written to the stream itself, not through `eprintln!`, which the test harness captures
    // and hides for a passing test.
    let say = |line: String| std::io::Write::write_all(&mut std::io::stderr(), line.as_bytes());
    match Gpu::new() {
        Ok(gpu) => {
            say(format!("{test}: on {gpu}\n")).unwrap();
            Some(gpu)
        }
        Err(why) => {
            assert!(
                std::env::var_os("APRT_REQUIRE_GPU").is_none(),
                "{test}: GPU required (APRT_REQUIRE_GPU) but {why}"
            );
            say(format!(
                "skipping {test}: {why}; install mesa-vulkan-drivers for lavapipe\n"
            ))
            .unwrap();
            None
        }
    }
}
