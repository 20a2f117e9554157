//! What a device that runs the per-vertex loops itself (a GPU: `aprt-gpu`) needs: the vertex
//! rows as the blob stores them, and the per-frame weights that multiply them. The small
//! per-frame steps (pose, lighting, bone rotations) stay here, so every device computes them
//! with the same bits and only the loops over vertices move.

use super::weights::{LitWeights, PoseWeights, check_stamp};
use crate::blob::format::{Basis, Encoding, VERTEX_BLOCK};
use crate::blob::{Error, ModelInfo, Span};
use crate::irradiance_rig::{IrradianceRig, RigLitWeights};
use crate::proxies::{MAX_PROXIES, ProxyFrame};
use crate::rotation::Rotation;

/// The per-vertex rows of a resident model, as stored: blocks of [`VERTEX_BLOCK`] vertices,
/// each `lead_rows` rows of bone indices (bone-frame models) then `row_width` rows, every row
/// [`VERTEX_BLOCK`] values of `encoding` (one per vertex of the block, little-endian). The
/// bone indices are exact integers in the row's encoding (unsigned bytes for
/// [`Encoding::I8`]); [`Encoding::I8`] rows hold integers whose scales the per-frame weights
/// carry.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VertexRows<'a> {
    /// The rows section: `blocks` blocks of `VERTEX_BLOCK · (lead_rows + row_width)` values.
    pub bytes: &'a [u8],
    /// The encoding of every value.
    pub encoding: Encoding,
    /// Rows of bone indices per block: 1 for a bone-frame model, else 0.
    pub lead_rows: usize,
    /// Rows of values per block ([`ModelInfo::row_width`]).
    pub row_width: usize,
    /// Blocks: the vertex count rounded up to a whole block.
    pub blocks: usize,
}

impl ModelInfo {
    /// The rows section of the resident `blob` this info was read from (`Model::parse`
    /// checked that the span lies inside it).
    pub(crate) fn vertex_rows<'a>(&self, blob: &'a [u8]) -> VertexRows<'a> {
        let Span { offset, len, .. } = self.rows;
        VertexRows {
            bytes: &blob[offset as usize..(offset + len) as usize],
            encoding: self.rows.encoding,
            lead_rows: self.lead_rows(),
            row_width: self.row_width(),
            blocks: self.vertices.div_ceil(VERTEX_BLOCK),
        }
    }

    /// Values [`ModelInfo::transfer_weights`] writes: n² k_v for a stored basis, n²(1 + k_a)
    /// for an identity basis.
    pub fn transfer_weights_len(&self) -> usize {
        match self.basis {
            Basis::Stored => self.coeffs() * self.coef_dims,
            Basis::Identity => self.row_width(),
        }
    }

    /// The weights of the lighting in `lit` ([`ModelInfo::lit_weights_len`] values: per bone,
    /// one per value of a vertex row), checked to belong to this model. A vertex's shading is
    /// `Σ_r q[bone · row_width + r] U_r`, its rows `U` as [`VertexRows`] stores them.
    pub fn lit_values<'l, const L: usize>(
        &self,
        lit: &'l LitWeights<L>,
    ) -> Result<&'l [f32], Error> {
        check_stamp(lit.stamp, self)?;
        Ok(&lit.q[..self.lit_weights_len()])
    }

    /// Writes into `out` ([`ModelInfo::transfer_weights_len`] values) what each vertex row
    /// contributes to each transfer coefficient for the pose in `pose`: for a stored basis
    /// `t_c = Σ_k out[k n² + c] U_k`; for an identity basis row `r = c (1 + k_a) + i` feeds
    /// coefficient c alone, `t_c = Σ_i out[r] X_r`. Scaled-byte rows' scales are folded in, as
    /// [`Model::transfer`](crate::Model::transfer) folds them.
    pub fn transfer_weights<const P: usize>(
        &self,
        pose: &PoseWeights<P>,
        out: &mut [f32],
    ) -> Result<(), Error> {
        check_stamp(pose.stamp, self)?;
        let len = self.transfer_weights_len();
        if out.len() != len {
            return Err(Error::WrongLength {
                what: crate::Input::Transfer,
                expected: len,
                found: out.len(),
            });
        }
        match self.basis {
            Basis::Stored => out.copy_from_slice(&pose.w[..len]),
            Basis::Identity => {
                let z = self.identity_weights(pose);
                for (c, o) in out.chunks_exact_mut(z.len).enumerate() {
                    o.copy_from_slice(z.of(c));
                }
            }
        }
        Ok(())
    }
}

/// A frame's posed occluder proxies as a device reads them, checked against the per-vertex
/// inputs of the frame ([`ModelInfo::proxy_inputs`]): every proxy's posed sphere, each bone's
/// mask of the proxies that may reach its vertices, and the cull. A vertex of bone `b` loses
/// the caps of the proxies of `mask(b)` within their reach, summed in proxy order and
/// combined as aprt-core's `Model::occlude` combines them.
#[derive(Clone, Copy, Debug)]
pub struct ProxyView<'f> {
    frame: &'f ProxyFrame,
    bones: usize,
}

