//! Arbitrary bytes into the trainer's lights-file parser, as TOML text: at most `MAX_LIGHTS`
//! lights of finite f32 values, or an error naming the file, never a panic
//! (`aprt_tests::readers::lights`).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = aprt_tests::readers::lights(data);
});
