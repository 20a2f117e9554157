//! The one way the trainer opens a file a user names (on the command line, in a scene, as a
//! glTF buffer): regular files only, no larger than their kind's limit, the whole path in every
//! error. A FIFO would block the run forever and `/dev/zero` would fill memory, so both are
//! refused before the file is opened; the size is checked from the metadata first and again
//! while reading, since a file may grow in between.

use std::fmt;
use std::io::Read;
use std::path::{Path, PathBuf};

/// What a file is read as, which sets its size limit and names it in errors. The limits sit
/// far above every real input here (the largest: the CMU mannequin's 104 MB nearest-pose
/// model blob, a 2k × 1k EXR sky of 25 MB) and below what stops a 24 GB machine.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InputKind {
    /// A scene file (TOML): 1 MiB.
    Scene,
    /// A lights file (TOML): 16 MiB, some 100k lights.
    Lights,
    /// A Radiance HDR or OpenEXR environment map: 512 MiB (an uncompressed 16k × 8k RGBE file,
    /// though decoding one needs more than a run holds: its header is checked for that).
    EnvironmentMap,
    /// A `.shlm` SH light map: 1 GiB.
    LightMap,
    /// A NumPy `.npy` array: 4 GiB, about the run's memory budget.
    Npy,
    /// A BVH motion capture clip: 256 MiB.
    Bvh,
    /// A joint-angle CSV: 256 MiB.
    Angles,
    /// A Wavefront OBJ mesh: 1 GiB.
    Obj,
    /// An aprt model blob: 2 GiB.
    Model,
    /// A glTF document or binary glTF: 1 GiB.
    Gltf,
    /// A glTF buffer's external file: 1 GiB, and no more than its `byteLength`.
    GltfBuffer,
    /// A bake checkpoint's file: 4 GiB.
    Checkpoint,
}

impl InputKind {
    /// The most bytes a file of this kind may hold.
    pub const fn limit(self) -> u64 {
        const MIB: u64 = 1 << 20;
        match self {
            InputKind::Scene => MIB,
            InputKind::Lights => 16 * MIB,
            InputKind::EnvironmentMap => 512 * MIB,
            InputKind::Bvh | InputKind::Angles => 256 * MIB,
            InputKind::LightMap | InputKind::Obj | InputKind::Gltf | InputKind::GltfBuffer => {
                1024 * MIB
            }
            InputKind::Model => 2048 * MIB,
            InputKind::Npy | InputKind::Checkpoint => 4096 * MIB,
        }
    }

    fn name(self) -> &'static str {
        match self {
            InputKind::Scene => "scene file",
            InputKind::Lights => "lights file",
            InputKind::EnvironmentMap => "environment map",
            InputKind::LightMap => "light map",
            InputKind::Npy => "npy array",
            InputKind::Bvh => "BVH clip",
            InputKind::Angles => "angles CSV",
            InputKind::Obj => "OBJ mesh",
            InputKind::Model => "model blob",
            InputKind::Gltf => "glTF file",
            InputKind::GltfBuffer => "glTF buffer",
            InputKind::Checkpoint => "checkpoint file",
        }
    }
}

impl fmt::Display for InputKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Why a file could not be read: the whole path, the kind of file, and the problem.
#[derive(Debug)]
pub struct InputError {
    /// The file.
    pub path: PathBuf,
    /// What it was read as.
    pub kind: InputKind,
    /// What went wrong.
    pub problem: InputProblem,
}

/// What went wrong reading an input.
#[derive(Debug)]
pub enum InputProblem {
    /// The system refused to open or read it.
    Io(std::io::Error),
    /// A directory, FIFO, device or socket: what is there instead.
    NotRegular(&'static str),
    /// Larger than its kind may be: its size (or as much as was read), and the limit.
    TooLarge {
        /// Bytes found.
        size: u64,
        /// Bytes allowed.
        limit: u64,
    },
    /// A text file that is not UTF-8: the offset of the first byte that is not.
    NotText(usize),
}

impl InputError {
    fn new(path: &Path, kind: InputKind, problem: InputProblem) -> InputError {
        InputError {
            path: path.to_owned(),
            kind,
            problem,
        }
    }

    /// What is wrong, without the path: for errors that name the file themselves.
    pub fn problem(&self) -> String {
        let kind = self.kind;
        match &self.problem {
            InputProblem::Io(e) => format!("cannot read this {kind}: {e}"),
            InputProblem::NotRegular(found) => {
                format!("this {kind} is {found}, not a regular file: give the path of a file")
            }
            InputProblem::TooLarge { size, limit } => {
                format!("{size} bytes is more than a {kind} may hold ({limit} bytes)")
            }
            InputProblem::NotText(at) => format!("this {kind} is not UTF-8 text (byte {at})"),
        }
    }

