//! Helpers the ABI tests share: aligned storage for handles, and one whole frame driven
//! through the C functions (the occluder proxies' calls last), every status collected.

#![allow(dead_code)]

use std::ffi::c_void;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::ptr::{null, null_mut};

use aprt_capi::frame::*;
use aprt_capi::lightmap::*;
use aprt_capi::lights::*;
use aprt_capi::model::*;
use aprt_capi::proxies::*;
use aprt_capi::rig::*;
use aprt_capi::*;

/// 64-byte aligned bytes, for handle storage.
#[derive(Clone, Copy)]
#[repr(C, align(64))]
pub struct Block([u8; 64]);

/// Storage of at least `bytes` bytes, aligned to 64.
pub fn storage(bytes: usize) -> Vec<Block> {
    vec![Block([0; 64]); bytes.div_ceil(64)]
}

pub fn ptr(s: &mut [Block]) -> *mut c_void {
    s.as_mut_ptr().cast()
}

pub fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The staticlib cargo built beside this test: `cargo test` builds the library's every crate
/// type into `deps/` (a plain `cargo build` also copies it one level up).
pub fn staticlib() -> PathBuf {
    let exe = std::env::current_exe().unwrap();
    let deps = exe.parent().unwrap();
    [deps.join("libaprt_capi.a"), deps.join("../libaprt_capi.a")]
        .into_iter()
        .find(|p| p.exists())
        .expect("libaprt_capi.a next to the test binary (cargo builds it with the tests)")
}

/// Whether `tool` runs; CI (`.ci/run`) checks for `cc` and `c++` loudly first and sets
/// `APRT_REQUIRE_CC`, so there a missing compiler fails the test instead of skipping it.
pub fn have(tool: &str) -> bool {
    Command::new(tool).arg("--version").output().is_ok()
}

/// Says on stderr why part of a test is skipped (the harness hides a passing test's
/// `eprintln!`, so the line is written to the stream itself), or fails when `required` (an
/// environment variable CI sets) says it may not be.
pub fn skip(required: &str, why: &str) {
    assert!(
        std::env::var_os(required).is_none(),
        "{required} is set, but {why}"
    );
    let line = format!("skipped: {why}\n");
    std::io::Write::write_all(&mut std::io::stderr(), line.as_bytes()).unwrap();
}

pub fn golden(kind: &str) -> Vec<u8> {
    std::fs::read(repo().join(format!("fixtures/golden/v1-{kind}.aprt"))).unwrap()
}

/// The fuzz seed with an irradiance rig, its 48-byte probe prefix stripped.
pub fn rig_blob() -> Vec<u8> {
    std::fs::read(repo().join("fuzz/corpus/reader/seed-rig-bones-f32")).unwrap()[48..].to_vec()
}

pub const LIGHTS: [aprt_light; 3] = [
    aprt_light {
        kind: APRT_LIGHT_SPHERE,
        position: [0.5, 1.0, 2.0],
        direction: [0.0; 3],
        radius: 0.3,
        colour: [2.0, 1.5, 1.0],
    },
    aprt_light {
        kind: APRT_LIGHT_POINT,
        position: [-1.0, 0.5, 1.0],
        direction: [0.0; 3],
        radius: 0.0,
        colour: [1.0; 3],
    },
    aprt_light {
        kind: APRT_LIGHT_DIRECTIONAL,
        position: [0.0; 3],
        direction: [0.3, -0.2, 0.9],
        radius: 0.0,
        colour: [0.5, 0.6, 0.7],
    },
];

pub const PLACE: aprt_placement = aprt_placement {
    rotation: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
    translation: [0.1, 0.0, -0.2],
};

