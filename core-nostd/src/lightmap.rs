//! SH light maps (Xu, Pattanaik and Hughes, *Real-time Rendering of Dynamic Objects in
//! Dynamic, Low-frequency Lighting Environments*): precomputed radiance transfer unfolded onto
//! a character's UV atlas, each texel storing n² SH transfer coefficients `T_c(t)`, which any
//! lighting composes into an RGB light map, `SHLM(t) = Σ_c L_c T_c(t)`.
//!
//! Decoding a compressed map sequence needs an allocator (its entropy stage is zstd), so it
//! happens outside the core; the composition here takes the decoded coefficients a chunk of
//! texels at a time, in any chunk size, and writes the chunk's RGB into the caller's buffer.
//! It holds nothing between calls and allocates nothing.

use crate::blob::{Dim, Error, Input};
use crate::eval::kernels::{self, texel};
use crate::eval::{check_positions, finite_output};
use crate::irradiance_rig::{IrradianceRig, Placement};
use crate::light::{Light, Rgb};
use crate::sh::{MAX_COEFFS, MAX_ORDER, coeff_count};

/// The composition of SH light maps of one order: the order is checked once, by
/// [`LightMap::new`], and every call takes a chunk of texels.
///
/// Maps are texel-major, `maps[t · n² + c]`, the layout [`Model::transfer`](crate::Model::transfer)
/// gives per vertex; lighting is n² RGB SH radiance coefficients in the crate's convention (see
/// [`eval_basis`](crate::eval_basis)), as [`Light::add_radiance_sh`] and
/// [`IrradianceRig::vectors_from_lights`] produce. The scale is [`Model::shade`](crate::Model::shade)'s:
/// a texel's value is `Σ_c L_c T_c(t)`, so a texel whose transfer equals a vertex's composes to
/// that vertex's shading (under uniform unit radiance, an unoccluded texel gets π); multiply by
/// albedo / π for exit radiance. Every call checks all of its inputs before it writes anything.
///
/// ```
/// use aprt_core::{LightMap, clamped_cosine};
///
/// // Two texels of an order-3 map: one unoccluded facing +z, one half as bright.
/// let map = LightMap::new(3)?;
/// let mut up = [0.0f32; 9];
/// clamped_cosine(3, [0.0, 0.0, 1.0], &mut up)?;
/// let maps: Vec<f32> = up.iter().chain(&up.map(|t| 0.5 * t)).copied().collect();
///
/// // Uniform radiance 1 (L_00 = 2√π) in red only.
/// let mut lighting = [[0.0f32; 3]; 9];
/// lighting[0] = [2.0 * core::f32::consts::PI.sqrt(), 0.0, 0.0];
/// let mut rgb = [[0.0f32; 3]; 2];
/// map.compose(&maps, &lighting, &mut rgb)?;
/// assert!((rgb[0][0] - core::f32::consts::PI).abs() < 1e-5); // the irradiance, π
/// assert!((rgb[1][0] - core::f32::consts::FRAC_PI_2).abs() < 1e-5);
/// assert_eq!(rgb[0][1], 0.0);
/// # Ok::<(), Box<dyn core::error::Error>>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LightMap {
    order: usize,
}

impl LightMap {
    /// Light maps of SH order `order` (1..=6, n² = order² coefficients per texel);
    /// [`Error::BadDimension`] otherwise.
    pub fn new(order: usize) -> Result<LightMap, Error> {
        if order == 0 || order > MAX_ORDER {
            return Err(Error::BadDimension {
                what: Dim::Order,
                value: order as u64,
            });
        }
        Ok(LightMap { order })
    }

    /// The SH order n.
    pub fn order(&self) -> usize {
        self.order
    }

    /// Coefficients n² per texel.
    pub fn coeffs(&self) -> usize {
        coeff_count(self.order)
    }

