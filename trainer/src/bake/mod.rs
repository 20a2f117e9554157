//! Transfer simulation ("bake"): per-vertex diffuse SH transfer of one posed mesh.
//!
//! For a vertex at `x` with normal `n` the direct transfer is the paper's
//! `t_c(x) = ∫ V(x, ω) max(n·ω, 0) y_c(ω) dω` — no albedo and no `1/π`: the renderer applies
//! `albedo/π` once, so baked data stays valid for any material colour. It is estimated with a
//! cosine-weighted low-discrepancy pattern (see the `directions` module) as
//! `t_c ≈ (π/N) Σ V(ω_i) y_c(ω_i)`, accumulated in f64 and returned as f32.
//!
//! Every vertex uses the same local pattern, only placed in its own frame `R = [t, b, n]`, so
//! the basis is evaluated once per bake at the local directions: each vertex sums the rows of
//! that table for its unoccluded rays (its transfer in the local frame) and rotates the sum to
//! world space once, `Σ y(R ω_i) = D(R) Σ y(ω_i)`, by ZYZ Euler angles (`aprt_core::ShRotation`). On the
//! benchmark scene (`benches/bake.rs`) this replaced one basis evaluation per unoccluded ray
//! (23% of the bake's instructions): one pose went from 11.75 to 9.01 G instructions
//! (callgrind) with a full Ivanic–Ruedenberg matrix per vertex. The Euler form does not build
//! that matrix: 8.25 G against 9.07 G with the matrix, measured in one harness that includes
//! the scene and hierarchy build. With the matrix, the f32 rotation moved each vertex's
//! transfer by at most 4.4·10⁻⁷ of its size; the Euler form agrees with the matrix within
//! 2·10⁻⁵ absolute (`aprt_core::ShRotation` tests).
//!
//! Optional inter-reflections (the paper's Figure 7): with albedo ρ,
//! `t^{b+1}(x) = (ρ/N) Σ_{occluded i, front-facing hit} t^b(y_i)`, where `t^b(y_i)` is
//! interpolated from the hit triangle's vertices with barycentrics, and the result is
//! `Σ_{b=0..B} t^b`. The occluded directions and their hit points are those of the direct
//! pass, so each extra bounce costs no rays, only interpolation.
//!
//! # Self-intersection
//! Ray origins are moved off the surface by [`ORIGIN_OFFSET`] × the bounding-box diagonal
//! along the vertex normal, and hits closer than [`T_MIN`] × the diagonal are ignored. Scaling
//! by the model size makes the bake invariant to units (metres or centimetres give the same
//! transfer). `10⁻⁴` of the diagonal (0.2 mm on a 2 m character) is about 800 f32 ulps at
//! unit scale, far above the Möller–Trumbore rounding error for rays leaving a vertex along
//! its own face, yet below the size of any occluding detail a vertex-resolution bake resolves.
//!
//! # Determinism
//! Vertices are processed in parallel, but every vertex's sums run sequentially in a fixed
//! order and every vertex writes only its own output, so the result is bit-identical for any
//! thread count (no float reduction crosses threads).

pub mod budget;
pub mod checkpoint;
pub mod clip;
mod directions;
pub mod shard;
#[cfg(test)]
mod tests;
pub(crate) mod tracer;
mod wide;

pub use tracer::Accel;

use aprt_core::{MAX_COEFFS, MAX_ORDER, ShError, ShRotation, coeff_count, eval_basis};
use glam::DVec3;
use rayon::prelude::*;
use std::ops::Range;
use tracer::{Hit, Tracer, TraversalStack};

use crate::limits::{MAX_EXTENT, MAX_RAYS};
use crate::progress::{BakeProgress, Reporter, Silent};
use crate::rig::mesh::{Mesh, area_weighted_normals};

