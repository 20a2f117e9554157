//! Nothing lost: a long bake checkpoints every finished pose, and a resumed bake is
//! bit-identical to an uninterrupted one.
//!
//! A checkpoint is a directory holding `manifest.json` (bake settings, vertex and triangle
//! counts, and a CRC-32 fingerprint of every pose's mesh) and one `pose-NNNNNN.bin` per finished
//! pose. Every file is written with [`write_atomic`], so a kill at any moment leaves whole
//! files only and loses at most the pose being baked. Resuming re-fingerprints the inputs and
//! refuses a checkpoint made from other meshes or other settings, because mixing transfers
//! baked under different conditions would silently corrupt the model. Model options (fit,
//! precision) are not part of the manifest: the baked transfer does not depend on them, so a
//! resume may change them.
//!
//! The bake itself is unchanged: each missing pose goes through its [`BakeTarget`] (for
//! vertices [`crate::bake::bake_pose_progress`], the same code path as
//! [`crate::bake::bake_poses`]; for a light map the texels of its atlas), and stored poses are
//! read back as the exact f32 bits that were written.
//!
//! Shards of a bake farm ([`crate::bake::shard`]) share one checkpoint, perhaps from several
//! machines at once on a shared volume: the manifest depends only on the inputs and settings,
//! so every shard writes the same bytes, and it is created with [`write_new`] (the first
//! shard's appears whole, the others find it and compare); each pose file has one shard
//! that writes it; and a shard never removes the checkpoint ([`Checkpoint::bake_shard`]). The
//! shards' directories may equally be baked apart and copied together: a pose file is the
//! same wherever it was baked.

use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::bake::shard::Shard;
use crate::bake::{BakeError, BakeSettings, bake_pose_progress};
use crate::input::{InputError, InputKind, read_input, read_input_text};
use crate::io::atomic::{write_atomic, write_new};
use crate::progress::{BakeProgress, Reporter};
use crate::rig::mesh::Mesh;

/// What every pose of a checkpoint is baked at: its vertices, or other points of its surface
/// (the texels of a light map). The description goes into the manifest, so a resume at other
/// points is refused.
pub trait BakeTarget: Sync {
    /// One line naming the points, equal for equal targets (for example the atlas's resolution
    /// and a fingerprint of its UVs).
    fn describe(&self) -> String;
    /// Points baked per pose of `mesh` (the unit of progress; `order²` values each).
    fn points(&self, mesh: &Mesh) -> usize;
    /// The transfer at the points on posed `mesh`, advancing `progress` by one per point.
    fn bake(
        &self,
        mesh: &Mesh,
        settings: &BakeSettings,
        progress: &dyn BakeProgress,
    ) -> Result<Vec<f32>, BakeError>;
}

/// Every vertex of every pose: what `aprt train` bakes.
pub struct Vertices;

impl BakeTarget for Vertices {
    fn describe(&self) -> String {
        "vertices".to_owned()
    }

    fn points(&self, mesh: &Mesh) -> usize {
        mesh.vertex_count()
    }

    fn bake(
        &self,
        mesh: &Mesh,
        settings: &BakeSettings,
        progress: &dyn BakeProgress,
    ) -> Result<Vec<f32>, BakeError> {
        bake_pose_progress(mesh, settings, progress)
    }
}

fn vertices_target() -> String {
    Vertices.describe()
}

/// Version of the manifest and pose-file layout; a checkpoint of another version is refused.
const FORMAT: u32 = 1;
const MANIFEST: &str = "manifest.json";
const POSE_MAGIC: &[u8; 8] = b"APRTPOSE";
/// Magic, payload CRC-32, value count.
const POSE_HEADER: usize = 8 + 4 + 8;

