//! Joint-angle tables: one pose per CSV row, one column per joint angle.

use std::path::{Path, PathBuf};

/// A malformed angles file, with the place and the reason.
#[derive(Debug, thiserror::Error)]
pub enum AnglesError {
    /// The file could not be read (the error names it and why).
    #[error(transparent)]
    Read(#[from] crate::input::InputError),
    /// A cell is not a finite number.
    #[error("{path}: row {row}, column {column}: {reason}")]
    Cell {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        row: usize,
        /// 1-based column.
        column: usize,
        /// What is wrong.
        reason: String,
    },
    /// A row has a different number of cells than the first data row.
    #[error("{path}: row {row} has {found} values, row {first_row} has {expected}")]
    Ragged {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        row: usize,
        /// Cells found.
        found: usize,
        /// Cells in the first data row.
        expected: usize,
        /// Line of the first data row.
        first_row: usize,
    },
    /// A row has more cells than a model has pose entries.
    #[error(
        "{path}: row {row} has {found} angles, more than the {max} pose entries aprt-core takes",
        max = aprt_core::MAX_POSE_LEN
    )]
    Columns {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        row: usize,
        /// Cells found.
        found: usize,
    },
    /// A row has a different number of cells than the model has pose entries.
    #[error("{path}: row {row} has {found} angles, the model takes {expected}")]
    Width {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        row: usize,
        /// Cells found.
        found: usize,
        /// The model's pose length.
        expected: usize,
    },
    /// No data rows.
    #[error("{path}: no rows of joint angles")]
    Empty {
        /// The file.
        path: PathBuf,
    },
}

/// Reads an angles CSV: comma-separated numbers, one row per pose. A first row that is not
/// numeric is taken as a header; blank lines and lines starting with `#` are skipped. With
/// `pose_len` (a model's pose length), a row of another width is an error naming that row.
pub fn read_angles(path: &Path, pose_len: Option<usize>) -> Result<Vec<Vec<f64>>, AnglesError> {
    let text = crate::input::read_input_text(path, crate::input::InputKind::Angles)?;
    parse_angles(path, &text, pose_len)
}

/// Parses angles CSV text; `path` only names the source in errors. With `pose_len`, every row
/// must have that many cells; without, as many as the first data row. A leading UTF-8
/// byte-order mark is skipped.
pub fn parse_angles(
    path: &Path,
    text: &str,
    pose_len: Option<usize>,
) -> Result<Vec<Vec<f64>>, AnglesError> {
    let text = crate::text::without_bom(text);
    let mut rows: Vec<Vec<f64>> = Vec::new();
    let mut first_row = 0;
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let cells: Vec<&str> = line.split(',').map(str::trim).collect();
        let parsed: Vec<Result<f64, _>> = cells.iter().map(|c| c.parse::<f64>()).collect();
        if rows.is_empty() && first_row == 0 && parsed.iter().all(|p| p.is_err()) {
            first_row = usize::MAX; // a header row: names, not numbers
            continue;
        }
        if cells.len() > aprt_core::MAX_POSE_LEN {
            return Err(AnglesError::Columns {
                path: path.into(),
                row: i + 1,
                found: cells.len(),
            });
        }
        let mut row = Vec::with_capacity(cells.len());
        for (j, (cell, value)) in cells.iter().zip(parsed).enumerate() {
            let bad = |reason: String| AnglesError::Cell {
                path: path.into(),
                row: i + 1,
                column: j + 1,
                reason,
            };
            // Escaped and cut: a 100 KB cell gives a short line.
            let cell = || crate::text::shown(cell);
            match value {
                // Larger angles overflow the fit's squares and the runtime's f32 pose vector.
                Ok(x) if x.abs() > f64::from(f32::MAX) && x.is_finite() => {
                    return Err(bad(format!(
                        "'{}' is beyond ±3.4e38, the largest angle the runtime's f32 pose vector holds",
                        cell()
                    )));
                }
                Ok(x) if x.is_finite() => row.push(x),
                Ok(_) => return Err(bad(format!("'{}' is not finite", cell()))),
                Err(_) => return Err(bad(format!("'{}' is not a number", cell()))),
            }
        }
        if let Some(expected) = pose_len.filter(|&n| n != row.len()) {
            return Err(AnglesError::Width {
                path: path.into(),
                row: i + 1,
                found: row.len(),
                expected,
            });
        }
        if let Some(first) = rows.first() {
            if row.len() != first.len() {
                return Err(AnglesError::Ragged {
                    path: path.into(),
                    row: i + 1,
                    found: row.len(),
                    expected: first.len(),
                    first_row,
                });
            }
        } else {
            first_row = i + 1;
        }
        rows.push(row);
    }
    if rows.is_empty() {
        return Err(AnglesError::Empty { path: path.into() });
    }
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_row_and_comments_are_skipped() {
        let rows = parse_angles(
            Path::new("a.csv"),
            "hip,knee\n# comment\n0.1, 0.2\n\n-1e-3,3\n",
            Some(2),
        )
        .unwrap();
        assert_eq!(rows, vec![vec![0.1, 0.2], vec![-1e-3, 3.0]]);
    }

    #[test]
    fn a_byte_order_mark_is_skipped_before_a_header_or_a_number() {
        for text in ["\u{feff}hip,knee\n0.1,0.2\n", "\u{feff}0.1,0.2\n"] {
            let rows = parse_angles(Path::new("a.csv"), text, Some(2)).unwrap();
            assert_eq!(rows, vec![vec![0.1, 0.2]], "{text:?}");
        }
    }

    #[test]
    fn errors_name_row_and_column() {
        let err = parse_angles(Path::new("a.csv"), "0,1\n2,x\n", None)
            .unwrap_err()
            .to_string();
        assert_eq!(err, "a.csv: row 2, column 2: 'x' is not a number");
        let err = parse_angles(Path::new("a.csv"), "0,1\n2,NaN\n", None)
            .unwrap_err()
            .to_string();
        assert_eq!(err, "a.csv: row 2, column 2: 'NaN' is not finite");
        let err = parse_angles(Path::new("a.csv"), "0,1\n-1e308,1\n", None)
            .unwrap_err()
            .to_string();
        assert!(
            err.starts_with("a.csv: row 2, column 1: '-1e308' is beyond ±3.4e38"),
            "{err}"
        );
        let err = parse_angles(Path::new("a.csv"), "0,1\n2\n", None)
            .unwrap_err()
            .to_string();
        assert_eq!(err, "a.csv: row 2 has 1 values, row 1 has 2");
        assert!(parse_angles(Path::new("a.csv"), "a,b\n", None).is_err());
        let err = parse_angles(Path::new("a.csv"), "a,b\n0,1\n", Some(3))
            .unwrap_err()
            .to_string();
        assert_eq!(err, "a.csv: row 2 has 2 angles, the model takes 3");
        let wide = vec!["0"; aprt_core::MAX_POSE_LEN + 1].join(",");
        let err = parse_angles(Path::new("a.csv"), &wide, None)
            .unwrap_err()
            .to_string();
        assert!(
            err.starts_with("a.csv: row 1 has 513 angles, more than"),
            "{err}"
        );
        let err = parse_angles(
            Path::new("a.csv"),
            &format!("0\n{}y", "x".repeat(100_000)),
            None,
        )
        .unwrap_err()
        .to_string();
        assert!(err.len() < 200, "{err}");
    }
}
