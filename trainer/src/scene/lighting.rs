//! A scene's lighting as SH: the environment (given as coefficients or projected from a map)
//! plus the lights, projected at a point, and the exact unshadowed irradiance it is judged by.

use anyhow::{Context, Result};
use aprt_core::{Light, LightError, MAX_COEFFS, MAX_ORDER, Rgb, ShRotation, irradiance_sh};
use glam::{DQuat, DVec3, Vec3};

use crate::irradiance_rig::fit::bounds;
use crate::lighting::GREY_PER_IRRADIANCE;
use crate::rig::mesh::Mesh;
use crate::scene::file::{Environment, Scene};

/// A scene's lighting, ready to project.
#[derive(Clone, Debug, Default)]
pub struct SceneLighting {
    /// The environment's SH radiance, up to order 6 (empty when the scene has none).
    pub environment: Vec<Rgb>,
    /// The lights.
    pub lights: Vec<Light>,
}

impl SceneLighting {
    /// The scene's lighting in the character's frame: its SH environment as given (already in
    /// that frame), or its map projected at order 6 and turned from the map's +Y up to the
    /// character's up axis, so a sky lights the top of the head whichever axis the mesh
    /// stands on. `rig_up` is the rig's [`Rig::up`](crate::rig::Rig::up); the scene's
    /// `[source] up` overrides it.
    pub fn of(scene: &Scene, rig_up: Vec3) -> Result<SceneLighting> {
        let environment = match &scene.environment {
            None => Vec::new(),
            Some(Environment::Sh(sh)) => sh.clone(),
            Some(Environment::Map(path)) => {
                let mut sh = crate::lighting::read_environment(path, MAX_ORDER)
                    .with_context(|| format!("{}: [environment]", scene.path.display()))?;
                y_up_to(scene.up.unwrap_or(rig_up), &mut sh);
                sh
            }
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

/// Turns order-6 SH radiance `sh` projected with +Y up (an environment map's convention) into
/// a frame whose up axis is `up`: the rotation taking +Y to `up` by the shortest arc, applied
/// to each colour channel.
fn y_up_to(up: Vec3, sh: &mut [Rgb]) {
    let turn = DQuat::from_rotation_arc(DVec3::Y, up.as_dvec3().normalize());
    let rows = glam::DMat3::from_quat(turn).transpose().to_cols_array_2d();
    let rotation = ShRotation::new(MAX_ORDER).expect("MAX_ORDER is a valid order");
    for k in 0..3 {
        let mut channel = [0.0f32; MAX_COEFFS];
        for (c, rgb) in channel.iter_mut().zip(sh.iter()) {
            *c = rgb[k];
        }
        rotation
            .apply(&rows, &mut channel)
            .expect("a channel holds MAX_COEFFS values");
        for (rgb, c) in sh.iter_mut().zip(channel) {
            rgb[k] = c;
        }
    }
}

/// The largest channel of `|a − b|`, in grey levels.
pub fn grey_error(a: Rgb, b: Rgb) -> f32 {
    (0..3).map(|k| (a[k] - b[k]).abs()).fold(0.0, f32::max) * GREY_PER_IRRADIANCE as f32
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use aprt_core::clamped_cosine;
    use glam::Vec3;
    use image::Rgb32FImage;
    use image::codecs::hdr::HdrEncoder;

    use super::SceneLighting;
    use crate::scene::file::parse_scene;

    /// A 16×8 equirect sky: bright above the horizon (the top rows, +Y in the map's frame),
    /// dark below.
    fn write_sky(path: &Path) {
        let (width, height) = (16u32, 8u32);
        let flat = (0..height)
            .flat_map(|row| {
                let v = if row < height / 2 { 2.0 } else { 0.0 };
                std::iter::repeat_n(v, (width * 3) as usize)
            })
            .collect();
        let file = std::fs::File::create(path).unwrap();
        Rgb32FImage::from_raw(width, height, flat)
            .unwrap()
            .write_with_encoder(HdrEncoder::new(std::io::BufWriter::new(file)))
            .unwrap();
    }

    /// The sky's band 1 (red) in the character's frame, for a scene with `source_extra`
    /// under `[source]` and a rig whose up axis is `rig_up`.
    fn band1(dir: &Path, source_extra: &str, rig_up: Vec3) -> [f32; 3] {
        write_sky(&dir.join("sky.hdr"));
        let text = format!(
            "[source]\nbuiltin = \"human\"\ntrain = [\"walk\"]\n{source_extra}\n[environment]\nhdr = \"sky.hdr\"\n"
        );
        let scene = parse_scene(&text, &dir.join("scene.toml")).unwrap();
        let env = SceneLighting::of(&scene, rig_up).unwrap().environment;
        [env[1][0], env[2][0], env[3][0]]
    }

    /// `band` points along `up` (positive) with the other band-1 components ~0.
    fn assert_along(band: [f32; 3], up: Vec3) {
        let mut lobe = [0.0f32; 4];
        clamped_cosine(2, up.to_array(), &mut lobe).unwrap();
        let lobe = Vec3::new(lobe[1], lobe[2], lobe[3]);
        let band = Vec3::from_array(band);
        assert!(
            band.dot(lobe) > 0.5 * band.length() * lobe.length(),
            "{band} vs {lobe}"
        );
        let across = band - lobe * band.dot(lobe) / lobe.length_squared();
        assert!(across.length() < 1e-3 * band.length(), "{band} vs {lobe}");
    }

    #[test]
    fn a_sky_lights_from_the_up_axis_of_a_z_up_and_a_y_up_character() {
        let dir = tempfile::tempdir().unwrap();
        for up in [Vec3::Z, Vec3::Y] {
            assert_along(band1(dir.path(), "", up), up);
        }
    }

    #[test]
    fn the_scene_up_key_overrides_the_rig() {
        let dir = tempfile::tempdir().unwrap();
        assert_along(band1(dir.path(), "up = \"y\"", Vec3::Z), Vec3::Y);
        assert_along(band1(dir.path(), "up = \"z\"", Vec3::Y), Vec3::Z);
    }

    #[test]
    fn a_bad_up_key_is_refused_naming_the_key() {
        let text = "[source]\nbuiltin = \"human\"\ntrain = [\"walk\"]\nup = \"x\"\n[environment]\nsh = [[1, 1, 1]]\n";
        let err = parse_scene(text, Path::new("s.toml"))
            .unwrap_err()
            .to_string();
        assert_eq!(
            err,
            "s.toml: [source] up: \"x\": expected \"y\" or \"z\" (the character's up axis)"
        );
    }
}
