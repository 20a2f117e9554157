//! The only module with `unsafe` code: every raw pointer the C ABI receives becomes a Rust
//! reference or slice here, and a C callback is called here, nowhere else.
//!
//! Why it exists: C hands over pointers and lengths, and no Rust type can say that they are
//! valid. Confining the conversions to one small module keeps the rest of the crate safe code
//! that cannot misuse a pointer, and puts every check in one place:
//!
//! - NULL is refused ([`aprt_status::NullPointer`]), except a NULL array of length 0, which is
//!   the empty slice (C callers pass `NULL, 0` for "none").
//! - Misalignment for the element type is refused ([`aprt_status::Misaligned`]). A length whose
//!   byte size overflows `isize` fits no buffer, so it is the caller's wrong length
//!   ([`aprt_status::WrongLength`]; [`past_vertices`] and the lights name it better), never
//!   the blob's [`aprt_status::LengthOverflow`].
//! - Elements are [`Plain`]: types for which every bit pattern is a valid value (integers,
//!   floats, arrays and `#[repr(C)]` structs of them), so no C bytes can make an invalid value.
//! - Handles are `#[repr(C)]` with a tag word first, checked before a reference is made
//!   ([`aprt_status::BadHandle`]): storage that was never initialised (zeroed, or another
//!   kind's) is refused rather than read as a handle. The check reads the first 8 bytes only,
//!   which lie inside every kind of handle, so a handle of another (smaller) kind is never
//!   read past its end. This is a best effort against mistakes, not a proof: garbage that
//!   happens to hold the tag cannot be told apart.
//!
//! What the caller promises, as the header states on each function: a pointer with a length
//! points to that many initialised elements that no one else writes during the call; outputs
//! do not overlap inputs; a handle's storage, the blob a resident model reads in place, a
//! stream's scratch and the buffer of `aprt_light_rig` stay valid and untouched for as long as
//! the handle that refers to them is used; a read callback obeys `aprt_read_fn`.
#![allow(unsafe_code)]

use std::ffi::c_void;

use crate::status::aprt_status;

/// Element types whose every bit pattern is a valid value, so a C buffer of them can be read
/// as a slice. Sealed: implemented in this module only.
pub(crate) trait Plain: Copy + private::Sealed {}

mod private {
    pub trait Sealed {}
}

macro_rules! plain {
    ($($t:ty),*) => {$(
        impl private::Sealed for $t {}
        impl Plain for $t {}
    )*};
}
plain!(u8, u16, f32, [f32; 3], [f32; 12], [[f32; 3]; 3]);
plain!(crate::lights::aprt_light, crate::rig::aprt_placement);
plain!(crate::model::aprt_source);

/// A handle type stored in caller memory, recognised by `TAG` in its first 8 bytes.
pub(crate) trait Handle {
    /// The word a live handle of this type holds.
    const TAG: u64;
    /// Where the word is, `offset_of!` its field: 0 (`check_handle` refuses to compile
    /// otherwise), so that checking any storage reads only bytes every handle has.
    const TAG_OFFSET: usize;
}

fn check<T>(ptr: *const T, len: usize) -> Result<(), aprt_status> {
    if ptr.is_null() {
        return Err(aprt_status::NullPointer);
    }
    if !ptr.cast::<u8>().addr().is_multiple_of(align_of::<T>()) {
        return Err(aprt_status::Misaligned);
    }
    match len.checked_mul(size_of::<T>()) {
        Some(bytes) if bytes <= isize::MAX as usize => Ok(()),
        _ => Err(aprt_status::WrongLength),
    }
}

/// The status of a vertex count no buffer can hold: it runs past every model's vertices.
pub(crate) fn past_vertices(status: aprt_status) -> aprt_status {
    match status {
        aprt_status::WrongLength => aprt_status::VertexRange,
        other => other,
    }
}

/// `len` elements at `ptr`, read-only. Any lifetime: the caller's promise above bounds it.
pub(crate) fn slice<'a, T: Plain>(ptr: *const T, len: usize) -> Result<&'a [T], aprt_status> {
    if len == 0 {
        return Ok(&[]);
    }
    check(ptr, len)?;
    // SAFETY: non-NULL, aligned, `len * size_of::<T>()` fits in isize (checked); the caller
    // promises `len` initialised elements not written during the borrow; `T: Plain` makes any
    // bytes a valid `T`.
    Ok(unsafe { std::slice::from_raw_parts(ptr, len) })
}

/// `len` elements at `ptr`, writable.
pub(crate) fn slice_mut<'a, T: Plain>(ptr: *mut T, len: usize) -> Result<&'a mut [T], aprt_status> {
    if len == 0 {
        return Ok(&mut []);
    }
    check(ptr, len)?;
    // SAFETY: as in `slice`, and the caller promises no other access during the borrow.
    Ok(unsafe { std::slice::from_raw_parts_mut(ptr, len) })
}

/// `count` 3-vectors (positions, RGB) from `3 · count` floats.
pub(crate) fn triples<'a>(ptr: *const f32, count: usize) -> Result<&'a [[f32; 3]], aprt_status> {
    slice(ptr.cast::<[f32; 3]>(), count)
}

