//! A fitted irradiance rig under a set of lights, on one posed mesh: which lights it carries
//! and which go per vertex (the error-driven choice of *Irradiance Rigs*, section 3.1), its
//! error against the exact, horizon-clipped irradiance at every vertex. What the core spends
//! on it per frame is the runtime's to measure (`model::runtime::rig_frame_cost`).

use aprt_core::{
    DEFAULT_BAND, IrradianceRig, Light, MAX_COEFFS, Placement, PointLight, Rgb, irradiance_sh,
    light_strength,
};
use rayon::prelude::*;
use serde::Serialize;

use super::fit::{FittedRig, GreyError, directions, rig_vectors};
use crate::lighting::GREY_PER_IRRADIANCE;
use crate::lighting::kind_name;
use crate::rig::mesh::Mesh;

/// Distances of the error table, in radii of the character from its centre: from just outside
/// the bounding sphere to where every rig is within a fraction of a grey level for a light of
/// unit strength.
const TABLE_DISTANCES: usize = 24;
const TABLE_NEAREST: f64 = 1.05;
const TABLE_FARTHEST: f64 = 64.0;
/// Vertices the table's error is measured at, at most (every k-th vertex).
const TABLE_VERTICES: usize = 4096;
/// What to evaluate a rig for.
#[derive(Clone, Copy, Debug)]
pub struct RigSettings {
    /// SH order of the lighting.
    pub order: usize,
    /// The error a light may cost the rig, in 8-bit grey levels.
    pub target_error: f32,
    /// Width of the blend past a light's transition distance, as a share of it.
    pub band: f32,
}

impl Default for RigSettings {
    /// Order 3 (irradiance needs no more), one grey level, a quarter-distance band.
    fn default() -> Self {
        RigSettings {
            order: 3,
            target_error: 1.0,
            band: DEFAULT_BAND,
        }
    }
}

/// One light's path.
#[derive(Clone, Debug, Serialize)]
pub struct LightPath {
    /// Its position in the lights file, from 1.
    pub index: usize,
    /// `sphere`, `point` or `directional`.
    pub kind: &'static str,
    /// `"rig"` when the rig carries at least half of it, else `"analytic"` (per vertex).
    pub mode: &'static str,
    /// The share the rig carries, 0 to 1 (between, the light is in the blend band).
    pub rig_share: f32,
    /// Distance from the rig's centre (`null` for a directional light).
    pub distance: Option<f32>,
    /// Distance from the rig's centre beyond which the rig meets the target for this light;
    /// 0 when it does everywhere (a directional light, or a faint one).
    pub transition_distance: f32,
}

/// A rig under a set of lights on one mesh.
#[derive(Clone, Debug, Serialize)]
pub struct RigEvaluation {
    /// The rig kind, as `--rig` spells it.
    pub rig: String,
    /// SH vectors the rig hands a shader per frame.
    pub sh_vectors: usize,
    /// Surface samples the lights are projected at per frame.
    pub samples: usize,
    /// SH order.
    pub order: usize,
    /// Vertices shaded.
    pub vertices: usize,
    /// The target of the rig-or-analytic choice, grey levels.
    pub target_error: f32,
    /// The character's radius about the rig's centre.
    pub radius: f64,
    /// Each light's path.
    pub lights: Vec<LightPath>,
    /// Rig plus per-vertex lights, as chosen, against the exact irradiance with horizon
    /// clipping, unshadowed, at every vertex.
    pub error_grey: GreyError,
    /// Every light in the rig, against the exact irradiance.
    pub error_grey_all_rig: GreyError,
    /// Every light per vertex through SH, against the exact irradiance: the truncation floor
    /// no choice of rig can go below.
    pub error_grey_per_vertex: GreyError,
}

impl RigEvaluation {
    /// Each light's share carried by the rig, in order (what its cost is measured with).
    pub fn shares(&self) -> Vec<f32> {
        self.lights.iter().map(|l| l.rig_share).collect()
    }
}

