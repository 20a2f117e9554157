//! Every relative link and image in the documentation resolves: README.md, ARCHITECTURE.md,
//! FORMAT.md and every `.md` under `docs/`. Inline links `[text](target)`, images
//! `![alt](target)` and reference definitions `[label]: target` are checked; web and mail
//! addresses and links to an anchor of the same page are skipped, and a `#fragment` is
//! dropped before the file is looked up relative to the page. Fenced code blocks and inline
//! code spans are not links.

use std::fs;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The markdown files checked: the three top-level documents and `docs/**/*.md`.
fn pages() -> Vec<PathBuf> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        let Ok(entries) = fs::read_dir(dir) else {
            return;
        };
        let mut entries: Vec<PathBuf> = entries.filter_map(|e| e.ok()).map(|e| e.path()).collect();
        entries.sort();
        for path in entries {
            if path.is_dir() {
                walk(&path, out);
            } else if path.extension().is_some_and(|e| e == "md") {
                out.push(path);
            }
        }
    }
    let root = root();
    let mut out: Vec<PathBuf> = ["README.md", "ARCHITECTURE.md", "FORMAT.md"]
        .iter()
        .map(|f| root.join(f))
        .collect();
    walk(&root.join("docs"), &mut out);
    out
}

/// `text` with fenced code blocks and inline code spans blanked out (newlines kept, so line
/// numbers still hold).
fn without_code(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut fence: Option<&str> = None;
    for line in text.split_inclusive('\n') {
        let trimmed = line.trim_start();
        let marker = ["```", "~~~"].into_iter().find(|m| trimmed.starts_with(m));
        match (fence, marker) {
            (None, Some(m)) => {
                fence = Some(m);
                out.push('\n');
                continue;
            }
            (Some(f), Some(m)) if f == m => {
                fence = None;
                out.push('\n');
                continue;
            }
            _ => {}
        }
        if fence.is_some() {
            if line.ends_with('\n') {
                out.push('\n');
            }
            continue;
        }
        // Inline code: a run of backticks up to the same run on this line.
        let chars: Vec<char> = line.chars().collect();
        let mut i = 0;
        while i < chars.len() {
            if chars[i] == '`' {
                let run = chars[i..].iter().take_while(|&&c| c == '`').count();
                let close = (i + run..chars.len()).find(|&j| {
                    chars[j..].iter().take_while(|&&c| c == '`').count() == run
                        && (j == 0 || chars[j - 1] != '`')
                });
                if let Some(j) = close {
                    out.push_str(&" ".repeat(j + run - i));
                    i = j + run;
                    continue;
                }
            }
            out.push(chars[i]);
            i += 1;
        }
    }
    out
}

/// Every link target of `text` with its 1-based line.
fn targets(text: &str) -> Vec<(usize, String)> {
    let text = without_code(text);
    let mut out = Vec::new();
    // Inline links and images: `](` up to the matching `)`.
    let bytes = text.as_bytes();
    let mut i = 0;
    while let Some(at) = text[i..].find("](") {
        let start = i + at + 2;
        let mut depth = 1;
        let mut end = start;
        while end < bytes.len() && depth > 0 {
            match bytes[end] {
                b'(' => depth += 1,
                b')' => depth -= 1,
                b'\n' => break,
                _ => {}
            }
            end += 1;
        }
        if depth == 0 {
            let inner = text[start..end - 1].trim();
            // `<path with spaces>` or `path "title"`.
            let target = if let Some(rest) = inner.strip_prefix('<') {
                rest.split('>').next().unwrap_or("")
            } else {
                inner.split_whitespace().next().unwrap_or("")
            };
            let line = text[..start].matches('\n').count() + 1;
            out.push((line, target.to_owned()));
        }
        i = start;
    }
    // Reference definitions: `[label]: target` at the start of a line.
    for (n, line) in text.lines().enumerate() {
        let t = line.trim_start();
        if let Some(rest) = t.strip_prefix('[')
            && let Some((label, target)) = rest.split_once("]:")
            && !label.is_empty()
            && !label.contains(']')
            && let Some(target) = target.split_whitespace().next()
        {
            out.push((n + 1, target.trim_matches(['<', '>']).to_owned()));
        }
    }
    out
}

/// Whether `target` is a link to a file of the repository.
fn is_relative(target: &str) -> bool {
    let lower = target.to_ascii_lowercase();
    !(target.is_empty()
        || target.starts_with('#')
        || lower.starts_with("http://")
        || lower.starts_with("https://")
        || lower.starts_with("mailto:")
        || lower.contains("://"))
}

/// `%20` and the like in a link, decoded byte by byte.
fn percent_decoded(s: &str) -> String {
    let bytes = s.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%'
            && i + 2 < bytes.len()
            && bytes[i + 1].is_ascii_hexdigit()
            && bytes[i + 2].is_ascii_hexdigit()
        {
            let hex = |b: u8| (b as char).to_digit(16).unwrap_or(0) as u8;
            out.push(hex(bytes[i + 1]) * 16 + hex(bytes[i + 2]));
            i += 3;
            continue;
        }
        out.push(bytes[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

#[test]
fn every_relative_link_and_image_in_the_docs_resolves() {
    let root = root();
    let pages = pages();
    assert!(
        pages.len() > 3,
        "no markdown under {}",
        root.join("docs").display()
    );
    let mut broken = Vec::new();
    let mut checked = 0;
    for page in &pages {
        let text = fs::read_to_string(page)
            .unwrap_or_else(|e| panic!("cannot read {}: {e}", page.display()));
        let dir = page.parent().expect("a page is in a directory");
        for (line, target) in targets(&text) {
            if !is_relative(&target) {
                continue;
            }
            checked += 1;
            let file = target.split('#').next().unwrap_or("");
            let file = percent_decoded(file);
            let resolved = if let Some(from_root) = file.strip_prefix('/') {
                root.join(from_root)
            } else {
                dir.join(&file)
            };
            if !resolved.exists() {
                let shown = page.strip_prefix(&root).unwrap_or(page);
                broken.push(format!("{}:{line}: {target}", shown.display()));
            }
        }
    }
    assert!(
        checked > 0,
        "no relative links found: is the scanner broken?"
    );
    assert!(
        broken.is_empty(),
        "{} broken relative link(s) in the docs:\n{}",
        broken.len(),
        broken.join("\n")
    );
}

#[test]
fn the_scanner_finds_links_and_images_but_not_code() {
    let text = "see [a](x.md#part) and ![b](img/p.png \"title\")\n\
                `[not](code.md)` and [web](https://example.com) [here](#anchor)\n\
                ```\n[also not](fenced.md)\n```\n\
                [ref]: refs/r.md\n\
                [nested (parens)](dir/f(1).md)\n";
    let found: Vec<(usize, String)> = targets(text);
    let want = [
        (1, "x.md#part"),
        (1, "img/p.png"),
        (2, "https://example.com"),
        (2, "#anchor"),
        (7, "dir/f(1).md"),
        (6, "refs/r.md"),
    ];
    assert_eq!(
        found,
        want.iter()
            .map(|&(l, t)| (l, t.to_owned()))
            .collect::<Vec<_>>()
    );
    let relative: Vec<&str> = want
        .iter()
        .map(|&(_, t)| t)
        .filter(|t| is_relative(t))
        .collect();
    assert_eq!(
        relative,
        ["x.md#part", "img/p.png", "dir/f(1).md", "refs/r.md"]
    );
}
