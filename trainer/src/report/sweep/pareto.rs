//! The Pareto front of measured settings, the recommendation inside a budget (near-ties in
//! error go to the cheaper setting), and the named presets read off the front.

/// One measured setting, as the front sees it: lower is better on every axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cost {
    /// Error.
    pub error: f64,
    /// Microseconds per frame.
    pub us: f64,
    /// Bytes.
    pub bytes: f64,
}

/// For each point, whether no other point is at least as good on both `error` and `axis` and
/// strictly better on one (ties keep every tied point on the front).
pub fn front(points: &[Cost], axis: impl Fn(&Cost) -> f64) -> Vec<bool> {
    points
        .iter()
        .map(|p| {
            !points.iter().any(|q| {
                let (qe, qa, pe, pa) = (q.error, axis(q), p.error, axis(p));
                qe <= pe && qa <= pa && (qe < pe || qa < pa)
            })
        })
        .collect()
}

/// Errors this close to the lowest are ties, in grey levels: a twentieth of an 8-bit level
/// is far below what a viewer sees and within the sweep's own noise between runs.
pub const TIE_GREY: f64 = 0.05;

/// Errors within this fraction of the lowest are ties too, where 1 % of it is more than
/// [`TIE_GREY`].
pub const TIE_FRACTION: f64 = 0.01;

/// The recommendation within the budgets (`None`: no limit): among the points that fit, the
/// lowest error `e` is found; every point whose error is within `max(TIE_GREY, TIE_FRACTION ·
/// e)` of it ties, and the cheapest of the ties in µs a frame is chosen (the more accurate
/// of equally cheap ones), so a negligible gain in error never costs twice the time. `None`
/// when no point fits.
pub fn recommend(points: &[Cost], us: Option<f64>, bytes: Option<f64>) -> Option<usize> {
    let fits = |p: &&Cost| us.is_none_or(|b| p.us <= b) && bytes.is_none_or(|b| p.bytes <= b);
    let best = points
        .iter()
        .filter(fits)
        .map(|p| p.error)
        .min_by(f64::total_cmp)?;
    let tie = best + TIE_GREY.max(TIE_FRACTION * best);
    points
        .iter()
        .enumerate()
        .filter(|(_, p)| fits(p) && p.error <= tie)
        .min_by(|(_, a), (_, b)| a.us.total_cmp(&b.us).then(a.error.total_cmp(&b.error)))
        .map(|(i, _)| i)
}

/// The named presets: the fastest point of the error-against-time front, the most accurate,
/// and between them the knee, the front point closest to the ideal corner when both axes are
/// put on a log scale spanning the front (so a tenfold saving counts the same on either axis).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct Presets {
    /// Index of the fastest point on the front.
    pub fastest: usize,
    /// Index of the knee.
    pub balanced: usize,
    /// Index of the most accurate point.
    pub best: usize,
}