/// Each light's share carried by the rig, in order.
pub fn shares(rig: &IrradianceRig<'_>, lights: &[Light], settings: &RigSettings) -> Vec<f32> {
    lights
        .iter()
        .map(|l| {
            rig.share_of(
                l,
                &Placement::IDENTITY,
                settings.target_error,
                settings.band,
            )
        })
        .collect()
}

/// Errors in grey levels, accumulated per vertex and channel.
#[derive(Default)]
struct Tally {
    sum: f64,
    max: f64,
    count: usize,
}

impl Tally {
    fn add(&mut self, a: Rgb, b: Rgb) {
        for k in 0..3 {
            let e = GREY_PER_IRRADIANCE * f64::from((a[k] - b[k]).abs());
            self.sum += e;
            self.max = self.max.max(e);
            self.count += 1;
        }
    }

    fn result(&self) -> GreyError {
        GreyError {
            mean: self.sum / self.count.max(1) as f64,
            max: self.max,
        }
    }
}

/// The per-vertex SH irradiance of `lights` weighted by `weights` (n² lighting at `p`).
fn per_vertex(lights: &[Light], weights: &[f32], order: usize, p: [f32; 3], n: [f32; 3]) -> Rgb {
    let mut l = [[0.0f32; 3]; MAX_COEFFS];
    for (light, &w) in lights.iter().zip(weights) {
        if w > 0.0 {
            // A vertex whose offset to a light overflows f32 sees nothing from it: skipped.
            let _ = light
                .scaled(w)
                .add_radiance_sh(order, p, &mut l[..order * order]);
        }
    }
    irradiance_sh(order, &l[..order * order], n).unwrap_or([0.0; 3])
}

/// A rig's errors against the exact, horizon-clipped, unshadowed irradiance, in grey levels.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct RigErrors {
    /// Rig plus per-vertex lights, as the shares chose.
    pub chosen: GreyError,
    /// Every light in the rig.
    pub all_rig: GreyError,
    /// Every light per vertex through SH: the truncation floor.
    pub per_vertex: GreyError,
    /// Every light in the rig against every light per vertex through SH: what the rig adds
    /// to the truncation (what [`FittedRig::tabulate`] measures).
    pub rig_vs_per_vertex: GreyError,
}

/// The errors of `rig` under `lights` at the vertices `which` of `mesh` (root frame), each
/// light's share of the rig given by `share` (see [`shares`]); an error names the light the
/// core refused.
pub fn rig_errors(
    rig: &IrradianceRig<'_>,
    mesh: &Mesh,
    which: impl Iterator<Item = usize>,
    lights: &[Light],
    share: &[f32],
    order: usize,
) -> Result<RigErrors, aprt_core::Error> {
    let rest: Vec<f32> = share.iter().map(|s| 1.0 - s).collect();
    let in_rig: Vec<Light> = lights
        .iter()
        .zip(share)
        .map(|(l, &s)| l.scaled(s))
        .collect();
    let all = rig_vectors(rig, lights, order, &Placement::IDENTITY)?;
    let split = rig_vectors(rig, &in_rig, order, &Placement::IDENTITY)?;
    let (mut chosen, mut all_rig, mut floor, mut added) = (
        Tally::default(),
        Tally::default(),
        Tally::default(),
        Tally::default(),
    );
    let mut here = [[0.0f32; 3]; MAX_COEFFS];
    let ones = vec![1.0f32; lights.len()];
    for j in which {
        let (p, n) = (&mesh.positions[j], &mesh.normals[j]);
        let exact = lights
            .iter()
            .fold([0.0f32; 3], |acc, l| match l.irradiance(*p, *n) {
                Ok(e) => std::array::from_fn(|k| acc[k] + e[k]),
                Err(_) => acc,
            });
        let here = &mut here[..order * order];
        rig.lighting_at(&all, &Placement::IDENTITY, *p, here);
        let every = irradiance_sh(order, here, *n).unwrap_or([0.0; 3]);
        all_rig.add(every, exact);
        rig.lighting_at(&split, &Placement::IDENTITY, *p, here);
        let from_rig = irradiance_sh(order, here, *n).unwrap_or([0.0; 3]);
        let near = per_vertex(lights, &rest, order, *p, *n);
        chosen.add(std::array::from_fn(|k| from_rig[k] + near[k]), exact);
        let sh = per_vertex(lights, &ones, order, *p, *n);
        floor.add(sh, exact);
        added.add(every, sh);
    }
    Ok(RigErrors {
        chosen: chosen.result(),
        all_rig: all_rig.result(),
        per_vertex: floor.result(),
        rig_vs_per_vertex: added.result(),
    })
}

