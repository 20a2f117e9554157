//! Lights at the boundary: the `#[repr(C)]` light, checked and converted to the core's
//! [`Light`] on entry, the per-vertex lights of a frame, and the SH projections a C caller
//! needs to build its own lighting vectors.
// `#[unsafe(no_mangle)]` is the only unsafe here (exported names must be unique); every
// unsafe operation lives in `ffi_ptr`, which `tests/unsafe_confined.rs` checks.
#![allow(unsafe_code)]

use aprt_core::{
    DirectionalLight, Light, LightError, PointLight, ShError, SphereLight, project_directional,
};

use crate::ffi_ptr;
use crate::frame::aprt_frame;
use crate::model::{LightSet, Range, aprt_model, check_bone_count, with_model};
use crate::status::{aprt_status, guard};

/// A sphere of uniform emitted radiance: `position`, `radius` > 0, `colour` = radiance.
pub const APRT_LIGHT_SPHERE: u32 = 1;
/// A point light: `position`, `colour` = radiant intensity (irradiance I / d² at distance d),
/// a sphere of radius 1e-3 of that intensity, so its light stays finite as a surface reaches
/// it (at most I / 1e-6, at d = 0).
pub const APRT_LIGHT_POINT: u32 = 2;
/// A light at infinity: `direction` towards the light, `colour` = irradiance at normal
/// incidence.
pub const APRT_LIGHT_DIRECTIONAL: u32 = 3;
/// Most lights one call takes (the library converts them on the stack, allocating nothing).
/// `aprt_shade_lights` adds, so more lights take several calls.
pub const APRT_MAX_LIGHTS: usize = 64;

/// One light. `kind` is one of `APRT_LIGHT_*` (checked: anything else is
/// `APRT_STATUS_BAD_LIGHT_KIND`); the fields a kind does not use are ignored. Values are
/// checked by the core: non-finite, negative or zero-length ones give `APRT_STATUS_BAD_LIGHT`.
#[allow(non_camel_case_types)]
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct aprt_light {
    /// `APRT_LIGHT_SPHERE`, `APRT_LIGHT_POINT` or `APRT_LIGHT_DIRECTIONAL`.
    pub kind: u32,
    /// Centre of a sphere, position of a point light (world space).
    pub position: [f32; 3],
    /// Towards a directional light (any non-zero length).
    pub direction: [f32; 3],
    /// Radius of a sphere light.
    pub radius: f32,
    /// Linear RGB: radiance (sphere), intensity (point) or irradiance (directional).
    pub colour: [f32; 3],
}

/// The core's light for `l`, or `BadLightKind`.
pub(crate) fn to_core(l: &aprt_light) -> Result<Light, aprt_status> {
    Ok(match l.kind {
        APRT_LIGHT_SPHERE => Light::Sphere(SphereLight {
            position: l.position,
            radius: l.radius,
            radiance: l.colour,
        }),
        APRT_LIGHT_POINT => Light::Point(PointLight {
            position: l.position,
            intensity: l.colour,
        }),
        APRT_LIGHT_DIRECTIONAL => Light::Directional(DirectionalLight {
            direction: l.direction,
            irradiance: l.colour,
        }),
        _ => return Err(aprt_status::BadLightKind),
    })
}

/// The status of a light count no buffer can hold: more than [`APRT_MAX_LIGHTS`].
pub(crate) fn too_many(status: aprt_status) -> aprt_status {
    match status {
        aprt_status::WrongLength => aprt_status::TooManyLights,
        other => other,
    }
}

/// The status of a failed SH projection: an order outside 1..=6 is a bad dimension, as the
/// light maps call it, a short output a short buffer, and the rest a bad light.
fn sh_status(e: ShError) -> aprt_status {
    match e {
        ShError::BadOrder => aprt_status::BadDimension,
        ShError::OutputTooSmall => aprt_status::BufferTooSmall,
        _ => aprt_status::BadLight,
    }
}

/// Up to [`APRT_MAX_LIGHTS`] converted lights, on the stack.
pub(crate) struct Lights {
    buf: [Light; APRT_MAX_LIGHTS],
    len: usize,
}

impl Lights {
    /// Converts the caller's lights (after every pointer of the call is checked, so a NULL is
    /// reported before a bad kind).
    pub(crate) fn convert(given: &[aprt_light]) -> Result<Lights, aprt_status> {
        if given.len() > APRT_MAX_LIGHTS {
            return Err(aprt_status::TooManyLights);
        }
        let dark = Light::Directional(DirectionalLight {
            direction: [0.0, 0.0, 1.0],
            irradiance: [0.0; 3],
        });
        let mut lights = Lights {
            buf: [dark; APRT_MAX_LIGHTS],
            len: given.len(),
        };
        for (slot, l) in lights.buf.iter_mut().zip(given) {
            *slot = to_core(l)?;
        }
        Ok(lights)
    }

