//! What one run may ask of the machine. A bake or an evaluation of a clip is estimated before
//! any pose is skinned, baked or predicted: the frames, the bytes held in memory, the rays
//! cast and the checkpoint files written. A request beyond a bound is refused with those
//! numbers instead of running for days, writing hundreds of thousands of files or being
//! killed for memory.
//!
//! The bounds sit above the real uses measured here and well below what stops a machine of
//! this project's size (2 cores, 24 GB, shared). The largest real input, the CMU capture
//! `cmu_01_01` driving a 10.7k-vertex mannequin, trains at order 4 and 256 rays on its 688
//! frames at 30 fps within them (1.3 GB of posed meshes and transfer, 1.9·10⁹ rays); all 2752
//! frames at its own 120 fps would hold 5.2 GB and are refused.

use crate::bake::BakeSettings;
use crate::bake::tracer::Hit;
use crate::limits::{MAX_BYTES, MAX_FRAMES};
use crate::rig::mesh::Mesh;

/// Most rays one bake casts: about 40 hours at the 7 Mrays/s the bake bench measures on
/// 2 cores.
pub const MAX_RAY_CASTS: u64 = 1_000_000_000_000;

/// Bytes of one posed vertex (position and normal, f32) and of one triangle (three u32).
const VERTEX_BYTES: u64 = 24;
const TRIANGLE_BYTES: u64 = 12;
/// Bytes of a checkpoint pose file beside its values (magic, CRC-32, count).
const POSE_FILE_HEADER: u64 = 20;

/// What a run will do with a clip, as far as its cost goes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Workload {
    /// Frames baked or evaluated.
    pub frames: usize,
    /// Vertices of the mesh.
    pub vertices: usize,
    /// Points baked or evaluated per frame: the vertices, or a light map's texel samples.
    pub points: usize,
    /// What the points are, for the message: `"vertices"` or `"texels"`.
    pub point_name: &'static str,
    /// Triangles of each posed mesh; 0 when no mesh is posed (evaluation).
    pub triangles: usize,
    /// SH coefficients per vertex (n²).
    pub coeffs: usize,
    /// Rays per vertex; 0 when nothing is baked.
    pub rays: usize,
    /// Whether the bake records every occluded ray's hit for inter-reflections.
    pub bounces: bool,
    /// Copies of the f32 transfer of every frame held at once: the bake's result, a change
    /// of frame, the output array and its encoding.
    pub copies: usize,
    /// Whether every frame is saved to a checkpoint file.
    pub checkpoint: bool,
}

impl Workload {
    /// Baking `frames` poses of `mesh` (every pose skinned first, so all posed meshes are held)
    /// with `settings`, holding `copies` of the transfer.
    pub fn bake(frames: usize, mesh: &Mesh, settings: &BakeSettings, copies: usize) -> Workload {
        Workload {
            frames,
            vertices: mesh.vertex_count(),
            points: mesh.vertex_count(),
            point_name: "vertices",
            triangles: mesh.triangles.len(),
            coeffs: settings.order * settings.order,
            rays: settings.rays,
            bounces: settings.bounces > 0,
            copies,
            checkpoint: false,
        }
    }

    /// Evaluating a model of `vertices` vertices and `coeffs` coefficients at `frames` poses,
    /// holding `copies` of the predicted transfer.
    pub fn evaluation(frames: usize, vertices: usize, coeffs: usize, copies: usize) -> Workload {
        Workload {
            frames,
            vertices,
            points: vertices,
            point_name: "vertices",
            triangles: 0,
            coeffs,
            rays: 0,
            bounces: false,
            copies,
            checkpoint: false,
        }
    }

    /// Baking `frames` poses of `mesh` at `texels` texel samples of a light map instead of its
    /// vertices, holding `copies` of the maps.
    pub fn light_maps(
        frames: usize,
        mesh: &Mesh,
        texels: usize,
        settings: &BakeSettings,
        copies: usize,
    ) -> Workload {
        Workload {
            points: texels,
            point_name: "texels",
            ..Workload::bake(frames, mesh, settings, copies)
        }
    }