/// Ray origins are offset along the normal by this fraction of the bounding-box diagonal.
pub const ORIGIN_OFFSET: f64 = 1e-4;
/// Hits closer than this fraction of the bounding-box diagonal are ignored.
pub const T_MIN: f64 = 1e-4;
/// What to simulate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BakeSettings {
    /// SH order `n` (bands `0..n`, `n²` coefficients), `1..=6`.
    pub order: usize,
    /// Directions per vertex, `1..=`[`MAX_RAYS`]. The paper uses 500.
    pub rays: usize,
    /// Inter-reflection bounces after the direct pass; 0 is shadowed transfer only.
    pub bounces: usize,
    /// Diffuse albedo of the surface the bounces reflect from, in `[0, 1]`. Only read when
    /// `bounces > 0`.
    pub albedo: f32,
    /// Whether the character shadows itself. Without shadows no ray is cast: the transfer is
    /// the clamped cosine lobe turned to each normal, `Â_l y_lm(n)`, in closed form
    /// ([`aprt_core::clamped_cosine`]), and nothing occludes, so there is nothing to bounce.
    pub shadows: bool,
}

impl Default for BakeSettings {
    /// Order 6, 500 rays (the paper's data-generation setting), no bounces.
    fn default() -> Self {
        BakeSettings {
            order: 6,
            rays: 500,
            bounces: 0,
            albedo: 0.5,
            shadows: true,
        }
    }
}

impl BakeSettings {
    /// Checks every field; the bake calls this first.
    pub fn validate(&self) -> Result<(), BakeError> {
        if self.order == 0 || self.order > MAX_ORDER {
            return Err(BakeError::BadOrder(self.order));
        }
        if self.rays == 0 || self.rays > MAX_RAYS {
            return Err(BakeError::BadRayCount(self.rays));
        }
        if self.bounces > 0 && !(0.0..=1.0).contains(&self.albedo) {
            return Err(BakeError::BadAlbedo(self.albedo));
        }
        if self.bounces > 0 && !self.shadows {
            return Err(BakeError::BouncesNeedShadows);
        }
        Ok(())
    }

    /// Visibility rays the direct pass casts for `points` surface points: none without
    /// shadows (the bounce passes reuse the direct pass's hits and cast none).
    pub fn rays_cast(&self, points: usize) -> u64 {
        if self.shadows {
            points as u64 * self.rays as u64
        } else {
            0
        }
    }
}

/// Why a bake refused its input.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BakeError {
    /// SH order outside `1..=6`.
    #[error("SH order {0} is outside 1..={max}", max = MAX_ORDER)]
    BadOrder(usize),
    /// Ray count outside `1..=MAX_RAYS`.
    #[error("ray count {0} is outside 1..={MAX_RAYS}")]
    BadRayCount(usize),
    /// Albedo outside `[0, 1]` (or NaN) with bounces requested: the bounce series would not
    /// describe a physical surface and for ρ > 1 would grow with every bounce.
    #[error("albedo {0} is outside [0, 1]")]
    BadAlbedo(f32),
    /// A vertex position has a NaN or infinite coordinate.
    #[error("vertex {vertex} has a non-finite position {position:?}")]
    NonFinitePosition {
        /// Index of the offending vertex.
        vertex: usize,
        /// Its position.
        position: [f32; 3],
    },
    /// The mesh is so large (or so far from the origin) that ray arithmetic would overflow f32.
    #[error("mesh extent {extent:e} is beyond what f32 ray arithmetic can represent")]
    ExtentTooLarge {
        /// Largest absolute coordinate plus the bounding-box diagonal.
        extent: f64,
    },
    /// The mesh has a different number of normals than positions.
    #[error("mesh has {positions} positions but {normals} normals")]
    NormalCountMismatch {
        /// Number of positions.
        positions: usize,
        /// Number of normals.
        normals: usize,
    },
    /// A triangle references a vertex that does not exist.
    #[error("triangle {triangle} references vertex {index}, but the mesh has {vertices}")]
    IndexOutOfRange {
        /// Index of the offending triangle.
        triangle: usize,
        /// The bad vertex index.
        index: u32,
        /// Number of vertices.
        vertices: usize,
    },
    /// A vertex range outside the mesh was requested.
    #[error("vertex range {start}..{end} is outside the mesh's {vertices} vertices")]
    BadVertexRange {
        /// Range start.
        start: usize,
        /// Range end.
        end: usize,
        /// Number of vertices.
        vertices: usize,
    },
    /// Bounces were asked for without shadows: with nothing occluding, no ray hits the
    /// character, so there is no light to reflect.
    #[error(
        "bounces need shadows: without occlusion no ray hits the character, so nothing reflects"
    )]
    BouncesNeedShadows,
    /// A partial bake was asked for bounces, which need the transfer of every vertex.
    #[error("bounces need the whole mesh; a vertex-range bake is direct transfer only")]
    BouncesNeedWholeMesh,
    /// The SH basis refused a direction or the rotation its order (cannot happen for the unit
    /// directions and checked orders the bake uses; kept typed rather than unwrapped).
    #[error("SH basis: {0}")]
    Basis(ShError),
}

