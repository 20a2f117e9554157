//! An irradiance rig's bytes (the blob's `IrradianceRig` section, or a rig on its own), read in
//! place after one validation, and the per-frame steps that only need the rig.
//!
//! ```text
//! offset  size    field
//! 0       1       shape: 0 product of axes, 1 gradient
//! 1       3       axis codes x, y, z (product; 0 for a gradient): 0 constant, 1 linear,
//!                 n ≥ 2 a lattice of n nodes
//! 4       4       N, sample points, u32 LE
//! 8       4       K, SH vectors (what the shape gives), u32 LE
//! 12      4       M, error-table entries, u32 LE
//! 16      12      centre of the rig's box, root frame, 3 f32
//! 28      12      half-widths of the box, 3 f32, > 0
//! 40      4       radius R of the character about the centre, f32, > 0
//! 44      8 M     error table: (distance / R, grey levels per unit strength), distances
//!                 increasing
//! ..      12 N    sample points, root frame
//! ..      4 K N   the fit matrix L, row k holds every sample's weight for vector k
//! ```
//! Every value is a little-endian f32 after the 16-byte prelude, and finite.

use super::Placement;
use super::check::{PRELUDE, RigCheck, RigFailure};
use super::shape::{AxisKind, RigShape, RigWeights};
use crate::blob::{Dim, Error, Input};
use crate::light::Light;
use crate::sh::{MAX_COEFFS, MAX_ORDER, coeff_count};

/// A rig as the trainer builds it, for [`RigLayout::write`].
#[derive(Clone, Copy, Debug)]
pub struct RigLayout<'a> {
    /// The basis functions.
    pub shape: RigShape,
    /// Centre of the rig's box in the root frame.
    pub centre: [f32; 3],
    /// Half-widths of the box.
    pub half: [f32; 3],
    /// Radius of the character about the centre: the unit of the error table's distances.
    pub radius: f32,
    /// (distance / radius, grey levels per unit strength), distances increasing.
    pub table: &'a [[f32; 2]],
    /// Sample points in the root frame.
    pub samples: &'a [[f32; 3]],
    /// The fit matrix, K rows of N.
    pub matrix: &'a [f32],
}

impl RigLayout<'_> {
    /// Bytes [`RigLayout::write`] needs.
    pub fn len(&self) -> usize {
        PRELUDE + 4 * (2 * self.table.len() + 3 * self.samples.len() + self.matrix.len())
    }

    /// Always false: a rig has a prelude.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// Writes the rig's bytes into the start of `out`; the count written, or
    /// [`Error::BufferTooSmall`]. The bytes are not checked here: [`IrradianceRig::parse`] them.
    pub fn write(&self, out: &mut [u8]) -> Result<usize, Error> {
        let len = self.len();
        let out = out
            .get_mut(..len)
            .ok_or(Error::BufferTooSmall { needed: len })?;
        let (shape, axes) = match self.shape {
            RigShape::Gradient => (1, [0; 3]),
            RigShape::Product(axes) => (0, axes.map(AxisKind::code)),
        };
        out[0] = shape;
        out[1..4].copy_from_slice(&axes);
        let counts = [self.samples.len(), self.shape.vectors(), self.table.len()];
        for (dst, n) in out[4..16].chunks_exact_mut(4).zip(counts) {
            dst.copy_from_slice(&(n as u32).to_le_bytes());
        }
        let values = self
            .centre
            .iter()
            .chain(&self.half)
            .chain(core::iter::once(&self.radius))
            .chain(self.table.iter().flatten())
            .chain(self.samples.iter().flatten())
            .chain(self.matrix);
        for (dst, v) in out[16..].chunks_exact_mut(4).zip(values) {
            dst.copy_from_slice(&v.to_le_bytes());
        }
        Ok(len)
    }
}

