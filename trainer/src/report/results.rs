//! `aprt results`: the paper's experiments on real characters and motion capture, written as a
//! markdown document with PNG figures: per study the table of the demo, the PCA spectra
//! (the paper's Figure 4), error against α (Figure 3), the residual distribution and its CDF
//! (Figure 2), and renders of a novel frame.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result};
use glam::{Quat, Vec3};

use crate::bake::BakeSettings;
use crate::bake::clip::{BakedClip, bake_clip};
use crate::io::atomic::write_atomic;
use crate::model::ModelFrame;
use crate::model::export::{Precision, encode_model};
use crate::model::fit::{Alpha, CoefDims, FitOptions};
use crate::model::predict::predict_world;
use crate::pipeline::train::{ClipSet, fit_clip};
use crate::progress::Reporter;
use crate::report::evaluate::relative_error;
use crate::report::experiment::{
    self, Experiment, ModelConfig, SAMPLED_LEGEND, TABLE_LEGEND, sampled_config, standard_configs,
    table_markdown,
};
use crate::report::figures::{picture_lighting, save_model_frame};
use crate::report::plots::{Axes, Series, line_plot};
use crate::rig::Rig;
use crate::rig::gltf::GltfRig;
use crate::rig::mannequin::{MocapOptions, MocapRig};
use crate::rig::mocap::Mocap;
use crate::rig::pose_layout::PoseLayout;

/// A clip's name and frames (the rig's pose vectors).
pub type NamedFrames = (String, Vec<Vec<f64>>);

/// One experiment: a character, the frames it trains on and the clips it is tested on.
pub struct Study {
    /// File-name-safe identifier, used for the figures' names.
    pub id: String,
    /// Heading in the document.
    pub title: String,
    /// One line on where the data comes from and how it is split.
    pub about: String,
    /// The character.
    pub rig: Box<dyn Rig>,
    /// The character's up axis (glTF and BVH are y-up, the built-in character z-up); renders
    /// turn it to the screen's up.
    pub up: Vec3,
    /// Name and frames of the training clip.
    pub train: NamedFrames,
    /// Names and frames of the novel clips.
    pub tests: Vec<NamedFrames>,
}

/// Splits one clip into a training part (the first `fraction` of the frames) and a test part
/// (the rest), for characters with a single animation.
pub fn split_clip(name: &str, frames: Vec<Vec<f64>>, fraction: f64) -> (NamedFrames, NamedFrames) {
    let cut = ((frames.len() as f64 * fraction).round() as usize).clamp(1, frames.len() - 1);
    let mut train = frames;
    let test = train.split_off(cut);
    (
        (format!("{name} [0, {cut})"), train),
        (format!("{name} [{cut}, {})", cut + test.len()), test),
    )
}

/// Settings of a results run.
#[derive(Clone, Debug)]
pub struct ResultsSettings {
    /// Bake settings of the ground truth.
    pub bake: BakeSettings,
    /// α values of the sweep (Figure 3), besides 0.
    pub alphas: Vec<f64>,
    /// Validation poses per study (`--validation-poses`): sampled from the training clip as
    /// `aprt train` samples them, baked and used to choose every model by (0: held-out runs).
    pub validation_poses: usize,
}

/// The configuration whose vertex basis is chosen by energy.
const BY_ENERGY: &str = "PCA(all, 99.9 % energy)";

/// Sampled training poses of the `default, --sample-poses N` row: one count for every study,
/// the 240 of the remix measured in issue 29 (the studies train on 26 to 300 frames).
const SAMPLE_POSES: usize = 240;

/// The model shapes of the results: the standard ones, the default with [`SAMPLE_POSES`]
/// sampled training poses right after the default, and the vertex basis chosen by energy
/// (99.9 %), whose longer spectrum Figure 4 plots.
fn results_configs() -> Vec<ModelConfig> {
    let mut configs = standard_configs();
    configs.insert(1, sampled_config(SAMPLE_POSES));
    configs.push(ModelConfig {
        name: BY_ENERGY.into(),
        options: FitOptions {
            coef_dims: CoefDims::Variance(0.999),
            ..FitOptions::default()
        },
        frame: ModelFrame::Bone,
        sample_poses: 0,
    });
    configs
}

