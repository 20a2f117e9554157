//! Writes the fuzz seed corpus of `fuzz/corpus/` again: run after a format change
//! (`cargo run -p aprt-tests --release --example write_corpus`), then `tests/tests/corpus.rs`
//! checks that every seed passes its harness.

use std::fs;

use aprt_tests::harness::Probe;
use aprt_tests::samples::sample_blobs;
use aprt_tests::{fuzz_corpus, noise};
use aprt_trainer::io::npy::encode_f32;
use aprt_trainer::lightmap::codec::{
    CodecKind, CodecSettings, Grouping, MapSequence, PlaneSettings, SignMode, encode,
};
use image::codecs::hdr::HdrEncoder;
use image::codecs::openexr::OpenExrEncoder;
use image::{Rgb32FImage, Rgba32FImage};

/// Probe inputs the evaluator must refuse: NaN angles, a stretching rotation, a vertex range
/// whose end overflows, one byte less scratch than needed.
const HOSTILE: Probe = Probe {
    angles: [0.5, f32::NAN, 1.0, -2.0],
    lighting: [1.0, f32::INFINITY, 0.0, -1.0],
    skew: true,
    far: true,
    scratch_delta: -1,
    open_scratch: 3,
    ..Probe::GENTLE
};

/// Writes `bytes` as the seed `name` of `target`.
fn write(target: &str, name: &str, bytes: &[u8]) {
    let dir = fuzz_corpus(target);
    fs::create_dir_all(&dir).unwrap();
    fs::write(dir.join(format!("seed-{name}")), bytes).unwrap();
}

/// The seeds of the blob targets (`reader`, `round_trip`): a probe, then the bytes.
fn write_blob_seeds() {
    let with = |probe: &Probe, bytes: &[u8]| [&probe.to_bytes()[..], bytes].concat();
    for (name, blob) in sample_blobs() {
        write("reader", name, &with(&Probe::GENTLE, &blob));
        write("reader", &format!("{name}-hostile"), &with(&HOSTILE, &blob));
        let half = &blob[..blob.len() / 2];
        write(
            "reader",
            &format!("{name}-truncated"),
            &with(&Probe::GENTLE, half),
        );
    }
    for (seed, len) in [(1u64, 16usize), (2, 64), (3, 256), (4, 1024)] {
        let bytes: Vec<u8> = noise(seed, len)
            .iter()
            .map(|x| ((x + 1.0) * 128.0) as u8)
            .collect();
        write(
            "round_trip",
            &format!("noise-{len}"),
            &with(&Probe::GENTLE, &bytes),
        );
    }
}

/// Scenes the fixtures do not cover: every source kind and key, SH and map environments,
/// every light kind, overlapping clips, `confine`.
const SCENES: [(&str, &str); 6] = [
    (
        "gltf",
        "confine = false\n[source]\ngltf = \"Fox.gltf\"\nfps = 24.0\nup = \"y\"\ntrain = [\"Survey\"]\nvalidate = [\"Run\"]\ntest = [\"Walk\"]\n\
         [effects]\nshadows = true\nbounces = 1\nalbedo = 0.5\nrays = 64\norder = 3\nerror_target = 0.5\nrig = \"lattice:2x2x2\"\nprecision = \"f16\"\nframe = \"world\"\n\
         [budget]\nus_per_frame = 50.5\nbytes = 1_000_000\n\
         [environment]\nhdr = \"studio.hdr\"\n\
         [[light]]\nkind = \"sphere\"\nposition = [0.0, 1.2, 0.8]\nradius = 0.1\nradiance = [4.0, 3.5, 3.0]\n\
         [[light]]\nkind = \"point\"\nposition = [1.0, 2.0, 0.0]\nintensity = [2.0, 2.0, 2.0]\n",
    ),
    (
        "obj-seq",
        "[source]\nobj_seq = \"poses\"\nangles = \"poses.csv\"\nup = \"z\"\n\
         [effects]\nshadows = false\norder = \"auto\"\nrig = \"none\"\nprecision = \"i8\"\n\
         [environment]\nexr = \"sky.exr\"\n",
    ),
    (
        "bvh-ranges",
        "[source]\nbvh = \"walk.bvh\"\ntrain = [\"0..240\", \"other.bvh\"]\nvalidate = [\"240..300\"]\ntest = [\"300..344\"]\n\
         [effects]\nrig = \"gradient\"\norder = 6\n\
         [environment]\nsh = [[1, 1, 1], [0, 0.5, 0], [0, 0, 0], [0, 0, 0], [0, 0, 0], [0, 0, 0], [0, 0, 0], [0, 0, 0], [0.1, 0, 0]]\n",
    ),
    (
        "bvh-overlap",
        "[source]\nbvh = \"walk.bvh\"\ntrain = [\"0..240\"]\ntest = [\"200..344\"]\n\
         [environment]\nsh = [[0.5, 0.5, 0.5]]\n",
    ),
    (
        "confined",
        "confine = true\n[source]\nbuiltin = \"creature\"\ntrain = [\"training\"]\n\
         [environment]\nhdr = \"../outside.hdr\"\n",
    ),
    (
        "lights-only",
        "[source]\nbuiltin = \"human\"\ntrain = [\"training\"]\ntest = [\"walk\"]\n\
         [[light]]\nkind = \"directional\"\ndirection = [0, 1, 0]\nirradiance = [1, 1, 1]\n",
    ),
];

