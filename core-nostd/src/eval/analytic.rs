//! Per-vertex ("analytic") lights through the pose model's transfer. An irradiance rig carries
//! far lights cheaply, but a light near the character varies too fast over it; *Irradiance
//! Rigs* (Yuan, Nowrouzezahrai and Sloan) evaluates such lights per vertex instead, against
//! the vertex's own transfer, so they stay self-shadowed.
//!
//! `shade_j += Σ_i w_i c_i Σ_l b_il Σ_m t_j,lm y_lm(R_bᵀ ω_ij)`: the light's radiance seen from
//! `p_j` is zonal about the direction `ω_ij` towards it (bands `b_il`), so in the vertex's bone
//! frame it is the same bands about the rotated direction. Rotating that one direction costs
//! nine multiplies per vertex and light, where rotating the SH vector would cost O(n³).

use super::rig::check_positions;
use super::{PoseWeights, finite_output};
use crate::blob::format::{Frame, VERTEX_BLOCK};
use crate::blob::{Error, Input, ModelInfo, Reader};
use crate::light::Light;
use crate::rotation::Rotation;
use crate::sh::{MAX_COEFFS, MAX_ORDER, eval_basis_lanes, normalise};

/// `y_00 = 1 / (2√π)`: the only basis value of uniform radiance (inside a sphere light).
const Y00: f32 = 0.282_094_8;

impl ModelInfo {
    /// What `shade_lights` checks of its inputs: pose weights of this model, its bones'
    /// rotations, every light valid, one finite non-negative weight per light, `count`
    /// finite positions (one per vertex shaded).
    pub(super) fn check_light_inputs<const P: usize>(
        &self,
        pose: &PoseWeights<P>,
        bones: &[Rotation],
        (lights, weights): (&[Light], &[f32]),
        (positions, count): (&[[f32; 3]], usize),
    ) -> Result<(), Error> {
        self.check_lighting_inputs(pose, bones)?;
        for (index, light) in lights.iter().enumerate() {
            light
                .validate()
                .map_err(|reason| Error::BadLight { index, reason })?;
        }
        if weights.len() != lights.len() {
            return Err(Error::WrongLength {
                what: Input::LightWeights,
                expected: lights.len(),
                found: weights.len(),
            });
        }
        if let Some(index) = weights.iter().position(|w| !(w.is_finite() && *w >= 0.0)) {
            return Err(Error::BadLightWeight { index });
        }
        check_positions(positions, count)?;
        self.check_rotations(bones)
    }

    #[allow(clippy::too_many_arguments)]
    pub(crate) fn shade_lights<R: Reader, const P: usize>(
        &self,
        r: &mut R,
        pose: &PoseWeights<P>,
        bones: &[Rotation],
        lights: &[Light],
        weights: &[f32],
        positions: &[[f32; 3]],
        first: usize,
        out: &mut [[f32; 3]],
    ) -> Result<(), Error> {
        let lit = (lights, weights);
        self.check_light_inputs(pose, bones, lit, (positions, out.len()))?;
        self.check_range(first, out.len())?;

        let (order, n2) = (self.order, self.coeffs());
        let world = self.frame == Frame::World;
        let end = first + out.len();
        let mut lanes = [0.0f32; VERTEX_BLOCK * MAX_COEFFS];
        self.each_block(r, first, out.len(), |v0, lane_bones, bytes| {
            // The transfer once per vertex, eight at a time, as `transfer` gives it.
            let t = &mut lanes[..VERTEX_BLOCK * n2];
            self.block_transfer(pose, bytes, t);
            let live = v0.max(first) - v0..(v0 + VERTEX_BLOCK).min(end) - v0;
            let block = Block {
                order,
                t,
                rotations: core::array::from_fn(|l| match world {
                    true => None,
                    false => bones.get(lane_bones[l]),
                }),
                positions: core::array::from_fn(|l| {
                    live.contains(&l).then(|| positions[v0 + l - first])
                }),
            };
            let add = block.shade(lights, weights);
            for l in live {
                for (o, a) in out[v0 + l - first].iter_mut().zip(add[l]) {
                    *o += a as f32;
                }
            }
        })?;
        finite_output(out.as_flattened_mut())
    }
}

/// One block's vertices under per-vertex lights: their transfer (vertex-major, n² each), bone
/// rotations (`None`: world frame) and positions (`None`: not asked for).
struct Block<'a> {
    order: usize,
    t: &'a [f32],
    rotations: [Option<&'a Rotation>; VERTEX_BLOCK],
    positions: [Option<[f32; 3]>; VERTEX_BLOCK],
}

