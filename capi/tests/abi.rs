//! The boundary's own checks: NULL for every pointer argument of every function gives
//! `NULL_POINTER`, bad storage gives its status, handles of the wrong kind or never
//! initialised are refused, lights of unknown kind too, every status has a message, and a
//! re-entrant read callback gets `BUSY`; valid inputs run a whole frame to `OK`.

use crate::common;

use std::ffi::{CStr, c_void};
use std::ptr::{null, null_mut};

use aprt_capi::frame::*;
use aprt_capi::lightmap::*;
use aprt_capi::lights::*;
use aprt_capi::model::*;
use aprt_capi::rig::*;
use aprt_capi::status::{ALL, aprt_status_message};
use aprt_capi::*;
use common::*;

use aprt_status::{BadHandle, NullPointer, Ok as OK, VertexRange};

/// A resident model of `blob` (kept alive by the caller) and an empty frame.
struct Fixture {
    _model_mem: Vec<Block>,
    _frame_mem: Vec<Block>,
    model: *mut aprt_model,
    frame: *mut aprt_frame,
}

fn fixture(blob: &[u8]) -> Fixture {
    let (mut model_mem, mut frame_mem) = (storage(aprt_model_size()), storage(aprt_frame_size()));
    let (mut model, mut frame) = (null_mut(), null_mut());
    let len = aprt_model_size();
    let init = aprt_model_init(
        blob.as_ptr(),
        blob.len(),
        ptr(&mut model_mem),
        len,
        &mut model,
    );
    assert_eq!(init, OK);
    let len = aprt_frame_size();
    assert_eq!(aprt_frame_init(ptr(&mut frame_mem), len, &mut frame), OK);
    Fixture {
        _model_mem: model_mem,
        _frame_mem: frame_mem,
        model,
        frame,
    }
}

#[test]
fn a_whole_frame_runs_to_ok() {
    for kind in ["atlas", "bones", "proxies", "world"] {
        let blob = golden(kind);
        let f = fixture(&blob);
        for (i, s) in whole_frame(f.model).into_iter().enumerate() {
            // Calls 9 to 12 and 14 need the rig, which the golden blobs do not carry; calls
            // 16 to 18 need the proxies, which only the golden `proxies` carries.
            let rig_call = (9..=12).contains(&i) || i == 14;
            let proxy_call = (16..=18).contains(&i) && kind != "proxies";
            let want: &[aprt_status] = match (rig_call, proxy_call) {
                (true, _) => &[
                    aprt_status::NoIrradianceRig,
                    aprt_status::WeightsNotSet,
                    aprt_status::WrongLength,
                ],
                (_, true) => &[aprt_status::NoProxies],
                _ => &[OK],
            };
            assert!(want.contains(&s), "{kind}: call {i} gave {s:?}");
        }
    }
    let blob = rig_blob();
    let f = fixture(&blob);
    for (i, s) in whole_frame(f.model).into_iter().enumerate() {
        let want = match i {
            16..=18 => aprt_status::NoProxies,
            _ => OK,
        };
        assert_eq!(s, want, "rig: call {i}");
    }
}

