//! How many components to keep from a spectrum: by count, by captured fraction, or all.
//!
//! Shared by the pose PCA and the vertex basis so both sides of the model read the same knob
//! the same way. The count is always capped by the numerical rank: directions with (almost)
//! zero energy carry no information, and keeping them would only add arbitrary basis vectors
//! (pose side: constant joints, collinear angles; vertex side: fewer distinct rows than asked).

/// A choice of reduced dimension.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Dims {
    /// Keep this many components (fewer if the numerical rank is lower).
    Count(usize),
    /// Keep the fewest leading components whose energy reaches this fraction of the total
    /// (a value in `(0, 1]`).
    Variance(f64),
    /// Keep every component up to the numerical rank (and, like `Variance`, no more than the
    /// runtime holds).
    All,
    /// Pose side only: the count is chosen by held-out error among counts up to what `All`
    /// keeps (see [`crate::model::fit::fit_input`]); elsewhere it reads as `All`.
    Auto,
}

impl Dims {
    /// The most components this choice may keep when the runtime holds `runtime`: all or a
    /// fraction stop there; an explicit count is kept as asked (the writer then says it is too
    /// many).
    pub fn cap(self, runtime: usize) -> usize {
        match self {
            Dims::Count(_) => usize::MAX,
            Dims::Variance(_) | Dims::All | Dims::Auto => runtime,
        }
    }
}

/// Number of singular values (sorted descending) above `max(m, n) · ε · σ_max`, the usual
/// threshold of LAPACK's rank decisions. `epsilon` is the unit roundoff of the data's storage:
/// transfer baked in f32 carries rounding noise at the f32 level, and singular values at that
/// level are indistinguishable from it.
pub fn numerical_rank(singular_values: &[f64], rows: usize, cols: usize, epsilon: f64) -> usize {
    let Some(&max) = singular_values.first() else {
        return 0;
    };
    if max <= 0.0 {
        return 0;
    }
    let tol = rows.max(cols) as f64 * epsilon * max;
    singular_values.iter().take_while(|&&s| s > tol).count()
}

/// Number of components to keep given the energies (squared singular values, descending),
/// the total energy the fractions refer to and the numerical rank.
///
/// For [`Dims::Variance`], returns `None` when the supplied energies do not reach the target
/// fraction: the caller holds only a leading part of the spectrum and must compute more.
pub fn choose(dims: Dims, energies: &[f64], total: f64, rank: usize) -> Option<usize> {
    let cap = rank.min(energies.len());
    match dims {
        Dims::Count(k) => Some(k.min(cap)),
        Dims::All | Dims::Auto => Some(cap),
        Dims::Variance(fraction) => {
            if total <= 0.0 {
                return Some(0);
            }
            let target = fraction * total;
            let mut captured = 0.0;
            for (k, e) in energies[..cap].iter().enumerate() {
                captured += e;
                // Rounding in the running sum must not push an exact fraction (e.g. 1.0)
                // one component past the rank.
                if captured >= target * (1.0 - 4.0 * f64::EPSILON * (k + 1) as f64) {
                    return Some(k + 1);
                }
            }
            (rank <= energies.len()).then_some(cap)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn variance_fraction_picks_smallest_count_reaching_target() {
        let e = [50.0, 30.0, 15.0, 4.0, 1.0];
        let total = 100.0;
        assert_eq!(choose(Dims::Variance(0.5), &e, total, 5), Some(1));
        assert_eq!(choose(Dims::Variance(0.8), &e, total, 5), Some(2));
        assert_eq!(choose(Dims::Variance(0.81), &e, total, 5), Some(3));
        assert_eq!(choose(Dims::Variance(0.99), &e, total, 5), Some(4));
        assert_eq!(choose(Dims::Variance(1.0), &e, total, 5), Some(5));
    }

    #[test]
    fn variance_fraction_beyond_partial_spectrum_asks_for_more() {
        // Only three leading energies known, of a total of 100 and rank 5.
        let e = [50.0, 30.0, 15.0];
        assert_eq!(choose(Dims::Variance(0.9), &e, 100.0, 5), Some(3));
        assert_eq!(choose(Dims::Variance(0.96), &e, 100.0, 5), None);
    }

    #[test]
    fn counts_are_capped_by_rank() {
        let e = [4.0, 1.0, 0.0];
        assert_eq!(choose(Dims::Count(3), &e, 5.0, 2), Some(2));
        assert_eq!(choose(Dims::All, &e, 5.0, 2), Some(2));
        assert_eq!(choose(Dims::Variance(1.0), &e, 5.0, 2), Some(2));
        assert_eq!(choose(Dims::Count(1), &e, 5.0, 2), Some(1));
    }

    #[test]
    fn rank_ignores_rounding_level_values() {
        assert_eq!(numerical_rank(&[3.0, 1.0, 1e-17], 10, 3, f64::EPSILON), 2);
        assert_eq!(numerical_rank(&[3.0, 1.0, 1e-7], 10, 3, f64::EPSILON), 3);
        assert_eq!(
            numerical_rank(&[3.0, 1.0, 1e-7], 10, 3, f32::EPSILON.into()),
            2
        );
        assert_eq!(numerical_rank(&[0.0, 0.0], 10, 3, f64::EPSILON), 0);
        assert_eq!(numerical_rank(&[], 0, 0, f64::EPSILON), 0);
    }
}
