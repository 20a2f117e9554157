//! Arbitrary bytes into the trainer's BVH parser and the mannequin built from the skeleton it
//! reads: a rig that poses its motion, or an error naming the file, never a panic
//! (`aprt_tests::loaders::bvh`).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = aprt_tests::loaders::bvh(data);
});
