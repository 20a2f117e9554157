//! NumPy `.npy` (format 1.0) for little-endian float32 arrays: the writer, so results load
//! with `numpy.load` without any aprt code, and a reader of exactly what it writes, so one
//! command's output can be measured against another's (`aprt lightmap eval --against`).

/// Encodes a C-order float32 array of the given shape as `.npy` bytes.
pub fn encode_f32(shape: &[usize], data: &[f32]) -> Vec<u8> {
    debug_assert_eq!(shape.iter().product::<usize>(), data.len());
    let dims: Vec<String> = shape.iter().map(|d| d.to_string()).collect();
    let shape_text = match dims.len() {
        1 => format!("({},)", dims[0]),
        _ => format!("({})", dims.join(", ")),
    };
    let mut header = format!("{{'descr': '<f4', 'fortran_order': False, 'shape': {shape_text}, }}");
    // Magic (6) + version (2) + length (2) + header + '\n' is padded to a multiple of 64.
    let unpadded = 10 + header.len() + 1;
    header.push_str(&" ".repeat(unpadded.next_multiple_of(64) - unpadded));
    header.push('\n');
    let mut out = Vec::with_capacity(10 + header.len() + data.len() * 4);
    out.extend_from_slice(b"\x93NUMPY\x01\x00");
    out.extend_from_slice(&(header.len() as u16).to_le_bytes());
    out.extend_from_slice(header.as_bytes());
    for x in data {
        out.extend_from_slice(&x.to_le_bytes());
    }
    out
}

/// Why a `.npy` file could not be read back.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum NpyError {
    /// Not a format-1.0 `.npy` file.
    #[error("not a NumPy .npy file (format 1.0)")]
    NotNpy,
    /// The header is not the dictionary NumPy writes, or describes an array this reader does
    /// not take (anything but C-order little-endian float32).
    #[error("header: {0}")]
    Header(String),
    /// The data is shorter or longer than the shape says.
    #[error("the shape {shape:?} needs {expected} bytes of data, the file has {found}")]
    Length {
        /// The header's shape.
        shape: Vec<usize>,
        /// Bytes the shape needs.
        expected: usize,
        /// Bytes after the header.
        found: usize,
    },
}

/// Reads a C-order little-endian float32 array written by [`encode_f32`] (or by NumPy with
/// the same dtype): its shape and values.
pub fn decode_f32(bytes: &[u8]) -> Result<(Vec<usize>, Vec<f32>), NpyError> {
    if bytes.len() < 10 || &bytes[..8] != b"\x93NUMPY\x01\x00" {
        return Err(NpyError::NotNpy);
    }
    let len = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    let header = bytes
        .get(10..10 + len)
        .and_then(|h| std::str::from_utf8(h).ok())
        .ok_or(NpyError::NotNpy)?;
    let shape = parse_header(header).map_err(NpyError::Header)?;
    let data = &bytes[10 + len..];
    let expected = shape
        .iter()
        .try_fold(4usize, |n, &d| n.checked_mul(d))
        .ok_or_else(|| NpyError::Header(format!("the shape {shape:?} overflows")))?;
    if data.len() != expected {
        return Err(NpyError::Length {
            shape,
            expected,
            found: data.len(),
        });
    }
    let values = data
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    Ok((shape, values))
}

/// A value of the header's dictionary.
#[derive(Debug, PartialEq)]
enum HeaderValue {
    Text(String),
    Bool(bool),
    Tuple(Vec<usize>),
}

