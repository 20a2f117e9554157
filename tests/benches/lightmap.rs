//! SH light-map composition (`LightMap::compose`) of a 512 × 512 map, 4096 texels a call as a
//! streaming decoder hands them over, at orders 3 and 6, against a plain memory copy of the
//! same map bytes and against the scalar composition it replaced (the same checks, then one
//! texel at a time, written here as it was). Beside them, `compose_lights` of one directional
//! light, whose per-texel lighting (an SH basis evaluation per texel) is why it keeps the
//! scalar dot product. Every step runs in interleaved batches (`interleaved_seconds`) and each
//! ratio is the median of per-round ratios, so the machine's drift cancels. One core.
//! `cargo bench -p aprt-tests --bench lightmap`.

use std::hint::black_box;
use std::time::Duration;

use aprt_core::{DirectionalLight, Light, LightMap};
use aprt_tests::{interleaved_seconds, median_ratio, noise};

const SIDE: usize = 512;
const CHUNK: usize = 4096;
const ROUNDS: usize = 15;

/// The composition as it was before the kernels: every value tested with `is_finite`, then
/// `Σ_c l_c t_c` texel by texel (the bits the kernels keep).
fn scalar_compose(maps: &[f32], lighting: &[[f32; 3]], out: &mut [[f32; 3]]) {
    let n2 = lighting.len();
    assert!(maps.iter().all(|x| x.is_finite()));
    assert_eq!(maps.len(), out.len() * n2);
    for (t, o) in maps.chunks_exact(n2).zip(out.iter_mut()) {
        let mut acc = [0.0f32; 3];
        for (&x, lc) in t.iter().zip(lighting) {
            for (a, c) in acc.iter_mut().zip(lc) {
                *a += c * x;
            }
        }
        *o = acc;
    }
}

fn main() {
    let budget = Duration::from_millis(6000);
    let texels = SIDE * SIDE;
    println!(
        "aprt-core light-map composition, one core; {SIDE} x {SIDE} texels, {CHUNK} a call; \
         medians of {ROUNDS} interleaved rounds"
    );
    println!(
        "{:<44} {:>10} {:>10} {:>10} {:>10}",
        "order / step", "map MB", "µs/map", "× memcpy", "× compose"
    );
    for order in [3, 6] {
        let map = LightMap::new(order).unwrap();
        let n2 = order * order;
        let maps: Vec<f32> = noise(21, texels * n2).iter().map(|&x| x as f32).collect();
        let lighting: Vec<[f32; 3]> = noise(22, 3 * n2)
            .chunks_exact(3)
            .map(|c| [c[0] as f32, c[1] as f32, c[2] as f32])
            .collect();
        let positions: Vec<[f32; 3]> = noise(23, 3 * texels)
            .chunks_exact(3)
            .map(|c| [c[0] as f32, c[1] as f32, c[2] as f32])
            .collect();
        let light = [Light::Directional(DirectionalLight {
            direction: [0.3, 0.8, 0.5],
            irradiance: [1.0, 0.9, 0.8],
        })];
        let (mut copy, mut out) = (vec![0.0f32; maps.len()], vec![[0.0f32; 3]; texels]);
        let (mut out2, mut out3) = (out.clone(), out.clone());
        let mut memcpy = || {
            copy.copy_from_slice(black_box(&maps));
            black_box(&copy);
        };
        let mut compose = || {
            for (m, o) in maps.chunks(CHUNK * n2).zip(out.chunks_mut(CHUNK)) {
                map.compose(black_box(m), black_box(&lighting), o).unwrap();
            }
            black_box(&out);
        };
        let mut scalar = || {
            for (m, o) in maps.chunks(CHUNK * n2).zip(out2.chunks_mut(CHUNK)) {
                scalar_compose(black_box(m), black_box(&lighting), o);
            }
            black_box(&out2);
        };
        let mut lights = || {
            let chunks = maps.chunks(CHUNK * n2).zip(positions.chunks(CHUNK));
            for ((m, p), o) in chunks.zip(out3.chunks_mut(CHUNK)) {
                map.compose_lights(black_box(m), p, &light, &[], o).unwrap();
            }
            black_box(&out3);
        };
        let times = interleaved_seconds(
            budget,
            ROUNDS,
            &mut [&mut memcpy, &mut compose, &mut scalar, &mut lights],
        );
        // The kernels give the scalar bits.
        assert!(
            out.iter()
                .zip(&out2)
                .all(|(a, b)| a.map(f32::to_bits) == b.map(f32::to_bits))
        );
        let steps = [
            "memcpy of the map",
            "compose (SIMD kernels)",
            "scalar compose, as before",
            "compose_lights, one directional light",
        ];
        for (step, t) in steps.iter().zip(&times) {
            println!(
                "{:<44} {:>10.2} {:>10.0} {:>9.2}x {:>9.2}x",
                format!("order {order}: {step}"),
                (maps.len() * 4) as f64 / 1e6,
                median_ratio(t, &[1.0; ROUNDS]) * 1e6,
                median_ratio(t, &times[0]),
                median_ratio(t, &times[1]),
            );
        }
    }
}
