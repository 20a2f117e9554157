//! The frame handle: one character's per-frame state (pose weights, lighting weights, and the
//! rig lighting weights over a buffer the caller lends), in the caller's storage, and the
//! steps of a frame that fill and read it: pose, SH lighting, shading or transfer.
//!
//! A frame holds any model's weights (the core's largest capacities, about 82 KiB), so one
//! frame size serves every model; it records which model filled it, and a step given weights
//! of another model refuses them (`APRT_STATUS_WEIGHTS_FOR_OTHER_MODEL`).
// `#[unsafe(no_mangle)]` is the only unsafe here (exported names must be unique); every
// unsafe operation lives in `ffi_ptr`, which `tests/unsafe_confined.rs` checks.
#![allow(unsafe_code)]

use std::ffi::c_void;

use aprt_core::{LitWeights, PoseWeights, RigLitWeights};

use crate::ffi_ptr::{self, Handle};
use crate::model::{aprt_model, check_bone_count, with_model};
use crate::status::{aprt_status, guard};

/// One character's per-frame state in the caller's storage. Opaque; see `aprt_frame_init`.
// `repr(C)` puts the tag first, where every handle check reads (a Rust layout put it last, so
// checking a model passed as a frame read 82 KiB past the model). `align(8)` keeps cbindgen
// from spelling out fields C cannot name: it declares the type opaque.
#[allow(non_camel_case_types)]
#[repr(C, align(8))]
pub struct aprt_frame {
    tag: u64,
    pub(crate) pose: PoseWeights,
    pub(crate) lit: LitWeights,
    /// Whether `lit` is of the current pose: `aprt_set_pose` clears it, a successful
    /// `aprt_light_sh` sets it, so `aprt_shade` never shades with the last pose's lighting.
    pub(crate) lit_current: bool,
    /// Filled by `aprt_light_rig` over the caller's buffer, read by `aprt_shade_rig`.
    pub(crate) rig: Option<RigLitWeights<'static>>,
}

impl Handle for aprt_frame {
    const TAG: u64 = u64::from_le_bytes(*b"aprtFRAM");
    const TAG_OFFSET: usize = std::mem::offset_of!(aprt_frame, tag);
}

/// Bytes of storage an `aprt_frame` needs (about 82 KiB: the weights of the largest model).
#[unsafe(no_mangle)]
pub extern "C" fn aprt_frame_size() -> usize {
    size_of::<aprt_frame>()
}

/// Alignment the storage of an `aprt_frame` needs.
#[unsafe(no_mangle)]
pub extern "C" fn aprt_frame_align() -> usize {
    align_of::<aprt_frame>()
}

/// Writes an empty frame into `storage` (`storage_len` ≥ `aprt_frame_size()` bytes, aligned
/// to `aprt_frame_align()`) and its address to `*out`. It holds no resources: free the
/// storage when done. Re-initialising it empties it.
#[unsafe(no_mangle)]
pub extern "C" fn aprt_frame_init(
    storage: *mut c_void,
    storage_len: usize,
    out: *mut *mut aprt_frame,
) -> aprt_status {
    guard(|| {
        ffi_ptr::write(out, std::ptr::null_mut())?;
        let frame = aprt_frame {
            tag: aprt_frame::TAG,
            pose: PoseWeights::new(),
            lit: LitWeights::new(),
            lit_current: false,
            rig: None,
        };
        ffi_ptr::write(out, ffi_ptr::place(storage, storage_len, frame)?)
    })
}

/// Sets the frame's pose from the pose vector `angles` (`angles_len` = `info.pose_len`
/// floats: each kept joint's rotation vector relative to its rest pose, see the core's
/// `Model::set_pose`). It drops the frame's lighting, which was pushed through the old pose:
/// `aprt_shade` returns `APRT_STATUS_WEIGHTS_NOT_SET` until `aprt_light_sh` lights the frame
/// again, even when the lighting has not changed; likewise the rig weights
/// (`aprt_light_rig` again before `aprt_shade_rig`). A failed call drops them too.
#[unsafe(no_mangle)]
pub extern "C" fn aprt_set_pose(
    model: *const aprt_model,
    frame: *mut aprt_frame,
    angles: *const f32,
    angles_len: usize,
) -> aprt_status {
    guard(|| {
        let angles = ffi_ptr::slice(angles, angles_len)?;
        let frame = ffi_ptr::handle_mut(frame)?;
        // Lighting and rig weights are of the old pose: drop them (and the buffer lent).
        frame.lit_current = false;
        frame.rig = None;
        with_model(model, |m| Ok(m.set_pose(angles, &mut frame.pose)?))
    })
}

