//! Occluder proxies: a few spheres per bone that move with the bones and shadow the vertices of
//! other parts. A pose-driven model learns the shadowing its training poses show; a shadow
//! that no training pose casts (a hat's brim over a raised arm) it cannot invent. The spheres
//! bring that occlusion in from geometry, as capsule shadows do in engines, and the model
//! learns only what they miss: its targets are the baked transfer plus the spheres'
//! occlusion, so that at runtime `transfer = model(pose) − occlusion(pose)`.
//!
//! Each sphere seen from a vertex is a cap of half-angle `α`, `sin α = r/d`. Its occlusion of
//! the vertex's transfer is the cap's clamped-cosine integral `F` (the horizon-clipped form
//! factor of a sphere, `π sin²α cos β` when the cap is above the horizon, within 1e-6 of the
//! exact one: its `acos` and `atan` are polynomials, `caps.rs`) spread over the
//! bands as the cosine-weighted cap's zonal harmonic `2π ∫ t P_l(t)` about the cap's centre of
//! weight (its axis moved towards the normal by the cosine's tilt, to first order):
//! `D_lm = F · ζ_l · y_lm(a')`. Band 0 is exact, and every band for a cap about the normal;
//! a tilted cap's higher bands are off by the second order of the shift (FORMAT.md). Caps of
//! one vertex overlap (neighbouring spheres of one bone do by construction), so they combine
//! by the product of their visible fractions in band 0, `1 − Π (1 − F_i / π)`, the sum of
//! their vectors scaled to it. A vertex inside a sphere is fully occluded: its `D` is the
//! clamped cosine lobe, the transfer of an unoccluded point. Every step depends only on the
//! geometry, so the correction is linear in the lighting.
//!
//! Cost grows with contacts, not bones × vertices: a cap below `cull` (in `sin²α`) is
//! dropped, faded in smoothly over `[cull, 2 cull]` so that nothing pops, and once a frame
//! each bone's bounding sphere (of the vertices it carries) is tested against each proxy's
//! reach `r / √cull`, leaving each bone a mask of the proxies that can touch it. The bone's
//! own proxies and its neighbours' are masked out in the blob: the learnt model carries them.
//! A block of eight vertices then tests each proxy of its lanes' masks against all eight at
//! once, and computes the caps of those that reach any lane together, lane-wise and
//! branch-free (`occlusion.rs`), in AVX2 where the CPU has it: the same bits on every target.

mod caps;
mod frame;
mod occlusion;
mod section;

pub use frame::{ProxyFrame, ProxySet, Skinning};
#[cfg(target_arch = "x86_64")]
pub(crate) use occlusion::occlusion_kernel;
pub(crate) use occlusion::{Block, Output, block_occlusion};
pub use section::MAX_PROXIES;
pub(crate) use section::ProxyCheck;
#[cfg(feature = "format")]
pub use section::{BONE_RECORD, PRELUDE, PROXY_RECORD, proxies_len};
