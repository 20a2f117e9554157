//! A command's outputs, checked before any work: none may be one of its inputs (or another of
//! its outputs), and each must be something [`crate::io::atomic::write_atomic`] can replace.
//!
//! Two paths are the same file when their canonical paths are equal or, on Unix, when they
//! have the same device and inode, so a symlink, a `..` detour or a hard link to an input is
//! caught as well as the same spelling. An output that does not exist yet is compared by
//! where it would be created (the canonical path of its nearest existing ancestor, joined with
//! the rest of the path, `..` and `.` resolved): `new/../scene.toml` is `scene.toml` once
//! `new/` is created. A directory output is compared file by file: each file the command
//! writes into it is an output too, and the directory may not lie inside an input directory
//! (whose files the command reads by names it does not list).

use std::path::{Component, Path, PathBuf};

use crate::input::{InputKind, read_input};
use crate::io::atomic::{OutputError, output_target};
use crate::rig::gltf::{external_file, gltf_split};

/// A file or directory a command reads.
#[derive(Clone, Debug)]
pub struct Input {
    /// The path, as the user gave it or as the input that names it resolves it.
    pub path: PathBuf,
    /// What it is to the command, in the user's terms: `the mesh`, `the angles CSV`, `a buffer
    /// of scene.gltf`, …
    pub role: String,
}

impl Input {
    /// An input called `role`.
    pub fn new(path: impl Into<PathBuf>, role: impl Into<String>) -> Input {
        Input {
            path: path.into(),
            role: role.into(),
        }
    }
}

/// A path a command writes.
#[derive(Clone, Debug)]
pub struct Output {
    /// The path.
    pub path: PathBuf,
    /// How the command line names it: `--npy`, `-o`, `--checkpoint`, …
    pub flag: String,
    /// Whether a file is written there (replaced whole) or a directory filled.
    pub kind: OutputKind,
    /// For a directory, the files the command writes into it, relative to it.
    pub files: Vec<PathBuf>,
}

/// What a command writes at an [`Output`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OutputKind {
    /// A file, written whole by rename.
    File,
    /// A directory the command creates or fills with files of its own.
    Directory,
}

impl Output {
    /// A file written at `path`, named `flag` on the command line.
    pub fn file(path: impl Into<PathBuf>, flag: impl Into<String>) -> Output {
        Output {
            path: path.into(),
            flag: flag.into(),
            kind: OutputKind::File,
            files: Vec::new(),
        }
    }

    /// A directory filled at `path`, named `flag` on the command line, into which the command
    /// writes `files` (relative paths): each is checked against the inputs as a file output
    /// is, so `aprt report DIR/report.md --out DIR` cannot overwrite the scene it reads.
    pub fn directory(path: impl Into<PathBuf>, flag: impl Into<String>, files: &[&str]) -> Output {
        Output {
            path: path.into(),
            flag: flag.into(),
            kind: OutputKind::Directory,
            files: files.iter().map(PathBuf::from).collect(),
        }
    }
}

/// Why a command's outputs were refused.
#[derive(Debug, thiserror::Error)]
pub enum GuardError {
    /// An output is one of the inputs.
    #[error(
        "{flag} {}: that is {role} {}; writing it would destroy the input, so give another output path",
        output.display(),
        input.display()
    )]
    IsInput {
        /// The output's flag.
        flag: String,
        /// The output as given.
        output: PathBuf,
        /// What the input is.
        role: String,
        /// The input as given.
        input: PathBuf,
    },
    /// A file a command writes into its output directory is one of the inputs.
    #[error(
        "{flag} {}: the command writes {} there, which is {role} {}; writing it would destroy the input, so give another output directory",
        output.display(),
        file.display(),
        input.display()
    )]
    WritesInput {
        /// The output directory's flag.
        flag: String,
        /// The output directory as given.
        output: PathBuf,
        /// The file written into it, as it would be named.
        file: PathBuf,
        /// What the input is.
        role: String,
        /// The input as given.
        input: PathBuf,
    },
    /// An output lies inside an input directory.
    #[error(
        "{flag} {}: that is inside {role} {}; the command would write among the files it reads, so give a path outside it",
        output.display(),
        input.display()
    )]
    InsideInput {
        /// The output's flag.
        flag: String,
        /// The output as given.
        output: PathBuf,
        /// What the input is.
        role: String,
        /// The input directory as given.
        input: PathBuf,
    },
    /// Two outputs are the same path.
    #[error(
        "{flag} {} and {other_flag} {} are the same path; each output needs its own",
        output.display(),
        other.display()
    )]
    SameOutput {
        /// The first output's flag.
        flag: String,
        /// The first output.
        output: PathBuf,
        /// The second output's flag.
        other_flag: String,
        /// The second output.
        other: PathBuf,
    },
    /// A file output cannot be replaced (it is a FIFO, a device, a directory, a symlink loop).
    #[error("{flag} {}", path.display())]
    NotWritable {
        /// The output's flag.
        flag: String,
        /// The output as given.
        path: PathBuf,
        /// Why.
        #[source]
        source: OutputError,
    },
    /// A directory output exists and is not a directory.
    #[error("{flag} {}: exists and is not a directory", path.display())]
    NotADirectory {
        /// The output's flag.
        flag: String,
        /// The output as given.
        path: PathBuf,
    },
}