    /// Whether the file does not exist.
    pub fn is_missing(&self) -> bool {
        matches!(&self.problem, InputProblem::Io(e) if e.kind() == std::io::ErrorKind::NotFound)
    }
}

impl fmt::Display for InputError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.path.display(), self.problem())
    }
}

impl std::error::Error for InputError {}

/// The bytes of the regular file at `path`, at most `kind`'s limit of them.
pub fn read_input(path: &Path, kind: InputKind) -> Result<Vec<u8>, InputError> {
    read_at_most(path, kind, kind.limit())
}

/// [`read_input`] with a tighter limit: a file whose length another file states (a glTF
/// buffer's `byteLength`).
pub fn read_at_most(path: &Path, kind: InputKind, limit: u64) -> Result<Vec<u8>, InputError> {
    let fail = |problem| InputError::new(path, kind, problem);
    // Checked before opening: opening a FIFO for reading waits for a writer.
    let meta = std::fs::metadata(path).map_err(|e| fail(InputProblem::Io(e)))?;
    if !meta.is_file() {
        return Err(fail(InputProblem::NotRegular(file_type_name(
            &meta.file_type(),
        ))));
    }
    let too_large = |size| fail(InputProblem::TooLarge { size, limit });
    if meta.len() > limit {
        return Err(too_large(meta.len()));
    }
    let file = std::fs::File::open(path).map_err(|e| fail(InputProblem::Io(e)))?;
    let mut data = Vec::with_capacity(meta.len() as usize);
    file.take(limit.saturating_add(1))
        .read_to_end(&mut data)
        .map_err(|e| fail(InputProblem::Io(e)))?;
    if data.len() as u64 > limit {
        return Err(too_large(data.len() as u64));
    }
    Ok(data)
}

/// The text of the regular file at `path` (UTF-8, at most `kind`'s limit), without a leading
/// byte-order mark.
pub fn read_input_text(path: &Path, kind: InputKind) -> Result<String, InputError> {
    let bytes = read_input(path, kind)?;
    let mut text = String::from_utf8(bytes).map_err(|e| {
        InputError::new(
            path,
            kind,
            InputProblem::NotText(e.utf8_error().valid_up_to()),
        )
    })?;
    if text.starts_with('\u{feff}') {
        text.drain(..'\u{feff}'.len_utf8());
    }
    Ok(text)
}

/// What is at a path that is not a regular file, for errors about inputs and outputs.
pub(crate) fn file_type_name(kind: &std::fs::FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if kind.is_fifo() {
            return "a named pipe (FIFO)";
        }
        if kind.is_socket() {
            return "a socket";
        }
        if kind.is_char_device() || kind.is_block_device() {
            return "a device";
        }
    }
    if kind.is_dir() {
        "a directory"
    } else {
        "not a file"
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refuses_devices_fifos_and_directories_without_blocking() {
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("pipe");
        assert!(
            std::process::Command::new("mkfifo")
                .arg(&fifo)
                .status()
                .unwrap()
                .success()
        );
        for (path, found) in [
            (Path::new("/dev/zero"), "a device"),
            (fifo.as_path(), "a named pipe (FIFO)"),
            (dir.path(), "a directory"),
        ] {
            let e = read_input(path, InputKind::Scene).unwrap_err().to_string();
            assert!(e.contains(found) && e.contains("scene file"), "{e}");
            assert!(e.starts_with(&path.display().to_string()), "{e}");
        }
    }

    #[test]
    fn refuses_files_over_the_limit_with_the_numbers() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("big.toml");
        std::fs::write(&path, vec![b'#'; (InputKind::Scene.limit() + 1) as usize]).unwrap();
        let e = read_input(&path, InputKind::Scene).unwrap_err().to_string();
        assert!(
            e.contains("1048577 bytes") && e.contains("(1048576 bytes)"),
            "{e}"
        );
        let small = dir.path().join("buffer.bin");
        std::fs::write(&small, [0u8; 10]).unwrap();
        assert!(read_at_most(&small, InputKind::Gltf, 9).is_err());
        assert_eq!(read_at_most(&small, InputKind::Gltf, 10).unwrap().len(), 10);
    }

    #[test]
    fn text_loses_its_byte_order_mark_and_must_be_utf8() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("scene.toml");
        std::fs::write(&path, "\u{feff}order = 3\n").unwrap();
        assert_eq!(
            read_input_text(&path, InputKind::Scene).unwrap(),
            "order = 3\n"
        );
        std::fs::write(&path, b"order = \xff").unwrap();
        let e = read_input_text(&path, InputKind::Scene).unwrap_err();
        assert!(e.to_string().contains("not UTF-8 text (byte 8)"), "{e}");
        let missing = dir.path().join("missing.toml");
        let e = read_input(&missing, InputKind::Lights)
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with(&missing.display().to_string()) && e.contains("lights file"),
            "{e}"
        );
    }
}
