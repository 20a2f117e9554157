//! Scenes through the real binary: `aprt train --scene` computes only what the scene calls for
//! and says so in `--report`, with what the model costs a frame against the scene's budget;
//! `aprt report` sweeps the knobs, marks the fronts and recommends the cheapest of the most
//! accurate settings within the budget; bad scenes are refused naming the item.

use std::path::Path;

use run::{aprt, refuse, succeed, tiny_character};

use crate::run;

/// Frames of the small character's clip: trained on the first 8, tested on the rest.
const FRAMES: usize = 12;

fn path(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Writes a scene for the small character in `dir` with `effects` (lines of `[effects]`).
fn scene(dir: &Path, name: &str, effects: &str) -> String {
    tiny_character(dir, FRAMES);
    let text = format!(
        "[source]\nbvh = \"character.bvh\"\ntrain = [\"0..8\"]\ntest = [\"8..12\"]\n\
         [effects]\nrays = 32\nerror_target = 4.0\n{effects}\n\
         [environment]\nsh = [[0.6, 0.6, 0.6], [0.0, 0.3, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]\n\
         [[light]]\nkind = \"directional\"\ndirection = [0.3, 0.9, 0.2]\nirradiance = [0.2, 0.2, 0.2]\n"
    );
    let file = dir.join(name);
    std::fs::write(&file, text).unwrap();
    path(&file).to_owned()
}

fn json(file: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(file).unwrap()).unwrap()
}

/// Without shadows no ray is cast, no checkpoint is kept, and the report says what was
/// skipped; the same scene with shadows casts vertices × rays × poses rays, and the shadowless
/// bake is many times faster than the full simulation timed in the same run.
#[test]
fn a_shadowless_scene_casts_no_rays_and_reports_what_it_skipped() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let off = scene(d, "off.toml", "shadows = false\nrig = \"none\"\n");
    let on = scene(d, "on.toml", "shadows = true\nrig = \"none\"\n");
    for (file, tag) in [(&off, "off"), (&on, "on")] {
        let model = d.join(format!("{tag}.aprt"));
        let report = d.join(format!("{tag}.json"));
        succeed(&[
            "train",
            "--scene",
            file,
            "-o",
            path(&model),
            "--report",
            path(&report),
        ]);
        assert!(model.exists() && !d.join(format!("{tag}.aprt.bake")).exists());
    }
    let (off, on) = (json(&d.join("off.json")), json(&d.join("on.json")));
    for key in [
        "rays_cast",
        "bounce_passes",
        "sh_order",
        "skipped",
        "seconds",
    ] {
        assert!(off.get(key).is_some() && on.get(key).is_some(), "{key}");
    }
    assert_eq!(off["rays_cast"], 0);
    // No `[budget] us_per_frame`: the cost is measured, and there is no budget to fit.
    assert!(off["us_per_frame"].as_f64().unwrap() > 0.0, "{off}");
    assert!(off["within_budget"].is_null(), "{off}");
    assert_eq!(off["bounce_passes"], 0);
    let skipped = off["skipped"].to_string();
    assert!(skipped.contains("visibility rays"), "{skipped}");
    assert!(skipped.contains("bounces = 0"), "{skipped}");
    assert!(skipped.contains("irradiance rig"), "{skipped}");
    // Shadowed: every vertex of every pose (training frames, the default's 64 validation
    // poses and the rest pose) casts rays.
    for report in [&off, &on] {
        assert_eq!(report["validation_poses"], 64, "{report}");
    }
    let rays = on["rays_cast"].as_u64().unwrap();
    assert!(
        rays > 0 && rays % 32 == 0 && rays % (8 + 64 + 1) == 0,
        "{rays}"
    );
    assert!(on["computed"].to_string().contains("shadows"));
    // The smooth environment and a faint sun need order 3 at 4 grey levels, or less.
    assert!(
        off["sh_order"].as_u64().unwrap() <= 3,
        "{}",
        off["sh_order_reason"]
    );
    let speedup = off["full_simulation"]["speedup"].as_f64().unwrap();
    assert!(speedup > 5.0, "shadowless bake only {speedup}x faster");
}

