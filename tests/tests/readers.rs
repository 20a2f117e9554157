//! The readers of settings and data under hostile bytes, on stable `cargo test`: the harness of
//! the `scene`, `lights`, `shlm`, `env_map` and `npy` fuzz targets (`aprt_tests::readers`) on
//! every prefix of their seeds and on deterministic mutations of them: byte edits, and for the
//! TOML files edits that mostly keep them TOML, so they reach the checks behind the parser (a
//! token replaced by a hostile value such as `1e300`, `nan`, `-1`, `""`, `[]` or a huge
//! integer, dropped or repeated; a line dropped or repeated). Each case is a value the reader
//! promises or a one-line refusal, never a panic.

use std::fs;
use std::path::{Path, PathBuf};
use std::sync::LazyLock;

use aprt_tests::edit::Mutation;
use aprt_tests::{noise, readers};
use arbitrary::{Arbitrary, Unstructured};

type Harness = fn(&[u8]) -> Result<(), String>;

/// The files of `dir` (under the workspace) whose names start with `prefix`, sorted.
fn files(dir: &str, prefix: &str) -> Vec<Vec<u8>> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(dir);
    let mut paths: Vec<PathBuf> = fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.file_name().unwrap().to_str().unwrap().starts_with(prefix))
        .collect();
    paths.sort();
    paths.iter().map(|p| fs::read(p).unwrap()).collect()
}

/// A fuzz target: its name, harness and seeds, as `fuzz/` runs it (see README, Fuzzing).
struct Target {
    name: &'static str,
    harness: Harness,
    seeds: Vec<Vec<u8>>,
}

static TARGETS: LazyLock<[Target; 5]> = LazyLock::new(|| {
    let both = |a: &str, b: &str, prefix: &str| [files(a, prefix), files(b, "")].concat();
    let target = |name, harness, seeds| Target {
        name,
        harness,
        seeds,
    };
    [
        target(
            "scene",
            readers::scene,
            both("fuzz/corpus/scene", "fixtures/scenes", "seed-"),
        ),
        target(
            "lights",
            readers::lights,
            both("fixtures/lights", "fixtures/malformed/lights", ""),
        ),
        target("shlm", readers::shlm, files("fuzz/corpus/shlm", "seed-")),
        target(
            "env_map",
            readers::env_map,
            files("fuzz/corpus/env_map", "seed-"),
        ),
        target("npy", readers::npy, files("fuzz/corpus/npy", "seed-")),
    ]
});

/// Deterministic bytes for the `arbitrary` edits of case `case`.
fn bytes(case: u64, len: usize) -> Vec<u8> {
    noise(case, len)
        .iter()
        .map(|x| ((x + 1.0) * 128.0) as u8)
        .collect()
}

#[test]
fn every_prefix_of_every_seed_is_read_or_refused() {
    for Target {
        name,
        harness,
        seeds,
    } in TARGETS.iter()
    {
        assert!(!seeds.is_empty(), "{name} has no seeds");
        for seed in seeds {
            for n in 0..seed.len() {
                let read = harness(&seed[..n]);
                // A cut file fails its checksum or its declared lengths.
                if matches!(*name, "shlm" | "npy") {
                    assert!(read.is_err(), "{name} prefix {n} was accepted");
                }
            }
        }
    }
}

/// Byte mutations drawn from fuzzer-like bytes (`Mutation`'s `arbitrary`), at most six.
fn mutated(base: &[u8], case: u64) -> Vec<u8> {
    let mut out = base.to_vec();
    let seed = bytes(case, 96);
    let edits = Vec::<Mutation>::arbitrary(&mut Unstructured::new(&seed)).unwrap_or_default();
    edits.iter().take(6).for_each(|m| m.apply(&mut out));
    out
}

#[test]
fn byte_mutations_of_every_seed_are_read_or_refused() {
    for (t, target) in TARGETS.iter().enumerate() {
        let Target {
            name,
            harness,
            seeds,
        } = target;
        let mut accepted = 0;
        for case in 0..5000u64 {
            let base = &seeds[case as usize % seeds.len()];
            accepted += usize::from(harness(&mutated(base, case + 1000 * t as u64)).is_ok());
        }
        assert!(accepted > 0, "no mutation of a {name} seed was accepted");
    }
}