/// Why a checkpointed bake stopped.
#[derive(Debug, thiserror::Error)]
pub enum CheckpointError {
    /// A checkpoint file or directory could not be read, written or removed.
    #[error("checkpoint {}", path.display())]
    Io {
        /// The file or directory.
        path: PathBuf,
        /// What the operating system said.
        #[source]
        source: std::io::Error,
    },
    /// A checkpoint file is not a regular file, too large or unreadable (the error says which).
    #[error(transparent)]
    Input(#[from] InputError),
    /// A checkpoint exists and `--resume` was not given.
    #[error(
        "{} holds the checkpoint of an unfinished bake: pass --resume to continue it, or delete the directory to start over",
        dir.display()
    )]
    Exists {
        /// The checkpoint directory.
        dir: PathBuf,
    },
    /// The directory exists, is not empty and has no manifest: not ours to fill or delete.
    #[error(
        "{} is not empty and holds no {MANIFEST}: not a checkpoint directory",
        dir.display()
    )]
    NotACheckpoint {
        /// The directory.
        dir: PathBuf,
    },
    /// The manifest cannot be parsed.
    #[error("{}: unreadable manifest: {reason}", path.display())]
    BadManifest {
        /// The manifest file.
        path: PathBuf,
        /// The parser's message.
        reason: String,
    },
    /// The checkpoint was made from other inputs or settings.
    #[error(
        "cannot resume from {}: {what} (checkpoint: {was}, now: {now}); rerun with the original inputs and settings, or delete the directory to start over",
        dir.display()
    )]
    Mismatch {
        /// The checkpoint directory.
        dir: PathBuf,
        /// What differs.
        what: String,
        /// Its value in the checkpoint.
        was: String,
        /// Its value now.
        now: String,
    },
    /// A pose could not be baked.
    #[error("{name}: baking")]
    Bake {
        /// The pose's name.
        name: String,
        /// The bake's error.
        #[source]
        source: BakeError,
    },
}

/// What one shard of a bake farm did ([`Checkpoint::bake_shard`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ShardBaked {
    /// The shard.
    pub shard: Shard,
    /// Its frames it baked now.
    pub baked: usize,
    /// Its frames that were already in the checkpoint (from an earlier attempt of the shard).
    pub resumed: usize,
    /// Frames of every shard in the checkpoint now.
    pub stored: usize,
    /// Frames of the whole bake.
    pub frames: usize,
    /// The checkpoint directory.
    pub dir: PathBuf,
}

impl std::fmt::Display for ShardBaked {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "shard {} baked {} of its {} frames ({} were already there); {} of {} frames are now in {}",
            self.shard,
            self.baked,
            self.baked + self.resumed,
            self.resumed,
            self.stored,
            self.frames,
            self.dir.display()
        )
    }
}

/// What [`Checkpoint::open`] does with a checkpoint that is already there.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OnExisting {
    /// Continue its bake, if it was made from the same meshes and settings (`--resume`).
    Resume,
    /// Refuse it rather than overwrite it: it may hold hours of work.
    Refuse,
}

/// What a checkpoint was made from; a resume must match it field for field.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
struct Manifest {
    format: u32,
    order: usize,
    rays: usize,
    bounces: usize,
    albedo: f32,
    /// Checkpoints from before shadowless bakes always cast shadows.
    #[serde(default = "casts_shadows")]
    shadows: bool,
    vertices: usize,
    triangles: usize,
    /// [`BakeTarget::describe`]; checkpoints from before light maps baked vertices.
    #[serde(default = "vertices_target")]
    target: String,
    /// CRC-32 of each pose's positions, normals and triangles, as hex.
    poses: Vec<String>,
}

fn casts_shadows() -> bool {
    true
}

impl Manifest {
    fn new(settings: &BakeSettings, meshes: &[Mesh], target: &dyn BakeTarget) -> Manifest {
        let first = meshes.first();
        Manifest {
            format: FORMAT,
            order: settings.order,
            rays: settings.rays,
            bounces: settings.bounces,
            albedo: settings.albedo,
            shadows: settings.shadows,
            vertices: first.map_or(0, Mesh::vertex_count),
            triangles: first.map_or(0, |m| m.triangles.len()),
            target: target.describe(),
            poses: meshes.iter().map(fingerprint).collect(),
        }
    }

    /// The first field that differs, as (what, was, now).
    fn difference(&self, now: &Manifest) -> Option<(String, String, String)> {
        let fields: [(&str, String, String); 9] = [
            ("format", self.format.to_string(), now.format.to_string()),
            ("SH order", self.order.to_string(), now.order.to_string()),
            ("rays", self.rays.to_string(), now.rays.to_string()),
            ("bounces", self.bounces.to_string(), now.bounces.to_string()),
            ("albedo", self.albedo.to_string(), now.albedo.to_string()),
            ("shadows", self.shadows.to_string(), now.shadows.to_string()),
            (
                "vertices",
                self.vertices.to_string(),
                now.vertices.to_string(),
            ),
            (
                "triangles",
                self.triangles.to_string(),
                now.triangles.to_string(),
            ),
            ("baked points", self.target.clone(), now.target.clone()),
        ];
        if let Some((what, was, now)) = fields.into_iter().find(|(_, a, b)| a != b) {
            return Some((what.to_owned(), was, now));
        }
        if self.poses.len() != now.poses.len() {
            return Some((
                "pose count".to_owned(),
                self.poses.len().to_string(),
                now.poses.len().to_string(),
            ));
        }
        let i = (0..self.poses.len()).find(|&i| self.poses[i] != now.poses[i])?;
        Some((
            format!("the mesh of pose {i} differs"),
            format!("fingerprint {}", self.poses[i]),
            format!("fingerprint {}", now.poses[i]),
        ))
    }
}