    /// Writes `out[t] = Σ_c lighting[c] · maps[t · n² + c]` for every texel of the chunk:
    /// `maps` holds `out.len()` texels of n² values, `lighting` n² RGB coefficients. The one
    /// lighting for all texels: a character small against its lights, or a world-frame map.
    ///
    /// Eight texels at a time in SIMD registers (sixteen with AVX-512), each texel with the
    /// bits of the one-at-a-time sum `Σ_c` in ascending c on every target, which the tests
    /// check. About 2.9× (order 3) and 3.0× (order 6) the speed of the scalar sum on x86-64
    /// with AVX-512, within 10–20 % of a memory copy of the map; 1.4–1.5× with SSE2 alone (`cargo bench -p aprt-tests --bench lightmap`, docs/results/performance.md).
    pub fn compose(
        &self,
        maps: &[f32],
        lighting: &[[f32; 3]],
        out: &mut [[f32; 3]],
    ) -> Result<(), Error> {
        self.check_maps(maps, out.len())?;
        let lighting = self.check_lighting(lighting)?;
        kernels::compose(maps, lighting, out);
        finite_output(out.as_flattened_mut())
    }

    /// Each texel lit by `lights` seen from its own world position (`positions`, one per texel
    /// of the chunk) plus a uniform `environment` (n² RGB coefficients, or empty): the exact
    /// per-texel path, for lights near the character. A texel's lighting is the environment
    /// plus [`Light::add_radiance_sh`] of every light at its position, so a light costs one SH
    /// basis evaluation per texel; a texel whose offset to a light overflows f32 gets nothing
    /// from that light (a texel on a point light is inside its sphere, [`Light`]). Every light is validated first ([`Error::BadLight`]).
    ///
    /// The dot product stays one texel at a time: each texel's own lighting costs about ten
    /// times the product (one directional light: 21.6 ms for a 512 × 512 map at order 3
    /// against 2.4 ms for the scalar `compose`, 65 ms against 9.0 ms at order 6, in the
    /// bench above), so the SIMD kernel would save about a tenth.
    pub fn compose_lights(
        &self,
        maps: &[f32],
        positions: &[[f32; 3]],
        lights: &[Light],
        environment: &[[f32; 3]],
        out: &mut [[f32; 3]],
    ) -> Result<(), Error> {
        self.check_maps(maps, out.len())?;
        check_positions(positions, out.len())?;
        if !environment.is_empty() {
            self.check_lighting(environment)?;
        }
        for (index, light) in lights.iter().enumerate() {
            light
                .validate()
                .map_err(|reason| Error::BadLight { index, reason })?;
        }
        let n2 = self.coeffs();
        let mut l = [[0.0f32; 3]; MAX_COEFFS];
        let texels = maps.chunks_exact(n2).zip(positions).zip(out.iter_mut());
        for ((t, &p), o) in texels {
            let l = &mut l[..n2];
            match environment.is_empty() {
                true => l.fill([0.0; 3]),
                false => l.copy_from_slice(environment),
            }
            for light in lights {
                // Nothing is added on an error: the texel's offset to the light overflows f32.
                let _ = light.add_radiance_sh(self.order, p, l);
            }
            *o = texel(t, l);
        }
        finite_output(out.as_flattened_mut())
    }

    /// Each texel lit by an irradiance rig's lighting at its own world position
    /// ([`IrradianceRig::lighting_at`]): `vectors` are the rig's K SH vectors for this frame
    /// (`K · n²` RGB values, vector-major, from [`IrradianceRig::vectors_from_lights`]),
    /// `placement` the character's root in the world, `positions` the texels' world positions
    /// (for a texel of the bind-pose atlas, its surface point placed with the character). A
    /// texel costs at most [`RIG_SUPPORT`](crate::RIG_SUPPORT) vector reads and one n² dot
    /// product, whatever the number of lights. The product stays one texel at a time, as in
    /// [`LightMap::compose_lights`]: each vector read is itself n² RGB multiply–adds, after the
    /// rig's weights at the texel, so the product is at most half of a texel's cost (not
    /// measured separately).
    pub fn compose_rig(
        &self,
        maps: &[f32],
        rig: &IrradianceRig<'_>,
        vectors: &[[f32; 3]],
        placement: &Placement,
        positions: &[[f32; 3]],
        out: &mut [[f32; 3]],
    ) -> Result<(), Error> {
        self.check_maps(maps, out.len())?;
        check_positions(positions, out.len())?;
        let n2 = self.coeffs();
        let expected = rig.vectors() * n2;
        if vectors.len() != expected {
            return Err(Error::WrongLength {
                what: Input::RigVectors,
                expected,
                found: vectors.len(),
            });
        }
        if let Some(index) = vectors.iter().position(|c| !finite(c)) {
            return Err(Error::NonFiniteLighting { index });
        }
        // A placement far from the origin (or not finite) can push a finite position out of
        // f32 in the rig's frame, where its basis weights would be NaN.
        if let Some(index) = positions
            .iter()
            .position(|&p| !finite(&placement.to_root(p)))
        {
            return Err(Error::NonFinitePosition { index });
        }
        let mut l = [[0.0f32; 3]; MAX_COEFFS];
        let texels = maps.chunks_exact(n2).zip(positions).zip(out.iter_mut());
        for ((t, &p), o) in texels {
            rig.lighting_at(vectors, placement, p, &mut l[..n2]);
            *o = texel(t, &l[..n2]);
        }
        finite_output(out.as_flattened_mut())
    }