/// `aprt train --scene --validation-poses N` bakes N validation poses besides the scene's
/// frames, says what they cost on the line of what was written, and reports both in
/// `--report` (`validation_poses`, `validation_bake_s`); 0 bakes the frames and the rest pose
/// alone.
#[test]
fn a_scene_reports_its_validation_poses_and_their_bake() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let file = scene(d, "scene.toml", "shadows = true\nrig = \"none\"\n");
    let train = |count: &str| {
        let (model, report) = (
            d.join(format!("{count}.aprt")),
            d.join(format!("{count}.json")),
        );
        let out = aprt(&[
            "train",
            "--scene",
            &file,
            "--validation-poses",
            count,
            "-o",
            path(&model),
            "--report",
            path(&report),
        ]);
        let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
        assert!(out.status.success(), "{stderr}");
        (stderr, json(&report))
    };
    let (said, eight) = train("8");
    let wrote = said.lines().find(|l| l.contains(".aprt: ")).unwrap();
    assert!(wrote.contains(", 8 validation poses baked in "), "{said}");
    assert_eq!(eight["validation_poses"], 8, "{eight}");
    let seconds = eight["validation_bake_s"].as_f64().unwrap();
    assert!(seconds > 0.0, "{eight}");
    assert!(
        seconds < eight["stages"]["bake"].as_f64().unwrap(),
        "{eight}"
    );
    let (said, none) = train("0");
    assert!(!said.contains("validation pose"), "{said}");
    assert_eq!(none["validation_poses"], 0, "{none}");
    assert_eq!(none["validation_bake_s"], 0.0, "{none}");
    // The same rays a pose, over 8 frames and the rest pose, then 8 more.
    let rays = |r: &serde_json::Value| r["rays_cast"].as_u64().unwrap();
    assert_eq!(rays(&none) % 9, 0);
    assert_eq!(rays(&eight), rays(&none) / 9 * 17);
}

/// The sweep writes its files, every point has the documented keys, the fronts are
/// undominated, and the recommendation is the cheapest of the points within `--budget-us`
/// whose error ties the lowest there (within max(0.05 grey levels, 1 %)); each setting is
/// chosen by 64 validation poses unless `--validation-poses 0`.
#[test]
fn the_report_recommends_the_most_accurate_point_within_the_budget() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let file = scene(d, "scene.toml", "shadows = true\n");
    let out = d.join("report");
    let model = d.join("best.aprt");
    // A budget every setting meets, then one that only part of them meet.
    succeed(&["report", &file, "--out", path(&out), "--stride", "1"]);
    let all = json(&out.join("report.json"));
    let points = all["points"].as_array().unwrap();
    assert!(points.len() >= 20, "{}", points.len());
    // Each setting's model is chosen as `train --scene` chooses it: by validation poses.
    assert_eq!(all["validation_poses"], 64, "{all}");
    assert!(all["validation_bake_s"].as_f64().unwrap() > 0.0, "{all}");
    assert!(
        all["frames"]
            .to_string()
            .contains("[\"validation poses\",64]"),
        "{}",
        all["frames"]
    );
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(md.contains("on 64 validation poses sampled"), "{md}");
    let us: Vec<f64> = points
        .iter()
        .map(|p| p["us_per_frame"].as_f64().unwrap())
        .collect();
    let mut sorted = us.clone();
    sorted.sort_by(f64::total_cmp);
    let budget = sorted[sorted.len() / 2];
    succeed(&[
        "report",
        &file,
        "--out",
        path(&out),
        "--stride",
        "1",
        "--budget-us",
        &budget.to_string(),
        "--write-model",
        path(&model),
        "--validation-poses",
        "0",
    ]);
    let report = json(&out.join("report.json"));
    assert_eq!(report["validation_poses"], 0, "{report}");
    assert!(!report["frames"].to_string().contains("validation poses"));
    let points = report["points"].as_array().unwrap();
    for p in points {
        for key in ["setting", "error", "us_per_frame", "bytes", "pareto"] {
            assert!(p.get(key).is_some(), "{key}");
        }
    }
    let error = |p: &serde_json::Value| p["error"].as_f64().unwrap();
    let cost = |p: &serde_json::Value| p["us_per_frame"].as_f64().unwrap();
    let i = report["recommended"].as_u64().unwrap() as usize;
    assert!(cost(&points[i]) <= budget);
    let fits = || points.iter().filter(|p| cost(p) <= budget);
    let lowest = fits().map(error).fold(f64::INFINITY, f64::min);
    let tie = lowest + 0.05f64.max(0.01 * lowest);
    assert!(error(&points[i]) <= tie);
    for p in fits().filter(|p| error(p) <= tie) {
        assert!(cost(&points[i]) <= cost(p));
    }
    for (a, p) in points.iter().enumerate() {
        let dominated = points.iter().any(|q| {
            error(q) <= error(p) && cost(q) <= cost(p) && (error(q) < error(p) || cost(q) < cost(p))
        });
        assert_eq!(p["pareto"].as_bool().unwrap(), !dominated, "point {a}");
    }
    for f in [
        "report.md",
        "pareto_us.png",
        "pareto_us.svg",
        "pareto_bytes.png",
        "pareto_bytes.svg",
    ] {
        assert!(out.join(f).exists(), "{f}");
    }
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(md.contains("![error against µs per frame](pareto_us.png)"));
    assert_eq!(
        std::fs::read(&model).unwrap().len() as u64,
        points[i]["bytes"].as_u64().unwrap()
    );
    succeed(&["inspect", path(&model)]);
}

