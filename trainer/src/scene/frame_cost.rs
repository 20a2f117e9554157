//! What a scene's model costs aprt-core each frame, and whether that fits the scene's
//! `[budget]`: the one measure `aprt train --scene` quotes for the model it writes and
//! `aprt report` ranks its settings by, so the two agree.

use anyhow::{Context, Result};
use aprt_core::{DEFAULT_BAND, LightMap, Model, PoseWeights, Rgb};

use crate::irradiance_rig::fit::bounds;
use crate::model::export::Precision;
use crate::model::runtime::{CoreFrame, FrameInputs, median_us};
use crate::rig::mesh::Mesh;
use crate::scene::lighting::SceneLighting;

/// Median µs of one frame of `blob` through aprt-core under the scene's `lighting`, as an
/// engine runs it ([`CoreFrame`]): set the pose, light (under the model's irradiance rig, or
/// the environment and lights projected at the character's centre when it has none), shade
/// every vertex, add the lights the rig leaves to each vertex (split at `target` grey
/// levels), and the occluder proxies when the model has them.
///
/// Timed on `bind` (the character's bind pose, in the rig's root frame), with the rest pose's
/// angles and identity bones: a frame's work does not depend on the pose's values, and one
/// fixed pose makes every caller time the same frame.
pub fn us_per_frame(
    blob: &[u8],
    bind: &Mesh,
    lighting: &SceneLighting,
    target: f32,
) -> Result<FrameCost> {
    let info = *Model::parse(blob)?.info();
    if info.vertices() != bind.vertex_count() {
        anyhow::bail!(
            "the model has {} vertices and the character {}",
            info.vertices(),
            bind.vertex_count()
        );
    }
    let n2 = info.coeffs();
    let environment: Vec<Rgb> = match lighting.environment.is_empty() {
        true => Vec::new(),
        false => (0..n2)
            .map(|c| lighting.environment.get(c).copied().unwrap_or([0.0; 3]))
            .collect(),
    };
    let identity = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let still = [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0];
    let (centre, _, _) = bounds(&[bind]);
    let angles = vec![0.0f32; info.pose_len()];
    let rotations = vec![identity; info.bones()];
    let skinning = vec![still; info.bones()];
    let inputs = FrameInputs {
        angles: &angles,
        rotations: &rotations,
        positions: &bind.positions,
        skinning: &skinning,
        normals: &bind.normals,
        environment: &environment,
        lights: &lighting.lights,
        centre: centre.map(|x| x as f32),
        target,
        band: DEFAULT_BAND,
    };
    let mut frame = CoreFrame::new(blob, lighting.lights.len())?;
    let us = frame
        .median_us(&inputs)
        .context("timing a frame through aprt-core")?;
    Ok(FrameCost {
        us,
        rig: frame.has_rig(),
        proxies: info.has_proxies(),
        per_vertex_lights: match frame.has_rig() {
            true => frame.shares.iter().filter(|&&s| s < 1.0).count(),
            false => 0,
        },
    })
}

/// Median µs of one frame of light-map model `blob` (its rows the texels of an atlas) through
/// aprt-core, as an engine ships it: set the pose, every texel's transfer
/// ([`Model::transfer`]), and the RGB light map composed under the scene's `lighting`
/// projected at `bind`'s centre ([`LightMap::compose`]), which the renderer then samples.
/// A bone-frame model's texels are composed under one lighting here; an engine turns the
/// lighting into each bone's frame first, n² × bones multiply-adds that do not show beside
/// the texels'.
pub fn light_map_us_per_frame(blob: &[u8], bind: &Mesh, lighting: &SceneLighting) -> Result<f64> {
    let model = Model::parse(blob)?;
    let info = *model.info();
    let (texels, n2) = (info.vertices(), info.coeffs());
    let composed: Vec<Rgb> = lighting.sh_at_centre(info.order(), bind)?;
    let map = LightMap::new(info.order())?;
    let angles = vec![0.0f32; info.pose_len()];
    let mut pose = Box::new(PoseWeights::new());
    let mut transfer = vec![0.0f32; texels * n2];
    let mut rgb = vec![[0.0f32; 3]; texels];
    let mut frame = || -> Result<(), aprt_core::Error> {
        model.set_pose(&angles, &mut pose)?;
        model.transfer(&pose, 0, &mut transfer)?;
        map.compose(&transfer, &composed, &mut rgb)
    };
    frame().context("timing a light-map frame through aprt-core")?;
    Ok(median_us(|| {
        let _ = frame();
    }))
}