/// Refuses `outputs` when one of them (or a file written into an output directory) is one of
/// `inputs` or another output, when a file output exists and is not a regular file (after
/// following symlinks), or when a directory output exists and is not a directory or lies
/// inside an input directory. Reads metadata only.
pub fn check(outputs: &[Output], inputs: &[Input]) -> Result<(), GuardError> {
    // An input missing now is compared by place: `--npy Y --against Y` would otherwise write Y
    // and then read it back as the truth.
    let inputs: Vec<(&Input, Identity)> = inputs
        .iter()
        .map(|i| {
            (
                i,
                Identity::of(&i.path).unwrap_or_else(|| Identity::missing(&i.path)),
            )
        })
        .collect();
    let mut seen: Vec<(&Output, PathBuf)> = Vec::new();
    for output in outputs {
        let target = match output.kind {
            OutputKind::File => {
                output_target(&output.path).map_err(|source| GuardError::NotWritable {
                    flag: output.flag.clone(),
                    path: output.path.clone(),
                    source,
                })?
            }
            OutputKind::Directory => output.path.clone(),
        };
        if output.kind == OutputKind::Directory && target.exists() && !target.is_dir() {
            return Err(GuardError::NotADirectory {
                flag: output.flag.clone(),
                path: output.path.clone(),
            });
        }
        if let Some(input) = input_at(&target, &inputs) {
            return Err(GuardError::IsInput {
                flag: output.flag.clone(),
                output: output.path.clone(),
                role: input.role.clone(),
                input: input.path.clone(),
            });
        }
        check_outside(output, &inputs)?;
        if output.kind == OutputKind::Directory {
            check_directory(output, &inputs)?;
        }
        let place = location(&target);
        if let Some((other, _)) = seen.iter().find(|(_, p)| *p == place) {
            return Err(GuardError::SameOutput {
                flag: other.flag.clone(),
                output: other.path.clone(),
                other_flag: output.flag.clone(),
                other: output.path.clone(),
            });
        }
        seen.push((output, place));
    }
    Ok(())
}

/// The input that `path` is, or would be once written: the same file if it exists, or the
/// same place.
fn input_at<'a>(path: &Path, inputs: &[(&'a Input, Identity)]) -> Option<&'a Input> {
    let existing = Identity::of(path);
    let place = location(path);
    inputs
        .iter()
        .find(|(_, i)| existing.as_ref().is_some_and(|e| i.same_as(e)) || i.canonical == place)
        .map(|(input, _)| *input)
}

/// An output does not lie inside an input directory, whose files the command reads by listing
/// them: a `.shlm` written into the OBJ sequence it was baked from broke the next `train` on
/// that folder.
fn check_outside(output: &Output, inputs: &[(&Input, Identity)]) -> Result<(), GuardError> {
    let place = location(&output.path);
    match inputs
        .iter()
        .find(|(_, i)| i.is_dir && place.starts_with(&i.canonical))
    {
        Some((input, _)) => Err(GuardError::InsideInput {
            flag: output.flag.clone(),
            output: output.path.clone(),
            role: input.role.clone(),
            input: input.path.clone(),
        }),
        None => Ok(()),
    }
}

/// No file a directory output receives is an input.
fn check_directory(output: &Output, inputs: &[(&Input, Identity)]) -> Result<(), GuardError> {
    for file in &output.files {
        let written = output.path.join(file);
        if let Some(input) = input_at(&written, inputs) {
            return Err(GuardError::WritesInput {
                flag: output.flag.clone(),
                output: output.path.clone(),
                file: written,
                role: input.role.clone(),
                input: input.path.clone(),
            });
        }
    }
    Ok(())
}

