//! Mode (d) of [`SignMode`](super::SignMode): a uniform absolute quantiser step per
//! coefficient map and a 2-D predictor over the `R × R` grid.
//!
//! Each value becomes the signed integer `q = round(v / step)` of its map's step; an L2
//! metric sees quantisation noise of `step² / 12` per value wherever it falls, so one step for
//! every map (chosen from an error target, not from each texel's largest value) is where the
//! bits buy the most error. `q` is then predicted from its filled neighbours on the grid with
//! LOCO-I's median edge detector (left, up, up-left; the one present if only left or up is;
//! their mean if up-left is missing; 0 with neither), and the residual, zigzagged to 16 bits,
//! is stored as a low-byte plane and a high-byte plane per map. Smooth maps leave residuals
//! near 0 and high planes of zeros, which zstd squeezes to almost nothing.
//!
//! Plane set: `n2` f32 steps, `n2` low-byte planes of `T` bytes, `n2` high-byte planes of `T`
//! bytes. The encoder keeps `|q| < 2^14` (raising a map's step if needed) so every residual
//! fits; the decoder accepts any bytes (wrapping integer arithmetic, finite steps ≥ 0).

/// The largest `|q|` the encoder writes: MED and mean predictions lie between two
/// neighbours, so residuals stay within `±2^15 − 2` and zigzag into a `u16`.
const Q_MAX: f64 = 16383.0;
/// No neighbour.
const NONE: u32 = u32::MAX;

/// The compact indices of each filled texel's left, up and up-left neighbours on the grid
/// (`u32::MAX` where that texel is outside the map or not filled).
#[derive(Debug, Clone, Default)]
pub struct Grid {
    neighbours: Vec<[u32; 3]>,
}

impl Grid {
    /// From the ascending texel indices of the filled texels of an `R × R` map. Linear in
    /// `T`, with no `R²` table (a hostile header may declare `R = 8192`).
    pub fn new(texels: &[usize], resolution: usize) -> Grid {
        let r = resolution.max(1);
        // Index in `texels` of the first entry ≥ target, advanced monotonically.
        let find = |cursor: &mut usize, target: usize| -> u32 {
            while *cursor < texels.len() && texels[*cursor] < target {
                *cursor += 1;
            }
            match texels.get(*cursor) {
                Some(&t) if t == target => *cursor as u32,
                _ => NONE,
            }
        };
        let (mut up_cursor, mut diag_cursor) = (0, 0);
        let neighbours = texels
            .iter()
            .enumerate()
            .map(|(i, &t)| {
                let (x, y) = (t % r, t / r);
                let left = if x > 0 && i > 0 && texels[i - 1] == t - 1 {
                    (i - 1) as u32
                } else {
                    NONE
                };
                let up = if y > 0 {
                    find(&mut up_cursor, t - r)
                } else {
                    NONE
                };
                let diag = if y > 0 && x > 0 {
                    find(&mut diag_cursor, t - r - 1)
                } else {
                    NONE
                };
                [left, up, diag]
            })
            .collect();
        Grid { neighbours }
    }

    /// `texels` texels in one row: each predicted from the one before (1-D delta).
    pub fn row(texels: usize) -> Grid {
        let all: Vec<usize> = (0..texels).collect();
        Grid::new(&all, texels)
    }

    /// Texels the grid was built for.
    pub fn texels(&self) -> usize {
        self.neighbours.len()
    }
}

/// The prediction of texel `i` from the already decoded `q` of one map.
#[inline]
fn predict(q: &[i32], [left, up, diag]: [u32; 3]) -> i32 {
    let get = |j: u32| q[j as usize];
    match (left != NONE, up != NONE) {
        (true, true) if diag != NONE => {
            let (a, b, c) = (get(left), get(up), get(diag));
            if c >= a.max(b) {
                a.min(b)
            } else if c <= a.min(b) {
                a.max(b)
            } else {
                a.wrapping_add(b).wrapping_sub(c)
            }
        }
        (true, true) => ((i64::from(get(left)) + i64::from(get(up))) >> 1) as i32,
        (true, false) => get(left),
        (false, true) => get(up),
        (false, false) => 0,
    }
}

/// Plane-set bytes for `texels` filled texels; `None` on overflow.
pub fn plane_bytes(texels: usize, n2: usize) -> Option<usize> {
    texels.checked_mul(n2)?.checked_mul(2)?.checked_add(n2 * 4)
}

