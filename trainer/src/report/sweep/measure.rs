//! Measuring one blob against ground truth on the test clips: the paper's relative transfer
//! error (section 6), the shading error in 8-bit grey levels under the scene's lighting, and
//! the per-frame cost through aprt-core on one core under the scene's lighting
//! ([`frame_cost::us_per_frame`], the figure `aprt train --scene` quotes).

use anyhow::{Result, bail};

use crate::bake::clip::BakedClip;
use crate::lighting::GREY_PER_IRRADIANCE;
use crate::model::predict::predict_world;
use crate::report::experiment::{megaops, transfer_us};
use crate::rig::mesh::Mesh;
use crate::scene::frame_cost;
use crate::scene::lighting::SceneLighting;

/// The ground truth a blob is measured against.
pub struct Truth<'a> {
    /// Test clips baked at the reference settings (order 6).
    pub tests: &'a [BakedClip],
    /// The scene's lighting at the character's centre, luminance, order 6 (36 values).
    pub lighting: &'a [f32],
    /// Coefficients per vertex of the truth.
    pub n2: usize,
    /// The scene's lighting, which each frame is timed under.
    pub scene: &'a SceneLighting,
    /// The character's bind pose, which each frame is timed on.
    pub bind: &'a Mesh,
    /// The rig's error target, grey levels: what splits each light between rig and vertex.
    pub target: f32,
}

/// What one blob measured.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct Measured {
    /// RMS shading error over every test frame and vertex, grey levels.
    pub grey_rms: f64,
    /// Largest shading error, grey levels.
    pub grey_max: f64,
    /// `‖pred − truth‖ / ‖truth‖` over every frame, vertex and coefficient of the truth (the
    /// bands a model leaves out count as error).
    pub transfer_error: f64,
    /// µs per frame through aprt-core as `train --scene` measures it: pose, light under the
    /// scene's rig (or at the centre), shade every vertex, the lights left per vertex, and
    /// the occluder proxies of a model that has them.
    pub us_per_frame: f64,
    /// µs per frame for the full per-vertex transfer.
    pub transfer_us: f64,
    /// Million multiply-adds per frame for RGB shading.
    pub megaops: f64,
}

impl Measured {
    /// The first figure that is not a finite number, by name: a report that printed it, or
    /// chose a setting by it, would say nothing true.
    pub fn non_finite(&self) -> Option<(&'static str, f64)> {
        [
            ("RMS shading error", self.grey_rms),
            ("largest shading error", self.grey_max),
            ("relative transfer error", self.transfer_error),
            ("µs per frame", self.us_per_frame),
            ("transfer µs per frame", self.transfer_us),
            ("million multiply-adds per frame", self.megaops),
        ]
        .into_iter()
        .find(|(_, v)| !v.is_finite())
    }
}

/// Measures `blob` on `truth`; refuses a figure that is not finite, naming it.
pub fn measure(blob: &[u8], truth: &Truth<'_>) -> Result<Measured> {
    let info = *aprt_core::Model::parse(blob)?.info();
    let m2 = info.coeffs();
    let lighting = &truth.lighting[..m2];
    let (mut diff, mut norm, mut grey2, mut grey_max, mut count) = (0.0, 0.0, 0.0, 0.0f64, 0usize);
    for clip in truth.tests {
        let predicted = predict_world(blob, &clip.angles, &clip.rotations, Some(clip.geometry()))?;
        for (p, t) in predicted.iter().zip(&clip.transfer) {
            for (pv, tv) in p.chunks_exact(m2).zip(t.chunks_exact(truth.n2)) {
                let mut shade = 0.0f64;
                let mut exact = 0.0f64;
                for c in 0..truth.n2 {
                    let tc = f64::from(tv[c]);
                    let pc = pv.get(c).map_or(0.0, |&x| f64::from(x));
                    diff += (pc - tc).powi(2);
                    norm += tc * tc;
                    exact += f64::from(truth.lighting[c]) * tc;
                    if c < m2 {
                        shade += f64::from(lighting[c]) * pc;
                    }
                }
                let grey = (shade - exact).abs() * GREY_PER_IRRADIANCE;
                grey2 += grey * grey;
                grey_max = grey_max.max(grey);
                count += 1;
            }
        }
    }
    let us_per_frame = frame_cost::us_per_frame(blob, truth.bind, truth.scene, truth.target)?.us;
    let transfer_us = transfer_us(blob, &truth.tests[0].angles[0])?;
    let measured = Measured {
        grey_rms: (grey2 / count.max(1) as f64).sqrt(),
        grey_max,
        transfer_error: (diff / norm.max(f64::MIN_POSITIVE)).sqrt(),
        us_per_frame,
        transfer_us,
        megaops: megaops(&info),
    };
    match measured.non_finite() {
        Some((figure, value)) => bail!(
            "its {figure} is {value}: the lighting or the model's values are beyond what f32 \
             shading holds; scale the lighting down"
        ),
        None => Ok(measured),
    }
}

#[cfg(test)]
mod tests {
    use super::Measured;

    #[test]
    fn the_first_figure_that_is_not_finite_is_named() {
        let fine = Measured {
            grey_rms: 1.0,
            grey_max: 2.0,
            transfer_error: 0.1,
            us_per_frame: 50.0,
            transfer_us: 900.0,
            megaops: 1.5,
        };
        assert_eq!(fine.non_finite(), None);
        let nan = Measured {
            grey_max: f64::NAN,
            us_per_frame: f64::INFINITY,
            ..fine
        };
        let (figure, value) = nan.non_finite().unwrap();
        assert_eq!(figure, "largest shading error");
        assert!(value.is_nan());
        let huge = Measured {
            grey_rms: f64::INFINITY,
            ..fine
        };
        assert_eq!(
            huge.non_finite(),
            Some(("RMS shading error", f64::INFINITY))
        );
    }
}
