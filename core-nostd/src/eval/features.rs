//! Pose features: what the pose projection sees. The angles, then `1 − cos a` of each entry
//! the model flags: an even function of the angle, for occlusion that is the same whichever
//! way a joint turns (an arm lowered in front or behind the body shadows the hip alike), which
//! a model linear in the angles cannot represent. Computed as `2 sin²(a/2)`, which keeps its
//! precision near 0 where `1 − cos a` cancels. A few operations per flagged entry per pose.

use crate::blob::{Error, ModelInfo, Reader};
use crate::math::sin;

/// `1 − cos a`, as `2 sin²(a/2)`.
pub(crate) fn versine(a: f32) -> f32 {
    let s = sin(0.5 * a);
    2.0 * s * s
}

impl ModelInfo {
    /// Completes the pose features in place: `features` (`feature_len` values) holds the
    /// bounded angles in its first `pose_len` values, and gets the versine of each flagged
    /// entry, in entry order, after them.
    pub(crate) fn add_cosines<R: Reader>(
        &self,
        r: &mut R,
        features: &mut [f32],
    ) -> Result<(), Error> {
        let Some(span) = self.pose_features else {
            return Ok(());
        };
        let (angles, versines) = features.split_at_mut(self.pose_len);
        let mut next = versines.iter_mut();
        r.chunks(span.offset, 4, self.pose_len, |first, bytes| {
            for (i, word) in bytes.as_chunks::<4>().0.iter().enumerate() {
                if f32::from_le_bytes(*word) == 1.0
                    && let Some(v) = next.next()
                {
                    *v = versine(angles[first + i]);
                }
            }
            Ok(())
        })
    }
}