    pub(crate) fn as_slice(&self) -> &[Light] {
        &self.buf[..self.len]
    }
}

/// Adds (`+=`) to `out_rgb` (`count` RGB triples) the shading of vertices `first .. first +
/// count` under `lights`, each evaluated at the vertex's own world position (`positions`,
/// `count` triples, skinned by the caller) and scaled by its weight (`weights`, one per light;
/// 1 for all of it, `1 − aprt_rig_share` when a rig carries the rest), through the vertex's
/// posed transfer: lights near the character stay self-shadowed. `bones` as in `aprt_light_sh`.
/// Needs `aprt_set_pose` first (not `aprt_light_sh`). Everything is checked before anything is
/// written, but for `APRT_STATUS_OVERFLOW`, found in the sums (the outputs are then 0).
#[allow(clippy::too_many_arguments)]
#[unsafe(no_mangle)]
pub extern "C" fn aprt_shade_lights(
    model: *const aprt_model,
    frame: *const aprt_frame,
    bones: *const f32,
    bone_count: usize,
    lights: *const aprt_light,
    weights: *const f32,
    light_count: usize,
    positions: *const f32,
    first: usize,
    out_rgb: *mut f32,
    count: usize,
) -> aprt_status {
    guard(|| {
        let bones = ffi_ptr::matrices(bones, bone_count)?;
        let lights = ffi_ptr::slice(lights, light_count).map_err(too_many)?;
        let weights = ffi_ptr::slice(weights, light_count).map_err(too_many)?;
        let range = Range::from_c(positions, first, out_rgb, count)?;
        let frame = ffi_ptr::handle(frame)?;
        let set = Lights::convert(lights)?;
        let light_set = LightSet {
            bones,
            lights: set.as_slice(),
            weights,
        };
        with_model(model, |m| {
            check_bone_count(m, bones)?;
            Ok(m.shade_lights(&frame.pose, &light_set, range)?)
        })
    })
}

/// Writes to `out` (`out_len` ≥ order² floats; the first order² are written) the SH
/// projection of a directional light of `intensity` from `direction` (3 floats, towards the
/// light, any non-zero length): a lighting vector for `aprt_light_sh`. `order` is 1..=6
/// (`APRT_STATUS_BAD_DIMENSION`); a shorter `out` is `APRT_STATUS_BUFFER_TOO_SMALL`; a zero
/// or non-finite direction, or an intensity that is negative, NaN, infinite or so large
/// that the projection overflows, `APRT_STATUS_BAD_LIGHT`.
#[unsafe(no_mangle)]
pub extern "C" fn aprt_project_directional(
    order: u32,
    direction: *const f32,
    intensity: f32,
    out: *mut f32,
    out_len: usize,
) -> aprt_status {
    guard(|| {
        let direction = ffi_ptr::read(direction.cast::<[f32; 3]>())?;
        let out = ffi_ptr::slice_mut(out, out_len)?;
        project_directional(order as usize, direction, intensity, out).map_err(sh_status)
    })
}

/// Adds (`+=`) to `out_rgb` (`coeffs` RGB triples, `coeffs` = order², order 1..=6) the RGB
/// SH radiance of `light` as seen from the world point `at` (3 floats): with
/// `aprt_project_directional`, how a C caller builds an environment for `aprt_light_sh`,
/// `aprt_rig_vectors` or the light maps. Nothing is written on an error: `BAD_LIGHT` for an
/// invalid light or `at`, or a sum that overflows; an order or `coeffs` as in
/// `aprt_project_directional`.
#[unsafe(no_mangle)]
pub extern "C" fn aprt_light_radiance_sh(
    light: *const aprt_light,
    order: u32,
    at: *const f32,
    out_rgb: *mut f32,
    coeffs: usize,
) -> aprt_status {
    guard(|| {
        let light = ffi_ptr::read(light)?;
        let at = ffi_ptr::read(at.cast::<[f32; 3]>())?;
        let out = ffi_ptr::triples_mut(out_rgb, coeffs)?;
        to_core(&light)?
            .add_radiance_sh(order as usize, at, out)
            .map_err(|e| match e {
                LightError::Sh(e) => sh_status(e),
                _ => aprt_status::BadLight,
            })
    })
}
