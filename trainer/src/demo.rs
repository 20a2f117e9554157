//! `aprt demo`: the whole pipeline on the built-in character, with the paper's tables
//! (Tables 1 and 2) against three baselines, and pictures of a novel pose.

use std::fmt::Write as _;
use std::time::Instant;

use anyhow::{Context, Result};
use glam::Vec3;
use nalgebra::DMatrix;

use crate::atomic::write_atomic;
use crate::bake::{BakeSettings, bake_poses};
use crate::bone_frames::{bone_rotations, change_frame, dominant_bones, to_bone_frames};
use crate::character::Character;
use crate::cli::DemoArgs;
use crate::evaluate::{mean_transfer, nearest_pose, relative_error, skinned_transfer};
use crate::export::{Precision, encode_model};
use crate::fit::{Alpha, CoefDims, Dims, FitOptions, fit};
use crate::mesh::Mesh;
use crate::render::{Colormap, View, render_scalar, save_png_atomic, side_by_side};
use crate::rig::{Clip, Rig};
use crate::sh_rotate::row_major;
use aprt_core::rotate::ShRotation;
use aprt_core::{LitWeights, Model, PoseWeights, SliceSource};
use glam::DMat3;

/// One row of the report table.
#[derive(Debug, serde::Serialize)]
pub struct Row {
    /// Model or baseline name.
    pub name: String,
    /// Bytes the method needs at runtime.
    pub bytes: usize,
    /// `bytes` as a percentage of one frame of f32 PRT.
    pub percent_of_frame: f64,
    /// Relative transfer error on the training frames.
    pub train_error: f64,
    /// Relative transfer error per novel clip, in clip order.
    pub test_errors: Vec<f64>,
    /// Microseconds per frame through aprt-core: pose step, lighting, shading of every vertex.
    pub shade_us: Option<f64>,
    /// Microseconds per frame through aprt-core for the full per-vertex transfer.
    pub transfer_us: Option<f64>,
    /// Multiply-adds per frame to shade every vertex in RGB, in millions.
    pub megaops: Option<f64>,
    /// Seconds to fit (α selection, both PCAs, solve).
    pub fit_s: Option<f64>,
    /// k_a and k_v and α, for models.
    pub shape: Option<(usize, usize, f64)>,
}

/// Ground truth of one clip: its poses, meshes and baked transfer.
struct Baked {
    name: String,
    angles: Vec<Vec<f64>>,
    meshes: Vec<Mesh>,
    /// World-frame ground truth.
    transfer: Vec<Vec<f32>>,
    /// Per frame, every bone's world rotation.
    rotations: Vec<Vec<DMat3>>,
}

fn bake_clip(
    rig: &dyn Rig,
    clip: &Clip,
    stride: usize,
    settings: &BakeSettings,
) -> Result<(Baked, f64)> {
    let angles: Vec<Vec<f64>> = clip.frames.iter().step_by(stride.max(1)).cloned().collect();
    let meshes = angles
        .iter()
        .map(|a| rig.pose(a))
        .collect::<Result<Vec<_>, _>>()
        .with_context(|| format!("posing clip {}", clip.name))?;
    let start = Instant::now();
    let transfer = bake_poses(&meshes, settings, true)
        .with_context(|| format!("baking clip {}", clip.name))?;
    let per_frame = start.elapsed().as_secs_f64() / angles.len().max(1) as f64;
    eprintln!(
        "  {}: {} frames, {:.2} s/frame",
        clip.name,
        angles.len(),
        per_frame
    );
    let rotations = angles
        .iter()
        .map(|a| bone_rotations(rig, a))
        .collect::<Result<Vec<_>>>()?;
    Ok((
        Baked {
            name: clip.name.clone(),
            angles,
            meshes,
            transfer,
            rotations,
        },
        per_frame,
    ))
}

/// Median seconds of `f` over 31 calls (robust to a busy machine).
fn median_seconds(mut f: impl FnMut()) -> f64 {
    let mut samples: Vec<f64> = (0..31)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64()
        })
        .collect();
    samples.sort_by(f64::total_cmp);
    samples[15]
}

