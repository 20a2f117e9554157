//! The one status type of the ABI: a stable `#[repr(C)]` enum whose numbers never change, the
//! mapping from the core's [`Error`], and a static message per status.
//!
//! Codes are grouped: 0 is success, 1–99 are mistakes at the boundary (a NULL or misaligned
//! pointer, storage too small, a handle that was never initialised), 100–199 a blob the core
//! refuses, 200–299 a call the core refuses. New codes are only ever appended; a core error
//! newer than this table is [`aprt_status::Unknown`].
// `#[unsafe(no_mangle)]` is the only unsafe here (exported names must be unique); every
// unsafe operation lives in `ffi_ptr`, which `tests/unsafe_confined.rs` checks.
#![allow(unsafe_code)]

use std::ffi::{CStr, c_char};

use aprt_core::Error;

/// What a call did: `APRT_STATUS_OK` (0), or why it did nothing useful. Every entry point
/// returns one; outputs are only meaningful after `APRT_STATUS_OK`.
#[allow(non_camel_case_types)]
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum aprt_status {
    /// Success.
    Ok = 0,
    /// A pointer argument is NULL (a NULL array is accepted only with length 0).
    NullPointer = 1,
    /// A pointer is not aligned for its type (storage: `aprt_*_align()`; floats: 4 bytes).
    Misaligned = 2,
    /// The storage for a handle is smaller than `aprt_model_size()` / `aprt_frame_size()`.
    StorageTooSmall = 3,
    /// A handle pointer does not point to an initialised handle of its kind.
    BadHandle = 4,
    /// An `aprt_light` has a kind that is not one of `APRT_LIGHT_*`.
    BadLightKind = 5,
    /// More lights than `APRT_MAX_LIGHTS` in one call.
    TooManyLights = 6,
    /// A streamed model was re-entered from its own read callback.
    Busy = 7,
    /// A bug: the library panicked, and the panic was stopped at the boundary.
    Panic = 8,
    /// The model has no pose entry of that name.
    NoSuchName = 9,
    /// The blob ends before the bytes it announces.
    Truncated = 100,
    /// Not an aprt model (bad magic).
    BadMagic = 101,
    /// A format version this library does not read.
    UnsupportedVersion = 102,
    /// The header announces more bytes than any valid header needs.
    HeaderTooLarge = 103,
    /// The header does not match its checksum.
    HeaderChecksum = 104,
    /// The header does not decode.
    HeaderMalformed = 105,
    /// Bytes follow the header encoding or the last section.
    TrailingBytes = 106,
    /// A header dimension is zero, too large or inconsistent, or an `order` argument is
    /// outside 1..=6.
    BadDimension = 107,
    /// A section lies outside the blob or inside the header.
    SectionOutOfRange = 108,
    /// A section is misaligned.
    SectionMisaligned = 109,
    /// Two sections share bytes.
    SectionOverlap = 110,
    /// A section's length differs from what the dimensions need.
    SectionLength = 111,
    /// A product of dimensions overflows.
    LengthOverflow = 112,
    /// A section kind appears twice.
    DuplicateSection = 113,
    /// A required section is missing.
    MissingSection = 114,
    /// A section marked required has an unknown kind.
    UnknownRequiredSection = 115,
    /// A section uses an encoding not allowed for it.
    BadEncoding = 116,
    /// A section does not match its checksum.
    ChecksumMismatch = 117,
    /// A section holds NaN or infinity.
    NonFinite = 118,
    /// A vertex's bone index is out of range.
    BadBoneIndex = 119,
    /// The angle names are not one UTF-8 line per pose entry.
    BadAngleNames = 120,
    /// The pose bounds are inconsistent.
    BadPoseBounds = 121,
    /// The pose-feature flags are invalid.
    BadPoseFeatures = 122,
    /// The irradiance rig section is invalid.
    BadIrradianceRig = 123,
    /// The texel atlas section is invalid.
    BadTexelAtlas = 124,
    /// The occluder proxies section is invalid.
    BadProxies = 125,
    /// The call needs an irradiance rig and the model has none.
    NoIrradianceRig = 200,
    /// The call needs occluder proxies and the model has none.
    NoProxies = 201,
    /// A skinning matrix holds NaN or infinity.
    BadSkinning = 202,
    /// A normal is NaN or infinite.
    NonFiniteNormal = 203,
    /// Rig lighting weights were computed for a rig of another size.
    WeightsForOtherRig = 204,
    /// A buffer is too small (for a stream's scratch, the size needed is reported).
    BufferTooSmall = 205,
    /// The frame's weights are too small for this model.
    WeightsTooSmall = 206,
    /// An array has the wrong length for this model, or one no buffer can have (its bytes
    /// overflow).
    WrongLength = 207,
    /// A pose entry is NaN or infinite.
    NonFiniteAngle = 208,
    /// A lighting coefficient is NaN or infinite.
    NonFiniteLighting = 209,
    /// A light-map coefficient is NaN or infinite.
    NonFiniteLightMap = 210,
    /// A position is NaN or infinite.
    NonFinitePosition = 211,
    /// A bone rotation is not a proper rotation (orthonormal within 1e-3, determinant +1: not
    /// mirrored) or not finite.
    BadRotation = 212,
    /// A light is invalid (non-finite, negative, zero radius or direction).
    BadLight = 213,
    /// A light's weight is negative or not finite.
    BadLightWeight = 214,
    /// The vertex range runs past the model's vertices.
    VertexRange = 215,
    /// The frame holds no weights yet for this step (call the step before it).
    WeightsNotSet = 216,
    /// The frame's weights were computed for another model.
    WeightsForOtherModel = 217,
    /// The stream's read callback failed.
    Source = 218,
    /// The triangle is past the last one whose corner UVs the texel atlas records.
    TriangleRange = 219,
    /// A result overflowed to infinity or NaN (inputs, or a blob's values, too large for
    /// f32): the call's outputs are zeroed. No call returns OK with a non-finite output.
    Overflow = 220,
    /// An error of a newer core than this table knows.
    Unknown = 999,
}