/// CRC-32 of everything the bake reads from a mesh.
fn fingerprint(mesh: &Mesh) -> String {
    let mut h = crc32fast::Hasher::new();
    for x in mesh.positions.iter().chain(&mesh.normals).flatten() {
        h.update(&x.to_le_bytes());
    }
    for i in mesh.triangles.iter().flatten() {
        h.update(&i.to_le_bytes());
    }
    format!("{:08x}", h.finalize())
}

/// The error of an operation on `path`.
fn io(path: &Path) -> impl FnOnce(std::io::Error) -> CheckpointError {
    let path = path.to_owned();
    move |source| CheckpointError::Io { path, source }
}

/// Whether a file called `name` is one a checkpoint writes: the manifest, a pose file, or a
/// temporary of an interrupted or ongoing write (of this or an earlier version).
fn checkpoint_file(name: &str) -> bool {
    name == MANIFEST
        || (name.starts_with("pose-") && name.ends_with(".bin"))
        || crate::io::atomic::temporary_owner(name).is_some()
        || name.starts_with(".tmp")
}

/// Starts a checkpoint in `dir` by writing its manifest `json`, unless a process sharing the
/// directory (a shard started at the same moment) has just written one; returns whether this
/// call did. The directory is created if missing; one holding anything but a manifest and
/// temporaries (which may be another shard's manifest being written) is not ours to fill.
fn start(dir: &Path, json: &[u8]) -> Result<bool, CheckpointError> {
    let manifest_path = dir.join(MANIFEST);
    match std::fs::read_dir(dir) {
        Ok(entries) => {
            let foreign = entries.flatten().any(|e| {
                let name = e.file_name();
                let name = name.to_str().unwrap_or("");
                name != MANIFEST && crate::io::atomic::temporary_owner(name).is_none()
            });
            // Pose files appear only after a manifest, which the listing may have missed.
            if foreign && !manifest_path.exists() {
                return Err(CheckpointError::NotACheckpoint { dir: dir.into() });
            }
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            std::fs::create_dir_all(dir).map_err(io(dir))?;
        }
        Err(e) => return Err(io(dir)(e)),
    }
    write_new(&manifest_path, json).map_err(io(&manifest_path))
}

/// An open checkpoint directory whose manifest matches the current inputs.
#[derive(Debug)]
pub struct Checkpoint {
    dir: PathBuf,
    settings: BakeSettings,
    manifest: Manifest,
    /// Whether any pose file is in the directory (from an earlier run or this one).
    holds_poses: bool,
    /// Whether [`Checkpoint::open`] started it (no checkpoint was there).
    created: bool,
}

impl Checkpoint {
    /// The default checkpoint directory of a model written to `output`: `OUTPUT.bake` beside it.
    pub fn default_dir(output: &Path) -> PathBuf {
        let mut name = output.as_os_str().to_owned();
        name.push(".bake");
        PathBuf::from(name)
    }

    /// Opens the checkpoint in `dir` for baking `meshes` with `settings`.
    ///
    /// A missing (or empty) directory starts a new checkpoint whatever `existing` says, so
    /// scripts may always pass `--resume`. An existing checkpoint is continued only with
    /// [`OnExisting::Resume`], and only if it was made from the same meshes and settings; with
    /// [`OnExisting::Refuse`] it is an error rather than overwritten, because it may hold hours
    /// of work. Processes may open one directory at the same moment (a bake farm's shards
    /// with `Resume`): exactly one of them writes the manifest, and the others compare it.
    pub fn open(
        dir: &Path,
        existing: OnExisting,
        settings: &BakeSettings,
        meshes: &[Mesh],
    ) -> Result<Self, CheckpointError> {
        Self::open_at(dir, existing, settings, meshes, &Vertices)
    }

