//! Choosing among candidates whose validation errors differ by less than their noise.
//!
//! A validation set is a sample of the poses the model will meet: the difference between two
//! candidates' mean errors on it has a standard error, and a lead smaller than that is noise
//! (the CMU mannequin's rest prior won its held-out runs by 0.14 % and lost the test clip).
//! The rule is the one-standard-error rule of model selection: every candidate whose mean
//! error exceeds the best's by at most one standard error of the paired difference (over the
//! same poses) ties with it, and the simplest of those is chosen, the lowest mean among equally
//! simple ones. Simpler means fewer pose dimensions, the angles before their cosines, no
//! occluder proxies before proxies: what extrapolates more safely and costs less a frame.
//!
//! Without per-pose errors (held-out runs of the training clip, whose poses are not
//! independent) the lowest mean wins, as it always did.

/// The rule, as the selection report states it.
pub const RULE: &str = "within one standard error of the best (paired over the validation \
                        poses) a candidate ties with it, and the simplest of the tied wins";

/// One candidate offered to [`choose`].
#[derive(Clone, Copy, Debug)]
pub struct Offer<'a> {
    /// Its mean validation error (a non-finite one never wins while a finite one exists).
    pub error: f64,
    /// Its error on each validation pose, when known (the same poses for every offer).
    pub rows: Option<&'a [f64]>,
    /// Lower is simpler.
    pub complexity: usize,
}

/// What [`choose`] decided and by how much.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Verdict {
    /// The offer chosen.
    pub chosen: usize,
    /// The offer of lowest mean error.
    pub best: usize,
    /// The chosen offer's mean error minus the best's; when the best is chosen, its nearest
    /// rival's minus its own (its lead).
    pub margin: f64,
    /// The standard error of the difference between the chosen and the best offers (for
    /// the best itself, that of its nearest rival's difference); 0 without per-pose errors.
    pub standard_error: f64,
    /// Poses the standard error is over (0 without per-pose errors).
    pub poses: usize,
    /// Whether the chosen offer is not the best, chosen by the rule.
    pub tie: bool,
}