impl Block<'_> {
    /// Each vertex's shading under every light of non-zero weight, in f64 so that colours,
    /// weights and radiances near f32's limits multiply without overflow (a result beyond f32
    /// is refused as `Overflow` by the caller). A light whose bands fail at a vertex (its
    /// offset to the light overflows f32) adds nothing there.
    fn shade(&self, lights: &[Light], weights: &[f32]) -> [[f64; 3]; VERTEX_BLOCK] {
        let mut acc = [[0.0f64; 3]; VERTEX_BLOCK];
        for (light, &weight) in lights.iter().zip(weights) {
            if weight == 0.0 {
                continue;
            }
            let seen = self.light(light);
            for (a, s) in acc.iter_mut().zip(seen) {
                let Some(s) = s else { continue };
                let scale = s * f64::from(weight);
                for (a, c) in a.iter_mut().zip(light.colour()) {
                    *a += scale * f64::from(c);
                }
            }
        }
        acc
    }

    /// `Σ_l b_l Σ_m t_lm y_lm(R_bᵀ ω)` per vertex for one light (`None` where it fails): the
    /// bands and directions vertex by vertex, then the eight bases at once.
    fn light(&self, light: &Light) -> [Option<f64>; VERTEX_BLOCK] {
        let n2 = self.t.len() / VERTEX_BLOCK;
        let mut seen = [None; VERTEX_BLOCK];
        let mut bands = [[0.0f32; MAX_ORDER]; VERTEX_BLOCK];
        // Lanes without a direction keep +z and are not read.
        let mut dirs = [
            [0.0f32; VERTEX_BLOCK],
            [0.0; VERTEX_BLOCK],
            [1.0; VERTEX_BLOCK],
        ];
        let mut basis = [false; VERTEX_BLOCK];
        for l in 0..VERTEX_BLOCK {
            let Some(p) = self.positions[l] else { continue };
            let Ok((b, dir)) = light.zonal_at(p) else {
                continue;
            };
            let t = &self.t[l * n2..][..n2];
            let Some(omega) = dir else {
                // Inside a sphere light: uniform radiance, band 0 alone.
                seen[l] = Some(f64::from(b[0]) * f64::from(Y00) * f64::from(t[0]));
                continue;
            };
            // ω_b = R_bᵀ ω: the direction in the vertex's bone frame.
            let omega = match self.rotations[l] {
                Some(r) => core::array::from_fn(|i| {
                    r[0][i] * omega[0] + r[1][i] * omega[1] + r[2][i] * omega[2]
                }),
                None => omega,
            };
            let Ok(unit) = normalise(omega) else { continue };
            (bands[l], basis[l]) = (b, true);
            for (axis, x) in dirs.iter_mut().zip(unit) {
                axis[l] = x;
            }
        }
        let mut y = [[0.0f32; VERTEX_BLOCK]; MAX_COEFFS];
        eval_basis_lanes(self.order, dirs, &mut y);
        let sums = band_sums(self.order, self.t, &y, &bands);
        for l in (0..VERTEX_BLOCK).filter(|&l| basis[l]) {
            seen[l] = Some(sums[l]);
        }
        seen
    }
}

/// `Σ_l bands[lane][l] Σ_m t_lm y_lm` for the eight vertices of a block (`t` vertex-major,
/// `y[c][lane]`): each band's dot product in f32, eight lanes at a time, or in f64 for a lane
/// whose transfer near f32's limit overflows it.
fn band_sums(
    order: usize,
    t: &[f32],
    y: &[[f32; VERTEX_BLOCK]; MAX_COEFFS],
    bands: &[[f32; MAX_ORDER]; VERTEX_BLOCK],
) -> [f64; VERTEX_BLOCK] {
    let n2 = t.len() / VERTEX_BLOCK;
    let mut s = [0.0f64; VERTEX_BLOCK];
    for (l, band) in (0..order).map(|l| (l, l * l..(l + 1) * (l + 1))) {
        // Summed from −0.0 like `Iterator::sum`, as the f64 fallback below is.
        let mut p = [-0.0f32; VERTEX_BLOCK];
        for c in band.clone() {
            for (lane, p) in p.iter_mut().enumerate() {
                *p += t[lane * n2 + c] * y[c][lane];
            }
        }
        for (lane, (s, p)) in s.iter_mut().zip(p).enumerate() {
            let p = match p.is_finite() {
                true => f64::from(p),
                false => band
                    .clone()
                    .map(|c| f64::from(t[lane * n2 + c]) * f64::from(y[c][lane]))
                    .sum(),
            };
            *s += f64::from(bands[lane][l]) * p;
        }
    }
    s
}