    /// [`Checkpoint::open`] for baking `meshes` at the points of `target`.
    pub fn open_at(
        dir: &Path,
        existing: OnExisting,
        settings: &BakeSettings,
        meshes: &[Mesh],
        target: &dyn BakeTarget,
    ) -> Result<Self, CheckpointError> {
        settings
            .validate()
            .map_err(|source| CheckpointError::Bake {
                name: "settings".to_owned(),
                source,
            })?;
        let manifest = Manifest::new(settings, meshes, target);
        let manifest_path = dir.join(MANIFEST);
        let json = serde_json::to_vec_pretty(&manifest).expect("manifest serialises");
        let created = !manifest_path.exists() && start(dir, &json)?;
        if !created {
            if existing == OnExisting::Refuse {
                return Err(CheckpointError::Exists { dir: dir.into() });
            }
            let text = read_input_text(&manifest_path, InputKind::Checkpoint)?;
            let stored: Manifest =
                serde_json::from_str(&text).map_err(|e| CheckpointError::BadManifest {
                    path: manifest_path.clone(),
                    reason: e.to_string(),
                })?;
            if let Some((what, was, now)) = stored.difference(&manifest) {
                return Err(CheckpointError::Mismatch {
                    dir: dir.into(),
                    what,
                    was,
                    now,
                });
            }
        }
        Ok(Checkpoint {
            dir: dir.into(),
            settings: *settings,
            manifest,
            holds_poses: !created,
            created,
        })
    }

    /// Whether [`Checkpoint::open`] started this checkpoint, there being none to resume.
    pub fn is_new(&self) -> bool {
        self.created
    }

    fn pose_path(&self, pose: usize) -> PathBuf {
        self.dir.join(format!("pose-{pose:06}.bin"))
    }

    /// Pose `pose`'s stored transfer, if a whole, uncorrupted file of `len` values is there.
    /// A damaged file (only possible through disk faults: writes are atomic) is reported to
    /// `reporter` and baked again.
    fn load(
        &self,
        pose: usize,
        len: usize,
        reporter: &dyn Reporter,
    ) -> Result<Option<Vec<f32>>, CheckpointError> {
        let path = self.pose_path(pose);
        let bytes = match read_input(&path, InputKind::Checkpoint) {
            Ok(b) => b,
            Err(e) if e.is_missing() => return Ok(None),
            Err(e) => return Err(e.into()),
        };
        let payload = bytes.get(POSE_HEADER..).unwrap_or_default();
        let whole = bytes.len() == POSE_HEADER + 4 * len
            && &bytes[..8] == POSE_MAGIC
            && bytes[8..12] == crc32fast::hash(payload).to_le_bytes()
            && bytes[12..20] == (len as u64).to_le_bytes();
        if !whole {
            reporter.note(&format!(
                "aprt: {} is damaged; baking it again",
                path.display()
            ));
            return Ok(None);
        }
        Ok(Some(
            payload
                .chunks_exact(4)
                .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                .collect(),
        ))
    }

    fn store(&self, pose: usize, transfer: &[f32]) -> Result<(), CheckpointError> {
        let payload: Vec<u8> = transfer.iter().flat_map(|x| x.to_le_bytes()).collect();
        let mut bytes = Vec::with_capacity(POSE_HEADER + payload.len());
        bytes.extend_from_slice(POSE_MAGIC);
        bytes.extend_from_slice(&crc32fast::hash(&payload).to_le_bytes());
        bytes.extend_from_slice(&(transfer.len() as u64).to_le_bytes());
        bytes.extend_from_slice(&payload);
        let path = self.pose_path(pose);
        write_atomic(&path, &bytes).map_err(|source| CheckpointError::Io { path, source })
    }

    /// The transfer of every pose of `meshes` (the meshes the checkpoint was opened for,
    /// checked again by fingerprint): stored poses are read back, missing ones baked one after
    /// the other and stored as soon as each is done. Equal, bit for bit, to
    /// [`crate::bake::bake_poses`] on the same meshes. A pose that fails to bake is named
    /// `name(i)` in the error. Progress, damaged pose files and the number of poses resumed go
    /// to `reporter`.
    ///
    /// If the bake fails before any pose is stored, the checkpoint is removed again: it holds
    /// nothing worth resuming, and a failed run should leave no trace.
    pub fn bake(
        &mut self,
        meshes: &[Mesh],
        name: impl Fn(usize) -> String,
        reporter: &dyn Reporter,
    ) -> Result<Vec<Vec<f32>>, CheckpointError> {
        self.bake_at(meshes, &Vertices, name, reporter)
    }

