//! The raw exports `web/aprt.js` calls, over fixed-size `static` buffers.
//!
//! Why unsafe, and why only here: a wasm module without an allocator shares memory with
//! JavaScript through addresses of statics, which needs `#[unsafe(no_mangle)]` exports and
//! mutable statics (an `UnsafeCell` behind a `Sync` wrapper). It is sound because wasm32
//! runs one thread and JavaScript touches a buffer only between calls, never while a Rust
//! reference to it lives: each export borrows what it needs for the call alone, and
//! [`aprt_blob`] drops the session (the one long-lived borrow, of the blob) before handing
//! the blob's address out for writing. On the host one test drives the calling sequence as
//! `web/aprt.js` does (tests run on threads, so no other test may touch the statics).
//!
//! The calling sequence: `aprt_blob(len)` → write the blob there → `aprt_load(len)`; then
//! every frame write `aprt_angles()` (pose_len f32), `aprt_bone_rotations()` (bones × 9
//! f32, row-major) and `aprt_lighting()` (order² f32), optionally `aprt_add_directional`,
//! then `aprt_shade()` and read `aprt_shading()` (vertices f32). A model with occluder
//! proxies (`aprt_has_proxies()`) then takes `aprt_skinning()` (bones × 12 f32, 3 × 4
//! row-major), `aprt_positions()` and `aprt_normals()` (vertices × 3 f32, the posed mesh)
//! and `aprt_occlude()`, which corrects `aprt_shading()` in place. A call that fails returns
//! −1 and leaves its message at `aprt_error()` (`aprt_error_len()` bytes of UTF-8).
//!
//! A page that runs the loop over the vertices on its own device (`web/webgpu.js`, WebGPU)
//! reads `aprt_vertex_rows()` once after loading (where the rows lie in the blob, and their
//! layout), then each frame calls `aprt_light()` instead of `aprt_shade()` and multiplies the
//! lighting weights it returns by the rows; its shading, written to `aprt_shading()`, takes
//! `aprt_occlude()` as the core's does.
#![allow(unsafe_code)]

use core::cell::UnsafeCell;
use core::fmt::Write;

use aprt_core::{MAX_BONES, MAX_COEFFS, MAX_POSE_LEN, Rotation, Skinning};

use crate::session::{BLOB_CAPACITY, MAX_SHADED, RowsLayout, Session, add_directional};

/// A static JavaScript and Rust share; see the module documentation for why it is sound.
struct Shared<T>(UnsafeCell<T>);

// SAFETY: wasm32 has one thread; on the host only one test calls the exports.
unsafe impl<T> Sync for Shared<T> {}

impl<T> Shared<T> {
    const fn new(value: T) -> Self {
        Shared(UnsafeCell::new(value))
    }

    fn ptr(&self) -> *mut T {
        self.0.get()
    }

    /// The value, borrowed for one export.
    ///
    /// # Safety
    /// No other reference to it may live while this one does (module documentation).
    #[allow(clippy::mut_from_ref)]
    unsafe fn get(&self) -> &mut T {
        // SAFETY: the caller's promise.
        unsafe { &mut *self.0.get() }
    }
}

static BLOB: Shared<[u8; BLOB_CAPACITY]> = Shared::new([0; BLOB_CAPACITY]);
static SESSION: Shared<Option<Session<'static>>> = Shared::new(None);
static ANGLES: Shared<[f32; MAX_POSE_LEN]> = Shared::new([0.0; MAX_POSE_LEN]);
static BONES: Shared<[Rotation; MAX_BONES]> = Shared::new([[[0.0; 3]; 3]; MAX_BONES]);
static LIGHTING: Shared<[f32; MAX_COEFFS]> = Shared::new([0.0; MAX_COEFFS]);
static SHADING: Shared<[f32; MAX_SHADED]> = Shared::new([0.0; MAX_SHADED]);
static SKINNING: Shared<[Skinning; MAX_BONES]> = Shared::new([[0.0; 12]; MAX_BONES]);
static POSITIONS: Shared<[[f32; 3]; MAX_SHADED]> = Shared::new([[0.0; 3]; MAX_SHADED]);
static NORMALS: Shared<[[f32; 3]; MAX_SHADED]> = Shared::new([[0.0; 3]; MAX_SHADED]);
static ROWS: Shared<RowsLayout> = Shared::new(RowsLayout {
    offset: 0,
    len: 0,
    encoding: 0,
    lead_rows: 0,
    row_width: 0,
    blocks: 0,
    bones: 0,
    coeffs: 0,
    lit_len: 0,
});
static ERROR: Shared<Message> = Shared::new(Message {
    bytes: [0; 256],
    len: 0,
});