/// Runs a whole frame on `model` through the C ABI, with inputs sized by its info (capped, so
/// a hostile model that claims huge sizes cannot make the test allocate without bound), and
/// returns every status.
pub fn whole_frame(model: *const aprt_model) -> Vec<aprt_status> {
    let mut info = aprt_model_info::default();
    let mut statuses = vec![aprt_model_get_info(model, &mut info)];
    if statuses[0] != aprt_status::Ok {
        return statuses;
    }
    let cap = |x: u32| (x as usize).min(1 << 16);
    let (n, n2, bones) = (cap(info.vertices), cap(info.coeffs), cap(info.bones));
    let mut frame_mem = storage(aprt_frame_size());
    let mut frame = null_mut();
    statuses.push(aprt_frame_init(
        ptr(&mut frame_mem),
        aprt_frame_size(),
        &mut frame,
    ));
    let angles = vec![0.1f32; cap(info.pose_len)];
    let identity = [1.0f32, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
    let rotations: Vec<f32> = identity.iter().copied().cycle().take(9 * bones).collect();
    let mut sky = vec![0.0f32; n2.max(1)];
    let dir = [0.5f32, -0.8, 0.9];
    let order = info.order;
    statuses.push(aprt_project_directional(
        order,
        dir.as_ptr(),
        3.0,
        sky.as_mut_ptr(),
        sky.len(),
    ));
    statuses.push(aprt_set_pose(model, frame, angles.as_ptr(), angles.len()));
    statuses.push(aprt_light_sh(
        model,
        frame,
        sky.as_ptr(),
        n2,
        rotations.as_ptr(),
        bones,
    ));
    let mut shading = vec![0.0f32; n];
    statuses.push(aprt_shade(model, frame, 0, shading.as_mut_ptr(), n));
    let mut transfer = vec![0.0f32; n * n2];
    statuses.push(aprt_transfer(
        model,
        frame,
        0,
        transfer.as_mut_ptr(),
        transfer.len(),
    ));
    let mut vertex_bones = vec![0u16; n];
    statuses.push(aprt_vertex_bones(model, 0, vertex_bones.as_mut_ptr(), n));
    let positions = vec![0.25f32; 3 * n];
    let mut rgb = vec![0.0f32; 3 * n];
    let weights = [1.0f32; 3];
    statuses.push(aprt_shade_lights(
        model,
        frame,
        rotations.as_ptr(),
        bones,
        LIGHTS.as_ptr(),
        weights.as_ptr(),
        3,
        positions.as_ptr(),
        0,
        rgb.as_mut_ptr(),
        n,
    ));
    let k = cap(info.rig_vectors);
    let mut vectors = vec![0.0f32; 3 * k * n2];
    statuses.push(aprt_rig_vectors(
        model,
        &PLACE,
        LIGHTS.as_ptr(),
        3,
        null(),
        0,
        vectors.as_mut_ptr(),
        k * n2,
    ));
    let mut share = 0.0f32;
    statuses.push(aprt_rig_share(
        model, &LIGHTS[0], &PLACE, 1.0, 0.25, &mut share,
    ));
    let mut rig_lit = vec![0.0f32; info.rig_lit_len.min(1 << 20)];
    statuses.push(aprt_light_rig(
        model,
        frame,
        vectors.as_ptr(),
        k * n2,
        rotations.as_ptr(),
        bones,
        rig_lit.as_mut_ptr(),
        rig_lit.len(),
    ));
    statuses.push(aprt_shade_rig(
        model,
        frame,
        &PLACE,
        positions.as_ptr(),
        0,
        rgb.as_mut_ptr(),
        n,
    ));
    let env: Vec<f32> = sky.iter().flat_map(|&c| [c; 3]).collect();
    statuses.push(aprt_lightmap_compose(
        order,
        transfer.as_ptr(),
        transfer.len(),
        env.as_ptr(),
        n2,
        rgb.as_mut_ptr(),
        n,
    ));
    statuses.push(aprt_lightmap_compose_rig(
        model,
        transfer.as_ptr(),
        transfer.len(),
        vectors.as_ptr(),
        k * n2,
        &PLACE,
        positions.as_ptr(),
        rgb.as_mut_ptr(),
        n,
    ));
    // The occluder proxies: still bones, every normal up.
    let mut proxies_mem = storage(aprt_proxy_frame_size());
    let mut proxies = null_mut();
    statuses.push(aprt_proxy_frame_init(
        ptr(&mut proxies_mem),
        aprt_proxy_frame_size(),
        &mut proxies,
    ));
    let still = [
        1.0f32, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0,
    ];
    let skinning: Vec<f32> = still.iter().copied().cycle().take(12 * bones).collect();
    statuses.push(aprt_pose_proxies(
        model,
        skinning.as_ptr(),
        skinning.len(),
        proxies,
    ));
    let normals: Vec<f32> = [0.0f32, 0.0, 1.0]
        .iter()
        .copied()
        .cycle()
        .take(3 * n)
        .collect();
    statuses.push(aprt_occlude(
        model,
        proxies,
        sky.as_ptr(),
        n2,
        positions.as_ptr(),
        normals.as_ptr(),
        0,
        shading.as_mut_ptr(),
        n,
    ));
    statuses.push(aprt_occlude_transfer(
        model,
        proxies,
        rotations.as_ptr(),
        bones,
        positions.as_ptr(),
        normals.as_ptr(),
        0,
        n,
        transfer.as_mut_ptr(),
        transfer.len(),
    ));
    statuses
}

/// A stream over bytes in memory, for `aprt_model_stream_init`.
pub struct Memory {
    pub bytes: Vec<u8>,
    /// Set to make every read fail.
    pub fail: bool,
    /// Bytes read so far.
    pub read: std::cell::Cell<usize>,
}

impl Memory {
    pub fn new(bytes: Vec<u8>) -> Memory {
        Memory {
            bytes,
            fail: false,
            read: Default::default(),
        }
    }
}

#[allow(unsafe_code)]
pub unsafe extern "C" fn read_memory(
    user: *mut c_void,
    offset: u64,
    buf: *mut u8,
    len: usize,
) -> i32 {
    // SAFETY: `user` is the `Memory` the test passed; `buf` holds `len` bytes (the ABI's
    // contract for `aprt_read_fn`).
    let m = unsafe { &*user.cast::<Memory>() };
    let Some(src) = usize::try_from(offset)
        .ok()
        .and_then(|o| m.bytes.get(o..o.checked_add(len)?))
    else {
        return 1;
    };
    if m.fail {
        return 1;
    }
    unsafe { std::ptr::copy_nonoverlapping(src.as_ptr(), buf, len) };
    m.read.set(m.read.get() + len);
    0
}

/// Opens `memory` as a streamed model in `storage`, growing `scratch` while it asks.
pub fn stream(
    memory: &mut Memory,
    scratch: &mut Vec<u8>,
    model_mem: &mut [Block],
) -> (aprt_status, *mut aprt_model) {
    let source = aprt_source {
        read_at: Some(read_memory),
        user: (memory as *mut Memory).cast(),
        len: memory.bytes.len() as u64,
    };
    let mut model = null_mut();
    for _ in 0..3 {
        let mut needed = 0;
        let status = aprt_model_stream_init(
            &source,
            scratch.as_mut_ptr(),
            scratch.len(),
            &mut needed,
            ptr(model_mem),
            aprt_model_size(),
            &mut model,
        );
        if status != aprt_status::BufferTooSmall {
            return (status, model);
        }
        assert!(needed > scratch.len(), "asks for more than it has");
        scratch.resize(needed, 0);
    }
    panic!("the stream asked for more scratch three times")
}