    /// [`Checkpoint::bake`] at the points of `target`, the one the checkpoint was opened for.
    pub fn bake_at(
        &mut self,
        meshes: &[Mesh],
        target: &dyn BakeTarget,
        name: impl Fn(usize) -> String,
        reporter: &dyn Reporter,
    ) -> Result<Vec<Vec<f32>>, CheckpointError> {
        Ok(self.bake_at_timed(meshes, target, name, reporter)?.0)
    }

    /// [`Checkpoint::bake_at`], with the wall-clock seconds each pose took in this run (its
    /// bake and storing it): 0 for a pose read back from the checkpoint.
    pub fn bake_at_timed(
        &mut self,
        meshes: &[Mesh],
        target: &dyn BakeTarget,
        name: impl Fn(usize) -> String,
        reporter: &dyn Reporter,
    ) -> Result<(Vec<Vec<f32>>, Vec<f64>), CheckpointError> {
        let result = self.bake_inner(meshes, target, name, reporter);
        if result.is_err() && !self.holds_poses {
            // Best effort: the original error is the one worth reporting.
            let _ = self.remove();
        }
        result
    }

    fn bake_inner(
        &mut self,
        meshes: &[Mesh],
        target: &dyn BakeTarget,
        name: impl Fn(usize) -> String,
        reporter: &dyn Reporter,
    ) -> Result<(Vec<Vec<f32>>, Vec<f64>), CheckpointError> {
        let count = meshes.len();
        let mut out = Vec::with_capacity(count);
        let mut seconds = Vec::with_capacity(count);
        let all = |_| true;
        let keep = |t, s| {
            out.push(t);
            seconds.push(s);
        };
        let resumed = self.bake_where(meshes, target, all, name, reporter, keep)?;
        if resumed > 0 {
            reporter.note(&format!(
                "resumed {resumed} of {count} poses from {}",
                self.dir.display()
            ));
        }
        Ok((out, seconds))
    }

    /// Shard `shard`'s share of the poses of `meshes` at the points of `target` (the meshes
    /// and target the checkpoint was opened for): those not yet stored are baked, exactly as
    /// [`Checkpoint::bake_at`] bakes them, and stored; nothing is kept in memory.
    ///
    /// Other shards may be baking into the same directory at the same moment, so a shard
    /// writes only its own pose files and, unlike [`Checkpoint::bake_at`], never removes the
    /// checkpoint, even when its bake fails: other shards' poses may be in it.
    pub fn bake_shard(
        &mut self,
        meshes: &[Mesh],
        target: &dyn BakeTarget,
        shard: Shard,
        name: impl Fn(usize) -> String,
        reporter: &dyn Reporter,
    ) -> Result<ShardBaked, CheckpointError> {
        let mine = |i| shard.holds(i);
        let resumed = self.bake_where(meshes, target, mine, name, reporter, |_, _| {})?;
        let frames = meshes.len();
        Ok(ShardBaked {
            shard,
            baked: shard.share(frames) - resumed,
            resumed,
            stored: (0..frames).filter(|&i| self.pose_path(i).exists()).count(),
            frames,
            dir: self.dir.clone(),
        })
    }

    /// The poses of `meshes` that `selected` picks, in order, each handed to `keep` with the
    /// seconds it took: stored ones read back (0 s), missing ones baked and stored as soon as
    /// each is done. Returns how many were read back.
    fn bake_where(
        &mut self,
        meshes: &[Mesh],
        target: &dyn BakeTarget,
        selected: impl Fn(usize) -> bool,
        name: impl Fn(usize) -> String,
        reporter: &dyn Reporter,
        mut keep: impl FnMut(Vec<f32>, f64),
    ) -> Result<usize, CheckpointError> {
        let count = meshes.len();
        self.check_count(count)?;
        let described = target.describe();
        if described != self.manifest.target {
            return Err(CheckpointError::Mismatch {
                dir: self.dir.clone(),
                what: "baked points".to_owned(),
                was: self.manifest.target.clone(),
                now: described,
            });
        }
        let (mut progress, mut resumed) = (None, 0);
        for (i, mesh) in meshes.iter().enumerate().filter(|&(i, _)| selected(i)) {
            self.check_mesh(i, mesh)?;
            let points = target.points(mesh);
            let len = points * self.settings.order * self.settings.order;
            if let Some(stored) = self.load(i, len, reporter)? {
                resumed += 1;
                keep(stored, 0.0);
                continue;
            }
            let started = Instant::now();
            let progress = progress.get_or_insert_with(|| {
                let left = (i..count).filter(|&j| selected(j)).count();
                reporter.bake_progress(points * left)
            });
            progress.pose(i, count);
            let transfer = target
                .bake(mesh, &self.settings, progress.as_ref())
                .map_err(|source| CheckpointError::Bake {
                    name: name(i),
                    source,
                })?;
            self.store(i, &transfer)?;
            self.holds_poses = true;
            keep(transfer, started.elapsed().as_secs_f64());
        }
        if let Some(progress) = progress {
            progress.finish();
        }
        Ok(resumed)
    }

