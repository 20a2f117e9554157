//! Arbitrary bytes into the `.shlm` light-map reader, as they are and with the trailing CRC
//! recomputed: a file whose frames decode to finite values, or an error, never a panic
//! (`aprt_tests::readers::shlm`).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = aprt_tests::readers::shlm(data);
});
