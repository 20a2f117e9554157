//! Outputs appear whole or not at all: write a temporary file beside the target, then rename.
//!
//! - **Symbolic links are written through.** Renaming over a symlink would replace the link
//!   with a file and leave the file it names untouched; the target is the file the link (or
//!   chain of links) names, and the temporary goes beside that file.
//! - **Only regular files are replaced.** A named pipe, socket, device or directory given as
//!   an output is refused ([`OutputError::NotAFile`]): renaming over it would destroy it rather
//!   than write into it.
//! - **Temporaries are recognisable and never outlive the run.** Each is named
//!   `.<file name>.aprt-<pid>-<random>.tmp` beside the output. It is removed when the write
//!   fails, by [`clean_up_on_signals`]' handler on SIGINT, SIGTERM or SIGHUP, and, when the
//!   process was killed outright (SIGKILL, a crash, a power cut), by the next write to the
//!   same output, which removes the temporaries of that output whose process is gone. Files
//!   of any other name are never touched.

use std::collections::BTreeMap;
use std::ffi::OsStr;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard};

use crate::input::file_type_name;

/// Why a path cannot be written as an output.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// The path (or the file a symlink names) exists and is not a regular file.
    #[error(
        "{} is {kind}, not a regular file: outputs are written whole to a temporary file and renamed over the old one, which would destroy it; give the path of a file",
        path.display()
    )]
    NotAFile {
        /// The path, after following symlinks.
        path: PathBuf,
        /// What it is: `a directory`, `a named pipe (FIFO)`, `a socket`, `a device`.
        kind: &'static str,
    },
    /// Following the symlinks never reached a file (a loop, or a chain too long).
    #[error("{}: more than {MAX_LINKS} levels of symbolic links", path.display())]
    SymlinkLoop {
        /// The path given.
        path: PathBuf,
    },
    /// The path names a directory entry that cannot be a file (`/`, `..`).
    #[error("{} does not name a file", path.display())]
    NoFileName {
        /// The path given.
        path: PathBuf,
    },
}

impl From<OutputError> for std::io::Error {
    fn from(err: OutputError) -> std::io::Error {
        std::io::Error::new(std::io::ErrorKind::InvalidInput, err)
    }
}

/// Links followed before giving up, as Linux's `MAXSYMLINKS`.
const MAX_LINKS: usize = 40;

/// What a temporary's name ends with.
const TEMP_SUFFIX: &str = ".tmp";

/// Bytes of the output's file name kept in its temporaries' names, so that the whole name
/// stays within the 255 bytes file systems allow.
const NAME_IN_TEMP: usize = 96;

/// Writes `bytes` to `path` atomically: a crash or error leaves either the old file or none,
/// never a partial one. A symlink is written through to the file it names; anything else
/// that is not a regular file is refused with [`OutputError`] (inside the `io::Error`).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    write_whole(path, bytes, Publish::Replace).map(drop)
}

/// Writes `bytes` to `path` atomically unless a file is already there; returns whether this
/// call created it. For a file that several processes may create at the same moment, perhaps
/// on different machines sharing a volume (the manifest of a checkpoint that a bake farm's
/// shards share): exactly one creates it, and every other finds it whole and leaves it
/// alone. Unlike [`write_atomic`] it removes no stale temporaries, because a process id read
/// from a shared volume may name a live process on another machine.
pub fn write_new(path: &Path, bytes: &[u8]) -> std::io::Result<bool> {
    write_whole(path, bytes, Publish::IfAbsent)
}

/// How [`write_whole`] puts its temporary in place.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Publish {
    /// Over whatever is there, after removing the stale temporaries of the same output.
    Replace,
    /// Only where nothing is there.
    IfAbsent,
}

