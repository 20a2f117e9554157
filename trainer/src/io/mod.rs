//! Files in and out: OBJ meshes, joint-angle CSVs, NumPy `.npy` arrays, atomic writes, the
//! check that no output is an input, and where the command line's poses come from.

pub mod angles;
pub mod atomic;
pub mod npy;
pub mod obj;
pub mod outputs;
pub mod scene;
pub mod source;

/// `text` without the UTF-8 byte-order mark some editors write at the start of a text file
/// (U+FEFF): left in, it would glue itself to the first statement, cell or keyword.
pub fn without_bom(text: &str) -> &str {
    text.strip_prefix('\u{feff}').unwrap_or(text)
}
