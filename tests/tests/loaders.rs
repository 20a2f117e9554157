//! The readers of characters under hostile bytes, on stable `cargo test`: the harness of the
//! `gltf` and `bvh` fuzz targets (`aprt_tests::loaders`) on every prefix of the valid fixtures
//! and on random mutations of them — byte edits, and edits that keep the file well formed so
//! they reach the checks behind the parser: a JSON value of the glTF (in `.gltf` and in the
//! `.glb`'s JSON chunk) replaced by a hostile one or removed, a BVH token replaced, dropped or
//! repeated. Each case is a rig or a refusal naming the file, never a panic.

use std::path::{Path, PathBuf};
use std::sync::LazyLock;

use aprt_tests::edit::Mutation;
use aprt_tests::loaders;
use arbitrary::{Arbitrary, Unstructured};
use proptest::prelude::*;
use serde_json::{Value, json};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../fixtures/malformed")
        .join(name)
}

struct Bases {
    gltf: Vec<u8>,
    glb: Vec<u8>,
    bvh: Vec<u8>,
}

static BASES: LazyLock<Bases> = LazyLock::new(|| Bases {
    gltf: std::fs::read(fixture("gltf/ok.gltf")).unwrap(),
    glb: std::fs::read(fixture("gltf/ok.glb")).unwrap(),
    bvh: std::fs::read(fixture("bvh/ok.bvh")).unwrap(),
});

#[test]
fn the_valid_fixtures_load_through_the_harness() {
    loaders::gltf(&BASES.gltf).unwrap();
    loaders::gltf(&BASES.glb).unwrap();
    loaders::bvh(&BASES.bvh).unwrap();
}

#[test]
fn every_prefix_is_a_rig_or_a_refusal() {
    for n in 0..BASES.glb.len() {
        assert!(loaders::gltf(&BASES.glb[..n]).is_err(), "GLB prefix {n}");
    }
    for n in 0..BASES.gltf.len() {
        // A prefix ending inside the final white space is still the whole document.
        let whole = BASES.gltf[n..].iter().all(u8::is_ascii_whitespace);
        assert_eq!(loaders::gltf(&BASES.gltf[..n]).is_ok(), whole, "prefix {n}");
    }
    for n in 0..BASES.bvh.len() {
        let _ = loaders::bvh(&BASES.bvh[..n]);
    }
}

/// JSON values that upset readers: zeros, negatives, the edges of integer widths, huge
/// floats, every component type and accessor type, wrong kinds.
fn hostile_values() -> Vec<Value> {
    let mut values = vec![
        json!(0),
        json!(1),
        json!(2),
        json!(-1),
        json!(3),
        json!(7),
        json!(255),
        json!(65535),
        json!(4_294_967_295u64),
        json!(4_294_967_296u64),
        json!(u64::MAX),
        json!(1e308),
        json!(-1e308),
        json!(1e-40),
        json!(0.5),
        json!(-0.0),
        json!(""),
        json!("x"),
        json!(null),
        json!([]),
        json!({}),
        json!(true),
        json!([0, 0, 0]),
        json!([0, 0, 0, 0]),
        json!(["data:,"]),
        json!("/dev/zero"),
        json!("data:application/octet-stream;base64,AAAA"),
        json!("CUBICSPLINE"),
        json!("STEP"),
        json!("scale"),
        json!("weights"),
        json!("translation"),
        json!("1.0"),
        json!("3.0"),
    ];
    values.extend((5120..=5126).map(|c| json!(c)));
    values.extend(
        ["SCALAR", "VEC2", "VEC3", "VEC4", "MAT2", "MAT3", "MAT4"]
            .iter()
            .map(|t| json!(t)),
    );
    values
}

static HOSTILE: LazyLock<Vec<Value>> = LazyLock::new(hostile_values);

/// The JSON pointers of every value in `value` (objects and arrays included).
fn pointers(value: &Value, at: String, out: &mut Vec<String>) {
    match value {
        Value::Object(map) => {
            for (key, v) in map {
                pointers(v, format!("{at}/{key}"), out);
            }
        }
        Value::Array(items) => {
            for (i, v) in items.iter().enumerate() {
                pointers(v, format!("{at}/{i}"), out);
            }
        }
        _ => {}
    }
    out.push(at);
}

/// An edit that keeps the document JSON: the value at one pointer replaced by a hostile one,
/// or removed from its object or array.
#[derive(Clone, Debug)]
struct JsonEdit {
    at: usize,
    value: usize,
    remove: bool,
}

impl JsonEdit {
    fn apply(&self, doc: &mut Value) {
        let mut all = Vec::new();
        pointers(doc, String::new(), &mut all);
        let pointer = &all[self.at % all.len()];
        let Some((parent, key)) = pointer.rsplit_once('/') else {
            return;
        };
        if self.remove {
            match doc.pointer_mut(parent) {
                Some(Value::Object(map)) => {
                    map.remove(key);
                }
                Some(Value::Array(items)) => {
                    if let Ok(i) = key.parse::<usize>() {
                        items.remove(i);
                    }
                }
                _ => {}
            }
        } else if let Some(slot) = doc.pointer_mut(pointer) {
            *slot = HOSTILE[self.value % HOSTILE.len()].clone();
        }
    }
}