/// The step that gives a plane set a relative L2 error of about `2^−m`: one step for every
/// map, `2^−m · √12 · rms` of all its values.
pub fn step_for_bits(values: &[f32], m: u8) -> f64 {
    let sum: f64 = values.iter().map(|&v| f64::from(v).powi(2)).sum();
    let rms = (sum / values.len().max(1) as f64).sqrt();
    rms * 12f64.sqrt() * 2f64.powi(-i32::from(m))
}

/// Quantises `values` (texel-major, `n2` per filled texel, `grid.texels()` texels) with the
/// step `step` for every map (raised per map where `|q|` would pass `2^14 − 1`).
pub fn encode(values: &[f32], n2: usize, step: f64, grid: &Grid) -> Vec<u8> {
    let texels = grid.texels();
    let mut out = Vec::with_capacity(plane_bytes(texels, n2).unwrap_or(0));
    let mut q = vec![0i32; texels];
    let mut residuals = vec![0u16; texels * n2];
    for c in 0..n2 {
        let max = (0..texels)
            .map(|t| f64::from(values[t * n2 + c]).abs())
            .fold(0.0, f64::max);
        let mut s = (step.max(max / Q_MAX) as f32).max(f32::MIN_POSITIVE);
        if !(s.is_finite()) {
            s = f32::MAX;
        }
        out.extend_from_slice(&s.to_le_bytes());
        let inv = 1.0 / f64::from(s);
        // `q · s` must stay a finite f32 when the step rounded up near `f32::MAX`.
        let limit = Q_MAX.min((f64::from(f32::MAX) * inv).floor());
        for t in 0..texels {
            q[t] = (f64::from(values[t * n2 + c]) * inv)
                .round()
                .clamp(-limit, limit) as i32;
        }
        for t in 0..texels {
            let r = q[t] - predict(&q, grid.neighbours[t]);
            residuals[c * texels + t] = ((r << 1) ^ (r >> 31)) as u16;
        }
    }
    out.extend(residuals.iter().map(|&r| r as u8));
    out.extend(residuals.iter().map(|&r| (r >> 8) as u8));
    out
}

/// Inverts [`encode`] into `out` (`texels · n2` values, texel-major).
pub fn decode(planes: &[u8], n2: usize, grid: &Grid, out: &mut [f32]) -> Result<(), String> {
    if out.len() != grid.texels() * n2 {
        return Err("plane set size does not match the header".into());
    }
    let (steps, q) = decode_ints(planes, n2, grid)?;
    for (texel, ints) in out
        .chunks_exact_mut(n2.max(1))
        .zip(q.chunks_exact(n2.max(1)))
    {
        for ((v, &q), &step) in texel.iter_mut().zip(ints).zip(&steps) {
            *v = f32::from(q) * step;
        }
    }
    Ok(())
}

/// The `n2` steps and the integers `q` (texel-major) of a plane set: what [`decode`]
/// multiplies. Steps must be finite and ≥ 0, and `|q|` at most what the encoder writes.
pub fn decode_ints(planes: &[u8], n2: usize, grid: &Grid) -> Result<(Vec<f32>, Vec<i16>), String> {
    let texels = grid.texels();
    if plane_bytes(texels, n2) != Some(planes.len()) {
        return Err("plane set size does not match the header".into());
    }
    let (steps, rest) = planes.split_at(n2 * 4);
    let steps: Vec<f32> = steps
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    if steps.iter().any(|s| !s.is_finite() || *s < 0.0) {
        return Err("map step not finite and ≥ 0".into());
    }
    let (low, high) = rest.split_at(texels * n2);
    let mut q = vec![0i32; texels];
    let mut ints = vec![0i16; texels * n2];
    for c in 0..n2 {
        let (low, high) = (&low[c * texels..], &high[c * texels..]);
        for t in 0..texels {
            let z = u32::from(low[t]) | u32::from(high[t]) << 8;
            let r = (z >> 1) as i32 ^ -((z & 1) as i32);
            q[t] = predict(&q, grid.neighbours[t]).wrapping_add(r);
        }
        for (t, &v) in q.iter().enumerate() {
            if f64::from(v).abs() > Q_MAX {
                return Err(format!("quantised value {v} out of range"));
            }
            ints[t * n2 + c] = v as i16;
        }
    }
    Ok((steps, ints))
}