/// Bakes the transfer of every vertex of `mesh`: vertex-major, `order²` values per vertex
/// (entry `[j * order² + c]`). An empty mesh gives an empty result.
pub fn bake_pose(mesh: &Mesh, settings: &BakeSettings) -> Result<Vec<f32>, BakeError> {
    bake_pose_with(mesh, settings, Accel::default())
}

/// [`bake_pose`] with a chosen acceleration structure (results agree across structures up to
/// ties between equally distant hits; the choice is about speed).
pub fn bake_pose_with(
    mesh: &Mesh,
    settings: &BakeSettings,
    accel: Accel,
) -> Result<Vec<f32>, BakeError> {
    bake_pose_inner(mesh, settings, accel, &Silent)
}

/// Bakes several poses one after the other (each pose parallel over its vertices), with one
/// progress display over all poses' vertices from `reporter` (the command line's is a bar on
/// stderr; [`Silent`] shows nothing).
pub fn bake_poses(
    meshes: &[Mesh],
    settings: &BakeSettings,
    reporter: &dyn Reporter,
) -> Result<Vec<Vec<f32>>, BakeError> {
    settings.validate()?;
    let total: usize = meshes.iter().map(Mesh::vertex_count).sum();
    let progress = reporter.bake_progress(total);
    let mut out = Vec::with_capacity(meshes.len());
    for (p, mesh) in meshes.iter().enumerate() {
        progress.pose(p, meshes.len());
        out.push(bake_pose_inner(
            mesh,
            settings,
            Accel::default(),
            progress.as_ref(),
        )?);
    }
    progress.finish();
    Ok(out)
}

/// [`bake_pose`] advancing a caller's progress by one per vertex, for callers that bake poses
/// one at a time (checkpointing) yet show one display over all of them. Bit-identical to
/// [`bake_pose`] and to the same pose in [`bake_poses`].
pub fn bake_pose_progress(
    mesh: &Mesh,
    settings: &BakeSettings,
    progress: &dyn BakeProgress,
) -> Result<Vec<f32>, BakeError> {
    bake_pose_inner(mesh, settings, Accel::default(), progress)
}

/// Direct (shadowed, no bounce) transfer of the vertices in `vertices` only, vertex-major like
/// [`bake_pose`] and bit-identical to the corresponding slice of it. For measuring slow
/// reference configurations on a subset and for spreading one pose over several jobs.
pub fn bake_vertices(
    mesh: &Mesh,
    settings: &BakeSettings,
    accel: Accel,
    vertices: Range<usize>,
) -> Result<Vec<f32>, BakeError> {
    if settings.bounces > 0 {
        return Err(BakeError::BouncesNeedWholeMesh);
    }
    let v = mesh.vertex_count();
    if vertices.start > vertices.end || vertices.end > v {
        return Err(BakeError::BadVertexRange {
            start: vertices.start,
            end: vertices.end,
            vertices: v,
        });
    }
    let prepared = Prepared::new(mesh, settings)?;
    if !settings.shadows {
        return prepared.unshadowed(&prepared.normals[vertices], &Silent);
    }
    let tracer = Tracer::new(&mesh.positions, &mesh.triangles, accel);
    let (direct, _) = prepared.direct(&tracer, vertices, Hits::Skip, &Silent)?;
    Ok(direct.into_iter().map(|x| x as f32).collect())
}

