//! Pose features in trainer precision: the angles, then `1 − cos a` of each flagged entry, as
//! aprt-core computes them from its `PoseFeatures` section. The cosine is even in the angle,
//! so a model linear in the features can learn shadowing that is the same whichever way a
//! joint turns; near 0 it is `a²/2`, and it stays below 2 however far a joint turns.

use nalgebra::DMatrix;

/// `1 − cos a`, as `2 sin²(a/2)` (no cancellation near 0).
pub fn versine(a: f64) -> f64 {
    let s = (0.5 * a).sin();
    2.0 * s * s
}

/// Which entries of a pose vector add their cosine feature.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PoseFeatures {
    pose_len: usize,
    /// The flagged entries, ascending: feature `pose_len + k` is the versine of `cosines[k]`.
    cosines: Vec<usize>,
}

impl PoseFeatures {
    /// The features of `flags` (one per entry; missing entries are unflagged).
    pub fn new(pose_len: usize, flags: &[bool]) -> Self {
        let cosines = (0..pose_len)
            .filter(|&i| flags.get(i).copied().unwrap_or(false))
            .collect();
        Self { pose_len, cosines }
    }

    /// The number of features f: the angles and the flagged cosines.
    pub fn count(&self) -> usize {
        self.pose_len + self.cosines.len()
    }

    /// One flag per entry, as the model stores them: whether its cosine is a feature.
    pub fn flags(&self) -> Vec<bool> {
        (0..self.pose_len)
            .map(|i| self.cosines.binary_search(&i).is_ok())
            .collect()
    }

    /// Whether the features are the angles alone.
    pub fn is_angles(&self) -> bool {
        self.cosines.is_empty()
    }

    /// The features of one pose vector.
    pub fn of(&self, angles: &[f64]) -> Vec<f64> {
        let cosines = self.cosines.iter().map(|&i| versine(angles[i]));
        angles[..self.pose_len]
            .iter()
            .copied()
            .chain(cosines)
            .collect()
    }

    /// The features of each row of `angles` (`p × a` → `p × f`).
    pub fn of_rows(&self, angles: &DMatrix<f64>) -> DMatrix<f64> {
        let mut out = DMatrix::zeros(angles.nrows(), self.count());
        for (r, row) in angles.row_iter().enumerate() {
            let x = self.of(row.transpose().as_slice());
            out.row_mut(r).copy_from_slice(&x);
        }
        out
    }

    /// The features that depend on `entries` (ascending): each entry and its cosine.
    pub fn of_entries(&self, entries: &[usize]) -> Vec<usize> {
        let cosines = self
            .cosines
            .iter()
            .enumerate()
            .filter(|(_, i)| entries.contains(i))
            .map(|(k, _)| self.pose_len + k);
        entries.iter().copied().chain(cosines).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn versine_is_one_minus_cosine_and_exact_near_zero() {
        for a in [-3.0, -1.0, -0.25, 0.5, 2.0, 3.1] {
            assert!((versine(a) - (1.0 - f64::cos(a))).abs() < 1e-15, "{a}");
        }
        // 1 − cos(1e-9) is 0 in f64; the versine keeps a²/2.
        assert_eq!(versine(1e-9) / 5e-19, 1.0);
        assert_eq!(versine(0.3), versine(-0.3));
    }

    #[test]
    fn features_are_the_angles_then_the_flagged_cosines() {
        let f = PoseFeatures::new(3, &[true, false, true]);
        assert_eq!(f.count(), 5);
        let x = f.of(&[0.5, -1.0, 2.0]);
        assert_eq!(&x[..3], &[0.5, -1.0, 2.0]);
        assert_eq!(x[3], versine(0.5));
        assert_eq!(x[4], versine(2.0));
        assert_eq!(f.of_entries(&[1, 2]), vec![1, 2, 4]);
        assert_eq!(f.flags(), vec![true, false, true]);
        let none = PoseFeatures::new(3, &[]);
        assert!(none.is_angles());
        assert_eq!(none.of(&[1.0, 2.0, 3.0]), vec![1.0, 2.0, 3.0]);
        let rows = f.of_rows(&DMatrix::from_row_slice(
            2,
            3,
            &[0.5, -1.0, 2.0, 0.0, 0.0, 0.0],
        ));
        assert_eq!(rows.row(0).iter().copied().collect::<Vec<_>>(), x);
        assert_eq!(
            rows.row(1).iter().copied().collect::<Vec<_>>(),
            vec![0.0; 5]
        );
    }
}
