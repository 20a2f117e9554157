//! Where blob bytes come from: a resident slice, or any random-access store (flash, a file)
//! read through a caller-owned buffer, so a model never has to be resident.

use super::Error;

/// A [`BlobSource`] could not deliver the bytes asked for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SourceError;

/// Random-access, read-only bytes.
pub trait BlobSource {
    /// Total length in bytes.
    fn len(&self) -> u64;

    /// Whether the source holds no bytes.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Fills `buf` with the bytes at `offset..offset + buf.len()`. The reader only asks for
    /// ranges inside `0..len()`.
    fn read_at(&mut self, offset: u64, buf: &mut [u8]) -> Result<(), SourceError>;

    /// The whole blob, if it is resident: the reader then works in place and needs no buffer.
    fn as_slice(&self) -> Option<&[u8]> {
        None
    }
}

/// A resident blob.
#[derive(Clone, Copy, Debug)]
pub struct SliceSource<'a>(pub &'a [u8]);

impl BlobSource for SliceSource<'_> {
    fn len(&self) -> u64 {
        self.0.len() as u64
    }

    fn read_at(&mut self, offset: u64, buf: &mut [u8]) -> Result<(), SourceError> {
        let start = usize::try_from(offset).map_err(|_| SourceError)?;
        let end = start.checked_add(buf.len()).ok_or(SourceError)?;
        buf.copy_from_slice(self.0.get(start..end).ok_or(SourceError)?);
        Ok(())
    }

    fn as_slice(&self) -> Option<&[u8]> {
        Some(self.0)
    }
}

/// Delivers `count` items of `item_bytes` each, starting at byte `offset`, to `visit` in
/// chunks of whole items, as `(index of the chunk's first item, bytes)`. A resident source
/// yields one chunk in place; otherwise chunks are read into `scratch`, which must hold at
/// least one item.
pub(crate) fn for_each_chunk<S: BlobSource + ?Sized>(
    src: &mut S,
    offset: u64,
    item_bytes: usize,
    count: usize,
    scratch: &mut [u8],
    mut visit: impl FnMut(usize, &[u8]) -> Result<(), Error>,
) -> Result<(), Error> {
    let total = item_bytes.checked_mul(count).ok_or(Error::LengthOverflow)?;
    let end = offset
        .checked_add(total as u64)
        .ok_or(Error::LengthOverflow)?;
    if end > src.len() {
        return Err(Error::Truncated { needed: end });
    }
    if count == 0 {
        return Ok(());
    }
    if let Some(all) = src.as_slice() {
        let range = usize::try_from(offset).ok().zip(usize::try_from(end).ok());
        let bytes = range
            .and_then(|(a, b)| all.get(a..b))
            .ok_or(Error::Truncated { needed: end })?;
        return visit(0, bytes);
    }
    let per_chunk = scratch.len().checked_div(item_bytes).unwrap_or(0);
    if per_chunk == 0 {
        return Err(Error::BufferTooSmall { needed: item_bytes });
    }
    let mut first = 0;
    while first < count {
        let n = per_chunk.min(count - first);
        let buf = &mut scratch[..n * item_bytes];
        let at = offset + (first * item_bytes) as u64;
        src.read_at(at, buf).map_err(|_| Error::Source)?;
        visit(first, buf)?;
        first += n;
    }
    Ok(())
}