/// The offer of lowest mean (the first on equal means, a finite one before any other), or by
/// the rule above the simplest offer within one standard error of it. `None` for no offers.
pub fn choose(offers: &[Offer<'_>]) -> Option<Verdict> {
    let best = (0..offers.len()).min_by(|&a, &b| {
        let key = |i: usize| (!offers[i].error.is_finite(), offers[i].error);
        let (ka, kb) = (key(a), key(b));
        ka.0.cmp(&kb.0).then(ka.1.total_cmp(&kb.1))
    })?;
    let plain = Verdict {
        chosen: best,
        best,
        margin: 0.0,
        standard_error: 0.0,
        poses: 0,
        tie: false,
    };
    let Some(best_rows) = offers[best].rows.filter(|_| offers[best].error.is_finite()) else {
        return Some(plain);
    };
    // Every finite offer on the same poses, with its paired standard error against the best.
    let rivals: Vec<(usize, f64)> = (0..offers.len())
        .filter(|&i| i != best && offers[i].error.is_finite())
        .filter_map(|i| {
            let rows = offers[i].rows.filter(|r| r.len() == best_rows.len())?;
            Some((i, paired_standard_error(rows, best_rows)))
        })
        .collect();
    let tied = rivals
        .iter()
        .filter(|&&(i, se)| offers[i].error - offers[best].error <= se);
    let simplest = tied.min_by(|&&(a, _), &&(b, _)| {
        let key = |i: usize| (offers[i].complexity, offers[i].error);
        let (ka, kb) = (key(a), key(b));
        ka.0.cmp(&kb.0).then(ka.1.total_cmp(&kb.1))
    });
    let poses = best_rows.len();
    Some(match simplest {
        Some(&(i, se)) if offers[i].complexity < offers[best].complexity => Verdict {
            chosen: i,
            margin: offers[i].error - offers[best].error,
            standard_error: se,
            poses,
            tie: true,
            ..plain
        },
        _ => {
            // The best's lead over its nearest rival, and that difference's noise.
            let nearest = rivals
                .iter()
                .min_by(|&&(a, _), &&(b, _)| offers[a].error.total_cmp(&offers[b].error));
            let (margin, standard_error) = nearest.map_or((0.0, 0.0), |&(i, se)| {
                (offers[i].error - offers[best].error, se)
            });
            Verdict {
                margin,
                standard_error,
                poses,
                ..plain
            }
        }
    })
}

/// The standard error of the mean of `a − b` over the poses (0 for fewer than two).
fn paired_standard_error(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len();
    if n < 2 {
        return 0.0;
    }
    let d: Vec<f64> = a.iter().zip(b).map(|(x, y)| x - y).collect();
    let mean = d.iter().sum::<f64>() / n as f64;
    let variance = d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
    (variance / n as f64).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn offer(error: f64, rows: Option<&[f64]>, complexity: usize) -> Offer<'_> {
        Offer {
            error,
            rows,
            complexity,
        }
    }

    #[test]
    fn without_rows_the_lowest_mean_wins() {
        let v = choose(&[
            offer(2.0, None, 0),
            offer(1.0, None, 5),
            offer(1.0, None, 1),
        ])
        .unwrap();
        assert_eq!((v.chosen, v.best, v.tie), (1, 1, false));
        assert!(choose(&[]).is_none());
        // A finite error beats any other, whatever comes first.
        let v = choose(&[offer(f64::NAN, None, 0), offer(3.0, None, 1)]).unwrap();
        assert_eq!(v.chosen, 1);
    }

    #[test]
    fn a_lead_inside_the_noise_goes_to_the_simpler() {
        // The complex offer leads by 0.1 on average, with differences of ±1: noise.
        let simple = [1.0, 2.0, 1.0, 2.0, 1.0, 2.0, 1.0, 2.0];
        let complex = [0.0, 3.0, 0.0, 3.0, 0.0, 3.0, 0.0, 2.2];
        let mean = |r: &[f64]| r.iter().sum::<f64>() / r.len() as f64;
        let offers = [
            offer(mean(&simple), Some(&simple), 0),
            offer(mean(&complex), Some(&complex), 4),
        ];
        let v = choose(&offers).unwrap();
        assert_eq!((v.chosen, v.best, v.tie, v.poses), (0, 1, true, 8));
        assert!((v.margin - 0.1).abs() < 1e-12);
        // The paired differences: +1, −1, …, −0.2 → their standard error.
        let d = [1.0, -1.0, 1.0, -1.0, 1.0, -1.0, 1.0, -0.2];
        let m = mean(&d);
        let se = (d.iter().map(|x| (x - m).powi(2)).sum::<f64>() / 7.0 / 8.0).sqrt();
        assert!((v.standard_error - se).abs() < 1e-12);
        assert!(v.margin <= v.standard_error);
    }

    #[test]
    fn a_lead_beyond_the_noise_stands() {
        // Better on every pose by 0.5 ± 0.01: the complex offer wins.
        let simple = [1.0, 2.0, 3.0, 4.0];
        let complex = [0.5, 1.49, 2.51, 3.5];
        let offers = [offer(2.5, Some(&simple), 0), offer(2.0, Some(&complex), 4)];
        let v = choose(&offers).unwrap();
        assert_eq!((v.chosen, v.best, v.tie), (1, 1, false));
        assert!((v.margin - 0.5).abs() < 1e-12 && v.standard_error < 0.01);
    }

    #[test]
    fn the_best_stays_when_nothing_simpler_ties() {
        let a = [1.0, 2.0];
        let b = [1.0, 2.1];
        let v = choose(&[offer(1.5, Some(&a), 0), offer(1.55, Some(&b), 3)]).unwrap();
        assert_eq!((v.chosen, v.tie), (0, false));
    }
}
