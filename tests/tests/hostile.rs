//! Hostile blobs: the core returns `Ok` or a typed error for every input, never panics, and
//! its checksums catch every single-bit flip inside the header and the sections. The same
//! properties are fuzzed for longer by the cargo-fuzz targets.

use aprt_core::format::{Header, MAGIC, PREAMBLE_LEN, SectionEntry, crc32, read_header};
use aprt_core::{Basis, Error, Frame, Model, ModelInfo, SectionKind};
use std::sync::LazyLock;

use aprt_tests::edit::{self, Mutation, reseal};
use aprt_tests::harness::{self, Evaluation, Probe};
use aprt_tests::random_model;
use aprt_tests::samples::sample_blobs;
use aprt_trainer::{Precision, encode_model};
use proptest::prelude::*;

fn valid_blob() -> Vec<u8> {
    encode_model(&random_model(2, 9, 3, 2, Some(3)), Precision::F32).unwrap()
}

/// What the reader makes of a blob.
fn parse(blob: &[u8]) -> Result<ModelInfo, Error> {
    Model::parse(blob).map(|m| *m.info())
}

/// The shared fuzz harness with gentle inputs.
fn exercise(blob: &[u8]) -> Result<Evaluation, Error> {
    harness::exercise(blob, &Probe::GENTLE)
}

