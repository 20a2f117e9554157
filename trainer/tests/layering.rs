//! The trainer's stages only look down: ARCHITECTURE.md's numbered list under "## Stages" is
//! the order, lowest first, and no file of a stage may name a stage listed after its own
//! (`crate::stage` or, from a stage's top-level file, `super::stage`). Comment lines are not
//! read: a doc link explains, it does not depend. Every stage of the list is a module of
//! `trainer/src/lib.rs`, and every module there is in the list.

use std::path::{Path, PathBuf};

/// The stage order from ARCHITECTURE.md: the `` N. `name` `` items of its "## Stages" section.
fn stage_order(architecture: &str) -> Vec<String> {
    let section = architecture
        .split("\n## ")
        .find(|s| s.starts_with("Stages"))
        .expect("ARCHITECTURE.md has a \"## Stages\" section");
    section
        .lines()
        .filter_map(|line| {
            let (number, rest) = line.split_once(". `")?;
            number.trim().parse::<usize>().ok()?;
            Some(rest.split('`').next()?.to_owned())
        })
        .collect()
}

/// Every `.rs` file under `dir`.
fn sources(dir: &Path) -> Vec<PathBuf> {
    let mut files = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "rs") {
                files.push(path);
            }
        }
    }
    files.sort();
    files
}

/// The identifiers that follow `prefix` on `line` (`crate::` → `bake` in `crate::bake::X`).
fn named_after<'a>(line: &'a str, prefix: &str) -> Vec<&'a str> {
    line.match_indices(prefix)
        .filter(|(at, _)| {
            // `crate::` inside `aprt_crate::` or a longer identifier is not a path start.
            line[..*at]
                .chars()
                .next_back()
                .is_none_or(|c| !(c.is_alphanumeric() || c == '_'))
        })
        .map(|(at, _)| {
            let rest = &line[at + prefix.len()..];
            let end = rest
                .find(|c: char| !(c.is_alphanumeric() || c == '_'))
                .unwrap_or(rest.len());
            &rest[..end]
        })
        .collect()
}

#[test]
fn stages_only_look_down() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let architecture = std::fs::read_to_string(root.join("../ARCHITECTURE.md")).unwrap();
    let order = stage_order(&architecture);
    assert!(order.len() >= 8, "ARCHITECTURE.md lists {order:?}");
    let rank = |name: &str| order.iter().position(|s| s == name);
    let src = root.join("src");
    let lib = std::fs::read_to_string(src.join("lib.rs")).unwrap();
    let modules: Vec<&str> = lib
        .lines()
        .filter_map(|l| l.strip_prefix("pub mod ")?.strip_suffix(';'))
        .collect();
    let mut sorted_modules = modules.clone();
    sorted_modules.sort();
    let mut sorted_stages: Vec<&str> = order.iter().map(String::as_str).collect();
    sorted_stages.sort();
    assert_eq!(
        sorted_modules, sorted_stages,
        "trainer/src/lib.rs's modules and ARCHITECTURE.md's stages differ"
    );
    let mut offences = Vec::new();
    for file in sources(&src) {
        let relative = file.strip_prefix(&src).unwrap();
        let parts: Vec<String> = relative
            .iter()
            .map(|p| p.to_string_lossy().into_owned())
            .collect();
        let stage = parts[0].trim_end_matches(".rs").to_owned();
        let Some(own) = rank(&stage) else {
            continue; // lib.rs and main.rs sit above every stage
        };
        // `super::` leaves the stage only from its top-level file.
        let top_level = parts.len() == 1 || (parts.len() == 2 && parts[1] == "mod.rs");
        let text = std::fs::read_to_string(&file).unwrap();
        for (n, line) in text.lines().enumerate() {
            if line.trim_start().starts_with("//") {
                continue;
            }
            let mut named = named_after(line, "crate::");
            if top_level {
                named.extend(named_after(line, "super::"));
            }
            for other in named {
                if let Some(theirs) = rank(other)
                    && theirs > own
                {
                    offences.push(format!(
                        "trainer/src/{}:{}: {stage} uses {other}, a later stage: {}",
                        relative.display(),
                        n + 1,
                        line.trim()
                    ));
                }
            }
        }
    }
    assert!(
        offences.is_empty(),
        "stages that look up (ARCHITECTURE.md's order: {}):\n{}",
        order.join(" < "),
        offences.join("\n")
    );
}

/// The checker itself: it reads the list, and it catches an upward path and only that.
#[test]
fn the_checker_reads_the_list_and_paths() {
    let doc =
        "# A\n\n## Stages\n\nLowest first:\n\n1. `limits` — x\n2. `rig` — y\n\n## Next\n3. `no`\n";
    assert_eq!(stage_order(doc), ["limits", "rig"]);
    assert_eq!(
        named_after("use crate::bake::X; crate::rig::Y", "crate::"),
        ["bake", "rig"]
    );
    assert!(named_after("use aprt_crate::bake", "crate::").is_empty());
}