/// Transfer at surface points of `mesh` that are not its vertices (the texels of a light map,
/// `positions[j]` with unit normal `normals[j]`), on the same rays, pattern and occluders as
/// [`bake_pose`]: sample-major, `order²` values per sample. With bounces, each point's hits
/// gather the whole mesh's transfer of one bounce fewer: the sum over bounces `1..=B` of the
/// previous bounce interpolated at the hits equals the (B − 1)-bounce total interpolated there.
/// `progress` advances by one per point.
pub fn bake_points(
    mesh: &Mesh,
    (positions, normals): (&[[f32; 3]], &[[f32; 3]]),
    rotation: PatternRotation,
    settings: &BakeSettings,
    progress: &dyn BakeProgress,
) -> Result<Vec<f32>, BakeError> {
    let prepared = Prepared::new(mesh, settings)?;
    if normals.len() != positions.len() {
        return Err(BakeError::NormalCountMismatch {
            positions: positions.len(),
            normals: normals.len(),
        });
    }
    if let Some((vertex, &position)) = positions
        .iter()
        .enumerate()
        .find(|(_, p)| !p.iter().all(|x| x.is_finite()))
    {
        return Err(BakeError::NonFinitePosition { vertex, position });
    }
    // Normalised as `usable_normals` does, so a point at a vertex bakes that vertex's bits.
    let unit: Vec<DVec3> = normals
        .iter()
        .map(|n| {
            let n = DVec3::from(n.map(f64::from));
            let len = n.length();
            if len.is_finite() && len > 0.0 {
                n / len
            } else {
                DVec3::Z
            }
        })
        .collect();
    let points = Points {
        positions,
        normals: &unit,
        rotation,
    };
    if !settings.shadows {
        return prepared.unshadowed(&unit, progress);
    }
    if positions.is_empty() || mesh.vertex_count() == 0 {
        return Ok(vec![0.0; positions.len() * prepared.n2]);
    }
    let tracer = Tracer::new(&mesh.positions, &mesh.triangles, Accel::default());
    let total = if settings.bounces == 0 {
        prepared
            .direct_at(&points, &tracer, 0..positions.len(), Hits::Skip, progress)?
            .0
    } else {
        let fewer = BakeSettings {
            bounces: settings.bounces - 1,
            ..*settings
        };
        let vertices = bake_pose_inner(mesh, &fewer, Accel::default(), &Silent)?;
        let (direct, hits) =
            prepared.direct_at(&points, &tracer, 0..positions.len(), Hits::Record, progress)?;
        let gathered = prepared.gather(&vertices, &hits, &mesh.triangles);
        direct.iter().zip(&gathered).map(|(d, g)| d + g).collect()
    };
    Ok(total.into_iter().map(|x| x as f32).collect())
}

fn bake_pose_inner(
    mesh: &Mesh,
    settings: &BakeSettings,
    accel: Accel,
    progress: &dyn BakeProgress,
) -> Result<Vec<f32>, BakeError> {
    let prepared = Prepared::new(mesh, settings)?;
    let v = mesh.vertex_count();
    if !settings.shadows {
        return prepared.unshadowed(&prepared.normals, progress);
    }
    if v == 0 {
        return Ok(Vec::new());
    }
    let tracer = Tracer::new(&mesh.positions, &mesh.triangles, accel);
    let hits = if settings.bounces > 0 {
        Hits::Record
    } else {
        Hits::Skip
    };
    let (direct, recorded) = prepared.direct(&tracer, 0..v, hits, progress)?;
    let total = if hits == Hits::Record {
        prepared.add_bounces(direct, &recorded, &mesh.triangles)
    } else {
        direct
    };
    Ok(total.into_iter().map(|x| x as f32).collect())
}

/// Whether the direct pass keeps the hits of the occluded rays, which the bounce passes need.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Hits {
    /// Keep each vertex's front-facing hits (closest-hit rays).
    Record,
    /// Only ask whether each ray is blocked (any-hit rays, faster).
    Skip,
}

/// Validated inputs and the per-bake constants shared by every vertex.
struct Prepared<'a> {
    mesh: &'a Mesh,
    settings: BakeSettings,
    n2: usize,
    normals: Vec<DVec3>,
    pattern: Vec<DVec3>,
    /// `y_c` of every pattern direction in the local frame, `n2` values per direction.
    local_basis: Vec<f64>,
    /// The pattern's indices with similar directions next to each other, for packets.
    coherent: Vec<u32>,
    /// Takes each vertex's local-frame sum to world space.
    to_world: ShRotation,
    offset: f64,
    t_min: f32,
}

