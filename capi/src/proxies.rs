//! The occluder proxies of a model with them: a handle for one frame's posed proxies in the
//! caller's storage, and the steps that pose them and subtract their occlusion from shading or
//! transfer (the core's `Model::pose_proxies`, `occlude` and `occlude_transfer`).
//!
//! A model with proxies learnt its transfer plus the proxies' occlusion, so every frame it
//! needs `aprt_pose_proxies` and then `aprt_occlude` after `aprt_shade` (or
//! `aprt_occlude_transfer` after `aprt_transfer`); without them it is too bright wherever one
//! part of the character shades another (`info.has_proxies`).
// `#[unsafe(no_mangle)]` is the only unsafe here (exported names must be unique); every
// unsafe operation lives in `ffi_ptr`, which `tests/unsafe_confined.rs` checks.
#![allow(unsafe_code)]

use std::ffi::c_void;

use aprt_core::ProxyFrame;

use crate::ffi_ptr::{self, Handle};
use crate::model::{aprt_model, with_model};
use crate::status::{aprt_status, guard};

/// One frame's posed occluder proxies in the caller's storage (about 4 KiB, any model's).
/// Opaque; see `aprt_proxy_frame_init`.
// `repr(C)` puts the tag at offset 0, so checking a pointer for this handle reads only its
// first 8 bytes. `align(8)`, which the `u64`s inside need anyway, also keeps cbindgen from
// spelling out a struct whose core field C cannot name: it declares the type opaque.
#[allow(non_camel_case_types)]
#[repr(C, align(8))]
pub struct aprt_proxy_frame {
    tag: u64,
    pub(crate) proxies: ProxyFrame,
}

impl Handle for aprt_proxy_frame {
    const TAG: u64 = u64::from_le_bytes(*b"aprtPRXY");
    const TAG_OFFSET: usize = std::mem::offset_of!(aprt_proxy_frame, tag);
}

/// Bytes of storage an `aprt_proxy_frame` needs (about 4 KiB: the core's most proxies and
/// bones).
#[unsafe(no_mangle)]
pub extern "C" fn aprt_proxy_frame_size() -> usize {
    size_of::<aprt_proxy_frame>()
}

/// Alignment the storage of an `aprt_proxy_frame` needs.
#[unsafe(no_mangle)]
pub extern "C" fn aprt_proxy_frame_align() -> usize {
    align_of::<aprt_proxy_frame>()
}

/// Writes an empty proxy frame into `storage` (`storage_len` ≥ `aprt_proxy_frame_size()`
/// bytes, aligned to `aprt_proxy_frame_align()`) and its address to `*out`. It holds no
/// resources: free the storage when done. Re-initialising it empties it.
/// `APRT_STATUS_NULL_POINTER`, `APRT_STATUS_MISALIGNED` or `APRT_STATUS_STORAGE_TOO_SMALL`
/// for bad storage.
#[unsafe(no_mangle)]
pub extern "C" fn aprt_proxy_frame_init(
    storage: *mut c_void,
    storage_len: usize,
    out: *mut *mut aprt_proxy_frame,
) -> aprt_status {
    guard(|| {
        ffi_ptr::write(out, std::ptr::null_mut())?;
        let frame = aprt_proxy_frame {
            tag: aprt_proxy_frame::TAG,
            proxies: ProxyFrame::new(),
        };
        ffi_ptr::write(out, ffi_ptr::place(storage, storage_len, frame)?)
    })
}

/// Poses the model's occluder proxies for this frame into `proxies`: each sphere moved by its
/// bone's skinning matrix, and per bone the proxies that can reach its vertices. `skinning`
/// holds `skinning_len` = 12 · `info.bones` floats: per bone its skinning matrix, bind pose to
/// posed (the matrix an engine computes for linear blend skinning, `world · inverse_bind`),
/// 3 × 4 row-major `[r00 r01 r02 t0  r10 r11 r12 t1  r20 r21 r22 t2]`, in the units of the
/// model's positions. On any failure but a bad `proxies` pointer, `proxies` is left empty.
///
/// `APRT_STATUS_NO_PROXIES` when the model has none (`info.has_proxies`);
/// `APRT_STATUS_WRONG_LENGTH` when `skinning_len` is not 12 · `info.bones`;
/// `APRT_STATUS_BAD_SKINNING` for a NaN or infinite matrix entry.
#[unsafe(no_mangle)]
pub extern "C" fn aprt_pose_proxies(
    model: *const aprt_model,
    skinning: *const f32,
    skinning_len: usize,
    proxies: *mut aprt_proxy_frame,
) -> aprt_status {
    guard(|| {
        let frame = ffi_ptr::handle_mut(proxies)?;
        let posed = pose(model, skinning, skinning_len, &mut frame.proxies);
        if posed.is_err() {
            // The core unsets a frame it fails to pose; so do the checks before it.
            frame.proxies = ProxyFrame::new();
        }
        posed
    })
}

