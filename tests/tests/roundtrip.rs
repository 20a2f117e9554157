//! Trainer model → blob → aprt-core, from a resident slice and streamed through a
//! `BlobSource` with small buffers: the same numbers as the trainer's f64 reference.

use aprt_core::{BlobSource, LitWeights, Model, PoseWeights, SliceSource};
use aprt_tests::{Streamed, noise, random_model};
use aprt_trainer::{LinearModel, Precision, encode_model};

/// Transfer and shading for every vertex, through the core, with the given source and scratch.
fn evaluate<S: BlobSource>(
    model: &Model,
    src: &mut S,
    scratch: &mut [u8],
    angles: &[f32],
    light: &[f32],
) -> (Vec<f32>, Vec<f32>) {
    let n2 = model.order() * model.order();
    let mut pose = PoseWeights::default();
    model.set_pose(src, angles, scratch, &mut pose).unwrap();
    let mut lit = LitWeights::default();
    model.light(&pose, light, &mut lit).unwrap();
    let mut transfer = vec![0.0f32; model.vertices() * n2];
    let mut shading = vec![0.0f32; model.vertices()];
    // Uneven vertex ranges, to cross chunk boundaries at odd places.
    let mut first = 0;
    for (i, step) in [1usize, 7, 3, 64, 5].iter().cycle().enumerate() {
        if first >= model.vertices() {
            break;
        }
        let count = (*step + i % 2).min(model.vertices() - first);
        model
            .transfer(
                src,
                &pose,
                first,
                &mut transfer[first * n2..(first + count) * n2],
                scratch,
            )
            .unwrap();
        model
            .shade(
                src,
                &lit,
                first,
                &mut shading[first..first + count],
                scratch,
            )
            .unwrap();
        first += count;
    }
    (transfer, shading)
}

