//! The fuzz seed corpus in `fuzz/corpus/` (written by `cargo run -p aprt-tests --release
//! --example write_corpus`): every seed, crash reproducers included, passes its fuzz harness.

use std::fs;
use std::path::{Path, PathBuf};

use aprt_tests::edit::reseal;
use aprt_tests::harness::{Probe, exercise};
use aprt_tests::spec::{ModelSpec, round_trip};
use aprt_tests::{fuzz_corpus, loaders, readers};

/// The files of `fixtures/<dir>` ending in one of `extensions`, sorted: the seeds of the
/// `gltf`, `bvh`, `scene` and `lights` targets, which the fuzzer reads from there (see README,
/// Fuzzing).
fn fixtures(dir: &str, extensions: &[&str]) -> Vec<Vec<u8>> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../fixtures")
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
    let mut files: Vec<_> = fs::read_dir(fuzz_corpus(target))
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
    let seeds = fixtures("malformed/gltf", &["gltf", "glb"]);
    assert!(seeds.len() >= 30);
    let valid = seeds.iter().filter(|s| loaders::gltf(s).is_ok()).count();
    // ok.gltf, ok.glb, and no-animations.gltf (a rig without clips, which only the CLI
    // refuses, as it has nothing to bake); every other seed is refused.
    assert_eq!(valid, 3);
}

#[test]
fn bvh_seeds_pass_the_harness() {
    let seeds = fixtures("malformed/bvh", &["bvh"]);
    assert!(seeds.len() >= 6);
    assert!(seeds.iter().any(|s| loaders::bvh(s).is_ok()));
    for seed in &seeds {
        let _ = loaders::bvh(seed);
    }
}

/// How many of `seeds` `harness` accepts; every one passes its checks.
fn accepted(seeds: &[Vec<u8>], harness: fn(&[u8]) -> Result<(), String>) -> usize {
    seeds.iter().filter(|s| harness(s).is_ok()).count()
}

#[test]
fn scene_seeds_pass_the_harness() {
    let mut seeds = seeds("scene");
    seeds.extend(fixtures("scenes", &["toml"]));
    assert!(seeds.len() >= 11);
    // All but the overlapping clips and the confined scene whose map lies outside.
    assert_eq!(accepted(&seeds, readers::scene), seeds.len() - 2);
}

#[test]
fn lights_seeds_pass_the_harness() {
    let valid = fixtures("lights", &["toml"]);
    assert!(valid.len() >= 4);
    assert_eq!(accepted(&valid, readers::lights), valid.len());
    let malformed = fixtures("malformed/lights", &["toml"]);
    assert!(malformed.len() >= 6);
    assert_eq!(accepted(&malformed, readers::lights), 0);
}

#[test]
fn shlm_seeds_pass_the_harness() {
    let seeds = seeds("shlm");
    assert!(seeds.len() >= 7);
    assert_eq!(accepted(&seeds, readers::shlm), seeds.len());
}

#[test]
fn env_map_seeds_pass_the_harness() {
    let seeds = seeds("env_map");
    assert!(seeds.len() >= 5);
    // All but the OpenEXR header whose size overflowed the budget's arithmetic.
    assert_eq!(accepted(&seeds, readers::env_map), seeds.len() - 1);
}

#[test]
fn npy_seeds_pass_the_harness() {
    let seeds = seeds("npy");
    assert!(seeds.len() >= 13);
    // The five written by `encode_f32`; the hand-made headers are refused.
    assert_eq!(accepted(&seeds, readers::npy), 5);
}