impl ProxyView<'_> {
    /// `sin²α` below which a cap is dropped (faded in over `[cull, 2 cull]`).
    pub fn cull(&self) -> f32 {
        self.frame.cull
    }

    /// Proxy `i` (below [`MAX_PROXIES`]): posed centre, radius and reach (`r / √cull`,
    /// infinite when nothing is culled). Proxies no mask holds are zero.
    pub fn sphere(&self, i: usize) -> ([f32; 3], f32, f32) {
        let s = self.frame.sphere(i % MAX_PROXIES);
        (s.centre, s.radius, s.reach)
    }

    /// The proxies that may reach bone `bone`'s vertices this frame, bit `i` for proxy `i`.
    pub fn mask(&self, bone: usize) -> u64 {
        self.frame.candidates.get(bone).copied().unwrap_or(0)
    }

    /// Bones with a mask: [`ModelInfo::bones`].
    pub fn bones(&self) -> usize {
        self.bones
    }
}

impl ModelInfo {
    /// The posed proxies of `frame` for a device that subtracts them from every vertex's
    /// shading or transfer, after the checks `Model::occlude` and `Model::occlude_transfer`
    /// make: `frame` posed for this model, one finite position and normal per vertex, the
    /// lighting (`Some`, for shading) n² finite values, the rotations (`Some`, for transfer)
    /// one proper rotation per bone.
    pub fn proxy_inputs<'f>(
        &self,
        frame: &'f ProxyFrame,
        (positions, normals): (&[[f32; 3]], &[[f32; 3]]),
        lighting: Option<&[f32]>,
        rotations: Option<&[Rotation]>,
    ) -> Result<ProxyView<'f>, Error> {
        if let Some(lighting) = lighting {
            self.check_sh_lighting(lighting)?;
        }
        if let Some(bones) = rotations {
            self.check_bone_rotations(bones)?;
        }
        self.check_occlusion_inputs(frame, positions, normals, 0, self.vertices)?;
        Ok(ProxyView {
            frame,
            bones: self.bones(),
        })
    }
}

impl ModelInfo {
    /// Checks the inputs of per-vertex lights over every vertex as `Model::shade_lights`
    /// checks them (pose weights of this model, its bones' rotations, valid lights, one
    /// finite non-negative weight per light, one finite position per vertex), for a device
    /// that evaluates them itself ([`Light::shape`](crate::Light::shape) gives each light's
    /// geometry).
    pub fn light_inputs<const P: usize>(
        &self,
        pose: &PoseWeights<P>,
        bones: &[Rotation],
        (lights, weights): (&[crate::Light], &[f32]),
        positions: &[[f32; 3]],
    ) -> Result<(), Error> {
        self.check_light_inputs(pose, bones, (lights, weights), (positions, self.vertices))
    }
}

impl ModelInfo {
    /// The rig-lit weights of `lit` (from `Model::light_rig`, `3 K` sets of
    /// [`ModelInfo::lit_weights_len`] values, set `3k + channel` for vector k), after the
    /// checks `Model::shade_rig` makes: weights of this model and of `rig`, one finite position
    /// per vertex. A vertex's shading in a channel is `Σ_k φ_k(p) Σ_r q_k[bone · width + r]
    /// U_r`, `φ_k` from [`IrradianceRig::weights_at`](crate::IrradianceRig::weights_at).
    pub fn rig_inputs<'l>(
        &self,
        lit: &'l RigLitWeights<'_>,
        rig: &IrradianceRig<'_>,
        positions: &[[f32; 3]],
    ) -> Result<&'l [f32], Error> {
        self.check_rig_inputs(lit, rig, (positions, self.vertices))?;
        Ok(&lit.q[..self.rig_lit_weights_len(lit.vectors)])
    }
}

#[cfg(test)]
mod tests {
    use crate::{Error, LitWeights, Model, PoseWeights, ProxyFrame, VERTEX_BLOCK};

    /// The proxy view refuses what `occlude` and `occlude_transfer` refuse, and shows the
    /// frame's masks and spheres.
    #[test]
    fn the_proxy_view_checks_what_occlude_checks() {
        let model =
            Model::parse(include_bytes!("../../../fixtures/golden/v1-proxies.aprt")).unwrap();
        let info = *model.info();
        let identity = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let still = [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0];
        let bones = [identity; 2];
        let mut frame = ProxyFrame::new();
        let v = info.vertices();
        let (p, n) = ([[0.0f32; 3]; 64], [[0.0f32, 0.0, 1.0]; 64]);
        let vertices = (&p[..v], &n[..v]);
        let light = [1.0f32; 36];
        let n2 = info.coeffs();
        let unposed = info.proxy_inputs(&frame, vertices, None, None);
        assert_eq!(unposed.err(), Some(Error::WeightsNotSet));
        model.pose_proxies(&[still; 2], &mut frame).unwrap();
        let view = info
            .proxy_inputs(&frame, vertices, Some(&light[..n2]), Some(&bones))
            .unwrap();
        assert_eq!(view.bones(), info.bones());
        for b in 0..info.bones() {
            assert_eq!(view.mask(b).count_ones(), frame.candidates(b));
        }
        assert!(view.sphere(0).1 > 0.0);
        let short = (&p[..v - 1], &n[..v - 1]);
        assert!(info.proxy_inputs(&frame, short, None, None).is_err());
        let wrong_lighting = info.proxy_inputs(&frame, vertices, Some(&light[..n2 - 1]), None);
        assert!(wrong_lighting.is_err());
        let one_bone = info.proxy_inputs(&frame, vertices, None, Some(&bones[..1]));
        assert!(one_bone.is_err());
    }