/// Lights the posed frame with the world SH radiance `lighting` (`lighting_len` =
/// `info.coeffs` floats, real orthonormal SH, `c = l² + l + m`, z up). A bone-frame model needs
/// `bone_count` = `info.bones` rotations in `bones` (9 floats each, row-major: the rotation of
/// each bone's skinning matrix `world · inverse_bind`); a world-frame model takes `NULL, 0`.
/// Light again after every `aprt_set_pose`; a failed call leaves the frame unlit.
#[unsafe(no_mangle)]
pub extern "C" fn aprt_light_sh(
    model: *const aprt_model,
    frame: *mut aprt_frame,
    lighting: *const f32,
    lighting_len: usize,
    bones: *const f32,
    bone_count: usize,
) -> aprt_status {
    guard(|| {
        let lighting = ffi_ptr::slice(lighting, lighting_len)?;
        let bones = ffi_ptr::matrices(bones, bone_count)?;
        let frame = ffi_ptr::handle_mut(frame)?;
        frame.lit_current = false;
        with_model(model, |m| {
            check_bone_count(m, bones)?;
            Ok(m.light(&frame.pose, lighting, bones, &mut frame.lit)?)
        })?;
        frame.lit_current = true;
        Ok(())
    })
}

/// Writes the shading of vertices `first .. first + count` under the frame's lighting to
/// `out` (`count` floats): `Σ_c L_c t_c(j)`; multiply by albedo / π for exit radiance. Any
/// range works, so threads may shade disjoint ranges of one frame. Needs `aprt_light_sh`
/// since the frame's last `aprt_set_pose` (`APRT_STATUS_WEIGHTS_NOT_SET`).
#[unsafe(no_mangle)]
pub extern "C" fn aprt_shade(
    model: *const aprt_model,
    frame: *const aprt_frame,
    first: usize,
    out: *mut f32,
    count: usize,
) -> aprt_status {
    guard(|| {
        let out = ffi_ptr::slice_mut(out, count).map_err(ffi_ptr::past_vertices)?;
        let frame = ffi_ptr::handle(frame)?;
        with_model(model, |m| {
            if !frame.lit_current {
                return Err(aprt_status::WeightsNotSet);
            }
            Ok(m.shade(&frame.lit, first, out)?)
        })
    })
}

/// Writes the posed transfer of vertices `first ..` to `out` (`out_len` floats: `info.coeffs`
/// per vertex, vertex-major), for a GPU that does the lighting dot product. A bone-frame
/// model's transfer is in each vertex's bone frame (`aprt_vertex_bones`).
#[unsafe(no_mangle)]
pub extern "C" fn aprt_transfer(
    model: *const aprt_model,
    frame: *const aprt_frame,
    first: usize,
    out: *mut f32,
    out_len: usize,
) -> aprt_status {
    guard(|| {
        let out = ffi_ptr::slice_mut(out, out_len).map_err(ffi_ptr::past_vertices)?;
        let frame = ffi_ptr::handle(frame)?;
        with_model(model, |m| Ok(m.transfer(&frame.pose, first, out)?))
    })
}

/// Writes the bone of vertices `first .. first + count` to `out` (all 0 for a world-frame
/// model), for engines that light `aprt_transfer` output on the GPU.
#[unsafe(no_mangle)]
pub extern "C" fn aprt_vertex_bones(
    model: *const aprt_model,
    first: usize,
    out: *mut u16,
    count: usize,
) -> aprt_status {
    guard(|| {
        let out = ffi_ptr::slice_mut(out, count).map_err(ffi_ptr::past_vertices)?;
        with_model(model, |m| Ok(m.vertex_bones(first, out)?))
    })
}