    /// Baking `frames` poses of `mesh` at `points` points spread over its surface instead of
    /// its vertices (`aprt simulate --surface`), holding `copies` of their transfer.
    pub fn surface_points(
        frames: usize,
        mesh: &Mesh,
        points: usize,
        settings: &BakeSettings,
        copies: usize,
    ) -> Workload {
        Workload {
            points,
            point_name: "surface points",
            ..Workload::bake(frames, mesh, settings, copies)
        }
    }

    /// The same work with every frame saved to a checkpoint file.
    pub fn with_checkpoint(self) -> Workload {
        Workload {
            checkpoint: true,
            ..self
        }
    }

    /// Bytes of one frame's f32 transfer.
    fn frame_transfer_bytes(&self) -> u64 {
        (self.points as u64)
            .saturating_mul(self.coeffs as u64)
            .saturating_mul(4)
    }

    /// Bytes held in memory at the peak: every posed mesh, the copies of every frame's
    /// transfer, and one pose's ray hits when bouncing.
    pub fn bytes(&self) -> u64 {
        let frames = self.frames as u64;
        let mesh = if self.triangles == 0 {
            0
        } else {
            (self.vertices as u64 * VERTEX_BYTES)
                .saturating_add(self.triangles as u64 * TRIANGLE_BYTES)
        };
        let hits = if self.bounces {
            (self.points as u64)
                .saturating_mul(self.rays as u64)
                .saturating_mul(std::mem::size_of::<Hit>() as u64)
        } else {
            0
        };
        frames
            .saturating_mul(mesh)
            .saturating_add(
                frames
                    .saturating_mul(self.frame_transfer_bytes())
                    .saturating_mul(self.copies as u64),
            )
            .saturating_add(hits)
    }

    /// Rays cast by the bake.
    pub fn ray_casts(&self) -> u64 {
        (self.frames as u64)
            .saturating_mul(self.points as u64)
            .saturating_mul(self.rays as u64)
    }

    /// Checkpoint files (one per frame and the manifest) and their bytes; `None` without a
    /// checkpoint.
    pub fn checkpoint_files(&self) -> Option<(u64, u64)> {
        self.checkpoint.then(|| {
            let frames = self.frames as u64;
            let per_file = self.frame_transfer_bytes().saturating_add(POSE_FILE_HEADER);
            (frames + 1, frames.saturating_mul(per_file))
        })
    }

    /// Refuses the work if it exceeds a bound; `what` names the clip or the files in the
    /// message.
    pub fn check(&self, what: &str) -> Result<(), BudgetError> {
        let over = if self.frames > MAX_FRAMES {
            Bound::Frames
        } else if self.bytes() > MAX_BYTES {
            Bound::Bytes
        } else if self.ray_casts() > MAX_RAY_CASTS {
            Bound::Rays
        } else {
            return Ok(());
        };
        Err(BudgetError {
            what: what.to_owned(),
            work: *self,
            over,
        })
    }
}

/// Which bound a request exceeds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Bound {
    /// [`MAX_FRAMES`].
    Frames,
    /// [`MAX_BYTES`].
    Bytes,
    /// [`MAX_RAY_CASTS`].
    Rays,
}

/// A bake or an evaluation beyond one of the bounds, with its estimated cost.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{}", self.describe())]
pub struct BudgetError {
    /// The clip or files.
    pub what: String,
    /// The work asked for.
    pub work: Workload,
    /// The bound it exceeds.
    pub over: Bound,
}