    /// The meshes given to [`Checkpoint::bake`] must be the ones the checkpoint was opened for.
    fn check_count(&self, count: usize) -> Result<(), CheckpointError> {
        let stored = self.manifest.poses.len();
        if count == stored {
            return Ok(());
        }
        Err(CheckpointError::Mismatch {
            dir: self.dir.clone(),
            what: "pose count".to_owned(),
            was: stored.to_string(),
            now: count.to_string(),
        })
    }

    fn check_mesh(&self, pose: usize, mesh: &Mesh) -> Result<(), CheckpointError> {
        let now = fingerprint(mesh);
        if now == self.manifest.poses[pose] {
            return Ok(());
        }
        Err(CheckpointError::Mismatch {
            dir: self.dir.clone(),
            what: format!("the mesh of pose {pose} differs"),
            was: format!("fingerprint {}", self.manifest.poses[pose]),
            now: format!("fingerprint {now}"),
        })
    }

    /// Deletes the checkpoint once its poses are safely in the model. Only the files a
    /// checkpoint holds are removed (the manifest, pose files, temporaries of interrupted
    /// writes), then the directory if that left it empty: a directory named with
    /// `--checkpoint` may hold other files, and those are the user's.
    pub fn remove(&self) -> Result<(), CheckpointError> {
        for entry in std::fs::read_dir(&self.dir).map_err(io(&self.dir))? {
            let path = entry.map_err(io(&self.dir))?.path();
            let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("");
            if checkpoint_file(name) {
                std::fs::remove_file(&path).map_err(io(&path))?;
            }
        }
        match std::fs::remove_dir(&self.dir) {
            Ok(()) => Ok(()),
            Err(e) if e.kind() == std::io::ErrorKind::DirectoryNotEmpty => Ok(()),
            Err(e) => Err(io(&self.dir)(e)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bake::bake_poses;
    use crate::progress::Silent;

    fn meshes(n: usize) -> Vec<Mesh> {
        (0..n)
            .map(|i| {
                let h = 0.5 + 0.1 * i as f32;
                Mesh::with_area_weighted_normals(
                    vec![
                        [-1.0, -1.0, 0.0],
                        [1.0, -1.0, 0.0],
                        [1.0, 1.0, 0.0],
                        [-1.0, 1.0, 0.0],
                        [-0.3, -0.3, h],
                        [0.3, -0.3, h],
                        [0.0, 0.3, h],
                    ],
                    vec![[0, 1, 2], [0, 2, 3], [4, 6, 5]],
                )
            })
            .collect()
    }

    fn pose_name(i: usize) -> String {
        format!("pose {i}")
    }

    const SETTINGS: BakeSettings = BakeSettings {
        order: 3,
        rays: 64,
        bounces: 1,
        albedo: 0.5,
        shadows: true,
    };

    #[test]
    fn resumed_bake_equals_the_uninterrupted_one() {
        let dir = tempfile::tempdir().unwrap();
        let ck = dir.path().join("m.aprt.bake");
        let poses = meshes(4);
        let reference = bake_poses(&poses, &SETTINGS, &Silent).unwrap();

        // As if interrupted: pose 1's file is missing.
        let mut first = Checkpoint::open(&ck, OnExisting::Refuse, &SETTINGS, &poses).unwrap();
        assert_eq!(first.bake(&poses, pose_name, &Silent).unwrap(), reference);
        std::fs::remove_file(ck.join("pose-000001.bin")).unwrap();
        // A damaged pose file is baked again, not trusted.
        std::fs::write(ck.join("pose-000000.bin"), b"APRTPOSE").unwrap();

        assert!(matches!(
            Checkpoint::open(&ck, OnExisting::Refuse, &SETTINGS, &poses),
            Err(CheckpointError::Exists { .. })
        ));
        let mut resumed = Checkpoint::open(&ck, OnExisting::Resume, &SETTINGS, &poses).unwrap();
        assert_eq!(resumed.bake(&poses, pose_name, &Silent).unwrap(), reference);
        // Every pose is now stored; a second resume bakes nothing and reads the same bits.
        let mut again = Checkpoint::open(&ck, OnExisting::Resume, &SETTINGS, &poses).unwrap();
        assert_eq!(again.bake(&poses, pose_name, &Silent).unwrap(), reference);
        again.remove().unwrap();
        assert!(!ck.exists());
    }

    #[test]
    fn other_inputs_or_settings_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let ck = dir.path().join("ck");
        let poses = meshes(3);
        Checkpoint::open(&ck, OnExisting::Refuse, &SETTINGS, &poses).unwrap();
        let refused = |settings: BakeSettings, poses: &[Mesh], what: &str| {
            let err = Checkpoint::open(&ck, OnExisting::Resume, &settings, poses).unwrap_err();
            let message = err.to_string();
            assert!(
                matches!(err, CheckpointError::Mismatch { .. }) && message.contains(what),
                "{message}"
            );
        };
        refused(
            BakeSettings {
                rays: 65,
                ..SETTINGS
            },
            &poses,
            "rays (checkpoint: 64, now: 65)",
        );
        refused(
            BakeSettings {
                order: 2,
                ..SETTINGS
            },
            &poses,
            "SH order",
        );
        refused(
            BakeSettings {
                albedo: 0.6,
                ..SETTINGS
            },
            &poses,
            "albedo",
        );

        refused(SETTINGS, &poses[..2], "pose count");
        let mut moved = poses.clone();
        moved[2].positions[4][2] += 1e-6;
        refused(SETTINGS, &moved, "the mesh of pose 2 differs");
        // The matching inputs still resume, and baking other inputs through it is refused.
        let mut c = Checkpoint::open(&ck, OnExisting::Resume, &SETTINGS, &poses).unwrap();
        assert!(matches!(
            c.bake(&moved[..], pose_name, &Silent),
            Err(CheckpointError::Mismatch { .. })
        ));
        assert!(c.bake(&poses[..2], pose_name, &Silent).is_err());
    }

    #[test]
    fn foreign_directories_are_neither_filled_nor_deleted() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("notes.txt"), "mine").unwrap();
        let poses = meshes(1);
        assert!(matches!(
            Checkpoint::open(dir.path(), OnExisting::Resume, &SETTINGS, &poses),
            Err(CheckpointError::NotACheckpoint { .. })
        ));
        // An empty directory named by the user is used, and on removal only our files go.
        let ck = dir.path().join("empty");
        std::fs::create_dir(&ck).unwrap();
        let mut c = Checkpoint::open(&ck, OnExisting::Refuse, &SETTINGS, &poses).unwrap();
        c.bake(&poses, pose_name, &Silent).unwrap();
        std::fs::write(ck.join("keep.txt"), "mine").unwrap();
        c.remove().unwrap();
        let left: Vec<_> = std::fs::read_dir(&ck)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(left, ["keep.txt"]);
    }

