//! The cross-crate tests, one module a file, in one binary: one link instead of one per file,
//! and their tests share the two cores instead of waiting for each other's file.
//! `cargo test -p aprt-tests --release --test integration golden::` runs one file's tests.

mod analytic_lights;
mod corpus;
mod doc_links;
mod golden;
mod hard_cases;
mod hostile;
mod irradiance_rig;
mod lightmap;
mod lights;
mod loaders;
mod properties;
mod proxies;
mod readers;
mod roundtrip;
