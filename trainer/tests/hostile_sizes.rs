//! Sizes that files and flags claim are checked before any work (issue 30); each case's own
//! doc says what it claims and what it cost before. Each case runs the real `aprt` through
//! `aprt-measure` (its only child, under a time limit), which reads its peak memory with
//! `getrusage(RUSAGE_CHILDREN)`: a non-zero exit with one `aprt: ` line naming the file
//! or flag and the numbers, no panic, under 1 GB, every input unchanged and nothing written.

#![cfg(unix)]

use std::path::{Path, PathBuf};
use std::time::Duration;

use crate::run;

/// Longest a refusal may take: every case here is refused in well under a second.
const TIMEOUT: Duration = Duration::from_secs(60);
/// Most memory a refusal may use.
const MAX_MB: f64 = 1024.0;

fn s(path: &Path) -> String {
    path.to_str().unwrap().to_owned()
}

/// Runs `aprt args` through `aprt-measure`; it must be refused within [`TIMEOUT`] and
/// [`MAX_MB`], with exactly one `aprt: ` line holding every fragment, no panic, every file of
/// `inputs` unchanged and nothing in `out`. Returns the line.
fn refused(args: &[String], inputs: &[&Path], out: &Path, fragments: &[&str]) -> String {
    let before: Vec<Vec<u8>> = inputs.iter().map(|p| std::fs::read(p).unwrap()).collect();
    let usage = run::measured(args, TIMEOUT);
    let stderr = &usage.stderr;
    assert!(!usage.timed_out, "{args:?} hung:\n{stderr}");
    assert_ne!(usage.code, 0, "{args:?} succeeded:\n{stderr}");
    let rss_mb = usage.rss_mb;
    assert!(rss_mb < MAX_MB, "{args:?} used {rss_mb:.0} MB:\n{stderr}");
    let error = run::the_one_error(args, stderr, fragments);
    for (path, bytes) in inputs.iter().zip(before) {
        assert!(
            std::fs::read(path).unwrap() == bytes,
            "{args:?} changed {}",
            path.display()
        );
    }
    let left: Vec<_> = std::fs::read_dir(out).unwrap().collect();
    assert!(
        left.is_empty(),
        "{args:?} left {left:?} in {}",
        out.display()
    );
    error
}

fn strings(args: &[&str]) -> Vec<String> {
    args.iter().map(|a| (*a).to_owned()).collect()
}

/// A fresh empty directory for one case's outputs.
fn out_dir(work: &Path, name: &str) -> PathBuf {
    let dir = work.join(name);
    std::fs::create_dir(&dir).unwrap();
    dir
}

/// A lights file of `count` point lights.
fn lights_file(path: &Path, count: usize) {
    let light =
        "[[light]]\nkind = \"point\"\nposition = [0.0, 0.0, 2.0]\nintensity = [1.0, 1.0, 1.0]\n";
    std::fs::write(path, light.repeat(count)).unwrap();
}