    #[test]
    fn a_bake_that_fails_before_storing_anything_leaves_no_checkpoint() {
        let dir = tempfile::tempdir().unwrap();
        let ck = dir.path().join("ck");
        let mut poses = meshes(2);
        poses[0].positions[0] = [2e12, 0.0, 0.0];
        let mut c = Checkpoint::open(&ck, OnExisting::Refuse, &SETTINGS, &poses).unwrap();
        let err = c.bake(&poses, pose_name, &Silent).unwrap_err();
        let message = format!("{:#}", anyhow::Error::from(err));
        assert!(
            message.starts_with("pose 0: baking: mesh extent"),
            "{message}"
        );
        assert!(!ck.exists());
    }

    /// Three shards started at the same moment into one directory: one of them writes the
    /// manifest, every one bakes only its own poses, and the merged checkpoint reads back as
    /// the unsharded bake. A shard never removes what others stored.
    #[test]
    fn concurrent_shards_fill_one_checkpoint_with_the_unsharded_bake() {
        let dir = tempfile::tempdir().unwrap();
        let ck = dir.path().join("ck");
        let poses = meshes(7);
        let reference = bake_poses(&poses, &SETTINGS, &Silent).unwrap();
        let baked: Vec<ShardBaked> = std::thread::scope(|scope| {
            let shards: Vec<_> = (0..3)
                .map(|i| {
                    let (ck, poses) = (&ck, &poses);
                    scope.spawn(move || {
                        let shard = Shard::new(i, 3).unwrap();
                        let mut c =
                            Checkpoint::open(ck, OnExisting::Resume, &SETTINGS, poses).unwrap();
                        c.bake_shard(poses, &Vertices, shard, pose_name, &Silent)
                            .unwrap()
                    })
                })
                .collect();
            shards.into_iter().map(|s| s.join().unwrap()).collect()
        });
        let own: Vec<usize> = baked.iter().map(|b| b.baked).collect();
        assert_eq!(own, [3, 2, 2]);
        assert!(baked.iter().all(|b| b.frames == 7 && b.resumed == 0));
        assert_eq!(baked.iter().map(|b| b.stored).max(), Some(7));
        let names: Vec<String> = std::fs::read_dir(&ck)
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect();
        assert_eq!(names.len(), 8, "{names:?}");
        // A failing shard (other meshes) leaves the others' poses alone.
        let mut moved = poses.clone();
        moved[0].positions[4][2] += 1e-3;
        assert!(Checkpoint::open(&ck, OnExisting::Resume, &SETTINGS, &moved).is_err());
        let mut all = Checkpoint::open(&ck, OnExisting::Resume, &SETTINGS, &poses).unwrap();
        assert_eq!(all.bake(&poses, pose_name, &Silent).unwrap(), reference);
    }

