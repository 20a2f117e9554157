//! Editing blobs behind the writer's back: rewriting the header, recomputing checksums, and
//! random byte mutations. A mutated blob whose checksums are recomputed ("resealed") gets past
//! the CRCs to the deeper validation: dimensions, section table, lengths, finiteness.

use aprt_core::format::{Header, MAX_HEADER_LEN, PREAMBLE_LEN, crc32, read_header};

/// The blob with its header edited and re-encoded (header CRC recomputed). The section bytes
/// keep their places relative to each other; if the header grew past them, everything after it
/// moves by whole alignment units and the offsets with it. `None` when the blob has no
/// decodable header or its first section lies outside it.
pub fn with_header(blob: &[u8], edit: impl FnOnce(&mut Header)) -> Option<Vec<u8>> {
    let original = read_header(blob).ok()?;
    let header_end = PREAMBLE_LEN + header_len(blob)?;
    let first = original
        .sections
        .iter()
        .map(|s| s.offset)
        .min()
        .map_or(Some(blob.len()), |o| usize::try_from(o).ok())?;
    if first < header_end || first > blob.len() {
        return None;
    }
    let mut edited = original;
    edit(&mut edited);
    let mut shift = 0u64;
    let bytes = loop {
        let mut h = edited.clone();
        h.sections
            .iter_mut()
            .for_each(|s| s.offset = s.offset.saturating_add(shift));
        let bytes = postcard::to_allocvec(&h).ok()?;
        if PREAMBLE_LEN + bytes.len() <= first + shift as usize {
            break bytes;
        }
        shift += 16;
    };
    let mut out = Vec::with_capacity(blob.len() + shift as usize);
    out.extend_from_slice(&blob[..12]);
    out.extend_from_slice(&(bytes.len() as u32).to_le_bytes());
    out.extend_from_slice(&crc32(&bytes).to_le_bytes());
    out.extend_from_slice(&bytes);
    out.resize(first + shift as usize, 0);
    out.extend_from_slice(&blob[first..]);
    Some(out)
}

/// The announced header length, if the preamble holds one the reader would accept.
fn header_len(blob: &[u8]) -> Option<usize> {
    let len = u32::from_le_bytes(blob.get(12..16)?.try_into().unwrap());
    (len <= MAX_HEADER_LEN && PREAMBLE_LEN + len as usize <= blob.len()).then_some(len as usize)
}

/// The blob with every checksum made to match: the CRC of every section that lies inside the
/// blob, and the header's. A header that no longer decodes only gets its CRC fixed, so the
/// reader reports what is wrong with it rather than a checksum.
pub fn reseal(blob: &[u8]) -> Vec<u8> {
    let mut out = blob.to_vec();
    if let Some(len) = header_len(blob) {
        let crc = crc32(&blob[PREAMBLE_LEN..PREAMBLE_LEN + len]);
        out[16..20].copy_from_slice(&crc.to_le_bytes());
    }
    let resealed = with_header(&out, |h| {
        for s in h.sections.iter_mut() {
            let range = usize::try_from(s.offset)
                .ok()
                .zip(usize::try_from(s.offset.saturating_add(s.len)).ok());
            if let Some(bytes) = range.and_then(|(a, b)| out.get(a..b)) {
                s.crc32 = crc32(bytes);
            }
        }
    });
    resealed.unwrap_or(out)
}

/// One random edit of a blob; positions wrap around the blob's length.
#[derive(Clone, Debug, arbitrary::Arbitrary)]
pub enum Mutation {
    /// Flip one bit.
    Flip {
        /// Byte position.
        at: usize,
        /// Bit 0..8.
        bit: u8,
    },
    /// Overwrite bytes from `at` (as far as the blob reaches).
    Overwrite {
        /// First byte.
        at: usize,
        /// New bytes.
        bytes: Vec<u8>,
    },
    /// Overwrite four bytes with a little-endian value chosen to upset arithmetic.
    Word {
        /// First byte.
        at: usize,
        /// Index into [`Mutation::WORDS`].
        which: usize,
    },
    /// Insert bytes before `at`.
    Insert {
        /// Position.
        at: usize,
        /// New bytes.
        bytes: Vec<u8>,
    },
    /// Remove up to `len` bytes from `at`.
    Remove {
        /// First byte.
        at: usize,
        /// Bytes to remove.
        len: usize,
    },
}

impl Mutation {
    /// Boundary values: zero, one, sign bits, all ones, NaN, infinity, f32 and f16 extremes.
    pub const WORDS: [u32; 12] = [
        0,
        1,
        0x7f,
        0x80,
        0xff,
        0x8000_0000,
        0xffff_ffff,
        0x7fc0_0000,
        0x7f80_0000,
        0x7f7f_ffff,
        0x7c00_7c00,
        0x0000_0400,
    ];

    /// Applies the edit to `blob`.
    pub fn apply(&self, blob: &mut Vec<u8>) {
        let at = |at: usize, blob: &Vec<u8>| at.checked_rem(blob.len()).unwrap_or(0);
        match self {
            Mutation::Flip { at: i, bit } => {
                let i = at(*i, blob);
                if let Some(b) = blob.get_mut(i) {
                    *b ^= 1 << (bit % 8);
                }
            }
            Mutation::Overwrite { at: i, bytes } => {
                let i = at(*i, blob);
                let n = bytes.len().min(blob.len() - i);
                blob[i..i + n].copy_from_slice(&bytes[..n]);
            }
            Mutation::Word { at: i, which } => {
                let word = Self::WORDS[which % Self::WORDS.len()].to_le_bytes();
                Mutation::Overwrite {
                    at: *i,
                    bytes: word.to_vec(),
                }
                .apply(blob)
            }
            Mutation::Insert { at: i, bytes } => {
                let i = at(*i, blob);
                blob.splice(i..i, bytes.iter().copied());
            }
            Mutation::Remove { at: i, len } => {
                let i = at(*i, blob);
                let end = i.saturating_add(*len).min(blob.len());
                blob.drain(i..end);
            }
        }
    }
}
