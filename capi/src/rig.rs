//! The irradiance rig of a model (*Irradiance Rigs*): the rig's K SH vectors from the frame's
//! lights, the share of each light the rig should carry, and rig-lit shading through the
//! frame's pose. The rig lighting weights live in a buffer the caller lends to the frame
//! (`info.rig_lit_len` floats), since for a large rig they are too big for a fixed frame.
// `#[unsafe(no_mangle)]` is the only unsafe here (exported names must be unique); every
// unsafe operation lives in `ffi_ptr`, which `tests/unsafe_confined.rs` checks.
#![allow(unsafe_code)]

use aprt_core::{Placement, RigLitWeights};

use crate::ffi_ptr;
use crate::frame::aprt_frame;
use crate::lights::{Lights, aprt_light, to_core, too_many};
use crate::model::{Range, aprt_model, check_bone_count, with_model};
use crate::status::{aprt_status, guard};

/// Where the character's root frame is in the world this frame: `world = rotation · p +
/// translation`, the rotation row-major and a proper rotation (orthonormal within 1e-3, not
/// mirrored: `APRT_STATUS_BAD_ROTATION` otherwise), the translation finite
/// (`APRT_STATUS_NON_FINITE_POSITION`).
#[allow(non_camel_case_types)]
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct aprt_placement {
    /// Root → world rotation, row-major.
    pub rotation: [[f32; 3]; 3],
    /// The root's origin in the world.
    pub translation: [f32; 3],
}

/// The caller's placement, checked: the core takes one on trust, and a NaN, scaled or
/// mirrored one would place the rig's lighting wrongly without a word.
pub(crate) fn read_placement(p: *const aprt_placement) -> Result<Placement, aprt_status> {
    let p = ffi_ptr::read(p)?;
    if !is_rotation(&p.rotation) {
        return Err(aprt_status::BadRotation);
    }
    if !p.translation.iter().all(|t| t.is_finite()) {
        return Err(aprt_status::NonFinitePosition);
    }
    Ok(Placement {
        rotation: p.rotation,
        translation: p.translation,
    })
}

