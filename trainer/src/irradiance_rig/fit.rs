//! Fitting an irradiance rig to a character (*Irradiance Rigs*, sections 2.2 and 3.1): the
//! least-squares matrix from lighting sampled on the surface to the rig's SH vectors, and the
//! table of the rig's error against distance that decides which lights it carries.
//!
//! The character deforms, so the rig lives in its root frame and is fitted over the surface
//! of the bind pose and of its training poses, all in that frame: one matrix serves every
//! pose, and the samples cover where the surface goes, not only where it rests.

use anyhow::Context;
use aprt_core::{AxisKind, IrradianceRig, Light, Placement, Rgb, RigLayout, RigShape};
use nalgebra::DMatrix;

use super::kind::RigKind;
use super::surface_samples::surface_samples;
use crate::io::source::joined;
use crate::rig::mesh::Mesh;
use crate::rig::{Clip, Rig, RigError};

/// Surface samples per rig vector, and at least this many in all: a least-squares fit wants
/// several samples per unknown, and a lattice's corner cells hold little surface.
const SAMPLES_PER_VECTOR: usize = 6;
const MIN_SAMPLES: usize = 64;
/// Seed of the samples, so a fit is the same on every run.
const SAMPLE_SEED: u64 = 0x51A2_7E11_9D0C_4B3F;
/// Smoothness weight on a lattice's neighbouring nodes, relative to the mean squared weight a
/// sample gives a vector: small enough that a field the rig represents comes back to 1e-4 on
/// the surface (at 1e-6 the paper's mixed rig on the human was off by 6e-4), large enough
/// against the 1e-14 ridge that nodes no sample reaches take their neighbours' lighting
/// instead of 0.
const SMOOTHNESS: f64 = 1e-8;

/// A rig fitted to a character, ready to be written ([`FittedRig::bytes`]) into a model blob or
/// evaluated on its own.
#[derive(Clone, Debug, PartialEq)]
pub struct FittedRig {
    /// The kind asked for.
    pub kind: RigKind,
    /// Centre of the box around every pose's surface, root frame.
    pub centre: [f64; 3],
    /// Half-widths of that box.
    pub half: [f64; 3],
    /// Largest distance of a vertex from the centre, over the poses.
    pub radius: f64,
    /// Sample points, root frame.
    pub samples: Vec<[f64; 3]>,
    /// K × N, row-major: `C_k = Σ_i matrix[k][i] l(samples[i])`.
    pub matrix: Vec<f64>,
    /// (distance / radius, grey levels per unit strength), filled by [`FittedRig::tabulate`].
    pub table: Vec<[f64; 2]>,
}

impl FittedRig {
    /// The rig's bytes: the `IrradianceRig` section of a model blob.
    pub fn bytes(&self) -> Vec<u8> {
        let f = |v: [f64; 3]| v.map(|x| x as f32);
        let samples: Vec<[f32; 3]> = self.samples.iter().map(|&p| f(p)).collect();
        let matrix: Vec<f32> = self.matrix.iter().map(|&x| x as f32).collect();
        let table: Vec<[f32; 2]> = self.table.iter().map(|e| e.map(|x| x as f32)).collect();
        let layout = RigLayout {
            shape: self.kind.shape,
            centre: f(self.centre),
            half: f(self.half),
            radius: self.radius as f32,
            table: &table,
            samples: &samples,
            matrix: &matrix,
        };
        let mut bytes = vec![0u8; layout.len()];
        layout
            .write(&mut bytes)
            .expect("the buffer is the layout's own length");
        bytes
    }
}

/// The 26 directions to the faces, edges and corners of a cube, normalised.
pub(super) fn directions() -> Vec<[f64; 3]> {
    let mut out = Vec::new();
    for x in -1..=1 {
        for y in -1..=1 {
            for z in -1..=1 {
                if (x, y, z) != (0, 0, 0) {
                    let v = [x as f64, y as f64, z as f64];
                    let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
                    out.push(v.map(|c| c / n));
                }
            }
        }
    }
    out
}

/// Mean and largest of a set of errors, in grey levels.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct GreyError {
    /// Mean over vertices and channels.
    pub mean: f64,
    /// Largest.
    pub max: f64,
}