/// Per-frame cost through aprt-core on one pose: (shade µs, transfer µs).
fn time_core(
    blob: &[u8],
    angles: &[f64],
    rotations: &[[[f32; 3]; 3]],
    lighting: &[f32],
) -> Result<(f64, f64)> {
    let model = Model::parse(blob)?;
    let a: Vec<f32> = angles.iter().map(|&x| x as f32).collect();
    let mut pose = PoseWeights::default();
    let mut lit = LitWeights::default();
    let mut shading = vec![0.0f32; model.vertices()];
    let mut transfer = vec![0.0f32; model.vertices() * model.order() * model.order()];
    let mut src = SliceSource(blob);
    let mut result = Ok(());
    let shade = median_seconds(|| {
        result = result
            .and(model.set_pose(&mut src, &a, &mut [], &mut pose))
            .and(crate::runtime::light(
                &model, &pose, lighting, rotations, &mut lit,
            ))
            .and(model.shade(&mut src, &lit, 0, &mut shading, &mut []));
    });
    let full = median_seconds(|| {
        result = result
            .and(model.set_pose(&mut src, &a, &mut [], &mut pose))
            .and(model.transfer(&mut src, &pose, 0, &mut transfer, &mut []));
    });
    result?;
    Ok((shade * 1e6, full * 1e6))
}

/// Multiply-adds per frame for RGB shading of every vertex.
fn megaops(model: &Model) -> f64 {
    let (n2, ka, kv, v, a) = (
        (model.order() * model.order()) as f64,
        model.pose_dims() as f64,
        model.coef_dims() as f64,
        model.vertices() as f64,
        model.joints() as f64,
    );
    let ops = match model.basis() {
        aprt_core::blob::Basis::Stored => ka * a + n2 * (ka + 1.0) * kv + 3.0 * (n2 * kv + kv * v),
        aprt_core::blob::Basis::Identity => ka * a + 3.0 * n2 * (ka + 1.0) * (1.0 + v),
    };
    ops / 1e6
}

/// SH lighting of the pictures: a directional light (Hanning-windowed to tame ringing) and a
/// dim uniform sky, so shadowed regions stay readable.
pub fn demo_lighting(order: usize, to_light: Vec3) -> Vec<f32> {
    let mut l = vec![0.0f32; order * order];
    aprt_core::sh::project_directional(order, to_light.normalize().to_array(), 1.0, &mut l)
        .expect("valid order and direction");
    for (c, x) in l.iter_mut().enumerate() {
        let band = aprt_core::sh::band_of(c) as f32;
        *x *= 0.5 * (1.0 + (std::f32::consts::PI * band / order as f32).cos());
    }
    l[0] += 0.15 * (4.0 * std::f32::consts::PI).sqrt() / std::f32::consts::PI;
    l
}

/// Shading `Σ_c L_c t_c` per vertex (shown directly as grey: an albedo of π).
fn shade_with(transfer: &[f32], lighting: &[f32]) -> Vec<f32> {
    transfer
        .chunks_exact(lighting.len())
        .map(|t| t.iter().zip(lighting).map(|(a, b)| a * b).sum::<f32>())
        .collect()
}

