//! Per-vertex ("analytic") lights through the pose model's transfer. An irradiance rig carries
//! far lights cheaply, but a light near the character varies too fast over it; *Irradiance
//! Rigs* (Yuan, Nowrouzezahrai and Sloan) evaluates such lights per vertex instead, against
//! the vertex's own transfer, so they stay self-shadowed.
//!
//! `shade_j += Σ_i w_i c_i Σ_l b_il Σ_m t_j,lm y_lm(R_bᵀ ω_ij)`: the light's radiance seen from
//! `p_j` is zonal about the direction `ω_ij` towards it (bands `b_il`), so in the vertex's bone
//! frame it is the same bands about the rotated direction. Rotating that one direction costs
//! nine multiplies per vertex and light, where rotating the SH vector would cost O(n³).

use super::PoseWeights;
use super::rig::check_positions;
use crate::blob::format::{Frame, VERTEX_BLOCK};
use crate::blob::{Error, Input, ModelInfo, Reader};
use crate::light::Light;
use crate::rotation::Rotation;
use crate::sh::{MAX_COEFFS, MAX_ORDER, eval_basis};

/// `y_00 = 1 / (2√π)`: the only basis value of uniform radiance (inside a sphere light).
const Y00: f32 = 0.282_094_8;

impl ModelInfo {
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
        check_positions(positions, out.len())?;
        self.check_range(first, out.len())?;
        self.check_rotations(bones)?;

        let (order, n2) = (self.order, self.coeffs());
        let world = self.frame == Frame::World;
        let end = first + out.len();
        let mut lanes = [0.0f32; VERTEX_BLOCK * MAX_COEFFS];
        self.each_block(r, first, out.len(), |v0, lane_bones, bytes| {
            // The transfer once per vertex, eight at a time, as `transfer` gives it.
            let t = &mut lanes[..VERTEX_BLOCK * n2];
            self.block_transfer(pose, bytes, t);
            for j in v0.max(first)..(v0 + VERTEX_BLOCK).min(end) {
                let lane = j - v0;
                let rotation = match world {
                    true => None,
                    false => bones.get(lane_bones[lane]),
                };
                let tj = &t[lane * n2..(lane + 1) * n2];
                let add = shade_vertex(order, tj, rotation, lights, weights, positions[j - first]);
                for (o, a) in out[j - first].iter_mut().zip(add) {
                    *o += a as f32;
                }
            }
        })
    }
}

/// One vertex's shading under every light of non-zero weight, in f64 so that colours, weights
/// and `1/d²` near f32's limits multiply without overflow (the result saturates to ±∞ only
/// when converted back). A light whose bands fail at this vertex (the vertex is on a point
/// light, or its offset to the light overflows f32) adds nothing: its radiance there has no
/// finite SH projection.
fn shade_vertex(
    order: usize,
    t: &[f32],
    rotation: Option<&Rotation>,
    lights: &[Light],
    weights: &[f32],
    p: [f32; 3],
) -> [f64; 3] {
    let mut acc = [0.0f64; 3];
    let mut y = [0.0f32; MAX_COEFFS];
    for (light, &weight) in lights.iter().zip(weights) {
        if weight == 0.0 {
            continue;
        }
        let Ok((bands, dir)) = light.zonal_at(p) else {
            continue;
        };
        let s = match dir {
            // Inside a sphere light: uniform radiance, band 0 alone.
            None => f64::from(bands[0]) * f64::from(Y00) * f64::from(t[0]),
            Some(omega) => {
                // ω_b = R_bᵀ ω: the direction in the vertex's bone frame.
                let omega = match rotation {
                    Some(r) => core::array::from_fn(|i| {
                        r[0][i] * omega[0] + r[1][i] * omega[1] + r[2][i] * omega[2]
                    }),
                    None => omega,
                };
                if eval_basis(order, omega, &mut y).is_err() {
                    continue;
                }
                band_sum(order, t, &y, &bands)
            }
        };
        let scale = s * f64::from(weight);
        for (a, c) in acc.iter_mut().zip(light.colour()) {
            *a += scale * f64::from(c);
        }
    }
    acc
}

/// `Σ_l bands[l] Σ_m t_lm y_lm`: each band's dot product in f32, or in f64 when a transfer
/// near f32's limit overflows it.
fn band_sum(order: usize, t: &[f32], y: &[f32; MAX_COEFFS], bands: &[f32; MAX_ORDER]) -> f64 {
    let mut s = 0.0f64;
    for (l, &b) in bands.iter().enumerate().take(order) {
        let (t, y) = (&t[l * l..(l + 1) * (l + 1)], &y[l * l..(l + 1) * (l + 1)]);
        let p: f32 = t.iter().zip(y).map(|(a, b)| a * b).sum();
        let p = match p.is_finite() {
            true => f64::from(p),
            false => t
                .iter()
                .zip(y)
                .map(|(a, b)| f64::from(*a) * f64::from(*b))
                .sum(),
        };
        s += f64::from(b) * p;
    }
    s
}