fn with_header(blob: &[u8], edit: impl FnOnce(&mut Header)) -> Vec<u8> {
    edit::with_header(blob, edit).expect("a valid blob's header")
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

/// Checksums catch every single-bit flip: in a section's bytes as that section's
/// `ChecksumMismatch`, in the header as `HeaderChecksum`, in the preamble as some error; a flip
/// in the alignment padding between sections (no checksum) leaves the result unchanged.
#[test]
fn every_single_bit_flip_is_caught_or_harmless() {
    for (name, blob) in sample_blobs() {
        let header = read_header(&blob).unwrap();
        let header_end =
            PREAMBLE_LEN + u32::from_le_bytes(blob[12..16].try_into().unwrap()) as usize;
        let section = |i: usize| {
            header
                .sections
                .iter()
                .find(|s| (s.offset as usize..(s.offset + s.len) as usize).contains(&i))
        };
        let clean = exercise(&blob).unwrap();
        let mut caught = 0;
        for i in 0..blob.len() {
            for bit in 0..8 {
                let mut bad = blob.clone();
                bad[i] ^= 1 << bit;
                let result = exercise(&bad);
                let expected = match (i, section(i)) {
                    (..PREAMBLE_LEN, _) => None,
                    (i, _) if i < header_end => Some(Error::HeaderChecksum),
                    (_, Some(s)) => Some(Error::ChecksumMismatch {
                        section: SectionKind::from_tag(s.kind),
                    }),
                    (_, None) => {
                        assert_eq!(
                            result.as_ref(),
                            Ok(&clean),
                            "{name}: padding flip in byte {i}"
                        );
                        continue;
                    }
                };
                let err = result.expect_err("flip not caught");
                assert!(
                    expected.is_none_or(|e| e == err),
                    "{name}: flip of bit {bit} in byte {i}: {err:?}, expected {expected:?}"
                );
                caught += 1;
            }
        }
        assert!(
            caught >= 8 * (blob.len() - 15 * header.sections.len()),
            "{name}: {caught} flips"
        );
    }
}

/// A pose-features flag must be 0 or 1: anything else, checksums matching, is refused.
#[test]
fn a_pose_feature_flag_other_than_0_or_1_is_refused() {
    let (_, blob) = sample_blobs()
        .into_iter()
        .find(|(name, _)| name.starts_with("cosines"))
        .expect("a sample with cosine features");
    assert_eq!(parse(&blob).map(|i| i.feature_len()), Ok(5));
    let header = read_header(&blob).unwrap();
    let flags = header
        .sections
        .iter()
        .find(|s| s.kind == SectionKind::PoseFeatures.tag())
        .expect("the pose-features section");
    for bad in [0.5f32, -1.0, 2.0, f32::NAN] {
        let mut edited = blob.clone();
        let at = flags.offset as usize;
        edited[at..at + 4].copy_from_slice(&bad.to_le_bytes());
        let result = parse(&reseal(&edited));
        let expected = if bad.is_nan() {
            Error::NonFinite {
                section: SectionKind::PoseFeatures,
            }
        } else {
            Error::BadPoseFeatures
        };
        assert_eq!(result, Err(expected), "flag {bad}");
    }
}

/// Scaled-byte rows are read only with their scales, whose values must be finite; a bone byte
/// at or past the bone count, a scales section of the wrong length, and scaled bytes in a
/// section that may not hold them are each refused with their error, checksums matching.
#[test]
fn scaled_byte_damage_gets_its_error() {
    let (_, blob) = sample_blobs()
        .into_iter()
        .find(|(name, _)| *name == "bones-identity-i8")
        .expect("a bone-frame sample in scaled bytes");
    let info = parse(&blob).expect("the sample is valid");
    assert_eq!(info.encoding(), aprt_core::Encoding::I8);
    let header = read_header(&blob).unwrap();
    let index = |kind: SectionKind| {
        header
            .sections
            .iter()
            .position(|s| s.kind == kind.tag())
            .expect("the section")
    };
    let (scales, rows) = (
        header.sections[index(SectionKind::RowScales)],
        header.sections[index(SectionKind::VertexWeights)],
    );
    let section = SectionKind::RowScales;
    let without = with_header(&blob, |h| {
        h.sections[index(section)].kind = 99;
        h.sections[index(section)].required = false;
    });
    assert_eq!(parse(&without), Err(Error::MissingSection { section }));
    let short = with_header(&blob, |h| h.sections[index(section)].len -= 4);
    assert!(matches!(
        parse(&reseal(&short)),
        Err(Error::SectionLength {
            section: SectionKind::RowScales,
            ..
        })
    ));
    for bad in [f32::NAN, f32::INFINITY] {
        let mut edited = blob.clone();
        let at = scales.offset as usize + 4;
        edited[at..at + 4].copy_from_slice(&bad.to_le_bytes());
        assert_eq!(parse(&reseal(&edited)), Err(Error::NonFinite { section }));
    }
    // The first block's lead row: one unsigned byte per lane, below the 3 bones.
    for (bone, expect) in [
        (2u8, Ok(())),
        (3, Err(Error::BadBoneIndex)),
        (255, Err(Error::BadBoneIndex)),
    ] {
        let mut edited = blob.clone();
        edited[rows.offset as usize + 5] = bone;
        assert_eq!(
            parse(&reseal(&edited)).map(|_| ()),
            expect,
            "bone byte {bone}"
        );
    }
    let (_, stored) = sample_blobs()
        .into_iter()
        .find(|(name, _)| *name == "stored-f32")
        .unwrap();
    let weights = with_header(&stored, |h| {
        let e = h
            .sections
            .iter_mut()
            .find(|s| s.kind == SectionKind::Weights.tag())
            .unwrap();
        e.encoding = aprt_core::Encoding::I8 as u8;
    });
    assert_eq!(
        parse(&weights),
        Err(Error::BadEncoding {
            section: SectionKind::Weights
        })
    );
}

#[test]
fn crafted_headers_get_the_right_error() {
    let blob = valid_blob();
    let mut future = blob.clone();
    future[8..12].copy_from_slice(&2u32.to_le_bytes());
    assert_eq!(parse(&future), Err(Error::UnsupportedVersion { found: 2 }));
    let mut magic = blob.clone();
    magic[0] = b'X';
    assert_eq!(parse(&magic), Err(Error::BadMagic));
    let mut trailing = blob.clone();
    trailing.push(0);
    assert_eq!(parse(&trailing), Err(Error::TrailingBytes { extra: 1 }));

    // Regression (found by the mutation test): a NaN α was accepted, and the model was then
    // unequal to itself.
    for alpha in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        let bad = with_header(&blob, |h| h.alpha = alpha);
        assert_eq!(parse(&bad), Err(Error::HeaderMalformed));
    }

    let huge = with_header(&blob, |h| h.vertices = u32::MAX);
    assert!(matches!(parse(&huge), Err(Error::BadDimension { .. })));
    let overlap = with_header(&blob, |h| h.sections[1].offset = h.sections[0].offset);
    assert!(matches!(parse(&overlap), Err(Error::SectionOverlap { .. })));
    let outside = with_header(&blob, |h| h.sections[2].offset = u64::MAX - 15);
    assert!(matches!(
        parse(&outside),
        Err(Error::SectionOutOfRange { .. })
    ));
    let misaligned = with_header(&blob, |h| h.sections[3].offset += 4);
    assert!(parse(&misaligned).is_err());
    let missing = with_header(&blob, |h| {
        h.sections.remove(0);
    });
    assert!(matches!(
        parse(&missing),
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
        crc32: crc32(&[7u8; 16]),
    };
    extended.extend_from_slice(&[7u8; 16]);
    let optional = with_header(&extended, |h| h.sections.push(extra).unwrap());
    exercise(&optional).unwrap();
    let corrupt = with_header(&extended, |h| {
        h.sections.push(SectionEntry { crc32: 0, ..extra }).unwrap()
    });
    assert_eq!(
        parse(&corrupt),
        Err(Error::ChecksumMismatch {
            section: SectionKind::Unknown(999)
        })
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
        parse(&required),
        Err(Error::UnknownRequiredSection {
            section: SectionKind::Unknown(999)
        })
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

    /// Arbitrary bytes never panic the reader: as a whole blob, after the magic, and as a
    /// header behind a valid preamble and checksum, so they reach the header's decoding.
    #[test]
    fn random_bytes_never_panic(
        bytes in proptest::collection::vec(any::<u8>(), 0..400),
        header_len in 0usize..400,
    ) {
        let _ = exercise(&bytes);
        let mut with_magic = MAGIC.to_vec();
        with_magic.extend_from_slice(&bytes);
        let _ = exercise(&with_magic);
        let header = &bytes[..header_len.min(bytes.len())];
        let mut sealed = MAGIC.to_vec();
        sealed.extend_from_slice(&1u32.to_le_bytes());
        sealed.extend_from_slice(&(header.len() as u32).to_le_bytes());
        sealed.extend_from_slice(&crc32(header).to_le_bytes());
        sealed.extend_from_slice(&bytes);
        let result = exercise(&sealed);
        prop_assert!(
            !matches!(
                result,
                Err(Error::BadMagic | Error::UnsupportedVersion { .. } | Error::HeaderChecksum)
            ),
            "{:?}",
            result
        );
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
        header.pose_len = joints;
        header.pose_dims = pose_dims;
        header.coef_dims = coef_dims;
        header.basis = if identity { Basis::Identity } else { Basis::Stored };
        header.sections = entries.into_iter().collect();
        let bytes = postcard::to_allocvec(&header).unwrap();
        let mut blob = MAGIC.to_vec();
        blob.extend_from_slice(&1u32.to_le_bytes());
        blob.extend_from_slice(&(bytes.len() as u32).to_le_bytes());
        blob.extend_from_slice(&crc32(&bytes).to_le_bytes());
        blob.extend_from_slice(&bytes);
        blob.extend_from_slice(&body);
        let _ = exercise(&blob);
    }
}

/// The sample blobs, encoded once.
fn samples() -> &'static [(&'static str, Vec<u8>)] {
    static SAMPLES: LazyLock<Vec<(&'static str, Vec<u8>)>> = LazyLock::new(sample_blobs);
    &SAMPLES
}

fn arb_mutation() -> impl Strategy<Value = Mutation> {
    let bytes = || proptest::collection::vec(any::<u8>(), 1..24);
    prop_oneof![
        (any::<usize>(), 0u8..8).prop_map(|(at, bit)| Mutation::Flip { at, bit }),
        (any::<usize>(), bytes()).prop_map(|(at, bytes)| Mutation::Overwrite { at, bytes }),
        (any::<usize>(), any::<usize>()).prop_map(|(at, which)| Mutation::Word { at, which }),
        (any::<usize>(), bytes()).prop_map(|(at, bytes)| Mutation::Insert { at, bytes }),
        (any::<usize>(), 1usize..40).prop_map(|(at, len)| Mutation::Remove { at, len }),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 3000, ..ProptestConfig::default() })]

    /// Random multi-byte mutations of every kind of valid blob, half of them with every
    /// checksum recomputed so they reach the validation behind the CRCs, under random probe
    /// inputs: the full harness holds (verdicts, refusals, streaming, reference).
    #[test]
    fn mutated_blobs_hold_the_harness(
        sample in 0usize..4,
        mutations in proptest::collection::vec(arb_mutation(), 1..6),
        sealed in any::<bool>(),
        probe in proptest::collection::vec(any::<u8>(), harness::PROBE_BYTES),
    ) {
        let mut blob = samples()[sample].1.clone();
        mutations.iter().for_each(|m| m.apply(&mut blob));
        if sealed {
            blob = reseal(&blob);
        }
        let _ = harness::exercise(&blob, &Probe::from_bytes(&probe));
    }
}

