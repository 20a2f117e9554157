//! Rig-lit frames: the K SH vectors of an irradiance rig pushed through the pose weights
//! (`light_rig`), then each vertex shaded by the rig's lighting at its own position
//! (`shade_rig`): `shade_j = t_j · Σ_k φ_k(p_j) C_k = Σ_k φ_k(p_j) (t_j · C_k)`. The rig is
//! linear in the lighting, so each `t_j · C_k` is the ordinary O(k_v) shading of the pose model
//! with lighting `C_k`: a vertex costs 3 k_v per non-zero `φ_k` (at most eight), never n² k_v,
//! and its transfer keeps its self-shadowing.

use super::kernels::shade_bytes;
use super::weights::{check_capacity, check_stamp};
use super::{PoseWeights, finite_output, first_non_finite};
use crate::blob::format::VERTEX_BLOCK;
use crate::blob::{Error, Input, ModelInfo, Reader};
use crate::irradiance_rig::{
    IrradianceRig, MAX_RIG_VECTORS, Placement, RIG_SUPPORT, RigLitWeights, RigWeights,
};
use crate::rotation::Rotation;
use crate::sh::MAX_COEFFS;

/// Most distinct rig vectors the eight vertices of a block can touch.
const BLOCK_VECTORS: usize = VERTEX_BLOCK * RIG_SUPPORT;

impl ModelInfo {
    /// Values [`RigLitWeights`] must hold for this model and a rig of `vectors` SH vectors:
    /// one [`LitWeights`](crate::LitWeights) per vector and colour channel.
    pub fn rig_lit_weights_len(&self, vectors: usize) -> usize {
        3 * vectors * self.lit_weights_len()
    }

    pub(crate) fn light_rig<const P: usize>(
        &self,
        pose: &PoseWeights<P>,
        vectors: &[[f32; 3]],
        bones: &[Rotation],
        lit: &mut RigLitWeights<'_>,
    ) -> Result<(), Error> {
        lit.stamp = None;
        self.check_lighting_inputs(pose, bones)?;
        let n2 = self.coeffs();
        let k = vectors.len() / n2;
        if !vectors.len().is_multiple_of(n2) || !(1..=MAX_RIG_VECTORS).contains(&k) {
            return Err(Error::WrongLength {
                what: Input::RigVectors,
                expected: n2 * k.clamp(1, MAX_RIG_VECTORS),
                found: vectors.len(),
            });
        }
        if let Some(index) = vectors.iter().position(|c| first_non_finite(c).is_some()) {
            return Err(Error::NonFiniteLighting { index });
        }
        let lit_len = self.lit_weights_len();
        check_capacity(self.rig_lit_weights_len(k), lit.q.len())?;
        self.check_rotations(bones)?;
        let mut channel = [0.0f32; MAX_COEFFS];
        let sets = lit.q.chunks_exact_mut(lit_len);
        for (set, q) in sets.take(3 * k).enumerate() {
            let (kk, ch) = (set / 3, set % 3);
            for (l, c) in channel.iter_mut().zip(&vectors[kk * n2..(kk + 1) * n2]) {
                *l = c[ch];
            }
            self.light_checked(pose, &channel[..n2], bones, q);
        }
        finite_output(&mut lit.q[..3 * k * lit_len])?;
        lit.vectors = k;
        lit.stamp = Some(self.id);
        Ok(())
    }

    /// What `shade_rig` checks of its inputs: rig weights of this model and this rig, `count`
    /// finite positions.
    pub(super) fn check_rig_inputs(
        &self,
        lit: &RigLitWeights<'_>,
        rig: &IrradianceRig<'_>,
        (positions, count): (&[[f32; 3]], usize),
    ) -> Result<(), Error> {
        check_stamp(lit.stamp, self)?;
        if lit.vectors != rig.vectors() {
            return Err(Error::WeightsForOtherRig);
        }
        check_positions(positions, count)
    }

    #[allow(clippy::too_many_arguments)]
    pub(crate) fn shade_rig<R: Reader>(
        &self,
        r: &mut R,
        lit: &RigLitWeights<'_>,
        rig: &IrradianceRig<'_>,
        placement: &Placement,
        positions: &[[f32; 3]],
        first: usize,
        out: &mut [[f32; 3]],
    ) -> Result<(), Error> {
        self.check_rig_inputs(lit, rig, (positions, out.len()))?;
        self.check_range(first, out.len())?;
        let (width, lit_len) = (self.row_width(), self.lit_weights_len());
        let encoding = self.rows.encoding;
        let end = first + out.len();
        self.each_block(r, first, out.len(), |v0, bones, bytes| {
            let (lo, hi) = (v0.max(first), (v0 + VERTEX_BLOCK).min(end));
            let empty = RigWeights {
                index: [0; RIG_SUPPORT],
                weight: [0.0; RIG_SUPPORT],
                len: 0,
            };
            let lanes: [RigWeights; VERTEX_BLOCK] = core::array::from_fn(|l| {
                let j = v0 + l;
                match (lo..hi).contains(&j) {
                    true => rig.weights_at(placement.to_root(positions[j - first])),
                    false => empty,
                }
            });
            let (touched, count) = touched_vectors(&lanes);
            // Each lane's weight per touched vector (0 where it has none), so the loop below
            // runs over eight lanes at once without looking anything up.
            let mut phi = [[0.0f32; VERTEX_BLOCK]; BLOCK_VECTORS];
            for (l, lane) in lanes.iter().enumerate() {
                for (k, w) in lane.pairs() {
                    phi[touched[..count].partition_point(|&t| t < k)][l] += w;
                }
            }
            // `t_j · C_k` eight lanes at a time for each vector the block touches, in ascending
            // k: a vertex sums its terms in the same order whichever others share its block or
            // the call (another vertex's vectors add exact zeros).
            let mut acc = [[0.0f32; 3]; VERTEX_BLOCK];
            for (&k, phi_k) in touched[..count].iter().zip(&phi) {
                let sets = lit.q[3 * k * lit_len..].chunks_exact(lit_len);
                for (ch, q) in sets.take(3).enumerate() {
                    let dots = shade_bytes(encoding, bytes, q, width, bones);
                    for l in 0..VERTEX_BLOCK {
                        acc[l][ch] += phi_k[l] * dots[l];
                    }
                }
            }
            out[lo - first..hi - first].copy_from_slice(&acc[lo - v0..hi - v0]);
        })?;
        finite_output(out.as_flattened_mut())
    }
}

/// Positions must be one per output value (vertex or texel), and finite.
pub(crate) fn check_positions(positions: &[[f32; 3]], count: usize) -> Result<(), Error> {
    if positions.len() != count {
        return Err(Error::WrongLength {
            what: Input::Positions,
            expected: count,
            found: positions.len(),
        });
    }
    match first_non_finite(positions.as_flattened()) {
        Some(i) => Err(Error::NonFinitePosition { index: i / 3 }),
        None => Ok(()),
    }
}

/// The distinct rig vectors any lane of a block uses, ascending, and how many there are.
fn touched_vectors(lanes: &[RigWeights; VERTEX_BLOCK]) -> ([usize; BLOCK_VECTORS], usize) {
    let mut touched = [0usize; BLOCK_VECTORS];
    let mut count = 0;
    for (k, _) in lanes.iter().flat_map(RigWeights::pairs) {
        // Insertion into the sorted prefix; a block touches a few dozen vectors at most.
        let at = touched[..count].partition_point(|&t| t < k);
        if touched.get(at) != Some(&k) || at == count {
            touched.copy_within(at..count, at + 1);
            touched[at] = k;
            count += 1;
        }
    }
    (touched, count)
}