fn check_model(reference: &LinearModel, precision: Precision, tolerance: f64) {
    let blob = encode_model(reference, precision).unwrap();
    let model = Model::parse(&blob).unwrap();
    assert_eq!(
        aprt_trainer::export::read_angle_names(&blob).as_deref(),
        Some(&reference.angle_names[..])
    );
    let n2 = reference.order * reference.order;
    let angles64 = noise(9, reference.pose_len);
    let angles: Vec<f32> = angles64.iter().map(|&x| x as f32).collect();
    let light: Vec<f32> = noise(10, n2).iter().map(|&x| x as f32).collect();

    let (t_slice, s_slice) = evaluate(&model, &mut SliceSource(&blob), &mut [], &angles, &light);
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

    // Streaming with buffers from one row up: bit-identical to the resident evaluation.
    let opened = Model::open(&mut Streamed::new(&blob), &mut [0u8; 4]).unwrap();
    assert_eq!(opened, model);
    for extra in [0usize, 1, 13, 4096] {
        let mut scratch = vec![0u8; model.scratch_bytes() + extra];
        let mut src = Streamed::new(&blob);
        let (t, s) = evaluate(&model, &mut src, &mut scratch, &angles, &light);
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
    let model = Model::parse(&blob).unwrap();
    let mut src = Streamed::new(&blob);
    let mut pose = PoseWeights::default();
    model
        .set_pose(
            &mut src,
            &[0.0; 4],
            &mut vec![0u8; model.scratch_bytes()],
            &mut pose,
        )
        .unwrap();
    let mut lit = LitWeights::default();
    model.light(&pose, &[1.0; 9], &mut lit).unwrap();
    let mut out = [0.0f32; 3];
    let err = model
        .shade(&mut src, &lit, 0, &mut out, &mut [0u8; 255])
        .unwrap_err();
    assert_eq!(err, aprt_core::Error::BufferTooSmall { needed: 8 * 8 * 4 });
}

/// Bone-frame models: `transfer` gives bone-frame transfer equal to the trainer's reference,
/// and `light_skinned` + `shade` equal world lighting rotated into each vertex's bone frame
/// dotted with that transfer, for resident and streamed blobs alike.
#[test]
fn bone_frame_model_shades_with_per_bone_lighting() {
    use aprt_core::rotate::ShRotation;
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
        let rotation = ShRotation::new(order).unwrap();
        let expect = reference.predict(&angles.iter().map(|&x| x as f64).collect::<Vec<_>>());
        for streamed in [false, true] {
            let mut scratch = vec![0u8; if streamed { model.scratch_bytes() } else { 0 }];
            let run = |src: &mut dyn BlobSource, scratch: &mut [u8]| {
                let mut pose = PoseWeights::default();
                let mut lit = LitWeights::default();
                let (mut transfer, mut shading, mut bones_out) =
                    (vec![0.0f32; 45 * n2], vec![0.0f32; 45], vec![0u16; 45]);
                model.set_pose(src, &angles, scratch, &mut pose).unwrap();
                assert_eq!(
                    model.light(&pose, &light, &mut lit),
                    Err(aprt_core::Error::FrameMismatch)
                );
                model
                    .light_skinned(&pose, &light, &rotations, &mut lit)
                    .unwrap();
                model
                    .transfer(src, &pose, 0, &mut transfer, scratch)
                    .unwrap();
                model.shade(src, &lit, 0, &mut shading, scratch).unwrap();
                model.vertex_bones(src, 0, &mut bones_out, scratch).unwrap();
                (transfer, shading, bones_out)
            };
            let (transfer, shading, vertex_bones) = if streamed {
                run(&mut Streamed::new(&blob), &mut scratch)
            } else {
                run(&mut SliceSource(&blob), &mut scratch)
            };
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

/// Weights computed for one model are refused by a model of another shape or frame, even when
/// their dimensions agree: they would shade with another model's numbers.
#[test]
fn weights_of_another_model_are_refused() {
    use aprt_trainer::BoneFrames;
    let world = random_model(2, 16, 3, 2, Some(4));
    let mut skinned = world.clone();
    skinned.bones = Some(BoneFrames {
        count: 2,
        vertex_bone: vec![1; 16],
    });
    let (a, b) = (
        encode_model(&world, Precision::F32).unwrap(),
        encode_model(&skinned, Precision::F32).unwrap(),
    );
    let (ma, mb) = (Model::parse(&a).unwrap(), Model::parse(&b).unwrap());
    let mut pose = PoseWeights::default();
    ma.set_pose(&mut SliceSource(&a), &[0.1; 3], &mut [], &mut pose)
        .unwrap();
    let mut lit = LitWeights::default();
    ma.light(&pose, &[1.0; 4], &mut lit).unwrap();
    let mut out = [0.0f32; 16];
    assert_eq!(
        mb.shade(&mut SliceSource(&b), &lit, 0, &mut out, &mut []),
        Err(aprt_core::Error::ShapeMismatch)
    );
    assert_eq!(
        mb.transfer(&mut SliceSource(&b), &pose, 0, &mut [0.0; 64], &mut []),
        Err(aprt_core::Error::ShapeMismatch)
    );
}

/// Regression (found by the fuzz harness): `Model::open` promises that any scratch of at least
/// 4 bytes works, but checked a bone-frame model's bone rows a whole block at a time and
/// refused buffers under 32 bytes.
#[test]
fn bone_frame_model_opens_with_the_smallest_scratch() {
    use aprt_trainer::BoneFrames;
    let mut reference = random_model(2, 13, 3, 1, Some(5));
    reference.bones = Some(BoneFrames {
        count: 3,
        vertex_bone: (0..13).map(|j| (j % 3) as u16).collect(),
    });
    for precision in [Precision::F32, Precision::F16] {
        let blob = encode_model(&reference, precision).unwrap();
        let model = Model::parse(&blob).unwrap();
        assert_eq!(
            Model::open(&mut Streamed::new(&blob), &mut [0u8; 4]),
            Ok(model)
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
        /// every scratch size from nothing to one block beyond the least, and sizes below the
        /// least are refused with `BufferTooSmall`, never a panic.
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
            let sizes = 0..=model.scratch_bytes() + model.block_bytes();
            prop_assume!(*sizes.end() <= 1024);
            harness::check_streaming(&blob, &Probe::GENTLE, sizes);
        }
    }
}
