//! Arbitrary bytes into the trainer's glTF loader, as a `.gltf` (JSON) or, when they start
//! with the magic `glTF`, a `.glb`: a rig that poses, or an error naming the file, never a
//! panic (`aprt_tests::loaders::gltf`).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = aprt_tests::loaders::gltf(data);
});