    /// Every golden blob: shading and transfer recomputed from the rows and the weights these
    /// calls give, in f64 and in plain row order, match `shade` and `transfer` within f32
    /// rounding: what a device does with them is what the CPU does.
    #[test]
    fn the_rows_and_weights_give_the_cpus_shading_and_transfer() {
        let golden: [&[u8]; 5] = [
            include_bytes!("../../../fixtures/golden/v1-world.aprt"),
            include_bytes!("../../../fixtures/golden/v1-bones.aprt"),
            include_bytes!("../../../fixtures/golden/v1-proxies.aprt"),
            include_bytes!("../../../fixtures/golden/v1-atlas.aprt"),
            include_bytes!("../../../fixtures/golden/v1-atlas-uvs.aprt"),
        ];
        for blob in golden {
            let model = Model::parse(blob).unwrap();
            let info = *model.info();
            let rows = model.vertex_rows();
            let (mut pose, mut lit) = (PoseWeights::new(), LitWeights::new());
            let angles: [f32; 64] = core::array::from_fn(|i| 0.1 * (i as f32 - 2.5));
            model
                .set_pose(&angles[..info.pose_len()], &mut pose)
                .unwrap();
            let n2 = info.coeffs();
            let lighting: [f32; 36] = core::array::from_fn(|c| 1.0 / (1.0 + c as f32));
            let turn = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]];
            let bones = [turn; crate::MAX_BONES];
            model
                .light(&pose, &lighting[..n2], &bones[..info.bones()], &mut lit)
                .unwrap();
            let q = info.lit_values(&lit).unwrap();
            let mut w = [0.0f32; crate::MAX_POSE_WEIGHTS];
            let w = &mut w[..info.transfer_weights_len()];
            info.transfer_weights(&pose, w).unwrap();
            let value = |block: usize, row: usize, lane: usize| {
                let size = rows.encoding.size();
                let block_len = VERTEX_BLOCK * (rows.lead_rows + rows.row_width) * size;
                let at = block * block_len + (row * VERTEX_BLOCK + lane) * size;
                let b = &rows.bytes[at..at + size];
                f64::from(match rows.encoding {
                    crate::Encoding::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
                    crate::Encoding::F16 => half::f16::from_le_bytes([b[0], b[1]]).to_f32(),
                    crate::Encoding::I8 if row < rows.lead_rows => f32::from(b[0]),
                    crate::Encoding::I8 => f32::from(b[0] as i8),
                })
            };
            let width = rows.row_width;
            let mut shade = [0.0f32; 1];
            let mut transfer = [0.0f32; 36];
            for v in 0..info.vertices() {
                let (block, lane) = (v / VERTEX_BLOCK, v % VERTEX_BLOCK);
                let bone = match rows.lead_rows {
                    0 => 0,
                    _ => value(block, 0, lane) as usize,
                };
                let u = |k: usize| value(block, rows.lead_rows + k, lane);
                let expected: f64 = (0..width)
                    .map(|k| f64::from(q[bone * width + k]) * u(k))
                    .sum();
                model.shade(&lit, v, &mut shade).unwrap();
                let scale: f64 = (0..width)
                    .map(|k| (f64::from(q[bone * width + k]) * u(k)).abs())
                    .sum();
                assert!((f64::from(shade[0]) - expected).abs() <= 1e-6 * scale.max(1e-30));
                model.transfer(&pose, v, &mut transfer[..n2]).unwrap();
                for (c, &t) in transfer[..n2].iter().enumerate() {
                    let (expected, scale) = match info.basis() {
                        crate::Basis::Stored => (0..width).fold((0.0, 0.0), |(s, a), k| {
                            let x = f64::from(w[k * n2 + c]) * u(k);
                            (s + x, a + x.abs())
                        }),
                        crate::Basis::Identity => {
                            let per = width / n2;
                            (c * per..(c + 1) * per).fold((0.0, 0.0), |(s, a), r| {
                                let x = f64::from(w[r]) * u(r);
                                (s + x, a + x.abs())
                            })
                        }
                    };
                    assert!((f64::from(t) - expected).abs() <= 1e-6 * f64::max(scale, 1e-30));
                }
            }
        }
    }
}
