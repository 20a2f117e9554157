//! Hostile `.shlm` bytes: truncations, flipped bytes, and headers declaring huge sizes with a
//! valid checksum all give errors, never panics or huge allocations.

use crate::lightmap::codec::synth::clip;
use crate::lightmap::codec::{CodecError, CodecKind, CodecSettings, ShlmFile, encode};

/// A small file of each kind, then the uniform quantiser (sign mode 3) under each kind.
fn small_files() -> Vec<Vec<u8>> {
    let seq = clip(8, 2, 4, 1e-3);
    let mut files = shlm_files(&seq, CodecSettings::default());
    let uniform = CodecSettings {
        planes: crate::lightmap::codec::PlaneSettings {
            mantissa_bits: 6,
            sign: crate::lightmap::codec::SignMode::Uniform,
            ..CodecSettings::default().planes
        },
        ..CodecSettings::default()
    };
    files.extend(shlm_files(&seq, uniform));
    files
}

/// `seq` under each kind, with `base`'s quantiser.
fn shlm_files(seq: &crate::lightmap::codec::MapSequence, base: CodecSettings) -> Vec<Vec<u8>> {
    [
        CodecKind::Frames,
        CodecKind::Keyframes { interval: 2 },
        CodecKind::Pca {
            target_error: 0.0,
            max_components: 3,
        },
    ]
    .into_iter()
    .map(|kind| encode(seq, &CodecSettings { kind, ..base }).expect("encodes"))
    .collect()
}

/// Parses and, if that succeeds, decodes every frame; must never panic.
fn exercise(bytes: &[u8]) -> Result<(), CodecError> {
    let file = ShlmFile::parse(bytes)?;
    let mut out = vec![0f32; file.resolution() * file.resolution() * file.order() * file.order()];
    for k in 0..file.frames() {
        file.decode_frame(k, &mut out)?;
    }
    Ok(())
}

/// Rewrites the trailing CRC so corruption reaches the validation behind it.
fn reseal(bytes: &mut [u8]) {
    let len = bytes.len();
    let crc = crc32fast::hash(&bytes[..len - 4]);
    bytes[len - 4..].copy_from_slice(&crc.to_le_bytes());
}

#[test]
fn every_truncation_is_an_error() {
    for file in small_files() {
        assert!(exercise(&file).is_ok());
        for len in 0..file.len() {
            assert!(exercise(&file[..len]).is_err(), "truncated at {len} parsed");
        }
    }
}

#[test]
fn flipped_bytes_are_errors_or_decode_safely() {
    for file in small_files() {
        for at in 0..file.len() {
            let mut bad = file.clone();
            bad[at] ^= 0x5a;
            assert!(exercise(&bad).is_err(), "flip at {at} passed the checksum");
            if at + 4 < bad.len() {
                reseal(&mut bad);
                let _ = exercise(&bad); // any result, but no panic
            }
        }
    }
}

#[test]
fn named_errors() {
    let file = small_files().remove(0);
    let mut magic = file.clone();
    magic[0] = b'X';
    assert_eq!(ShlmFile::parse(&magic).unwrap_err(), CodecError::BadMagic);
    let mut version = file.clone();
    version[8] = 9;
    assert_eq!(
        ShlmFile::parse(&version).unwrap_err(),
        CodecError::Version(9)
    );
    let mut crc = file.clone();
    let last = crc.len() - 1;
    crc[last] ^= 1;
    assert!(matches!(
        ShlmFile::parse(&crc),
        Err(CodecError::Checksum { .. })
    ));
    let parsed = ShlmFile::parse(&file).expect("parses");
    let mut out = vec![0f32; 8 * 8 * 4];
    assert!(matches!(
        parsed.decode_frame(4, &mut out),
        Err(CodecError::FrameOutOfRange { index: 4, .. })
    ));
    assert!(matches!(
        parsed.decode_frame(0, &mut out[1..]),
        Err(CodecError::SizeMismatch { .. })
    ));
}

/// Sign mode 3 needs version 2; a negative or non-finite step is refused.
#[test]
fn uniform_fields_are_checked() {
    for file in &small_files()[3..] {
        assert_eq!(file[29], 3);
        assert!(exercise(file).is_ok());
        let mut old = file.clone();
        old[8] = 1;
        reseal(&mut old);
        assert!(
            exercise(&old).is_err(),
            "sign mode 3 in a version-1 file parsed"
        );
    }
    // A one-frame clip of independent frames: its only chunk (the last bytes before the CRC)
    // starts with the steps of its plane set; rewrite the first step and splice it back.
    let seq = clip(8, 2, 4, 1e-3);
    let settings = CodecSettings {
        kind: CodecKind::Frames,
        planes: crate::lightmap::codec::PlaneSettings {
            mantissa_bits: 6,
            sign: crate::lightmap::codec::SignMode::Uniform,
            ..CodecSettings::default().planes
        },
        ..CodecSettings::default()
    };
    for bad_step in [-1.0f32, f32::NAN, f32::INFINITY] {
        let one = crate::lightmap::codec::MapSequence {
            atlas: None,
            frames: seq.frames[..1].to_vec(),
            ..seq.clone()
        };
        let bytes = encode(&one, &settings).expect("encodes");
        let word = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap());
        let table_at = 52 + (word(40) + word(44) + word(48)) as usize;
        let (chunk_at, chunk_end) = (table_at + 16, bytes.len() - 4);
        let mut planes =
            zstd::bulk::decompress(&bytes[chunk_at..chunk_end], 1 << 20).expect("zstd");
        planes[..4].copy_from_slice(&bad_step.to_le_bytes());
        let chunk = zstd::bulk::compress(&planes, 3).expect("zstd");
        let mut bad = bytes[..chunk_at].to_vec();
        bad[table_at + 8..chunk_at].copy_from_slice(&(chunk.len() as u64).to_le_bytes());
        bad.extend_from_slice(&chunk);
        bad.extend_from_slice(&[0; 4]);
        reseal(&mut bad);
        assert!(
            matches!(exercise(&bad), Err(CodecError::Invalid { .. })),
            "step {bad_step} decoded"
        );
    }
}

/// Headers declaring the largest sizes (and past them), resealed, fail fast and small.
#[test]
fn huge_declared_sizes_are_errors() {
    let file = small_files().remove(2);
    let patches: [(usize, u32); 9] = [
        (12, 8192),      // resolution at the limit: the mask no longer matches
        (12, 8193),      // past the limit
        (16, 7),         // order past the limit
        (20, 1_000_000), // a million frames: the offset table is not there
        (20, 1_000_001),
        (24, u32::MAX),    // more filled texels than texels
        (36, u32::MAX),    // components
        (40, u32::MAX),    // mask section length
        (48, 0x7fff_ffff), // shared section length
    ];
    for (at, value) in patches {
        let mut bad = file.clone();
        bad[at..at + 4].copy_from_slice(&value.to_le_bytes());
        reseal(&mut bad);
        assert!(
            exercise(&bad).is_err(),
            "header field at {at} = {value} parsed"
        );
    }
}
