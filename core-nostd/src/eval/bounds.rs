//! The pose bound: a pose outside the training poses is brought back inside their box and,
//! the further outside it was, blended towards the prior's pose, where the model's transfer
//! is its prior (the rest transfer carried by the skin, or the mean). A linear model's
//! extrapolation is unbounded; this keeps a novel pose from ever being lit by a transfer that
//! grows without limit, at a cost of a few operations per pose entry.

use super::kernels::RowRef;
use crate::blob::format::MAX_POSE_LEN;
use crate::blob::{Error, ModelInfo, Reader};
use crate::math::sqrt_f64;

/// Rows of the pose-bounds section, in order.
const LO: usize = 0;
const HI: usize = 1;
const SCALE: usize = 2;

/// `row` decoded into `out` (its first `out.len()` values).
fn decode(row: RowRef<'_>, out: &mut [f32]) {
    out.fill(0.0);
    row.add_scaled(1.0, out.iter_mut());
}

impl ModelInfo {
    /// The bounded pose of `angles` (finite, `pose_len` values) in `out`: `c = clamp(a, lo,
    /// hi)`, `d = ‖(a − c) · scale‖`, `β = max(0, 1 − d)`, `out = prior + β (c − prior)`.
    /// Without a bound, `out = a`. The distance and the blend are computed in f64, so no
    /// finite pose overflows.
    pub(crate) fn bound_pose<R: Reader>(
        &self,
        r: &mut R,
        angles: &[f32],
        out: &mut [f32],
    ) -> Result<(), Error> {
        out.copy_from_slice(angles);
        let Some(span) = self.pose_bounds else {
            return Ok(());
        };
        let a = self.pose_len;
        let mut row = [0.0f32; MAX_POSE_LEN];
        let row = &mut row[..a];
        let mut d2 = 0.0f64;
        self.each_row(r, span, a, |i, values| {
            decode(values, row);
            match i {
                LO => out
                    .iter_mut()
                    .zip(&*row)
                    .for_each(|(x, lo)| *x = x.max(*lo)),
                HI => out
                    .iter_mut()
                    .zip(&*row)
                    .for_each(|(x, hi)| *x = x.min(*hi)),
                SCALE => {
                    d2 = angles
                        .iter()
                        .zip(&*out)
                        .zip(&*row)
                        .map(|((&x, &c), &s)| {
                            let e = (f64::from(x) - f64::from(c)) * f64::from(s);
                            e * e
                        })
                        .sum();
                }
                _ => {
                    let beta = (1.0 - sqrt_f64(d2)).max(0.0);
                    for (x, &prior) in out.iter_mut().zip(&*row) {
                        let prior = f64::from(prior);
                        *x = (prior + beta * (f64::from(*x) - prior)) as f32;
                    }
                }
            }
        })
    }

    /// Checks the bound's rows: `lo ≤ prior ≤ hi` and `scale ≥ 0` for every entry. Read value
    /// by value, so any scratch that holds one f32 will do (the buffer is checked after).
    pub(crate) fn verify_bounds<R: Reader>(&self, r: &mut R) -> Result<(), Error> {
        let Some(span) = self.pose_bounds else {
            return Ok(());
        };
        let a = self.pose_len;
        let (mut lo, mut hi) = ([0.0f32; MAX_POSE_LEN], [0.0f32; MAX_POSE_LEN]);
        let mut ok = true;
        r.chunks(span.offset, 4, 4 * a, |first, bytes| {
            for (i, x) in bytes.as_chunks::<4>().0.iter().enumerate() {
                let (row, j, x) = ((first + i) / a, (first + i) % a, f32::from_le_bytes(*x));
                match row {
                    LO => lo[j] = x,
                    HI => hi[j] = x,
                    SCALE => ok &= x >= 0.0,
                    _ => ok &= lo[j] <= x && x <= hi[j],
                }
            }
            Ok(())
        })?;
        if ok {
            Ok(())
        } else {
            Err(Error::BadPoseBounds)
        }
    }
}
