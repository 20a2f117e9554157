//! The proxies section's bytes, little-endian, validated as they stream past so that the
//! resident and the streamed reader run the same checks:
//!
//! ```text
//! offset       size  field
//! 0            4     P proxies, u32, 1..=64
//! 4            4     B bones, u32, the header's bone count
//! 8            4     cull: the smallest cap kept, in sin²α, f32 in [0, 1)
//! 12           4     reserved, 0
//! 16           20 P  per proxy: bone u32 (< B), centre 3 × f32 (bind pose), radius f32 (> 0)
//! 16 + 20 P    24 B  per bone: centre 3 × f32 and radius f32 (≥ 0) bounding the vertices
//!                    whose bone it is (bind pose), then a u64 mask of the proxies that never
//!                    occlude them (bit i: proxy i; no bit at or above P)
//! ```

use crate::blob::Error;
use crate::blob::format::SectionKind;

/// Most proxies of one model: one `u64` mask per bone says which may touch it.
pub const MAX_PROXIES: usize = 64;

/// Bytes before the proxy records.
pub const PRELUDE: usize = 16;
/// Bytes of one proxy record.
pub const PROXY_RECORD: usize = 20;
/// Bytes of one bone record.
pub const BONE_RECORD: usize = 24;

/// Bytes of a proxies section of `proxies` spheres over `bones` bones, `None` on overflow.
pub fn proxies_len(proxies: usize, bones: usize) -> Option<u64> {
    let p = (proxies as u64).checked_mul(PROXY_RECORD as u64)?;
    let b = (bones as u64).checked_mul(BONE_RECORD as u64)?;
    (PRELUDE as u64).checked_add(p)?.checked_add(b)
}

fn f32_at(record: &[u8], at: usize) -> f32 {
    let mut w = [0u8; 4];
    w.copy_from_slice(&record[at..at + 4]);
    f32::from_le_bytes(w)
}

fn u32_at(record: &[u8], at: usize) -> u32 {
    let mut w = [0u8; 4];
    w.copy_from_slice(&record[at..at + 4]);
    u32::from_le_bytes(w)
}

/// A proxy record: its bone, bind-pose centre and radius.
pub(crate) fn proxy_record(record: &[u8]) -> (u32, [f32; 3], f32) {
    let centre = [f32_at(record, 4), f32_at(record, 8), f32_at(record, 12)];
    (u32_at(record, 0), centre, f32_at(record, 16))
}

/// A bone record: its bounding centre and radius, and the mask of proxies it ignores.
pub(crate) fn bone_record(record: &[u8]) -> ([f32; 3], f32, u64) {
    let centre = [f32_at(record, 0), f32_at(record, 4), f32_at(record, 8)];
    let mask = u64::from(u32_at(record, 16)) | (u64::from(u32_at(record, 20)) << 32);
    (centre, f32_at(record, 12), mask)
}

/// The prelude: proxy count, bone count and the cull threshold.
pub(crate) fn prelude(bytes: &[u8; PRELUDE]) -> (u32, u32, f32, u32) {
    (
        u32_at(bytes, 0),
        u32_at(bytes, 4),
        f32_at(bytes, 8),
        u32_at(bytes, 12),
    )
}

/// Validates a proxies section as it streams past: the counts, the cull threshold, every
/// value finite, radii positive, bones below the count, masks within the proxies, and the
/// length the counts imply.
pub(crate) struct ProxyCheck {
    bones: usize,
    seen: u64,
    record: [u8; BONE_RECORD],
    filled: usize,
    proxies: usize,
    /// The prelude was read and valid: its counts say the length.
    counted: bool,
    bad: bool,
}

impl ProxyCheck {
    /// A check for a model of `bones` bones.
    pub(crate) fn new(bones: usize) -> ProxyCheck {
        ProxyCheck {
            bones,
            seen: 0,
            record: [0; BONE_RECORD],
            filled: 0,
            proxies: 0,
            counted: false,
            bad: false,
        }
    }

    /// Bytes of the record the next byte belongs to, 0 past the end.
    fn record_len(&self) -> usize {
        let proxies_end = PRELUDE as u64 + self.proxies as u64 * PROXY_RECORD as u64;
        match self.seen {
            s if s < PRELUDE as u64 => PRELUDE,
            s if s < proxies_end => PROXY_RECORD,
            _ => BONE_RECORD,
        }
    }

    pub(crate) fn feed(&mut self, bytes: &[u8]) {
        for &b in bytes {
            let len = self.record_len();
            self.record[self.filled] = b;
            self.filled += 1;
            self.seen += 1;
            if self.filled == len {
                self.filled = 0;
                self.check_record(len);
            }
        }
    }

    fn check_record(&mut self, len: usize) {
        let r = &self.record[..len];
        let finite = |xs: &[f32]| xs.iter().all(|x| x.is_finite());
        self.bad |= match len {
            PRELUDE => {
                let mut p = [0u8; PRELUDE];
                p.copy_from_slice(r);
                let (proxies, bones, cull, reserved) = prelude(&p);
                self.proxies = proxies as usize;
                let bad = !(1..=MAX_PROXIES as u32).contains(&proxies)
                    || bones as usize != self.bones
                    || !(cull.is_finite() && (0.0..1.0).contains(&cull))
                    || reserved != 0;
                self.counted = !bad;
                bad
            }
            PROXY_RECORD => {
                let (bone, centre, radius) = proxy_record(r);
                bone as usize >= self.bones
                    || !finite(&centre)
                    || !(radius.is_finite() && radius > 0.0)
            }
            _ => {
                let (centre, radius, mask) = bone_record(r);
                let beyond = mask.checked_shr(self.proxies as u32).unwrap_or(0) != 0;
                !(finite(&centre) && radius.is_finite() && radius >= 0.0) || beyond
            }
        };
    }

    /// Ok when every record was valid and the length is the one the counts imply: a valid
    /// prelude announcing another length is [`Error::SectionLength`], anything else wrong
    /// [`Error::BadProxies`].
    pub(crate) fn finish(self) -> Result<(), Error> {
        let expected = proxies_len(self.proxies, self.bones).ok_or(Error::LengthOverflow)?;
        if self.counted && expected != self.seen {
            return Err(Error::SectionLength {
                section: SectionKind::Proxies,
                expected,
                found: self.seen,
            });
        }
        if self.bad || !self.counted {
            return Err(Error::BadProxies);
        }
        Ok(())
    }
}
