//! A rig-lit frame for the demo: the pose model's transfer lit by its irradiance rig for the
//! far lights and per vertex for a near one (*Irradiance Rigs*), through aprt-core, beside the
//! ray-traced transfer of the same frame lit per vertex by every light.

use std::path::Path;

use anyhow::Result;
use aprt_core::{DEFAULT_BAND, DirectionalLight, Light, MAX_COEFFS, PointLight, Rgb, SphereLight};
use glam::Vec3;

use crate::bake::clip::BakedClip;
use crate::irradiance_rig::GreyError;
use crate::lighting::GREY_PER_IRRADIANCE;
use crate::lighting::{kind_name, luminance};
use crate::model::occluders::skinning_of;
use crate::model::runtime::predict_rig_shading;
use crate::report::figures::{ErrorPanel, save_panels, upright};

/// The demo's rig-or-analytic target, grey levels.
const TARGET: f32 = 1.0;

/// What the frame showed.
#[derive(Clone, Debug, serde::Serialize)]
pub struct RigFrame {
    /// Each light: kind, distance from the rig's centre and the share the rig carried.
    pub lights: Vec<(String, f32, f32)>,
    /// Model + rig + per-vertex lights against the ray-traced transfer lit per vertex, in
    /// grey levels of the displayed shading (luminance).
    pub error_grey: GreyError,
}

/// The demo's lights for a frame of `mesh`: a small bright sphere light a hand's breadth in
/// front of the character's right shoulder (near: per vertex), a lamp 11 m away and a sun
/// (both far: in the rig).
pub fn demo_lights(mesh: &crate::rig::mesh::Mesh) -> Vec<Light> {
    let n = mesh.positions.len().max(1) as f32;
    let c = mesh.positions.iter().fold([0.0f32; 3], |a, p| {
        [a[0] + p[0] / n, a[1] + p[1] / n, a[2] + p[2] / n]
    });
    vec![
        Light::Sphere(SphereLight {
            position: [c[0] + 0.3, c[1] - 0.45, c[2] + 0.3],
            radius: 0.04,
            radiance: [60.0, 45.0, 30.0],
        }),
        Light::Point(PointLight {
            position: [c[0] - 8.0, c[1] - 6.0, c[2] + 5.0],
            intensity: [3.0, 3.6, 4.8],
        }),
        Light::Directional(DirectionalLight {
            direction: [-0.3, -0.5, 0.8],
            irradiance: [0.25, 0.25, 0.25],
        }),
    ]
}

/// Writes ray-traced transfer lit per vertex | the model with its rig | 4× error, for frame
/// `frame` of `clip` under `lights`, shading shown as luminance; `blob` must carry a rig.
pub fn save_rig_frame(
    path: &Path,
    blob: &[u8],
    clip: &BakedClip,
    frame: usize,
    lights: &[Light],
) -> Result<RigFrame> {
    let mesh = &clip.meshes[frame];
    let skinning: Vec<_> = clip.joints[frame].iter().map(skinning_of).collect();
    let (model, shares) = predict_rig_shading(
        blob,
        &clip.angles[frame],
        &clip.core_rotations(frame),
        &mesh.positions,
        (&skinning, &mesh.normals),
        lights,
        TARGET,
        DEFAULT_BAND,
    )?;
    let n2 = clip.transfer[frame].len() / mesh.vertex_count();
    let order = (n2 as f64).sqrt() as usize;
    let truth: Vec<Rgb> = mesh
        .positions
        .iter()
        .zip(clip.transfer[frame].chunks_exact(n2))
        .map(|(p, t)| {
            let mut l = [[0.0f32; 3]; MAX_COEFFS];
            for light in lights {
                let _ = light.add_radiance_sh(order, *p, &mut l[..n2]);
            }
            std::array::from_fn(|k| t.iter().zip(&l).map(|(a, b)| a * b[k]).sum())
        })
        .collect();
    let (truth, model): (Vec<f32>, Vec<f32>) = (
        truth.iter().map(|&c| luminance(c)).collect(),
        model.iter().map(|&c| luminance(c)).collect(),
    );
    let errors: Vec<f64> = truth
        .iter()
        .zip(&model)
        .map(|(a, b)| GREY_PER_IRRADIANCE * f64::from((a - b).abs()))
        .collect();
    let error_grey = GreyError {
        mean: errors.iter().sum::<f64>() / errors.len().max(1) as f64,
        max: errors.iter().copied().fold(0.0, f64::max),
    };
    save_panels(
        path,
        &upright(mesh, Vec3::Z),
        &[&truth, &model],
        &["ray-traced, lights per vertex", "model: rig + near light"],
        ErrorPanel::Shown,
    )?;
    let centre = aprt_core::Model::parse(blob)?
        .irradiance_rig()
        .map_or([0.0; 3], |r| r.centre());
    Ok(RigFrame {
        lights: lights
            .iter()
            .zip(&shares)
            .map(|(l, &s)| {
                let d = match l {
                    Light::Sphere(x) => Some(x.position),
                    Light::Point(x) => Some(x.position),
                    Light::Directional(_) => None,
                }
                .map_or(f32::INFINITY, |p| {
                    (0..3)
                        .map(|k| (p[k] - centre[k]).powi(2))
                        .sum::<f32>()
                        .sqrt()
                });
                (kind_name(l).to_owned(), d, s)
            })
            .collect(),
        error_grey,
    })
}