impl From<Error> for aprt_status {
    fn from(e: Error) -> Self {
        use aprt_status as S;
        match e {
            Error::Truncated { .. } => S::Truncated,
            Error::BadMagic => S::BadMagic,
            Error::UnsupportedVersion { .. } => S::UnsupportedVersion,
            Error::HeaderTooLarge { .. } => S::HeaderTooLarge,
            Error::HeaderChecksum => S::HeaderChecksum,
            Error::HeaderMalformed => S::HeaderMalformed,
            Error::TrailingBytes { .. } => S::TrailingBytes,
            Error::BadDimension { .. } => S::BadDimension,
            Error::SectionOutOfRange { .. } => S::SectionOutOfRange,
            Error::SectionMisaligned { .. } => S::SectionMisaligned,
            Error::SectionOverlap { .. } => S::SectionOverlap,
            Error::SectionLength { .. } => S::SectionLength,
            Error::LengthOverflow => S::LengthOverflow,
            Error::DuplicateSection { .. } => S::DuplicateSection,
            Error::MissingSection { .. } => S::MissingSection,
            Error::UnknownRequiredSection { .. } => S::UnknownRequiredSection,
            Error::BadEncoding { .. } => S::BadEncoding,
            Error::ChecksumMismatch { .. } => S::ChecksumMismatch,
            Error::NonFinite { .. } => S::NonFinite,
            Error::BadBoneIndex => S::BadBoneIndex,
            Error::BadAngleNames => S::BadAngleNames,
            Error::BadPoseBounds => S::BadPoseBounds,
            Error::BadPoseFeatures => S::BadPoseFeatures,
            Error::BadIrradianceRig => S::BadIrradianceRig,
            Error::BadTexelAtlas => S::BadTexelAtlas,
            Error::BadProxies => S::BadProxies,
            Error::NoIrradianceRig => S::NoIrradianceRig,
            Error::NoProxies => S::NoProxies,
            Error::BadSkinning { .. } => S::BadSkinning,
            Error::NonFiniteNormal { .. } => S::NonFiniteNormal,
            Error::WeightsForOtherRig => S::WeightsForOtherRig,
            Error::BufferTooSmall { .. } => S::BufferTooSmall,
            Error::WeightsTooSmall { .. } => S::WeightsTooSmall,
            Error::WrongLength { .. } => S::WrongLength,
            Error::NonFiniteAngle { .. } => S::NonFiniteAngle,
            Error::NonFiniteLighting { .. } => S::NonFiniteLighting,
            Error::NonFiniteLightMap { .. } => S::NonFiniteLightMap,
            Error::NonFinitePosition { .. } => S::NonFinitePosition,
            Error::BadRotation { .. } => S::BadRotation,
            Error::BadLight { .. } => S::BadLight,
            Error::BadLightWeight { .. } => S::BadLightWeight,
            Error::VertexRange { .. } => S::VertexRange,
            Error::WeightsNotSet => S::WeightsNotSet,
            Error::WeightsForOtherModel => S::WeightsForOtherModel,
            Error::Source => S::Source,
            Error::TriangleRange { .. } => S::TriangleRange,
            Error::Overflow => S::Overflow,
            _ => S::Unknown,
        }
    }
}

