//! The trainer's integration tests, one module a file, in one binary: one link instead of one
//! per file, and their tests share the two cores instead of waiting for each other's file.
//! `cargo test -p aprt-trainer --release --test integration scene::` runs one file's tests.

mod common;
mod run;

mod bake_farm;
mod browser;
mod cli;
mod cli_refusals;
mod extrapolation;
mod gltf;
mod hostile_gltf;
mod hostile_inputs;
mod hostile_io;
mod hostile_limits;
mod hostile_sizes;
mod hostile_values;
mod irradiance_rig;
mod layering;
mod lightmap_uvs;
mod lights;
mod malformed;
mod mocap;
mod precision_i8;
mod proxies;
mod quality;
mod resume;
mod scene;
mod shlm;
mod simulate_surface;
mod sources;
mod surface_quad;