/// Resealed mutations get past the checksums: over a few thousand of them the reader reports
/// most of its kinds of error, and some mutated blobs are valid and evaluate.
#[test]
fn resealed_mutations_reach_the_deep_checks() {
    use std::collections::BTreeMap;
    let mut seen: BTreeMap<String, usize> = BTreeMap::new();
    let r = aprt_tests::noise(77, 4 * 3000);
    let pick = |x: f64, n: usize| ((x + 1.0) * 0.5 * n as f64) as usize % n;
    for i in 0..3000 {
        let x = &r[4 * i..4 * i + 4];
        let mut blob = samples()[i % samples().len()].1.clone();
        let at = pick(x[0], blob.len());
        let m = match i % 3 {
            0 => Mutation::Word {
                at,
                which: pick(x[1], Mutation::WORDS.len()),
            },
            1 => Mutation::Flip {
                at,
                bit: pick(x[1], 8) as u8,
            },
            _ => Mutation::Overwrite {
                at,
                bytes: vec![pick(x[1], 256) as u8, pick(x[2], 256) as u8],
            },
        };
        m.apply(&mut blob);
        let verdict = match exercise(&reseal(&blob)) {
            Ok(_) => "Ok".to_string(),
            Err(e) => format!("{e:?}")
                .split([' ', '{', '('])
                .next()
                .unwrap()
                .to_string(),
        };
        *seen.entry(verdict).or_default() += 1;
    }
    for kind in [
        "Ok",
        "NonFinite",
        "SectionLength",
        "BadDimension",
        "HeaderMalformed",
        "SectionOutOfRange",
        "BadBoneIndex",
    ] {
        assert!(seen.contains_key(kind), "{kind} never reached: {seen:?}");
    }
}

