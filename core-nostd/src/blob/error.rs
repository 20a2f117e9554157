//! The one error type of the core: small, `Copy`, no heap payload.

use super::format::SectionKind;

/// Which header dimension was out of range.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dim {
    /// SH order (1..=6).
    Order,
    /// Vertex count.
    Vertices,
    /// Joint angles per pose.
    Joints,
    /// Pose dimensions k_a after projection.
    PoseDims,
    /// Vertex-basis dimensions k_v.
    CoefDims,
    /// Bones of a skinned-frame model.
    Bones,
}

/// Everything that can go wrong reading a blob or evaluating a model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Error {
    /// The blob ends before byte `needed`.
    Truncated {
        /// Bytes the blob would need to hold what it announces.
        needed: u64,
    },
    /// The first eight bytes are not the aprt magic.
    BadMagic,
    /// The format version is not one this reader understands.
    UnsupportedVersion {
        /// Version found in the blob.
        found: u32,
    },
    /// The header announces more bytes than any valid header needs.
    HeaderTooLarge {
        /// Announced header length.
        len: u32,
    },
    /// The header bytes do not match their checksum.
    HeaderChecksum,
    /// The header bytes do not decode, or hold a non-finite α.
    HeaderMalformed,
    /// Bytes follow the header encoding or the last section.
    TrailingBytes {
        /// Number of unexpected bytes.
        extra: u64,
    },
    /// A header dimension is zero, too large for this build, or inconsistent.
    BadDimension {
        /// Which dimension.
        what: Dim,
        /// Its value.
        value: u64,
    },
    /// A section lies outside the blob or inside the header.
    SectionOutOfRange {
        /// Section kind tag.
        kind: u16,
    },
    /// A section does not start on a multiple of the section alignment.
    SectionMisaligned {
        /// Section kind tag.
        kind: u16,
    },
    /// Two sections share bytes.
    SectionOverlap {
        /// Kind tag of the later section.
        kind: u16,
    },
    /// A section's length differs from what the header dimensions require.
    SectionLength {
        /// Section kind tag.
        kind: u16,
        /// Bytes required by the dimensions.
        expected: u64,
        /// Bytes announced.
        found: u64,
    },
    /// A product of dimensions overflows.
    LengthOverflow,
    /// The same section kind appears twice.
    DuplicateSection {
        /// Section kind tag.
        kind: u16,
    },
    /// A section the model needs is absent.
    MissingSection {
        /// The missing section.
        kind: SectionKind,
    },
    /// A section marked required has a kind this reader does not know.
    UnknownRequiredSection {
        /// Section kind tag.
        kind: u16,
    },
    /// A section uses an encoding not allowed for it.
    BadEncoding {
        /// Section kind tag.
        kind: u16,
    },
    /// A section's bytes do not match its checksum.
    ChecksumMismatch {
        /// Section kind tag.
        kind: u16,
    },
    /// A section holds NaN or infinity.
    NonFinite {
        /// Section kind tag.
        kind: u16,
    },
    /// The caller's buffer is too small; `needed` bytes would do.
    BufferTooSmall {
        /// Minimum size in bytes.
        needed: usize,
    },
    /// An input or output slice has the wrong length.
    WrongLength {
        /// Length required.
        expected: usize,
        /// Length given.
        found: usize,
    },
    /// An input value (angle or lighting coefficient) is NaN or infinite.
    NonFiniteInput,
    /// The vertex range runs past the model's vertices.
    VertexRange {
        /// First vertex requested.
        first: usize,
        /// Number of vertices requested.
        count: usize,
    },
    /// The pose or lighting weights were computed for another model shape.
    ShapeMismatch,
    /// A vertex's bone index is not an integer below the bone count.
    BadBoneIndex,
    /// The call does not match the model's frame: `light` is for world-frame models,
    /// `light_skinned` for bone-frame models.
    FrameMismatch,
    /// A bone rotation is not orthonormal or holds NaN.
    BadRotation,
    /// The [`BlobSource`](super::BlobSource) failed to read.
    Source,
}

impl core::fmt::Display for Error {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Error::Truncated { needed } => {
                write!(f, "blob truncated: needs at least {needed} bytes")
            }
            Error::BadMagic => write!(f, "not an aprt model (bad magic)"),
            Error::UnsupportedVersion { found } => {
                write!(
                    f,
                    "unsupported format version {found} (this reader knows {})",
                    super::VERSION
                )
            }
            Error::HeaderTooLarge { len } => write!(f, "header length {len} exceeds the maximum"),
            Error::HeaderChecksum => write!(f, "header checksum mismatch"),
            Error::HeaderMalformed => {
                write!(f, "header does not decode or holds a non-finite alpha")
            }
            Error::TrailingBytes { extra } => write!(f, "{extra} unexpected trailing bytes"),
            Error::BadDimension { what, value } => {
                write!(f, "dimension {what:?} = {value} is out of range")
            }
            Error::SectionOutOfRange { kind } => write!(f, "section {kind} lies outside the blob"),
            Error::SectionMisaligned { kind } => write!(f, "section {kind} is misaligned"),
            Error::SectionOverlap { kind } => write!(f, "section {kind} overlaps another section"),
            Error::SectionLength {
                kind,
                expected,
                found,
            } => {
                write!(
                    f,
                    "section {kind} is {found} bytes, dimensions need {expected}"
                )
            }
            Error::LengthOverflow => write!(f, "dimension product overflows"),
            Error::DuplicateSection { kind } => write!(f, "section {kind} appears twice"),
            Error::MissingSection { kind } => write!(f, "required section {kind:?} is missing"),
            Error::UnknownRequiredSection { kind } => write!(f, "unknown required section {kind}"),
            Error::BadEncoding { kind } => write!(f, "section {kind} has an unsupported encoding"),
            Error::ChecksumMismatch { kind } => write!(f, "section {kind} checksum mismatch"),
            Error::NonFinite { kind } => write!(f, "section {kind} holds NaN or infinity"),
            Error::BufferTooSmall { needed } => write!(f, "buffer too small: needs {needed} bytes"),
            Error::WrongLength { expected, found } => {
                write!(f, "slice length {found}, expected {expected}")
            }
            Error::NonFiniteInput => write!(f, "input holds NaN or infinity"),
            Error::VertexRange { first, count } => {
                write!(f, "vertex range {first}..{first}+{count} is out of bounds")
            }
            Error::ShapeMismatch => write!(f, "weights were computed for a different model"),
            Error::BadBoneIndex => write!(f, "vertex bone index out of range"),
            Error::FrameMismatch => write!(f, "lighting call does not match the model's frame"),
            Error::BadRotation => write!(f, "bone rotation is not orthonormal"),
            Error::Source => write!(f, "blob source read failed"),
        }
    }
}

impl core::error::Error for Error {}