/// [`write_atomic`] and [`write_new`]: a temporary beside the target, renamed into place.
fn write_whole(path: &Path, bytes: &[u8], publish: Publish) -> std::io::Result<bool> {
    let target = output_target(path)?;
    let name = target
        .file_name()
        .ok_or_else(|| OutputError::NoFileName { path: path.into() })?;
    let dir = match target.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if publish == Publish::Replace {
        remove_stale_temporaries(dir, name);
    }
    let prefix = temp_prefix(name);
    let (mut tmp, _pending) = Pending::create(|| {
        tempfile::Builder::new()
            .prefix(&prefix)
            .suffix(TEMP_SUFFIX)
            .rand_bytes(6)
            .tempfile_in(dir)
    })?;
    tmp.write_all(bytes)?;
    // Temporary files are created private (0600); outputs are ordinary files.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        tmp.as_file()
            .set_permissions(std::fs::Permissions::from_mode(0o644))?;
    }
    tmp.as_file().sync_all()?;
    // The rename and the signal handler's clean-up exclude each other: once a signal is being
    // handled, this blocks until the process ends, so no output appears after it.
    let _lock = pending();
    match publish {
        Publish::Replace => tmp.persist(&target).map(drop),
        // A refused temporary is removed as the error drops it.
        Publish::IfAbsent => match tmp.persist_noclobber(&target) {
            Err(e) if e.error.kind() == std::io::ErrorKind::AlreadyExists => return Ok(false),
            persisted => persisted.map(drop),
        },
    }
    .map_err(|e| e.error)?;
    Ok(true)
}

/// The file a write to `path` replaces: `path` itself, or the file its symlinks name (which
/// may not exist yet). Errors when that exists and is not a regular file.
pub fn output_target(path: &Path) -> Result<PathBuf, OutputError> {
    let mut target = path.to_path_buf();
    for _ in 0..=MAX_LINKS {
        let Ok(meta) = std::fs::symlink_metadata(&target) else {
            // Missing (or unreadable, which the write will report): written as named.
            return Ok(target);
        };
        let kind = meta.file_type();
        if kind.is_file() {
            return Ok(target);
        }
        if !kind.is_symlink() {
            return Err(OutputError::NotAFile {
                path: target,
                kind: file_type_name(&kind),
            });
        }
        let Ok(link) = std::fs::read_link(&target) else {
            return Ok(target);
        };
        // A relative link is relative to the directory holding it.
        target = match target.parent() {
            Some(dir) => dir.join(link),
            None => link,
        };
    }
    Err(OutputError::SymlinkLoop { path: path.into() })
}

/// `.<name>.aprt-<pid>-`: the start of the name of every temporary this process writes for an
/// output called `name`.
fn temp_prefix(name: &OsStr) -> String {
    format!(".{}{MARK}{}-", name_part(name), std::process::id())
}

/// What separates the output's name from the process id in a temporary's name.
const MARK: &str = ".aprt-";

/// The output's name as its temporaries carry it: lossy UTF-8, cut to [`NAME_IN_TEMP`] bytes.
fn name_part(name: &OsStr) -> String {
    let mut name = name.to_string_lossy().into_owned();
    let mut end = name.len().min(NAME_IN_TEMP);
    while !name.is_char_boundary(end) {
        end -= 1;
    }
    name.truncate(end);
    name
}

/// The process id of `<pid>-<6 letters or digits>.tmp`, the end of a temporary's name.
fn owner_of_tail(tail: &str) -> Option<u32> {
    let (pid, random) = tail.strip_suffix(TEMP_SUFFIX)?.split_once('-')?;
    let random_ok = random.len() == 6 && random.bytes().all(|b| b.is_ascii_alphanumeric());
    let pid_ok = !pid.is_empty() && pid.bytes().all(|b| b.is_ascii_digit());
    if random_ok && pid_ok {
        pid.parse().ok()
    } else {
        None
    }
}

/// Whether `file_name` is a temporary of [`write_atomic`] (for any output), and if so the id
/// of the process that wrote it.
pub fn temporary_owner(file_name: &str) -> Option<u32> {
    let rest = file_name.strip_prefix('.')?;
    let (_, tail) = rest.rsplit_once(MARK)?;
    owner_of_tail(tail)
}

/// Removes the temporaries of the output called `name` in `dir` that an ended process left
/// behind. Best effort: what cannot be removed stays, and nothing else is touched. A directory
/// is listed on this process's first write into it only, and the stale temporaries found are
/// kept for the writes of their outputs: listing it on every write made a checkpoint of
/// thousands of pose files cost the square of their count.
fn remove_stale_temporaries(dir: &Path, name: &OsStr) {
    static STALE: Mutex<BTreeMap<PathBuf, Vec<PathBuf>>> = Mutex::new(BTreeMap::new());
    let mut stale = STALE
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner());
    let found = stale
        .entry(dir.to_path_buf())
        .or_insert_with(|| stale_temporaries(dir));
    let start = format!(".{}{MARK}", name_part(name));
    found.retain(|path| {
        let of_this_output = path
            .file_name()
            .and_then(OsStr::to_str)
            .and_then(|n| n.strip_prefix(&start))
            .and_then(owner_of_tail)
            .is_some();
        if of_this_output {
            let _ = std::fs::remove_file(path);
        }
        !of_this_output
    });
}

