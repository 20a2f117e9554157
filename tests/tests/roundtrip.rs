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
    let n2 = reference.order * reference.order;
    let angles64 = noise(9, reference.joints);
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