/// The shape of the array the header describes. The header is a Python dictionary literal
/// with exactly the keys `descr`, `fortran_order` and `shape`, parsed whole (a search for
/// substrings once let `'fortran_order': True` or `'descr': '>f4'` through, and such arrays
/// were read with their values scrambled); only `'<f4'` in C order is read.
fn parse_header(header: &str) -> Result<Vec<usize>, String> {
    let mut p = Parser {
        rest: header.trim_end_matches([' ', '\n']),
    };
    p.expect('{')?;
    let (mut descr, mut fortran, mut shape) = (None, None, None);
    while !p.eat('}') {
        let key = p.string()?;
        p.expect(':')?;
        let value = p.value()?;
        let slot = match key.as_str() {
            "descr" => &mut descr,
            "fortran_order" => &mut fortran,
            "shape" => &mut shape,
            other => return Err(format!("unknown key '{}'", quoted(other))),
        };
        if slot.replace(value).is_some() {
            return Err(format!("key '{}' given twice", quoted(&key)));
        }
        if !p.eat(',') {
            p.expect('}')?;
            break;
        }
    }
    if !p.rest.is_empty() {
        return Err(format!("{:?} after the dictionary", p.rest));
    }
    match descr {
        Some(HeaderValue::Text(d)) if d == "<f4" => {}
        Some(HeaderValue::Text(d)) => {
            return Err(format!(
                "'descr' is '{}': only '<f4' (little-endian float32) is read",
                quoted(&d)
            ));
        }
        Some(_) => return Err("'descr' is not a string".into()),
        None => return Err("missing key 'descr'".into()),
    }
    match fortran {
        Some(HeaderValue::Bool(false)) => {}
        Some(HeaderValue::Bool(true)) => {
            return Err("'fortran_order' is True: only C-order arrays are read".into());
        }
        Some(_) => return Err("'fortran_order' is not True or False".into()),
        None => return Err("missing key 'fortran_order'".into()),
    }
    match shape {
        Some(HeaderValue::Tuple(shape)) => Ok(shape),
        Some(_) => Err("'shape' is not a tuple of sizes".into()),
        None => Err("missing key 'shape'".into()),
    }
}

/// A string of the header as an error quotes it: control characters escaped, so the message
/// stays on one line (a key `'desc\n'` printed two), and at most an [`excerpt`] of it.
///
/// [`excerpt`]: crate::text::excerpt
fn quoted(text: &str) -> String {
    crate::text::excerpt(&text.escape_debug().to_string())
}

/// The unread part of a header, with the few tokens a NumPy header dictionary has.
struct Parser<'a> {
    rest: &'a str,
}

