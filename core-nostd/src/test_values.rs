//! Deterministic test values shared by the crate's unit tests (no `std`, no random crate).

/// The `i`-th value of a golden-ratio sequence in [-0.85, 0.85): full 24-bit mantissas, so
/// that every product rounds and summing in another order gives other bits, and spread evenly
/// enough to stand in for random positions and directions.
pub(crate) fn weight(i: usize) -> f32 {
    let x = (i as f64 * 0.618_033_988_749_895).fract();
    ((x - 0.5) * 1.7) as f32
}
