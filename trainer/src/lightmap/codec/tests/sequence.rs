//! Round trips of whole clips: constant fields, random access, the target ratio.

use crate::lightmap::codec::synth::clip;
use crate::lightmap::codec::{
    CodecKind, CodecSettings, MapSequence, ShlmFile, atlas_record, encode,
};
use crate::rig::uv::UvLayout;

/// Every temporal scheme, with the default quantiser.
fn kinds() -> Vec<CodecSettings> {
    [
        CodecKind::Frames,
        CodecKind::Keyframes { interval: 3 },
        CodecKind::Pca {
            target_error: 0.01,
            max_components: 8,
        },
    ]
    .into_iter()
    .map(|kind| CodecSettings {
        kind,
        ..CodecSettings::default()
    })
    .collect()
}

fn decode_all(file: &ShlmFile<'_>) -> Vec<Vec<f32>> {
    let len = file.resolution() * file.resolution() * file.order() * file.order();
    (0..file.frames())
        .map(|k| {
            let mut out = vec![f32::NAN; len];
            file.decode_frame(k, &mut out).expect("decodes");
            out
        })
        .collect()
}

/// A constant transfer field comes back within the quantiser's bound (`M / (2^m − ½)` of the
/// texel's largest coefficient) under every scheme, and the mask and positions exactly.
#[test]
fn constant_field_round_trips_within_the_bound() {
    let mut seq = clip(16, 3, 7, 0.0);
    let mut lobe = [0f32; 9];
    aprt_core::clamped_cosine(3, [0.2, 0.9, 0.1], &mut lobe).expect("unit normal");
    for frame in &mut seq.frames {
        for (t, texel) in frame.chunks_exact_mut(9).enumerate() {
            let on = if seq.filled[t] { 0.8 } else { 0.0 };
            texel.iter_mut().zip(&lobe).for_each(|(x, l)| *x = on * l);
        }
    }
    let max = lobe.iter().map(|x| 0.8 * x.abs()).fold(0.0, f32::max);
    for settings in kinds() {
        let bytes = encode(&seq, &settings).expect("encodes");
        let file = ShlmFile::parse(&bytes).expect("parses");
        assert_eq!(file.filled(), seq.filled);
        assert_eq!(file.positions(), seq.positions);
        let bound = max / (2f32.powi(i32::from(settings.planes.mantissa_bits)) - 0.5);
        for (decoded, original) in decode_all(&file).iter().zip(&seq.frames) {
            for (d, o) in decoded.iter().zip(original) {
                assert!(
                    (d - o).abs() <= bound * 1.0001,
                    "{:?}: {o} -> {d}",
                    settings.kind
                );
            }
        }
    }
}

/// Decoding frames in any order gives the same bits as decoding them in order.
#[test]
fn random_access_equals_in_order() {
    let seq = clip(24, 2, 9, 1e-3);
    for settings in kinds() {
        let bytes = encode(&seq, &settings).expect("encodes");
        let file = ShlmFile::parse(&bytes).expect("parses");
        let in_order = decode_all(&file);
        let mut out = vec![0f32; in_order[0].len()];
        for k in (0..file.frames()).rev().step_by(2).chain([4, 0, 8, 5]) {
            file.decode_frame(k, &mut out).expect("decodes");
            assert_eq!(out, in_order[k], "{:?} frame {k}", settings.kind);
        }
    }
}

/// Sequences the file cannot hold are refused, not written.
#[test]
fn bad_sequences_are_refused() {
    let good = clip(8, 2, 3, 0.0);
    let mut nan = good.clone();
    nan.frames[1][4] = f32::NAN;
    let mut short = good.clone();
    short.frames[2].pop();
    let mut positions = good.clone();
    positions.positions.pop();
    let empty = MapSequence {
        atlas: None,
        frames: Vec::new(),
        ..good.clone()
    };
    for seq in [nan, short, positions, empty] {
        assert!(encode(&seq, &CodecSettings::default()).is_err());
    }
}

/// The product target: the default codec reaches ≥ 30:1 against raw f32 maps at ≤ 3 %
/// relative error on a 128², order-4, 40-frame clip. (`cargo run -p aprt-trainer --release
/// --example shlm_codecs` prints every variant beside it.)
#[test]
fn default_meets_the_target() {
    let seq = clip(128, 4, 40, 1e-3);
    let bytes = encode(&seq, &CodecSettings::default()).expect("encodes");
    let file = ShlmFile::parse(&bytes).expect("parses");
    let ratio = file.raw_bytes() as f64 / bytes.len() as f64;
    let error = relative_error(&seq, &decode_all(&file));
    assert!(ratio >= 30.0 && error <= 0.03, "{ratio}:1 at {error}");
}

