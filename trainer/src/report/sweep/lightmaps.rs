//! The light-map half of `aprt report`: pose-driven SH light maps (the pose-driven paper's
//! linear model with texels as rows, *Real-time Rendering of Dynamic Objects in Dynamic,
//! Low-frequency Lighting Environments* for the maps) at each resolution the scene allows,
//! several k_v and every precision, measured on the same test clips and surface points as the
//! per-vertex settings, so both methods share one Pareto front. Each is timed as it ships:
//! the pose, every texel's transfer, and the light map composed through aprt-core's
//! [`aprt_core::LightMap`] ([`frame_cost::light_map_us_per_frame`]).

use anyhow::{Context, Result};

use super::measure::{Measured, Truth, accuracy, finite, measured};
use super::{Point, SceneClips, Setting, strided_clips};
use crate::bake::BakeSettings;
use crate::bake::checkpoint::OnExisting;
use crate::io::source::joined;
use crate::lightmap::bake::{BakedMaps, CheckpointSettings, bake_light_maps};
use crate::lightmap::layout::{AtlasSpec, LightMapUvs};
use crate::lightmap::model::{ModelFrames, encode_light_map, fit_light_map_model};
use crate::lightmap::sample::rows_at_vertices;
use crate::model::ModelFrame;
use crate::model::export::Precision;
use crate::model::fit::{CoefDims, FitOptions};
use crate::progress::{Reporter, Silent};
use crate::report::experiment::{megaops, transfer_us};
use crate::rig::pose_layout::PoseLayout;
use crate::rig::uv::UvLayout;
use crate::rig::{Clip, Rig};
use crate::scene::file::{Choice, LIGHTMAP_RESOLUTIONS, Scene};
use crate::scene::frame_cost;
use crate::surface::SurfacePoints;

/// The light-map settings a sweep fits: every resolution with the default k_v, and more k_v
/// at the smallest resolution whose atlas can be built.
#[derive(Clone, Debug, PartialEq)]
pub struct LightMapCandidates {
    /// Texels a side, ascending.
    pub resolutions: Vec<usize>,
    /// The k_v tried beside the default at the smallest resolution that bakes.
    pub coef_dims: Vec<CoefDims>,
}

/// The light-map settings a sweep fits for `scene`: every resolution it allows (its
/// `lightmap_resolution`, or [`LIGHTMAP_RESOLUTIONS`]), k_v 8 and 32 beside the default.
pub fn light_map_candidates(scene: &Scene) -> LightMapCandidates {
    LightMapCandidates {
        resolutions: match scene.effects.lightmap_resolution {
            Choice::Fixed(r) => vec![r],
            Choice::Auto => LIGHTMAP_RESOLUTIONS.to_vec(),
        },
        coef_dims: vec![CoefDims::Count(8), CoefDims::Count(32)],
    }
}

/// What the light-map settings are fitted from and measured on.
pub struct LightMapSweep<'a> {
    /// The character and its clips.
    pub clips: &'a SceneClips<'a>,
    /// Every `stride`-th frame of every clip.
    pub stride: usize,
    /// The pose layout of the training frames.
    pub layout: &'a PoseLayout,
    /// The training bake's settings (the scene's order, rays and bounces).
    pub bake: BakeSettings,
    /// The frame the models learn transfer in.
    pub frame: ModelFrame,
}

/// Fits and measures every candidate of `list` (each resolution's maps baked once) against
/// `truth`. A resolution whose atlas cannot be built (the charts do not fit) is left out, with
/// the reason in the returned notes.
pub fn sweep_light_maps(
    sweep: &LightMapSweep<'_>,
    list: &LightMapCandidates,
    truth: &Truth<'_>,
    reporter: &dyn Reporter,
) -> Result<(Vec<Point>, Vec<String>)> {
    let rig = sweep.clips.rig;
    let (train, _) = strided_clips(sweep.clips, sweep.stride);
    let train = joined(train);
    let tests: Vec<Clip> = sweep
        .clips
        .tests
        .iter()
        .map(|c| super::strided(c, sweep.stride))
        .collect();
    let scratch = tempfile::tempdir().context("cannot create a scratch directory")?;
    let (mut points, mut notes) = (Vec::new(), Vec::new());
    for &resolution in &list.resolutions {
        reporter.note(&format!(
            "baking {resolution}x{resolution} light maps of {} frames",
            train.frames.len()
        ));
        let spec = AtlasSpec {
            resolution,
            uvs: LightMapUvs::DEFAULT_GENERATE,
        };
        let checkpoint = CheckpointSettings {
            dir: &scratch.path().join(format!("maps-{resolution}.bake")),
            existing: OnExisting::Refuse,
        };
        let what = format!("the {resolution}x{resolution} light map");
        let baked =
            match bake_light_maps(rig, &what, &train, spec, &sweep.bake, &checkpoint, &Silent) {
                Ok(baked) => baked,
                Err(e) => {
                    notes.push(format!("light maps at {resolution}x{resolution}: {e:#}"));
                    continue;
                }
            };
        let fitted = Fitted {
            sweep,
            train: &train,
            baked: &baked,
        };
        let mut coef_dims = vec![FitOptions::default().coef_dims];
        if points.is_empty() {
            coef_dims.extend(&list.coef_dims);
        }
        for k_v in coef_dims {
            points.extend(fitted.measure(resolution, k_v, &tests, truth)?);
        }
    }
    Ok((points, notes))
}