/// Runs the demo.
pub fn run(args: &DemoArgs) -> Result<()> {
    let out = &args.out;
    std::fs::create_dir_all(out).with_context(|| format!("cannot create {}", out.display()))?;
    let order = args.order as usize;
    let n2 = order * order;
    let character = Character::builtin();
    let bind = character.bind_mesh();
    eprintln!(
        "aprt demo: built-in character, {} vertices, {} triangles, {} joint angles; order {order}, {} rays",
        bind.vertex_count(),
        bind.triangles.len(),
        character.joint_angle_count(),
        args.rays
    );
    let settings = BakeSettings {
        order,
        rays: args.rays,
        bounces: 0,
        albedo: 0.0,
    };
    let (train, bake_s) = bake_clip(
        &character,
        &character.training_clip(),
        args.stride,
        &settings,
    )?;
    let mut tests = Vec::new();
    for clip in character.novel_clips() {
        tests.push(bake_clip(&character, &clip, args.stride, &settings)?.0);
    }
    let angles = DMatrix::from_fn(train.angles.len(), character.joint_angle_count(), |i, j| {
        train.angles[i][j]
    });
    let frame_bytes = bind.vertex_count() * n2 * 4;
    let lighting = demo_lighting(order, Vec3::new(0.5, -0.8, 0.9));

    let bones = dominant_bones(&character);
    let rotation = ShRotation::new(order)?;
    let to_world = |set: &Baked, frame: usize, t: &[f32]| {
        change_frame(&rotation, t, &bones, &set.rotations[frame], false)
    };
    let train_local = to_bone_frames(&character, &train.angles, &train.transfer)?;
    let default = FitOptions::default();
    let configs: Vec<(&str, FitOptions, bool)> = vec![
        ("default: bone frame, LOSO α", default, true),
        (
            "default shape, LOO α",
            FitOptions {
                alpha: Alpha::Loo,
                ..default
            },
            true,
        ),
        ("default shape, world frame", default, false),
        (
            "full linear",
            FitOptions {
                pose_dims: Dims::All,
                coef_dims: CoefDims::Full,
                ..default
            },
            true,
        ),
        (
            "full linear, least squares (α = 0)",
            FitOptions {
                pose_dims: Dims::All,
                coef_dims: CoefDims::Full,
                alpha: Alpha::Fixed(0.0),
            },
            true,
        ),
        (
            "PCA(8, 22)",
            FitOptions {
                pose_dims: Dims::Count(8),
                coef_dims: CoefDims::Count(22),
                ..default
            },
            true,
        ),
        (
            "PCA(4, 12)",
            FitOptions {
                pose_dims: Dims::Count(4),
                coef_dims: CoefDims::Count(12),
                ..default
            },
            true,
        ),
    ];
    let f32_rotations = |set: &Baked, frame: usize| -> Vec<[[f32; 3]; 3]> {
        set.rotations[frame].iter().map(|r| row_major(*r)).collect()
    };
    let mut rows = Vec::new();
    let mut default_blob = Vec::new();
    for (i, (name, options, bone_frame)) in configs.iter().enumerate() {
        eprintln!("fitting {name}");
        let targets = if *bone_frame {
            &train_local
        } else {
            &train.transfer
        };
        let mut fitted =
            fit(&angles, targets, order, options).with_context(|| format!("fitting {name}"))?;
        if *bone_frame {
            fitted.model.bones = Some(bones.clone());
        }
        let s = &fitted.report.seconds;
        let fit_s =
            s.validate + s.pose_pca + s.vertex_basis + s.projection + s.cross_validation + s.solve;
        let blob = encode_model(&fitted.model, Precision::F32)
            .with_context(|| format!("writing {name}"))?;
        let model = Model::parse(&blob)?;
        // World-frame predictions through aprt-core.
        let predict = |set: &Baked| -> Result<Vec<Vec<f32>>> {
            let raw = crate::runtime::predict_transfer(&blob, &set.angles)?;
            Ok(if *bone_frame {
                raw.iter()
                    .enumerate()
                    .map(|(f, t)| to_world(set, f, t))
                    .collect()
            } else {
                raw
            })
        };
        let train_error = relative_error(&predict(&train)?, &train.transfer);
        let test_errors = tests
            .iter()
            .map(|t| Ok(relative_error(&predict(t)?, &t.transfer)))
            .collect::<Result<Vec<_>>>()?;
        let rotations = if *bone_frame {
            f32_rotations(&tests[0], 0)
        } else {
            Vec::new()
        };
        let (shade_us, transfer_us) = time_core(&blob, &tests[0].angles[0], &rotations, &lighting)?;
        rows.push(Row {
            name: (*name).into(),
            bytes: blob.len(),
            percent_of_frame: 100.0 * blob.len() as f64 / frame_bytes as f64,
            train_error,
            test_errors,
            shade_us: Some(shade_us),
            transfer_us: Some(transfer_us),
            megaops: Some(megaops(&model)),
            fit_s: Some(fit_s),
            shape: Some((model.pose_dims(), model.coef_dims(), fitted.model.alpha)),
        });
        if i == 0 {
            default_blob = blob;
        }
    }
    write_atomic(&out.join("model.aprt"), &default_blob)
        .with_context(|| format!("cannot write {}", out.join("model.aprt").display()))?;

    // Baselines.
    let mean = mean_transfer(&train.transfer);
    let mean_of = |set: &Baked| vec![mean.clone(); set.transfer.len()];
    let nearest_of = |set: &Baked| {
        set.angles
            .iter()
            .map(|a| train.transfer[nearest_pose(&train.angles, a)].clone())
            .collect::<Vec<_>>()
    };
    let bind_transfer = bake_poses(std::slice::from_ref(bind), &settings, false)?.remove(0);
    let skin = character.skin();
    let skinned_of = |set: &Baked| -> Result<Vec<Vec<f32>>> {
        set.angles
            .iter()
            .map(|a| {
                let matrices = character.joint_matrices(a)?;
                Ok(skinned_transfer(
                    &rotation,
                    &bind_transfer,
                    |j| skin.influences(j).collect(),
                    &matrices,
                ))
            })
            .collect()
    };
    let baseline =
        |name: &str, bytes: usize, train_pred: Vec<Vec<f32>>, test_preds: Vec<Vec<Vec<f32>>>| Row {
            name: name.into(),
            bytes,
            percent_of_frame: 100.0 * bytes as f64 / frame_bytes as f64,
            train_error: relative_error(&train_pred, &train.transfer),
            test_errors: test_preds
                .iter()
                .zip(&tests)
                .map(|(p, t)| relative_error(p, &t.transfer))
                .collect(),
            shade_us: None,
            transfer_us: None,
            megaops: None,
            fit_s: None,
            shape: None,
        };
    rows.push(baseline(
        "baseline: mean training transfer",
        frame_bytes,
        mean_of(&train),
        tests.iter().map(mean_of).collect(),
    ));
    rows.push(baseline(
        "baseline: nearest training pose",
        frame_bytes * train.transfer.len(),
        nearest_of(&train),
        tests.iter().map(nearest_of).collect(),
    ));
    rows.push(baseline(
        "baseline: bind transfer, skinned",
        frame_bytes,
        skinned_of(&train)?,
        tests.iter().map(skinned_of).collect::<Result<Vec<_>>>()?,
    ));

    // Pictures of one novel pose: ground truth | model | 4× error.
    let test = &tests[0];
    let frame = test.angles.len() / 2;
    let truth_shade = shade_with(&test.transfer[frame], &lighting);
    // The model's shading straight from the core's bone-frame shading path.
    let model_shade = crate::runtime::predict_shading(
        &default_blob,
        &test.angles[frame],
        &f32_rotations(test, frame),
        &lighting,
    )?;
    let error: Vec<f32> = truth_shade
        .iter()
        .zip(&model_shade)
        .map(|(a, b)| 4.0 * (a - b).abs())
        .collect();
    let mesh = &test.meshes[frame];
    let view = View {
        yaw: 0.5,
        pitch: 0.15,
    };
    let (w, h) = (360, 480);
    let panels = [
        render_scalar(mesh, &truth_shade, view, w, h, Colormap::Grey)?,
        render_scalar(mesh, &model_shade, view, w, h, Colormap::Grey)?,
        render_scalar(mesh, &error, view, w, h, Colormap::Error { max: 1.0 })?,
    ];
    let picture = out.join("novel_pose.png");
    save_png_atomic(&picture, &side_by_side(&panels))?;
    let mean_shade = shade_with(&mean, &lighting);
    let nearest_shade = shade_with(
        &train.transfer[nearest_pose(&train.angles, &test.angles[frame])],
        &lighting,
    );
    let baselines = [
        render_scalar(mesh, &truth_shade, view, w, h, Colormap::Grey)?,
        render_scalar(mesh, &mean_shade, view, w, h, Colormap::Grey)?,
        render_scalar(mesh, &nearest_shade, view, w, h, Colormap::Grey)?,
    ];
    save_png_atomic(&out.join("baselines.png"), &side_by_side(&baselines))?;

    let report = Report {
        character: format!(
            "built-in, {} vertices, {} joint angles",
            bind.vertex_count(),
            character.joint_angle_count()
        ),
        order,
        rays: args.rays,
        train_clip: train.name.clone(),
        train_frames: train.angles.len(),
        test_clips: tests
            .iter()
            .map(|t| (t.name.clone(), t.angles.len()))
            .collect(),
        bake_s_per_frame: bake_s,
        frame_prt_bytes: frame_bytes,
        rows,
    };
    write_atomic(
        &out.join("report.json"),
        serde_json::to_string_pretty(&report)?.as_bytes(),
    )?;
    let markdown = report.markdown(test, frame);
    write_atomic(&out.join("report.md"), markdown.as_bytes())?;
    print!("{markdown}");
    eprintln!(
        "wrote {}/{{model.aprt, report.md, report.json, novel_pose.png, baselines.png}}",
        out.display()
    );
    Ok(())
}

