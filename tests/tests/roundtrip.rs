//! Trainer model → blob → aprt-core, from a resident slice and streamed through a
//! `BlobSource` with small buffers: the same numbers as the trainer's f64 reference.

use aprt_core::{Error, Input, LitWeights, Model, PoseWeights, StreamedModel};
use aprt_tests::{Eval, Streamed, noise, random_model};
use aprt_trainer::{LinearModel, Precision, encode_model};

/// Transfer and shading for every vertex, through the core, resident or streamed.
fn evaluate(model: &mut impl Eval, angles: &[f32], light: &[f32]) -> (Vec<f32>, Vec<f32>) {
    let info = *model.info();
    let (n2, v) = (info.coeffs(), info.vertices());
    let mut pose = Box::new(PoseWeights::new());
    model.set_pose(angles, &mut pose).unwrap();
    let mut lit = Box::new(LitWeights::new());
    model.light(&pose, light, &[], &mut lit).unwrap();
    let mut transfer = vec![0.0f32; v * n2];
    let mut shading = vec![0.0f32; v];
    // Uneven vertex ranges, to cross chunk boundaries at odd places.
    let mut first = 0;
    for (i, step) in [1usize, 7, 3, 64, 5].iter().cycle().enumerate() {
        if first >= v {
            break;
        }
        let count = (*step + i % 2).min(v - first);
        model
            .transfer(
                &pose,
                first,
                &mut transfer[first * n2..(first + count) * n2],
            )
            .unwrap();
        model
            .shade(&lit, first, &mut shading[first..first + count])
            .unwrap();
        first += count;
    }
    (transfer, shading)
}

fn check_model(reference: &LinearModel, precision: Precision, tolerance: f64) {
    let blob = encode_model(reference, precision).unwrap();
    let mut model = Model::parse(&blob).unwrap();
    let names: Vec<&str> = model.angle_names().iter().collect();
    assert_eq!(names, reference.angle_names);
    let n2 = reference.order * reference.order;
    let angles64 = noise(9, reference.pose_len);
    let angles: Vec<f32> = angles64.iter().map(|&x| x as f32).collect();
    let light: Vec<f32> = noise(10, n2).iter().map(|&x| x as f32).collect();

    let (t_slice, s_slice) = evaluate(&mut model, &angles, &light);
    // The f64 reference from the trainer, evaluated at the angles the core saw.
    let expect = reference.predict(&angles.iter().map(|&x| x as f64).collect::<Vec<_>>());
    let scale = expect.iter().fold(1.0f64, |m, x| m.max(x.abs()));
    for (i, (got, want)) in t_slice.iter().zip(&expect).enumerate() {
        assert!(
            (*got as f64 - want).abs() <= tolerance * scale,
            "transfer[{i}] = {got}, reference {want}"
        );
    }
    for (j, s) in s_slice.iter().enumerate() {
        let want: f64 = (0..n2).map(|c| light[c] as f64 * expect[j * n2 + c]).sum();
        assert!(
            (*s as f64 - want).abs() <= tolerance * scale * n2 as f64,
            "shade[{j}] = {s}, reference {want}"
        );
    }

    // Streaming with buffers from the least up: bit-identical to the resident evaluation.
    let least = model.info().scratch_bytes();
    for extra in [0usize, 1, 13, 4096] {
        let mut scratch = vec![0u8; least + extra];
        let mut src = Streamed::new(&blob);
        let mut streamed = StreamedModel::open(&mut src, &mut scratch).unwrap();
        assert_eq!(streamed.info(), model.info());
        let mut buf = vec![0u8; streamed.info().angle_names_bytes()];
        assert_eq!(streamed.angle_names(&mut buf).unwrap(), model.angle_names());
        let (t, s) = evaluate(&mut streamed, &angles, &light);
        assert!(src.reads > 0);
        assert_eq!(
            t.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
            t_slice.iter().map(|x| x.to_bits()).collect::<Vec<_>>()
        );
        assert_eq!(
            s.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
            s_slice.iter().map(|x| x.to_bits()).collect::<Vec<_>>()
        );
    }
}

#[test]
fn stored_basis_round_trip_f32() {
    check_model(&random_model(3, 301, 7, 4, Some(11)), Precision::F32, 2e-6);
    check_model(&random_model(6, 97, 20, 8, Some(22)), Precision::F32, 2e-6);
    check_model(&random_model(1, 5, 1, 0, Some(1)), Precision::F32, 2e-6);
}

#[test]
fn identity_basis_round_trip_f32() {
    check_model(&random_model(2, 77, 5, 3, None), Precision::F32, 2e-6);
    check_model(&random_model(6, 19, 30, 12, None), Precision::F32, 2e-6);
}

