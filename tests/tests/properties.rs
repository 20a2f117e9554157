//! Property tests of the core's mathematics: SH rotations preserve each band's energy, and
//! shading is linear in the lighting. (Orthonormality of the basis by quadrature is tested in
//! `tests/src/quadrature.rs`; streaming and the round trip in `roundtrip.rs`.)

use aprt_core::{LitWeights, MAX_ORDER, Model, PoseWeights, ShRotation};
use aprt_tests::decode::decode;
use aprt_tests::quadrature::QuadratureRotation;
use aprt_tests::reference::{magnitude, rounding};
use aprt_tests::spec::ModelSpec;
use aprt_trainer::encode_model;
use proptest::prelude::*;

/// A uniformly random rotation from a random quaternion (rejected when too short).
fn arb_rotation() -> impl Strategy<Value = [[f32; 3]; 3]> {
    proptest::array::uniform4(-1.0f64..1.0)
        .prop_filter("a quaternion long enough to normalise", |q| {
            q.iter().map(|x| x * x).sum::<f64>() > 0.01
        })
        .prop_map(|q| {
            let n = q.iter().map(|x| x * x).sum::<f64>().sqrt();
            let [w, x, y, z] = q.map(|c| c / n);
            [
                [
                    1.0 - 2.0 * (y * y + z * z),
                    2.0 * (x * y - w * z),
                    2.0 * (x * z + w * y),
                ],
                [
                    2.0 * (x * y + w * z),
                    1.0 - 2.0 * (x * x + z * z),
                    2.0 * (y * z - w * x),
                ],
                [
                    2.0 * (x * z - w * y),
                    2.0 * (y * z + w * x),
                    1.0 - 2.0 * (x * x + y * y),
                ],
            ]
            .map(|row| row.map(|v| v as f32))
        })
}

fn band_energies(order: usize, x: &[f32]) -> Vec<f64> {
    (0..order)
        .map(|l| {
            x[l * l..(l + 1) * (l + 1)]
                .iter()
                .map(|v| (*v as f64).powi(2))
                .sum()
        })
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, ..ProptestConfig::default() })]

    /// A rotation mixes coefficients only within a band and is orthogonal there, so each
    /// band's energy `Σ_m x_lm²` is unchanged, by the core's Euler angles (built on the
    /// Ivanic–Ruedenberg recurrences) and the quadrature alike.
    #[test]
    fn rotation_preserves_band_energies(
        order in 1usize..=MAX_ORDER,
        x in proptest::collection::vec(-1.0f32..1.0, 36),
        r in arb_rotation(),
    ) {
        let before = band_energies(order, &x);
        let total: f64 = before.iter().sum();
        let mut by_euler: [f32; 36] = x.clone().try_into().unwrap();
        ShRotation::new(order).unwrap().apply(&r.map(|row| row.map(f64::from)), &mut by_euler).unwrap();
        let mut by_quadrature = [0.0f32; 36];
        QuadratureRotation::new(order).unwrap().rotate(&r, &x, &mut by_quadrature).unwrap();
        for rotated in [&by_euler, &by_quadrature] {
            for (l, (a, b)) in before.iter().zip(band_energies(order, rotated)).enumerate() {
                prop_assert!((a - b).abs() <= 1e-4 * total.max(1e-3), "band {l}: {a} -> {b}");
            }
        }
    }

    /// Shading is linear in the lighting: `shade(a L1 + b L2) = a shade(L1) + b shade(L2)`,
    /// within the f32 rounding of the three evaluations, bounded from the magnitudes of the
    /// model's terms (the same bound the fuzz harness uses against the f64 reference).
    #[test]
    fn shading_is_linear_in_the_lighting(
        spec in proptest::collection::vec(any::<u8>(), 0..256),
        l1 in proptest::collection::vec(-2.0f32..2.0, 36),
        l2 in proptest::collection::vec(-2.0f32..2.0, 36),
        a in -4.0f32..4.0,
        b in -4.0f32..4.0,
        angle in -3.0f32..3.0,
    ) {
        let spec = ModelSpec::from_bytes(&spec);
        prop_assume!(spec.model.weights.iter().chain(&spec.model.pose_projection)
            .chain(&spec.model.pose_mean).all(|x| x.abs() < 1e6));
        let Ok(blob) = encode_model(&spec.model, spec.precision) else { return Ok(()) };
        let model = Model::parse(&blob).expect("the reader accepts what the writer writes");
        let info = *model.info();
        let stored = decode(&blob).unwrap();
        prop_assume!(match &stored.basis {
            aprt_trainer::VertexBasis::Stored { data, .. } => data.iter().all(|x| x.abs() < 1e6),
            aprt_trainer::VertexBasis::Identity => true,
        });
        let n2 = info.coeffs();
        let (l1, l2) = (&l1[..n2], &l2[..n2]);
        let mix: Vec<f32> = l1.iter().zip(l2).map(|(x, y)| a * x + b * y).collect();
        let angles = vec![angle; info.pose_len()];
        let mut pose = Box::new(PoseWeights::new());
        model.set_pose(&angles, &mut pose).unwrap();
        let rotations: Vec<[[f32; 3]; 3]> = (0..info.bones()).map(|k| {
            let (s, c) = (0.3 * k as f32).sin_cos();
            [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
        }).collect();
        let shade = |lighting: &[f32]| {
            let mut lit = Box::new(LitWeights::new());
            model.light(&pose, lighting, &rotations, &mut lit).unwrap();
            let mut out = vec![0.0f32; info.vertices()];
            model.shade(&lit, 0, &mut out).unwrap();
            out
        };
        let (s1, s2, s) = (shade(l1), shade(l2), shade(&mix));
        let norm = |l: &[f32]| l.iter().map(|x| (*x as f64).abs()).sum::<f64>();
        let light = norm(&mix) + (a as f64).abs() * norm(l1) + (b as f64).abs() * norm(l2);
        let terms = magnitude(&stored, &angles.iter().map(|&x| x as f64).collect::<Vec<_>>(), |x| x);
        let gamma = rounding(&stored);
        for j in 0..info.vertices() {
            let want = a as f64 * s1[j] as f64 + b as f64 * s2[j] as f64;
            let bound = 2.0 * gamma * light * terms[j * n2..(j + 1) * n2].iter().sum::<f64>() + 1e-30;
            prop_assert!(
                (s[j] as f64 - want).abs() <= bound,
                "vertex {}: {} vs {} (bound {})", j, s[j], want, bound
            );
        }
    }
}