/// The small character's scene with a strong point light beside its spine, which no rig of
/// the scene carries (it is evaluated per vertex), and `[budget] us_per_frame = budget`.
fn near_light_scene(dir: &Path, name: &str, budget: &str) -> String {
    let file = scene(
        dir,
        name,
        "shadows = false\nirradiance_rig = \"constant\"\n",
    );
    let mut text = std::fs::read_to_string(&file).unwrap();
    text += &format!(
        "[[light]]\nkind = \"point\"\nposition = [6.0, 8.0, 0.0]\nintensity = [100.0, 100.0, 100.0]\n\
         [budget]\nus_per_frame = {budget}\n"
    );
    std::fs::write(&file, text).unwrap();
    file
}

/// `train --scene` times the model it wrote through aprt-core with the scene's rig and the
/// light it leaves per vertex, and checks `[budget]`: a budget no model meets (0.001 µs) is
/// missed, said plainly with what to change, and `within_budget` is false; one every model
/// meets (a second a frame) is met. Neither depends on the machine's speed.
#[test]
fn train_scene_checks_the_budget_of_the_model_it_writes() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for (budget, fits) in [("0.001", false), ("1_000_000", true)] {
        let file = near_light_scene(d, &format!("near-{fits}.toml"), budget);
        let (model, report) = (
            d.join(format!("{fits}.aprt")),
            d.join(format!("{fits}.json")),
        );
        let out = aprt(&[
            "train",
            "--scene",
            &file,
            "-o",
            path(&model),
            "--report",
            path(&report),
        ]);
        let said = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{said}");
        let json = json(&report);
        let us = json["us_per_frame"].as_f64().unwrap();
        assert!(us > 0.0 && us < 1e6, "{json}");
        assert_eq!(json["within_budget"].as_bool(), Some(fits), "{json}");
        assert_eq!(json["rig"]["kind"], "constant", "{json}");
        let miss = said.lines().find(|l| l.starts_with("over budget"));
        if fits {
            assert!(miss.is_none(), "{said}");
            assert!(said.contains("within the scene's [budget]"), "{said}");
        } else {
            let miss = miss.unwrap_or_else(|| panic!("no miss message:\n{said}"));
            for part in [
                &format!("{us:.1} µs a frame"),
                "us_per_frame = 0.001",
                "x the budget",
                "k_v",
                "1 evaluated per vertex",
                "aprt report",
            ] {
                assert!(miss.contains(part), "{part:?} not in {miss}");
            }
            // i8 is suggested unless the model already is i8.
            let i8 = json["precision"] == "i8";
            assert_eq!(miss.contains("precision i8"), !i8, "{json}\n{miss}");
        }
    }
}

