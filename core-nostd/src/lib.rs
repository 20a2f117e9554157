//! aprt-core: the `no_std`, allocation-free runtime of aprt.
//!
//! It reads a model blob written by the trainer and, every frame, turns a pose vector and an
//! SH lighting vector into per-vertex shading or transfer (Nowrouzezahrai et al., *Compact
//! and Efficient Generation of Radiance Transfer for Dynamically Articulated Characters*).
//! Every entry point returns a `Result`; no input makes it panic, allocate, or read out of
//! bounds, and all state is caller-owned and fixed-size.
//!
//! - [`Model`] holds a resident blob and reads it in place; [`StreamedModel`] reads any
//!   [`BlobSource`] (flash, a file) through a caller's buffer. Both validate the whole blob
//!   once and have the same per-frame calls.
//! - A frame is [`Model::set_pose`] (the pose vector, see there for its exact contract),
//!   [`Model::light`] (SH lighting, and the bones' rotations for a bone-frame model), then
//!   [`Model::shade`] or [`Model::transfer`] over any vertex range.
//! - [`PoseWeights`] and [`LitWeights`] carry a frame's state; their `const fn new` lets them
//!   live in a `static`, and their capacity parameter sizes them for the models you load.
//! - The SH convention (real, orthonormal, `c = l² + l + m`, no Condon–Shortley phase, z up)
//!   is stated once, at [`eval_basis`]; [`project_directional`] and [`clamped_cosine`] project
//!   lights, [`ShRotation`] rotates SH vectors.
//! - [`Light`] (sphere, point, directional) projects into RGB SH radiance with its gradient,
//!   and gives the exact unshadowed irradiance the SH path ([`irradiance_sh`]) is judged by.
//! - [`LightMap`] composes SH light maps (n² transfer coefficients per texel) under any
//!   lighting, a chunk of texels at a time; a light-map model's [`TexelAtlas`] places its rows
//!   in the map.
//!
//! ```
//! use aprt_core::{LitWeights, Model, PoseWeights, project_directional};
//!
//! let blob: &[u8] = include_bytes!("../../fixtures/golden/v1-world.aprt");
//! let model = Model::parse(blob)?; // validates header, sections, CRCs, values, once
//! let info = *model.info();
//!
//! // Per frame: pose, lighting, shading. The state can live anywhere, a `static` included.
//! let (mut pose, mut lit) = (PoseWeights::new(), LitWeights::new());
//! let mut lighting = [0.0; 9];
//! project_directional(info.order(), [0.5, -0.8, 0.9], 3.0, &mut lighting)?;
//! model.set_pose(&[0.1, -0.2, 0.3, 0.0], &mut pose)?;
//! model.light(&pose, &lighting[..info.coeffs()], &[], &mut lit)?;
//! let mut shading = vec![0.0; info.vertices()];
//! model.shade(&lit, 0, &mut shading)?;
//! # Ok::<(), Box<dyn core::error::Error>>(())
//! ```
//!
//! The `format` feature adds `aprt_core::format`: the byte layout, for blob writers and tools.
#![no_std]
#![deny(unsafe_code)]

mod blob;
mod eval;
mod irradiance_rig;
mod lanes;
mod light;
mod lightmap;
mod math;
mod model;
mod proxies;
mod rotation;
mod sh;
#[cfg(test)]
mod test_values;

pub use blob::format::{
    Basis, Encoding, Frame, MAX_BONES, MAX_COEF_DIMS, MAX_LIT, MAX_POSE_DIMS, MAX_POSE_LEN,
    MAX_VERTICES, SectionKind, VERSION as FORMAT_VERSION, VERTEX_BLOCK,
};
pub use blob::{
    AngleNames, BlobSource, Dim, Error, Input, MAX_ATLAS_RESOLUTION, MAX_ATLAS_TRIANGLES,
    ModelInfo, SourceError, TexelAtlas,
};
pub use eval::{
    LitWeights, MAX_POSE_WEIGHTS, PoseWeights, ProxyView, VertexRows, use_portable_kernels,
};
pub use irradiance_rig::{
    AxisKind, DEFAULT_BAND, IrradianceRig, MAX_LATTICE, MAX_RIG_SAMPLES, MAX_RIG_TABLE,
    MAX_RIG_VECTORS, Placement, RIG_SUPPORT, RigLayout, RigLitWeights, RigShape, RigWeights,
    light_strength,
};
pub use light::{
    DERIVATIVE_COS2_FLOOR, DirectionalLight, GRADIENT_STEP, Light, LightError, LightShape,
    POINT_LIGHT_RADIUS, PointLight, Rgb, SphereLight, Window, apply_window, irradiance_sh,
    sphere_light_bands, sphere_light_derivative_bands,
};
pub use lightmap::LightMap;
pub use model::{Model, StreamNeeds, StreamedModel};
pub use proxies::{MAX_PROXIES, ProxyFrame, ProxySet, Skinning};
pub use rotation::{Rotation, ShRotation};
pub use sh::{
    CLAMPED_COSINE_BANDS, MAX_COEFFS, MAX_ORDER, ShError, band_of, clamped_cosine, coeff_count,
    eval_basis, project_directional, rotate_zonal,
};

/// The blob's byte layout, for writers and tools (the trainer's writer, `aprt inspect`, the
/// tests' independent decoder): the preamble, the postcard [`Header`](format::Header) and its
/// section table. See `FORMAT.md`. Engines need none of it.
#[cfg(feature = "format")]
pub mod format {
    pub use crate::blob::format::{
        Header, MAGIC, MAX_HEADER_LEN, MAX_SECTIONS, PREAMBLE_LEN, SECTION_ALIGN, SectionEntry,
        align_up, crc32, padded_vertices,
    };
    pub use crate::blob::read_header;
    pub use crate::proxies::{
        BONE_RECORD as PROXY_BONE_RECORD, PRELUDE as PROXY_PRELUDE, PROXY_RECORD, proxies_len,
    };
}

#[cfg(doctest)]
#[doc = include_str!("../../README.md")]
struct ReadmeDoctests;

#[cfg(doctest)]
#[doc = include_str!("../../docs/guide/core-api.md")]
struct GuideCoreApiDoctests;