/// A 256², order-4 frame decodes in a few milliseconds with the default codec.
#[test]
fn default_decodes_256_frames_quickly() {
    let seq = clip(256, 4, 24, 1e-3);
    let bytes = encode(&seq, &CodecSettings::default()).expect("encodes");
    let file = ShlmFile::parse(&bytes).expect("parses");
    let mut ms = f64::MAX;
    let mut out = vec![0f32; 256 * 256 * 16];
    for k in 0..seq.frames.len() {
        let start = std::time::Instant::now();
        file.decode_frame(k, &mut out).expect("decodes");
        ms = ms.min(start.elapsed().as_secs_f64() * 1e3);
    }
    let decoded = decode_all(&file);
    let ratio = file.raw_bytes() as f64 / bytes.len() as f64;
    let error = relative_error(&seq, &decoded);
    println!(
        "256² order 4, 24 frames: {} bytes, {ratio:.1}:1, {:.3}%, {ms:.2} ms/frame (fastest)",
        bytes.len(),
        100.0 * error
    );
    assert!(error <= 0.03 && ratio >= 30.0);
}

fn relative_error(seq: &MapSequence, decoded: &[Vec<f32>]) -> f64 {
    let (mut e, mut n) = (0f64, 0f64);
    for (d, o) in decoded.iter().zip(&seq.frames) {
        for (x, y) in d.iter().zip(o) {
            e += f64::from(x - y).powi(2);
            n += f64::from(*y).powi(2);
        }
    }
    (e / n).sqrt()
}

/// A sequence with an atlas fingerprint is written as version 4 and decodes as the version-2
/// file of the same maps does; the fingerprint is read back from the header alone. The same
/// file as version 3 (no light-map UV fields) still reads.
#[test]
fn the_atlas_fingerprint_is_a_header_field_and_version_3_still_reads() {
    let mut seq = clip(16, 2, 4, 0.01);
    let old = encode(&seq, &CodecSettings::default()).unwrap();
    seq.atlas = Some(0x1234_5678);
    let new = encode(&seq, &CodecSettings::default()).unwrap();
    assert_eq!((old[8], new[8]), (2, 4));
    assert_eq!(new.len(), old.len() + 12);
    assert_eq!(atlas_record(&old), Ok((None, 0)));
    assert_eq!(atlas_record(&new), Ok((Some(0x1234_5678), 0)));
    let v3 = as_version_3(&new);
    assert_eq!(atlas_record(&v3), Ok((Some(0x1234_5678), 0)));
    let files = [&old, &new, &v3].map(|b| ShlmFile::parse(b).unwrap());
    assert_eq!(decode_all(&files[0]), decode_all(&files[1]));
    assert_eq!(decode_all(&files[0]), decode_all(&files[2]));
    assert!(files.iter().all(|f| f.layout().is_none()));
}

/// A version-4 file without light-map UVs rewritten as version 3: the UV triangle count and
/// section size (bytes 56..64) dropped, the checksum redone.
fn as_version_3(v4: &[u8]) -> Vec<u8> {
    assert_eq!(&v4[56..64], &[0; 8]);
    let mut out = [&v4[..56], &v4[64..v4.len() - 4]].concat();
    out[8..12].copy_from_slice(&3u32.to_le_bytes());
    let crc = crc32fast::hash(&out);
    out.extend_from_slice(&crc.to_le_bytes());
    out
}

/// Generated light-map UVs travel in the file and come back bit for bit; a layout whose
/// fingerprint is not the header's is refused when writing, and UVs outside `[0, 1]` or of
/// another fingerprint when reading.
#[test]
fn light_map_uvs_round_trip_and_bad_ones_are_refused() {
    let mut seq = clip(16, 2, 4, 0.01);
    let layout = UvLayout {
        corners: vec![
            [[0.1, 0.2], [0.9, 0.2], [0.5, 0.8]],
            [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]],
        ],
    };
    seq.layout = Some(layout.clone());
    seq.atlas = Some(0);
    assert!(encode(&seq, &CodecSettings::default()).is_err());
    seq.atlas = Some(layout.fingerprint());
    let bytes = encode(&seq, &CodecSettings::default()).unwrap();
    assert_eq!(atlas_record(&bytes), Ok((seq.atlas, 2)));
    let file = ShlmFile::parse(&bytes).unwrap();
    assert_eq!(file.layout(), Some(&layout));
    let plain = MapSequence {
        layout: None,
        ..seq.clone()
    };
    let plain = encode(&plain, &CodecSettings::default()).unwrap();
    assert_eq!(
        decode_all(&file),
        decode_all(&ShlmFile::parse(&plain).unwrap())
    );
    for (corners, atlas) in [
        (vec![[[0.1, 0.2], [1.5, 0.2], [0.5, 0.8]]], None),
        (vec![[[0.1, 0.2], [0.9, f32::NAN], [0.5, 0.8]]], None),
        (layout.corners.clone(), Some(7)),
    ] {
        let bad = UvLayout { corners };
        let mut seq = seq.clone();
        seq.atlas = Some(bad.fingerprint());
        seq.layout = Some(bad);
        let mut bytes = encode(&seq, &CodecSettings::default()).unwrap();
        if let Some(other) = atlas {
            let body = bytes.len() - 4;
            bytes[52..56].copy_from_slice(&u32::to_le_bytes(other));
            let crc = crc32fast::hash(&bytes[..body]);
            bytes[body..].copy_from_slice(&crc.to_le_bytes());
        }
        let err = ShlmFile::parse(&bytes).unwrap_err().to_string();
        assert!(err.contains("light-map UVs"), "{err}");
    }
}