/// Dimensions at, just past and far past every limit, with section lengths set to the
/// wrapped (overflowed) products a careless reader would compute: never a panic, and never
/// accepted with a dimension out of range.
#[test]
fn overflowing_dimensions_are_refused() {
    let blob = valid_blob();
    let orders = [0u8, 1, 6, 7, u8::MAX];
    let vertices = [0u32, 1, 1 << 22, (1 << 22) + 1, u32::MAX];
    let joints = [0u16, 1, 512, 513, u16::MAX];
    let coef = [0u32, 1, 96, 97, u32::MAX];
    for (i, (&order, &v)) in orders.iter().zip(&vertices).enumerate() {
        for (&a, &kv) in joints.iter().zip(&coef) {
            for (pose_dims, bones) in [(0u16, 0u16), (128, 256), (129, 257), (u16::MAX, u16::MAX)] {
                let edited = with_header(&blob, |h| {
                    (h.order, h.vertices, h.pose_len, h.pose_dims, h.coef_dims) =
                        (order, v, a, pose_dims, kv);
                    if i % 2 == 1 {
                        h.frame = Frame::Bones { count: bones };
                    }
                    let n2 = (order as u64).pow(2);
                    let wrapped = n2
                        .wrapping_mul(1 + pose_dims as u64)
                        .wrapping_mul(kv as u64)
                        .wrapping_mul(v as u64)
                        .wrapping_mul(4);
                    h.sections.iter_mut().for_each(|s| s.len = wrapped);
                });
                let within = (1..=6).contains(&order)
                    && (1..=1 << 22).contains(&v)
                    && (1..=512).contains(&a)
                    && pose_dims <= 128.min(a);
                let result = exercise(&edited);
                // Refused for the dimension itself: every section length is wrong too, so
                // any other error would pass even with the dimension checks gone.
                assert!(
                    within || matches!(result, Err(Error::BadDimension { .. })),
                    "{order} {v} {a} {pose_dims} {kv}: {result:?}"
                );
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    /// Each kind of damage gets its own error, in every kind of blob: any other version, a
    /// header longer than allowed, a wrong header or section checksum, trailing bytes.
    #[test]
    fn each_damage_gets_its_error(
        sample in 0usize..4,
        version in any::<u32>().prop_filter("another version", |v| *v != 1),
        header_len in 1025u32..,
        crc in any::<u32>(),
        section in any::<usize>(),
        trailing in proptest::collection::vec(any::<u8>(), 1..64),
    ) {
        let blob = &samples()[sample].1;
        let patched = |at: usize, word: u32| {
            let mut b = blob.clone();
            b[at..at + 4].copy_from_slice(&word.to_le_bytes());
            b
        };
        prop_assert_eq!(
            parse(&patched(8, version)),
            Err(Error::UnsupportedVersion { found: version })
        );
        prop_assert_eq!(
            parse(&patched(12, header_len)),
            Err(Error::HeaderTooLarge { len: header_len })
        );
        let header_crc = u32::from_le_bytes(blob[16..20].try_into().unwrap());
        if crc != header_crc {
            prop_assert_eq!(parse(&patched(16, crc)), Err(Error::HeaderChecksum));
        }
        let entries = read_header(blob).unwrap().sections;
        let e = entries[section % entries.len()];
        if crc != e.crc32 {
            let wrong = with_header(blob, |h| h.sections[section % entries.len()].crc32 = crc);
            prop_assert_eq!(
                parse(&wrong),
                Err(Error::ChecksumMismatch { section: SectionKind::from_tag(e.kind) })
            );
        }
        let long = [&blob[..], &trailing].concat();
        prop_assert_eq!(
            parse(&long),
            Err(Error::TrailingBytes { extra: trailing.len() as u64 })
        );
    }
}

/// Moving or resizing any section, with every checksum recomputed to match, is refused:
/// sections are packed, so it now overlaps another, the header or the end, or its length no
/// longer matches the dimensions; the angle names, whose length is free, no longer hold one
/// name per pose entry. One edit may leave a valid blob: an empty section (no pose
/// dimensions) moved to another boundary. Every section of every sample, every move by up to
/// 64 alignment steps either way and every resize by up to 64 values (about 330k blobs, a
/// second).
#[test]
fn moved_or_resized_sections_are_refused() {
    // Empty sections moved and still valid; angle names edited and refused for their content.
    let (mut empty_valid, mut names_refused) = (0usize, 0usize);
    for (name, blob) in samples() {
        let entries = read_header(blob).unwrap().sections;
        for (section, before) in entries.iter().enumerate() {
            let is_names = SectionKind::from_tag(before.kind) == SectionKind::AngleNames;
            let is_rig = SectionKind::from_tag(before.kind) == SectionKind::IrradianceRig;
            let is_atlas = SectionKind::from_tag(before.kind) == SectionKind::TexelAtlas;
            let is_proxies = SectionKind::from_tag(before.kind) == SectionKind::Proxies;
            for (offset_delta, len_delta) in
                (-64i64..64).flat_map(|o| (-64i64..64).map(move |l| (o, l)))
            {
                let offset = before.offset.saturating_add_signed(offset_delta * 16);
                let len = before.len.saturating_add_signed(len_delta * 4);
                if (offset, len) == (before.offset, before.len) {
                    continue; // saturation undid the edit (an empty section cannot shrink)
                }
                let edited = with_header(blob, |h| {
                    (h.sections[section].offset, h.sections[section].len) = (offset, len)
                });
                let result = exercise(&reseal(&edited));
                let empty_moved = before.len == 0 && len == 0 && offset <= blob.len() as u64;
                empty_valid += usize::from(empty_moved && result.is_ok());
                names_refused += usize::from(result == Err(Error::BadAngleNames));
                assert!(
                    matches!(
                        result,
                        Err(Error::SectionOverlap { .. }
                            | Error::SectionOutOfRange { .. }
                            | Error::SectionLength { .. }
                            | Error::SectionMisaligned { .. }
                            | Error::TrailingBytes { .. })
                    ) || (is_names && result == Err(Error::BadAngleNames))
                        || (is_rig && result == Err(Error::BadIrradianceRig))
                        || (is_atlas && result == Err(Error::BadTexelAtlas))
                        || (is_proxies && result == Err(Error::BadProxies))
                        || (empty_moved && result.is_ok()),
                    "{name}, section {section} moved to {offset}, resized to {len}: {result:?}"
                );
            }
        }
    }
    assert!(
        empty_valid > 0 && names_refused > 0,
        "empty sections moved and valid: {empty_valid}, angle names refused: {names_refused}"
    );
}

/// A source whose bytes change after the model was opened from it (a file rewritten under a
/// streaming reader) gives wrong numbers, never a panic: the evaluator reads the changed
/// sections of every sample, filled with NaN, huge values and random bytes, through every
/// call a frame makes, streamed through the least buffer. (A resident `Model` borrows its
/// blob, so its bytes cannot change under it.)
#[test]
fn a_source_changed_after_open_never_panics() {
    use aprt_core::{BlobSource, LitWeights, PoseWeights, SourceError, StreamedModel};
    use std::cell::Cell;

    /// The original bytes until `changed` is set, then the others.
    struct Changing<'a> {
        before: &'a [u8],
        after: &'a [u8],
        changed: Cell<bool>,
    }
    impl BlobSource for &Changing<'_> {
        fn len(&self) -> u64 {
            self.before.len() as u64
        }
        fn read_at(&mut self, offset: u64, buf: &mut [u8]) -> Result<(), SourceError> {
            let bytes = if self.changed.get() {
                self.after
            } else {
                self.before
            };
            let start = offset as usize;
            buf.copy_from_slice(bytes.get(start..start + buf.len()).ok_or(SourceError)?);
            Ok(())
        }
    }

    // Frames that reached the shading loop: some garbage must get that far.
    let mut shaded = 0;
    for (_, blob) in samples() {
        let info = *Model::parse(blob).unwrap().info();
        let sections = read_header(blob).unwrap().sections;
        let data_start = sections.iter().map(|s| s.offset).min().unwrap() as usize;
        let noise = aprt_tests::noise(5, blob.len());
        let fills: [&dyn Fn(usize) -> u8; 4] = [
            &|_| 0xff,
            &|i| [0x00, 0x00, 0x80, 0x7f][i % 4],
            &|i| [0xff, 0xff, 0x7f, 0x7f][i % 4],
            &|i| ((noise[i] + 1.0) * 128.0) as u8,
        ];
        for fill in fills {
            let mut after = blob.clone();
            (data_start..blob.len()).for_each(|i| after[i] = fill(i));
            let source = Changing {
                before: blob,
                after: &after,
                changed: Cell::new(false),
            };
            let mut scratch = vec![0u8; info.scratch_bytes()];
            let mut model = StreamedModel::open(&source, &mut scratch).unwrap();
            source.changed.set(true);
            let mut pose = Box::new(PoseWeights::new());
            let _ = model.set_pose(&vec![0.5; info.pose_len()], &mut pose);
            let identity = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
            let mut lit = Box::new(LitWeights::new());
            let _ = model.light(
                &pose,
                &vec![1.0; info.coeffs()],
                &vec![identity; info.bones()],
                &mut lit,
            );
            let mut shading = vec![0.0; info.vertices()];
            shaded += usize::from(model.shade(&lit, 0, &mut shading).is_ok());
            let mut transfer = vec![0.0; info.vertices() * info.coeffs()];
            let _ = model.transfer(&pose, 0, &mut transfer);
            let mut bones = vec![0u16; info.vertices()];
            let _ = model.vertex_bones(0, &mut bones);
            let mut names = vec![0u8; info.angle_names_bytes()];
            let _ = model.angle_names(&mut names);
        }
    }
    assert!(shaded > 0, "no changed source reached the shading loop");
}

/// Occluder proxies' damage, checksums matching, is refused with `BadProxies`: counts out of
/// range or not the model's bones, a cull outside [0, 1), a reserved word, a bone past the
/// count, non-finite or non-positive radii, a NaN centre, a mask bit past the proxies, a
/// length the counts do not imply; and so is a proxies section in a world-frame model.
#[test]
fn damaged_occluder_proxies_are_refused() {
    let (_, blob) = sample_blobs()
        .into_iter()
        .find(|(name, _)| *name == "proxies-bones-f32")
        .expect("the proxies sample");
    assert!(parse(&blob).unwrap().has_proxies());
    let header = read_header(&blob).unwrap();
    let at = header
        .sections
        .iter()
        .find(|s| s.kind == SectionKind::Proxies.tag())
        .expect("the proxies section")
        .offset as usize;
    let word = |offset: usize, value: [u8; 4]| {
        let mut edited = blob.clone();
        edited[at + offset..at + offset + 4].copy_from_slice(&value);
        parse(&reseal(&edited))
    };
    let u = |x: u32| x.to_le_bytes();
    let f = |x: f32| x.to_le_bytes();
    // Prelude 16 bytes, then 20 per proxy (bone, centre, radius), then 24 per bone.
    let bad = [
        ("no proxies", 0, u(0)),
        ("65 proxies", 0, u(65)),
        ("other bone count", 4, u(3)),
        ("cull 1", 8, f(1.0)),
        ("cull NaN", 8, f(f32::NAN)),
        ("negative cull", 8, f(-0.1)),
        ("reserved word", 12, u(1)),
        ("bone past the count", 16, u(2)),
        ("NaN centre", 20, f(f32::NAN)),
        ("zero radius", 32, f(0.0)),
        ("negative radius", 32, f(-1.0)),
        ("infinite radius", 32, f(f32::INFINITY)),
        ("negative bound", 56 + 12, f(-1.0)),
        ("mask past the proxies", 56 + 16, u(4)),
        ("high mask word", 56 + 20, u(1)),
    ];
    for (what, offset, value) in bad {
        assert_eq!(word(offset, value), Err(Error::BadProxies), "{what}");
    }
    // One proxy fewer announced, or a section cut short: the length no longer matches.
    let length = |found| {
        Err(Error::SectionLength {
            section: SectionKind::Proxies,
            expected: 16 + 40 + 48,
            found,
        })
    };
    assert_eq!(
        word(0, u(1)),
        Err(Error::SectionLength {
            section: SectionKind::Proxies,
            expected: 16 + 20 + 48,
            found: 104
        }),
        "a count short"
    );
    let index = header
        .sections
        .iter()
        .position(|s| s.kind == SectionKind::Proxies.tag())
        .unwrap();
    let short = with_header(&blob, |h| h.sections[index].len -= 24);
    assert_eq!(parse(&reseal(&short)), length(80));
    let world = with_header(&blob, |h| h.frame = aprt_core::Frame::World);
    assert!(parse(&world).is_err());
}

/// The texel atlas's corner-UV trailer, damaged with every checksum recomputed: a count of
/// 0, past the limit, one off or wrapping a 32-bit length back to the true one; a UV NaN,
/// infinite or outside [0, 1]; a section cut short. Both readers refuse each with the same
/// error, the streamed one through the model's least scratch. (The core's unit tests feed
/// the streaming check every split of an atlas.)
#[test]
fn damaged_corner_uvs_are_refused() {
    use aprt_core::{MAX_ATLAS_TRIANGLES, StreamedModel};
    use aprt_tests::Streamed;
    use aprt_tests::samples::{SAMPLE_ATLAS, SAMPLE_ATLAS_UVS};

    let (_, blob) = sample_blobs()
        .into_iter()
        .find(|(name, _)| *name == "atlas-identity-f32")
        .expect("the atlas sample");
    let header = read_header(&blob).unwrap();
    let index = header
        .sections
        .iter()
        .position(|s| s.kind == SectionKind::TexelAtlas.tag())
        .expect("the atlas section");
    let (at, len) = (
        header.sections[index].offset as usize,
        header.sections[index].len as usize,
    );
    let least = parse(&blob).unwrap().scratch_bytes();
    let both = |blob: &[u8]| {
        let resident = parse(blob);
        let mut scratch = vec![0u8; least];
        let streamed = StreamedModel::open(Streamed::new(blob), &mut scratch).map(|m| *m.info());
        assert_eq!(resident, streamed, "the readers disagree");
        resident.map(|_| ())
    };
    assert_eq!(both(&blob), Ok(()));
    // The rows end at 4 (1 + v): the count, then 24 bytes per triangle.
    let trailer = 4 * (1 + SAMPLE_ATLAS.1.len());
    let triangles = SAMPLE_ATLAS_UVS.len() as u32;
    assert_eq!(len, trailer + 4 + 24 * triangles as usize);
    let word = |offset: usize, value: [u8; 4]| {
        let mut edited = blob.clone();
        edited[at + offset..at + offset + 4].copy_from_slice(&value);
        both(&reseal(&edited))
    };
    let u = |x: u32| x.to_le_bytes();
    let f = |x: f32| x.to_le_bytes();
    let uv = |t: usize, k: usize| trailer + 4 + 4 * k + 24 * t;
    let bad = [
        ("no triangles", trailer, u(0)),
        ("count past the limit", trailer, u(MAX_ATLAS_TRIANGLES + 1)),
        ("count u32::MAX", trailer, u(u32::MAX)),
        (
            "24 T wraps a u32 to the length",
            trailer,
            u(triangles + (1 << 29)),
        ),
        ("u NaN", uv(0, 0), f(f32::NAN)),
        ("v infinite", uv(1, 3), f(f32::INFINITY)),
        ("v below 0", uv(2, 5), f(-1e-7)),
        ("u above 1", uv(2, 4), f(1.0000001)),
    ];
    for (what, offset, value) in bad {
        assert_eq!(word(offset, value), Err(Error::BadTexelAtlas), "{what}");
    }
    assert_eq!(word(uv(2, 5), f(-0.0)), Ok(()), "-0 is in [0, 1]");
    let length = |expected: usize, found: usize| {
        Err(Error::SectionLength {
            section: SectionKind::TexelAtlas,
            expected: expected as u64,
            found: found as u64,
        })
    };
    for t in [triangles - 1, triangles + 1] {
        let expected = trailer + 4 + 24 * t as usize;
        assert_eq!(word(trailer, u(t)), length(expected, len), "count {t}");
    }
    // Cut short: by a UV, to a count and less than a triangle, to a part of the count.
    for cut in [4, 24, len - trailer - 4, len - trailer - 1] {
        let short = with_header(&blob, |h| h.sections[index].len -= cut as u64);
        let expected = if cut < len - trailer - 4 {
            len
        } else {
            trailer
        };
        assert_eq!(
            both(&reseal(&short)),
            length(expected, len - cut),
            "cut {cut}"
        );
    }
}

/// Values near f32's limit in every per-vertex and per-pose array of a valid, sealed blob
/// (3e38 in a basis row, as a hostile exporter might write): every call returns finite
/// outputs or `Overflow` with its outputs zeroed, never `Ok` with Inf or NaN.
#[test]
fn huge_finite_blob_values_never_give_non_finite_output() {
    use aprt_core::{LitWeights, PoseWeights};
    type Edit = fn(&mut aprt_trainer::LinearModel);
    let edits: [(&str, Edit); 4] = [
        ("basis", |m| {
            if let aprt_trainer::VertexBasis::Stored { data, .. } = &mut m.basis {
                data[5] = 3e38;
            }
        }),
        ("weights", |m| m.weights[2] = 3e38),
        ("projection", |m| m.pose_projection[1] = 3e38),
        ("mean", |m| m.pose_mean[0] = -3e38),
    ];
    let mut overflowed = 0;
    for (what, edit) in edits {
        let mut model = random_model(3, 19, 3, 2, Some(4));
        edit(&mut model);
        let blob = encode_model(&model, Precision::F32).unwrap();
        let core = Model::parse(&blob).unwrap();
        let info = *core.info();
        let (mut pose, mut lit) = (PoseWeights::new(), LitWeights::new());
        let pose_result = core.set_pose(&[1.0, -2.0, 0.5], &mut pose);
        if pose_result == Err(Error::Overflow) {
            overflowed += 1;
            continue;
        }
        pose_result.unwrap();
        let lighting = [1e30f32; 9];
        let mut out = vec![7.0f32; info.vertices()];
        match core.light(&pose, &lighting, &[], &mut lit) {
            Err(Error::Overflow) => overflowed += 1,
            Err(e) => panic!("{what}: {e}"),
            Ok(()) => match core.shade(&lit, 0, &mut out) {
                Ok(()) => assert!(out.iter().all(|x| x.is_finite()), "{what}: {out:?}"),
                Err(e) => {
                    assert_eq!(e, Error::Overflow, "{what}");
                    assert!(out.iter().all(|&x| x == 0.0), "{what}: {out:?}");
                    overflowed += 1;
                }
            },
        }
        let mut transfer = vec![7.0f32; info.vertices() * 9];
        match core.transfer(&pose, 0, &mut transfer) {
            Ok(()) => assert!(transfer.iter().all(|x| x.is_finite()), "{what}"),
            Err(e) => {
                assert_eq!(e, Error::Overflow, "{what}");
                assert!(transfer.iter().all(|&x| x == 0.0), "{what}");
                overflowed += 1;
            }
        }
    }
    // Each edit overflows somewhere: the test reaches the checks it is about.
    assert!(overflowed >= 4, "{overflowed} overflows");
}
