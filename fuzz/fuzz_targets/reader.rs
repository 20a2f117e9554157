//! Arbitrary bytes into the blob reader (resident and streamed) and, when they parse, the
//! evaluator. The input is a 48-byte `Probe` (angles, lighting, rotations, vertex range,
//! scratch sizes) followed by the blob. Each blob is tried as is and resealed (every checksum
//! recomputed), so mutations reach the validation behind the CRCs.
#![no_main]

use aprt_tests::edit::reseal;
use aprt_tests::harness::{Probe, exercise};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let (probe, blob) = Probe::split(data);
    let _ = exercise(blob, &probe);
    let _ = exercise(&reseal(blob), &probe);
});