/// `aprt report` writes every setting with the rig `train --scene` stores for the scene and
/// times it with the light that rig leaves per vertex: the recommended model it writes
/// carries that rig.
#[test]
fn the_report_measures_every_setting_with_the_scenes_rig() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let file = near_light_scene(d, "near.toml", "1_000_000");
    let (out, model) = (d.join("report"), d.join("best.aprt"));
    succeed(&[
        "report",
        &file,
        "--out",
        path(&out),
        "--stride",
        "2",
        "--write-model",
        path(&model),
    ]);
    let report = json(&out.join("report.json"));
    assert_eq!(report["irradiance_rig"]["kind"], "constant", "{report}");
    let i = report["recommended"].as_u64().unwrap() as usize;
    assert!(report["points"][i]["us_per_frame"].as_f64().unwrap() > 0.0);
    let inspect = String::from_utf8(succeed(&["inspect", path(&model)])).unwrap();
    assert!(inspect.contains("irradiance rig  constant"), "{inspect}");
}

/// A bad scene is refused before any work, naming the file and the item.
#[test]
fn bad_scenes_are_refused_naming_the_file_and_the_item() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let file = scene(d, "bad.toml", "shadows = false\nbounces = 2\n");
    let model = d.join("m.aprt");
    refuse(
        &["train", "--scene", &file, "-o", path(&model)],
        &["bad.toml", "[effects] bounces", "need shadows"],
    );
    assert!(!model.exists());
    let file = scene(d, "flags.toml", "");
    let clash = aprt(&["train", "--scene", &file, "-o", path(&model), "--rays", "8"]);
    let said = String::from_utf8_lossy(&clash.stderr);
    assert!(!clash.status.success());
    assert!(
        said.contains("'--scene <SCENE>' cannot be used with '--rays <RAYS>'"),
        "{said}"
    );
    refuse(
        &[
            "report",
            &file,
            "--out",
            path(&d.join("r")),
            "--budget-us",
            "-1",
        ],
        &["--budget-us"],
    );
}

/// A scene's bake farm: three shards into one checkpoint, then `--resume`, write the same
/// model bytes as one run of the scene (every decision of the plan is deterministic).
#[test]
fn a_scene_sharded_three_ways_trains_the_same_bytes_as_one_run() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let file = scene(d, "farm.toml", "shadows = true\n");
    let whole = d.join("whole.aprt");
    succeed(&["train", "--scene", &file, "-o", path(&whole)]);
    let farmed = d.join("farmed.aprt");
    for shard in ["0/3", "1/3", "2/3"] {
        succeed(&[
            "train",
            "--scene",
            &file,
            "-o",
            path(&farmed),
            "--shard",
            shard,
        ]);
        assert!(!farmed.exists(), "a shard writes no model");
    }
    succeed(&["train", "--scene", &file, "-o", path(&farmed), "--resume"]);
    assert_eq!(
        std::fs::read(&whole).unwrap(),
        std::fs::read(&farmed).unwrap()
    );
    let shadowless = scene(d, "farm-off.toml", "shadows = false\n");
    refuse(
        &[
            "train",
            "--scene",
            &shadowless,
            "-o",
            path(&farmed),
            "--shard",
            "0/2",
        ],
        &["--shard 0/2", "closed-form"],
    );
}

/// Writes a scene for the small character in `dir` whose `[source]` names `clips` (lines of
/// `train = …`, `validate = …`, `test = …`).
fn clips_scene(dir: &Path, name: &str, clips: &str) -> String {
    tiny_character(dir, FRAMES);
    let text = format!(
        "[source]\nbvh = \"character.bvh\"\n{clips}\n[effects]\nrays = 8\n\
         [environment]\nsh = [[0.6, 0.6, 0.6]]\n"
    );
    let file = dir.join(name);
    std::fs::write(&file, text).unwrap();
    path(&file).to_owned()
}