/// Runs one study, writes its figures into `out` and returns its markdown section. Progress goes
/// to `reporter`.
pub fn run_study(
    study: &Study,
    settings: &ResultsSettings,
    out: &Path,
    reporter: &dyn Reporter,
) -> Result<String> {
    let start = Instant::now();
    let measured = measure(study, settings, reporter)?;
    write_figures(study, &measured, out)?;
    Ok(section_markdown(
        study,
        &measured,
        start.elapsed().as_secs_f64(),
    ))
}

/// Everything one study measured: what its figures and its section are made of.
struct Measured {
    /// The kept entries of the rig's pose vector.
    layout: PoseLayout,
    /// Ground truth of the training clip.
    train: BakedClip,
    /// Ground truth of the novel clips.
    tests: Vec<BakedClip>,
    /// Bake seconds per training frame.
    bake_s: f64,
    /// Validation poses the models were chosen by, and the seconds their bake took.
    validation: (usize, f64),
    /// The lighting of the renders and timings.
    lighting: Vec<f32>,
    /// The models and the table.
    experiment: Experiment,
    /// (α, train error, test error per clip) of the default shape, for Figure 3.
    sweep: Vec<(f64, f64, Vec<f64>)>,
    /// The default model's per-vertex residuals on the novel clips, for Figure 2.
    residuals: Vec<f64>,
}

impl Measured {
    /// The default model (the study fails without it).
    fn default_model(&self) -> Result<&experiment::Fitted> {
        self.experiment.model(experiment::DEFAULT_CONFIG)
    }

    /// The novel frame the renders show: the middle of the first test clip.
    fn novel_frame(&self) -> (&BakedClip, usize) {
        let test = &self.tests[0];
        (test, test.angles.len() / 2)
    }

    fn test_names(&self) -> Vec<String> {
        self.tests.iter().map(|t| t.name.clone()).collect()
    }
}

/// Bakes the study's clips, fits and measures its models, sweeps α and collects residuals.
fn measure(study: &Study, settings: &ResultsSettings, reporter: &dyn Reporter) -> Result<Measured> {
    let rig = study.rig.as_ref();
    let names = rig.angle_names();
    let layout = PoseLayout::from_training(&names, &study.train.1)
        .with_context(|| format!("{}: training clip {}", study.title, study.train.0))?;
    reporter.note(&format!("study {}: baking", study.title));
    let (train, bake_s) = bake_clip(
        rig,
        &layout,
        &study.train.0,
        study.train.1.clone(),
        &settings.bake,
        reporter,
    )?;
    let tests = study
        .tests
        .iter()
        .map(|(name, frames)| {
            Ok(bake_clip(rig, &layout, name, frames.clone(), &settings.bake, reporter)?.0)
        })
        .collect::<Result<Vec<_>>>()?;
    let order = settings.bake.order;
    let to_light = Quat::from_rotation_arc(study.up.normalize(), Vec3::Z).inverse()
        * Vec3::new(0.5, -0.8, 0.9);
    let lighting = picture_lighting(order, to_light);
    let validation_poses = experiment::baked_validation_poses(
        rig,
        &layout,
        &train,
        settings.validation_poses,
        &settings.bake,
        reporter,
    )?;
    let (validation, validation_seconds) = match validation_poses {
        Some((clip, seconds)) => (vec![clip], seconds),
        None => (Vec::new(), 0.0),
    };
    let experiment = experiment::run(
        rig,
        &layout,
        &train,
        &validation,
        &tests,
        &results_configs(),
        &settings.bake,
        &lighting,
        reporter,
    )?;
    let default = experiment.model(experiment::DEFAULT_CONFIG)?;
    let sweep = alpha_sweep(
        rig,
        &layout,
        &train,
        &experiment.rest,
        &tests,
        order,
        &settings.alphas,
    )?;
    let residuals = vertex_residuals(&default.blob, &tests)?;
    Ok(Measured {
        layout,
        train,
        tests,
        bake_s,
        validation: (
            validation.first().map_or(0, |v| v.angles.len()),
            validation_seconds,
        ),
        lighting,
        experiment,
        sweep,
        residuals,
    })
}

/// The file name of figure `what` of the study `id`.
fn figure_file(id: &str, what: &str) -> String {
    format!("{id}_{what}.png")
}