/// Every status, for the table of messages and the tests.
pub const ALL: [aprt_status; 57] = {
    use aprt_status as S;
    [
        S::Ok,
        S::NullPointer,
        S::Misaligned,
        S::StorageTooSmall,
        S::BadHandle,
        S::BadLightKind,
        S::TooManyLights,
        S::Busy,
        S::Panic,
        S::NoSuchName,
        S::Truncated,
        S::BadMagic,
        S::UnsupportedVersion,
        S::HeaderTooLarge,
        S::HeaderChecksum,
        S::HeaderMalformed,
        S::TrailingBytes,
        S::BadDimension,
        S::SectionOutOfRange,
        S::SectionMisaligned,
        S::SectionOverlap,
        S::SectionLength,
        S::LengthOverflow,
        S::DuplicateSection,
        S::MissingSection,
        S::UnknownRequiredSection,
        S::BadEncoding,
        S::ChecksumMismatch,
        S::NonFinite,
        S::BadBoneIndex,
        S::BadAngleNames,
        S::BadPoseBounds,
        S::BadPoseFeatures,
        S::BadIrradianceRig,
        S::BadTexelAtlas,
        S::BadProxies,
        S::NoIrradianceRig,
        S::NoProxies,
        S::BadSkinning,
        S::NonFiniteNormal,
        S::WeightsForOtherRig,
        S::BufferTooSmall,
        S::WeightsTooSmall,
        S::WrongLength,
        S::NonFiniteAngle,
        S::NonFiniteLighting,
        S::NonFiniteLightMap,
        S::NonFinitePosition,
        S::BadRotation,
        S::BadLight,
        S::BadLightWeight,
        S::VertexRange,
        S::WeightsNotSet,
        S::WeightsForOtherModel,
        S::Source,
        S::TriangleRange,
        S::Overflow,
    ]
};

