//! Arbitrary bytes into the environment-map decoder, as OpenEXR when they start with `v` (the
//! first byte of its magic), Radiance HDR otherwise, then projected to SH: finite coefficients,
//! or an error naming the file, never a panic (`aprt_tests::readers::env_map`).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = aprt_tests::readers::env_map(data);
});