impl BudgetError {
    fn describe(&self) -> String {
        let w = &self.work;
        let verb = if w.rays > 0 { "baking" } else { "evaluating" };
        let order = (w.coeffs as f64).sqrt().round() as usize;
        let mut cost = vec![format!("{} of memory", bytes(w.bytes()))];
        if w.rays > 0 {
            cost.push(format!("{:.1e} rays", w.ray_casts() as f64));
        }
        if let Some((files, size)) = w.checkpoint_files() {
            cost.push(format!("{files} checkpoint files ({})", bytes(size)));
        }
        let limit = match self.over {
            Bound::Frames => format!(
                "one run bakes or evaluates at most {MAX_FRAMES} frames: take fewer frames or a lower frame rate"
            ),
            Bound::Bytes => format!(
                "one run holds at most {}: take fewer frames, a lower frame rate{} or a lower SH order",
                bytes(MAX_BYTES),
                match w.point_name {
                    "texels" => ", a lower --resolution",
                    "surface points" => ", fewer --surface points",
                    _ => "",
                }
            ),
            Bound::Rays => format!(
                "one bake casts at most {:.1e} rays (about 40 hours on 2 cores): take fewer rays or fewer frames",
                MAX_RAY_CASTS as f64
            ),
        };
        format!(
            "{}: {verb} {} frames of {} {} at SH order {order} would need {}; {limit}",
            self.what,
            w.frames,
            w.points,
            w.point_name,
            cost.join(", "),
        )
    }
}

/// A byte count for people: `8.1 GB`, `620 kB`.
pub fn bytes(n: u64) -> String {
    let units = [(1e12, "TB"), (1e9, "GB"), (1e6, "MB"), (1e3, "kB")];
    let x = n as f64;
    match units.iter().find(|(scale, _)| x >= *scale) {
        Some((scale, unit)) => format!("{:.1} {unit}", x / scale),
        None => format!("{n} bytes"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn settings(order: usize, rays: usize) -> BakeSettings {
        BakeSettings {
            order,
            rays,
            bounces: 0,
            albedo: 0.5,
            shadows: true,
        }
    }

    fn mesh(vertices: usize, triangles: usize) -> Mesh {
        Mesh {
            positions: vec![[0.0; 3]; vertices],
            normals: vec![[0.0, 0.0, 1.0]; vertices],
            triangles: vec![[0, 0, 0]; triangles],
        }
    }

    #[test]
    fn estimates_add_up() {
        let w = Workload::bake(10, &mesh(100, 200), &settings(4, 64), 2).with_checkpoint();
        // 10 × (100·24 + 200·12) + 2 · 10 · 100 · 16 · 4.
        assert_eq!(w.bytes(), 48_000 + 128_000);
        assert_eq!(w.ray_casts(), 64_000);
        assert_eq!(w.checkpoint_files(), Some((11, 10 * (6400 + 20))));
        assert!(w.check("clip").is_ok());
    }

    #[test]
    fn each_bound_is_refused_with_the_numbers() {
        // A two-second clip sampled at 100 000 fps.
        let fast = Workload::bake(200_001, &mesh(96, 188), &settings(4, 256), 2).with_checkpoint();
        let err = fast.check("clip Walk").unwrap_err();
        assert_eq!(err.over, Bound::Frames);
        let text = err.to_string();
        for part in [
            "clip Walk",
            "200001 frames",
            "200002 checkpoint files",
            "at most 10000",
        ] {
            assert!(text.contains(part), "{part:?} missing from {text}");
        }
        let big = Workload::evaluation(9_000, 300_000, 36, 3);
        assert_eq!(big.check("m.aprt").unwrap_err().over, Bound::Bytes);
        let slow = Workload::bake(5_000, &mesh(20_000, 1), &settings(1, 1 << 16), 1);
        assert_eq!(slow.check("clip").unwrap_err().over, Bound::Rays);
    }

    #[test]
    fn byte_counts_read_as_people_write_them() {
        assert_eq!(bytes(999), "999 bytes");
        assert_eq!(bytes(620_000), "620.0 kB");
        assert_eq!(bytes(8_100_000_000), "8.1 GB");
    }
}