/// The message of a status: one static line, NUL-terminated.
pub(crate) fn message(status: aprt_status) -> &'static CStr {
    use aprt_status as S;
    match status {
        S::Ok => c"ok",
        S::NullPointer => c"a pointer argument is NULL",
        S::Misaligned => c"a pointer is not aligned for its type",
        S::StorageTooSmall => c"the storage is smaller than the handle's size",
        S::BadHandle => c"the pointer is not an initialised handle of its kind",
        S::BadLightKind => c"a light's kind is not one of APRT_LIGHT_*",
        S::TooManyLights => c"more lights than APRT_MAX_LIGHTS in one call",
        S::Busy => c"a streamed model was re-entered from its read callback",
        S::Panic => c"internal error: the library panicked (please report it)",
        S::NoSuchName => c"the model has no pose entry of that name",
        S::Truncated => c"blob truncated",
        S::BadMagic => c"not an aprt model (bad magic)",
        S::UnsupportedVersion => c"unsupported format version",
        S::HeaderTooLarge => c"header length exceeds the maximum",
        S::HeaderChecksum => c"header checksum mismatch",
        S::HeaderMalformed => c"header does not decode",
        S::TrailingBytes => c"unexpected trailing bytes",
        S::BadDimension => c"a dimension is out of range",
        S::SectionOutOfRange => c"a section lies outside the blob",
        S::SectionMisaligned => c"a section is misaligned",
        S::SectionOverlap => c"a section overlaps another",
        S::SectionLength => c"a section's length does not match the dimensions",
        S::LengthOverflow => c"a length overflows",
        S::DuplicateSection => c"a section appears twice",
        S::MissingSection => c"a required section is missing",
        S::UnknownRequiredSection => c"an unknown section is marked required",
        S::BadEncoding => c"a section has an unsupported encoding",
        S::ChecksumMismatch => c"a section checksum mismatch",
        S::NonFinite => c"a section holds NaN or infinity",
        S::BadBoneIndex => c"a vertex bone index is out of range",
        S::BadAngleNames => c"angle names are not one UTF-8 line per pose entry",
        S::BadPoseBounds => c"pose bounds are inconsistent",
        S::BadPoseFeatures => c"pose-feature flags are invalid",
        S::BadIrradianceRig => c"the irradiance rig is invalid",
        S::BadTexelAtlas => c"the texel atlas is invalid",
        S::BadProxies => c"the occluder proxies are invalid",
        S::NoIrradianceRig => c"the model has no irradiance rig",
        S::NoProxies => c"the model has no occluder proxies",
        S::BadSkinning => c"a skinning matrix is NaN or infinite",
        S::NonFiniteNormal => c"a normal is NaN or infinite",
        S::WeightsForOtherRig => c"rig lighting weights were computed for another rig",
        S::BufferTooSmall => c"a buffer is too small",
        S::WeightsTooSmall => c"the frame's weights are too small for this model",
        S::WrongLength => c"an array has the wrong length for this model",
        S::NonFiniteAngle => c"a pose entry is NaN or infinite",
        S::NonFiniteLighting => c"a lighting coefficient is NaN or infinite",
        S::NonFiniteLightMap => c"a light-map coefficient is NaN or infinite",
        S::NonFinitePosition => c"a position is NaN or infinite",
        S::BadRotation => c"a bone rotation is not a rotation (orthonormal, not mirrored)",
        S::BadLight => c"a light is invalid",
        S::BadLightWeight => c"a light weight is negative, NaN or infinite",
        S::VertexRange => c"the vertex range is out of bounds",
        S::WeightsNotSet => c"the frame's weights were not computed (call the step before)",
        S::WeightsForOtherModel => c"the frame's weights were computed for another model",
        S::Source => c"the read callback failed",
        S::TriangleRange => c"the triangle is past the atlas's last",
        S::Overflow => c"a result overflowed: an input or a blob value is too large",
        S::Unknown => c"an error this ABI version does not name",
    }
}

/// The message of a status code, a static NUL-terminated string (never NULL, never to be
/// freed). Takes the code as an `int32_t`, so any value is safe: a code this library does not
/// know gives "unknown status".
#[unsafe(no_mangle)]
pub extern "C" fn aprt_status_message(status: i32) -> *const c_char {
    let known = ALL.iter().chain(&[aprt_status::Unknown]).copied();
    match known.into_iter().find(|s| *s as i32 == status) {
        Some(s) => message(s).as_ptr(),
        None => c"unknown status".as_ptr(),
    }
}

/// Runs one entry point's body: its `Err` becomes the status, and a panic (a bug) becomes
/// [`aprt_status::Panic`] instead of unwinding into C, which would be undefined behaviour.
pub(crate) fn guard(body: impl FnOnce() -> Result<(), aprt_status>) -> aprt_status {
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(body)) {
        Ok(Ok(())) => aprt_status::Ok,
        Ok(Err(status)) => status,
        Err(_) => aprt_status::Panic,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_panic_becomes_a_status() {
        assert_eq!(guard(|| panic!("a bug")), aprt_status::Panic);
        assert_eq!(guard(|| Err(aprt_status::Busy)), aprt_status::Busy);
        assert_eq!(guard(|| Ok(())), aprt_status::Ok);
    }

    #[test]
    fn core_errors_map_to_their_statuses() {
        assert_eq!(aprt_status::from(Error::BadMagic), aprt_status::BadMagic);
        let small = Error::BufferTooSmall { needed: 3 };
        assert_eq!(aprt_status::from(small), aprt_status::BufferTooSmall);
    }
}