/// Writes the study's figures into `out`: the spectra (Figure 4), error against α (Figure 3),
/// the residual distribution and CDF (Figure 2), and a novel frame.
fn write_figures(study: &Study, measured: &Measured, out: &Path) -> Result<()> {
    let figure = |what: &str| out.join(figure_file(&study.id, what));
    let result = &measured.experiment;
    let default = measured.default_model()?;
    // A skipped (too large) energy model leaves the default's spectrum to plot.
    let by_energy = if result.skipped.iter().any(|(name, _)| name == BY_ENERGY) {
        default
    } else {
        result.model(BY_ENERGY)?
    };
    spectra_plot(&figure("spectra"), &study.title, by_energy)?;
    alpha_plot(
        &figure("alpha"),
        &study.title,
        &measured.sweep,
        &measured.test_names(),
        default.fit.report.alpha,
    )?;
    residual_plots(
        &figure("residuals"),
        &figure("residual_cdf"),
        &study.title,
        &measured.residuals,
    )?;
    // Ground truth | model | 4× error.
    let (test, frame) = measured.novel_frame();
    save_model_frame(
        &figure("frame"),
        &default.blob,
        test,
        frame,
        &measured.lighting,
        study.up,
    )?;
    Ok(())
}

/// The study's markdown section; `seconds` is how long the study took.
fn section_markdown(study: &Study, measured: &Measured, seconds: f64) -> String {
    let Measured {
        layout,
        train,
        tests,
        experiment: result,
        ..
    } = measured;
    let mut s = String::new();
    let _ = writeln!(s, "## {}\n\n{}\n", study.title, study.about);
    let bind = study.rig.bind_mesh();
    let _ = writeln!(
        s,
        "{} vertices, {} triangles; pose vector of {} entries ({} joints dropped as never moving in training{}). Trained on `{}` ({} frames); tested on {}. Bake {:.3} s per frame{}; study {:.0} s.\n",
        bind.vertex_count(),
        bind.triangles.len(),
        layout.names().len(),
        layout.dropped().len(),
        if layout.dropped().is_empty() {
            String::new()
        } else {
            format!(": {}", layout.dropped().join(", "))
        },
        train.name,
        train.angles.len(),
        tests
            .iter()
            .map(|t| format!("`{}` ({} frames)", t.name, t.angles.len()))
            .collect::<Vec<_>>()
            .join(", "),
        measured.bake_s,
        match measured.validation {
            (0, _) => String::new(),
            (n, s) => format!(" ({n} validation poses, {s:.1} s)"),
        },
        seconds,
    );
    s.push_str(&table_markdown(&result.rows, &measured.test_names()));
    for (name, reason) in &result.skipped {
        let _ = writeln!(s, "\n*Not in the table: {name}, because {reason}.*");
    }
    if let Some(selection) = experiment::selection_markdown(&result.rows, "###") {
        let _ = writeln!(s, "{selection}");
    }
    let file = |what: &str| figure_file(&study.id, what);
    let _ = writeln!(
        s,
        "\n![PCA spectra]({})\n\n*Figure 4: eigenvalues of the pose covariance and energy of the vertex-coefficient components, each relative to its largest.*\n",
        file("spectra")
    );
    let _ = writeln!(
        s,
        "![error against alpha]({})\n\n*Figure 3: train and test error of the default shape against α (α = 0, no regularisation, is drawn at the left edge); the dashed marker is the α that leave-one-segment-out chose.*\n",
        file("alpha")
    );
    let _ = writeln!(
        s,
        "![residual distribution]({})\n![residual CDF]({})\n\n*Figure 2: per-vertex residual ‖t̂ − t‖ of the default model on the novel clips, relative to the RMS per-vertex norm of the true transfer: distribution and empirical CDF.*\n",
        file("residuals"),
        file("residual_cdf")
    );
    let (test, frame) = measured.novel_frame();
    let _ = writeln!(
        s,
        "![ground truth, model, 4x error]({})\n\n*Frame {frame} of `{}`: ground truth | default model through aprt-core | 4× absolute error.*\n",
        file("frame"),
        test.name
    );
    s
}