#[test]
fn null_pointers_are_refused() {
    let blob = golden("bones");
    let f = fixture(&blob);
    let (m, fr) = (f.model.cast_const(), f.frame);
    let (mut o, mut handle, mut size) = ([0.0f32; 256], null_mut(), 0usize);
    let (v, l, p, pl) = (
        o.as_ptr(),
        LIGHTS.as_ptr(),
        [0.0f32; 3].as_ptr(),
        &PLACE as *const _,
    );
    let out = o.as_mut_ptr();
    let mut mem = storage(aprt_model_size());
    let s = ptr(&mut mem);
    let ms = aprt_model_size();
    let mut info = aprt_model_info::default();
    let source = aprt_source {
        read_at: None,
        user: null_mut(),
        len: 10,
    };
    let null_f = null::<f32>();
    let calls: Vec<(&str, aprt_status)> = vec![
        (
            "model_init blob",
            aprt_model_init(null(), 10, s, ms, &mut handle),
        ),
        (
            "model_init storage",
            aprt_model_init(blob.as_ptr(), blob.len(), null_mut(), ms, &mut handle),
        ),
        (
            "model_init out",
            aprt_model_init(blob.as_ptr(), blob.len(), s, ms, null_mut()),
        ),
        (
            "stream source",
            aprt_model_stream_init(null(), null_mut(), 0, &mut size, s, ms, &mut handle),
        ),
        (
            "stream read_at",
            aprt_model_stream_init(&source, null_mut(), 0, &mut size, s, ms, &mut handle),
        ),
        (
            "frame_init storage",
            aprt_frame_init(null_mut(), aprt_frame_size(), null_mut()),
        ),
        ("get_info model", aprt_model_get_info(null(), &mut info)),
        ("get_info out", aprt_model_get_info(m, null_mut())),
        (
            "angle_index name",
            aprt_model_angle_index(m, null(), 3, &mut size),
        ),
        (
            "angle_index out",
            aprt_model_angle_index(m, b"neck.y".as_ptr(), 6, null_mut()),
        ),
        (
            "angle_index model",
            aprt_model_angle_index(null(), b"neck.y".as_ptr(), 6, &mut size),
        ),
        ("set_pose model", aprt_set_pose(null(), fr, v, 5)),
        ("set_pose frame", aprt_set_pose(m, null_mut(), v, 5)),
        ("set_pose angles", aprt_set_pose(m, fr, null_f, 5)),
        ("light_sh model", aprt_light_sh(null(), fr, v, 9, v, 3)),
        ("light_sh frame", aprt_light_sh(m, null_mut(), v, 9, v, 3)),
        ("light_sh lighting", aprt_light_sh(m, fr, null_f, 9, v, 3)),
        ("light_sh bones", aprt_light_sh(m, fr, v, 9, null_f, 3)),
        ("shade model", aprt_shade(null(), fr, 0, out, 4)),
        ("shade frame", aprt_shade(m, null(), 0, out, 4)),
        ("shade out", aprt_shade(m, fr, 0, null_mut(), 4)),
        ("transfer model", aprt_transfer(null(), fr, 0, out, 9)),
        ("transfer frame", aprt_transfer(m, null(), 0, out, 9)),
        ("transfer out", aprt_transfer(m, fr, 0, null_mut(), 9)),
        (
            "vertex_bones model",
            aprt_vertex_bones(null(), 0, [0u16; 4].as_mut_ptr(), 4),
        ),
        ("vertex_bones out", aprt_vertex_bones(m, 0, null_mut(), 4)),
        (
            "shade_lights model",
            aprt_shade_lights(null(), fr, v, 3, l, v, 1, v, 0, out, 1),
        ),
        (
            "shade_lights frame",
            aprt_shade_lights(m, null(), v, 3, l, v, 1, v, 0, out, 1),
        ),
        (
            "shade_lights bones",
            aprt_shade_lights(m, fr, null_f, 3, l, v, 1, v, 0, out, 1),
        ),
        (
            "shade_lights lights",
            aprt_shade_lights(m, fr, v, 3, null(), v, 1, v, 0, out, 1),
        ),
        (
            "shade_lights weights",
            aprt_shade_lights(m, fr, v, 3, l, null_f, 1, v, 0, out, 1),
        ),
        (
            "shade_lights positions",
            aprt_shade_lights(m, fr, v, 3, l, v, 1, null_f, 0, out, 1),
        ),
        (
            "shade_lights out",
            aprt_shade_lights(m, fr, v, 3, l, v, 1, v, 0, null_mut(), 1),
        ),
        (
            "project direction",
            aprt_project_directional(3, null_f, 1.0, out, 9),
        ),
        (
            "project out",
            aprt_project_directional(3, p, 1.0, null_mut(), 9),
        ),
        (
            "radiance light",
            aprt_light_radiance_sh(null(), 3, p, out, 9),
        ),
        ("radiance at", aprt_light_radiance_sh(l, 3, null_f, out, 9)),
        (
            "radiance out",
            aprt_light_radiance_sh(l, 3, p, null_mut(), 9),
        ),
        (
            "rig_vectors model",
            aprt_rig_vectors(null(), pl, l, 1, v, 9, out, 9),
        ),
        (
            "rig_vectors placement",
            aprt_rig_vectors(m, null(), l, 1, v, 9, out, 9),
        ),
        (
            "rig_vectors lights",
            aprt_rig_vectors(m, pl, null(), 1, v, 9, out, 9),
        ),
        (
            "rig_vectors environment",
            aprt_rig_vectors(m, pl, l, 1, null_f, 9, out, 9),
        ),
        (
            "rig_vectors out",
            aprt_rig_vectors(m, pl, l, 1, v, 9, null_mut(), 9),
        ),
        (
            "rig_share model",
            aprt_rig_share(null(), l, pl, 1.0, 0.25, out),
        ),
        (
            "rig_share light",
            aprt_rig_share(m, null(), pl, 1.0, 0.25, out),
        ),
        (
            "rig_share placement",
            aprt_rig_share(m, l, null(), 1.0, 0.25, out),
        ),
        (
            "rig_share out",
            aprt_rig_share(m, l, pl, 1.0, 0.25, null_mut()),
        ),
        (
            "light_rig model",
            aprt_light_rig(null(), fr, v, 9, v, 3, out, 9),
        ),
        (
            "light_rig frame",
            aprt_light_rig(m, null_mut(), v, 9, v, 3, out, 9),
        ),
        (
            "light_rig vectors",
            aprt_light_rig(m, fr, null_f, 9, v, 3, out, 9),
        ),
        (
            "light_rig bones",
            aprt_light_rig(m, fr, v, 9, null_f, 3, out, 9),
        ),
        (
            "light_rig buffer",
            aprt_light_rig(m, fr, v, 9, v, 3, null_mut(), 9),
        ),
        (
            "shade_rig model",
            aprt_shade_rig(null(), fr, pl, v, 0, out, 1),
        ),
        (
            "shade_rig frame",
            aprt_shade_rig(m, null(), pl, v, 0, out, 1),
        ),
        (
            "shade_rig placement",
            aprt_shade_rig(m, fr, null(), v, 0, out, 1),
        ),
        (
            "shade_rig positions",
            aprt_shade_rig(m, fr, pl, null_f, 0, out, 1),
        ),
        (
            "shade_rig out",
            aprt_shade_rig(m, fr, pl, v, 0, null_mut(), 1),
        ),
        (
            "compose maps",
            aprt_lightmap_compose(3, null_f, 9, v, 9, out, 1),
        ),
        (
            "compose lighting",
            aprt_lightmap_compose(3, v, 9, null_f, 9, out, 1),
        ),
        (
            "compose out",
            aprt_lightmap_compose(3, v, 9, v, 9, null_mut(), 1),
        ),
        (
            "compose_lights maps",
            aprt_lightmap_compose_lights(3, null_f, 9, v, l, 1, v, 9, out, 1),
        ),
        (
            "compose_lights positions",
            aprt_lightmap_compose_lights(3, v, 9, null_f, l, 1, v, 9, out, 1),
        ),
        (
            "compose_lights lights",
            aprt_lightmap_compose_lights(3, v, 9, v, null(), 1, v, 9, out, 1),
        ),
        (
            "compose_lights env",
            aprt_lightmap_compose_lights(3, v, 9, v, l, 1, null_f, 9, out, 1),
        ),
        (
            "compose_lights out",
            aprt_lightmap_compose_lights(3, v, 9, v, l, 1, v, 9, null_mut(), 1),
        ),
        (
            "compose_rig model",
            aprt_lightmap_compose_rig(null(), v, 9, v, 9, pl, v, out, 1),
        ),
        (
            "compose_rig maps",
            aprt_lightmap_compose_rig(m, null_f, 9, v, 9, pl, v, out, 1),
        ),
        (
            "compose_rig vectors",
            aprt_lightmap_compose_rig(m, v, 9, null_f, 9, pl, v, out, 1),
        ),
        (
            "compose_rig placement",
            aprt_lightmap_compose_rig(m, v, 9, v, 9, null(), v, out, 1),
        ),
        (
            "compose_rig positions",
            aprt_lightmap_compose_rig(m, v, 9, v, 9, pl, null_f, out, 1),
        ),
        (
            "compose_rig out",
            aprt_lightmap_compose_rig(m, v, 9, v, 9, pl, v, null_mut(), 1),
        ),
    ];
    for (what, status) in calls {
        assert_eq!(status, NullPointer, "{what}");
    }
    // The stream's scratch-size out-parameter is required too.
    let mut memory = Memory::new(blob.clone());
    let source = aprt_source {
        read_at: Some(read_memory),
        user: (&mut memory as *mut Memory).cast(),
        len: blob.len() as u64,
    };
    let status = aprt_model_stream_init(&source, null_mut(), 0, null_mut(), s, ms, &mut handle);
    assert_eq!(status, NullPointer);
}