impl<'a> Prepared<'a> {
    fn new(mesh: &'a Mesh, settings: &BakeSettings) -> Result<Self, BakeError> {
        settings.validate()?;
        let v = mesh.vertex_count();
        if mesh.normals.len() != v {
            return Err(BakeError::NormalCountMismatch {
                positions: v,
                normals: mesh.normals.len(),
            });
        }
        if let Some((vertex, &position)) = mesh
            .positions
            .iter()
            .enumerate()
            .find(|(_, p)| !p.iter().all(|x| x.is_finite()))
        {
            return Err(BakeError::NonFinitePosition { vertex, position });
        }
        for (triangle, t) in mesh.triangles.iter().enumerate() {
            if let Some(&index) = t.iter().find(|&&i| i as usize >= v) {
                return Err(BakeError::IndexOutOfRange {
                    triangle,
                    index,
                    vertices: v,
                });
            }
        }
        let diagonal = bounding_diagonal(&mesh.positions);
        // Ray origins and hit points stay within |p| + diagonal; keep a margin below f32::MAX
        // so the intersection arithmetic cannot overflow into infinities.
        let largest = mesh
            .positions
            .iter()
            .flatten()
            .fold(0.0f64, |m, &x| m.max(f64::from(x).abs()));
        let extent = largest + diagonal;
        if extent > MAX_EXTENT {
            return Err(BakeError::ExtentTooLarge { extent });
        }
        let pattern = directions::cosine_hammersley(settings.rays);
        Ok(Prepared {
            mesh,
            settings: *settings,
            n2: coeff_count(settings.order),
            normals: usable_normals(mesh),
            local_basis: local_basis(settings.order, &pattern)?,
            coherent: directions::coherent_order(&pattern),
            to_world: ShRotation::new(settings.order).map_err(BakeError::Basis)?,
            pattern,
            offset: ORIGIN_OFFSET * diagonal,
            t_min: (T_MIN * diagonal) as f32,
        })
    }

    /// The unshadowed transfer at unit `normals`, `order²` values each: the clamped cosine
    /// lobe in closed form, no rays. `progress` advances by one per normal.
    fn unshadowed(
        &self,
        normals: &[DVec3],
        progress: &dyn BakeProgress,
    ) -> Result<Vec<f32>, BakeError> {
        let n2 = self.n2;
        let mut out = vec![0.0f32; normals.len() * n2];
        for (t, n) in out.chunks_exact_mut(n2).zip(normals) {
            let n = n.as_vec3().to_array();
            aprt_core::clamped_cosine(self.settings.order, n, t).map_err(BakeError::Basis)?;
        }
        normals.iter().for_each(|_| progress.vertex_done());
        Ok(out)
    }

    /// Direct transfer of `vertices` (vertex-major f64), and with [`Hits::Record`], for each
    /// vertex the front-facing hits of its occluded rays (for the bounce passes).
    fn direct(
        &self,
        tracer: &Tracer,
        vertices: Range<usize>,
        hits_wanted: Hits,
        progress: &dyn BakeProgress,
    ) -> Result<(Vec<f64>, Vec<Vec<Hit>>), BakeError> {
        let points = Points {
            positions: &self.mesh.positions,
            normals: &self.normals,
            rotation: PatternRotation::PerPoint,
        };
        self.direct_at(&points, tracer, vertices, hits_wanted, progress)
    }