/// (α, train error, test error per clip) of the default shape at each α, plus α = 0 first.
fn alpha_sweep(
    rig: &dyn Rig,
    layout: &PoseLayout,
    train: &BakedClip,
    rest: &BakedClip,
    tests: &[BakedClip],
    order: usize,
    alphas: &[f64],
) -> Result<Vec<(f64, f64, Vec<f64>)>> {
    std::iter::once(0.0)
        .chain(alphas.iter().copied())
        .map(|alpha| {
            let options = FitOptions {
                alpha: Alpha::Fixed(alpha),
                ..FitOptions::default()
            };
            let clips = ClipSet {
                train,
                rest: Some(rest),
                validation: &[],
            };
            let fitted = fit_clip(rig, layout, clips, order, &options, ModelFrame::Bone)?;
            let blob = encode_model(&fitted.model, Precision::F32)?;
            let error = |clip: &BakedClip| -> Result<f64> {
                let predicted =
                    predict_world(&blob, &clip.angles, &clip.rotations, Some(clip.geometry()))?;
                Ok(relative_error(&predicted, &clip.transfer))
            };
            let tests = tests.iter().map(error).collect::<Result<Vec<_>>>()?;
            Ok((alpha, error(train)?, tests))
        })
        .collect()
}

/// Per vertex and frame of every clip: ‖t̂ − t‖ / RMS‖t‖.
fn vertex_residuals(blob: &[u8], tests: &[BakedClip]) -> Result<Vec<f64>> {
    let mut residuals = Vec::new();
    let mut norms = Vec::new();
    for clip in tests {
        let predicted = predict_world(blob, &clip.angles, &clip.rotations, Some(clip.geometry()))?;
        let n2 = clip.transfer[0].len() / clip.meshes[0].vertex_count();
        for (p, t) in predicted.iter().zip(&clip.transfer) {
            for (pv, tv) in p.chunks_exact(n2).zip(t.chunks_exact(n2)) {
                let diff: f64 = pv
                    .iter()
                    .zip(tv)
                    .map(|(a, b)| (f64::from(*a) - f64::from(*b)).powi(2))
                    .sum();
                residuals.push(diff.sqrt());
                norms.push(tv.iter().map(|x| f64::from(*x).powi(2)).sum::<f64>());
            }
        }
    }
    let rms = (norms.iter().sum::<f64>() / norms.len().max(1) as f64).sqrt();
    Ok(residuals.into_iter().map(|r| r / rms.max(1e-30)).collect())
}

fn spectra_plot(path: &Path, title: &str, fitted: &experiment::Fitted) -> Result<()> {
    let normalised = |values: &[f64]| -> Vec<(f64, f64)> {
        let top = values.first().copied().unwrap_or(1.0).max(1e-300);
        // Below 1e-12 of the largest, an eigenvalue is rounding noise of a null direction
        // (joints that move together): leave it out rather than stretch the axis to 1e-30.
        values
            .iter()
            .enumerate()
            .map(|(k, v)| ((k + 1) as f64, v / top))
            .filter(|&(_, v)| v > 1e-12)
            .collect()
    };
    let report = &fitted.fit.report;
    line_plot(
        path,
        &Axes {
            title: &format!("{title}: PCA spectra"),
            x: "component k",
            y: "relative eigenvalue / energy",
            log_x: false,
            log_y: true,
        },
        &[
            Series {
                name: "pose covariance eigenvalues".into(),
                points: normalised(&report.pose_eigenvalues),
                markers: true,
                line: true,
            },
            Series {
                name: "vertex-coefficient energy σ²".into(),
                points: normalised(&report.coef_energy),
                markers: false,
                line: true,
            },
        ],
    )
}

