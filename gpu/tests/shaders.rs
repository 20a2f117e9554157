//! Every shader parses and validates with naga, with no device: as wgpu would check it on a
//! device with no optional features and WebGPU's full baseline (wgpu's default downlevel
//! capabilities), so a kernel that passes here runs in a browser too.

use std::collections::BTreeSet;

use aprt_gpu::shaders::ALL;
use naga::valid::{ValidationFlags, Validator};

#[test]
fn every_shader_validates_with_naga() {
    let capabilities = wgpu_naga_bridge::features_to_naga_capabilities(
        wgpu::Features::empty(),
        wgpu::DownlevelCapabilities::default().flags,
    );
    for shader in ALL {
        let module = naga::front::wgsl::parse_str(shader.source).unwrap_or_else(|e| {
            panic!("{}", e.emit_to_string_with_path(shader.source, shader.name))
        });
        Validator::new(ValidationFlags::all(), capabilities)
            .validate(&module)
            .unwrap_or_else(|e| {
                panic!("{}", e.emit_to_string_with_path(shader.source, shader.name))
            });
    }
}

#[test]
fn every_wgsl_file_is_listed() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src/shaders");
    let files: BTreeSet<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|entry| entry.unwrap().file_name().into_string().unwrap())
        .filter(|name| name.ends_with(".wgsl"))
        .collect();
    let listed: BTreeSet<String> = ALL.iter().map(|shader| shader.name.to_owned()).collect();
    assert_eq!(
        files, listed,
        "shaders::ALL must list every .wgsl file under src/shaders"
    );
}
