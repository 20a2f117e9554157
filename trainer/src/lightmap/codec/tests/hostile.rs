//! Hostile `.shlm` bytes: truncations, flipped bytes, and headers declaring huge sizes with a
//! valid checksum all give errors, never panics or huge allocations.

use super::synth::clip;
use crate::lightmap::codec::{CodecError, CodecKind, CodecSettings, ShlmFile, encode};

/// A small file of each kind.
fn small_files() -> Vec<Vec<u8>> {
    let seq = clip(8, 2, 4, 1e-3);
    [
        CodecKind::Frames,
        CodecKind::Keyframes { interval: 2 },
        CodecKind::Pca {
            target_error: 0.0,
            max_components: 3,
        },
    ]
    .into_iter()
    .map(|kind| {
        encode(
            &seq,
            &CodecSettings {
                kind,
                ..CodecSettings::default()
            },
        )
        .expect("encodes")
    })
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