fn alpha_plot(
    path: &Path,
    title: &str,
    sweep: &[(f64, f64, Vec<f64>)],
    test_names: &[String],
    chosen: f64,
) -> Result<()> {
    // α = 0 cannot sit on a log axis: draw it a decade left of the smallest α swept.
    let smallest = sweep
        .iter()
        .map(|s| s.0)
        .filter(|a| *a > 0.0)
        .fold(f64::INFINITY, f64::min);
    // The prior alone (α = ∞) is drawn a decade right of the largest α swept.
    let largest = sweep.iter().map(|s| s.0).fold(0.0f64, f64::max);
    let x = |a: f64| match a {
        f64::INFINITY => largest * 10.0,
        a if a > 0.0 => a,
        _ => smallest / 10.0,
    };
    let mut series = vec![Series {
        name: "train".into(),
        points: sweep.iter().map(|s| (x(s.0), 100.0 * s.1)).collect(),
        markers: true,
        line: true,
    }];
    for (c, clip) in test_names.iter().enumerate() {
        series.push(Series {
            name: format!("test {clip}"),
            points: sweep.iter().map(|s| (x(s.0), 100.0 * s.2[c])).collect(),
            markers: true,
            line: true,
        });
    }
    let (lo, hi) = series
        .iter()
        .flat_map(|s| s.points.iter().map(|p| p.1))
        .fold((f64::INFINITY, 0.0f64), |(a, b), y| (a.min(y), b.max(y)));
    series.push(Series {
        name: format!("LOSO choice α = {chosen:.2e}"),
        points: vec![(x(chosen), lo), (x(chosen), hi)],
        markers: false,
        line: true,
    });
    // Unregularised fits can extrapolate by orders of magnitude: then only a log axis shows
    // the curves near the chosen α.
    let log_y = lo > 0.0 && hi / lo > 50.0;
    line_plot(
        path,
        &Axes {
            title: &format!("{title}: error against α"),
            x: if chosen == f64::INFINITY {
                "α (leftmost point: α = 0; the choice at the right: α = ∞)"
            } else {
                "α (leftmost point: α = 0)"
            },
            y: "relative transfer error, %",
            log_x: true,
            log_y,
        },
        &series,
    )
}

fn residual_plots(hist_path: &Path, cdf_path: &Path, title: &str, residuals: &[f64]) -> Result<()> {
    let mut sorted = residuals.to_vec();
    sorted.sort_by(f64::total_cmp);
    let n = sorted.len().max(1);
    let top = sorted[(n - 1) * 99 / 100].max(1e-12); // the 99th percentile bounds the plot
    const BINS: usize = 60;
    let mut counts = [0usize; BINS];
    for r in &sorted {
        let bin = ((r / top) * BINS as f64) as usize;
        if bin < BINS {
            counts[bin] += 1;
        }
    }
    let width = top / BINS as f64;
    line_plot(
        hist_path,
        &Axes {
            title: &format!("{title}: residual distribution"),
            x: "per-vertex residual / RMS transfer norm",
            y: "density",
            log_x: false,
            log_y: false,
        },
        &[Series {
            name: format!("{} vertex-frames", sorted.len()),
            points: counts
                .iter()
                .enumerate()
                .map(|(b, &c)| ((b as f64 + 0.5) * width, c as f64 / (n as f64 * width)))
                .collect(),
            markers: false,
            line: true,
        }],
    )?;
    let step = (n / 400).max(1);
    line_plot(
        cdf_path,
        &Axes {
            title: &format!("{title}: residual CDF"),
            x: "per-vertex residual / RMS transfer norm",
            y: "fraction of vertex-frames ≤ x",
            log_x: false,
            log_y: false,
        },
        &[Series {
            name: format!(
                "median {:.3}, 90th percentile {:.3}",
                sorted[(n - 1) / 2],
                sorted[(n - 1) * 9 / 10]
            ),
            points: sorted
                .iter()
                .enumerate()
                .step_by(step)
                .filter(|(_, r)| **r <= top)
                .map(|(i, r)| (*r, (i + 1) as f64 / n as f64))
                .collect(),
            markers: false,
            line: true,
        }],
    )
}

/// Where the real assets are: `$APRT_ASSETS`, else `../shared/assets` (the repository's
/// neighbour, as CI has it).
pub fn default_assets() -> PathBuf {
    std::env::var_os("APRT_ASSETS").map_or_else(|| PathBuf::from("../shared/assets"), PathBuf::from)
}

/// Rate the studies sample clips at: the paper's 30 Hz animation rate.
const STUDY_FPS: f64 = 30.0;

