//! Gathering per-sample values into a map, and the gutter rings dilated around the covered
//! texels. Which texels each ring holds depends only on coverage, so it is worked out once,
//! at build, and [`Rings::gather`] only averages.

use rayon::prelude::*;

use super::{GUTTER, TexelSample};

/// Ring of a texel no ring reaches: it stays zero.
const EMPTY: u8 = u8::MAX;

/// Each texel's ring (0 covered, `k` filled by the `k`-th dilation, [`EMPTY`] beyond) and the
/// texels of each ring `1..=GUTTER`, in texel order.
#[derive(Clone, Debug)]
pub(super) struct Rings {
    resolution: usize,
    ring: Vec<u8>,
    dilated: Vec<Vec<u32>>,
}

impl Rings {
    /// The rings around the texels that have `samples`, at `resolution`².
    pub(super) fn around(samples: &[TexelSample], resolution: usize) -> Rings {
        let mut ring = vec![EMPTY; resolution * resolution];
        for s in samples {
            ring[s.texel as usize] = 0;
        }
        let mut dilated = Vec::with_capacity(GUTTER);
        for k in 1..=GUTTER as u8 {
            let previous = &ring;
            let grown: Vec<u32> = (0..resolution * resolution)
                .into_par_iter()
                .filter(|&t| {
                    previous[t] == EMPTY && neighbours(t, resolution).any(|n| previous[n] != EMPTY)
                })
                .map(|t| t as u32)
                .collect();
            for &t in &grown {
                ring[t as usize] = k;
            }
            dilated.push(grown);
        }
        Rings {
            resolution,
            ring,
            dilated,
        }
    }

    /// The map of `n2` values per texel: each covered texel the mean of its samples' `values`,
    /// then each ring's texels the mean of their neighbours in earlier rings.
    pub(super) fn gather(&self, samples: &[TexelSample], values: &[f32], n2: usize) -> Vec<f32> {
        let mut map = vec![0.0f32; self.ring.len() * n2];
        let mut start = 0;
        for group in samples.chunk_by(|a, b| a.texel == b.texel) {
            let texel = group[0].texel as usize;
            let out = &mut map[texel * n2..(texel + 1) * n2];
            for row in values[start * n2..(start + group.len()) * n2].chunks_exact(n2) {
                for (o, v) in out.iter_mut().zip(row) {
                    *o += v;
                }
            }
            let count = group.len() as f32;
            out.iter_mut().for_each(|o| *o /= count);
            start += group.len();
        }
        let mut sum = vec![0.0f32; n2];
        for (k, texels) in self.dilated.iter().enumerate() {
            let k = k as u8 + 1;
            for &t in texels {
                let t = t as usize;
                sum.iter_mut().for_each(|s| *s = 0.0);
                let mut count = 0.0f32;
                for n in neighbours(t, self.resolution).filter(|&n| self.ring[n] < k) {
                    for (s, v) in sum.iter_mut().zip(&map[n * n2..(n + 1) * n2]) {
                        *s += v;
                    }
                    count += 1.0;
                }
                for (o, s) in map[t * n2..(t + 1) * n2].iter_mut().zip(&sum) {
                    *o = s / count;
                }
            }
        }
        map
    }

    /// Whether each texel holds a value after [`Rings::gather`].
    pub(super) fn filled(&self) -> Vec<bool> {
        self.ring.iter().map(|&r| r != EMPTY).collect()
    }
}

/// The up to eight texels around texel `t` inside the map.
fn neighbours(t: usize, resolution: usize) -> impl Iterator<Item = usize> {
    let (x, y) = ((t % resolution) as isize, (t / resolution) as isize);
    let r = resolution as isize;
    (-1..=1)
        .flat_map(move |dy| (-1..=1).map(move |dx| (x + dx, y + dy)))
        .filter(move |&(nx, ny)| (nx, ny) != (x, y) && (0..r).contains(&nx) && (0..r).contains(&ny))
        .map(move |(nx, ny)| (ny * r + nx) as usize)
}