/// The rig's K SH vectors for `lights` (n² RGB each, vector-major), through the core.
pub fn rig_vectors(
    rig: &IrradianceRig<'_>,
    lights: &[Light],
    order: usize,
    placement: &Placement,
) -> Result<Vec<Rgb>, aprt_core::Error> {
    let mut out = vec![[0.0f32; 3]; rig.vectors() * order * order];
    rig.vectors_from_lights(order, placement, lights, &[], &mut out)?;
    Ok(out)
}

/// The box around `meshes` (centre, half-widths; a flat axis gets a millimetre) and the
/// largest distance of a vertex from its centre.
pub(crate) fn bounds(meshes: &[&Mesh]) -> ([f64; 3], [f64; 3], f64) {
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for p in meshes.iter().flat_map(|m| &m.positions) {
        for k in 0..3 {
            lo[k] = lo[k].min(f64::from(p[k]));
            hi[k] = hi[k].max(f64::from(p[k]));
        }
    }
    let centre = std::array::from_fn(|k| 0.5 * (lo[k] + hi[k]));
    let half = std::array::from_fn(|k| (0.5 * (hi[k] - lo[k])).max(1e-3));
    let radius = meshes
        .iter()
        .flat_map(|m| &m.positions)
        .map(|p| {
            (0..3)
                .map(|k| (f64::from(p[k]) - centre[k]).powi(2))
                .sum::<f64>()
                .sqrt()
        })
        .fold(1e-3, f64::max);
    (centre, half, radius)
}

/// Poses of a clip the rig of a deforming character is fitted over, besides the bind pose.
pub const FIT_POSES: usize = 24;

/// The meshes a character's rig is fitted over: the bind pose and up to [`FIT_POSES`] frames
/// spread evenly over `clip`, as the rig poses them (its root frame).
pub fn fitting_meshes(rig: &dyn Rig, clip: &Clip) -> Result<Vec<Mesh>, RigError> {
    let frames = clip.frames.len();
    let step = frames.div_ceil(FIT_POSES).max(1);
    let mut meshes = vec![rig.bind_mesh().clone()];
    for pose in clip.frames.iter().step_by(step) {
        meshes.push(rig.pose(pose)?);
    }
    Ok(meshes)
}

/// The surfaces a rig of a character trained on `clips` is fitted over: its bind pose and up
/// to [`FIT_POSES`] frames spread over the clips joined (for per-vertex models and light-map
/// models alike: texels lie on the same surface as vertices).
pub fn rig_fitting_surfaces(rig: &dyn Rig, clips: &[Clip]) -> anyhow::Result<Vec<Mesh>> {
    let clip = joined(clips.to_vec());
    fitting_meshes(rig, &clip)
        .with_context(|| format!("posing clip {} to fit the irradiance rig", clip.name))
}

/// The bytes of an irradiance rig of `kind` fitted to `meshes` ([`rig_fitting_surfaces`]: a
/// character's bind pose and training poses in its root frame; or up to [`FIT_POSES`] of the
/// meshes read from files), its error table computed at `order` on the first of them.
pub fn fit_irradiance_rig(kind: RigKind, meshes: &[Mesh], order: usize) -> anyhow::Result<Vec<u8>> {
    let refs: Vec<&Mesh> = meshes.iter().collect();
    let mut fitted = fit_rig(kind, &refs, None);
    fitted
        .tabulate(&meshes[0], order)
        .context("tabulating the irradiance rig's error")?;
    Ok(fitted.bytes())
}

/// Fits a rig of `kind` to `meshes`: the character's surface in its bind pose and training
/// poses, in its root frame. `samples` overrides the sample count. The error table is left
/// empty ([`FittedRig::tabulate`] fills it).
pub fn fit_rig(kind: RigKind, meshes: &[&Mesh], samples: Option<usize>) -> FittedRig {
    let (centre, half, radius) = bounds(meshes);
    let k = kind.shape.vectors();
    let mut rig = FittedRig {
        kind,
        centre,
        half,
        radius,
        samples: vec![centre],
        matrix: vec![1.0],
        table: Vec::new(),
    };
    if kind.centroid {
        return rig; // the paper's centroid rig: one probe at the centre
    }
    let n = samples.unwrap_or((SAMPLES_PER_VECTOR * k).max(MIN_SAMPLES));
    let mut points = surface_samples(meshes, n, SAMPLE_SEED);
    if points.is_empty() {
        // No triangle has area (a point cloud, or a flattened mesh): the vertices are the
        // surface. Returning the centroid's one-probe matrix here would give a rig whose
        // matrix does not match its kind's vectors, which the core refuses to read.
        points = meshes
            .iter()
            .flat_map(|m| &m.positions)
            .map(|p| p.map(f64::from))
            .collect();
    }
    let phi = design_matrix(kind.shape, &points, centre, half);
    rig.matrix = least_squares(&phi, &smoothness(kind.shape));
    rig.samples = points;
    rig
}

