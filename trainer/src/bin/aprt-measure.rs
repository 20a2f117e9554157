//! `aprt-measure SECONDS PROGRAM [ARGS…]`: runs PROGRAM as this process's only child, kills
//! it past SECONDS, and prints one line on stdout,
//! `measured max_rss_kb=… cpu_s=… timed_out=… code=…`, from `getrusage(RUSAGE_CHILDREN)`.
//! The child's stdout is discarded and its stderr passed through.
//!
//! The hostile-input tests use it to read the peak memory and CPU time of one run of `aprt`.
//! `RUSAGE_CHILDREN` sums every child the caller has waited for, so the caller must have had
//! only this one; `wait4` would give one child's usage directly but needs `unsafe`, which the
//! workspace forbids.

#[cfg(unix)]
fn main() -> std::process::ExitCode {
    use nix::sys::resource::{UsageWho, getrusage};
    use std::process::{Command, ExitCode, Stdio};
    use std::time::{Duration, Instant};

    let args: Vec<String> = std::env::args().skip(1).collect();
    let (Some(timeout), Some(program)) = (args.first().and_then(|s| s.parse().ok()), args.get(1))
    else {
        eprintln!("usage: aprt-measure SECONDS PROGRAM [ARGS…]");
        return ExitCode::from(2);
    };
    let timeout = Duration::from_secs_f64(timeout);
    let mut child = match Command::new(program)
        .args(&args[2..])
        .stdout(Stdio::null())
        .spawn()
    {
        Ok(child) => child,
        Err(e) => {
            eprintln!("aprt-measure: cannot run {program}: {e}");
            return ExitCode::from(2);
        }
    };
    let start = Instant::now();
    let mut timed_out = false;
    let status = loop {
        match child.try_wait() {
            Ok(Some(status)) => break status,
            Ok(None) if !timed_out && start.elapsed() > timeout => {
                timed_out = true;
                let _ = child.kill();
            }
            Ok(None) => std::thread::sleep(Duration::from_millis(10)),
            Err(e) => {
                eprintln!("aprt-measure: waiting for {program}: {e}");
                return ExitCode::from(2);
            }
        }
    };
    let usage = getrusage(UsageWho::RUSAGE_CHILDREN).expect("getrusage(RUSAGE_CHILDREN)");
    let seconds = |t: nix::sys::time::TimeVal| t.tv_sec() as f64 + t.tv_usec() as f64 * 1e-6;
    println!(
        "measured max_rss_kb={} cpu_s={} timed_out={timed_out} code={}",
        usage.max_rss(),
        seconds(usage.user_time()) + seconds(usage.system_time()),
        status.code().unwrap_or(-1)
    );
    ExitCode::SUCCESS
}

#[cfg(not(unix))]
fn main() -> std::process::ExitCode {
    eprintln!("aprt-measure: needs getrusage, which only unix has");
    std::process::ExitCode::from(2)
}
