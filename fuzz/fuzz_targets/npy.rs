//! Arbitrary bytes into the `.npy` float32 reader: an array with one value per element of its
//! shape that reads back from the writer bit for bit, or an error, never a panic
//! (`aprt_tests::readers::npy`).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = aprt_tests::readers::npy(data);
});
