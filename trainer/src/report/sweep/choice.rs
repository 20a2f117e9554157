//! The method `aprt train --scene` writes when its scene leaves it to `auto` (or a light map's
//! resolution or precision): the kind `aprt report` recommends, chosen by running the report's
//! own sweep (every setting of both methods on the scene's test clips, at the report's default
//! stride and surface points), so the two commands agree on the kind by construction: one
//! measure of what a method costs and what it shows over the surface, not two.

use anyhow::{Context, Result, bail};

use super::{Point, ReportSettings, SceneClips, check_stride, run};
use crate::model::export::Precision;
use crate::progress::Reporter;
use crate::rig::pose_sampler::DEFAULT_VALIDATION_POSES;
use crate::scene::file::{Method, Scene};
use crate::scene::lighting::SceneLighting;
use crate::scene::method::MethodDecision;
use crate::surface::DEFAULT_SURFACE_POINTS;

/// Frames of each clip the choice's sweep uses: one in three, `aprt report`'s default.
pub const CHOICE_STRIDE: usize = 3;

/// The method the report's sweep of `scene` on `clips` under `lighting` recommends
/// ([`decision_from`]). Progress and notes go to `reporter`.
pub fn swept_method(
    scene: &Scene,
    lighting: &SceneLighting,
    clips: &SceneClips<'_>,
    reporter: &dyn Reporter,
) -> Result<MethodDecision> {
    let started = std::time::Instant::now();
    reporter.note("choosing the method by `aprt report`'s sweep of both (1 frame in 3)");
    let settings = ReportSettings {
        budget_us: None,
        budget_bytes: None,
        stride: CHOICE_STRIDE,
        validation_poses: DEFAULT_VALIDATION_POSES,
        surface_points: DEFAULT_SURFACE_POINTS as usize,
    };
    check_stride(clips.train, CHOICE_STRIDE)?;
    let report = run(scene, lighting.clone(), clips, &settings, reporter)
        .context("choosing the method by the report's sweep")?;
    let mut decision = decision_from(&report.points, report.recommended)?;
    decision.seconds = started.elapsed().as_secs_f64();
    Ok(decision)
}

/// The method of a sweep's recommended point (`recommended`, an index into `points`), or of
/// its most accurate setting when none fits the budget, with the sentence that says why.
pub fn decision_from(points: &[Point], recommended: Option<usize>) -> Result<MethodDecision> {
    let most_accurate = points.iter().min_by(|a, b| a.error.total_cmp(&b.error));
    let (chosen, why) = match (recommended, most_accurate) {
        (Some(i), _) => (&points[i], "recommended within the scene's budget"),
        (None, Some(p)) => (p, "the most accurate: no setting fits the scene's budget"),
        (None, None) => bail!("the report's sweep measured no setting to choose the method by"),
    };
    let method = match chosen.setting.method {
        "lightmap" => Method::LightMap,
        _ => Method::Vertex,
    };
    let precision = [Precision::F32, Precision::F16, Precision::I8]
        .into_iter()
        .find(|p| p.name() == chosen.setting.precision);
    Ok(MethodDecision {
        method,
        resolution: chosen.setting.resolution,
        precision: (method == Method::LightMap).then_some(precision).flatten(),
        reason: format!(
            "method {}: `aprt report`'s sweep ({} settings, error over the surface on the test clips) has {} {why}, {:.2} grey levels at {:.1} µs a frame and {} bytes",
            method.name(),
            points.len(),
            chosen.setting.label,
            chosen.error,
            chosen.us_per_frame,
            chosen.bytes
        ),
        seconds: 0.0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::sweep::Setting;
    use crate::report::sweep::measure::Measured;

    fn point(method: &'static str, precision: &'static str, error: f64) -> Point {
        Point {
            setting: Setting {
                label: format!("{method} {precision}"),
                method,
                resolution: (method == "lightmap").then_some(128),
                order: 3,
                pose_dims: "auto".into(),
                coef_dims: "auto".into(),
                fitted: (4, 15),
                precision,
                rays: 128,
                bounces: 0,
                proxies: ("none", false),
            },
            error,
            us_per_frame: 100.0,
            bytes: 1000,
            pareto: false,
            pareto_bytes: false,
            measured: Measured::default(),
            bake_s_per_frame: 0.0,
            fit_s: 0.0,
            blob: Vec::new(),
        }
    }

    /// The recommendation's kind is written, a light map with its resolution and precision;
    /// with no recommendation (nothing fits the budget) the most accurate setting's kind, and
    /// the reason says which.
    #[test]
    fn the_kind_is_the_recommendations_or_the_most_accurate() {
        let points = vec![point("vertex", "f32", 5.0), point("lightmap", "i8", 4.0)];
        let chosen = decision_from(&points, Some(0)).unwrap();
        assert_eq!(
            (chosen.method, chosen.resolution, chosen.precision),
            (Method::Vertex, None, None)
        );
        assert!(
            chosen.reason.contains("recommended within"),
            "{}",
            chosen.reason
        );
        let fallback = decision_from(&points, None).unwrap();
        assert_eq!(fallback.method, Method::LightMap);
        assert_eq!(
            (fallback.resolution, fallback.precision),
            (Some(128), Some(Precision::I8))
        );
        assert!(
            fallback.reason.contains("no setting fits"),
            "{}",
            fallback.reason
        );
        assert!(decision_from(&[], None).is_err());
    }
}