    /// Points other than the vertices (a light map's texels): a checkpoint made for one set
    /// of points is refused for another, and resumes bit-identically for the same.
    #[test]
    fn a_checkpoint_remembers_which_points_it_bakes() {
        struct Centroids;
        impl BakeTarget for Centroids {
            fn describe(&self) -> String {
                "triangle centroids".to_owned()
            }
            fn points(&self, mesh: &Mesh) -> usize {
                mesh.triangles.len()
            }
            fn bake(
                &self,
                mesh: &Mesh,
                settings: &BakeSettings,
                progress: &dyn BakeProgress,
            ) -> Result<Vec<f32>, BakeError> {
                let at = |t: &[u32; 3], k: usize| {
                    t.iter()
                        .map(|&i| mesh.positions[i as usize][k])
                        .sum::<f32>()
                        / 3.0
                };
                let centroids: Vec<[f32; 3]> = mesh
                    .triangles
                    .iter()
                    .map(|t| [at(t, 0), at(t, 1), at(t, 2)])
                    .collect();
                let up = vec![[0.0, 0.0, 1.0]; centroids.len()];
                crate::bake::bake_points(
                    mesh,
                    (&centroids, &up),
                    crate::bake::PatternRotation::Shared,
                    settings,
                    progress,
                )
            }
        }
        let dir = tempfile::tempdir().unwrap();
        let ck = dir.path().join("m.bake");
        let poses = meshes(2);
        let mut first = Checkpoint::open(&ck, OnExisting::Refuse, &SETTINGS, &poses).unwrap();
        first.bake(&poses, pose_name, &Silent).unwrap();
        let err = Checkpoint::open_at(&ck, OnExisting::Resume, &SETTINGS, &poses, &Centroids)
            .unwrap_err();
        assert!(err.to_string().contains("baked points"), "{err}");
        let other = dir.path().join("c.bake");
        let mut c =
            Checkpoint::open_at(&other, OnExisting::Refuse, &SETTINGS, &poses, &Centroids).unwrap();
        let baked = c.bake_at(&poses, &Centroids, pose_name, &Silent).unwrap();
        assert_eq!(baked[0].len(), 3 * SETTINGS.order * SETTINGS.order);
        // Asking the open checkpoint to bake at other points is refused too.
        assert!(c.bake(&poses, pose_name, &Silent).is_err());
        let mut resumed =
            Checkpoint::open_at(&other, OnExisting::Resume, &SETTINGS, &poses, &Centroids).unwrap();
        assert_eq!(
            resumed
                .bake_at(&poses, &Centroids, pose_name, &Silent)
                .unwrap(),
            baked
        );
    }
}