/// Every clip a scene names is checked by every command that reads it, before any bake, and
/// train, validate and test clips share no frame: refused naming the scene, the key and both
/// clips (a missing clip by its key, not by a flag the user never gave), nothing written.
#[test]
fn every_scene_clip_is_checked_and_held_out_clips_share_no_frame() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cases: [(&str, &[&str]); 6] = [
        (
            "train = [\"0..8\"]\ntest = [\"8..80\"]",
            &["[source] test", "8..80", "12 frames"],
        ),
        (
            "train = [\"0..8\"]\nvalidate = [\"nofile.bvh\"]",
            &["[source] validate", "nofile.bvh", "no such file"],
        ),
        (
            "train = [\"0..8\"]\ntest = [\"4..12\"]",
            &[
                "[source] test",
                "\"4..12\"",
                "train clip \"0..8\"",
                "frames 4..8",
            ],
        ),
        (
            "train = [\"0..8\"]\nvalidate = [\"character.bvh\"]",
            &[
                "[source] validate",
                "\"character.bvh\"",
                "train clip \"0..8\"",
            ],
        ),
        (
            "train = [\"0..4\"]\nvalidate = [\"4..8\"]\ntest = [\"6..12\"]",
            &["[source] test", "validate clip \"4..8\"", "share no frame"],
        ),
        (
            "train = [\"10..5\"]",
            &["[source] train", "\"10..5\"", "empty or reversed"],
        ),
    ];
    for (i, (clips, words)) in cases.iter().enumerate() {
        let name = format!("clips{i}.toml");
        let file = clips_scene(d, &name, clips);
        let before = std::fs::read(&file).unwrap();
        let model = d.join("m.aprt");
        let mut said = words.to_vec();
        said.push(&name);
        let line = refuse(&["train", "--scene", &file, "-o", path(&model)], &said);
        assert!(!line.contains("--validate"), "{line}");
        refuse(&["report", &file, "--out", path(&d.join("r"))], &said);
        assert!(!model.exists() && !d.join("r").exists());
        assert_eq!(std::fs::read(&file).unwrap(), before);
    }
}

/// Messages name what the user wrote: an environment map's error starts with the scene file
/// (not the character's), `order = 2.0` says what order takes (not how serde failed), and a
/// decoder's cause that its error already quotes is said once.
#[test]
fn scene_messages_name_the_scene_key_once() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let file = clips_scene(d, "env.toml", "train = [\"0..8\"]");
    let text = std::fs::read_to_string(&file).unwrap();
    let env = text.replace("sh = [[0.6, 0.6, 0.6]]", "hdr = \"missing.hdr\"");
    std::fs::write(&file, env).unwrap();
    let model = d.join("m.aprt");
    let line = refuse(
        &["train", "--scene", &file, "-o", path(&model)],
        &["[environment]", "missing.hdr"],
    );
    assert!(
        line.starts_with(&format!("aprt: {file}: [environment]")),
        "{line}"
    );
    let order = text.replace("rays = 8", "rays = 8\norder = 2.0");
    std::fs::write(&file, order).unwrap();
    let line = refuse(
        &["train", "--scene", &file, "-o", path(&model)],
        &["[effects] order", "order must be an integer 1..=6"],
    );
    assert!(!line.contains("untagged"), "{line}");
    let exr = d.join("sky.exr");
    std::fs::write(&exr, b"not an exr").unwrap();
    let line = refuse(&["light", "env", path(&exr), "--order", "2"], &["sky.exr"]);
    let cause = line.rsplit(": ").next().unwrap();
    assert_eq!(line.matches(cause).count(), 1, "{line}");
    assert!(!model.exists());
}

/// A scene path that points at a file of another kind is refused without quoting it (as
/// `/etc/passwd` would be), and content quoted elsewhere is cut to a short line.
#[test]
fn errors_quote_no_file_of_another_kind_and_cut_what_they_quote() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("secret.txt"), "root:x:0:0:root:/root:/bin/bash\n").unwrap();
    let file = d.join("leak.toml");
    std::fs::write(
        &file,
        "[source]\nbvh = \"secret.txt\"\ntrain = [\"0..3\"]\n[environment]\nsh = [[1, 1, 1]]\n",
    )
    .unwrap();
    let model = d.join("m.aprt");
    let line = refuse(
        &["train", "--scene", path(&file), "-o", path(&model)],
        &["secret.txt:1: not a BVH file (it does not start with HIERARCHY)"],
    );
    assert!(!line.contains("root"), "{line}");
    let long = "Y".repeat(400_000);
    std::fs::write(
        d.join("long.bvh"),
        format!("HIERARCHY\nROOT {long}\n{long}\n"),
    )
    .unwrap();
    std::fs::write(
        &file,
        "[source]\nbvh = \"long.bvh\"\ntrain = [\"0..3\"]\n[environment]\nsh = [[1, 1, 1]]\n",
    )
    .unwrap();
    let line = refuse(
        &["train", "--scene", path(&file), "-o", path(&model)],
        &["long.bvh"],
    );
    assert!(line.len() < 400, "{} bytes: {}", line.len(), &line[..400]);
    std::fs::write(&file, format!("[source]\nbuiltin = {long}\n")).unwrap();
    let line = refuse(
        &["train", "--scene", path(&file), "-o", path(&model)],
        &["leak.toml: TOML: line 2"],
    );
    assert!(line.len() < 400, "{} bytes", line.len());
}