/// `Φ[i][k] = φ_k(s_i)`, from the core's own basis so the fit and the runtime agree.
fn design_matrix(
    shape: RigShape,
    points: &[[f64; 3]],
    centre: [f64; 3],
    half: [f64; 3],
) -> DMatrix<f64> {
    let half32 = half.map(|h| h as f32);
    let mut phi = DMatrix::zeros(points.len(), shape.vectors());
    for (i, p) in points.iter().enumerate() {
        let rel = std::array::from_fn(|a| (p[a] - centre[a]) as f32);
        for (k, w) in shape.weights(rel, half32).pairs() {
            phi[(i, k)] += f64::from(w);
        }
    }
    phi
}

/// Rows of first differences between neighbouring nodes along every lattice axis of a
/// product rig (empty for other axes and the gradient rig).
fn smoothness(shape: RigShape) -> DMatrix<f64> {
    let RigShape::Product(axes) = shape else {
        return DMatrix::zeros(0, shape.vectors());
    };
    let n = axes.map(AxisKind::functions);
    let index = |i: [usize; 3]| i[0] + n[0] * (i[1] + n[1] * i[2]);
    let mut rows: Vec<(usize, usize)> = Vec::new();
    for a in 0..3 {
        if !matches!(axes[a], AxisKind::Lattice(_)) {
            continue;
        }
        for z in 0..n[2] {
            for y in 0..n[1] {
                for x in 0..n[0] {
                    let i = [x, y, z];
                    if i[a] + 1 < n[a] {
                        let mut j = i;
                        j[a] += 1;
                        rows.push((index(i), index(j)));
                    }
                }
            }
        }
    }
    let mut d = DMatrix::zeros(rows.len(), shape.vectors());
    for (r, (i, j)) in rows.into_iter().enumerate() {
        d[(r, i)] = -1.0;
        d[(r, j)] = 1.0;
    }
    d
}