/// Values that upset a TOML reader's checks once the syntax is right: the edges of f32, f64 and
/// i64, NaN and infinities, zero and negative sizes, empty and wrong kinds, strings holding a
/// line break, the words each key takes and some it does not, paths that leave the directory, reversed and huge frame ranges.
const HOSTILE: [&str; 61] = [
    "0",
    "-1",
    "1",
    "2",
    "7",
    "9",
    "65537",
    "0.5",
    "-0.0",
    "1e300",
    "-1e300",
    "1e39",
    "3.5e38",
    "1e-320",
    "nan",
    "-nan",
    "inf",
    "-inf",
    "9223372036854775807",
    "-9223372036854775808",
    "99999999999999999999",
    "\"\"",
    "\"a\\nb\"",
    "{ a = 1, b = \"x\\ny\" }",
    "[\"0..8\\n\", 1]",
    "\"auto\"",
    "\"none\"",
    "\"y\"",
    "\"z\"",
    "\"x\"",
    "\"..\"",
    "\"/\"",
    "\"/etc/passwd\"",
    "\"../a.bvh\"",
    "\"0..0\"",
    "\"5..2\"",
    "\"0..99999999999999999999\"",
    "\"18446744073709551615..18446744073709551616\"",
    "[]",
    "[[]]",
    "[0, 0, 0]",
    "[1e300, 1, 1]",
    "[[1, 1, 1]]",
    "{}",
    "true",
    "1979-05-27T07:32:00Z",
    "\"sphere\"",
    "\"point\"",
    "\"directional\"",
    "\"spot\"",
    "\"gradient\"",
    "\"lattice:0x0x0\"",
    "\"lattice:99999x99999x99999\"",
    "\"lattice:2x2x2\"",
    "\"f16\"",
    "\"i8\"",
    "\"world\"",
    "\"creature\"",
    "kind",
    "[[light]]",
    "[source]",
];

/// The tokens of one line: maximal runs of characters other than white space and the TOML
/// punctuation `=`, `,`, `[`, `]`, `{`, `}`, which stay where they are.
fn token_spans(line: &str) -> Vec<(usize, usize)> {
    let mut spans = Vec::new();
    let mut start = None;
    for (i, c) in line.char_indices().chain([(line.len(), ' ')]) {
        let part = !(c.is_whitespace() || "=,[]{}".contains(c));
        match (part, start) {
            (true, None) => start = Some(i),
            (false, Some(s)) => {
                spans.push((s, i));
                start = None;
            }
            _ => {}
        }
    }
    spans
}

/// `text` with `edits` (from `bytes(case)`) applied: each picks a token by index over the whole
/// text and replaces it by a [`HOSTILE`] value, drops it or repeats it, or drops or repeats its
/// line.
fn edited_toml(text: &[u8], case: u64) -> Vec<u8> {
    let mut lines: Vec<String> = String::from_utf8_lossy(text)
        .lines()
        .map(str::to_owned)
        .collect();
    let choices = bytes(case, 16);
    for edit in choices.chunks_exact(4).take(1 + choices[15] as usize % 3) {
        let spans: Vec<(usize, (usize, usize))> = lines
            .iter()
            .enumerate()
            .flat_map(|(l, line)| token_spans(line).into_iter().map(move |s| (l, s)))
            .collect();
        if spans.is_empty() {
            break;
        }
        let at = usize::from(u16::from_le_bytes([edit[0], edit[1]])) % spans.len();
        let (l, (a, b)) = spans[at];
        let line = &mut lines[l];
        match edit[2] % 8 {
            0..=3 => line.replace_range(a..b, HOSTILE[edit[3] as usize % HOSTILE.len()]),
            4 => line.replace_range(a..b, ""),
            5 => {
                let token = line[a..b].to_owned();
                line.insert_str(a, &format!("{token} "));
            }
            6 => drop(lines.remove(l)),
            _ => {
                let again = line.clone();
                lines.insert(l, again);
            }
        }
    }
    lines.join("\n").into_bytes()
}

#[test]
fn toml_token_edits_are_read_or_refused() {
    for Target {
        name,
        harness,
        seeds,
    } in TARGETS.iter().take(2)
    {
        let (mut accepted, mut refused) = (0, 0);
        for case in 0..6000u64 {
            let base = &seeds[case as usize % seeds.len()];
            match harness(&edited_toml(base, case + 77_000)) {
                Ok(()) => accepted += 1,
                Err(_) => refused += 1,
            }
        }
        // The edits reach both sides of the checks.
        assert!(
            accepted > 100 && refused > 100,
            "{name}: {accepted} accepted, {refused} refused"
        );
    }
}

#[test]
fn the_token_edits_keep_the_text_around_them() {
    assert_eq!(
        token_spans("radius = [1.0, nan]"),
        [(0, 6), (10, 13), (15, 18)]
    );
    let text = b"a = 1\nb = [2, 3]\n";
    let edits: Vec<Vec<u8>> = (0..64).map(|c| edited_toml(text, c)).collect();
    assert!(edits.iter().any(|e| e.starts_with(b"a = ") && e != text));
    assert!(edits.iter().all(|e| e.len() < 200));
}