/// The last error's text, cut at 256 bytes.
struct Message {
    bytes: [u8; 256],
    len: usize,
}

impl Write for Message {
    fn write_str(&mut self, s: &str) -> core::fmt::Result {
        let room = self.bytes.len() - self.len;
        let mut take = s.len().min(room);
        while !s.is_char_boundary(take) {
            take -= 1;
        }
        self.bytes[self.len..self.len + take].copy_from_slice(&s.as_bytes()[..take]);
        self.len += take;
        Ok(())
    }
}

/// Records `err` for [`aprt_error`] and returns −1.
fn fail(err: impl core::fmt::Display) -> i32 {
    // SAFETY: no other reference to ERROR lives during an export (module docs).
    let message = unsafe { ERROR.get() };
    message.len = 0;
    let _ = write!(message, "{err}");
    -1
}

/// The session, if a model is loaded.
fn session() -> Option<&'static mut Session<'static>> {
    // SAFETY: one export runs at a time and borrows the session for its duration only.
    unsafe { SESSION.get().as_mut() }
}

/// Drops the loaded model and returns where JavaScript writes a blob of `len` bytes, or null
/// when it is larger than the buffer.
#[unsafe(no_mangle)]
pub extern "C" fn aprt_blob(len: usize) -> *mut u8 {
    // SAFETY: dropping the session ends the only borrow of BLOB before it is written.
    unsafe { *SESSION.get() = None };
    if len > BLOB_CAPACITY {
        fail(format_args!(
            "the blob's {len} bytes exceed the page's {BLOB_CAPACITY}"
        ));
        return core::ptr::null_mut();
    }
    BLOB.ptr().cast()
}

/// Validates the `len` bytes written at [`aprt_blob`] and keeps the model: 0, or −1.
#[unsafe(no_mangle)]
pub extern "C" fn aprt_load(len: usize) -> i32 {
    // SAFETY: no other reference to SESSION lives during an export; dropping it ends the
    // previous load's borrow of BLOB.
    unsafe { *SESSION.get() = None };
    // SAFETY: JavaScript has finished writing; until the next `aprt_blob` no one writes BLOB,
    // so a shared 'static borrow of it holds (made from the pointer, never through `&mut`).
    let blob: &'static [u8] =
        unsafe { core::slice::from_raw_parts(BLOB.ptr().cast::<u8>(), len.min(BLOB_CAPACITY)) };
    match Session::open(blob) {
        // SAFETY: as above.
        Ok(session) => unsafe { *SESSION.get() = Some(session) },
        Err(err) => return fail(err),
    }
    0
}

/// The loaded model's dimension picked by `pick`, 0 without a model.
fn dimension(pick: fn(&aprt_core::ModelInfo) -> usize) -> usize {
    session().map_or(0, |s| pick(s.info()))
}

/// The loaded model's vertices (0 without a model).
#[unsafe(no_mangle)]
pub extern "C" fn aprt_vertices() -> usize {
    dimension(aprt_core::ModelInfo::vertices)
}

/// The loaded model's pose-vector length.
#[unsafe(no_mangle)]
pub extern "C" fn aprt_pose_len() -> usize {
    dimension(aprt_core::ModelInfo::pose_len)
}

/// The loaded model's bones (0 for a world-frame model).
#[unsafe(no_mangle)]
pub extern "C" fn aprt_bones() -> usize {
    dimension(aprt_core::ModelInfo::bones)
}

/// The loaded model's SH order.
#[unsafe(no_mangle)]
pub extern "C" fn aprt_order() -> usize {
    dimension(aprt_core::ModelInfo::order)
}

/// 1 when the loaded model has occluder proxies ([`aprt_occlude`] after every shade), else 0.
#[unsafe(no_mangle)]
pub extern "C" fn aprt_has_proxies() -> usize {
    dimension(|info| usize::from(info.has_proxies()))
}

/// Where JavaScript writes the pose vector.
#[unsafe(no_mangle)]
pub extern "C" fn aprt_angles() -> *mut f32 {
    ANGLES.ptr().cast()
}