/// A model's cost a frame under a scene's lighting.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameCost {
    /// Median µs a frame through aprt-core.
    pub us: f64,
    /// Whether the model lights through an irradiance rig.
    pub rig: bool,
    /// Whether the model has occluder proxies (posed and applied every frame).
    pub proxies: bool,
    /// Lights the rig leaves, wholly or partly, to each vertex.
    pub per_vertex_lights: usize,
}

/// How a measured cost stands against a budget of µs per frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BudgetCheck {
    /// What the model costs.
    pub cost: FrameCost,
    /// The budget, µs per frame.
    pub budget: f64,
    /// The precision the model was written in (i8 is not suggested to an i8 model).
    pub precision: Precision,
}

impl BudgetCheck {
    /// Whether the cost fits.
    pub fn within(&self) -> bool {
        self.cost.us <= self.budget
    }

    /// What a model that misses the budget should say: by how much, and what to change,
    /// naming the parts of its frame that cost it (per-vertex lights, proxies). `None` when
    /// it fits.
    pub fn miss_message(&self) -> Option<String> {
        if self.within() {
            return None;
        }
        let cost = &self.cost;
        let over = cost.us / self.budget;
        let by = if over >= 2.0 {
            format!("{over:.1}x the budget")
        } else {
            format!("{:.0} % over", 100.0 * (over - 1.0))
        };
        let mut changes =
            vec!["a lower k_v (--coef-dims) or SH order ([effects] order)".to_owned()];
        if self.precision != Precision::I8 {
            changes.push("precision i8 ([effects] precision = \"i8\")".to_owned());
        }
        if cost.per_vertex_lights > 0 {
            changes.push(format!(
                "fewer lights near the character, or farther ones that the rig carries ({} evaluated per vertex through its transfer)",
                cost.per_vertex_lights
            ));
        } else if cost.rig {
            changes.push("a rig with fewer SH vectors ([effects] irradiance_rig)".to_owned());
        }
        if cost.proxies {
            changes.push("no occluder proxies (--proxies none)".to_owned());
        }
        changes.push("the setting `aprt report` recommends within the budget".to_owned());
        Some(format!(
            "over budget: the model costs {:.1} µs a frame through aprt-core against the scene's [budget] us_per_frame = {} ({by}); to fit, try {}",
            cost.us,
            self.budget,
            changes.join("; ")
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::{BudgetCheck, FrameCost, Precision};

    #[test]
    fn a_miss_says_by_how_much_and_what_to_change() {
        let cost = |us, per_vertex_lights, proxies| FrameCost {
            us,
            rig: true,
            proxies,
            per_vertex_lights,
        };
        let check = |cost, budget| BudgetCheck {
            cost,
            budget,
            precision: Precision::F16,
        };
        let fits = check(cost(29.0, 1, false), 30.0);
        assert!(fits.within());
        assert_eq!(fits.miss_message(), None);
        let text = check(cost(571.0, 1, true), 30.0).miss_message().unwrap();
        assert!(text.contains("571.0 µs") && text.contains("= 30"), "{text}");
        assert!(text.contains("19.0x the budget"), "{text}");
        assert!(text.contains("1 evaluated per vertex"), "{text}");
        assert!(text.contains("--proxies none"), "{text}");
        assert!(
            text.contains("aprt report") && text.contains("i8"),
            "{text}"
        );
        let close = check(cost(33.0, 0, false), 30.0).miss_message().unwrap();
        assert!(close.contains("10 % over"), "{close}");
        assert!(close.contains("fewer SH vectors") && !close.contains("proxies"));
        let i8 = BudgetCheck {
            precision: Precision::I8,
            ..check(cost(33.0, 0, false), 30.0)
        };
        assert!(!i8.miss_message().unwrap().contains("i8"));
    }
}