    /// [`Prepared::direct`] at the surface points `points` of the mesh (its vertices, or the
    /// texels of a light map): sample `j` is shot from `points.positions[j]` around
    /// `points.normals[j]`, with the pattern rotated by sample `j`'s own angle.
    fn direct_at(
        &self,
        points: &Points<'_>,
        tracer: &Tracer,
        vertices: Range<usize>,
        hits_wanted: Hits,
        progress: &dyn BakeProgress,
    ) -> Result<(Vec<f64>, Vec<Vec<Hit>>), BakeError> {
        let n2 = self.n2;
        let mut out = vec![0.0f64; vertices.len() * n2];
        let mut hits: Vec<Vec<Hit>> = if hits_wanted == Hits::Record {
            vec![Vec::new(); vertices.len()]
        } else {
            Vec::new()
        };
        let scale = std::f64::consts::PI / self.settings.rays as f64;
        let work =
            |scratch: &mut Scratch, j: usize, t: &mut [f64], vertex_hits: Option<&mut Vec<Hit>>| {
                let p = DVec3::from(points.positions[j].map(f64::from));
                let n = points.normals[j];
                let origin = (p + n * self.offset).as_vec3a();
                let angle = match points.rotation {
                    PatternRotation::PerPoint => directions::vertex_rotation(j),
                    PatternRotation::Shared => directions::vertex_rotation(0),
                };
                let frame = directions::vertex_frame(n, angle);
                directions::place_pattern(&self.pattern, &frame, &mut scratch.dirs);
                self.visibility(tracer, origin, scratch, vertex_hits);
                for (&blocked, basis) in scratch
                    .blocked
                    .iter()
                    .zip(self.local_basis.chunks_exact(n2))
                {
                    if !blocked {
                        for (acc, &y) in t.iter_mut().zip(basis) {
                            *acc += y;
                        }
                    }
                }
                // Local frame to world: the rotation whose columns are t, b, n.
                let mut world: [f32; MAX_COEFFS] =
                    std::array::from_fn(|c| t.get(c).map_or(0.0, |&acc| (acc * scale) as f32));
                self.to_world
                    .apply(&directions::frame_matrix(&frame), &mut world)
                    .map_err(BakeError::Basis)?;
                for (acc, &w) in t.iter_mut().zip(&world) {
                    *acc = f64::from(w);
                }
                progress.vertex_done();
                Ok(())
            };
        let init = || Scratch {
            dirs: Vec::with_capacity(self.settings.rays),
            rays: Vec::with_capacity(self.settings.rays),
            blocked: Vec::with_capacity(self.settings.rays),
            stack: TraversalStack::default(),
        };
        let start = vertices.start;
        if hits_wanted == Hits::Record {
            out.par_chunks_mut(n2)
                .zip(hits.par_iter_mut())
                .enumerate()
                .try_for_each_init(init, |s, (i, (t, h))| work(s, start + i, t, Some(h)))?;
        } else {
            out.par_chunks_mut(n2)
                .enumerate()
                .try_for_each_init(init, |s, (i, t)| work(s, start + i, t, None))?;
        }
        Ok((out, hits))
    }

    /// Fills `scratch.blocked` with whether each of `scratch.dirs` from `origin` is blocked,
    /// and with `vertex_hits`, records the front-facing hits of the blocked ones (closest-hit
    /// rays, one at a time); otherwise shadow rays go to the tracer all together, so a
    /// packet-walking tracer can group them.
    fn visibility(
        &self,
        tracer: &Tracer,
        origin: glam::Vec3A,
        scratch: &mut Scratch,
        vertex_hits: Option<&mut Vec<Hit>>,
    ) {
        let Scratch {
            dirs,
            rays,
            blocked,
            stack,
        } = scratch;
        rays.clear();
        rays.extend(dirs.iter().map(|d| d.as_vec3a()));
        blocked.clear();
        blocked.resize(rays.len(), false);
        let Some(list) = vertex_hits else {
            tracer.occluded_from(origin, (rays, &self.coherent), self.t_min, blocked, stack);
            return;
        };
        for (b, &d) in blocked.iter_mut().zip(rays.iter()) {
            let hit = tracer.closest(tracer::ray(origin, d, self.t_min, f32::INFINITY), stack);
            if let Some(hit) = hit.filter(|h| h.front_facing) {
                list.push(hit);
            }
            *b = hit.is_some();
        }
    }

    /// Adds `B` bounces to the whole-mesh direct transfer, each interpolating the previous
    /// bounce at the recorded hits.
    fn add_bounces(&self, direct: Vec<f64>, hits: &[Vec<Hit>], triangles: &[[u32; 3]]) -> Vec<f64> {
        let mut total = direct.clone();
        let mut previous = direct;
        for _ in 0..self.settings.bounces {
            let next = self.gather(&previous, hits, triangles);
            for (acc, &b) in total.iter_mut().zip(&next) {
                *acc += b;
            }
            previous = next;
        }
        total
    }

