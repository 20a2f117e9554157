//! What a device that runs the per-vertex loops itself (a GPU: `aprt-gpu`) needs: the vertex
//! rows as the blob stores them, and the per-frame weights that multiply them. The small
//! per-frame steps (pose, lighting, bone rotations) stay here, so every device computes them
//! with the same bits and only the loops over vertices move.

use super::weights::{LitWeights, PoseWeights, check_stamp};
use crate::blob::format::{Basis, Encoding, VERTEX_BLOCK};
use crate::blob::{Error, ModelInfo, Span};

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

#[cfg(test)]
mod tests {
    use crate::{LitWeights, Model, PoseWeights, VERTEX_BLOCK};

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
