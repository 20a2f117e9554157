//! aprt-core in a web page: the core compiled to `wasm32-unknown-unknown` with raw `extern
//! "C"` exports and no allocator, for the hand-written `web/aprt.js`.
//!
//! The core allocates nothing, so neither does this crate: a model's blob, the pose, the
//! bones' rotations, the lighting, the shading and, for occluder proxies, the skinning
//! matrices and the posed mesh live in fixed-size `static` buffers that JavaScript reads and
//! writes through exported pointers ([`exports`]). The per-frame logic is [`Session`], safe
//! and unit-tested on the host; only the statics and the exports that hand out their
//! addresses are unsafe. Without wasm-bindgen the module stays small (its
//! bytes are in `docs/results/web.md`).
#![no_std]

// On the host the cdylib needs a panic handler and the tests a harness: std provides both.
// The code itself uses `core` only, as on wasm32.
#[cfg(not(target_arch = "wasm32"))]
extern crate std;

pub mod exports;
mod session;

pub use session::{BLOB_CAPACITY, MAX_SHADED, RowsLayout, Session, add_directional};

/// On wasm32 a panic (which the core never raises: every call returns a `Result`) traps.
#[cfg(all(target_arch = "wasm32", not(test)))]
#[panic_handler]
fn panic(_: &core::panic::PanicInfo<'_>) -> ! {
    core::arch::wasm32::unreachable()
}