/// `--confine` (train --scene, report) and the scene key `confine = true` refuse every path
/// a scene names that is absolute or leaves its directory, symlinks followed: the character,
/// its glTF's buffers, a clip, the environment map; the error names the scene, the key and the path, and nothing
/// is written. A scene whose paths stay inside still trains under `--confine`.
#[test]
fn confined_scenes_refuse_paths_outside_their_directory() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let inside = d.join("scenes");
    std::fs::create_dir(&inside).unwrap();
    tiny_character(d, FRAMES);
    tiny_character(&inside, FRAMES);
    std::os::unix::fs::symlink(d.join("character.bvh"), inside.join("link.bvh")).unwrap();
    let outside = path(&d.join("character.bvh")).to_owned();
    let lit = "[effects]\nrays = 8\nshadows = false\n";
    let mut cases = vec![
        (
            format!("bvh = {outside:?}\ntrain = [\"0..8\"]"),
            "[source] bvh",
            outside.clone(),
        ),
        (
            "bvh = \"../character.bvh\"\ntrain = [\"0..8\"]".into(),
            "[source] bvh",
            "../character.bvh".into(),
        ),
        (
            "bvh = \"link.bvh\"\ntrain = [\"0..8\"]".into(),
            "[source] bvh",
            "link.bvh".into(),
        ),
        (
            "bvh = \"character.bvh\"\ntrain = [\"0..8\"]\ntest = [\"sub/../../character.bvh\"]"
                .into(),
            "[source] test",
            "sub/../../character.bvh".into(),
        ),
    ];
    let spelled = path(&inside.join("character.bvh")).to_owned();
    cases.push((
        format!("bvh = {spelled:?}\ntrain = [\"0..8\"]"),
        "[source] bvh",
        spelled,
    ));
    let model = d.join("m.aprt");
    let train_confined = |file: &Path, said: &[&str]| {
        refuse(
            &[
                "train",
                "--scene",
                path(file),
                "--confine",
                "-o",
                path(&model),
            ],
            said,
        )
    };
    for (i, (source, key, named)) in cases.iter().enumerate() {
        let name = format!("confined{i}.toml");
        let file = inside.join(&name);
        let text = format!("[source]\n{source}\n{lit}[environment]\nsh = [[0.6, 0.6, 0.6]]\n");
        std::fs::write(&file, &text).unwrap();
        let said = [
            name.as_str(),
            key,
            named.as_str(),
            "outside the scene's directory",
        ];
        train_confined(&file, &said);
        refuse(
            &[
                "report",
                path(&file),
                "--confine",
                "--out",
                path(&d.join("r")),
            ],
            &said,
        );
        std::fs::write(&file, format!("confine = true\n{text}")).unwrap();
        refuse(
            &["train", "--scene", path(&file), "-o", path(&model)],
            &said,
        );
    }
    let file = inside.join("sky.toml");
    std::fs::write(
        &file,
        format!("[source]\nbvh = \"character.bvh\"\ntrain = [\"0..8\"]\n{lit}[environment]\nhdr = \"../sky.hdr\"\n"),
    )
    .unwrap();
    let said = ["sky.toml", "[environment]", "../sky.hdr", "outside"];
    train_confined(&file, &said);
    // A glTF inside the directory whose buffers climb out of it, or name a file: URI.
    std::fs::write(d.join("secret.bin"), [0u8; 4]).unwrap();
    let secret = path(&d.join("secret.bin")).to_owned();
    for (i, uri) in ["../secret.bin".to_owned(), format!("file://{secret}")]
        .iter()
        .enumerate()
    {
        let gltf = format!(
            "{{\"asset\":{{\"version\":\"2.0\"}},\"buffers\":[{{\"uri\":{uri:?},\"byteLength\":4}}]}}"
        );
        std::fs::write(inside.join(format!("leaky{i}.gltf")), gltf).unwrap();
        let file = inside.join(format!("leaky{i}.toml"));
        std::fs::write(
            &file,
            format!("[source]\ngltf = \"leaky{i}.gltf\"\ntrain = [\"walk\"]\n{lit}[environment]\nsh = [[0.6, 0.6, 0.6]]\n"),
        )
        .unwrap();
        let name = format!("leaky{i}.toml");
        train_confined(
            &file,
            &[
                &name,
                &format!("[source] gltf, a buffer of leaky{i}.gltf"),
                "secret.bin",
                "outside the scene's directory",
            ],
        );
    }
    assert!(!model.exists() && !d.join("r").exists());
    let file = inside.join("inside.toml");
    std::fs::write(
        &file,
        format!("confine = true\n[source]\nbvh = \"./character.bvh\"\ntrain = [\"0..8\"]\n{lit}[environment]\nsh = [[0.6, 0.6, 0.6]]\n"),
    )
    .unwrap();
    succeed(&[
        "train",
        "--scene",
        path(&file),
        "--confine",
        "-o",
        path(&model),
    ]);
    assert!(model.exists());
}