#[test]
fn bad_storage_and_handles_are_refused() {
    let blob = golden("world");
    let mut mem = storage(aprt_model_size() + 64);
    let mut handle = null_mut();
    let base = ptr(&mut mem).cast::<u8>();
    let misaligned = base.wrapping_add(1).cast::<c_void>();
    let ms = aprt_model_size();
    let (b, n) = (blob.as_ptr(), blob.len());
    assert_eq!(
        aprt_model_init(b, n, misaligned, ms, &mut handle),
        aprt_status::Misaligned
    );
    assert_eq!(
        aprt_model_init(b, n, base.cast(), ms - 1, &mut handle),
        aprt_status::StorageTooSmall
    );
    // The storage is checked before the blob: a bad storage is named even for junk bytes.
    let junk = b"junk";
    let status = aprt_model_init(junk.as_ptr(), 4, base.cast(), ms - 1, &mut handle);
    assert_eq!(status, aprt_status::StorageTooSmall);
    let mut frame = null_mut();
    let mut small = storage(64);
    assert_eq!(
        aprt_frame_init(ptr(&mut small), 64, &mut frame),
        aprt_status::StorageTooSmall
    );

    // Zeroed storage is no handle; a frame is not a model, nor a model a frame.
    let zeroed = storage(aprt_model_size());
    let mut info = aprt_model_info::default();
    assert_eq!(
        aprt_model_get_info(zeroed.as_ptr().cast(), &mut info),
        BadHandle
    );
    let f = fixture(&blob);
    assert_eq!(
        aprt_model_get_info(f.frame.cast_const().cast(), &mut info),
        BadHandle
    );
    let angles = [0.0f32; 4];
    assert_eq!(
        aprt_set_pose(f.model, f.model.cast(), angles.as_ptr(), 4),
        BadHandle
    );
    // A misaligned float array.
    let floats = [0.0f32; 8];
    let odd = floats.as_ptr().cast::<u8>().wrapping_add(2).cast::<f32>();
    assert_eq!(
        aprt_set_pose(f.model, f.frame, odd, 4),
        aprt_status::Misaligned
    );
    assert_eq!(aprt_set_pose(f.model, f.frame, angles.as_ptr(), 4), OK);
}

