//! Hostile blobs: the core returns `Ok` or a typed error for every input, never panics, and
//! its checksums catch every single-bit flip inside the header and the sections. The same
//! properties are fuzzed for longer by the cargo-fuzz targets.

use aprt_core::blob::{Error, Header, MAGIC, PREAMBLE_LEN, SectionEntry, read_header};
use aprt_core::{LitWeights, Model, PoseWeights, SliceSource};
use aprt_tests::{Streamed, random_model};
use aprt_trainer::{Precision, encode_model};
use proptest::prelude::*;

fn valid_blob() -> Vec<u8> {
    encode_model(&random_model(2, 9, 3, 2, Some(3)), Precision::F32).unwrap()
}

/// Parses, then (when valid) evaluates through both source kinds; must never panic. Returns
/// the shading of every vertex.
fn exercise(blob: &[u8]) -> Result<Vec<f32>, Error> {
    let model = Model::parse(blob)?;
    let streamed = Model::open(&mut Streamed::new(blob), &mut [0u8; 7])?;
    assert_eq!(model, streamed);
    let n2 = model.order() * model.order();
    let angles = vec![0.25f32; model.joints()];
    let mut pose = PoseWeights::default();
    model.set_pose(&mut SliceSource(blob), &angles, &mut [], &mut pose)?;
    let mut lit = LitWeights::default();
    model.light(&pose, &vec![1.0; n2], &mut lit)?;
    let mut out = vec![0.0; model.vertices()];
    model.shade(&mut SliceSource(blob), &lit, 0, &mut out, &mut [])?;
    assert!(out.iter().all(|x| x.is_finite()));
    Ok(out)
}

/// Rebuilds the blob with an edited header. The section bytes keep their places relative to
/// each other; if the header grew past them, everything after it moves by whole alignment
/// units and the offsets with it.
fn with_header(blob: &[u8], edit: impl FnOnce(&mut Header)) -> Vec<u8> {
    let original = read_header(blob).unwrap();
    let first = original.sections.iter().map(|s| s.offset).min().unwrap() as usize;
    let mut edited = original;
    edit(&mut edited);
    let mut shift = 0u64;
    let bytes = loop {
        let mut h = edited.clone();
        h.sections
            .iter_mut()
            .for_each(|s| s.offset = s.offset.saturating_add(shift));
        let bytes = postcard::to_allocvec(&h).unwrap();
        if PREAMBLE_LEN + bytes.len() <= first + shift as usize {
            break bytes;
        }
        shift += 16;
    };
    let mut out = Vec::new();
    out.extend_from_slice(&blob[..12]);
    out.extend_from_slice(&(bytes.len() as u32).to_le_bytes());
    out.extend_from_slice(&aprt_core::blob::crc32(&bytes).to_le_bytes());
    out.extend_from_slice(&bytes);
    out.resize(first + shift as usize, 0);
    out.extend_from_slice(&blob[first..]);
    out
}

#[test]
fn the_valid_blob_evaluates() {
    exercise(&valid_blob()).unwrap();
}

#[test]
fn every_proper_prefix_is_rejected() {
    let blob = valid_blob();
    for n in 0..blob.len() {
        assert!(
            exercise(&blob[..n]).is_err(),
            "prefix of {n} bytes accepted"
        );
    }
}

#[test]
fn every_single_bit_flip_is_caught_or_harmless() {
    let blob = valid_blob();
    let header = read_header(&blob).unwrap();
    let covered = |i: usize| {
        i < PREAMBLE_LEN + u32::from_le_bytes(blob[12..16].try_into().unwrap()) as usize
            || header
                .sections
                .iter()
                .any(|s| (s.offset as usize..(s.offset + s.len) as usize).contains(&i))
    };
    let mut caught = 0;
    let clean = exercise(&blob).unwrap();
    for i in 0..blob.len() {
        for bit in 0..8 {
            let mut bad = blob.clone();
            bad[i] ^= 1 << bit;
            let result = exercise(&bad);
            if covered(i) {
                assert!(result.is_err(), "flip of bit {bit} in byte {i} not caught");
                caught += 1;
            } else {
                // Alignment padding between sections: no checksum, and no effect either.
                assert_eq!(
                    result.as_ref(),
                    Ok(&clean),
                    "padding flip in byte {i} changed the result"
                );
            }
        }
    }
    assert!(caught > 8 * 300, "only {caught} flips in checked bytes");
}