impl FittedRig {
    /// The error table of section 3.1: for unit-strength point lights at
    /// `TABLE_DISTANCES` (24) distances (in radii) around the character, in 26 directions, the
    /// worst grey-level difference over the vertices of `mesh` (root frame) between the rig's
    /// irradiance and the per-vertex SH irradiance at `order`. An error is the core's refusal
    /// of the rig or of a light, never an empty or partial table.
    pub fn tabulate(&mut self, mesh: &Mesh, order: usize) -> Result<(), aprt_core::Error> {
        self.table.clear();
        let bytes = self.bytes();
        let rig = IrradianceRig::parse(&bytes)?;
        let step = mesh.positions.len().div_ceil(TABLE_VERTICES).max(1);
        let vertices: Vec<usize> = (0..mesh.positions.len()).step_by(step).collect();
        let ratio = (TABLE_FARTHEST / TABLE_NEAREST).powf(1.0 / (TABLE_DISTANCES - 1) as f64);
        let table = (0..TABLE_DISTANCES)
            .into_par_iter()
            .map(|i| {
                let d = TABLE_NEAREST * ratio.powi(i as i32);
                let mut worst = 0.0f64;
                for dir in directions() {
                    let at = std::array::from_fn(|k| self.centre[k] + d * self.radius * dir[k]);
                    let light = Light::Point(PointLight {
                        position: at.map(|x| x as f32),
                        intensity: [1.0; 3],
                    });
                    let errors = rig_errors(
                        &rig,
                        mesh,
                        vertices.iter().copied(),
                        &[light],
                        &[1.0],
                        order,
                    )?;
                    worst = worst.max(errors.rig_vs_per_vertex.max);
                }
                Ok([d, worst])
            })
            .collect::<Result<Vec<[f64; 2]>, aprt_core::Error>>()?;
        self.table = table;
        Ok(())
    }
}