/// `count` writable 3-vectors from `3 · count` floats.
pub(crate) fn triples_mut<'a>(
    ptr: *mut f32,
    count: usize,
) -> Result<&'a mut [[f32; 3]], aprt_status> {
    slice_mut(ptr.cast::<[f32; 3]>(), count)
}

/// `count` row-major 3 × 3 matrices from `9 · count` floats.
pub(crate) fn matrices<'a>(
    ptr: *const f32,
    count: usize,
) -> Result<&'a [[[f32; 3]; 3]], aprt_status> {
    slice(ptr.cast::<[[f32; 3]; 3]>(), count)
}

/// `floats / 12` skinning matrices (3 × 4, row-major) from `floats` floats;
/// [`aprt_status::WrongLength`] when `floats` is not a multiple of 12.
pub(crate) fn skinning<'a>(ptr: *const f32, floats: usize) -> Result<&'a [[f32; 12]], aprt_status> {
    slice(ptr, floats)?;
    match floats.is_multiple_of(12) {
        true => slice(ptr.cast::<[f32; 12]>(), floats / 12),
        false => Err(aprt_status::WrongLength),
    }
}

/// One value at `ptr`.
pub(crate) fn read<T: Plain>(ptr: *const T) -> Result<T, aprt_status> {
    Ok(slice(ptr, 1)?[0])
}

/// Writes `value` to the out-parameter `ptr` (a plain value or a handle pointer).
pub(crate) fn write<T: Copy>(ptr: *mut T, value: T) -> Result<(), aprt_status> {
    check(ptr.cast_const(), 1)?;
    // SAFETY: non-NULL and aligned (checked); the caller promises a writable slot. `T: Copy`
    // has no drop, so the old bytes are overwritten, not read.
    unsafe { ptr.write(value) };
    Ok(())
}

/// Whether `storage` (`len` bytes) can hold a `T`: not NULL, aligned, large enough. Inits
/// check it first, so a bad storage is reported before a bad blob.
pub(crate) fn check_storage<T: Handle>(
    storage: *mut c_void,
    len: usize,
) -> Result<(), aprt_status> {
    check(storage.cast::<T>().cast_const(), 1)?;
    match len < size_of::<T>() {
        true => Err(aprt_status::StorageTooSmall),
        false => Ok(()),
    }
}

/// Moves `value` into the caller's `storage` (`len` bytes) and returns it as a handle pointer.
/// Nothing is written when the storage is NULL, misaligned or too small.
pub(crate) fn place<T: Handle>(
    storage: *mut c_void,
    len: usize,
    value: T,
) -> Result<*mut T, aprt_status> {
    check_storage::<T>(storage, len)?;
    let ptr = storage.cast::<T>();
    // SAFETY: non-NULL, aligned for T and at least size_of::<T>() bytes (checked); the caller
    // lends them to the handle. Handles need no drop, so overwriting an old one leaks nothing.
    unsafe { ptr.write(value) };
    Ok(ptr)
}

/// Whether `ptr` holds a live handle of type `T` (NULL, the tag, then alignment checked).
/// The tag is read before `T`'s alignment is checked, so another kind of handle (aligned for
/// its own kind) is a bad handle, not a misaligned one.
fn check_handle<T: Handle>(ptr: *const T) -> Result<(), aprt_status> {
    const { assert!(T::TAG_OFFSET == 0, "a handle's tag comes first") };
    let word = ptr.cast::<u64>();
    check(word, 1)?;
    // SAFETY: non-NULL and aligned for the u64 (checked); the caller promises storage of some
    // handle, and every handle starts with its 8-byte tag. Reading it creates no reference to
    // a possibly invalid T.
    let tag = unsafe { word.read() };
    if tag != T::TAG {
        return Err(aprt_status::BadHandle);
    }
    check(ptr, 1)
}

/// The handle at `ptr`, shared.
pub(crate) fn handle<'a, T: Handle>(ptr: *const T) -> Result<&'a T, aprt_status> {
    check_handle(ptr)?;
    // SAFETY: a live handle written by `place` (tag checked); the caller promises no
    // concurrent writer.
    Ok(unsafe { &*ptr })
}

/// The handle at `ptr`, exclusive.
pub(crate) fn handle_mut<'a, T: Handle>(ptr: *mut T) -> Result<&'a mut T, aprt_status> {
    check_handle(ptr.cast_const())?;
    // SAFETY: as in `handle`, and the caller promises no other access during the call.
    Ok(unsafe { &mut *ptr })
}

/// The C read callback of a stream: fills `buf` from `offset`; 0 means success.
pub(crate) type ReadFn =
    unsafe extern "C" fn(user: *mut c_void, offset: u64, buf: *mut u8, len: usize) -> i32;

/// Calls a stream's read callback for `buf`.
pub(crate) fn call_read(read: ReadFn, user: *mut c_void, offset: u64, buf: &mut [u8]) -> i32 {
    // SAFETY: `aprt_read_fn`'s contract: it writes at most `len` bytes at `buf` (a valid
    // exclusive slice here) and neither unwinds nor keeps the pointer.
    unsafe { read(user, offset, buf.as_mut_ptr(), buf.len()) }
}
