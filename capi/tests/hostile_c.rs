//! The hostile-use C program (`tests/c/hostile.c`: every entry point with every wrong kind
//! of handle, every length at its edges, mirrored and scaled rotations, NaN, infinities and
//! FLT_MAX in every float argument, failing, short and re-entrant read callbacks) and the
//! C++ wrapper's checks (`tests/c/wrapper.cpp`), built with the system `cc` and `c++`
//! against the staticlib and run on the golden blobs, a model with an irradiance rig and
//! blobs holding ±3e38 under valid checksums. The C program runs plainly, under
//! AddressSanitizer and UBSan where the compiler has them, and under valgrind where it is
//! installed; a missing tool is a printed skip, or a failure under `.ci/run`, which sets
//! `APRT_REQUIRE_CC`, `APRT_REQUIRE_SANITIZERS` and `APRT_REQUIRE_VALGRIND`.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use aprt_core::SectionKind;
use aprt_core::format::{Header, MAX_HEADER_LEN, PREAMBLE_LEN, crc32, read_header};

use crate::common::{have, repo, rig_blob, skip, staticlib};

/// The golden blobs (`fixtures/golden/v1-*.aprt`).
const GOLDEN: [&str; 5] = ["atlas", "atlas-uvs", "bones", "proxies", "world"];

