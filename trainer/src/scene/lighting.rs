//! A scene's lighting as SH: the environment (given as coefficients or projected from a map)
//! plus the lights, projected at a point, and the exact unshadowed irradiance it is judged by.

use anyhow::{Context, Result};
use aprt_core::{Light, LightError, MAX_COEFFS, MAX_ORDER, Rgb, irradiance_sh};

use crate::io::scene::{Environment, Scene};
use crate::lighting::rig_fit::{GREY_PER_IRRADIANCE, bounds};
use crate::rig::mesh::Mesh;

/// A scene's lighting, ready to project.
#[derive(Clone, Debug, Default)]
pub struct SceneLighting {
    /// The environment's SH radiance, up to order 6 (empty when the scene has none).
    pub environment: Vec<Rgb>,
    /// The lights.
    pub lights: Vec<Light>,
}

impl SceneLighting {
    /// The scene's lighting: its SH environment as given, or its map projected at order 6.
    pub fn of(scene: &Scene) -> Result<SceneLighting> {
        let environment = match &scene.environment {
            None => Vec::new(),
            Some(Environment::Sh(sh)) => sh.clone(),
            Some(Environment::Map(path)) => crate::lighting::read_environment(path, MAX_ORDER)
                .with_context(|| format!("{}: [environment]", scene.path.display()))?,
        };
        Ok(SceneLighting {
            environment,
            lights: scene.lights.clone(),
        })
    }

    /// SH radiance of `order` at `at`: the environment truncated to the order plus every
    /// light projected there. An error names the light the core refused.
    pub fn sh_at(&self, order: usize, at: [f32; 3]) -> Result<Vec<Rgb>> {
        let n2 = order * order;
        let mut out = vec![[0.0f32; 3]; n2];
        for (o, e) in out.iter_mut().zip(&self.environment) {
            *o = *e;
        }
        for (i, light) in self.lights.iter().enumerate() {
            light
                .add_radiance_sh(order, at, &mut out)
                .map_err(|e| anyhow::anyhow!("light {}: {e}", i + 1))?;
        }
        Ok(out)
    }

    /// SH radiance of `order` at the centre of `mesh`'s bounding box (where an engine without
    /// a rig projects the lights).
    pub fn sh_at_centre(&self, order: usize, mesh: &Mesh) -> Result<Vec<Rgb>> {
        let (centre, _, _) = bounds(&[mesh]);
        self.sh_at(order, centre.map(|x| x as f32))
    }

    /// Irradiance at `at` on `normal` through SH of `order`, and exactly (the environment at
    /// all its bands, the lights in closed form, clipped by the horizon), light by light:
    /// `(sh, exact)` of the environment first, then of each light. `Ok(None)` where the core
    /// cannot evaluate a part (a point light at the point itself, a zero normal); a result
    /// beyond f32 is an error naming the part, never a point quietly left out.
    pub fn irradiance_parts(
        &self,
        order: usize,
        at: [f32; 3],
        normal: [f32; 3],
    ) -> Result<Option<Vec<(Rgb, Rgb)>>, String> {
        let mut parts = Vec::with_capacity(1 + self.lights.len());
        let env_order = (1..=MAX_ORDER).find(|o| o * o >= self.environment.len());
        match env_order {
            Some(full) if !self.environment.is_empty() => {
                let n = order.min(full);
                let env = irradiance_sh(n, &self.environment[..n * n], normal)
                    .and_then(|sh| Ok((sh, irradiance_sh(full, &self.environment, normal)?)));
                match env {
                    Ok(part) => parts.push(part),
                    Err(e) => return left_out("the environment", e),
                }
            }
            _ => parts.push(([0.0; 3], [0.0; 3])),
        }
        let mut sh = [[0.0f32; 3]; MAX_COEFFS];
        for (i, light) in self.lights.iter().enumerate() {
            let sh = &mut sh[..order * order];
            sh.fill([0.0; 3]);
            let part = light.add_radiance_sh(order, at, sh).and_then(|()| {
                Ok((
                    irradiance_sh(order, sh, normal)?,
                    light.irradiance(at, normal)?,
                ))
            });
            match part {
                Ok(part) => parts.push(part),
                Err(e) => return left_out(&format!("light {}", i + 1), e),
            }
        }
        Ok(Some(parts))
    }
}

/// A part the core refused at a point: left out (`Ok(None)`) when irradiance has no value
/// there, an error when a result is beyond f32 (the core says `Overflow` for a sum and
/// `NotFinite` for an irradiance).
fn left_out<T>(part: &str, error: LightError) -> Result<Option<T>, String> {
    match error {
        LightError::Overflow | LightError::NotFinite => Err(format!("{part}: {error}")),
        _ => Ok(None),
    }
}

/// The largest channel of `|a − b|`, in grey levels.
pub fn grey_error(a: Rgb, b: Rgb) -> f32 {
    (0..3).map(|k| (a[k] - b[k]).abs()).fold(0.0, f32::max) * GREY_PER_IRRADIANCE as f32
}

/// Luminance (Rec. 709) of each RGB coefficient: the one channel the model's shading takes.
pub fn luminance(rgb: &[Rgb]) -> Vec<f32> {
    rgb.iter()
        .map(|&c| crate::report::rig_frame::luminance(c))
        .collect()
}
