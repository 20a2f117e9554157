//! NumPy `.npy` (format 1.0) for little-endian float32 arrays: the writer, so results load
//! with `numpy.load` without any aprt code, and a reader of exactly what it writes, so one
//! command's output can be measured against another's (`aprt shlm eval --against`).

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
    /// A dtype, order or shape this reader does not take.
    #[error("unsupported array: {0} (expected C-order little-endian float32)")]
    Unsupported(String),
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
    if !header.contains("'descr': '<f4'") || !header.contains("'fortran_order': False") {
        return Err(NpyError::Unsupported(header.trim().to_owned()));
    }
    let shape_text = header
        .split_once("'shape': (")
        .and_then(|(_, rest)| rest.split_once(')'))
        .map(|(inside, _)| inside)
        .ok_or_else(|| NpyError::Unsupported(header.trim().to_owned()))?;
    let shape = shape_text
        .split(',')
        .map(str::trim)
        .filter(|d| !d.is_empty())
        .map(|d| d.parse::<usize>())
        .collect::<Result<Vec<_>, _>>()
        .map_err(|_| NpyError::Unsupported(header.trim().to_owned()))?;
    let data = &bytes[10 + len..];
    let expected = shape
        .iter()
        .try_fold(4usize, |n, &d| n.checked_mul(d))
        .ok_or_else(|| NpyError::Unsupported(format!("shape {shape:?} overflows")))?;
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
        let f8 = String::from_utf8_lossy(&bytes).replace("<f4", "<f8");
        assert!(matches!(
            decode_f32(f8.as_bytes()),
            Err(NpyError::Unsupported(_)) | Err(NpyError::NotNpy)
        ));
    }
}