/// Where JavaScript writes the bones' skinning rotations, 9 f32 each, row-major.
#[unsafe(no_mangle)]
pub extern "C" fn aprt_bone_rotations() -> *mut f32 {
    BONES.ptr().cast()
}

/// Where JavaScript writes the world SH lighting (order² f32).
#[unsafe(no_mangle)]
pub extern "C" fn aprt_lighting() -> *mut f32 {
    LIGHTING.ptr().cast()
}

/// Where JavaScript writes the bones' skinning matrices, 12 f32 each (3 × 4, row-major).
#[unsafe(no_mangle)]
pub extern "C" fn aprt_skinning() -> *mut f32 {
    SKINNING.ptr().cast()
}

/// Where JavaScript writes the posed vertex positions, 3 f32 each.
#[unsafe(no_mangle)]
pub extern "C" fn aprt_positions() -> *mut f32 {
    POSITIONS.ptr().cast()
}

/// Where JavaScript writes the posed vertex normals, 3 f32 each.
#[unsafe(no_mangle)]
pub extern "C" fn aprt_normals() -> *mut f32 {
    NORMALS.ptr().cast()
}

/// Where [`aprt_shade`] leaves one value per vertex, and where a device that ran the loop
/// itself writes its shading for [`aprt_occlude`].
#[unsafe(no_mangle)]
pub extern "C" fn aprt_shading() -> *mut f32 {
    SHADING.ptr().cast()
}

/// Adds a directional light from (x, y, z) of `strength` to the lighting buffer: 0, or −1.
#[unsafe(no_mangle)]
pub extern "C" fn aprt_add_directional(x: f32, y: f32, z: f32, strength: f32) -> i32 {
    let Some(order) = session().map(|s| s.info().order()) else {
        return fail("no model is loaded");
    };
    // SAFETY: no other reference to LIGHTING lives during an export.
    let lighting = unsafe { LIGHTING.get() };
    match add_directional(order, [x, y, z], strength, lighting) {
        Ok(()) => 0,
        Err(err) => fail(err),
    }
}

/// A frame's pose vector, bones' rotations and lighting, as long as the model reads them: the
/// inputs of [`aprt_shade`] and [`aprt_light`].
///
/// # Safety
/// No other reference to ANGLES, BONES or LIGHTING may live while these do (module docs).
unsafe fn frame_inputs(
    info: &aprt_core::ModelInfo,
) -> (&'static [f32], &'static [Rotation], &'static [f32]) {
    // SAFETY: the caller's promise.
    unsafe {
        (
            &ANGLES.get()[..info.pose_len()],
            &BONES.get()[..info.bones()],
            &LIGHTING.get()[..info.coeffs()],
        )
    }
}

/// One frame through the core: set_pose, light and shade of every vertex: 0, or −1.
#[unsafe(no_mangle)]
pub extern "C" fn aprt_shade() -> i32 {
    let Some(session) = session() else {
        return fail("no model is loaded");
    };
    let info = *session.info();
    // SAFETY: the buffers are distinct statics, none borrowed elsewhere during this export.
    let ((angles, bones, lighting), shading) = unsafe { (frame_inputs(&info), SHADING.get()) };
    match session.shade(angles, lighting, bones, shading) {
        Ok(()) => 0,
        Err(err) => fail(err),
    }
}

/// The loaded model's vertex rows for a device that shades them itself: the address of nine
/// u32 ([`RowsLayout`]: their offset and length in the blob, and their layout), or null
/// without a model.
#[unsafe(no_mangle)]
pub extern "C" fn aprt_vertex_rows() -> *const u32 {
    let Some(session) = session() else {
        fail("no model is loaded");
        return core::ptr::null();
    };
    // SAFETY: no other reference to ROWS lives during an export.
    unsafe { *ROWS.get() = session.rows_layout() };
    ROWS.ptr().cast()
}

/// [`aprt_shade`] without its loop over the vertices (set_pose and light), for a device that
/// runs that loop itself: the address of the lighting weights (`lit_len` f32 of
/// [`aprt_vertex_rows`], valid until the next call), or null.
#[unsafe(no_mangle)]
pub extern "C" fn aprt_light() -> *const f32 {
    let Some(session) = session() else {
        fail("no model is loaded");
        return core::ptr::null();
    };
    let info = *session.info();
    // SAFETY: the buffers are distinct statics, none borrowed elsewhere during this export.
    let (angles, bones, lighting) = unsafe { frame_inputs(&info) };
    match session.light(angles, lighting, bones) {
        Ok(q) => q.as_ptr(),
        Err(err) => {
            fail(err);
            core::ptr::null()
        }
    }
}

