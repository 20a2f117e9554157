//! Measuring one blob against ground truth on the test clips: the paper's relative transfer
//! error (section 6) and the shading error in 8-bit grey levels under the scene's lighting,
//! at the vertices and over the whole surface ([`crate::surface`]: per-vertex transfer
//! interpolated across each triangle, a light map read at each point's UV), and the per-frame
//! cost through aprt-core on one core under the scene's lighting ([`frame_cost`], the figure
//! `aprt train --scene` quotes).

use anyhow::{Result, bail};

use crate::bake::clip::BakedClip;
use crate::model::predict::predict_world;
use crate::report::experiment::{megaops, transfer_us};
use crate::rig::mesh::Mesh;
use crate::scene::frame_cost;
use crate::scene::lighting::SceneLighting;
use crate::surface::SurfacePoints;
use crate::surface::error::{Accuracy, ErrorSum};

/// The ground truth a blob is measured against.
pub struct Truth<'a> {
    /// Test clips baked at the reference settings (order 6).
    pub tests: &'a [BakedClip],
    /// The scene's lighting at the character's centre, luminance, order 6 (36 values).
    pub lighting: &'a [f32],
    /// The scene's lighting, which each frame is timed under.
    pub scene: &'a SceneLighting,
    /// The character's bind pose, which each frame is timed on.
    pub bind: &'a Mesh,
    /// The rig's error target, grey levels: what splits each light between rig and vertex.
    pub target: f32,
    /// Points spread over the surface, where the surface error is measured.
    pub surface: &'a SurfacePoints,
    /// Transfer at those points in every frame of every test clip, at the reference settings.
    pub surface_tests: &'a [Vec<Vec<f32>>],
    /// Each point's area weight, in point order (gathered once for every frame's sum).
    pub surface_weights: Vec<f64>,
}

impl Truth<'_> {
    /// Sums of a prediction's error at the vertices and over the surface: one frame at a
    /// time through [`Truth::add_frame`], then [`accuracy`].
    pub fn sums(&self) -> (ErrorSum<'_>, ErrorSum<'_>) {
        (ErrorSum::new(self.lighting), ErrorSum::new(self.lighting))
    }

    /// Adds frame `f` of test clip `clip`: `at_vertices` and `at_points` hold `m2` values per
    /// vertex and per surface point.
    pub fn add_frame(
        &self,
        sums: &mut (ErrorSum<'_>, ErrorSum<'_>),
        (clip, f): (usize, usize),
        (at_vertices, at_points): (&[f32], &[f32]),
        m2: usize,
    ) {
        sums.0
            .add(at_vertices, m2, &self.tests[clip].transfer[f], None);
        sums.1.add(
            at_points,
            m2,
            &self.surface_tests[clip][f],
            Some(&self.surface_weights),
        );
    }
}

/// The error figures of a [`Measured`], at the vertices and over the surface.
pub fn accuracy(sums: &(ErrorSum<'_>, ErrorSum<'_>)) -> (Accuracy, Accuracy) {
    (sums.0.finish(), sums.1.finish())
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
    /// RMS shading error over the whole surface, grey levels: every test frame at points
    /// spread by area, each weighted by the area it stands for, the method read there as a
    /// renderer shows it (per-vertex values interpolated, a light map filtered).
    pub surface_grey_rms: f64,
    /// `‖pred − truth‖ / ‖truth‖` at those points.
    pub surface_transfer_error: f64,
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
            ("RMS shading error over the surface", self.surface_grey_rms),
            (
                "relative transfer error over the surface",
                self.surface_transfer_error,
            ),
        ]
        .into_iter()
        .find(|(_, v)| !v.is_finite())
    }
}

/// Measures per-vertex model `blob` on `truth`; refuses a figure that is not finite, naming
/// it.
pub fn measure(blob: &[u8], truth: &Truth<'_>) -> Result<Measured> {
    let info = *aprt_core::Model::parse(blob)?.info();
    let m2 = info.coeffs();
    let mut sums = truth.sums();
    let triangles = &truth.bind.triangles;
    for (c, clip) in truth.tests.iter().enumerate() {
        let predicted = predict_world(blob, &clip.angles, &clip.rotations, Some(clip.geometry()))?;
        for (f, p) in predicted.iter().enumerate() {
            let at_points = truth.surface.from_vertices(p, m2, triangles);
            truth.add_frame(&mut sums, (c, f), (p, &at_points), m2);
        }
    }
    let us_per_frame = frame_cost::us_per_frame(blob, truth.bind, truth.scene, truth.target)?.us;
    let transfer_us = transfer_us(blob, &truth.tests[0].angles[0])?;
    finite(measured(
        accuracy(&sums),
        us_per_frame,
        transfer_us,
        megaops(&info),
    ))
}

/// The figures of a measurement.
pub fn measured(
    (vertices, surface): (Accuracy, Accuracy),
    us_per_frame: f64,
    transfer_us: f64,
    megaops: f64,
) -> Measured {
    Measured {
        grey_rms: vertices.grey_rms,
        grey_max: vertices.grey_max,
        transfer_error: vertices.transfer_error,
        us_per_frame,
        transfer_us,
        megaops,
        surface_grey_rms: surface.grey_rms,
        surface_transfer_error: surface.transfer_error,
    }
}

/// `measured`, or the error naming its first figure that is not finite.
pub fn finite(measured: Measured) -> Result<Measured> {
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
            surface_grey_rms: 1.5,
            surface_transfer_error: 0.12,
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
