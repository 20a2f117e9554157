//! SH light maps (Xu, Pattanaik and Hughes): decoded per-texel transfer (`info.coeffs` floats
//! per texel, texel-major, e.g. `aprt_transfer` output of a light-map model) composed into
//! RGB under one lighting, under per-texel lights, or under the model's irradiance rig, a
//! chunk of texels at a time. Nothing is kept between calls.
// `#[unsafe(no_mangle)]` is the only unsafe here (exported names must be unique); every
// unsafe operation lives in `ffi_ptr`, which `tests/unsafe_confined.rs` checks.
#![allow(unsafe_code)]

use aprt_core::LightMap;

use crate::ffi_ptr;
use crate::lights::{Lights, aprt_light, too_many};
use crate::model::{aprt_model, with_model};
use crate::rig::{aprt_placement, read_placement};
use crate::status::{aprt_status, guard};

/// Writes `out_rgb[t] = Σ_c lighting[c] · maps[t · n² + c]` for `texels` texels: `maps` holds
/// `maps_len` = texels · order² floats, `lighting_rgb` `coeffs` = order² RGB triples, `order`
/// 1..=6. A texel whose transfer equals a vertex's composes to that vertex's shading.
#[unsafe(no_mangle)]
pub extern "C" fn aprt_lightmap_compose(
    order: u32,
    maps: *const f32,
    maps_len: usize,
    lighting_rgb: *const f32,
    coeffs: usize,
    out_rgb: *mut f32,
    texels: usize,
) -> aprt_status {
    guard(|| {
        let maps = ffi_ptr::slice(maps, maps_len)?;
        let lighting = ffi_ptr::triples(lighting_rgb, coeffs)?;
        let out = ffi_ptr::triples_mut(out_rgb, texels)?;
        Ok(LightMap::new(order as usize)?.compose(maps, lighting, out)?)
    })
}

/// As `aprt_lightmap_compose`, each texel lit by `lights` (`light_count`) seen from its own
/// world position (`positions`, `texels` triples) plus a uniform `environment`
/// (`env_coeffs` = order² RGB triples, or `NULL, 0`): the exact per-texel path for lights
/// near the character.
#[allow(clippy::too_many_arguments)]
#[unsafe(no_mangle)]
pub extern "C" fn aprt_lightmap_compose_lights(
    order: u32,
    maps: *const f32,
    maps_len: usize,
    positions: *const f32,
    lights: *const aprt_light,
    light_count: usize,
    environment: *const f32,
    env_coeffs: usize,
    out_rgb: *mut f32,
    texels: usize,
) -> aprt_status {
    guard(|| {
        let maps = ffi_ptr::slice(maps, maps_len)?;
        let positions = ffi_ptr::triples(positions, texels)?;
        let lights = ffi_ptr::slice(lights, light_count).map_err(too_many)?;
        let environment = ffi_ptr::triples(environment, env_coeffs)?;
        let out = ffi_ptr::triples_mut(out_rgb, texels)?;
        let lights = Lights::convert(lights)?;
        let map = LightMap::new(order as usize)?;
        Ok(map.compose_lights(maps, positions, lights.as_slice(), environment, out)?)
    })
}

/// As `aprt_lightmap_compose`, each texel lit by the model's irradiance rig at its own world
/// position (`positions`, `texels` triples): `vectors_rgb` (`vector_count` triples) from
/// `aprt_rig_vectors` with the same `placement`. The order is the model's.
#[allow(clippy::too_many_arguments)]
#[unsafe(no_mangle)]
pub extern "C" fn aprt_lightmap_compose_rig(
    model: *const aprt_model,
    maps: *const f32,
    maps_len: usize,
    vectors_rgb: *const f32,
    vector_count: usize,
    placement: *const aprt_placement,
    positions: *const f32,
    out_rgb: *mut f32,
    texels: usize,
) -> aprt_status {
    guard(|| {
        let maps = ffi_ptr::slice(maps, maps_len)?;
        let vectors = ffi_ptr::triples(vectors_rgb, vector_count)?;
        let place = read_placement(placement)?;
        let positions = ffi_ptr::triples(positions, texels)?;
        let out = ffi_ptr::triples_mut(out_rgb, texels)?;
        with_model(model, |m| {
            let rig = m.rig().ok_or(aprt_status::NoIrradianceRig)?;
            let map = LightMap::new(m.info().order())?;
            Ok(map.compose_rig(maps, &rig, vectors, &place, positions, out)?)
        })
    })
}