/// Everything the demo measured.
#[derive(Debug, serde::Serialize)]
pub struct Report {
    /// The character.
    pub character: String,
    /// SH order.
    pub order: usize,
    /// Rays per vertex of the ground truth.
    pub rays: usize,
    /// Training clip name.
    pub train_clip: String,
    /// Training frames.
    pub train_frames: usize,
    /// Novel clips and their frame counts.
    pub test_clips: Vec<(String, usize)>,
    /// Bake seconds per training frame (all cores).
    pub bake_s_per_frame: f64,
    /// Bytes of one frame of f32 PRT.
    pub frame_prt_bytes: usize,
    /// The table.
    pub rows: Vec<Row>,
}

impl Report {
    fn markdown(&self, test: &Baked, frame: usize) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "# aprt demo report\n");
        let _ = writeln!(
            s,
            "Character: {}. SH order {} ({} coefficients), {} rays per vertex. Trained on `{}` ({} frames); tested on {}.\n",
            self.character,
            self.order,
            self.order * self.order,
            self.rays,
            self.train_clip,
            self.train_frames,
            self.test_clips
                .iter()
                .map(|(n, f)| format!("`{n}` ({f} frames)"))
                .collect::<Vec<_>>()
                .join(", ")
        );
        let _ = writeln!(
            s,
            "Bake: {:.2} s per frame on all cores. One frame of f32 PRT is {} bytes.\n",
            self.bake_s_per_frame, self.frame_prt_bytes
        );
        let _ = writeln!(
            s,
            "Errors are relative transfer errors ‖pred − truth‖ / ‖truth‖ over all frames, vertices and coefficients. Times are one core through aprt-core; megaops count multiply-adds for RGB shading of every vertex.\n"
        );
        let tests: Vec<String> = self
            .test_clips
            .iter()
            .map(|(n, _)| format!("test `{n}`"))
            .collect();
        let _ = writeln!(
            s,
            "| method | k_a | k_v | α | bytes | % of frame | train err | {} | shade µs/frame | transfer µs/frame | megaops/frame | fit s |",
            tests.join(" | ")
        );
        let _ = writeln!(s, "|{}", "---|".repeat(11 + tests.len()));
        for r in &self.rows {
            let opt =
                |x: Option<f64>, digits: usize| x.map_or("–".into(), |x| format!("{x:.digits$}"));
            let (ka, kv, alpha) = r
                .shape
                .map_or(("–".into(), "–".into(), "–".into()), |(a, v, al)| {
                    (a.to_string(), v.to_string(), format!("{al:.3e}"))
                });
            let _ = writeln!(
                s,
                "| {} | {ka} | {kv} | {alpha} | {} | {:.1} | {:.2}% | {} | {} | {} | {} | {} |",
                r.name,
                r.bytes,
                r.percent_of_frame,
                100.0 * r.train_error,
                r.test_errors
                    .iter()
                    .map(|e| format!("{:.2}%", 100.0 * e))
                    .collect::<Vec<_>>()
                    .join(" | "),
                opt(r.shade_us, 0),
                opt(r.transfer_us, 0),
                opt(r.megaops, 2),
                opt(r.fit_s, 2),
            );
        }
        let _ = writeln!(
            s,
            "\n## A novel pose\n\nFrame {frame} of `{}` under a directional light and a dim sky: ground truth | default model (through aprt-core) | 4× absolute error.\n",
            test.name
        );
        let _ = writeln!(s, "![ground truth, model, 4x error](novel_pose.png)\n");
        let _ = writeln!(
            s,
            "The same pose: ground truth | mean training transfer | nearest training pose.\n"
        );
        let _ = writeln!(
            s,
            "![ground truth, mean baseline, nearest-pose baseline](baselines.png)"
        );
        s
    }
}
