//! The entropy stage: zstd, with every decompression capped at the size the header implies.

use std::io::Read;

use super::CodecError;

/// Compresses `bytes` at `level`.
pub fn compress(bytes: &[u8], level: i32) -> Result<Vec<u8>, CodecError> {
    zstd::bulk::compress(bytes, level).map_err(|e| CodecError::Zstd {
        what: "encoder",
        message: e.to_string(),
    })
}

/// Decompresses a frame chunk of exactly `expected` bytes in one call (the hot path of
/// `decode_frame`). Allocating `expected` up front is safe here: it is below the `R² · n² · 4`
/// bytes of the output frame the caller already holds.
pub fn decompress_chunk(
    bytes: &[u8],
    expected: usize,
    what: &'static str,
) -> Result<Vec<u8>, CodecError> {
    let out = zstd::bulk::decompress(bytes, expected).map_err(|e| CodecError::Zstd {
        what,
        message: e.to_string(),
    })?;
    if out.len() != expected {
        return Err(CodecError::SizeMismatch {
            what,
            expected: expected as u64,
            got: out.len() as u64,
        });
    }
    Ok(out)
}

/// Decompresses `bytes`, which must hold exactly `expected` bytes. The output grows with what
/// zstd actually produces and stops one byte past `expected`, so a hostile frame header
/// cannot make this allocate more than the file's own header allows.
pub fn decompress_exact(
    bytes: &[u8],
    expected: usize,
    what: &'static str,
) -> Result<Vec<u8>, CodecError> {
    let zstd_error = |e: std::io::Error| CodecError::Zstd {
        what,
        message: e.to_string(),
    };
    let decoder = zstd::stream::read::Decoder::with_buffer(bytes).map_err(zstd_error)?;
    let mut out = Vec::new();
    let limit = u64::try_from(expected)
        .unwrap_or(u64::MAX)
        .saturating_add(1);
    decoder
        .take(limit)
        .read_to_end(&mut out)
        .map_err(zstd_error)?;
    if out.len() != expected {
        return Err(CodecError::SizeMismatch {
            what,
            expected: expected as u64,
            got: out.len() as u64,
        });
    }
    Ok(out)
}
