//! Small valid blobs, one per kind of model (stored or identity basis, world or bone frame,
//! f32 or f16, angles or cosine features): the starting points of the mutation tests and the seeds of the fuzz corpus
//! (`cargo test -p aprt-tests --test corpus -- --ignored` writes `fuzz/corpus/`).

use aprt_trainer::{BoneFrames, LinearModel, Precision, encode_model};

use crate::{random_model, with_cosines};

fn with_bones(mut m: LinearModel, count: usize) -> LinearModel {
    m.bones = Some(BoneFrames {
        count,
        vertex_bone: (0..m.vertices)
            .map(|j| (j * 5 / 3 % count) as u16)
            .collect(),
    });
    m
}

/// `(name, model, precision)` of each sample.
pub fn sample_models() -> Vec<(&'static str, LinearModel, Precision)> {
    vec![
        (
            "stored-f32",
            random_model(2, 9, 3, 2, Some(3)),
            Precision::F32,
        ),
        (
            "identity-f16",
            random_model(1, 5, 2, 1, None),
            Precision::F16,
        ),
        (
            "bones-stored-f16",
            with_bones(random_model(3, 11, 4, 0, Some(2)), 3),
            Precision::F16,
        ),
        (
            "bones-identity-f32",
            with_bones(random_model(2, 8, 1, 1, None), 2),
            Precision::F32,
        ),
        (
            "cosines-stored-f32",
            with_cosines(random_model(2, 7, 3, 2, Some(2)), &[true, false, true]),
            Precision::F32,
        ),
    ]
}

/// `(name, blob)` of each sample.
pub fn sample_blobs() -> Vec<(&'static str, Vec<u8>)> {
    sample_models()
        .into_iter()
        .map(|(name, m, p)| (name, encode_model(&m, p).expect("samples are valid")))
        .collect()
}
