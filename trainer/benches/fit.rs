//! Fitting-stage benchmark on synthetic but realistically sized data: 250 poses, 24 joint
//! angles, SH order 6 (36 coefficients), 12 000 vertices — the scale of the paper's Master Pai
//! (11.5k vertices; fitting 73 s + PCA 324 s there).
//!
//! Transfer is smooth in the angles: a mean field, a linear response, a nonlinear (sinusoidal)
//! response with decaying strength, and f32-level noise, all spread over 48 latent vertex
//! fields. Run with `cargo bench -p aprt-trainer --bench fit`. Pose dimensions are chosen at
//! 99.9 % of the angle variance; the table prints seconds per stage, the energy fraction the
//! vertex basis captures, and the held-out error at the chosen α as a mean squared error per
//! transfer value (within the span of the basis, so comparable across k_v).

use std::time::Instant;

use aprt_trainer::{Alpha, CoefDims, Dims, FitOptions, fit};
use nalgebra::DMatrix;
use rayon::prelude::*;

const POSES: usize = 250;
const JOINTS: usize = 24;
const ORDER: usize = 6;
const VERTICES: usize = 12_000;
const LATENT: usize = 48;

/// SplitMix64 hash of a counter: uniform in [−0.5, 0.5).
fn noise(counter: u64) -> f64 {
    let mut z = counter
        .wrapping_mul(0x9E37_79B9_7F4A_7C15)
        .wrapping_add(0x1234_5678);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 53) as f64 - 0.5
}

/// Three clips of smooth motion; joint 5 never moves and joint 7 is a fixed mix of 1 and 2.
fn angles() -> DMatrix<f64> {
    DMatrix::from_fn(POSES, JOINTS, |i, j| {
        let (clip, t) = (i / 84, (i % 84) as f64 / 30.0);
        let phase = |k: usize| 6.0 * noise((clip * 100 + k) as u64 + 7);
        match j {
            5 => 0.2,
            7 => 0.6 * (1.3 * t + phase(1)).sin() - 0.3 * (0.9 * t + phase(2)).sin(),
            _ => {
                let speed = 0.5 + 2.0 * (noise(j as u64) + 0.5);
                (0.3 + 0.5 * (noise(j as u64 + 50) + 0.5)) * (speed * t + phase(j)).sin()
            }
        }
    })
}

/// Per-pose latent weights: 1 (mean), 16 linear responses, 31 nonlinear ones decaying 1/k.
fn latent_weights(angles: &DMatrix<f64>) -> DMatrix<f64> {
    let mix = DMatrix::from_fn(JOINTS, LATENT, |j, k| {
        noise((j * LATENT + k) as u64 + 1_000)
    });
    let projected = angles * mix;
    DMatrix::from_fn(POSES, LATENT, |i, k| match k {
        0 => 4.0,
        1..=16 => projected[(i, k)],
        _ => (2.0 * projected[(i, k)]).sin() * 1.5 / (k - 15) as f64,
    })
}

/// `v × n²` vertex-major transfer per pose from latent fields smooth over the vertex index.
fn transfers(weights: &DMatrix<f64>) -> Vec<Vec<f32>> {
    let n2 = ORDER * ORDER;
    let fields: Vec<Vec<f32>> = (0..LATENT)
        .map(|k| {
            (0..VERTICES * n2)
                .map(|idx| {
                    let (j, c) = ((idx / n2) as f64, (idx % n2) as u64);
                    let freq = 0.001 * (1 + k) as f64;
                    ((freq * j + noise(c * 31 + k as u64)).sin()
                        * (1.0 + noise(c + 100 * k as u64))) as f32
                })
                .collect()
        })
        .collect();
    (0..POSES)
        .into_par_iter()
        .map(|i| {
            let mut t = vec![0f32; VERTICES * n2];
            for (k, field) in fields.iter().enumerate() {
                let w = weights[(i, k)] as f32;
                t.iter_mut().zip(field).for_each(|(x, f)| *x += w * f);
            }
            for (idx, x) in t.iter_mut().enumerate() {
                *x += 1e-3 * noise((i * VERTICES * n2 + idx) as u64) as f32;
            }
            t
        })
        .collect()
}

fn main() {
    let clock = Instant::now();
    let angles = angles();
    let transfers = transfers(&latent_weights(&angles));
    println!(
        "data: {POSES} poses × {JOINTS} angles, order {ORDER}, {VERTICES} vertices ({:.1} s to generate, {} threads)",
        clock.elapsed().as_secs_f64(),
        rayon::current_num_threads()
    );
    let configs = [
        ("k_v=22, LOO", CoefDims::Count(22), Alpha::Loo),
        (
            "k_v=22, LOSO",
            CoefDims::Count(22),
            Alpha::Loso { segment: None },
        ),
        ("var 0.999, LOO", CoefDims::Variance(0.999), Alpha::Loo),
        (
            "var 0.999, LOSO",
            CoefDims::Variance(0.999),
            Alpha::Loso { segment: None },
        ),
        // The full model: 432 000 outputs per pose, where the p × p Gram keeps CV cheap.
        ("full, LOSO", CoefDims::Full, Alpha::Loso { segment: None }),
    ];
    println!(
        "{:<16} {:>4} {:>5} {:>9} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>10} {:>10}",
        "config",
        "k_a",
        "k_v",
        "captured",
        "pca s",
        "basis s",
        "proj s",
        "cv s",
        "solve s",
        "total s",
        "alpha",
        "cv mse/val"
    );
    for (name, coef_dims, alpha) in configs {
        let options = FitOptions {
            pose_dims: Dims::Variance(0.999),
            coef_dims,
            alpha,
        };
        let clock = Instant::now();
        let fit = fit(&angles, &transfers, ORDER, &options).expect("synthetic data is valid");
        let total = clock.elapsed().as_secs_f64();
        let s = fit.report.seconds;
        let kv = fit.model.coef_dims();
        // Energy fraction of ‖R‖_F² the basis keeps (1 for the identity basis).
        let captured = match coef_dims {
            CoefDims::Full => 1.0,
            _ => fit.report.coef_energy[..kv].iter().sum::<f64>() / fit.report.coef_total_energy,
        };
        let best = fit
            .report
            .cv_curve
            .iter()
            .find(|c| c.alpha == fit.report.alpha);
        println!(
            "{:<16} {:>4} {:>5} {:>9.6} {:>8.3} {:>8.3} {:>8.3} {:>8.3} {:>8.3} {:>8.3} {:>10.3e} {:>10.3e}",
            name,
            fit.model.pose_dims(),
            fit.model.coef_dims(),
            captured,
            s.pose_pca,
            s.vertex_basis,
            s.projection,
            s.cross_validation,
            s.solve,
            total,
            fit.report.alpha,
            best.map_or(f64::NAN, |b| b.cv_error) * kv as f64 / VERTICES as f64,
        );
    }
}