#[test]
fn f16_round_trip_within_half_precision() {
    // f16 has an 11-bit significand: relative rounding 2^-11 per value, accumulated over k_v terms.
    check_model(
        &random_model(4, 150, 9, 5, Some(16)),
        Precision::F16,
        16.0 * 4.9e-4,
    );
    check_model(
        &random_model(3, 40, 9, 5, None),
        Precision::F16,
        9.0 * 4.9e-4,
    );
}

#[test]
fn streaming_rejects_a_buffer_smaller_than_a_block() {
    let reference = random_model(3, 10, 4, 2, Some(8));
    let blob = encode_model(&reference, Precision::F32).unwrap();
    let err = StreamedModel::open(Streamed::new(&blob), &mut [0u8; 255]).unwrap_err();
    assert_eq!(err, Error::BufferTooSmall { needed: 8 * 8 * 4 });
    assert!(StreamedModel::open(Streamed::new(&blob), &mut [0u8; 256]).is_ok());
}

/// Bone-frame models: `transfer` gives bone-frame transfer equal to the trainer's reference,
/// and `light` with the bones' rotations + `shade` equal world lighting rotated into each
/// vertex's bone frame dotted with that transfer, for resident and streamed blobs alike.
#[test]
fn bone_frame_model_shades_with_per_bone_lighting() {
    use aprt_tests::quadrature::QuadratureRotation;
    use aprt_trainer::BoneFrames;
    for (order, kv) in [(3usize, Some(7usize)), (2, None)] {
        let mut reference = random_model(order, 45, 6, 3, kv);
        let bones = 4;
        reference.bones = Some(BoneFrames {
            count: bones,
            vertex_bone: (0..45).map(|j| ((j * 7 / 5) % bones) as u16).collect(),
        });
        let blob = encode_model(&reference, Precision::F32).unwrap();
        let model = Model::parse(&blob).unwrap();
        let n2 = order * order;
        let angles: Vec<f32> = noise(11, 6).iter().map(|&x| x as f32).collect();
        let light: Vec<f32> = noise(12, n2).iter().map(|&x| x as f32).collect();
        // Rotations about different axes per bone.
        let rotations: Vec<[[f32; 3]; 3]> = (0..bones)
            .map(|b| {
                let (s, c) = (0.4 * b as f32 + 0.3).sin_cos();
                match b % 2 {
                    0 => [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]],
                    _ => [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]],
                }
            })
            .collect();
        let rotation = QuadratureRotation::new(order).unwrap();
        let expect = reference.predict(&angles.iter().map(|&x| x as f64).collect::<Vec<_>>());
        let run = |model: &mut dyn Eval| {
            let mut pose = Box::new(PoseWeights::new());
            let mut lit = Box::new(LitWeights::new());
            let (mut transfer, mut shading, mut bones_out) =
                (vec![0.0f32; 45 * n2], vec![0.0f32; 45], vec![0u16; 45]);
            model.set_pose(&angles, &mut pose).unwrap();
            assert_eq!(
                model.light(&pose, &light, &[], &mut lit),
                Err(Error::WrongLength {
                    what: Input::BoneRotations,
                    expected: bones,
                    found: 0
                })
            );
            model.light(&pose, &light, &rotations, &mut lit).unwrap();
            model.transfer(&pose, 0, &mut transfer).unwrap();
            model.shade(&lit, 0, &mut shading).unwrap();
            model.vertex_bones(0, &mut bones_out).unwrap();
            (transfer, shading, bones_out)
        };
        let mut scratch = vec![0u8; model.info().scratch_bytes()];
        let mut streamed = StreamedModel::open(Streamed::new(&blob), &mut scratch).unwrap();
        for (transfer, shading, vertex_bones) in [run(&mut { model }), run(&mut streamed)] {
            assert_eq!(vertex_bones, reference.bones.as_ref().unwrap().vertex_bone);
            for (got, want) in transfer.iter().zip(&expect) {
                assert!((*got as f64 - want).abs() < 1e-5, "{got} vs {want}");
            }
            for j in 0..45 {
                let r = rotations[vertex_bones[j] as usize];
                let rt: [[f32; 3]; 3] = std::array::from_fn(|a| std::array::from_fn(|b| r[b][a]));
                let mut local = vec![0.0f32; n2];
                rotation.rotate(&rt, &light, &mut local).unwrap();
                let want: f64 = (0..n2).map(|c| local[c] as f64 * expect[j * n2 + c]).sum();
                assert!(
                    (shading[j] as f64 - want).abs() < 1e-4,
                    "vertex {j}: {} vs {want}",
                    shading[j]
                );
            }
        }
    }
}