/// The temporaries in `dir`, of any output, whose process has ended.
fn stale_temporaries(dir: &Path) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    entries
        .flatten()
        .filter(|entry| {
            let pid = entry.file_name().to_str().and_then(temporary_owner);
            let is_file = entry.file_type().is_ok_and(|t| t.is_file());
            pid.is_some_and(|pid| is_file && process_gone(pid, entry))
        })
        .map(|entry| entry.path())
        .collect()
}

/// Whether the process that wrote a temporary has ended. Where `/proc` lists the live
/// processes, by its id; elsewhere a temporary untouched for a day counts as abandoned.
fn process_gone(pid: u32, entry: &std::fs::DirEntry) -> bool {
    if pid == std::process::id() {
        return false;
    }
    if Path::new("/proc/self").exists() {
        return !Path::new("/proc").join(pid.to_string()).exists();
    }
    entry
        .metadata()
        .and_then(|m| m.modified())
        .ok()
        .and_then(|t| t.elapsed().ok())
        .is_some_and(|age| age.as_secs() > 24 * 3600)
}

/// The temporaries being written now, for the signal handler to remove.
static PENDING: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn pending() -> MutexGuard<'static, Vec<PathBuf>> {
    PENDING
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// A temporary listed in [`PENDING`] while it exists.
struct Pending(PathBuf);

impl Pending {
    /// Creates a temporary with `create` and lists it, holding the list's lock throughout: a
    /// signal handled meanwhile waits, then finds the temporary listed and removes it.
    fn create(
        create: impl FnOnce() -> std::io::Result<tempfile::NamedTempFile>,
    ) -> std::io::Result<(tempfile::NamedTempFile, Pending)> {
        let mut list = pending();
        let tmp = create()?;
        list.push(tmp.path().to_owned());
        let listed = Pending(tmp.path().to_owned());
        Ok((tmp, listed))
    }
}

impl Drop for Pending {
    fn drop(&mut self) {
        let mut list = pending();
        if let Some(i) = list.iter().position(|p| *p == self.0) {
            list.swap_remove(i);
        }
    }
}

/// Removes every temporary being written and holds the lock, so no write can complete after
/// it; for a process about to end.
fn remove_pending_for_exit() -> MutexGuard<'static, Vec<PathBuf>> {
    let list = pending();
    for path in list.iter() {
        let _ = std::fs::remove_file(path);
    }
    list
}