/// A `.npy` file with `dict` as its header dictionary (padded as NumPy pads it) and `data`.
fn npy_with(dict: &str, data: &[u8]) -> Vec<u8> {
    let unpadded = 10 + dict.len() + 1;
    let header = format!(
        "{dict}{}\n",
        " ".repeat(unpadded.next_multiple_of(64) - unpadded)
    );
    let mut out = b"\x93NUMPY\x01\x00".to_vec();
    out.extend_from_slice(&(header.len() as u16).to_le_bytes());
    out.extend_from_slice(header.as_bytes());
    out.extend_from_slice(data);
    out
}

/// A small light-map clip: `resolution²` texels, two in three filled, SH order 2, `frames`
/// frames of smooth values of both signs that move from frame to frame.
fn light_maps(resolution: usize, frames: usize, atlas: Option<u32>) -> MapSequence {
    let n2 = 4;
    let filled: Vec<bool> = (0..resolution * resolution).map(|t| t % 3 != 2).collect();
    let positions = (0..filled.len())
        .filter(|&t| filled[t])
        .map(|t| {
            [
                (t % resolution) as f32 * 0.1,
                (t / resolution) as f32 * 0.1,
                0.5,
            ]
        })
        .collect();
    let frames = (0..frames)
        .map(|f| {
            (0..filled.len() * n2)
                .map(|i| match filled[i / n2] {
                    false => 0.0,
                    true => {
                        let phase = i as f32 * 0.37 + f as f32 * 0.2;
                        phase.sin() * 0.4 + if i % n2 == 0 { 0.6 } else { 0.0 }
                    }
                })
                .collect()
        })
        .collect();
    MapSequence {
        resolution,
        atlas,
        order: 2,
        filled,
        positions,
        layout: None,
        frames,
    }
}

/// An `Rgb32FImage` of smooth non-negative radiance with one bright texel.
fn sky(width: u32, height: u32) -> Rgb32FImage {
    Rgb32FImage::from_fn(width, height, |x, y| {
        let v = 0.2 + (x as f32 * 0.7).sin().abs() * 0.5 + y as f32 / height as f32;
        image::Rgb(if (x, y) == (1, 1) {
            [8.0, 6.0, 4.0]
        } else {
            [v, v * 0.9, v * 0.8]
        })
    })
}

/// The `scene` seeds: [`SCENES`].
fn write_scene_seeds() {
    for (name, text) in SCENES {
        write("scene", &format!("{name}.toml"), text.as_bytes());
    }
}

