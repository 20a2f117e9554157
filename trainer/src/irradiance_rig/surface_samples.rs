//! Points spread evenly over a character's surface, where an irradiance rig is fitted
//! (*Irradiance Rigs*, section 2.2, which spreads them by Lloyd's algorithm).

use rayon::prelude::*;

use crate::rig::mesh::Mesh;
use crate::rig::procedural::clips::SplitMix;

/// Lloyd rounds: the spread stops improving visibly after a handful (the largest gap between a
/// candidate and its nearest sample falls by under 2 % from round 8 to 16 on the creature).
const ROUNDS: usize = 8;
/// Candidates per sample: enough that each sample's cell holds dozens of surface points.
const CANDIDATES_PER_SAMPLE: usize = 32;
/// Most candidates in all, which bounds the cost (candidates × samples per round).
const MAX_CANDIDATES: usize = 65_536;

/// Area-weighted random points on the triangles of `meshes`, `count` in all, split between the
/// meshes by area. Degenerate triangles get none.
fn candidates(meshes: &[&Mesh], count: usize, rng: &mut SplitMix) -> Vec<[f64; 3]> {
    let mut triangles: Vec<([[f64; 3]; 3], f64)> = Vec::new();
    for mesh in meshes {
        for t in &mesh.triangles {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize].map(f64::from));
            let (u, v) = (sub(b, a), sub(c, a));
            let area = 0.5 * norm(cross(u, v));
            if area > 0.0 {
                triangles.push(([a, b, c], area));
            }
        }
    }
    let mut cdf = Vec::with_capacity(triangles.len());
    let mut total = 0.0;
    for (_, area) in &triangles {
        total += area;
        cdf.push(total);
    }
    if triangles.is_empty() {
        return Vec::new();
    }
    (0..count)
        .map(|_| {
            let pick = rng.next_unit() * total;
            let i = cdf.partition_point(|&c| c < pick).min(triangles.len() - 1);
            let [a, b, c] = triangles[i].0;
            // Uniform on the triangle: the square root folds the unit square onto it.
            let (r1, r2) = (rng.next_unit().sqrt(), rng.next_unit());
            let (wa, wb, wc) = (1.0 - r1, r1 * (1.0 - r2), r1 * r2);
            std::array::from_fn(|k| wa * a[k] + wb * b[k] + wc * c[k])
        })
        .collect()
}

/// `count` points spread evenly over the surfaces of `meshes` (the character in its bind pose
/// and its training poses, all in its root frame), deterministic for a `seed`: candidates drawn
/// by area, `count` of them as seeds, then Lloyd relaxation, each sample moved to the mean of
/// the candidates nearest it and snapped back to the candidate nearest that mean so it stays
/// on the surface. Fewer points come back only when there are fewer candidates than `count`
/// (a mesh with almost no area).
pub fn surface_samples(meshes: &[&Mesh], count: usize, seed: u64) -> Vec<[f64; 3]> {
    let mut rng = SplitMix(seed);
    let n_candidates = (count * CANDIDATES_PER_SAMPLE).clamp(count, MAX_CANDIDATES.max(count));
    let points = candidates(meshes, n_candidates, &mut rng);
    let mut samples: Vec<[f64; 3]> = points
        .iter()
        .step_by((points.len() / count.max(1)).max(1))
        .take(count)
        .copied()
        .collect();
    for _ in 0..ROUNDS {
        let owner: Vec<usize> = points.par_iter().map(|p| nearest(&samples, *p)).collect();
        let mut sums = vec![([0.0f64; 3], 0usize); samples.len()];
        for (p, &s) in points.iter().zip(&owner) {
            let (sum, n) = &mut sums[s];
            sum.iter_mut().zip(p).for_each(|(a, x)| *a += x);
            *n += 1;
        }
        let means: Vec<[f64; 3]> = sums
            .iter()
            .zip(&samples)
            .map(|((sum, n), old)| match n {
                0 => *old,
                n => sum.map(|x| x / *n as f64),
            })
            .collect();
        samples = means
            .par_iter()
            .map(|m| points[nearest(&points, *m)])
            .collect();
    }
    samples
}

/// Index of the point of `set` nearest `p` (the first on ties).
fn nearest(set: &[[f64; 3]], p: [f64; 3]) -> usize {
    let mut best = (f64::INFINITY, 0);
    for (i, q) in set.iter().enumerate() {
        let d = sub(*q, p);
        let d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        if d2 < best.0 {
            best = (d2, i);
        }
    }
    best.1
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn norm(a: [f64; 3]) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit square in z = 0 as two triangles.
    fn square() -> Mesh {
        Mesh::with_area_weighted_normals(
            vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [0.0, 1.0, 0.0],
            ],
            vec![[0, 1, 2], [0, 2, 3]],
        )
    }

    #[test]
    fn samples_lie_on_the_surface_and_spread_evenly() {
        let mesh = square();
        let samples = surface_samples(&[&mesh], 16, 7);
        assert_eq!(samples.len(), 16);
        assert!(
            samples
                .iter()
                .all(|p| p[2] == 0.0 && (0.0..=1.0).contains(&p[0]) && (0.0..=1.0).contains(&p[1]))
        );
        // Sixteen evenly spread points on a unit square are about 1/4 apart: no two within
        // a tenth, and no point of the square farther than 0.25 from every sample.
        for (i, a) in samples.iter().enumerate() {
            for b in &samples[..i] {
                assert!(norm(sub(*a, *b)) > 0.1, "{a:?} and {b:?} crowd");
            }
        }
        for x in 0..=10 {
            for y in 0..=10 {
                let p = [x as f64 / 10.0, y as f64 / 10.0, 0.0];
                let gap = norm(sub(samples[nearest(&samples, p)], p));
                assert!(gap < 0.25, "{p:?} is {gap} from every sample");
            }
        }
        assert_eq!(samples, surface_samples(&[&mesh], 16, 7), "deterministic");
    }

    #[test]
    fn degenerate_meshes_give_no_samples() {
        let flat = Mesh::with_area_weighted_normals(
            vec![[0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]],
            vec![[0, 1, 2]],
        );
        assert!(surface_samples(&[&flat], 4, 1).is_empty());
    }
}