#[test]
fn lights_of_unknown_kind_and_too_many_lights_are_refused() {
    let mut bad = LIGHTS[0];
    bad.kind = 7;
    let (at, mut out) = ([0.0f32; 3], [0.0f32; 27]);
    let status = aprt_light_radiance_sh(&bad, 3, at.as_ptr(), out.as_mut_ptr(), 9);
    assert_eq!(status, aprt_status::BadLightKind);
    let mut negative = LIGHTS[1];
    negative.colour = [-1.0; 3];
    let status = aprt_light_radiance_sh(&negative, 3, at.as_ptr(), out.as_mut_ptr(), 9);
    assert_eq!(status, aprt_status::BadLight);
    let many = vec![LIGHTS[2]; APRT_MAX_LIGHTS + 1];
    let (maps, mut rgb) = ([0.0f32; 9], [0.0f32; 3]);
    let status = aprt_lightmap_compose_lights(
        3,
        maps.as_ptr(),
        9,
        at.as_ptr(),
        many.as_ptr(),
        many.len(),
        null(),
        0,
        rgb.as_mut_ptr(),
        1,
    );
    assert_eq!(status, aprt_status::TooManyLights);
}

#[test]
fn every_status_has_a_message_and_the_versions_are_stated() {
    for s in ALL.iter().chain(&[aprt_status::Unknown]) {
        assert!(!text(aprt_status_message(*s as i32)).is_empty(), "{s:?}");
    }
    assert_eq!(text(aprt_status_message(12345)), "unknown status");
    assert_eq!(text(aprt_status_message(0)), "ok");
    assert_eq!(aprt_abi_version(), APRT_ABI_VERSION);
    assert_eq!(text(aprt_version()), env!("CARGO_PKG_VERSION"));
    // Distinct codes: the numbers are the ABI.
    let mut codes: Vec<i32> = ALL.iter().map(|s| *s as i32).collect();
    codes.sort();
    codes.dedup();
    assert_eq!(codes.len(), ALL.len());
}

