//! The optional angle-names section: the name of every pose-vector entry, so an engine binds
//! its joints to the model by name once, at load time.

use super::Error;

/// The names of a model's pose-vector entries, in pose-vector order (for example `LeftArm.x`,
/// `LeftArm.y`, `LeftArm.z`, `l_elbow_flex`). Empty when the blob records none (a model
/// trained on unnamed angle rows).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct AngleNames<'a> {
    /// `\n`-terminated lines, validated when the model was opened.
    text: &'a str,
}

impl<'a> AngleNames<'a> {
    /// The names in `bytes` if they are UTF-8 and exactly `count` non-empty `\n`-terminated
    /// lines.
    pub(crate) fn parse(bytes: &'a [u8], count: usize) -> Result<AngleNames<'a>, Error> {
        let mut check = NamesCheck::default();
        check.feed(bytes);
        check.finish(count)?;
        let text = core::str::from_utf8(bytes).map_err(|_| Error::BadAngleNames)?;
        Ok(AngleNames { text })
    }

    /// The names, in pose-vector order.
    pub fn iter(&self) -> impl DoubleEndedIterator<Item = &'a str> + 'a {
        self.text.split_terminator('\n')
    }

    /// The pose-vector index of the entry called `name`, if the model has it.
    pub fn index_of(&self, name: &str) -> Option<usize> {
        self.iter().position(|n| n == name)
    }

    /// The name of entry `index`.
    pub fn get(&self, index: usize) -> Option<&'a str> {
        self.iter().nth(index)
    }

    /// Number of names: the model's pose length, or 0 when it records none.
    pub fn len(&self) -> usize {
        self.iter().count()
    }

    /// Whether the model records no names.
    pub fn is_empty(&self) -> bool {
        self.text.is_empty()
    }
}

impl<'a> IntoIterator for AngleNames<'a> {
    type Item = &'a str;
    type IntoIter = core::str::SplitTerminator<'a, char>;

    fn into_iter(self) -> Self::IntoIter {
        self.text.split_terminator('\n')
    }
}

/// Validates the angle-names bytes chunk by chunk, as a streaming reader delivers them: a
/// multi-byte character may straddle two chunks, so its first bytes wait in `pending`.
#[derive(Default)]
pub(crate) struct NamesCheck {
    lines: usize,
    line_len: usize,
    pending: [u8; 4],
    pending_len: usize,
    bad: bool,
}

impl NamesCheck {
    pub(crate) fn feed(&mut self, mut bytes: &[u8]) {
        for &b in bytes {
            if b == b'\n' {
                self.bad |= self.line_len == 0;
                self.lines += 1;
                self.line_len = 0;
            } else {
                self.line_len += 1;
            }
        }
        // Complete a character left open by the last chunk, one byte at a time.
        while self.pending_len > 0 && !bytes.is_empty() && !self.bad {
            self.pending[self.pending_len] = bytes[0];
            self.pending_len += 1;
            bytes = &bytes[1..];
            match core::str::from_utf8(&self.pending[..self.pending_len]) {
                Ok(_) => self.pending_len = 0,
                Err(e) if e.error_len().is_some() || self.pending_len == 4 => self.bad = true,
                Err(_) => {}
            }
        }
        if self.pending_len > 0 || self.bad {
            return;
        }
        if let Err(e) = core::str::from_utf8(bytes) {
            let tail = &bytes[e.valid_up_to()..];
            if e.error_len().is_some() {
                self.bad = true;
            } else {
                self.pending[..tail.len()].copy_from_slice(tail);
                self.pending_len = tail.len();
            }
        }
    }

    /// Whether everything fed was `count` non-empty UTF-8 lines, each `\n`-terminated.
    pub(crate) fn finish(&self, count: usize) -> Result<(), Error> {
        let ok = !self.bad && self.pending_len == 0 && self.line_len == 0 && self.lines == count;
        if ok {
            Ok(())
        } else {
            Err(Error::BadAngleNames)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Labelled hard cases: what a streaming reader must accept and refuse.
    #[test]
    fn names_are_counted_lines_of_utf8() {
        let cases: [(&str, &[u8], usize, bool); 9] = [
            ("three names", b"a.x\na.y\nelbow\n", 3, true),
            ("non-ASCII names", "Hüfte.x\n腕.y\n".as_bytes(), 2, true),
            ("no names for no entries", b"", 0, true),
            ("one name short", b"a.x\na.y\n", 3, false),
            ("one name too many", b"a.x\na.y\nb\nc\n", 3, false),
            ("last line unterminated", b"a.x\na.y\nb", 3, false),
            ("an empty name", b"a.x\n\nb\n", 3, false),
            ("invalid UTF-8", b"a\xff\nb\nc\n", 3, false),
            ("a character cut at the end", b"a\nb\n\xe8\x85", 2, false),
        ];
        for (label, bytes, count, valid) in cases {
            assert_eq!(
                AngleNames::parse(bytes, count).is_ok(),
                valid,
                "{label}, whole"
            );
            // Every split into two chunks, and one byte at a time.
            for cut in 0..=bytes.len() {
                let mut check = NamesCheck::default();
                check.feed(&bytes[..cut]);
                check.feed(&bytes[cut..]);
                assert_eq!(check.finish(count).is_ok(), valid, "{label}, cut at {cut}");
            }
            let mut check = NamesCheck::default();
            bytes.chunks(1).for_each(|b| check.feed(b));
            assert_eq!(check.finish(count).is_ok(), valid, "{label}, bytewise");
        }
    }

    #[test]
    fn names_are_found_by_index_and_name() {
        let names = AngleNames::parse(b"hip.x\nhip.y\nknee\n", 3).unwrap();
        assert_eq!(names.len(), 3);
        assert_eq!(names.index_of("knee"), Some(2));
        assert_eq!(names.index_of("hip"), None);
        assert_eq!(names.get(1), Some("hip.y"));
        assert_eq!(names.get(3), None);
        assert_eq!(
            names.into_iter().collect::<heapless::Vec<_, 4>>(),
            ["hip.x", "hip.y", "knee"]
        );
        assert!(AngleNames::default().is_empty());
    }
}