/// The studies of the results document over the assets in `assets`: every glTF character
/// (train on one clip and test on the others, or on the rest of a single clip) and the CMU
/// motion capture driving a mannequin (train on subject 01's clip, test on its later frames
/// and on another subject's walk, retargeted by joint name).
pub fn asset_studies(assets: &Path) -> Result<Vec<Study>> {
    let gltf = assets.join("gltf");
    let bvh = assets.join("bvh");
    let mut studies = Vec::new();
    for (file, title) in [
        ("CesiumMan.gltf", "CesiumMan (glTF)"),
        ("RiggedFigure.glb", "RiggedFigure (glb)"),
        ("RiggedSimple.gltf", "RiggedSimple (glTF)"),
    ] {
        let rig = GltfRig::load(&gltf.join(file), STUDY_FPS)?;
        let name = rig.clip_names()[0].clone();
        let frames = rig.clip(&name)?.frames;
        let count = frames.len();
        let (train, test) = split_clip(&name, frames, 2.0 / 3.0);
        studies.push(Study {
            id: file.split('.').next().unwrap_or(file).to_lowercase(),
            title: title.into(),
            about: format!(
                "Khronos sample `{file}`, its only animation sampled at {STUDY_FPS} fps ({count} frames): the first two thirds train, the last third tests."
            ),
            up: rig.up(),
            rig: Box::new(rig),
            train,
            tests: vec![test],
        });
    }
    let fox = GltfRig::load(&gltf.join("Fox.gltf"), STUDY_FPS)?;
    let clip =
        |name: &str| -> Result<NamedFrames> { Ok((name.to_owned(), fox.clip(name)?.frames)) };
    let (train, tests) = (clip("Survey")?, vec![clip("Walk")?, clip("Run")?]);
    studies.push(Study {
        id: "fox".into(),
        title: "Fox (glTF)".into(),
        about: format!(
            "Khronos sample `Fox.gltf` (no normals in the file: flat normals are computed), sampled at {STUDY_FPS} fps: trained on `Survey`, tested on `Walk` and `Run`."
        ),
        up: fox.up(),
        rig: Box::new(fox),
        train,
        tests,
    });

    let options = MocapOptions {
        fps: Some(STUDY_FPS),
        ..MocapOptions::default()
    };
    let subject = MocapRig::from_file(&bvh.join("cmu_01_01.bvh"), &options)?;
    let walk = Mocap::read(&bvh.join("cmu_walk_delfem2.bvh"))?;
    let train = subject.clip_range(0..1200)?.frames;
    let later = subject.clip_range(1200..1800)?.frames;
    let retargeted = subject
        .retarget(&walk, "cmu_walk_delfem2", 0..walk.frame_count())?
        .clip
        .frames;
    studies.push(Study {
        id: "cmu".into(),
        title: "CMU motion capture on a mannequin (BVH)".into(),
        about: format!(
            "A mannequin built from the skeleton of CMU subject 01 (`cmu_01_01.bvh`, with the hat), resampled from 120 to {STUDY_FPS} fps: trained on file frames 0..1200, tested on frames 1200..1800 and on another subject's walk (`cmu_walk_delfem2.bvh`) retargeted by joint name."
        ),
        up: Vec3::Z,
        rig: Box::new(subject),
        train: ("cmu_01_01 [0, 1200)".into(), train),
        tests: vec![
            ("cmu_01_01 [1200, 1800)".into(), later),
            ("cmu_walk_delfem2".into(), retargeted),
        ],
    });
    Ok(studies)
}

/// Runs every study and writes `out/README.md` with their sections; returns its path.
/// Progress goes to `reporter`.
pub fn write_document(
    studies: &[Study],
    settings: &ResultsSettings,
    out: &Path,
    command: &str,
    reporter: &dyn Reporter,
) -> Result<PathBuf> {
    std::fs::create_dir_all(out).with_context(|| format!("cannot create {}", out.display()))?;
    let mut doc = String::new();
    let _ = writeln!(
        doc,
        "# aprt results on real characters and motion capture\n\nRegenerate with `{command}`. SH order {}, {} rays per vertex, bone-frame models unless the row says otherwise.\n\n{TABLE_LEGEND}\n\n{SAMPLED_LEGEND} N is {SAMPLE_POSES} in every study, the count issue 29 measured on a 240-frame walk: one count for all, so the sampled poses outnumber a short training clip's own frames several times over and about match a long one's (each study says its training frames).\n",
        settings.bake.order, settings.bake.rays
    );
    for study in studies {
        doc.push_str(&run_study(study, settings, out, reporter)?);
    }
    let path = out.join("README.md");
    write_atomic(&path, doc.as_bytes())
        .with_context(|| format!("cannot write {}", path.display()))?;
    Ok(path)
}
