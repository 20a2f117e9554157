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

/// Names from a file a list shows before it says how many more there are.
pub const LISTED: usize = 8;

/// `c` as a message shows it: itself, or [`char::escape_debug`]'s escape when it is a control
/// character (line breaks, tabs, escapes), a bidirectional mark or another invisible one, and,
/// with `quotes`, a double quote or a backslash.
fn escaped(c: char, quotes: bool) -> String {
    match c {
        '"' | '\\' if !quotes => c.to_string(),
        '\'' => c.to_string(),
        _ => c.escape_debug().collect(),
    }
}

/// `text` with its control and invisible characters escaped, as `escaped` does: text quoted
/// from a file keeps an error on one line, and can neither recolour the terminal nor reverse it.
pub fn escape_controls(text: &str) -> String {
    text.chars().map(|c| escaped(c, false)).collect()
}

/// At most about [`EXCERPT_CHARS`] characters of `text` escaped as `quotes` asks ([`escaped`]),
/// with `…` where it was cut.
fn escaped_excerpt(text: &str, quotes: bool) -> String {
    let mut out = String::new();
    let mut shown = 0;
    for c in text.chars() {
        let piece = escaped(c, quotes);
        shown += piece.chars().count();
        if shown > EXCERPT_CHARS {
            out.push('…');
            break;
        }
        out += &piece;
    }
    out
}

/// A name or token from a file, a blob or the command line as a message quotes it: in double
/// quotes, escaped as `{:?}` escapes it (control characters, bidirectional marks, quotes) and
/// cut with `…` after about [`EXCERPT_CHARS`] characters, so a 100 KB token gives a short line.
/// A plain name reads as `{:?}` shows it.
pub fn quote(text: &str) -> String {
    format!("\"{}\"", escaped_excerpt(text, true))
}

/// A name from a file or a blob as a listing shows it: [`quote`]'s escapes and cut, without
/// the quotes.
pub fn shown(text: &str) -> String {
    escaped_excerpt(text, false)
}

/// Names from a file as a message lists them: each [`shown`], joined with `, `, at most
/// [`LISTED`] of them and then how many more, so the list stays one short line.
pub fn shown_list<S: AsRef<str>>(names: &[S]) -> String {
    let mut list: Vec<String> = names
        .iter()
        .take(LISTED)
        .map(|n| shown(n.as_ref()))
        .collect();
    if names.len() > LISTED {
        list.push(format!("and {} more", names.len() - LISTED));
    }
    list.join(", ")
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

    /// A quoted name is escaped as `{:?}` escapes it and cut to one short line; a list of
    /// names says how many it leaves out.
    #[test]
    fn a_quoted_name_is_escaped_and_short() {
        assert_eq!(quote("hip.x"), format!("{:?}", "hip.x"));
        assert_eq!(quote("a\"b\\c"), format!("{:?}", "a\"b\\c"));
        let hostile = "\u{1b}[31mred\r\u{202e}txt\u{200f}";
        assert_eq!(quote(hostile), r#""\u{1b}[31mred\r\u{202e}txt\u{200f}""#);
        assert_eq!(shown("a\"b"), "a\"b");
        let long = quote(&"\u{1b}".repeat(100_000));
        assert!(long.chars().count() <= EXCERPT_CHARS + 3, "{long}");
        assert!(long.ends_with("…\""), "{long}");
        let names: Vec<String> = (0..20).map(|i| format!("n{i}")).collect();
        assert_eq!(shown_list(&names[..2]), "n0, n1");
        assert!(shown_list(&names).ends_with("n7, and 12 more"));
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