#[test]
fn crafted_headers_get_the_right_error() {
    let blob = valid_blob();
    let mut future = blob.clone();
    future[8..12].copy_from_slice(&2u32.to_le_bytes());
    assert_eq!(
        Model::parse(&future),
        Err(Error::UnsupportedVersion { found: 2 })
    );
    let mut magic = blob.clone();
    magic[0] = b'X';
    assert_eq!(Model::parse(&magic), Err(Error::BadMagic));
    let mut trailing = blob.clone();
    trailing.push(0);
    assert_eq!(
        Model::parse(&trailing),
        Err(Error::TrailingBytes { extra: 1 })
    );

    let huge = with_header(&blob, |h| h.vertices = u32::MAX);
    assert!(matches!(
        Model::parse(&huge),
        Err(Error::BadDimension { .. })
    ));
    let overlap = with_header(&blob, |h| h.sections[1].offset = h.sections[0].offset);
    assert!(matches!(
        Model::parse(&overlap),
        Err(Error::SectionOverlap { .. })
    ));
    let outside = with_header(&blob, |h| h.sections[2].offset = u64::MAX - 15);
    assert!(matches!(
        Model::parse(&outside),
        Err(Error::SectionOutOfRange { .. })
    ));
    let misaligned = with_header(&blob, |h| h.sections[3].offset += 4);
    assert!(Model::parse(&misaligned).is_err());
    let missing = with_header(&blob, |h| {
        h.sections.remove(0);
    });
    assert!(matches!(
        Model::parse(&missing),
        Err(Error::MissingSection { .. }) | Err(Error::TrailingBytes { .. })
    ));

    // A newer writer's optional section is skipped, but its checksum still counts; a required
    // one is refused.
    let mut extended = blob.clone();
    extended.resize(extended.len().next_multiple_of(16), 0);
    let extra = SectionEntry {
        kind: 999,
        required: false,
        encoding: 0,
        offset: extended.len() as u64,
        len: 16,
        crc32: aprt_core::blob::crc32(&[7u8; 16]),
    };
    extended.extend_from_slice(&[7u8; 16]);
    let optional = with_header(&extended, |h| h.sections.push(extra).unwrap());
    exercise(&optional).unwrap();
    let corrupt = with_header(&extended, |h| {
        h.sections.push(SectionEntry { crc32: 0, ..extra }).unwrap()
    });
    assert_eq!(
        Model::parse(&corrupt),
        Err(Error::ChecksumMismatch { kind: 999 })
    );
    let required = with_header(&extended, |h| {
        h.sections
            .push(SectionEntry {
                required: true,
                ..extra
            })
            .unwrap()
    });
    assert_eq!(
        Model::parse(&required),
        Err(Error::UnknownRequiredSection { kind: 999 })
    );
}

fn arb_entry() -> impl Strategy<Value = SectionEntry> {
    // Biased toward boundary values: small offsets, exact multiples, and near-overflow sizes.
    let edge = prop_oneof![
        0u64..256,
        Just(u64::MAX),
        Just(u64::MAX - 15),
        (0u64..64).prop_map(|x| x * 16)
    ];
    (
        1u16..7,
        any::<bool>(),
        0u8..3,
        edge.clone(),
        edge,
        any::<u32>(),
    )
        .prop_map(
            |(kind, required, encoding, offset, len, crc32)| SectionEntry {
                kind,
                required,
                encoding,
                offset,
                len,
                crc32,
            },
        )
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 3000, ..ProptestConfig::default() })]

    /// Arbitrary bytes never panic the reader.
    #[test]
    fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
        let _ = exercise(&bytes);
        let mut with_magic = MAGIC.to_vec();
        with_magic.extend_from_slice(&bytes);
        let _ = exercise(&with_magic);
    }

    /// Well-formed headers with arbitrary dimensions and section tables never panic the
    /// reader or the evaluator, including dimensions whose products overflow.
    #[test]
    fn random_headers_never_panic(
        order in 0u8..9,
        vertices in prop_oneof![0u32..40, Just(u32::MAX)],
        joints in prop_oneof![0u16..8, Just(u16::MAX)],
        pose_dims in 0u16..10,
        coef_dims in prop_oneof![0u32..40, Just(u32::MAX)],
        identity in any::<bool>(),
        entries in proptest::collection::vec(arb_entry(), 0..8),
        body in proptest::collection::vec(any::<u8>(), 0..600),
    ) {
        let mut header = read_header(&valid_blob()).unwrap();
        header.order = order;
        header.vertices = vertices;
        header.joints = joints;
        header.pose_dims = pose_dims;
        header.coef_dims = coef_dims;
        header.basis = if identity { aprt_core::blob::Basis::Identity } else { aprt_core::blob::Basis::Stored };
        header.sections = entries.into_iter().collect();
        let bytes = postcard::to_allocvec(&header).unwrap();
        let mut blob = MAGIC.to_vec();
        blob.extend_from_slice(&1u32.to_le_bytes());
        blob.extend_from_slice(&(bytes.len() as u32).to_le_bytes());
        blob.extend_from_slice(&aprt_core::blob::crc32(&bytes).to_le_bytes());
        blob.extend_from_slice(&bytes);
        blob.extend_from_slice(&body);
        let _ = exercise(&blob);
    }
}