/// Whether `r` is a proper rotation: columns unit and orthogonal within 1e-3 (the core's
/// tolerance for bone rotations) and a positive determinant. NaN fails every comparison.
fn is_rotation(r: &[[f32; 3]; 3]) -> bool {
    let col = |j: usize| [r[0][j], r[1][j], r[2][j]];
    let dot = |a: [f32; 3], b: [f32; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let unit = |i: usize, j: usize| if i == j { 1.0 } else { 0.0 };
    let orthonormal =
        (0..3).all(|i| (0..3).all(|j| (dot(col(i), col(j)) - unit(i, j)).abs() <= 1e-3));
    let [a, b, c] = [col(0), col(1), col(2)];
    let cross = [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ];
    orthonormal && dot(cross, c) > 0.0
}

/// Writes the model's rig vectors for this frame to `out_rgb` (`out_count` RGB triples, at
/// least `info.rig_vectors · info.coeffs`, vector-major): `lights` (`light_count`) projected
/// at the rig's sample points, placed by `placement`, plus a uniform `environment`
/// (`env_coeffs` = `info.coeffs` RGB triples of SH radiance, or `NULL, 0`). What an engine
/// computes once per frame, for `aprt_light_rig` or a shader. `APRT_STATUS_NO_IRRADIANCE_RIG`
/// when the model has none.
#[allow(clippy::too_many_arguments)]
#[unsafe(no_mangle)]
pub extern "C" fn aprt_rig_vectors(
    model: *const aprt_model,
    placement: *const aprt_placement,
    lights: *const aprt_light,
    light_count: usize,
    environment: *const f32,
    env_coeffs: usize,
    out_rgb: *mut f32,
    out_count: usize,
) -> aprt_status {
    guard(|| {
        let place = read_placement(placement)?;
        let lights = ffi_ptr::slice(lights, light_count).map_err(too_many)?;
        let environment = ffi_ptr::triples(environment, env_coeffs)?;
        let out = ffi_ptr::triples_mut(out_rgb, out_count)?;
        with_model(model, |m| {
            let lights = Lights::convert(lights)?;
            let rig = m.rig().ok_or(aprt_status::NoIrradianceRig)?;
            let order = m.info().order();
            Ok(rig.vectors_from_lights(order, &place, lights.as_slice(), environment, out)?)
        })
    })
}

/// Writes to `*share` the share of `light` the model's rig should carry, 0 (per vertex,
/// `aprt_shade_lights`) to 1 (the rig), for the character at `placement`: 0 nearer than the
/// distance where the rig's error exceeds `target` grey levels, 1 beyond `(1 + band)` times
/// it, linear between so nothing pops (the core's `IrradianceRig::share_of`; 0.25 is the
/// default band). Directional lights are always 1. `APRT_STATUS_BAD_LIGHT` for an invalid
/// light, `APRT_STATUS_BAD_LIGHT_WEIGHT` for a `target` or `band` that is negative, NaN or
/// infinite.
#[unsafe(no_mangle)]
pub extern "C" fn aprt_rig_share(
    model: *const aprt_model,
    light: *const aprt_light,
    placement: *const aprt_placement,
    target: f32,
    band: f32,
    share: *mut f32,
) -> aprt_status {
    guard(|| {
        ffi_ptr::write(share, 0.0)?;
        let light = ffi_ptr::read(light)?;
        let place = read_placement(placement)?;
        let s = with_model(model, |m| {
            let light = to_core(&light)?;
            light.validate().map_err(|_| aprt_status::BadLight)?;
            let fine = |x: f32| x >= 0.0 && x.is_finite();
            if !fine(target) || !fine(band) {
                return Err(aprt_status::BadLightWeight);
            }
            let rig = m.rig().ok_or(aprt_status::NoIrradianceRig)?;
            Ok(rig.share_of(&light, &place, target, band))
        })?;
        ffi_ptr::write(share, s)
    })
}

/// Pushes the rig's vectors (`vectors_rgb`, `vector_count` RGB triples from
/// `aprt_rig_vectors`) through the frame's pose, per colour channel, into `buffer`
/// (`buffer_len` ≥ `info.rig_lit_len` floats), which the frame keeps: `buffer` must stay
/// valid and untouched until the frame's next `aprt_set_pose` or `aprt_light_rig` (or its
/// last use). `bones` as in `aprt_light_sh`.
#[allow(clippy::too_many_arguments)]
#[unsafe(no_mangle)]
pub extern "C" fn aprt_light_rig(
    model: *const aprt_model,
    frame: *mut aprt_frame,
    vectors_rgb: *const f32,
    vector_count: usize,
    bones: *const f32,
    bone_count: usize,
    buffer: *mut f32,
    buffer_len: usize,
) -> aprt_status {
    guard(|| {
        let vectors = ffi_ptr::triples(vectors_rgb, vector_count)?;
        let bones = ffi_ptr::matrices(bones, bone_count)?;
        let frame = ffi_ptr::handle_mut(frame)?;
        // The frame lets go of the last buffer before this one (maybe the same) is lent.
        frame.rig = None;
        let buffer = ffi_ptr::slice_mut(buffer, buffer_len)?;
        let mut lit = RigLitWeights::new(buffer);
        with_model(model, |m| {
            check_bone_count(m, bones)?;
            Ok(m.light_rig(&frame.pose, vectors, bones, &mut lit)?)
        })?;
        frame.rig = Some(lit);
        Ok(())
    })
}

/// Writes to `out_rgb` (`count` RGB triples) the rig-lit shading of vertices
/// `first .. first + count`: each vertex's transfer under the rig's lighting at its own world position
/// (`positions`, `count` triples), `placement` as given to `aprt_rig_vectors`. Needs
/// `aprt_light_rig` first (`APRT_STATUS_WEIGHTS_NOT_SET`). Add `aprt_shade_lights` for the
/// lights' per-vertex shares.
#[unsafe(no_mangle)]
pub extern "C" fn aprt_shade_rig(
    model: *const aprt_model,
    frame: *const aprt_frame,
    placement: *const aprt_placement,
    positions: *const f32,
    first: usize,
    out_rgb: *mut f32,
    count: usize,
) -> aprt_status {
    guard(|| {
        let place = read_placement(placement)?;
        let range = Range::from_c(positions, first, out_rgb, count)?;
        let frame = ffi_ptr::handle(frame)?;
        with_model(model, |m| {
            let lit = frame.rig.as_ref().ok_or(aprt_status::WeightsNotSet)?;
            Ok(m.shade_rig(lit, &place, range)?)
        })
    })
}