impl Parser<'_> {
    /// Skips spaces, then takes `c` if it is next.
    fn eat(&mut self, c: char) -> bool {
        self.rest = self.rest.trim_start();
        match self.rest.strip_prefix(c) {
            Some(rest) => {
                self.rest = rest;
                true
            }
            None => false,
        }
    }

    fn expect(&mut self, c: char) -> Result<(), String> {
        if self.eat(c) {
            return Ok(());
        }
        let found: String = self.rest.chars().take(20).collect();
        Err(format!("expected '{c}', found {found:?}"))
    }

    /// A quoted string (either quote).
    fn string(&mut self) -> Result<String, String> {
        self.rest = self.rest.trim_start();
        let quote = match self.rest.chars().next() {
            Some(q @ ('\'' | '"')) => q,
            _ => return Err(format!("expected a quoted key, found {:?}", self.short())),
        };
        let (text, rest) = self.rest[1..]
            .split_once(quote)
            .ok_or_else(|| format!("unterminated string {:?}", self.short()))?;
        self.rest = rest;
        Ok(text.to_owned())
    }

    fn value(&mut self) -> Result<HeaderValue, String> {
        self.rest = self.rest.trim_start();
        for (word, value) in [("True", true), ("False", false)] {
            if let Some(rest) = self.rest.strip_prefix(word) {
                self.rest = rest;
                return Ok(HeaderValue::Bool(value));
            }
        }
        if !self.eat('(') {
            return self.string().map(HeaderValue::Text);
        }
        let mut sizes = Vec::new();
        while !self.eat(')') {
            let digits = self.rest.len()
                - self
                    .rest
                    .trim_start_matches(|c: char| c.is_ascii_digit())
                    .len();
            let size = self.rest[..digits]
                .parse()
                .map_err(|_| format!("expected a size in the shape, found {:?}", self.short()))?;
            self.rest = &self.rest[digits..];
            sizes.push(size);
            if !self.eat(',') {
                self.expect(')')?;
                break;
            }
        }
        Ok(HeaderValue::Tuple(sizes))
    }

    /// The next few characters, to quote in an error.
    fn short(&self) -> String {
        self.rest.chars().take(20).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_is_aligned_and_describes_the_array() {
        let bytes = encode_f32(&[2, 3], &[0.0, 1.0, 2.0, 3.0, 4.0, 5.0]);
        let header_len = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
        assert_eq!((10 + header_len) % 64, 0);
        let header = std::str::from_utf8(&bytes[10..10 + header_len]).unwrap();
        assert!(
            header.contains("'shape': (2, 3)")
                && header.contains("'<f4'")
                && header.ends_with('\n')
        );
        assert_eq!(
            &bytes[10 + header_len + 4..10 + header_len + 8],
            &1.0f32.to_le_bytes()
        );
        assert_eq!(bytes.len(), 10 + header_len + 24);
    }

    #[test]
    fn one_dimensional_shape_has_a_trailing_comma() {
        let bytes = encode_f32(&[1], &[7.0]);
        assert!(bytes.windows(4).any(|w| w == b"(1,)"));
    }

    #[test]
    fn reads_back_what_it_writes_and_refuses_the_rest() {
        let data = [0.5f32, -1.0, 3.25, 7.0, 8.0, 9.5];
        let bytes = encode_f32(&[3, 2], &data);
        assert_eq!(decode_f32(&bytes), Ok((vec![3, 2], data.to_vec())));
        assert_eq!(
            decode_f32(&encode_f32(&[1], &[2.0])),
            Ok((vec![1], vec![2.0]))
        );
        assert_eq!(decode_f32(b"PK\x03\x04"), Err(NpyError::NotNpy));
        assert!(matches!(
            decode_f32(&bytes[..bytes.len() - 4]),
            Err(NpyError::Length {
                expected: 24,
                found: 20,
                ..
            })
        ));
    }

    /// Headers are parsed whole: another dtype, byte order or memory order, a missing,
    /// unknown or repeated key, or a malformed dictionary is refused saying which.
    #[test]
    fn the_header_is_parsed_not_searched() {
        let bytes = encode_f32(&[3, 2], &[0.0; 6]);
        let len = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
        let header = std::str::from_utf8(&bytes[10..10 + len]).unwrap();
        let with = |from: &str, to: &str| {
            assert!(header.contains(from), "{from}");
            // Padded to the same length, so the header's length field still holds.
            let to = format!("{to:<width$}", width = from.len());
            let mut edited = bytes[..10].to_vec();
            edited.extend_from_slice(header.replacen(from, &to, 1).as_bytes());
            edited.extend_from_slice(&bytes[10 + len..]);
            decode_f32(&edited)
        };
        let cases = [
            ("'<f4'", "'>f4'", "'descr' is '>f4'"),
            ("'<f4'", "'<f8'", "'descr' is '<f8'"),
            ("False", "True", "'fortran_order' is True"),
            ("'descr': '<f4', ", "", "missing key 'descr'"),
            ("'shape'", "'shapf'", "unknown key 'shapf'"),
            // Quoted on one line: the CLI prints one line per error.
            ("'shape'", "'sh\nap'", "unknown key 'sh\\nap'"),
            ("'<f4'", "'<\r4'", "'descr' is '<\\r4'"),
            ("'descr'", "'shape'", "key 'shape' given twice"),
            ("(3, 2)", "(3, x)", "expected a size"),
            ("{", "[", "expected '{'"),
            ("} ", "}x", "after the dictionary"),
        ];
        for (from, to, message) in cases {
            let err = with(from, to).unwrap_err().to_string();
            assert!(err.contains(message), "{from} -> {to}: {err}");
        }
        // NumPy's own spacing and quotes read.
        let numpy = "{\"descr\":\"<f4\",\"fortran_order\":False,\"shape\":(3,2)}";
        assert_eq!(parse_header(numpy), Ok(vec![3, 2]));
        assert_eq!(
            parse_header("{'descr': '<f4', 'fortran_order': False, 'shape': (), }"),
            Ok(vec![])
        );
    }
}
