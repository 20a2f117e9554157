//! Validating a rig's bytes as they stream past, so the resident reader (one slice) and the
//! streamed one (chunks through a caller's buffer) run the very same checks.

use super::shape::{AxisKind, MAX_RIG_VECTORS, RigShape};
use crate::blob::Error;

/// Bytes before the arrays: the 16-byte prelude, the box and the radius.
pub(crate) const PRELUDE: usize = 44;
/// Most sample points of a rig.
pub const MAX_RIG_SAMPLES: usize = 4096;
/// Most entries of a rig's error table.
pub const MAX_RIG_TABLE: usize = 64;

/// What the prelude announces.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Layout {
    pub(crate) shape: RigShape,
    /// Samples N.
    pub(crate) samples: usize,
    /// Error-table entries M.
    pub(crate) table: usize,
    /// Bytes of the whole rig.
    pub(crate) len: usize,
}

fn u32_at(bytes: &[u8], at: usize) -> usize {
    let word: [u8; 4] = core::array::from_fn(|i| bytes[at + i]);
    u32::from_le_bytes(word) as usize
}

/// The shape, the counts against their limits, a finite positive box and radius.
fn read_prelude(p: &[u8; PRELUDE]) -> Result<Layout, Error> {
    let axes = [1, 2, 3].map(|i| AxisKind::from_code(p[i]));
    let shape = match (p[0], axes) {
        (0, [Some(x), Some(y), Some(z)]) => RigShape::Product([x, y, z]),
        (1, _) if p[1..4] == [0, 0, 0] => RigShape::Gradient,
        _ => return Err(Error::BadIrradianceRig),
    };
    let (n, k, m) = (u32_at(p, 4), u32_at(p, 8), u32_at(p, 12));
    let limits_ok = (1..=MAX_RIG_SAMPLES).contains(&n)
        && k == shape.vectors()
        && (1..=MAX_RIG_VECTORS).contains(&k)
        && m <= MAX_RIG_TABLE;
    let values: [f32; 7] =
        core::array::from_fn(|i| f32::from_le_bytes(core::array::from_fn(|b| p[16 + 4 * i + b])));
    // Centre finite; half-widths and radius finite and positive.
    let geometry_ok = values.iter().all(|v| v.is_finite()) && values[3..].iter().all(|&v| v > 0.0);
    if !(limits_ok && geometry_ok) {
        return Err(Error::BadIrradianceRig);
    }
    Ok(Layout {
        shape,
        samples: n,
        table: m,
        // Within the limits this cannot overflow even a 32-bit usize.
        len: PRELUDE + 4 * (2 * m + 3 * n + k * n),
    })
}

/// A rig's bytes fed in any chunks: after the prelude, every value finite and the error table's
/// distances positive and increasing, its errors non-negative.
pub(crate) struct RigCheck {
    prelude: [u8; PRELUDE],
    seen: usize,
    layout: Option<Layout>,
    word: [u8; 4],
    last_distance: f32,
    error: Option<Error>,
}

impl RigCheck {
    pub(crate) fn new() -> RigCheck {
        RigCheck {
            prelude: [0; PRELUDE],
            seen: 0,
            layout: None,
            word: [0; 4],
            last_distance: 0.0,
            error: None,
        }
    }

    pub(crate) fn feed(&mut self, bytes: &[u8]) {
        for &b in bytes {
            if self.error.is_some() {
                return;
            }
            if self.seen < PRELUDE {
                self.prelude[self.seen] = b;
                self.seen += 1;
                if self.seen == PRELUDE {
                    match read_prelude(&self.prelude) {
                        Ok(layout) => self.layout = Some(layout),
                        Err(e) => self.error = Some(e),
                    }
                }
                continue;
            }
            let at = self.seen - PRELUDE;
            self.word[at % 4] = b;
            self.seen += 1;
            if at % 4 == 3 {
                self.value(at / 4, f32::from_le_bytes(self.word));
            }
        }
    }

    /// Checks value `i` after the prelude.
    fn value(&mut self, i: usize, v: f32) {
        let m = self.layout.map_or(0, |l| l.table);
        let ok = v.is_finite()
            && match (i < 2 * m, i % 2) {
                (true, 0) => {
                    let increasing = v > self.last_distance;
                    self.last_distance = v;
                    increasing
                }
                (true, _) => v >= 0.0,
                (false, _) => true,
            };
        if !ok {
            self.error = Some(Error::BadIrradianceRig);
        }
    }

    /// The layout, once every byte was fed; a length that is not the layout's is
    /// [`RigFailure::Length`] with the length it should have (the prelude's, when shorter).
    pub(crate) fn finish(self) -> Result<Layout, RigFailure> {
        if let Some(e) = self.error {
            return Err(RigFailure::Content(e));
        }
        match self.layout {
            Some(layout) if self.seen == layout.len => Ok(layout),
            Some(layout) => Err(RigFailure::Length {
                expected: layout.len,
            }),
            None => Err(RigFailure::Length { expected: PRELUDE }),
        }
    }
}

/// Why a rig's bytes were refused: its content, or its length against what its prelude says.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum RigFailure {
    Content(Error),
    Length { expected: usize },
}