/// Weights computed for one model are refused by any other: of another frame, and of the
/// very same shape with other numbers, which a check of the dimensions alone let through.
#[test]
fn weights_of_another_model_are_refused() {
    use aprt_trainer::BoneFrames;
    let world = random_model(2, 16, 3, 2, Some(4));
    let mut skinned = world.clone();
    skinned.bones = Some(BoneFrames {
        count: 2,
        vertex_bone: vec![1; 16],
    });
    let mut same_shape = world.clone();
    same_shape.weights[0] += 0.5;
    let blobs = [&world, &skinned, &same_shape].map(|m| encode_model(m, Precision::F32).unwrap());
    let models = blobs.each_ref().map(|b| Model::parse(b).unwrap());
    let mut pose = PoseWeights::new();
    models[0].set_pose(&[0.1; 3], &mut pose).unwrap();
    let mut lit = LitWeights::new();
    models[0].light(&pose, &[1.0; 4], &[], &mut lit).unwrap();
    let mut out = [0.0f32; 16];
    assert!(models[0].shade(&lit, 0, &mut out).is_ok());
    for other in &models[1..] {
        assert_ne!(other.info().id(), models[0].info().id());
        assert_eq!(
            other.shade(&lit, 0, &mut out),
            Err(Error::WeightsForOtherModel)
        );
        assert_eq!(
            other.transfer(&pose, 0, &mut [0.0; 64]),
            Err(Error::WeightsForOtherModel)
        );
        // Lighting another model's pose is refused too, and leaves its output unset.
        let mut other_lit = LitWeights::new();
        let identity = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        assert_eq!(
            other.light(&pose, &[1.0; 4], &[identity; 2], &mut other_lit),
            Err(Error::WeightsForOtherModel)
        );
        assert_eq!(
            other.shade(&other_lit, 0, &mut out),
            Err(Error::WeightsNotSet)
        );
    }
}

/// Regression (found by the fuzz harness): validation checked a bone-frame model's bone rows a
/// whole block at a time and refused small buffers with the size of that step. Any buffer now
/// gets through validation, and one too small for evaluation is refused with the size
/// evaluation needs.
#[test]
fn bone_frame_model_validates_through_the_smallest_scratch() {
    use aprt_trainer::BoneFrames;
    let mut reference = random_model(2, 13, 3, 1, Some(5));
    reference.bones = Some(BoneFrames {
        count: 3,
        vertex_bone: (0..13).map(|j| (j % 3) as u16).collect(),
    });
    for precision in [Precision::F32, Precision::F16] {
        let blob = encode_model(&reference, precision).unwrap();
        let needed = Model::parse(&blob).unwrap().info().scratch_bytes();
        assert_eq!(
            StreamedModel::open(Streamed::new(&blob), &mut [0u8; 4]).unwrap_err(),
            Error::BufferTooSmall { needed }
        );
    }
}

mod random_shapes {
    use aprt_tests::harness::{self, PROBE_BYTES, Probe};
    use aprt_tests::spec::{ModelSpec, round_trip};
    use aprt_trainer::encode_model;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig { cases: 400, ..ProptestConfig::default() })]

        /// The fuzz target `round_trip` under proptest: random shapes (order, vertices,
        /// pose length, pose and basis dimensions, basis kind, bone frames, precision, values)
        /// written, read back exactly or within half precision, and evaluated like the f64
        /// reference. Raw probe bytes make angles and lighting of any magnitude (NaN and
        /// overflow included, where only "no panic" is asked); the same probe with moderate
        /// angles and lighting is then compared with the reference whenever the model's own
        /// values allow.
        #[test]
        fn writer_reader_round_trip(
            probe in proptest::collection::vec(any::<u8>(), PROBE_BYTES),
            spec in proptest::collection::vec(any::<u8>(), 0..512),
            angles in proptest::array::uniform4(-4.0f32..4.0),
            lighting in proptest::array::uniform4(-4.0f32..4.0),
        ) {
            let spec = ModelSpec::from_bytes(&spec);
            let raw = Probe::from_bytes(&probe);
            round_trip(&spec, &raw);
            round_trip(&spec, &Probe { angles, lighting, ..raw });
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

        /// Streaming through a `BlobSource` equals whole-slice evaluation bit for bit for
        /// every scratch size from nothing to twice the least, and sizes below the least are
        /// refused with `BufferTooSmall`, never a panic.
        #[test]
        fn streaming_equals_resident_for_every_buffer_size(
            spec in proptest::collection::vec(any::<u8>(), 0..256),
        ) {
            let spec = ModelSpec::from_bytes(&spec);
            let Ok(blob) = encode_model(&spec.model, spec.precision) else {
                return Ok(()); // values f16 cannot hold: the round trip test covers refusals
            };
            let model = aprt_core::Model::parse(&blob)
                .expect("the reader accepts what the writer writes");
            // Every size is thousands of evaluations for shapes at the format's limits; the
            // small shapes cross the same chunk boundaries.
            let sizes = 0..=2 * model.info().scratch_bytes();
            prop_assume!(*sizes.end() <= 1024);
            harness::check_streaming(&blob, &Probe::GENTLE, sizes);
        }
    }
}