fn pose(
    model: *const aprt_model,
    skinning: *const f32,
    skinning_len: usize,
    proxies: &mut ProxyFrame,
) -> Result<(), aprt_status> {
    let skinning = ffi_ptr::skinning(skinning, skinning_len)?;
    with_model(model, |m| Ok(m.pose_proxies(skinning, proxies)?))
}

/// Subtracts from `out` (the `aprt_shade` output of vertices `first .. first + count`, in
/// place) what the posed `proxies` block under the world SH `lighting` (`lighting_len` =
/// `info.coeffs` floats, as given to `aprt_light_sh`): `out_j −= Σ_c L_c D_jc`. `positions`
/// and `normals` hold `count` triples each (3 · `count` floats): the vertices' posed world
/// positions (the units of the skinning translations) and normals (any length; a zero normal
/// sees no proxy), i.e. the caller's skinned mesh. Any range works, as for `aprt_shade`.
///
/// `APRT_STATUS_NO_PROXIES` when the model has none; `APRT_STATUS_WEIGHTS_NOT_SET` before
/// `aprt_pose_proxies` (or after one that failed); `APRT_STATUS_WEIGHTS_FOR_OTHER_MODEL` for
/// proxies posed by another model; `APRT_STATUS_WRONG_LENGTH`, `APRT_STATUS_VERTEX_RANGE`,
/// `APRT_STATUS_NON_FINITE_LIGHTING`, `APRT_STATUS_NON_FINITE_POSITION` and
/// `APRT_STATUS_NON_FINITE_NORMAL` for bad inputs (`out` is then unchanged);
/// `APRT_STATUS_OVERFLOW` when inputs too large overflowed it (`out` is then 0).
#[allow(clippy::too_many_arguments)]
#[unsafe(no_mangle)]
pub extern "C" fn aprt_occlude(
    model: *const aprt_model,
    proxies: *const aprt_proxy_frame,
    lighting: *const f32,
    lighting_len: usize,
    positions: *const f32,
    normals: *const f32,
    first: usize,
    out: *mut f32,
    count: usize,
) -> aprt_status {
    guard(|| {
        let lighting = ffi_ptr::slice(lighting, lighting_len)?;
        let vertices = ffi_ptr::past_vertices;
        let positions = ffi_ptr::triples(positions, count).map_err(vertices)?;
        let normals = ffi_ptr::triples(normals, count).map_err(vertices)?;
        let out = ffi_ptr::slice_mut(out, count).map_err(vertices)?;
        let frame = &ffi_ptr::handle(proxies)?.proxies;
        with_model(model, |m| {
            if !m.info().has_proxies() {
                return Err(aprt_status::NoProxies);
            }
            Ok(m.occlude(frame, lighting, positions, normals, first, out)?)
        })
    })
}

/// Subtracts the posed `proxies`' occlusion `D_j` from `out` (the `aprt_transfer` output of
/// vertices `first .. first + count`, in place: `out_len` = `count` · `info.coeffs` floats,
/// vertex-major), in each vertex's bone frame for a bone-frame model: `bones` holds
/// `bone_count` = `info.bones` rotations (9 floats each, row-major, as for `aprt_light_sh`);
/// a world-frame model takes `NULL, 0`. `positions` and `normals` are as for `aprt_occlude`
/// (`count` triples each).
///
/// `APRT_STATUS_NO_PROXIES` when the model has none; `APRT_STATUS_WEIGHTS_NOT_SET` before
/// `aprt_pose_proxies`; `APRT_STATUS_WEIGHTS_FOR_OTHER_MODEL` for proxies posed by another
/// model; `APRT_STATUS_BAD_ROTATION` for a matrix that is not a proper rotation;
/// `APRT_STATUS_WRONG_LENGTH` (`out_len`, `bone_count`), `APRT_STATUS_VERTEX_RANGE`,
/// `APRT_STATUS_NON_FINITE_POSITION` and `APRT_STATUS_NON_FINITE_NORMAL` for bad inputs.
#[allow(clippy::too_many_arguments)]
#[unsafe(no_mangle)]
pub extern "C" fn aprt_occlude_transfer(
    model: *const aprt_model,
    proxies: *const aprt_proxy_frame,
    bones: *const f32,
    bone_count: usize,
    positions: *const f32,
    normals: *const f32,
    first: usize,
    count: usize,
    out: *mut f32,
    out_len: usize,
) -> aprt_status {
    guard(|| {
        let bones = ffi_ptr::matrices(bones, bone_count)?;
        let vertices = ffi_ptr::past_vertices;
        let positions = ffi_ptr::triples(positions, count).map_err(vertices)?;
        let normals = ffi_ptr::triples(normals, count).map_err(vertices)?;
        let out = ffi_ptr::slice_mut(out, out_len).map_err(vertices)?;
        let frame = &ffi_ptr::handle(proxies)?.proxies;
        with_model(model, |m| {
            if !m.info().has_proxies() {
                return Err(aprt_status::NoProxies);
            }
            Ok(m.occlude_transfer(frame, bones, positions, normals, first, out)?)
        })
    })
}