/// The presets of `points` on their error-against-time front; `None` for no points.
pub fn presets(points: &[Cost]) -> Option<Presets> {
    let on = front(points, |c| c.us);
    let members: Vec<usize> = (0..points.len()).filter(|&i| on[i]).collect();
    let by = |f: &dyn Fn(&Cost) -> f64| {
        members
            .iter()
            .copied()
            .min_by(|&a, &b| f(&points[a]).total_cmp(&f(&points[b])))
    };
    let fastest = by(&|c| c.us)?;
    let best = by(&|c| c.error)?;
    let span = |f: &dyn Fn(&Cost) -> f64| {
        let logs: Vec<f64> = members
            .iter()
            .map(|&i| f(&points[i]).max(1e-12).ln())
            .collect();
        let lo = logs.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = logs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        move |v: f64| {
            if hi > lo {
                (v.max(1e-12).ln() - lo) / (hi - lo)
            } else {
                0.0
            }
        }
    };
    let (ue, uu) = (span(&|c| c.error), span(&|c| c.us));
    let balanced = by(&|c| ue(c.error).hypot(uu(c.us)))?;
    Some(Presets {
        fastest,
        balanced,
        best,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cost(error: f64, us: f64, bytes: f64) -> Cost {
        Cost { error, us, bytes }
    }

    #[test]
    fn the_front_keeps_exactly_the_undominated_points() {
        let points = [
            cost(1.0, 100.0, 10.0), // best error
            cost(2.0, 50.0, 10.0),  // front
            cost(3.0, 60.0, 5.0),   // dominated in time by the one above, best bytes
            cost(4.0, 10.0, 50.0),  // fastest
            cost(2.0, 50.0, 20.0),  // tie with the second in error and time: kept
        ];
        assert_eq!(front(&points, |c| c.us), [true, true, false, true, true]);
        assert_eq!(
            front(&points, |c| c.bytes),
            [true, false, true, false, false]
        );
    }

    #[test]
    fn the_recommendation_is_the_most_accurate_point_within_the_budget() {
        let points = [
            cost(1.0, 100.0, 10.0),
            cost(2.0, 50.0, 10.0),
            cost(2.0, 40.0, 10.0),
            cost(4.0, 10.0, 50.0),
        ];
        assert_eq!(recommend(&points, None, None), Some(0));
        assert_eq!(recommend(&points, Some(99.0), None), Some(2));
        assert_eq!(recommend(&points, Some(50.0), Some(20.0)), Some(2));
        assert_eq!(recommend(&points, Some(20.0), None), Some(3));
        assert_eq!(recommend(&points, Some(20.0), Some(20.0)), None);
        assert_eq!(recommend(&points, Some(5.0), None), None);
        assert_eq!(recommend(&[], None, None), None);
        assert_eq!(recommend(&[], Some(1.0), Some(1.0)), None);
    }

    /// The case: an f32 model 0.03 grey levels better than an i8 one at twice its
    /// time. The gain is a tie, so the cheaper one is recommended; a gain past the tolerance
    /// is not a tie.
    #[test]
    fn a_near_tie_that_costs_twice_the_time_loses_to_the_cheaper_point() {
        let f32 = cost(2.00, 60.0, 40.0);
        let i8 = cost(2.03, 30.0, 10.0);
        assert_eq!(recommend(&[f32, i8], None, None), Some(1));
        assert_eq!(recommend(&[i8, f32], None, None), Some(0));
        // 0.06 grey levels is more than max(0.05, 1 % of 2.0): not a tie.
        let worse = cost(2.06, 30.0, 10.0);
        assert_eq!(recommend(&[f32, worse], None, None), Some(0));
        // At large errors the tolerance is 1 %: 0.9 on 100 ties, 1.1 does not.
        let big = cost(100.0, 60.0, 1.0);
        let (near, far) = (cost(100.9, 30.0, 1.0), cost(101.1, 30.0, 1.0));
        assert_eq!(recommend(&[big, near], None, None), Some(1));
        assert_eq!(recommend(&[big, far], None, None), Some(0));
        // A tie outside the budget is no candidate: the lowest error is found among the
        // points that fit, and the ties are taken among those.
        assert_eq!(recommend(&[f32, i8], Some(50.0), None), Some(1));
        assert_eq!(recommend(&[f32, i8], None, Some(5.0)), None);
        let slow = cost(2.01, 90.0, 1.0);
        assert_eq!(recommend(&[f32, slow], Some(80.0), None), Some(0));
    }

    #[test]
    fn presets_span_the_front_and_the_knee_lies_between() {
        let points = [
            cost(0.1, 1000.0, 1.0),
            cost(0.2, 100.0, 1.0),
            cost(0.3, 90.0, 1.0),
            cost(1.0, 80.0, 1.0),
            cost(10.0, 10.0, 1.0),
            cost(20.0, 2000.0, 1.0), // dominated
        ];
        let p = presets(&points).unwrap();
        assert_eq!((p.fastest, p.best), (4, 0));
        assert_eq!(p.balanced, 1);
        assert_eq!(presets(&[]), None);
        let one = presets(&[cost(1.0, 1.0, 1.0)]).unwrap();
        assert_eq!((one.fastest, one.balanced, one.best), (0, 0, 0));
    }
}
