//! The error-driven choice of *Irradiance Rigs* (section 3.1): which lights the rig carries
//! and which are evaluated per vertex, from the rig's error table, blended over a band of
//! distances so a moving light never jumps from one path to the other.

use super::{IrradianceRig, Placement};
use crate::light::Light;

/// The share of the band past the transition distance over which a light moves from the
/// per-vertex path into the rig: a quarter of the distance.
pub const DEFAULT_BAND: f32 = 0.25;

/// A light's strength in the error table's units, its colour's largest channel times what
/// makes its far-field irradiance `strength / d²`: a sphere light's radiance × π r², a point
/// light's intensity. Directional lights are the same everywhere and any rig carries them
/// exactly: 0.
pub fn light_strength(light: &Light) -> f32 {
    let peak = |c: [f32; 3]| c.iter().fold(0.0f32, |m, &x| m.max(x));
    match light {
        Light::Sphere(s) => peak(s.radiance) * core::f32::consts::PI * s.radius * s.radius,
        Light::Point(p) => peak(p.intensity),
        Light::Directional(_) => 0.0,
    }
}

impl IrradianceRig<'_> {
    /// The rig's worst error, grey levels per unit strength, at `distance` radii from its
    /// centre: the table's upper envelope from there outwards (so the choice it drives is
    /// monotone in distance), linearly interpolated; beyond the table the last entry falls
    /// with the inverse square, inside it the largest entry holds.
    pub fn error_at(&self, distance: f32) -> f32 {
        let m = self.table_len();
        if m == 0 {
            return 0.0;
        }
        let [d_last, e_last] = self.table_entry(m - 1);
        if distance >= d_last {
            return e_last * (d_last / distance) * (d_last / distance);
        }
        // `upper`: the largest entry beyond the segment; the interpolation never drops below it.
        let mut upper = e_last;
        for i in (0..m - 1).rev() {
            let ([d0, e0], [d1, e1]) = (self.table_entry(i), self.table_entry(i + 1));
            upper = upper.max(e1);
            if distance >= d0 {
                let t = (distance - d0) / (d1 - d0);
                return (e0 + (e1 - e0) * t).max(upper);
            }
        }
        upper.max(self.table_entry(0)[1])
    }

    /// The nearest distance from the rig's centre (world units) beyond which a light of
    /// `strength` costs the rig at most `target` grey levels, found by bisection on the
    /// decreasing envelope of [`IrradianceRig::error_at`]; 0 when the rig meets the target
    /// everywhere.
    pub fn transition_distance(&self, strength: f32, target: f32) -> f32 {
        let meets = |d: f32| self.error_at(d) * strength <= target;
        if strength.is_nan() || strength <= 0.0 || meets(0.0) {
            return 0.0;
        }
        // The envelope falls as 1/d² past the table, so some finite distance meets the target.
        let mut hi = 1.0f32;
        while !meets(hi) && hi < 1e30 {
            hi *= 2.0;
        }
        let mut lo = 0.0f32;
        for _ in 0..48 {
            let mid = 0.5 * (lo + hi);
            if meets(mid) {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        hi * self.radius()
    }

    /// The share of a light the rig should carry, 0 (per vertex) to 1 (the rig), for a light
    /// of `strength` at world distance `distance` from the rig's centre: 0 nearer than the
    /// transition distance `t`, 1 beyond `(1 + band) t`, linear between, so the rig's error
    /// stays below `target` grey levels and nothing pops as the light moves.
    pub fn rig_share(&self, strength: f32, distance: f32, target: f32, band: f32) -> f32 {
        let start = self.transition_distance(strength, target);
        if start == 0.0 || !distance.is_finite() {
            return 1.0;
        }
        ((distance - start) / (band.max(1e-6) * start)).clamp(0.0, 1.0)
    }

    /// [`IrradianceRig::rig_share`] of `light` for the character placed at `placement`.
    pub fn share_of(&self, light: &Light, placement: &Placement, target: f32, band: f32) -> f32 {
        let position = match light {
            Light::Sphere(s) => s.position,
            Light::Point(p) => p.position,
            Light::Directional(_) => return 1.0,
        };
        let centre = placement.to_world(self.centre());
        let d = (0..3)
            .map(|i| (position[i] - centre[i]) * (position[i] - centre[i]))
            .sum::<f32>();
        self.rig_share(light_strength(light), crate::math::sqrt(d), target, band)
    }
}
