//! What can go wrong encoding a sequence or reading a `.shlm` file.

use thiserror::Error;

/// An error of the SH light-map codec. Reading names the byte or frame at fault, so a
/// corrupt file is diagnosed rather than silently decoded.
#[derive(Debug, Error, PartialEq, Eq)]
pub enum CodecError {
    /// The file does not start with `APRTSHLM`.
    #[error("not a .shlm file (bad magic)")]
    BadMagic,
    /// A version this reader does not know.
    #[error("unsupported .shlm version {0}")]
    Version(u32),
    /// The file ends before a section it declares.
    #[error("truncated: {what} needs bytes up to {needed}, the file has {len}")]
    Truncated {
        /// The section being read.
        what: &'static str,
        /// The end offset it needs.
        needed: u64,
        /// The file's length.
        len: u64,
    },
    /// A header field outside its limits, or sizes whose product overflows.
    #[error("invalid header: {0}")]
    Header(String),
    /// The CRC-32 stored at the end does not match the bytes before it.
    #[error("checksum mismatch: stored {stored:#010x}, computed {computed:#010x}")]
    Checksum {
        /// The stored CRC-32.
        stored: u32,
        /// The CRC-32 of the bytes.
        computed: u32,
    },
    /// A frame index past the sequence.
    #[error("frame {index} out of range ({frames} frames)")]
    FrameOutOfRange {
        /// The requested frame.
        index: usize,
        /// The sequence's frame count.
        frames: usize,
    },
    /// zstd refused a section (corrupt, or larger than the header allows).
    #[error("zstd error in {what}: {message}")]
    Zstd {
        /// The section being decompressed.
        what: &'static str,
        /// zstd's message.
        message: String,
    },
    /// A section, buffer or input whose size is not the one the header implies.
    #[error("size mismatch in {what}: expected {expected}, got {got}")]
    SizeMismatch {
        /// The section, buffer or input.
        what: &'static str,
        /// The size implied by the header or the sequence.
        expected: u64,
        /// The size found.
        got: u64,
    },
    /// A value inside a section that no encoder writes (an exponent byte out of range, a
    /// non-finite float, an offset table that goes backwards).
    #[error("invalid data in {what}: {message}")]
    Invalid {
        /// The section.
        what: &'static str,
        /// What is wrong.
        message: String,
    },
    /// Work on a valid file that needs more memory than one run holds (every frame decoded).
    #[error("{0}")]
    OverBudget(String),
    /// The sequence to encode holds NaN or infinity, or a setting is out of range.
    #[error("cannot encode: {0}")]
    Input(String),
}
