//! Synthetic light-map clips: a smooth bent-normal field over two UV charts (a torso-like
//! cylinder and a head-like cap), clamped-cosine transfer scaled by a smooth visibility in
//! 0.3..1, swaying periodically like a walk, plus bake noise of about 1e-3: the codec's tests and
//! the `shlm_codecs` example measure on it.

use aprt_core::clamped_cosine;

use crate::lightmap::codec::MapSequence;

/// A deterministic uniform generator in `[-1, 1)`.
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0
    }
}

/// The surface point and normal a texel at `(u, v)` stands for, if it is inside a chart.
fn chart(u: f32, v: f32) -> Option<([f32; 3], [f32; 3])> {
    use std::f32::consts::TAU;
    if (0.05..0.6).contains(&u) && (0.05..0.95).contains(&v) {
        let theta = (u - 0.05) / 0.55 * TAU;
        let n = [theta.cos(), 0.0, theta.sin()];
        return Some(([0.3 * n[0], 1.5 * v, 0.3 * n[2]], n));
    }
    let (du, dv) = ((u - 0.8) / 0.17, (v - 0.3) / 0.17);
    let d2 = du * du + dv * dv;
    (d2 < 1.0).then(|| {
        let n = [du, (1.0 - d2).sqrt(), dv];
        ([0.15 * n[0], 1.7 + 0.15 * n[1], 0.15 * n[2]], n)
    })
}

/// Rotates `n` by `a` around z, then `b` around x.
fn rotate(n: [f32; 3], a: f32, b: f32) -> [f32; 3] {
    let (s, c) = a.sin_cos();
    let [x, y, z] = [c * n[0] - s * n[1], s * n[0] + c * n[1], n[2]];
    let (s, c) = b.sin_cos();
    [x, c * y - s * z, s * y + c * z]
}

/// A clip of `frames` frames of `resolution²` texels at SH `order`, with bake noise `noise`.
pub fn clip(resolution: usize, order: usize, frames: usize, noise: f32) -> MapSequence {
    let n2 = order * order;
    let mut filled = vec![false; resolution * resolution];
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    for (t, flag) in filled.iter_mut().enumerate() {
        let (u, v) = ((t % resolution) as f32 + 0.5, (t / resolution) as f32 + 0.5);
        if let Some((p, n)) = chart(u / resolution as f32, v / resolution as f32) {
            *flag = true;
            positions.push(p);
            normals.push((t, u / resolution as f32, v / resolution as f32, n));
        }
    }
    let mut rng = Lcg(7);
    let mut lobe = vec![0f32; n2];
    let frames = (0..frames)
        .map(|f| {
            let phase = std::f32::consts::TAU * f as f32 / frames as f32;
            let mut map = vec![0f32; resolution * resolution * n2];
            for &(t, u, v, n) in &normals {
                let sway = 0.25 * phase.sin() + 0.1 * (2.0 * phase + 3.0 * v).sin();
                let nod = 0.3 * (phase + 0.5).sin() * u;
                let vis = 0.65 + 0.35 * (12.0 * u + phase).sin() * (9.0 * v - phase).cos();
                let bent = rotate(n, sway, nod + 0.3 * (1.0 - vis));
                clamped_cosine(order, bent, &mut lobe).expect("a unit normal");
                for (c, &x) in lobe.iter().enumerate() {
                    map[t * n2 + c] = vis * x + noise * rng.next();
                }
            }
            map
        })
        .collect();
    MapSequence {
        atlas: None,
        resolution,
        order,
        filled,
        positions,
        layout: None,
        frames,
    }
}