/// After [`aprt_shade`], for a model with occluder proxies: poses them and subtracts what
/// they block under the same lighting from the shading: 0, or −1.
#[unsafe(no_mangle)]
pub extern "C" fn aprt_occlude() -> i32 {
    let Some(session) = session() else {
        return fail("no model is loaded");
    };
    let info = *session.info();
    // SAFETY: the buffers are distinct statics, none borrowed elsewhere during this export.
    let (skinning, lighting, positions, normals, shading) = unsafe {
        (
            &SKINNING.get()[..info.bones()],
            &LIGHTING.get()[..info.coeffs()],
            &POSITIONS.get()[..info.vertices()],
            &NORMALS.get()[..info.vertices()],
            SHADING.get(),
        )
    };
    match session.occlude(skinning, lighting, (positions, normals), shading) {
        Ok(()) => 0,
        Err(err) => fail(err),
    }
}

/// The last error's UTF-8 text.
#[unsafe(no_mangle)]
pub extern "C" fn aprt_error() -> *const u8 {
    // SAFETY: the address only; JavaScript reads it between calls.
    unsafe { ERROR.get().bytes.as_ptr() }
}

/// The length of [`aprt_error`]'s text in bytes.
#[unsafe(no_mangle)]
pub extern "C" fn aprt_error_len() -> usize {
    // SAFETY: a plain read, no borrow outlives it.
    unsafe { ERROR.get().len }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::boxed::Box;
    use std::vec;
    use std::vec::Vec;

    const BLOB: &[u8] = include_bytes!("../../../fixtures/golden/v1-bones.aprt");
    const PROXIES: &[u8] = include_bytes!("../../../fixtures/golden/v1-proxies.aprt");

    fn error_text() -> std::string::String {
        // SAFETY: the exports return the message's address and length.
        let bytes = unsafe { core::slice::from_raw_parts(aprt_error(), aprt_error_len()) };
        std::string::String::from_utf8(bytes.to_vec()).unwrap()
    }

    /// Writes `blob` where [`aprt_blob`] says and loads it, as `web/aprt.js` does.
    fn load(blob: &[u8]) -> i32 {
        let ptr = aprt_blob(blob.len());
        // SAFETY: the buffer holds BLOB_CAPACITY bytes and nothing borrows it after aprt_blob.
        unsafe { core::ptr::copy_nonoverlapping(blob.as_ptr(), ptr, blob.len()) };
        aprt_load(blob.len())
    }

    /// The `n` values [`aprt_shading`] holds.
    fn shading(n: usize) -> Vec<f32> {
        // SAFETY: the buffer holds MAX_SHADED values; no borrow is live.
        unsafe { core::slice::from_raw_parts(aprt_shading(), n) }.to_vec()
    }

    /// Copies `values` to an address an export handed out, as `web/aprt.js` does.
    fn write(ptr: *mut f32, values: &[f32]) {
        // SAFETY: every buffer holds at least what the model needs; no borrow is live.
        unsafe { core::ptr::copy_nonoverlapping(values.as_ptr(), ptr, values.len()) };
    }

    /// The one test that calls the exports: `web/aprt.js`'s sequence, its errors, and the
    /// shading equal to [`Session::shade`]'s, then [`Session::occlude`]'s for a model with
    /// occluder proxies.
    #[test]
    fn the_javascript_calling_sequence() {
        assert_eq!(aprt_shade(), -1);
        assert_eq!(error_text(), "no model is loaded");
        assert!(aprt_vertex_rows().is_null() && aprt_light().is_null());
        assert!(aprt_blob(BLOB_CAPACITY + 1).is_null());
        assert!(error_text().contains("exceed"), "{}", error_text());

        assert_eq!(load(BLOB), 0);
        assert_eq!(aprt_load(10), -1);
        assert!(error_text().contains("truncated"), "{}", error_text());
        assert_eq!(aprt_vertices(), 0);
        assert_eq!(aprt_load(BLOB.len()), 0, "{}", error_text());

        let mut session = Box::new(Session::open(BLOB).unwrap());
        let info = *session.info();
        assert_eq!(
            [aprt_vertices(), aprt_pose_len(), aprt_bones(), aprt_order()],
            [info.vertices(), info.pose_len(), info.bones(), info.order()]
        );
        let angles = vec![0.3; info.pose_len()];
        let turn = [[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]];
        let bones: Vec<[[f32; 3]; 3]> = vec![turn; info.bones()];
        let mut lighting = vec![0.2; info.coeffs()];
        write(aprt_angles(), &angles);
        write(aprt_bone_rotations(), bones.as_flattened().as_flattened());
        write(aprt_lighting(), &lighting);
        assert_eq!(aprt_add_directional(0.0, 0.0, 0.0, 1.0), -1);
        assert_eq!(aprt_add_directional(1.0, 0.0, 1.0, 2.0), 0);
        assert_eq!(aprt_shade(), 0, "{}", error_text());

        add_directional(info.order(), [1.0, 0.0, 1.0], 2.0, &mut lighting).unwrap();
        let mut expected = vec![0.0; info.vertices()];
        session
            .shade(&angles, &lighting, &bones, &mut expected)
            .unwrap();
        assert_eq!(shading(info.vertices()), expected);
        the_sequence_of_a_device(&mut session, (&angles, &lighting, &bones));
        assert_eq!(aprt_has_proxies(), 0);
        assert_eq!(aprt_occlude(), -1);
        assert!(
            error_text().contains("no occluder proxies"),
            "{}",
            error_text()
        );
        the_sequence_with_proxies();
    }

    /// `web/webgpu.js`'s calls: the rows' layout once, then each frame's lighting weights,
    /// both [`Session`]'s, with the same inputs as the frame just shaded.
    fn the_sequence_of_a_device(session: &mut Session<'_>, (angles, lighting, bones): Frame<'_>) {
        // SAFETY: the export returns the address of nine u32; no borrow is live.
        let layout = unsafe { *aprt_vertex_rows().cast::<RowsLayout>() };
        assert_eq!(layout, session.rows_layout());
        let q = aprt_light();
        assert!(!q.is_null(), "{}", error_text());
        // SAFETY: `lit_len` values at the returned address; no borrow is live.
        let q = unsafe { core::slice::from_raw_parts(q, layout.lit_len as usize) };
        assert_eq!(q, session.light(angles, lighting, bones).unwrap());
    }

    /// A frame's angles, lighting and bones' rotations.
    type Frame<'a> = (&'a [f32], &'a [f32], &'a [[[f32; 3]; 3]]);

    /// [`the_javascript_calling_sequence`] for a model with proxies: skinning matrices and
    /// the posed mesh written, then `aprt_occlude` after `aprt_shade`.
    fn the_sequence_with_proxies() {
        assert_eq!(load(PROXIES), 0, "{}", error_text());
        assert_eq!(aprt_has_proxies(), 1);
        let mut session = Box::new(Session::open(PROXIES).unwrap());
        let info = *session.info();
        let angles = vec![0.3; info.pose_len()];
        let bones = vec![[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]; info.bones()];
        let lighting = vec![0.7; info.coeffs()];
        let lift = [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.1, 0.0, 0.0, 1.0, 0.2];
        let skinning = vec![lift; info.bones()];
        let positions: Vec<[f32; 3]> = (0..info.vertices())
            .map(|j| [0.05 * j as f32 - 0.4, 0.0, 0.1])
            .collect();
        let normals = vec![[0.0, 0.6, 0.8]; info.vertices()];
        write(aprt_angles(), &angles);
        write(aprt_bone_rotations(), bones.as_flattened().as_flattened());
        write(aprt_lighting(), &lighting);
        write(aprt_skinning(), skinning.as_flattened());
        write(aprt_positions(), positions.as_flattened());
        write(aprt_normals(), normals.as_flattened());
        assert_eq!(aprt_shade(), 0, "{}", error_text());
        let unoccluded = shading(info.vertices());
        assert_eq!(aprt_occlude(), 0, "{}", error_text());

        let mut expected = vec![0.0; info.vertices()];
        let mesh = (&positions[..], &normals[..]);
        session
            .shade(&angles, &lighting, &bones, &mut expected)
            .unwrap();
        session
            .occlude(&skinning, &lighting, mesh, &mut expected)
            .unwrap();
        assert_eq!(shading(info.vertices()), expected);
        assert_ne!(expected, unoccluded);
    }
}