/// A static C string of the library.
#[allow(unsafe_code)]
fn text(p: *const std::ffi::c_char) -> &'static str {
    assert!(!p.is_null());
    // SAFETY: the library returns static NUL-terminated strings.
    unsafe { CStr::from_ptr(p) }.to_str().unwrap()
}

#[test]
fn pose_entries_are_bound_by_name() {
    let blob = golden("bones");
    let f = fixture(&blob);
    let mut index = usize::MAX;
    let status = aprt_model_angle_index(f.model, b"neck.y".as_ptr(), 6, &mut index);
    assert_eq!((status, index), (OK, 1));
    let status = aprt_model_angle_index(f.model, b"tail".as_ptr(), 4, &mut index);
    assert_eq!(status, aprt_status::NoSuchName);
    let mut memory = Memory::new(blob.clone());
    let (mut scratch, mut mem) = (Vec::new(), storage(aprt_model_size()));
    let (status, streamed) = stream(&mut memory, &mut scratch, &mut mem);
    assert_eq!(status, OK);
    let status = aprt_model_angle_index(streamed, b"l_elbow".as_ptr(), 7, &mut index);
    assert_eq!((status, index), (OK, 3));
}

/// A read callback that calls back into the model it is reading for.
#[allow(unsafe_code)]
unsafe extern "C" fn reenter(user: *mut c_void, offset: u64, buf: *mut u8, len: usize) -> i32 {
    // SAFETY: `user` is the test's `Reentrant`.
    let r = unsafe { &mut *user.cast::<Reentrant>() };
    if !r.model.is_null() {
        let mut info = aprt_model_info::default();
        r.seen = Some(aprt_model_get_info(r.model, &mut info));
    }
    // SAFETY: as `read_memory`.
    unsafe { read_memory((&mut r.memory as *mut Memory).cast(), offset, buf, len) }
}

struct Reentrant {
    memory: Memory,
    model: *const aprt_model,
    seen: Option<aprt_status>,
}

#[test]
fn a_reentrant_read_callback_gets_busy() {
    let blob = golden("world");
    let mut r = Reentrant {
        memory: Memory::new(blob.clone()),
        model: null(),
        seen: None,
    };
    let source = aprt_source {
        read_at: Some(reenter),
        user: (&mut r as *mut Reentrant).cast(),
        len: blob.len() as u64,
    };
    let (mut scratch, mut mem) = (vec![0u8; 4096], storage(aprt_model_size()));
    let (mut model, mut needed) = (null_mut(), 0);
    let status = aprt_model_stream_init(
        &source,
        scratch.as_mut_ptr(),
        scratch.len(),
        &mut needed,
        ptr(&mut mem),
        aprt_model_size(),
        &mut model,
    );
    assert_eq!(status, OK);
    r.model = model;
    let f = fixture(&blob);
    let angles = [0.0f32; 4];
    assert_eq!(aprt_set_pose(model, f.frame, angles.as_ptr(), 4), OK);
    assert_eq!(r.seen, Some(aprt_status::Busy));
}