/// `L = (ΦᵀΦ + λ DᵀD + ε I)⁻¹ Φᵀ` (K × N, row-major), λ and ε relative to the mean diagonal of
/// ΦᵀΦ: the least-squares map of section 2.2, with the lattice smoothness for nodes no sample
/// constrains and a vanishing ridge so a rank-deficient Φ (coplanar samples under a gradient
/// rig) still has an answer.
fn least_squares(phi: &DMatrix<f64>, d: &DMatrix<f64>) -> Vec<f64> {
    let k = phi.ncols();
    let gram = phi.transpose() * phi;
    let scale = (gram.trace() / k as f64).max(f64::MIN_POSITIVE);
    let system = &gram
        + d.transpose() * d * (SMOOTHNESS * scale)
        + DMatrix::identity(k, k) * (1e-14 * scale);
    let l = match system.clone().cholesky() {
        Some(c) => c.solve(&phi.transpose()),
        // Positive definite by the ridge; the SVD is the fallback for rounding.
        None => system
            .svd(true, true)
            .solve(&phi.transpose(), 1e-15 * scale)
            .unwrap_or_else(|_| DMatrix::zeros(k, phi.nrows())),
    };
    // Row-major K × N.
    let mut out = Vec::with_capacity(l.len());
    for r in 0..l.nrows() {
        out.extend(l.row(r).iter());
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rig::Rig;
    use crate::rig::character::Character;
    use aprt_core::MAX_COEFFS;

    /// A field the rig represents exactly: `l(p) = Σ_k φ_k(p) C_k` for random C.
    fn field(shape: RigShape, seed: u64) -> Vec<Rgb> {
        let mut rng = crate::rig::procedural::clips::SplitMix(seed);
        (0..shape.vectors() * 9)
            .map(|_| std::array::from_fn(|_| (rng.next_unit() * 2.0 - 1.0) as f32))
            .collect()
    }

    #[test]
    fn a_field_in_the_rig_is_recovered_exactly() {
        let human = Character::builtin();
        let mesh = human.bind_mesh();
        for text in [
            "gradient",
            "mixed:x=lattice3,y=gradient,z=constant",
            "lattice:2x2x3",
            "mixed:x=gradient,y=gradient,z=gradient",
        ] {
            let kind: RigKind = text.parse().unwrap();
            let fitted = fit_rig(kind, &[mesh], None);
            let bytes = fitted.bytes();
            let rig = IrradianceRig::parse(&bytes).unwrap();
            let truth = field(kind.shape, 3);
            let mut scratch = [[0.0f32; 3]; MAX_COEFFS];
            let mut got = vec![[0.0f32; 3]; truth.len()];
            rig.vectors_from(
                9,
                &Placement::IDENTITY,
                &mut scratch,
                |p, l| rig.lighting_at(&truth, &Placement::IDENTITY, p, l),
                &mut got,
            )
            .unwrap();
            // The field itself, at every vertex of the surface, is what must come back.
            let (mut a, mut b) = ([[0.0f32; 3]; 9], [[0.0f32; 3]; 9]);
            let mut worst = 0.0f32;
            for p in &mesh.positions {
                rig.lighting_at(&truth, &Placement::IDENTITY, *p, &mut a);
                rig.lighting_at(&got, &Placement::IDENTITY, *p, &mut b);
                for (x, y) in a.iter().flatten().zip(b.iter().flatten()) {
                    worst = worst.max((x - y).abs());
                }
            }
            assert!(worst < 1e-4, "{text}: recovered within {worst}");
        }
    }

    #[test]
    fn constant_lighting_is_exact_everywhere_even_where_no_sample_is() {
        let human = Character::builtin();
        let mesh = human.bind_mesh();
        // An 8 × 4 × 2 lattice on the human leaves nodes in the empty corners of its box.
        for text in ["lattice:8x4x2", "constant", "gradient"] {
            let kind: RigKind = text.parse().unwrap();
            let bytes = fit_rig(kind, &[mesh], None).bytes();
            let rig = IrradianceRig::parse(&bytes).unwrap();
            let mut scratch = [[0.0f32; 3]; MAX_COEFFS];
            let mut vectors = vec![[0.0f32; 3]; rig.vectors() * 4];
            let constant = [
                [0.5, 1.0, 2.0],
                [0.1, 0.0, 0.2],
                [0.3, 0.3, 0.3],
                [0.0, 0.4, 0.0],
            ];
            rig.vectors_from(
                4,
                &Placement::IDENTITY,
                &mut scratch,
                |_, l| l.copy_from_slice(&constant),
                &mut vectors,
            )
            .unwrap();
            let mut here = [[0.0f32; 3]; 4];
            let [c, h] = [rig.centre(), rig.half()];
            for corner in directions() {
                let p = std::array::from_fn(|a| c[a] + h[a] * corner[a] as f32 * 1.2);
                rig.lighting_at(&vectors, &Placement::IDENTITY, p, &mut here);
                for (a, b) in here.iter().flatten().zip(constant.iter().flatten()) {
                    assert!((a - b).abs() < 1e-3, "{text} at {p:?}: {here:?}");
                }
            }
        }
    }

    /// A mesh without triangles (nothing to sample by area) is sampled at its vertices: every
    /// kind gives a rig the core reads, with one matrix row per vector.
    #[test]
    fn a_mesh_without_triangles_still_fits_a_readable_rig() {
        let positions: Vec<[f32; 3]> = (0..24)
            .map(|i| {
                let a = i as f32 * std::f32::consts::TAU / 24.0;
                [a.cos(), a.sin(), 0.1 * (i % 3) as f32]
            })
            .collect();
        let mesh = Mesh {
            normals: positions.clone(),
            positions,
            triangles: Vec::new(),
        };
        for kind in [
            "constant",
            "gradient",
            "lattice:2x2x2",
            "mixed:x=constant,y=gradient,z=lattice3",
        ] {
            let fitted = fit_rig(kind.parse().unwrap(), &[&mesh], None);
            let bytes = fitted.bytes();
            let rig = IrradianceRig::parse(&bytes).unwrap_or_else(|e| panic!("{kind}: {e}"));
            // The centroid rig probes at the centre alone; the others sample the vertices.
            let samples = if fitted.kind.centroid { 1 } else { 24 };
            assert_eq!(rig.samples(), samples, "{kind}");
        }
    }
}