/// A triangle, as an OBJ.
fn triangle(path: &Path) {
    std::fs::write(path, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
}

/// `--samples` is held to the core's 4096 rig samples before the lights file or the mesh is
/// read: `u64::MAX` panicked ("capacity overflow"), 100 000 fitted for minutes before the
/// core refused the rig, and 0 was blamed on the lights file.
#[test]
fn rig_samples_are_checked_against_the_core_limit_first() {
    let work = tempfile::tempdir().unwrap();
    let (mesh, lights) = (work.path().join("t.obj"), work.path().join("l.toml"));
    triangle(&mesh);
    lights_file(&lights, 1);
    let out = out_dir(work.path(), "out");
    for samples in ["18446744073709551615", "100000", "0"] {
        let args = strings(&[
            "rig",
            &s(&mesh),
            "--lights",
            &s(&lights),
            "--rig",
            "gradient",
            "--samples",
            samples,
        ]);
        let line = refused(
            &args,
            &[&mesh, &lights],
            &out,
            &[&format!("--samples {samples}"), "1 to 4096"],
        );
        assert!(!line.contains("l.toml"), "{line}");
    }
}

/// A `.shlm` header of `resolution`, `order`, `texels` (one frame, independent frames, the
/// uniform quantiser) and section sizes, padded with zeros to `len` bytes.
fn shlm(path: &Path, (resolution, order, texels): (u32, u32, u32), sections: [u32; 3], len: usize) {
    let mut b = b"APRTSHLM".to_vec();
    for v in [2, resolution, order, 1, texels] {
        b.extend_from_slice(&v.to_le_bytes());
    }
    b.extend_from_slice(&[0, 3, 0, 7, 1, 0, 0, 0]);
    b.extend_from_slice(&0u32.to_le_bytes());
    for v in sections {
        b.extend_from_slice(&v.to_le_bytes());
    }
    b.resize(len, 0);
    std::fs::write(path, b).unwrap();
}

/// A 517-byte `.shlm` whose header claims 8192² texels at order 6 allocated 9.7 GB to decode;
/// now the header is held to the budget, and sections to what their bytes can decompress to.
#[test]
fn shlm_header_sizes_are_checked_before_any_allocation() {
    let work = tempfile::tempdir().unwrap();
    let out = out_dir(work.path(), "out");
    let huge = work.path().join("huge.shlm");
    shlm(&huge, (8192, 6, 0), [0, 0, 0], 517);
    let npy = s(&out.join("x.npy"));
    for args in [
        strings(&["shlm", "inspect", &s(&huge)]),
        strings(&[
            "shlm",
            "eval",
            &s(&huge),
            "--builtin",
            "--clip",
            "wave",
            "--npy",
            &npy,
        ]),
    ] {
        refused(
            &args,
            &[&huge],
            &out,
            &[
                "huge.shlm",
                "8192² map",
                "SH order 6",
                "19.3 GB",
                "at most 4.0 GB",
            ],
        );
    }
    // 1024² at order 4 fits the budget, but 10 bytes of positions cannot hold 1M texels'.
    let short = work.path().join("short.shlm");
    shlm(&short, (1024, 4, 1 << 20), [100, 10, 0], 517);
    let args = strings(&["shlm", "inspect", &s(&short)]);
    refused(
        &args,
        &[&short],
        &out,
        &["short.shlm", "10-byte positions section", "12582912 bytes"],
    );
}

/// `shlm bake --resolution 8192` baked with no estimate; now it is estimated as `train` is,
/// before the atlas is rasterised, and refused with its cost.
#[test]
fn a_light_map_bake_is_estimated_before_the_atlas() {
    let work = tempfile::tempdir().unwrap();
    let bvh = run::tiny_character(work.path(), 4);
    let out = out_dir(work.path(), "out");
    let args = strings(&[
        "shlm",
        "bake",
        "--bvh",
        &bvh,
        "--resolution",
        "8192",
        "--order",
        "2",
        "--rays",
        "16",
        "-o",
        &s(&out.join("m.shlm")),
    ]);
    refused(
        &args,
        &[Path::new(&bvh)],
        &out,
        &[
            "--resolution 8192",
            "67108864 texels",
            "GB of memory",
            "at most 4.0 GB",
            "lower --resolution",
        ],
    );
}

/// Ten thousand repeated clip names sampled every clip before the frame limit refused them;
/// now the clip is sampled once and the frames they add up to refused.
#[test]
fn repeated_clips_are_counted_before_they_are_sampled() {
    let work = tempfile::tempdir().unwrap();
    let out = out_dir(work.path(), "out");
    let mut args = strings(&[
        "simulate",
        "--builtin",
        "--order",
        "1",
        "--rays",
        "4",
        "--npy",
    ]);
    args.push(s(&out.join("x.npy")));
    for _ in 0..10_000 {
        args.extend(strings(&["--clip", "wave"]));
    }
    refused(
        &args,
        &[],
        &out,
        &[
            "10000 clips (wave, wave, wave, …)",
            "frames, more than the 10000",
        ],
    );
}

/// A lights file or scene of more lights than one run evaluates (100k ran over an hour) is
/// refused after parsing, before any light is read into the core or evaluated; 100k lights
/// in a 9 MB file parse within the memory bound.
#[test]
fn lights_beyond_the_limit_are_refused_before_evaluation() {
    let work = tempfile::tempdir().unwrap();
    let out = out_dir(work.path(), "out");
    let (mesh, many, most) = (
        work.path().join("t.obj"),
        work.path().join("many.toml"),
        work.path().join("most.toml"),
    );
    triangle(&mesh);
    lights_file(&many, 100_000);
    lights_file(&most, 1025);
    for (lights, count) in [(&many, "100000"), (&most, "1025")] {
        let args = strings(&[
            "rig",
            &s(&mesh),
            "--lights",
            &s(lights),
            "--rig",
            "gradient",
        ]);
        refused(
            &args,
            &[&mesh, lights],
            &out,
            &[&s(lights), &format!("{count} lights, more than the 1024")],
        );
    }
    let scene = work.path().join("scene.toml");
    let light = "[[light]]\nkind = \"directional\"\ndirection = [0.0, 0.0, 1.0]\n\
                 irradiance = [1.0, 1.0, 1.0]\n";
    let text = format!(
        "[source]\nbuiltin = \"human\"\ntrain = [\"training\"]\n\n{}",
        light.repeat(1025)
    );
    std::fs::write(&scene, text).unwrap();
    let args = strings(&[
        "train",
        "--scene",
        &s(&scene),
        "-o",
        &s(&out.join("m.aprt")),
    ]);
    refused(
        &args,
        &[&scene],
        &out,
        &["scene.toml", "[[light]]", "1025 lights, more than the 1024"],
    );
}

/// A 16k × 8k Radiance map failed with "Memory limit exceeded" and no size; its header's size
/// is now refused with the numbers before a texel is decoded.
#[test]
fn an_environment_map_is_sized_from_its_header() {
    let work = tempfile::tempdir().unwrap();
    let out = out_dir(work.path(), "out");
    let sky = work.path().join("sky.hdr");
    let mut bytes = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 8192 +X 16384\n".to_vec();
    bytes.extend_from_slice(&[0x80; 64]);
    std::fs::write(&sky, bytes).unwrap();
    let args = strings(&["light", "env", &s(&sky), "--order", "2"]);
    refused(
        &args,
        &[&sky],
        &out,
        &[
            "sky.hdr",
            "16384x8192",
            "16384 × 8192 texels",
            "5.4 GB",
            "at most 4.0 GB",
        ],
    );
}

/// A `.shlm` records the fingerprint of the UVs it was baked on, and `shlm eval` and
/// `shlm compose` with a character refuse another character's (CesiumMan's maps were read at
/// the Fox's UVs); a version-2 file, without one, is read with a note saying it is unchecked.
#[test]
fn a_light_map_refuses_another_characters_uvs() {
    let work = tempfile::tempdir().unwrap();
    let bvh = run::tiny_character(work.path(), 3);
    let bake = |maps: &Path, uv: &str| {
        run::succeed(&[
            "shlm",
            "bake",
            "--bvh",
            &bvh,
            "--resolution",
            "32",
            "--order",
            "2",
            "--rays",
            "16",
            "--uv",
            uv,
            "-o",
            &s(maps),
        ]);
    };
    // On the character's texture UVs the file records their fingerprint; on generated UVs
    // it stores them, and another character's triangle count gives it away.
    let maps = work.path().join("maps.shlm");
    bake(&maps, "texture");
    let generated = work.path().join("generated.shlm");
    bake(&generated, "generate");
    let out = out_dir(work.path(), "out");
    let npy = s(&out.join("x.npy"));
    let lights = work.path().join("l.toml");
    lights_file(&lights, 1);
    let png = s(&out.join("x.png"));
    let eval = |maps: &Path| {
        strings(&[
            "shlm",
            "eval",
            &s(maps),
            "--builtin",
            "--clip",
            "wave",
            "--npy",
            &npy,
        ])
    };
    refused(
        &eval(&generated),
        &[&generated, &lights],
        &out,
        &[
            "generated.shlm",
            "stores light-map UVs for",
            "give the character the light map was baked from",
        ],
    );
    for args in [
        eval(&maps),
        strings(&[
            "shlm",
            "compose",
            &s(&maps),
            "--builtin",
            "--clip",
            "wave",
            "--lights",
            &s(&lights),
            "--png",
            &png,
        ]),
    ] {
        refused(
            &args,
            &[&maps, &lights],
            &out,
            &[
                "maps.shlm",
                "was baked on UVs of atlas fingerprint",
                "give the character the light map was baked from",
            ],
        );
    }
    // The same character passes; the file without its fingerprint (version 2) passes too,
    // with the note.
    let own = ["shlm", "eval", &s(&maps), "--bvh", &bvh, "--npy", &npy];
    let ok = run::aprt(&own);
    assert!(
        ok.status.success(),
        "{}",
        String::from_utf8_lossy(&ok.stderr)
    );
    assert!(!String::from_utf8_lossy(&ok.stderr).contains("fingerprint"));
    std::fs::remove_file(&npy).unwrap();
    let mut old = std::fs::read(&maps).unwrap();
    assert_eq!(&old[8..12], &4u32.to_le_bytes());
    old[8..12].copy_from_slice(&2u32.to_le_bytes());
    old.drain(52..64);
    old.truncate(old.len() - 4);
    let crc = crc32fast::hash(&old);
    old.extend_from_slice(&crc.to_le_bytes());
    std::fs::write(&maps, old).unwrap();
    let ok = run::aprt(&own);
    let stderr = String::from_utf8_lossy(&ok.stderr);
    assert!(ok.status.success(), "{stderr}");
    assert!(stderr.contains("records no atlas fingerprint"), "{stderr}");
}
