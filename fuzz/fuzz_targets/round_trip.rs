//! Writer → reader round trip of arbitrary model shapes: a 48-byte `Probe` (evaluation
//! inputs), then the bytes `ModelSpec`'s `arbitrary` implementation draws the model from.
#![no_main]

use aprt_tests::harness::Probe;
use aprt_tests::spec::{ModelSpec, round_trip};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let (probe, rest) = Probe::split(data);
    round_trip(&ModelSpec::from_bytes(rest), &probe);
});
