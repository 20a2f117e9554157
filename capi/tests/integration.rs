//! The C ABI's tests, one module a file, in one binary (one link instead of one a file).
//! `cargo test -p aprt-capi --release --test integration abi::` runs one file's tests.

mod common;

mod abi;
mod examples;
mod header;
mod hostile;
mod hostile_c;
mod proxies;
mod unsafe_confined;
