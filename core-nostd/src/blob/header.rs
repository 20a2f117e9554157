//! The preamble and the postcard header: the first bytes of every blob.

use super::format::{Header, MAGIC, MAX_HEADER_LEN, PREAMBLE_LEN, VERSION, crc32};
use super::{Error, Reader};

/// A header with what the reader derives from the preamble around it.
pub(crate) struct Decoded {
    pub(crate) header: Header,
    /// Byte offset where the header ends.
    pub(crate) end: u64,
    /// The header's CRC-32: the model's identity.
    pub(crate) crc: u32,
}

/// Reads and checks the preamble and the header: magic, version, length, CRC, decoding with no
/// bytes left over, and a finite α.
pub(crate) fn decode_header<R: Reader>(r: &mut R) -> Result<Decoded, Error> {
    let mut pre = [0u8; PREAMBLE_LEN];
    if r.len() < PREAMBLE_LEN as u64 {
        return Err(Error::Truncated {
            needed: PREAMBLE_LEN as u64,
        });
    }
    r.read_at(0, &mut pre)?;
    let word = |i: usize| u32::from_le_bytes([pre[i], pre[i + 1], pre[i + 2], pre[i + 3]]);
    if pre[..8] != MAGIC {
        return Err(Error::BadMagic);
    }
    let (version, len, crc) = (word(8), word(12), word(16));
    if version != VERSION {
        return Err(Error::UnsupportedVersion { found: version });
    }
    if len > MAX_HEADER_LEN {
        return Err(Error::HeaderTooLarge { len });
    }
    let end = PREAMBLE_LEN as u64 + len as u64;
    if r.len() < end {
        return Err(Error::Truncated { needed: end });
    }
    let mut buf = [0u8; MAX_HEADER_LEN as usize];
    let bytes = &mut buf[..len as usize];
    r.read_at(PREAMBLE_LEN as u64, bytes)?;
    if crc32(bytes) != crc {
        return Err(Error::HeaderChecksum);
    }
    let (header, rest) =
        postcard::take_from_bytes::<Header>(bytes).map_err(|_| Error::HeaderMalformed)?;
    if !rest.is_empty() {
        return Err(Error::TrailingBytes {
            extra: rest.len() as u64,
        });
    }
    // NaN never leaves the trainer, and a NaN α would make the model unequal to itself.
    if !header.alpha.is_finite() {
        return Err(Error::HeaderMalformed);
    }
    Ok(Decoded { header, end, crc })
}

/// Reads and checks the preamble and header of a resident blob (the sections are not
/// validated: [`Model::parse`](crate::Model::parse) does that).
#[cfg_attr(not(feature = "format"), allow(dead_code))]
pub fn read_header(blob: &[u8]) -> Result<Header, Error> {
    decode_header(&mut super::Resident(blob)).map(|d| d.header)
}