/// The `shlm` seeds: small clips of each codec kind under each quantiser, and a version-2 file
/// (no atlas).
fn write_shlm_seeds() {
    let uniform = CodecSettings::default().planes;
    let planes = |mantissa_bits, sign, grouping, spatial_delta| PlaneSettings {
        mantissa_bits,
        sign,
        grouping,
        spatial_delta,
    };
    let pca = |max_components| CodecKind::Pca {
        target_error: 0.0,
        max_components,
    };
    let shlm = [
        ("pca-uniform", pca(3), uniform, Some(0xa7a5)),
        ("frames-uniform", CodecKind::Frames, uniform, Some(1)),
        (
            "keyframes-uniform",
            CodecKind::Keyframes { interval: 2 },
            uniform,
            Some(2),
        ),
        (
            "frames-offset",
            CodecKind::Frames,
            planes(8, SignMode::OffsetScale, Grouping::Texel, false),
            Some(3),
        ),
        (
            "keyframes-sign-plane",
            CodecKind::Keyframes { interval: 3 },
            planes(6, SignMode::SignPlane, Grouping::Triples, true),
            Some(4),
        ),
        (
            "pca-band0-ratio",
            pca(2),
            planes(7, SignMode::Band0Ratio, Grouping::Texel, true),
            Some(5),
        ),
        (
            "v2-frames-sign-plane",
            CodecKind::Frames,
            planes(5, SignMode::SignPlane, Grouping::Texel, false),
            None,
        ),
    ];
    for (name, kind, planes, atlas) in shlm {
        let settings = CodecSettings {
            kind,
            planes,
            zstd_level: 3,
        };
        let bytes = encode(&light_maps(6, 4, atlas), &settings).unwrap();
        write("shlm", &format!("{name}.shlm"), &bytes);
    }
}

/// The `env_map` seeds: a run-length and a flat Radiance file (with `EXPOSURE=`), an RGB and
/// an RGBA OpenEXR.
fn write_env_map_seeds() {
    let mut rle = Vec::new();
    sky(16, 8)
        .write_with_encoder(HdrEncoder::new(&mut rle))
        .unwrap();
    write("env_map", "rle.hdr", &rle);
    let mut flat = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\nEXPOSURE=2\n\n-Y 2 +X 4\n".to_vec();
    for i in 0..8u8 {
        flat.extend_from_slice(&[100 + i * 10, 90, 80 + i, 129]);
    }
    write("env_map", "flat-exposure.hdr", &flat);
    let mut exr = Vec::new();
    sky(8, 4)
        .write_with_encoder(OpenExrEncoder::new(std::io::Cursor::new(&mut exr)))
        .unwrap();
    write("env_map", "rgb.exr", &exr);
    let rgba = Rgba32FImage::from_fn(4, 2, |x, y| image::Rgba([x as f32, y as f32, 0.5, 1.0]));
    let mut exr = Vec::new();
    rgba.write_with_encoder(OpenExrEncoder::new(std::io::Cursor::new(&mut exr)))
        .unwrap();
    write("env_map", "rgba.exr", &exr);
}

/// The `npy` seeds: the writer's arrays of 0 to 3 dimensions, and headers it refuses.
fn write_npy_seeds() {
    let values = [
        0.0,
        -1.5,
        2.0,
        f32::MIN_POSITIVE,
        1e-45,
        f32::MAX,
        f32::NAN,
        f32::INFINITY,
    ];
    write("npy", "vector", &encode_f32(&[3], &values[..3]));
    write("npy", "matrix", &encode_f32(&[2, 3], &values[2..]));
    write("npy", "cube", &encode_f32(&[2, 2, 2], &values));
    write("npy", "scalar", &encode_f32(&[], &values[1..2]));
    write("npy", "empty", &encode_f32(&[4, 0], &[]));
    let data: Vec<u8> = values.iter().flat_map(|x| x.to_le_bytes()).collect();
    let dicts = [
        (
            "fortran",
            "{'descr': '<f4', 'fortran_order': True, 'shape': (2, 4), }",
        ),
        (
            "big-endian",
            "{'descr': '>f4', 'fortran_order': False, 'shape': (8,), }",
        ),
        (
            "float64",
            "{'descr': '<f8', 'fortran_order': False, 'shape': (4,), }",
        ),
        (
            "twice",
            "{'descr': '<f4', 'descr': '<f4', 'fortran_order': False, 'shape': (8,), }",
        ),
        (
            "unknown-key",
            "{'descr': '<f4', 'fortran_order': False, 'shape': (8,), 'x': 1}",
        ),
        ("no-shape", "{\"descr\": \"<f4\", \"fortran_order\": False}"),
        (
            "short",
            "{'descr': '<f4', 'fortran_order': False, 'shape': (9,), }",
        ),
        (
            "overflow",
            "{'descr': '<f4', 'fortran_order': False, 'shape': (4294967296, 4294967296), }",
        ),
    ];
    for (name, dict) in dicts {
        write("npy", name, &npy_with(dict, &data));
    }
}

fn main() {
    write_blob_seeds();
    write_scene_seeds();
    write_shlm_seeds();
    write_env_map_seeds();
    write_npy_seeds();
    println!("wrote the seeds of {}", fuzz_corpus("").display());
}