/// `method = "auto"` puts both methods on one front: every point names its method (a light
/// map its resolution) and is measured over the surface beside the vertices, the front ranks
/// by the surface error, and `aprt train --scene` writes the kind the report recommends. A
/// scene that fixes a light map gets one: a model whose rows are texels, timed as it ships.
#[test]
fn an_auto_scene_sweeps_both_methods_and_train_writes_the_recommended_kind() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let file = scene(
        d,
        "auto.toml",
        "method = \"auto\"\nlightmap_resolution = 64\n",
    );
    let out = d.join("report");
    succeed(&["report", &file, "--out", path(&out)]);
    let report = json(&out.join("report.json"));
    assert_eq!(report["error_at"], "surface", "{report}");
    assert_eq!(report["surface_points"], 8192);
    let points = report["points"].as_array().unwrap();
    for p in points {
        let m = &p["measured"];
        for key in ["surface_grey_rms", "surface_transfer_error", "grey_rms"] {
            assert!(m[key].as_f64().unwrap().is_finite(), "{key}: {p}");
        }
        assert_eq!(p["error"], m["surface_grey_rms"], "{p}");
        let resolution = &p["setting"]["resolution"];
        match p["setting"]["method"].as_str().unwrap() {
            "vertex" => assert!(resolution.is_null(), "{p}"),
            "lightmap" => assert_eq!(resolution, 64, "{p}"),
            other => panic!("method {other}"),
        }
    }
    let count = |m: &str| {
        points
            .iter()
            .filter(|p| p["setting"]["method"] == m)
            .count()
    };
    assert!(count("vertex") >= 20 && count("lightmap") == 9, "{report}");
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(md.contains("| surface grey RMS |") && md.contains("light map 64²"));
    let recommended = &points[report["recommended"].as_u64().unwrap() as usize];
    let (model, json_path) = (d.join("auto.aprt"), d.join("auto.json"));
    succeed(&[
        "train",
        "--scene",
        &file,
        "-o",
        path(&model),
        "--report",
        path(&json_path),
    ]);
    let trained = json(&json_path);
    assert_eq!(
        trained["method"]["method"], recommended["setting"]["method"],
        "{trained}"
    );
    let fixed = scene(
        d,
        "lightmap.toml",
        "method = \"lightmap\"\nlightmap_resolution = 64\nprecision = \"f16\"\n",
    );
    let lm = d.join("lightmap.aprt");
    succeed(&[
        "train",
        "--scene",
        &fixed,
        "-o",
        path(&lm),
        "--report",
        path(&json_path),
    ]);
    let trained = json(&json_path);
    assert_eq!(trained["method"]["method"], "lightmap", "{trained}");
    assert_eq!(trained["method"]["resolution"], 64, "{trained}");
    assert!(trained["full_simulation"].is_null(), "{trained}");
    assert!(trained["us_per_frame"].as_f64().unwrap() > 0.0);
    let inspected = String::from_utf8(succeed(&["inspect", path(&lm)])).unwrap();
    assert!(inspected.contains("texel"), "{inspected}");
}