fn arb_json_edit() -> impl Strategy<Value = JsonEdit> {
    (any::<usize>(), any::<usize>(), prop::bool::weighted(0.2))
        .prop_map(|(at, value, remove)| JsonEdit { at, value, remove })
}

/// `ok.gltf` or `ok.glb` with `edits` applied to its JSON.
fn edited_gltf(edits: &[JsonEdit], glb: bool) -> Vec<u8> {
    let base = if glb { &BASES.glb } else { &BASES.gltf };
    let container = glb.then(|| gltf::Glb::from_slice(base).expect("ok.glb"));
    let text: &[u8] = container.as_ref().map_or(base, |c| &c.json);
    let mut doc: Value = serde_json::from_slice(text).unwrap();
    for edit in edits {
        edit.apply(&mut doc);
    }
    let text = serde_json::to_vec(&doc).unwrap();
    match container {
        None => text,
        Some(container) => gltf::Glb {
            json: text.into(),
            ..container
        }
        .to_vec()
        .unwrap(),
    }
}

/// A BVH token edit: the token at `at` (counting all lines) replaced, dropped or repeated.
#[derive(Clone, Debug)]
struct TokenEdit {
    at: usize,
    token: usize,
    op: u8,
}

const TOKENS: [&str; 24] = [
    "0",
    "-1",
    "1e308",
    "-1e308",
    "nan",
    "inf",
    "1e-320",
    "99999999999",
    "3",
    "6",
    "9",
    "{",
    "}",
    "ROOT",
    "JOINT",
    "End",
    "Site",
    "OFFSET",
    "CHANNELS",
    "Xrotation",
    "Zposition",
    "MOTION",
    "Frames:",
    "Time:",
];

fn edited_bvh(edits: &[TokenEdit]) -> Vec<u8> {
    let text = String::from_utf8(BASES.bvh.clone()).unwrap();
    let mut lines: Vec<Vec<String>> = text
        .lines()
        .map(|l| l.split_whitespace().map(str::to_owned).collect())
        .collect();
    for edit in edits {
        let count: usize = lines.iter().map(Vec::len).sum();
        let mut k = edit.at % count.max(1);
        let Some(line) = lines.iter_mut().find(|l| {
            let here = k < l.len();
            if !here {
                k -= l.len();
            }
            here
        }) else {
            continue;
        };
        match edit.op % 3 {
            0 => line[k] = TOKENS[edit.token % TOKENS.len()].to_owned(),
            1 => {
                line.remove(k);
            }
            _ => {
                let again = line[k].clone();
                line.insert(k, again);
            }
        }
    }
    lines
        .iter()
        .map(|l| l.join(" "))
        .collect::<Vec<_>>()
        .join("\n")
        .into_bytes()
}

fn arb_token_edit() -> impl Strategy<Value = TokenEdit> {
    (any::<usize>(), any::<usize>(), any::<u8>()).prop_map(|(at, token, op)| TokenEdit {
        at,
        token,
        op,
    })
}

/// Byte mutations drawn from fuzzer-like bytes (`Mutation`'s `arbitrary`).
fn mutated(base: &[u8], seed: &[u8]) -> Vec<u8> {
    let mut bytes = base.to_vec();
    let mutations = Vec::<Mutation>::arbitrary(&mut Unstructured::new(seed)).unwrap_or_default();
    for m in mutations.iter().take(6) {
        m.apply(&mut bytes);
    }
    bytes
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 4000, ..ProptestConfig::default() })]

    /// Well-formed JSON with hostile values or missing members, as `.gltf` and inside a GLB.
    #[test]
    fn gltf_with_hostile_json_values_is_a_rig_or_a_refusal(
        edits in proptest::collection::vec(arb_json_edit(), 1..4),
        glb in any::<bool>(),
    ) {
        let _ = loaders::gltf(&edited_gltf(&edits, glb));
    }

    /// Well-formed BVH lines with hostile tokens, or tokens dropped or repeated.
    #[test]
    fn bvh_with_hostile_tokens_is_a_rig_or_a_refusal(
        edits in proptest::collection::vec(arb_token_edit(), 1..4),
    ) {
        let _ = loaders::bvh(&edited_bvh(&edits));
    }

    /// Byte edits of the three valid fixtures.
    #[test]
    fn byte_mutations_are_a_rig_or_a_refusal(
        which in 0usize..3,
        seed in proptest::collection::vec(any::<u8>(), 0..96),
    ) {
        let bases = [&BASES.gltf, &BASES.glb, &BASES.bvh];
        let bytes = mutated(bases[which], &seed);
        let _ = if which < 2 { loaders::gltf(&bytes) } else { loaders::bvh(&bytes) };
    }
}
