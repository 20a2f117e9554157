//! A user's text as the trainer reads and quotes it: without a byte-order mark, and in errors
//! at most an excerpt, so a 400 KB line is never echoed whole and an error never carries more
//! than a glimpse of a file. Every reader of text (BVH, OBJ, CSV, TOML) shares these.

/// Longest excerpt of a file's content an error quotes, in characters.
pub const EXCERPT_CHARS: usize = 80;

/// At most [`EXCERPT_CHARS`] characters of the first line of `text`, with `…` where it was cut:
/// what an error may quote of a file's content, so a 400 KB line is not echoed whole and an
/// error never carries more than a glimpse of a file.
pub fn excerpt(text: &str) -> String {
    let line = text.lines().next().unwrap_or_default();
    match line.char_indices().nth(EXCERPT_CHARS) {
        Some((cut, _)) => format!("{}…", &line[..cut]),
        None if line.len() < text.trim_end().len() => format!("{line}…"),
        None => line.to_owned(),
    }
}

/// `text` with its control characters (line breaks, tabs, escapes) written as Rust escapes
/// (`\n`, `\u{1b}`): a name or message quoted from a file keeps an error on one line.
pub fn escape_controls(text: &str) -> String {
    text.chars()
        .map(|c| match c.is_control() {
            true => c.escape_default().to_string(),
            false => c.to_string(),
        })
        .collect()
}

/// A TOML syntax or schema error as one line: where (line and column) and what, quoting at
/// most an [`excerpt`] of the text rather than the whole offending line the parser shows.
pub fn toml_problem(text: &str, e: &toml::de::Error) -> String {
    let at = e.span().map(|span| {
        let before = &text[..span.start.min(text.len())];
        let line = before.matches('\n').count() + 1;
        let column = before
            .rsplit('\n')
            .next()
            .unwrap_or_default()
            .chars()
            .count()
            + 1;
        format!("line {line}, column {column}: ")
    });
    format!("{}{}", at.unwrap_or_default(), excerpt(e.message()))
}

/// `text` without the UTF-8 byte-order mark some editors write at the start of a text file
/// (U+FEFF): left in, it would glue itself to the first statement, cell or keyword.
pub fn without_bom(text: &str) -> &str {
    text.strip_prefix('\u{feff}').unwrap_or(text)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An excerpt is one line of at most [`EXCERPT_CHARS`] characters, marked where cut.
    #[test]
    fn an_excerpt_is_one_short_line() {
        assert_eq!(excerpt("root:x:0:0"), "root:x:0:0");
        assert_eq!(excerpt("first\nsecond"), "first…");
        let long = "é".repeat(400_000);
        let cut = excerpt(&long);
        assert_eq!(cut.chars().count(), EXCERPT_CHARS + 1);
        assert!(cut.ends_with('…'));
    }

    /// A TOML error says where and what, without echoing the offending line.
    #[test]
    fn a_toml_problem_does_not_echo_the_line() {
        let text = format!("a = 1\nb = {}", "x".repeat(400_000));
        let e = text.parse::<toml::Table>().unwrap_err();
        let said = toml_problem(&text, &e);
        assert!(said.starts_with("line 2, column "), "{said}");
        assert!(said.len() < 200, "{said}");
    }
}
