//! Fitting `k` spheres to one part: centres by k-means, radii so that the spheres' union
//! matches the part's sampled volume.

use glam::DVec3;

/// Lloyd iterations of the k-means. Clusters of a few thousand points settle in fewer than
/// ten from a farthest-point start (measured on the built-in character's limbs); more cost
/// nothing that matters and a fixed count keeps the fit deterministic.
const ITERATIONS: usize = 24;

/// Rounds of radius refinement: each sphere's radius is re-chosen given the others. The union's
/// misfit stops changing after two rounds on the built-in character; the third is a margin.
const RADIUS_ROUNDS: usize = 3;

/// `k` spheres and their misfit.
#[derive(Clone, Debug)]
pub(super) struct Spheres {
    pub centres: Vec<DVec3>,
    pub radii: Vec<f64>,
    /// Sample points in the union but not in the part, or in the part but not in the union.
    pub misfit: usize,
}

impl Spheres {
    /// The spheres of positive radius, as `(centre, radius)`.
    pub fn nonzero(&self) -> Vec<(DVec3, f64)> {
        self.centres
            .iter()
            .zip(&self.radii)
            .filter(|&(_, &r)| r > 0.0)
            .map(|(&c, &r)| (c, r))
            .collect()
    }
}

/// `k` (≥ 1, at most `points.len()`) centres by k-means over `points`: farthest-point
/// initialisation (the point farthest from the mean, then repeatedly the point farthest from
/// every chosen centre; the lowest index on ties), then [`ITERATIONS`] Lloyd steps (each point
/// to its nearest centre, lowest index on ties; a centre that loses every point stays). Returns
/// the centres and each point's cluster.
pub(super) fn kmeans(points: &[DVec3], k: usize) -> (Vec<DVec3>, Vec<usize>) {
    let mean = points.iter().sum::<DVec3>() / points.len() as f64;
    let mut far: Vec<f64> = points.iter().map(|p| p.distance_squared(mean)).collect();
    let mut centres = Vec::with_capacity(k);
    while centres.len() < k {
        let (i, _) = far
            .iter()
            .enumerate()
            .fold((0, f64::NEG_INFINITY), |best, (i, &d)| {
                if d > best.1 { (i, d) } else { best }
            });
        let c = points[i];
        centres.push(c);
        for (d, p) in far.iter_mut().zip(points) {
            // After the first centre, distances are to the chosen centres, not to the mean.
            let to_c = p.distance_squared(c);
            *d = if centres.len() == 1 {
                to_c
            } else {
                d.min(to_c)
            };
        }
    }
    let mut cluster = vec![0; points.len()];
    for _ in 0..ITERATIONS {
        assign(points, &centres, &mut cluster);
        let mut sums = vec![(DVec3::ZERO, 0usize); k];
        for (p, &c) in points.iter().zip(&cluster) {
            sums[c].0 += *p;
            sums[c].1 += 1;
        }
        for (centre, (sum, n)) in centres.iter_mut().zip(sums) {
            if n > 0 {
                *centre = sum / n as f64;
            }
        }
    }
    assign(points, &centres, &mut cluster);
    (centres, cluster)
}

fn assign(points: &[DVec3], centres: &[DVec3], cluster: &mut [usize]) {
    for (p, c) in points.iter().zip(cluster.iter_mut()) {
        *c = (0..centres.len())
            .min_by(|&a, &b| {
                p.distance_squared(centres[a])
                    .total_cmp(&p.distance_squared(centres[b]))
            })
            .unwrap_or(0);
    }
}

/// The radius of a ball whose points' RMS distance to its centre is `rms`: `rms·√(5/3)`.
/// Only the start of [`fit_radii`]; it decides which sphere covers what in the first round.
pub(super) fn ball_radius(points: &[DVec3], cluster: &[usize], centres: &[DVec3]) -> Vec<f64> {
    let mut sums = vec![(0.0, 0usize); centres.len()];
    for (p, &c) in points.iter().zip(cluster) {
        sums[c].0 += p.distance_squared(centres[c]);
        sums[c].1 += 1;
    }
    sums.into_iter()
        .map(|(s, n)| (s / n.max(1) as f64 * 5.0 / 3.0).sqrt())
        .collect()
}