fn dir() -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("capi-hostile");
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Whether the system `cc` and `c++` are there; a printed skip (or, with
/// `APRT_REQUIRE_CC`, a failure) when not.
fn compilers() -> bool {
    let found = have("cc") && have("c++");
    if !found {
        skip(
            "APRT_REQUIRE_CC",
            "no system cc or c++ to build the C tests with",
        );
    }
    found
}

/// Builds `source` (under `tests/c`) with `tool` and `flags` against the staticlib.
fn build(tool: &str, flags: &[&str], source: &str, exe: &Path) -> Result<(), String> {
    let out = Command::new(tool)
        .args(flags)
        .args(["-Wall", "-Wextra", "-Werror", "-ffp-contract=off", "-I"])
        .arg(repo().join("capi/include"))
        .arg(repo().join("capi/tests/c").join(source))
        .arg(staticlib())
        .args(["-lpthread", "-ldl", "-lm", "-o"])
        .arg(exe)
        .output()
        .unwrap();
    match out.status.success() {
        true => Ok(()),
        false => Err(String::from_utf8_lossy(&out.stderr).into_owned()),
    }
}

fn check(what: &str, out: &Output) {
    assert!(
        out.status.success(),
        "{what} failed ({}):\n{}{}",
        out.status,
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Blobs with one stored f32 made ±3e38 (finite, so checks of finiteness pass it) and every
/// checksum recomputed: the first and a middle value of each golden blob's per-vertex rows,
/// weights, pose mean and pose projection. A mutant whose header would change length (its
/// CRC's varint grew or shrank) is left out, so no byte moves.
fn huge_value_blobs(dir: &Path) -> Vec<PathBuf> {
    let kinds = [
        SectionKind::VertexBasis,
        SectionKind::VertexWeights,
        SectionKind::Weights,
        SectionKind::PoseMean,
        SectionKind::PoseProjection,
    ];
    let mut paths = Vec::new();
    for name in GOLDEN {
        let blob = std::fs::read(repo().join(format!("fixtures/golden/v1-{name}.aprt"))).unwrap();
        let header = read_header(&blob).unwrap();
        for (i, e) in header.sections.iter().enumerate() {
            let f32_section = e.encoding == 0 && e.len >= 4;
            if !f32_section || !kinds.iter().any(|k| k.tag() == e.kind) {
                continue;
            }
            let (start, end) = (e.offset as usize, (e.offset + e.len) as usize);
            for (at, value) in [(start, 3e38f32), (start + (end - start) / 8 * 4, -3e38)] {
                let mut mutant = blob.clone();
                mutant[at..at + 4].copy_from_slice(&value.to_le_bytes());
                let mut h = header.clone();
                h.sections[i].crc32 = crc32(&mutant[start..end]);
                if reseal(&mut mutant, &h) {
                    let path = dir.join(format!("huge-{name}-{}-{at}.aprt", e.kind));
                    std::fs::write(&path, &mutant).unwrap();
                    paths.push(path);
                }
            }
        }
    }
    assert!(paths.len() >= 10, "only {} mutants", paths.len());
    paths
}

/// Writes header `h` over the blob's, with its CRC, when it encodes to the same length.
fn reseal(blob: &mut [u8], h: &Header) -> bool {
    let len = u32::from_le_bytes(blob[12..16].try_into().unwrap()) as usize;
    let mut buf = [0u8; MAX_HEADER_LEN as usize];
    match postcard::to_slice(h, &mut buf) {
        Ok(bytes) if bytes.len() == len => {
            blob[PREAMBLE_LEN..PREAMBLE_LEN + len].copy_from_slice(bytes);
            blob[16..20].copy_from_slice(&crc32(bytes).to_le_bytes());
            true
        }
        _ => false,
    }
}

/// The program's arguments: the models, then the hostile blobs.
fn arguments(dir: &Path) -> Vec<PathBuf> {
    let mut args: Vec<PathBuf> = GOLDEN
        .iter()
        .map(|k| repo().join(format!("fixtures/golden/v1-{k}.aprt")))
        .collect();
    let rig = dir.join("rig-bones-f32.aprt");
    std::fs::write(&rig, rig_blob()).unwrap();
    args.push(rig);
    args.push("--accepting-or-refusing".into());
    args.extend(huge_value_blobs(dir));
    args
}

/// Whether `cc` builds and runs a program with AddressSanitizer and UBSan.
fn sanitizers(dir: &Path) -> bool {
    let (source, exe) = (dir.join("probe.c"), dir.join("probe"));
    std::fs::write(&source, "int main(void) { return 0; }\n").unwrap();
    let built = Command::new("cc")
        .args(["-fsanitize=address,undefined", "-o"])
        .arg(&exe)
        .arg(&source)
        .status()
        .is_ok_and(|s| s.success());
    built && Command::new(&exe).status().is_ok_and(|s| s.success())
}

#[test]
fn the_hostile_c_program_gets_the_documented_statuses() {
    if !compilers() {
        return;
    }
    let dir = dir();
    let args = arguments(&dir);
    let plain = dir.join("hostile");
    let c99 = ["-std=c99", "-Wpedantic", "-O1", "-g"];
    build("cc", &c99, "hostile.c", &plain).unwrap();
    check(
        "hostile",
        &Command::new(&plain).args(&args).output().unwrap(),
    );

    if sanitizers(&dir) {
        let sanitized = dir.join("hostile-sanitized");
        let flags = [
            &c99[..],
            &[
                "-fsanitize=address,undefined",
                "-fno-sanitize-recover=all",
                "-fno-omit-frame-pointer",
            ],
        ]
        .concat();
        build("cc", &flags, "hostile.c", &sanitized).unwrap();
        let out = Command::new(&sanitized)
            .args(&args)
            .env("ASAN_OPTIONS", "detect_leaks=1")
            .env("UBSAN_OPTIONS", "print_stacktrace=1")
            .output()
            .unwrap();
        check("hostile under AddressSanitizer and UBSan", &out);
    } else {
        let why = "the C program under AddressSanitizer and UBSan: cc cannot build with \
                   -fsanitize=address,undefined here";
        skip("APRT_REQUIRE_SANITIZERS", why);
    }

    if have("valgrind") {
        let out = Command::new("valgrind")
            .args(["--error-exitcode=1", "--leak-check=full", "-q"])
            .arg(&plain)
            .args(&args)
            .output()
            .unwrap();
        check("hostile under valgrind", &out);
    } else {
        let why = "the C program under valgrind: no valgrind (apt-get install valgrind)";
        skip("APRT_REQUIRE_VALGRIND", why);
    }
}

#[test]
fn the_cpp_wrapper_refuses_partial_rotations_and_triples() {
    if !compilers() {
        return;
    }
    let dir = dir();
    let (exe, rig) = (dir.join("wrapper"), dir.join("wrapper-rig.aprt"));
    std::fs::write(&rig, rig_blob()).unwrap();
    build("c++", &["-std=c++17", "-O1"], "wrapper.cpp", &exe).unwrap();
    check("wrapper", &Command::new(&exe).arg(&rig).output().unwrap());
}

#[test]
fn the_header_needs_c99_or_cpp11_and_no_more() {
    if !compilers() {
        return;
    }
    let header = repo().join("capi/include/aprt.h");
    for (tool, language, std) in [("cc", "c", "-std=c99"), ("c++", "c++", "-std=c++11")] {
        let out = Command::new(tool)
            .args([
                std,
                "-pedantic-errors",
                "-Wall",
                "-Wextra",
                "-fsyntax-only",
                "-x",
            ])
            .arg(language)
            .arg(&header)
            .output()
            .unwrap();
        check(&format!("aprt.h under {tool} {std}"), &out);
    }
}
