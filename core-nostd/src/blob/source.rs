//! Where blob bytes come from: a resident slice read in place, or any random-access store
//! (flash, a file) read through a caller-owned buffer, so a model never has to be resident.
//! The reader and the evaluator are written once, over [`Reader`].

use super::Error;

/// A [`BlobSource`] could not deliver the bytes asked for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SourceError;

/// Random-access, read-only bytes that need not be in memory: flash, a file, a network
/// cache. [`StreamedModel`](crate::StreamedModel) reads a model from one.
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
}

impl<S: BlobSource + ?Sized> BlobSource for &mut S {
    fn len(&self) -> u64 {
        (**self).len()
    }

    fn read_at(&mut self, offset: u64, buf: &mut [u8]) -> Result<(), SourceError> {
        (**self).read_at(offset, buf)
    }
}

/// A slice as a source: every read copies, as from flash. For a resident blob use
/// [`Model`](crate::Model), which reads in place.
impl BlobSource for &[u8] {
    fn len(&self) -> u64 {
        <[u8]>::len(self) as u64
    }

    fn read_at(&mut self, offset: u64, buf: &mut [u8]) -> Result<(), SourceError> {
        let start = usize::try_from(offset).map_err(|_| SourceError)?;
        let end = start.checked_add(buf.len()).ok_or(SourceError)?;
        buf.copy_from_slice(self.get(start..end).ok_or(SourceError)?);
        Ok(())
    }
}

/// How the reader and the evaluator get at blob bytes: in place, or through a buffer. Each
/// kind says how much one fetch can return; the chunking is written once, in `chunks`.
pub(crate) trait Reader {
    /// Total length in bytes.
    fn len(&self) -> u64;

    /// Fills `buf` with the bytes at `offset`, which lie in the blob (whatever the buffer).
    fn read_at(&mut self, offset: u64, buf: &mut [u8]) -> Result<(), Error>;

    /// Most bytes one [`Reader::fetch`] returns.
    fn capacity(&self) -> usize;

    /// The `len` bytes at `offset`, which lie in the blob; `len` is at most the capacity.
    fn fetch(&mut self, offset: u64, len: usize) -> Result<&[u8], Error>;

    /// Delivers `count` items of `item_bytes` each, starting at byte `offset`, to `visit` in
    /// chunks of whole items, as `(index of the chunk's first item, bytes)`: one chunk in
    /// place for a resident blob, as many as the buffer holds at a time otherwise.
    fn chunks(
        &mut self,
        offset: u64,
        item_bytes: usize,
        count: usize,
        mut visit: impl FnMut(usize, &[u8]) -> Result<(), Error>,
    ) -> Result<(), Error> {
        span_end(offset, item_bytes, count, self.len())?;
        if count == 0 {
            return Ok(());
        }
        let per_chunk = self.capacity().checked_div(item_bytes).unwrap_or(count);
        if per_chunk == 0 {
            return Err(Error::BufferTooSmall { needed: item_bytes });
        }
        let mut first = 0;
        while first < count {
            let n = per_chunk.min(count - first);
            let at = offset + (first * item_bytes) as u64;
            visit(first, self.fetch(at, n * item_bytes)?)?;
            first += n;
        }
        Ok(())
    }
}

/// The end of `count` items of `item_bytes` from `offset`, checked against a blob of `len`.
fn span_end(offset: u64, item_bytes: usize, count: usize, len: u64) -> Result<u64, Error> {
    let total = item_bytes.checked_mul(count).ok_or(Error::LengthOverflow)?;
    let end = offset
        .checked_add(total as u64)
        .ok_or(Error::LengthOverflow)?;
    if end > len {
        return Err(Error::Truncated { needed: end });
    }
    Ok(end)
}

/// A resident blob, read in place.
#[derive(Clone, Copy)]
pub(crate) struct Resident<'a>(pub(crate) &'a [u8]);

impl Reader for Resident<'_> {
    fn len(&self) -> u64 {
        self.0.len() as u64
    }

    fn read_at(&mut self, offset: u64, buf: &mut [u8]) -> Result<(), Error> {
        buf.copy_from_slice(self.fetch(offset, buf.len())?);
        Ok(())
    }

    fn capacity(&self) -> usize {
        usize::MAX
    }

    fn fetch(&mut self, offset: u64, len: usize) -> Result<&[u8], Error> {
        let end = span_end(offset, 1, len, self.len())?;
        usize::try_from(offset)
            .ok()
            .and_then(|a| self.0.get(a..a + len))
            .ok_or(Error::Truncated { needed: end })
    }
}

/// A [`BlobSource`] read through a caller's buffer.
pub(crate) struct Streaming<'r, S: ?Sized> {
    pub(crate) src: &'r mut S,
    pub(crate) scratch: &'r mut [u8],
}

impl<S: BlobSource + ?Sized> Reader for Streaming<'_, S> {
    fn len(&self) -> u64 {
        self.src.len()
    }

    fn read_at(&mut self, offset: u64, buf: &mut [u8]) -> Result<(), Error> {
        span_end(offset, 1, buf.len(), self.len())?;
        self.src.read_at(offset, buf).map_err(|_| Error::Source)
    }

    fn capacity(&self) -> usize {
        self.scratch.len()
    }

    fn fetch(&mut self, offset: u64, len: usize) -> Result<&[u8], Error> {
        let buf = self
            .scratch
            .get_mut(..len)
            .ok_or(Error::BufferTooSmall { needed: len })?;
        self.src.read_at(offset, buf).map_err(|_| Error::Source)?;
        Ok(buf)
    }
}