/// What makes a file the file it is: where it is and, when it exists, its device and inode.
struct Identity {
    canonical: PathBuf,
    is_dir: bool,
    #[cfg(unix)]
    device_inode: Option<(u64, u64)>,
}

impl Identity {
    /// The identity of the file `path` names (following symlinks), if it exists.
    fn of(path: &Path) -> Option<Identity> {
        let meta = std::fs::metadata(path).ok()?;
        let canonical = std::fs::canonicalize(path).ok()?;
        Some(Identity {
            canonical,
            is_dir: meta.is_dir(),
            #[cfg(unix)]
            device_inode: {
                use std::os::unix::fs::MetadataExt;
                Some((meta.dev(), meta.ino()))
            },
        })
    }

    /// The identity of a file that does not exist: where it would be.
    fn missing(path: &Path) -> Identity {
        Identity {
            canonical: location(path),
            is_dir: false,
            #[cfg(unix)]
            device_inode: None,
        }
    }

    fn same_as(&self, other: &Identity) -> bool {
        #[cfg(unix)]
        if self.device_inode.is_some() && self.device_inode == other.device_inode {
            return true;
        }
        self.canonical == other.canonical
    }
}

/// Where `path` is or would be created: the canonical path of its nearest existing ancestor
/// joined with the rest, `.` dropped and `..` taken lexically (the missing directories will be
/// created as plain directories, so `..` after one is its parent).
fn location(path: &Path) -> PathBuf {
    let absolute = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    let parts: Vec<Component> = absolute.components().collect();
    for known in (1..=parts.len()).rev() {
        let prefix: PathBuf = parts[..known].iter().collect();
        if let Ok(mut resolved) = std::fs::canonicalize(&prefix) {
            for part in &parts[known..] {
                match part {
                    Component::ParentDir => {
                        resolved.pop();
                    }
                    Component::CurDir => {}
                    other => resolved.push(other),
                }
            }
            return resolved;
        }
    }
    absolute
}

/// The inputs an OBJ sequence directory stands for: the directory and every `.obj` file in it.
pub fn obj_sequence_inputs(dir: &Path) -> Vec<Input> {
    let mut inputs = vec![Input::new(dir, "the OBJ sequence directory")];
    let files = std::fs::read_dir(dir).into_iter().flatten().flatten();
    for path in files.map(|e| e.path()) {
        if path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("obj"))
        {
            inputs.push(Input::new(path, "a pose of the OBJ sequence"));
        }
    }
    inputs
}

/// The inputs a glTF file stands for: the file and the external files it references by a
/// relative path or `file:` URI (buffers and images), resolved as the importer resolves them.
/// A file that cannot be read or parsed stands for itself alone (the loader reports why).
pub fn gltf_inputs(path: &Path) -> Vec<Input> {
    let mut inputs = vec![Input::new(path, "the glTF file")];
    let Some(json) = gltf_json(path) else {
        return inputs;
    };
    let name = path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into(),
    );
    let base = path.parent().unwrap_or(Path::new(""));
    for (list, what) in [("buffers", "a buffer"), ("images", "an image")] {
        let items = json.get(list).and_then(|v| v.as_array());
        for uri in items
            .into_iter()
            .flatten()
            .filter_map(|b| b.get("uri")?.as_str())
        {
            if let Ok(file) = external_file(uri, Some(base)) {
                inputs.push(Input::new(file, format!("{what} of {name}")));
            }
        }
    }
    inputs
}