/// A validated irradiance rig over its bytes: from a model
/// ([`Model::irradiance_rig`](crate::Model::irradiance_rig)) or on
/// its own ([`IrradianceRig::parse`]).
///
/// One frame of rig lighting, as an engine runs it (here with a gradient rig written by hand;
/// `aprt train --rig KIND` fits one to the character and stores it in the model):
///
/// ```
/// use aprt_core::*;
///
/// let model = Model::parse(include_bytes!("../../../fixtures/golden/v1-bones.aprt"))?;
/// let samples = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
/// // C = L · l(samples): the centre's lighting and three differences, a gradient.
/// let matrix = [
///     1.0, 0.0, 0.0, 0.0, // l_c
///     -1.0, 1.0, 0.0, 0.0, // g_x
///     -1.0, 0.0, 1.0, 0.0, // g_y
///     -1.0, 0.0, 0.0, 1.0, // g_z
/// ];
/// let layout = RigLayout {
///     shape: RigShape::Gradient,
///     centre: [0.0; 3],
///     half: [1.0; 3],
///     radius: 1.0,
///     table: &[[1.5, 40.0], [4.0, 3.0], [16.0, 0.2]],
///     samples: &samples,
///     matrix: &matrix,
/// };
/// let mut bytes = vec![0u8; layout.len()];
/// layout.write(&mut bytes)?;
/// let rig = IrradianceRig::parse(&bytes)?;
///
/// // Per frame: the pose, each light's share (far lights in the rig, near ones per vertex).
/// let info = *model.info();
/// let mut pose = PoseWeights::new();
/// model.set_pose(&[0.1, 0.0, -0.2, 0.3, 0.0], &mut pose)?;
/// let bones = [[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]; 3];
/// let lights = [
///     Light::Point(PointLight { position: [0.0, 0.0, 30.0], intensity: [9.0; 3] }),
///     Light::Sphere(SphereLight { position: [0.3, 1.2, 0.0], radius: 0.1, radiance: [50.0; 3] }),
/// ];
/// let place = Placement::IDENTITY; // the character's root in the world
/// let share: Vec<f32> = lights.iter().map(|l| rig.share_of(l, &place, 1.0, DEFAULT_BAND)).collect();
/// assert_eq!(share, [1.0, 0.0]); // the far light in the rig, the near one per vertex
///
/// // The rig's K SH vectors from the rig's share of each light (a shader's uniforms)...
/// let in_rig: Vec<Light> = lights.iter().zip(&share).map(|(l, &s)| l.scaled(s)).collect();
/// let mut vectors = vec![[0.0; 3]; rig.vectors() * info.coeffs()];
/// rig.vectors_from_lights(info.order(), &place, &in_rig, &[], &mut vectors)?;
/// // ...pushed through the pose model, and every vertex shaded at its own position, with the
/// // rest of each light per vertex through the vertex's transfer: both self-shadowed.
/// let mut buffer = vec![0.0; info.rig_lit_weights_len(rig.vectors())];
/// let mut lit = RigLitWeights::new(&mut buffer);
/// model.light_rig(&pose, &vectors, &bones, &mut lit)?;
/// let positions = vec![[0.0, 0.5, 0.0]; info.vertices()]; // skinned by the engine
/// let mut rgb = vec![[0.0; 3]; info.vertices()];
/// model.shade_rig(&lit, &rig, &place, &positions, 0, &mut rgb)?;
/// let rest: Vec<f32> = share.iter().map(|s| 1.0 - s).collect();
/// model.shade_lights(&pose, &bones, &lights, &rest, &positions, 0, &mut rgb)?;
/// assert!(rgb.iter().flatten().all(|x| x.is_finite()));
/// # Ok::<(), aprt_core::Error>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IrradianceRig<'a> {
    shape: RigShape,
    centre: [f32; 3],
    half: [f32; 3],
    radius: f32,
    table: &'a [[u8; 4]],
    samples: &'a [[u8; 4]],
    matrix: &'a [[u8; 4]],
}

fn f32_at(words: &[[u8; 4]], i: usize) -> f32 {
    f32::from_le_bytes(words[i])
}

