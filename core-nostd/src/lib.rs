//! aprt-core: the `no_std`, allocation-free runtime of aprt.
//!
//! It reads a model blob written by the trainer (from a byte slice, or streamed from any
//! [`BlobSource`] through a caller-owned buffer) and turns joint angles and an SH lighting
//! vector into per-vertex shading or transfer. Every entry point returns a `Result`; no input
//! makes it panic, allocate, or read out of bounds.
#![no_std]
#![forbid(unsafe_code)]

pub mod math;
pub mod sh;