/// The JSON of a `.gltf` file, or the JSON chunk of a `.glb`; `None` when it is neither (the
/// loader will say why).
fn gltf_json(path: &Path) -> Option<serde_json::Value> {
    let bytes = read_input(path, InputKind::Gltf).ok()?;
    let (text, _) = gltf_split(&bytes).ok()?;
    serde_json::from_slice(text).ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn paths(inputs: Vec<Input>) -> Vec<PathBuf> {
        inputs.into_iter().map(|i| i.path).collect()
    }

    #[test]
    fn an_output_that_is_an_input_is_refused_however_it_is_spelled() {
        let dir = tempfile::tempdir().unwrap();
        let input = dir.path().join("same.obj");
        std::fs::write(&input, "v 0 0 0\n").unwrap();
        std::fs::create_dir(dir.path().join("sub")).unwrap();
        let inputs = [Input::new(&input, "the mesh")];
        let detour = dir.path().join("sub/../same.obj");
        let hard = dir.path().join("hard.obj");
        std::fs::hard_link(&input, &hard).unwrap();
        let mut spellings = vec![input.clone(), detour, hard];
        #[cfg(unix)]
        {
            let link = dir.path().join("link.npy");
            std::os::unix::fs::symlink("same.obj", &link).unwrap();
            spellings.push(link);
        }
        for output in spellings {
            let err = check(&[Output::file(&output, "--npy")], &inputs).unwrap_err();
            let message = err.to_string();
            assert!(matches!(err, GuardError::IsInput { .. }), "{message}");
            assert!(
                message.contains("that is the mesh") && message.contains("same.obj"),
                "{message}"
            );
        }
        let fresh = dir.path().join("out.npy");
        check(&[Output::file(&fresh, "--npy")], &inputs).unwrap();
    }

    /// Files written into a directory output are outputs too, compared where they would be
    /// created; a directory inside an input directory and an output at a missing input's
    /// place are refused.
    #[test]
    fn directory_outputs_are_compared_file_by_file() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let scene = d.join("report.md");
        std::fs::write(&scene, "[source]\n").unwrap();
        let inputs = [Input::new(&scene, "the scene file")];
        for out in [d.to_path_buf(), d.join("new/.."), d.join("new/./../.")] {
            let err = check(&[Output::directory(&out, "--out", &["report.md"])], &inputs);
            assert!(
                matches!(err, Err(GuardError::WritesInput { .. })),
                "{}: {err:?}",
                out.display()
            );
        }
        check(
            &[Output::directory(d.join("new"), "--out", &["report.md"])],
            &inputs,
        )
        .unwrap();
        let assets = [Input::new(d, "the assets directory")];
        let err = check(&[Output::directory(d.join("a/b"), "--out", &[])], &assets);
        assert!(
            matches!(err, Err(GuardError::InsideInput { .. })),
            "{err:?}"
        );
        let truth = d.join("missing.npy");
        let err = check(
            &[Output::file(d.join("x/../missing.npy"), "--npy")],
            &[Input::new(&truth, "--against")],
        );
        assert!(matches!(err, Err(GuardError::IsInput { .. })), "{err:?}");
    }

    #[test]
    fn two_outputs_at_one_place_are_refused_before_either_exists() {
        let dir = tempfile::tempdir().unwrap();
        let model = dir.path().join("m.aprt");
        let outputs = [
            Output::file(&model, "-o"),
            Output::directory(dir.path().join(".").join("m.aprt"), "--checkpoint", &[]),
        ];
        let err = check(&outputs, &[]).unwrap_err().to_string();
        assert!(err.contains("are the same path"), "{err}");
    }

    #[test]
    fn gltf_files_stand_for_their_external_files() {
        let dir = tempfile::tempdir().unwrap();
        let gltf = dir.path().join("c.gltf");
        std::fs::write(
            &gltf,
            r#"{"asset":{"version":"2.0"},"buffers":[{"uri":"my%20data.bin","byteLength":4},
               {"uri":"data:application/octet-stream;base64,AAAA","byteLength":3}],
               "images":[{"uri":"tex/skin.png"}]}"#,
        )
        .unwrap();
        assert_eq!(
            paths(gltf_inputs(&gltf)),
            [
                gltf.clone(),
                dir.path().join("my data.bin"),
                dir.path().join("tex/skin.png")
            ]
        );
        // A GLB's JSON chunk.
        let json = br#"{"buffers":[{"uri":"ext.bin","byteLength":1}]}"#;
        let mut glb = b"glTF".to_vec();
        glb.extend_from_slice(&2u32.to_le_bytes());
        glb.extend_from_slice(&(20 + json.len() as u32).to_le_bytes());
        glb.extend_from_slice(&(json.len() as u32).to_le_bytes());
        glb.extend_from_slice(b"JSON");
        glb.extend_from_slice(json);
        let path = dir.path().join("c.glb");
        std::fs::write(&path, glb).unwrap();
        assert_eq!(
            paths(gltf_inputs(&path)),
            [path.clone(), dir.path().join("ext.bin")]
        );
        // Unreadable or not JSON: the file alone.
        std::fs::write(&path, b"glTF\x02\0\0\0").unwrap();
        assert_eq!(gltf_inputs(&path).len(), 1);
    }
}