impl<'a> IrradianceRig<'a> {
    /// Validates a rig's bytes: the shape, the counts against their limits and the length,
    /// every value finite, a positive box and radius, an increasing table of non-negative
    /// errors. Anything else is [`Error::BadIrradianceRig`] (or [`Error::Truncated`]).
    pub fn parse(bytes: &'a [u8]) -> Result<IrradianceRig<'a>, Error> {
        let mut check = RigCheck::new();
        check.feed(bytes);
        let layout = check.finish().map_err(|failure| match failure {
            RigFailure::Content(e) => e,
            RigFailure::Length { expected } if bytes.len() < expected => Error::Truncated {
                needed: expected as u64,
            },
            RigFailure::Length { .. } => Error::BadIrradianceRig,
        })?;
        let words = bytes[16..].as_chunks::<4>().0;
        let (head, rest) = words.split_at(7);
        let (table, rest) = rest.split_at(2 * layout.table);
        let (samples, matrix) = rest.split_at(3 * layout.samples);
        Ok(IrradianceRig {
            shape: layout.shape,
            centre: core::array::from_fn(|i| f32_at(head, i)),
            half: core::array::from_fn(|i| f32_at(head, 3 + i)),
            radius: f32_at(head, 6),
            table,
            samples,
            matrix,
        })
    }

    /// The basis functions.
    pub fn shape(&self) -> RigShape {
        self.shape
    }
    /// SH vectors K.
    pub fn vectors(&self) -> usize {
        self.shape.vectors()
    }
    /// Sample points N.
    pub fn samples(&self) -> usize {
        self.samples.len() / 3
    }
    /// Centre of the rig's box, root frame.
    pub fn centre(&self) -> [f32; 3] {
        self.centre
    }
    /// Half-widths of the box.
    pub fn half(&self) -> [f32; 3] {
        self.half
    }
    /// The character's radius about the centre.
    pub fn radius(&self) -> f32 {
        self.radius
    }
    /// Sample point `i` in the root frame (`i < N`).
    pub fn sample(&self, i: usize) -> [f32; 3] {
        core::array::from_fn(|a| f32_at(self.samples, 3 * i + a))
    }
    /// Error-table entries.
    pub fn table_len(&self) -> usize {
        self.table.len() / 2
    }
    /// Error-table entry `i`: (distance / radius, grey levels per unit strength).
    pub fn table_entry(&self, i: usize) -> [f32; 2] {
        [f32_at(self.table, 2 * i), f32_at(self.table, 2 * i + 1)]
    }

    /// The weights `φ_k` at a root-frame point.
    pub fn weights_at(&self, p_root: [f32; 3]) -> RigWeights {
        let p = core::array::from_fn(|i| p_root[i] - self.centre[i]);
        self.shape.weights(p, self.half)
    }

    /// The rig's K SH vectors from the lighting at its sample points: `sample(p, out)` adds
    /// the lighting at world point `p` into `out` (n² RGB coefficients, zeroed before each
    /// call); `out` receives `C_k = Σ_i L_ki l_i`, vector-major (`out[k · n² + c]`).
    /// `scratch` holds one sample's lighting (at least n² entries). Costs N light projections
    /// and 3 K N n² multiply–adds.
    pub fn vectors_from(
        &self,
        coeffs: usize,
        placement: &Placement,
        scratch: &mut [[f32; 3]],
        mut sample: impl FnMut([f32; 3], &mut [[f32; 3]]),
        out: &mut [[f32; 3]],
    ) -> Result<(), Error> {
        let k = self.vectors();
        let need = |found: usize, expected: usize| {
            if found < expected {
                Err(Error::BufferTooSmall { needed: expected })
            } else {
                Ok(())
            }
        };
        need(scratch.len(), coeffs)?;
        need(out.len(), k * coeffs)?;
        let (l, out) = (&mut scratch[..coeffs], &mut out[..k * coeffs]);
        out.fill([0.0; 3]);
        let n = self.samples();
        for i in 0..n {
            l.fill([0.0; 3]);
            sample(placement.to_world(self.sample(i)), l);
            for (kk, ck) in out.chunks_exact_mut(coeffs).enumerate() {
                let w = f32_at(self.matrix, kk * n + i);
                for (c, li) in ck.iter_mut().zip(l.iter()) {
                    for ch in 0..3 {
                        c[ch] += w * li[ch];
                    }
                }
            }
        }
        Ok(())
    }

    /// The rig's K SH vectors for `lights` and a uniform `environment` (n² RGB radiance
    /// coefficients, or empty): each light projected at every sample ([`Light::add_radiance_sh`];
    /// a sample whose offset to a light overflows f32 skips that light), then mapped by the fit matrix
    /// ([`IrradianceRig::vectors_from`]). Every light is validated first
    /// ([`Error::BadLight`]). What an engine calls once per frame; the vectors go to
    /// [`Model::light_rig`](crate::Model::light_rig) or to a shader.
    pub fn vectors_from_lights(
        &self,
        order: usize,
        placement: &Placement,
        lights: &[Light],
        environment: &[[f32; 3]],
        out: &mut [[f32; 3]],
    ) -> Result<(), Error> {
        let coeffs = coeff_count(order);
        if order == 0 || order > MAX_ORDER {
            return Err(Error::BadDimension {
                what: Dim::Order,
                value: order as u64,
            });
        }
        if !environment.is_empty() && environment.len() != coeffs {
            return Err(Error::WrongLength {
                what: Input::Lighting,
                expected: coeffs,
                found: environment.len(),
            });
        }
        if let Some(index) = environment
            .iter()
            .position(|c| c.iter().any(|x| !x.is_finite()))
        {
            return Err(Error::NonFiniteLighting { index });
        }
        for (index, light) in lights.iter().enumerate() {
            light
                .validate()
                .map_err(|reason| Error::BadLight { index, reason })?;
        }
        let mut scratch = [[0.0f32; 3]; MAX_COEFFS];
        self.vectors_from(
            coeffs,
            placement,
            &mut scratch,
            |p, l| {
                l.iter_mut().zip(environment).for_each(|(a, e)| *a = *e);
                for light in lights {
                    let _ = light.add_radiance_sh(order, p, l);
                }
            },
            out,
        )
    }

    /// The rig's lighting at a world point: `Σ_k φ_k(p) C_k` into `out` (n² RGB).
    pub fn lighting_at(
        &self,
        vectors: &[[f32; 3]],
        placement: &Placement,
        p_world: [f32; 3],
        out: &mut [[f32; 3]],
    ) {
        let coeffs = out.len();
        out.fill([0.0; 3]);
        for (k, w) in self.weights_at(placement.to_root(p_world)).pairs() {
            let Some(ck) = vectors.get(k * coeffs..(k + 1) * coeffs) else {
                continue;
            };
            for (o, c) in out.iter_mut().zip(ck) {
                for ch in 0..3 {
                    o[ch] += w * c[ch];
                }
            }
        }
    }
}