/// Evaluates a fitted rig under `lights` on `mesh` (in the rig's root frame); an error names
/// the light the core refused.
pub fn evaluate_rig(
    fitted: &FittedRig,
    mesh: &Mesh,
    lights: &[Light],
    settings: &RigSettings,
) -> Result<RigEvaluation, aprt_core::Error> {
    let bytes = fitted.bytes();
    let rig = IrradianceRig::parse(&bytes)?;
    let order = settings.order;
    let share = shares(&rig, lights, settings);
    let errors = rig_errors(&rig, mesh, 0..mesh.vertex_count(), lights, &share, order)?;
    let paths = lights
        .iter()
        .zip(&share)
        .enumerate()
        .map(|(i, (light, &s))| {
            let distance = match light {
                Light::Sphere(l) => Some(l.position),
                Light::Point(l) => Some(l.position),
                Light::Directional(_) => None,
            }
            .map(|p| {
                let c = rig.centre();
                (0..3).map(|k| (p[k] - c[k]).powi(2)).sum::<f32>().sqrt()
            });
            LightPath {
                index: i + 1,
                kind: kind_name(light),
                mode: if s >= 0.5 { "rig" } else { "analytic" },
                rig_share: s,
                distance,
                transition_distance: rig
                    .transition_distance(light_strength(light), settings.target_error),
            }
        })
        .collect();
    Ok(RigEvaluation {
        rig: fitted.kind.to_string(),
        sh_vectors: rig.vectors(),
        samples: rig.samples(),
        order,
        vertices: mesh.vertex_count(),
        target_error: settings.target_error,
        radius: fitted.radius,
        lights: paths,
        error_grey: errors.chosen,
        error_grey_all_rig: errors.all_rig,
        error_grey_per_vertex: errors.per_vertex,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::irradiance_rig::fit_rig;
    use crate::rig::Rig;
    use crate::rig::character::Character;
    use aprt_core::PointLight;

    /// A light moving from the character's flank out to many radii: the error the rig adds on
    /// top of per-vertex evaluation (chosen − per vertex) never jumps by more than the target
    /// between positions a centimetre apart, and never exceeds the target by much anywhere.
    #[test]
    fn the_choice_is_continuous_as_a_light_moves() {
        let human = Character::builtin();
        let mesh = human.bind_mesh();
        let mut fitted = fit_rig("gradient".parse().unwrap(), &[mesh], None);
        let settings = RigSettings::default();
        fitted.tabulate(mesh, settings.order).unwrap();
        let bytes = fitted.bytes();
        let rig = IrradianceRig::parse(&bytes).unwrap();
        let which: Vec<usize> = (0..mesh.vertex_count()).step_by(37).collect();
        let c = rig.centre();
        let added = |x: f32| -> Vec<Rgb> {
            let light = Light::Point(PointLight {
                position: [c[0] + x, c[1] - 0.3 * x, c[2] + 0.2],
                intensity: [3.0, 2.0, 1.0],
            });
            let share = rig.share_of(
                &light,
                &Placement::IDENTITY,
                settings.target_error,
                settings.band,
            );
            let vectors =
                rig_vectors(&rig, &[light.scaled(share)], 3, &Placement::IDENTITY).unwrap();
            let mut here = [[0.0f32; 3]; 9];
            which
                .iter()
                .map(|&j| {
                    let (p, n) = (mesh.positions[j], mesh.normals[j]);
                    rig.lighting_at(&vectors, &Placement::IDENTITY, p, &mut here);
                    let from_rig = irradiance_sh(3, &here, n).unwrap();
                    let near = per_vertex(&[light], &[1.0 - share], 3, p, n);
                    let all = per_vertex(&[light], &[1.0], 3, p, n);
                    std::array::from_fn(|k| from_rig[k] + near[k] - all[k])
                })
                .collect()
        };
        let grey = |a: Rgb| {
            a.iter().fold(0.0f64, |m, &x| {
                m.max(GREY_PER_IRRADIANCE * f64::from(x.abs()))
            })
        };
        let (mut previous, mut worst_jump, mut worst) = (added(0.6), 0.0f64, 0.0f64);
        let mut x = 0.6f32;
        let (mut saw_analytic, mut saw_rig) = (false, false);
        while x < 30.0 {
            x += 0.01;
            let now = added(x);
            for (a, b) in now.iter().zip(&previous) {
                worst_jump = worst_jump.max(grey(std::array::from_fn(|k| a[k] - b[k])));
                worst = worst.max(grey(*a));
            }
            saw_analytic |= now.iter().all(|a| grey(*a) == 0.0);
            saw_rig |= now.iter().any(|a| grey(*a) > 0.0);
            previous = now;
        }
        assert!(
            saw_analytic && saw_rig,
            "the light crossed from analytic to rig"
        );
        let target = f64::from(settings.target_error);
        assert!(worst_jump <= target, "a jump of {worst_jump} grey levels");
        // The table is the worst of 26 directions at 24 distances; a light between them may
        // cost a little more than the target.
        assert!(worst <= 2.0 * target, "the rig added {worst} grey levels");
    }

    #[test]
    fn error_table_falls_with_distance() {
        let human = Character::builtin();
        let mesh = human.bind_mesh();
        let mut fitted = fit_rig("gradient".parse().unwrap(), &[mesh], None);
        fitted.tabulate(mesh, 3).unwrap();
        assert_eq!(fitted.table.len(), TABLE_DISTANCES);
        let (near, far) = (fitted.table[0][1], fitted.table[TABLE_DISTANCES - 1][1]);
        assert!(near > 10.0 * far && far >= 0.0, "{near} → {far}");
        // The core reads the same table and bisects it for a transition distance.
        let bytes = fitted.bytes();
        let rig = IrradianceRig::parse(&bytes).unwrap();
        let t = rig.transition_distance(1.0, 1.0);
        assert!(t > 0.0 && rig.error_at(t / rig.radius()) <= 1.0 + 1e-3);
    }
}
