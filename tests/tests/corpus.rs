//! The fuzz seed corpus in `fuzz/corpus/`: its generator (ignored; run it after a format
//! change, with `cargo test -p aprt-tests --release --test corpus -- --ignored`) and a stable
//! test that every seed, crash reproducers included, passes its fuzz harness.

use std::fs;
use std::path::{Path, PathBuf};

use aprt_tests::edit::reseal;
use aprt_tests::harness::{Probe, exercise};
use aprt_tests::samples::sample_blobs;
use aprt_tests::spec::{ModelSpec, round_trip};
use aprt_tests::{loaders, noise};

fn corpus(target: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../fuzz/corpus")
        .join(target)
}

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

#[test]
#[ignore = "writes fuzz/corpus; run by hand after a format change"]
fn write_fuzz_corpus() {
    let reader = corpus("reader");
    fs::create_dir_all(&reader).unwrap();
    for (name, blob) in sample_blobs() {
        let with = |probe: &Probe, bytes: &[u8]| [&probe.to_bytes()[..], bytes].concat();
        fs::write(
            reader.join(format!("seed-{name}")),
            with(&Probe::GENTLE, &blob),
        )
        .unwrap();
        fs::write(
            reader.join(format!("seed-{name}-hostile")),
            with(&HOSTILE, &blob),
        )
        .unwrap();
        let half = &blob[..blob.len() / 2];
        fs::write(
            reader.join(format!("seed-{name}-truncated")),
            with(&Probe::GENTLE, half),
        )
        .unwrap();
    }
    let round_trip = corpus("round_trip");
    fs::create_dir_all(&round_trip).unwrap();
    for (seed, len) in [(1u64, 16usize), (2, 64), (3, 256), (4, 1024)] {
        let bytes: Vec<u8> = noise(seed, len)
            .iter()
            .map(|x| ((x + 1.0) * 128.0) as u8)
            .collect();
        let data = [&Probe::GENTLE.to_bytes()[..], &bytes].concat();
        fs::write(round_trip.join(format!("seed-noise-{len}")), data).unwrap();
    }
}

/// The files of `fixtures/malformed/<dir>` ending in one of `extensions`, sorted: the seeds of
/// the `gltf` and `bvh` targets, which the fuzzer reads from there (see README, Fuzzing).
fn fixtures(dir: &str, extensions: &[&str]) -> Vec<Vec<u8>> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../fixtures/malformed")
        .join(dir);
    let mut files: Vec<PathBuf> = fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| {
            p.extension()
                .is_some_and(|e| extensions.iter().any(|x| e == *x))
        })
        .collect();
    files.sort();
    files.iter().map(|p| fs::read(p).unwrap()).collect()
}

fn seeds(target: &str) -> Vec<Vec<u8>> {
    let mut files: Vec<_> = fs::read_dir(corpus(target))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| {
            p.file_name()
                .unwrap()
                .to_str()
                .unwrap()
                .starts_with("seed-")
        })
        .collect();
    files.sort();
    files.iter().map(|p| fs::read(p).unwrap()).collect()
}

#[test]
fn reader_seeds_pass_the_harness() {
    let seeds = seeds("reader");
    assert!(seeds.len() >= 12);
    let mut valid = 0;
    for data in seeds {
        let (probe, blob) = Probe::split(&data);
        valid += usize::from(exercise(blob, &probe).is_ok());
        let _ = exercise(&reseal(blob), &probe);
    }
    assert!(valid >= 8, "only {valid} seeds hold valid blobs");
}

#[test]
fn round_trip_seeds_pass_the_harness() {
    for data in seeds("round_trip") {
        let (probe, rest) = Probe::split(&data);
        round_trip(&ModelSpec::from_bytes(rest), &probe);
    }
}

#[test]
fn gltf_seeds_pass_the_harness() {
    let seeds = fixtures("gltf", &["gltf", "glb"]);
    assert!(seeds.len() >= 30);
    let valid = seeds.iter().filter(|s| loaders::gltf(s).is_ok()).count();
    // ok.gltf, ok.glb, and no-animations.gltf (a rig without clips, which only the CLI
    // refuses, as it has nothing to bake); every other seed is refused.
    assert_eq!(valid, 3);
}

#[test]
fn bvh_seeds_pass_the_harness() {
    let seeds = fixtures("bvh", &["bvh"]);
    assert!(seeds.len() >= 6);
    assert!(seeds.iter().any(|s| loaders::bvh(s).is_ok()));
    for seed in &seeds {
        let _ = loaders::bvh(seed);
    }
}