/// Radii for spheres at `centres` (starting from `radii`) that minimise the misfit on the
/// samples `points` (`part[i]`: sample `i` is in the part). Coordinate descent: each sphere's
/// radius in turn becomes the exact minimiser of the misfit given the others (a sweep over the
/// sorted distances of the samples no other sphere covers), for [`RADIUS_ROUNDS`] rounds.
/// The misfit never grows from one step to the next. Among equally good radii the smallest is
/// taken, and a radius between two samples is their midpoint.
pub(super) fn fit_radii(
    points: &[DVec3],
    part: &[bool],
    centres: &[DVec3],
    mut radii: Vec<f64>,
) -> Spheres {
    let mut free = Vec::with_capacity(points.len());
    for _ in 0..RADIUS_ROUNDS {
        for i in 0..centres.len() {
            free.clear();
            free.extend(
                points
                    .iter()
                    .zip(part)
                    .filter(|(p, _)| {
                        !(0..centres.len()).any(|j| j != i && p.distance(centres[j]) <= radii[j])
                    })
                    .map(|(p, &inside)| (p.distance(centres[i]), inside)),
            );
            free.sort_by(|a, b| a.0.total_cmp(&b.0));
            // Misfit with radius below every distance: every free part sample is missed.
            let mut misfit = free.iter().filter(|s| s.1).count() as i64;
            let (mut best, mut best_r) = (misfit, 0.0);
            for (k, &(d, inside)) in free.iter().enumerate() {
                misfit += if inside { -1 } else { 1 };
                let next = free.get(k + 1).map(|s| s.0);
                if next == Some(d) {
                    continue; // the radius cannot separate equal distances
                }
                if misfit < best {
                    best = misfit;
                    best_r = next.map_or(d, |n| 0.5 * (d + n));
                }
            }
            radii[i] = best_r;
        }
    }
    let misfit = misfit(points, part, centres, &radii);
    Spheres {
        centres: centres.to_vec(),
        radii,
        misfit,
    }
}

/// Mean-shift steps that move a new sphere's centre into the uncovered part.
const SHIFTS: usize = 4;

/// `previous` plus one sphere where the part is least covered: seeded at the uncovered part
/// sample farthest outside every sphere (the lowest index on ties), moved by [`SHIFTS`] steps
/// to the mean of the uncovered part samples within the largest radius of `previous` of it
/// (towards the middle of the uncovered piece rather than its edge), then every radius
/// refitted from the previous radii and 0 for the new one, so the misfit cannot grow.
pub(super) fn grow(points: &[DVec3], part: &[bool], previous: &Spheres) -> Spheres {
    let outside = |p: DVec3| {
        previous
            .centres
            .iter()
            .zip(&previous.radii)
            .map(|(c, r)| p.distance(*c) - r)
            .fold(f64::INFINITY, f64::min)
    };
    let uncovered: Vec<DVec3> = points
        .iter()
        .zip(part)
        .filter(|&(p, &inside)| inside && outside(*p) > 0.0)
        .map(|(p, _)| *p)
        .collect();
    let mut centres = previous.centres.clone();
    let mut radii = previous.radii.clone();
    let seed = uncovered
        .iter()
        .copied()
        .fold(None, |best: Option<DVec3>, p| match best {
            Some(b) if outside(b) >= outside(p) => Some(b),
            _ => Some(p),
        });
    let Some(mut centre) = seed else {
        // Nothing left to cover: the extra sphere stays empty.
        centres.push(previous.centres[0]);
        radii.push(0.0);
        return Spheres {
            centres,
            radii,
            misfit: previous.misfit,
        };
    };
    let reach = radii.iter().copied().fold(0.0, f64::max);
    for _ in 0..SHIFTS {
        let near: Vec<DVec3> = uncovered
            .iter()
            .copied()
            .filter(|p| p.distance(centre) <= reach)
            .collect();
        if !near.is_empty() {
            centre = near.iter().sum::<DVec3>() / near.len() as f64;
        }
    }
    centres.push(centre);
    radii.push(0.0);
    fit_radii(points, part, &centres, radii)
}

/// Samples in exactly one of the union of the spheres and the part.
pub(super) fn misfit(points: &[DVec3], part: &[bool], centres: &[DVec3], radii: &[f64]) -> usize {
    points
        .iter()
        .zip(part)
        .filter(|&(p, &inside)| {
            let covered = centres.iter().zip(radii).any(|(c, &r)| p.distance(*c) <= r);
            covered != inside
        })
        .count()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::proxies::solid::box_points;

    #[test]
    fn two_blobs_get_one_centre_each() {
        let mut points = box_points(DVec3::splat(-1.0), DVec3::splat(1.0), 0, 300);
        points.extend(box_points(DVec3::splat(9.0), DVec3::splat(11.0), 300, 200));
        let (centres, cluster) = kmeans(&points, 2);
        let mut c = centres.clone();
        c.sort_by(|a, b| a.x.total_cmp(&b.x));
        assert!(
            c[0].length() < 0.1 && c[1].distance(DVec3::splat(10.0)) < 0.1,
            "{c:?}"
        );
        assert!(cluster[..300].iter().all(|&k| k == cluster[0]));
        assert!(cluster[300..].iter().all(|&k| k != cluster[0]));
    }

    #[test]
    fn the_radius_of_a_ball_is_found_from_its_samples() {
        let points = box_points(DVec3::splat(-2.0), DVec3::splat(2.0), 0, 8000);
        let part: Vec<bool> = points.iter().map(|p| p.length() <= 1.3).collect();
        let fit = fit_radii(&points, &part, &[DVec3::ZERO], vec![0.2]);
        assert!((fit.radii[0] - 1.3).abs() < 0.02, "{:?}", fit.radii);
        assert!(fit.misfit < 40, "{}", fit.misfit);
    }
}
