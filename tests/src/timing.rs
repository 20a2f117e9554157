//! The benchmarks' interleaved timing. Plain std, no crate of this workspace: the GPU crate's
//! bench (`gpu/benches/frame.rs`, its own workspace, which must not build the trainer)
//! includes this file by path, so its figures are timed as these benches' are.

/// Seconds per call of each of `steps`, timed in interleaved rounds: each round runs a batch
/// of every step in turn (batches sized from a first pass to about `budget / (rounds · steps)`),
/// so a ratio of two steps taken round by round cancels the machine's drift (clock, other
/// load). Returns, per step, its seconds per call in each round.
pub fn interleaved_seconds(
    budget: std::time::Duration,
    rounds: usize,
    steps: &mut [&mut dyn FnMut()],
) -> Vec<Vec<f64>> {
    let share = budget.as_secs_f64() / (rounds * steps.len()).max(1) as f64;
    let batches: Vec<u32> = steps
        .iter_mut()
        .map(|f| {
            f();
            let t = std::time::Instant::now();
            f();
            (share / t.elapsed().as_secs_f64().max(1e-9)).clamp(1.0, 1e6) as u32
        })
        .collect();
    let mut out = vec![Vec::with_capacity(rounds); steps.len()];
    for _ in 0..rounds {
        for ((f, &batch), times) in steps.iter_mut().zip(&batches).zip(&mut out) {
            let t = std::time::Instant::now();
            for _ in 0..batch {
                f();
            }
            times.push(t.elapsed().as_secs_f64() / batch as f64);
        }
    }
    out
}

/// The median over rounds of `a / b`, both from [`interleaved_seconds`].
pub fn median_ratio(a: &[f64], b: &[f64]) -> f64 {
    let mut r: Vec<f64> = a.iter().zip(b).map(|(a, b)| a / b).collect();
    r.sort_by(f64::total_cmp);
    r[r.len() / 2]
}