/// Installs the handler that, on SIGINT, SIGTERM or SIGHUP, removes the temporaries being
/// written and then ends the process as the signal would have (a checkpoint of finished poses
/// stays, to resume from). A thread of its own waits for the signals; nothing else changes
/// until one arrives. Call once, at the start of the program. Elsewhere than Unix it does
/// nothing.
pub fn clean_up_on_signals() -> std::io::Result<()> {
    #[cfg(unix)]
    {
        use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
        let mut signals = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP])?;
        std::thread::Builder::new()
            .name("aprt-signals".into())
            .spawn(move || {
                if let Some(signal) = signals.forever().next() {
                    let _held = remove_pending_for_exit();
                    let _ = signal_hook::low_level::emulate_default_handler(signal);
                    std::process::exit(128 + signal);
                }
            })?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn replaces_the_file_whole_and_leaves_no_temporary() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.bin");
        write_atomic(&path, b"first").unwrap();
        write_atomic(&path, b"second").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"second");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            assert_eq!(
                std::fs::metadata(&path).unwrap().permissions().mode() & 0o777,
                0o644
            );
        }
    }

    /// The first writer creates the file; later ones leave it whole, even while a temporary
    /// of a process that has ended lies beside it (on a shared volume it may be another
    /// machine's, being written).
    #[test]
    fn a_new_file_is_created_once_and_never_replaced() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("manifest.json");
        let other = dir
            .path()
            .join(format!(".manifest.json.aprt-{}-abcdef.tmp", u32::MAX - 1));
        std::fs::write(&other, b"in flight").unwrap();
        assert!(write_new(&path, b"first").unwrap());
        assert!(!write_new(&path, b"second").unwrap());
        assert_eq!(std::fs::read(&path).unwrap(), b"first");
        assert!(other.exists());
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
    }

    #[test]
    fn temporaries_are_recognised_by_their_whole_name() {
        let prefix = temp_prefix(OsStr::new("out.npy"));
        let own = format!("{prefix}Ab3dE9{TEMP_SUFFIX}");
        assert_eq!(temporary_owner(&own), Some(std::process::id()));
        assert_eq!(temporary_owner(".out.npy.aprt-12-abcdef.tmp"), Some(12));
        assert_eq!(temporary_owner(".a-b.aprt-7.aprt-3-abcdef.tmp"), Some(3));
        for other in [
            "out.npy",
            ".tmpAbc123",
            ".out.npy.aprt-12-abcdef",
            ".out.npy.aprt-12-abcde.tmp",
            ".out.npy.aprt-x2-abcdef.tmp",
            ".out.npy.aprt--abcdef.tmp",
            "out.npy.aprt-12-abcdef.tmp",
            ".out.npy.aprt-12-abc_ef.tmp",
        ] {
            assert_eq!(temporary_owner(other), None, "{other}");
        }
    }

    #[test]
    fn long_names_keep_temporaries_within_the_file_name_limit() {
        let name = "é".repeat(120);
        let prefix = temp_prefix(OsStr::new(&name));
        assert!(prefix.len() + 6 + TEMP_SUFFIX.len() < 255);
        let dir = tempfile::tempdir().unwrap();
        write_atomic(&dir.path().join(&name), b"x").unwrap();
        assert_eq!(std::fs::read(dir.path().join(&name)).unwrap(), b"x");
    }

    /// A temporary of a process that has ended (an id no process has) is removed by the next
    /// write to the same output; one of a live process (this one's), one of another output and
    /// files of other names stay.
    #[cfg(target_os = "linux")]
    #[test]
    fn the_next_write_removes_stale_temporaries_of_its_output_only() {
        let dir = tempfile::tempdir().unwrap();
        let gone = u32::MAX - 1;
        let stale = format!(".out.npy.aprt-{gone}-abcdef.tmp");
        let keep = [
            format!(".out.npy.aprt-{}-abcdef.tmp", std::process::id()),
            format!(".other.npy.aprt-{gone}-abcdef.tmp"),
            ".tmpAbc123".to_owned(),
            ".out.npy.aprt-1-notes.txt".to_owned(),
        ];
        for name in keep.iter().chain([&stale]) {
            std::fs::write(dir.path().join(name), b"partial").unwrap();
        }
        write_atomic(&dir.path().join("out.npy"), b"whole").unwrap();
        assert!(!dir.path().join(&stale).exists());
        for name in &keep {
            assert!(dir.path().join(name).exists(), "{name}");
        }
    }

    #[cfg(unix)]
    #[test]
    fn a_symlink_is_written_through_and_a_directory_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let real = dir.path().join("real.bin");
        std::fs::write(&real, b"old").unwrap();
        let link = dir.path().join("link.bin");
        std::os::unix::fs::symlink("real.bin", &link).unwrap();
        write_atomic(&link, b"new").unwrap();
        assert!(
            std::fs::symlink_metadata(&link)
                .unwrap()
                .file_type()
                .is_symlink()
        );
        assert_eq!(std::fs::read(&real).unwrap(), b"new");
        // A dangling link creates the file it names.
        let dangling = dir.path().join("dangling.bin");
        std::os::unix::fs::symlink("made.bin", &dangling).unwrap();
        write_atomic(&dangling, b"made").unwrap();
        assert_eq!(std::fs::read(dir.path().join("made.bin")).unwrap(), b"made");
        // A loop.
        let a = dir.path().join("a");
        std::os::unix::fs::symlink("b", &a).unwrap();
        std::os::unix::fs::symlink("a", dir.path().join("b")).unwrap();
        let err = write_atomic(&a, b"x").unwrap_err();
        assert!(
            err.to_string().contains("levels of symbolic links"),
            "{err}"
        );
        // A directory.
        let sub = dir.path().join("sub");
        std::fs::create_dir(&sub).unwrap();
        let err = write_atomic(&sub, b"x").unwrap_err();
        assert!(
            err.to_string()
                .contains("is a directory, not a regular file"),
            "{err}"
        );
        assert!(sub.is_dir());
        let names: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect();
        assert!(!names.iter().any(|n| n.ends_with(TEMP_SUFFIX)), "{names:?}");
    }
}