/// One resolution's maps, ready to fit candidates to.
struct Fitted<'a> {
    sweep: &'a LightMapSweep<'a>,
    train: &'a Clip,
    baked: &'a BakedMaps,
}

impl Fitted<'_> {
    /// Fits the model of `coef_dims` to the maps at `r`² and measures it in every precision
    /// on `tests` against `truth`.
    fn measure(
        &self,
        r: usize,
        coef_dims: CoefDims,
        tests: &[Clip],
        truth: &Truth<'_>,
    ) -> Result<Vec<Point>> {
        let sweep = self.sweep;
        let k_v = match coef_dims {
            CoefDims::Count(k) => k.to_string(),
            _ => "auto".to_owned(),
        };
        let label = format!("light map {r}², k_v {k_v}");
        let options = FitOptions {
            coef_dims,
            ..FitOptions::default()
        };
        let started = std::time::Instant::now();
        let rig = sweep.clips.rig;
        let fitted = fit_light_map_model(
            rig,
            sweep.layout,
            self.train,
            self.baked,
            &options,
            sweep.frame,
        )
        .with_context(|| format!("fitting {label}"))?;
        let fit_s = started.elapsed().as_secs_f64();
        let mut points = Vec::new();
        for precision in [Precision::F32, Precision::F16, Precision::I8] {
            let blob = encode_light_map(&fitted, &self.baked.sequence, precision, None)
                .with_context(|| format!("writing {label} in {}", precision.name()))?;
            let measured = measure_light_map(&blob, rig, tests, &self.baked.layout, truth)
                .with_context(|| format!("measuring {label}, {}", precision.name()))?;
            let info = *aprt_core::Model::parse(&blob)?.info();
            let bake = sweep.bake;
            let bake_s = self.baked.seconds / self.train.frames.len().max(1) as f64;
            points.push(Point::new(
                Setting {
                    label: format!("{label}, {}", precision.name()),
                    method: "lightmap",
                    resolution: Some(r),
                    order: bake.order,
                    pose_dims: "auto".into(),
                    coef_dims: k_v.clone(),
                    fitted: (info.pose_dims(), info.coef_dims()),
                    precision: precision.name(),
                    rays: bake.rays,
                    bounces: bake.bounces,
                    proxies: ("none", false),
                },
                (measured, blob),
                (bake_s, fit_s),
            ));
        }
        Ok(points)
    }
}

/// Measures light-map model `blob` on the test clips `tests` (their frames those of
/// `truth.tests`) of `rig`, its texels on `layout`: each frame's predicted texels read at
/// every vertex's UV and at every surface point's UV (bilinear, as a renderer samples the
/// map), and its frame timed through aprt-core's light-map composition.
pub fn measure_light_map(
    blob: &[u8],
    rig: &dyn Rig,
    tests: &[Clip],
    layout: &UvLayout,
    truth: &Truth<'_>,
) -> Result<Measured> {
    let info = *aprt_core::Model::parse(blob)?.info();
    let m2 = info.coeffs();
    let bind = truth.bind;
    let vertex_uvs = layout.vertex_uvs(&bind.triangles, bind.vertex_count());
    let point_uvs = truth.surface.uvs(layout);
    let mut sums = truth.sums();
    for (c, clip) in tests.iter().enumerate() {
        let model = ModelFrames::new(blob, "the light-map model", rig, clip)?;
        let (r, texels) = (model.resolution, &model.texels);
        for (f, rows) in model.predict(0..clip.frames.len())?.iter().enumerate() {
            let at_vertices = rows_at_vertices(rows, texels, r, m2, &vertex_uvs);
            let at_points = SurfacePoints::from_map_rows(rows, texels, r, m2, &point_uvs);
            truth.add_frame(&mut sums, (c, f), (&at_vertices, &at_points), m2);
        }
    }
    let us = frame_cost::light_map_us_per_frame(blob, bind, truth.scene)?;
    let transfer_us = transfer_us(blob, &truth.tests[0].angles[0])?;
    finite(measured(accuracy(&sums), us, transfer_us, megaops(&info)))
}
