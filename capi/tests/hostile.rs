//! Hostile blobs through the C ABI get a status, never a crash: the fuzz corpus of the reader
//! (its probe prefix stripped as `Probe::split` does), every malformed blob fixture, every
//! truncation and single-bit flip of the golden blobs, resident and streamed; where a blob is
//! accepted, a whole frame runs and every call returns a status, none of them a panic.

use crate::common;

use std::path::Path;
use std::ptr::null_mut;

use aprt_capi::aprt_status;
use aprt_capi::model::*;
use common::*;

/// The probe prefix of a reader fuzz input (`aprt_tests::harness::PROBE_BYTES`).
const PROBE_BYTES: usize = 48;

/// Initialises `blob` resident and streamed; runs a frame on what opens. Returns whether the
/// resident init accepted it.
fn exercise(blob: &[u8]) -> bool {
    let mut model_mem = storage(aprt_model_size());
    let mut model = null_mut();
    let init = aprt_model_init(
        blob.as_ptr(),
        blob.len(),
        ptr(&mut model_mem),
        aprt_model_size(),
        &mut model,
    );
    assert_ne!(init, aprt_status::Panic);
    if init == aprt_status::Ok {
        let statuses = whole_frame(model);
        assert!(!statuses.contains(&aprt_status::Panic), "{statuses:?}");
    } else {
        assert!(model.is_null(), "a refused blob leaves *out NULL");
    }
    let mut memory = Memory::new(blob.to_vec());
    let (mut scratch, mut streamed_mem) = (Vec::new(), storage(aprt_model_size()));
    let (status, streamed) = stream(&mut memory, &mut scratch, &mut streamed_mem);
    // Both readers validate the same way: they accept and refuse the same blobs.
    assert_eq!(
        status == aprt_status::Ok,
        init == aprt_status::Ok,
        "{status:?} vs {init:?}"
    );
    if status == aprt_status::Ok {
        let statuses = whole_frame(streamed);
        assert!(!statuses.contains(&aprt_status::Panic), "{statuses:?}");
        // A source that fails from now on is a status too.
        memory.fail = true;
        let statuses = whole_frame(streamed);
        assert!(!statuses.contains(&aprt_status::Panic), "{statuses:?}");
    }
    init == aprt_status::Ok
}

#[test]
fn the_reader_fuzz_corpus_gets_statuses() {
    let dir = repo().join("fuzz/corpus/reader");
    let mut files: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    files.sort();
    assert!(files.len() >= 30);
    let mut accepted = 0;
    for path in &files {
        let data = std::fs::read(path).unwrap();
        let blob = &data[data.len().min(PROBE_BYTES)..];
        accepted += usize::from(exercise(blob));
    }
    // The plain seeds are valid models; the hostile and truncated ones are not all refused
    // (a hostile probe may sit before a valid blob), but at least the plain ten open.
    assert!(accepted >= 10, "only {accepted} seeds open");
}

fn blobs_under(dir: &Path, out: &mut Vec<Vec<u8>>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            blobs_under(&path, out);
        } else if path.extension().is_some_and(|e| e == "aprt") {
            out.push(std::fs::read(path).unwrap());
        }
    }
}

#[test]
fn malformed_fixtures_are_refused() {
    let mut blobs = Vec::new();
    blobs_under(&repo().join("fixtures/malformed"), &mut blobs);
    assert!(!blobs.is_empty());
    for blob in blobs {
        assert!(!exercise(&blob), "a malformed fixture opened");
    }
}

#[test]
fn truncations_and_bit_flips_of_the_golden_blobs_get_statuses() {
    for kind in ["atlas", "bones", "proxies", "world"] {
        let blob = golden(kind);
        assert!(exercise(&blob), "golden {kind} opens");
        for len in 0..blob.len() {
            assert!(!exercise(&blob[..len]), "{kind} truncated to {len} opened");
        }
        for i in 0..blob.len() {
            let mut flipped = blob.clone();
            flipped[i] ^= 1 << (i % 8);
            exercise(&flipped);
        }
    }
    let rig = rig_blob();
    assert!(exercise(&rig));
    for i in (0..rig.len()).step_by(7) {
        let mut flipped = rig.clone();
        flipped[i] ^= 0x80;
        exercise(&flipped);
    }
}
