//! Arbitrary bytes into the trainer's scene-file parser, as TOML text: a scene whose values
//! are what the reader promises, or an error naming the file, never a panic
//! (`aprt_tests::readers::scene`).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = aprt_tests::readers::scene(data);
});