    /// The maps hold n² finite values for each of `texels` texels.
    fn check_maps(&self, maps: &[f32], texels: usize) -> Result<(), Error> {
        let n2 = self.coeffs();
        let expected = texels.checked_mul(n2).ok_or(Error::LengthOverflow)?;
        if maps.len() != expected {
            return Err(Error::WrongLength {
                what: Input::LightMap,
                expected,
                found: maps.len(),
            });
        }
        match first_non_finite(maps) {
            Some(index) => Err(Error::NonFiniteLightMap { texel: index / n2 }),
            None => Ok(()),
        }
    }

    /// n² finite RGB coefficients.
    fn check_lighting<'l>(&self, lighting: &'l [[f32; 3]]) -> Result<&'l [Rgb], Error> {
        let n2 = self.coeffs();
        if lighting.len() != n2 {
            return Err(Error::WrongLength {
                what: Input::Lighting,
                expected: n2,
                found: lighting.len(),
            });
        }
        match lighting.iter().position(|c| !finite(c)) {
            Some(index) => Err(Error::NonFiniteLighting { index }),
            None => Ok(lighting),
        }
    }
}

fn finite(v: &[f32; 3]) -> bool {
    v.iter().all(|x| x.is_finite())
}

/// The index of the first NaN or infinity in `xs`. A chunk at a time, each scanned without
/// a branch: a value is not finite when its exponent bits are all set, so adding 2²³ to
/// them carries into bit 31; OR-ing the sums over the chunk is integer work that vectorises
/// on every target, where `position(|x| !x.is_finite())` stops to test each value. With it
/// `LightMap::compose` of a 512 × 512 map took 865 µs at order 3 and 3245 µs at order 6, with
/// `position` 1314 and 4998 µs (`cargo bench -p aprt-tests --bench lightmap`, one run each).
fn first_non_finite(xs: &[f32]) -> Option<usize> {
    const CHUNK: usize = 64;
    const EXPONENT: u32 = 0x7f80_0000;
    let bad = |x: &f32| x.to_bits() & EXPONENT == EXPONENT;
    let mut start = 0;
    for chunk in xs.chunks(CHUNK) {
        let any = chunk
            .iter()
            .fold(0, |acc, x| acc | ((x.to_bits() & EXPONENT) + 0x0080_0000));
        if any & 0x8000_0000 != 0 {
            return chunk.iter().position(bad).map(|i| start + i);
        }
        start += chunk.len();
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The branch-free scan finds what `position(|x| !x.is_finite())` finds: the first NaN or
    /// infinity of either sign at every index of every length up to three chunks, among the
    /// finite values nearest to them (±`f32::MAX`, subnormals, −0), and nothing without one.
    #[test]
    fn the_scan_finds_the_first_non_finite_value() {
        let finite = [
            f32::MAX,
            -f32::MAX,
            f32::from_bits(1),
            -0.0,
            1.5,
            f32::MIN_POSITIVE,
        ];
        let mut xs = [0.0f32; 200];
        for len in 0..=xs.len() {
            let xs = &mut xs[..len];
            for (i, x) in xs.iter_mut().enumerate() {
                *x = finite[i % finite.len()];
            }
            assert_eq!(first_non_finite(xs), None, "length {len}");
            for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, -f32::NAN] {
                for at in (0..len).step_by(7).chain(len.checked_sub(1)) {
                    let keep = xs[at];
                    xs[at] = bad;
                    if at + 3 < len {
                        xs[at + 3] = f32::NAN;
                    }
                    assert_eq!(first_non_finite(xs), Some(at), "{bad} at {at} of {len}");
                    xs[at] = keep;
                    if at + 3 < len {
                        xs[at + 3] = finite[(at + 3) % finite.len()];
                    }
                }
            }
        }
    }
}