#[test]
fn a_new_pose_drops_the_rig_weights() {
    let blob = rig_blob();
    let f = fixture(&blob);
    let mut info = aprt_model_info::default();
    assert_eq!(aprt_model_get_info(f.model, &mut info), OK);
    let (n, k) = (
        info.vertices as usize,
        (info.rig_vectors * info.coeffs) as usize,
    );
    let angles = vec![0.0f32; info.pose_len as usize];
    let identity = [1.0f32, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
    let bones: Vec<f32> = identity
        .iter()
        .copied()
        .cycle()
        .take(9 * info.bones as usize)
        .collect();
    let (vectors, mut buffer) = (vec![0.5f32; 3 * k], vec![0.0f32; info.rig_lit_len]);
    let (positions, mut rgb) = (vec![0.1f32; 3 * n], vec![0.0f32; 3 * n]);
    let (b, nb) = (bones.as_ptr(), info.bones as usize);
    let light_rig = |buffer: &mut [f32]| {
        aprt_light_rig(
            f.model,
            f.frame,
            vectors.as_ptr(),
            k,
            b,
            nb,
            buffer.as_mut_ptr(),
            buffer.len(),
        )
    };
    let shade_rig = |rgb: &mut [f32]| {
        aprt_shade_rig(
            f.model,
            f.frame,
            &PLACE,
            positions.as_ptr(),
            0,
            rgb.as_mut_ptr(),
            n,
        )
    };
    assert_eq!(
        aprt_set_pose(f.model, f.frame, angles.as_ptr(), angles.len()),
        OK
    );
    assert_eq!(shade_rig(&mut rgb), aprt_status::WeightsNotSet);
    assert_eq!(light_rig(&mut buffer), OK);
    assert_eq!(shade_rig(&mut rgb), OK);
    assert_eq!(
        aprt_set_pose(f.model, f.frame, angles.as_ptr(), angles.len()),
        OK
    );
    assert_eq!(shade_rig(&mut rgb), aprt_status::WeightsNotSet);
    // A buffer too small is refused, and leaves no weights.
    assert_eq!(light_rig(&mut buffer[..1]), aprt_status::WeightsTooSmall);
    assert_eq!(shade_rig(&mut rgb), aprt_status::WeightsNotSet);
}

#[test]
fn a_new_pose_drops_the_sh_lighting() {
    let blob = golden("bones");
    let f = fixture(&blob);
    let mut info = aprt_model_info::default();
    assert_eq!(aprt_model_get_info(f.model, &mut info), OK);
    let (n, n2, nb) = (
        info.vertices as usize,
        info.coeffs as usize,
        info.bones as usize,
    );
    let identity = [1.0f32, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
    let bones: Vec<f32> = identity.iter().copied().cycle().take(9 * nb).collect();
    let sky = vec![0.5f32; n2];
    let mut out = vec![0.0f32; n];
    let pose = |angles: &[f32]| aprt_set_pose(f.model, f.frame, angles.as_ptr(), angles.len());
    let light = || aprt_light_sh(f.model, f.frame, sky.as_ptr(), n2, bones.as_ptr(), nb);
    let mut shade = || aprt_shade(f.model, f.frame, 0, out.as_mut_ptr(), n);
    let (still, bent) = (vec![0.0f32; info.pose_len as usize], vec![0.4f32; 5]);
    assert_eq!(pose(&still), OK);
    assert_eq!(shade(), aprt_status::WeightsNotSet, "never lit");
    assert_eq!(light(), OK);
    assert_eq!(shade(), OK);
    // A second pose without lighting: the old shading is not served.
    assert_eq!(pose(&bent), OK);
    assert_eq!(shade(), aprt_status::WeightsNotSet, "lit for the last pose");
    assert_eq!(light(), OK);
    assert_eq!(shade(), OK);
    // A failed pose or lighting leaves the frame unlit too.
    assert_eq!(pose(&[f32::NAN; 5]), aprt_status::NonFiniteAngle);
    assert_eq!(shade(), aprt_status::WeightsNotSet);
    assert_eq!(pose(&bent), OK);
    assert_eq!(light(), OK);
    let nan = vec![f32::NAN; n2];
    let status = aprt_light_sh(f.model, f.frame, nan.as_ptr(), n2, bones.as_ptr(), nb);
    assert_eq!(status, aprt_status::NonFiniteLighting);
    assert_eq!(shade(), aprt_status::WeightsNotSet);
}

#[test]
fn lengths_no_buffer_can_have_name_the_callers_range() {
    let blob = golden("world");
    let f = fixture(&blob);
    let mut info = aprt_model_info::default();
    assert_eq!(aprt_model_get_info(f.model, &mut info), OK);
    let mut out = [0.0f32; 64];
    let o = out.as_mut_ptr();
    let three = [0.0f32; 3];
    let (p, l) = (three.as_ptr(), LIGHTS.as_ptr());
    let (max, half) = (usize::MAX, usize::MAX / 2);
    assert_eq!(aprt_shade(f.model, f.frame, 1, o, max), VertexRange);
    assert_eq!(aprt_transfer(f.model, f.frame, 0, o, max), VertexRange);
    let status = aprt_shade_lights(f.model, f.frame, null(), 0, l, p, 1, p, 0, o, half);
    assert_eq!(status, VertexRange);
    let status = aprt_shade_lights(f.model, f.frame, null(), 0, l, p, max, p, 0, o, 1);
    assert_eq!(status, aprt_status::TooManyLights);
    let status = aprt_set_pose(f.model, f.frame, p, max);
    assert_eq!(status, aprt_status::WrongLength);
}

/// Asking a stream for its scratch size once read and checked the whole blob (1.26 MB for
/// a model of 20,449 reads), and the call that then opened it did it all again, twice with
/// a rig. The size is now read from the header: the query reads a few hundred bytes, and
/// the model opens after one pass over the blob (and one over its rig, into the scratch).
#[test]
fn a_stream_is_sized_from_its_header_and_read_once() {
    let demo = std::fs::read(repo().join("web/data/model.aprt")).unwrap();
    for (what, blob, rig) in [
        ("the page's model", demo, false),
        ("a model with a rig", rig_blob(), true),
    ] {
        let memory = Memory::new(blob.clone());
        let source = aprt_source {
            read_at: Some(read_memory),
            user: (&memory as *const Memory).cast_mut().cast(),
            len: blob.len() as u64,
        };
        let mut mem = storage(aprt_model_size());
        let (mut model, mut needed) = (null_mut(), 0);
        let mut open = |scratch: &mut [u8], needed: &mut usize| {
            let (p, len) = (scratch.as_mut_ptr(), scratch.len());
            let m = ptr(&mut mem);
            aprt_model_stream_init(&source, p, len, needed, m, aprt_model_size(), &mut model)
        };
        let status = open(&mut [], &mut needed);
        assert_eq!(status, aprt_status::BufferTooSmall, "{what}");
        assert!(
            memory.read.get() < 1024,
            "{what}: the query read {} bytes",
            memory.read.get()
        );
        memory.read.set(0);
        let mut scratch = vec![0u8; needed];
        assert_eq!(open(&mut scratch, &mut 0), OK, "{what}");
        let mut info = aprt_model_info::default();
        assert_eq!(aprt_model_get_info(model, &mut info), OK);
        assert_eq!(info.has_rig, rig);
        // One query gave all the scratch: the block and, with a rig, the rig's bytes.
        assert_eq!(needed, info.scratch_bytes, "{what}");
        assert_eq!(rig, rig_bytes(&blob) > 0);
        // The header twice (the size, then the validation), every section once, the rig
        // twice, and the bone-index row of each block of 8 vertices again (1 row in 23 here).
        let once = blob.len() + rig_bytes(&blob);
        let read = memory.read.get();
        assert!(
            (once..once + once / 10 + 512).contains(&read),
            "{what}: opening read {read} bytes of a {}-byte blob",
            blob.len()
        );
    }
}

/// The bytes of a blob's irradiance rig section (0 without one).
fn rig_bytes(blob: &[u8]) -> usize {
    aprt_core::StreamedModel::needs(blob)
        .unwrap()
        .irradiance_rig_bytes
}