    /// One bounce at every sample: albedo / rays × the sum over the sample's hits of `source`
    /// (whole-mesh transfer, vertex-major) interpolated at the hit.
    fn gather<T: Copy + Into<f64> + Sync>(
        &self,
        source: &[T],
        hits: &[Vec<Hit>],
        triangles: &[[u32; 3]],
    ) -> Vec<f64> {
        let n2 = self.n2;
        let weight = f64::from(self.settings.albedo) / self.settings.rays as f64;
        let mut next = vec![0.0f64; hits.len() * n2];
        next.par_chunks_mut(n2)
            .zip(hits.par_iter())
            .for_each(|(t, sample_hits)| {
                for hit in sample_hits {
                    let corners = triangles[hit.triangle as usize];
                    for (&k, &w) in corners.iter().zip(&hit.bary) {
                        let src = &source[k as usize * n2..][..n2];
                        for (acc, &s) in t.iter_mut().zip(src) {
                            *acc += f64::from(w) * s.into();
                        }
                    }
                }
                for acc in t.iter_mut() {
                    *acc *= weight;
                }
            });
        next
    }
}

/// Where the direct pass shoots from: one position and unit normal per sample.
struct Points<'p> {
    positions: &'p [[f32; 3]],
    normals: &'p [DVec3],
    /// The pattern's rotation about the normal: its own per point (the vertex bake: the
    /// Monte Carlo error decorrelates between neighbours), or one shared by every point.
    rotation: PatternRotation,
}

/// How the ray pattern is turned about each point's normal.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PatternRotation {
    /// Point `j` turns by its own pseudo-random angle, as vertex `j` of the vertex bake does.
    PerPoint,
    /// Every point turns by the same angle: points with the same normal and surroundings cast
    /// the same rays, so the Monte Carlo error varies as smoothly over a light map as the
    /// geometry does instead of as white noise, which the sequence codec cannot compress.
    Shared,
}

/// One worker thread's buffers, reused for all the vertices it bakes.
struct Scratch {
    /// The vertex's ray directions in world space.
    dirs: Vec<DVec3>,
    /// The same directions in the `f32` the rays are cast with.
    rays: Vec<glam::Vec3A>,
    /// Whether each ray is blocked.
    blocked: Vec<bool>,
    stack: TraversalStack,
}

/// The SH basis of every direction of `pattern`, `order²` values per direction, widened to
/// f64 once here so the per-ray accumulation is plain f64 additions.
fn local_basis(order: usize, pattern: &[DVec3]) -> Result<Vec<f64>, BakeError> {
    let mut basis = [0.0f32; MAX_COEFFS];
    let mut table = Vec::with_capacity(pattern.len() * coeff_count(order));
    for d in pattern {
        eval_basis(order, d.as_vec3().to_array(), &mut basis).map_err(BakeError::Basis)?;
        table.extend(basis[..coeff_count(order)].iter().map(|&y| f64::from(y)));
    }
    Ok(table)
}

/// Length of the axis-aligned bounding box's diagonal, in f64 so huge coordinates cannot
/// overflow. 0 for an empty mesh or a single point.
fn bounding_diagonal(positions: &[[f32; 3]]) -> f64 {
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    for p in positions {
        let p = DVec3::from(p.map(f64::from));
        lo = lo.min(p);
        hi = hi.max(p);
    }
    if positions.is_empty() {
        0.0
    } else {
        (hi - lo).length()
    }
}

/// Unit normals for every vertex. A normal that is zero, NaN or infinite is replaced by the
/// vertex's area-weighted geometric normal (itself +z where no triangle with area touches the
/// vertex), so degenerate input still gets a hemisphere.
fn usable_normals(mesh: &Mesh) -> Vec<DVec3> {
    let mut fallback: Option<Vec<[f32; 3]>> = None;
    mesh.normals
        .iter()
        .enumerate()
        .map(|(j, n)| {
            let n = DVec3::from(n.map(f64::from));
            let len = n.length();
            if len.is_finite() && len > 0.0 {
                n / len
            } else {
                let geometric = fallback
                    .get_or_insert_with(|| area_weighted_normals(&mesh.positions, &mesh.triangles));
                DVec3::from(geometric[j].map(f64::from))
            }
        })
        .collect()
}
