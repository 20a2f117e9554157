//! Pose-driven light maps: the linear model of the pose-driven paper fitted with texels in
//! place of vertices. The training clip's light maps are baked, the filled texels become the
//! model's rows, and the blob records which texel each row is ([`aprt_core::TexelAtlas`]), so
//! a novel pose gets its light map from a model of a few megabytes instead of a stored
//! sequence. As a per-vertex model's vertices, rows are learned in the frame of the bone that
//! drives their triangles most ([`dominant_texel_bones`]), so a limb's rigid motion rotates
//! its texels' transfer at runtime with no learning, or in the character's world (root) frame.
//! An irradiance rig, when asked for, is fitted over the surface the texels stand for, as
//! `aprt train --rig` fits one over the vertices, and stored in the blob.

use std::ops::Range;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use glam::DMat3;
use nalgebra::DMatrix;

use super::bake::{BakedMaps, CheckpointSettings, bake_light_maps};
use super::codec::MapSequence;
use super::layout::AtlasSpec;
use crate::bake::BakeSettings;
use crate::io::source::joined;
use crate::irradiance_rig::RigKind;
use crate::irradiance_rig::fit::{fit_irradiance_rig, rig_fitting_surfaces};
use crate::model::LinearModel;
use crate::model::ModelFrame;
use crate::model::export::{Extras, Precision, TexelAtlasExtra, encode_model_with};
use crate::model::fit::{FitOptions, FitReport, fit};
use crate::model::runtime::{BlobInfo, describe};
use crate::progress::Reporter;
use crate::rig::bone_frames::{FrameChange, all_rotations, change_frames, dominant_texel_bones};
use crate::rig::pose_layout::PoseLayout;
use crate::rig::uv::UvLayout;
use crate::rig::{Clip, Rig};

/// The model a light-map training fits: its shape, precision and frame.
#[derive(Clone, Copy)]
pub struct LightMapFit<'a> {
    /// The model's shape and regularisation.
    pub options: &'a FitOptions,
    /// Precision of the blob's large sections.
    pub precision: Precision,
    /// The frame rows are learned in: each texel's bone, or world space.
    pub frame: ModelFrame,
}

/// What a pose-driven light-map model is trained with.
pub struct LightMapTraining<'a> {
    /// The atlas the maps are baked on.
    pub atlas: AtlasSpec,
    /// How each frame's texels are baked.
    pub bake: BakeSettings,
    /// The model fitted to the maps.
    pub model: LightMapFit<'a>,
    /// Where the bake keeps its finished frames.
    pub checkpoint: CheckpointSettings<'a>,
    /// The irradiance rig to fit and store with the model, if any.
    pub irradiance_rig: Option<RigKind>,
}

/// A trained light-map model and what training measured.
pub struct TrainedLightMaps {
    /// The model blob.
    pub blob: Vec<u8>,
    /// The blob as `aprt inspect` describes it.
    pub info: BlobInfo,
    /// The fit's choices (prior, α, k_a, every candidate).
    pub report: FitReport,
    /// Training frames.
    pub frames: usize,
    /// Seconds the bake took and seconds the fit took.
    pub seconds: (f64, f64),
}

/// Each frame's transfer at the filled texels only (row-major over the atlas), the rows of the
/// model.
pub fn filled_rows(sequence: &MapSequence) -> (Vec<u32>, Vec<Vec<f32>>) {
    let n2 = sequence.order * sequence.order;
    let rows: Vec<u32> = sequence
        .filled
        .iter()
        .enumerate()
        .filter(|&(_, &f)| f)
        .map(|(t, _)| t as u32)
        .collect();
    let transfers = sequence
        .frames
        .iter()
        .map(|map| {
            rows.iter()
                .flat_map(|&t| &map[t as usize * n2..][..n2])
                .copied()
                .collect()
        })
        .collect();
    (rows, transfers)
}

/// Bakes the light maps of `clips` of `rig` (called `what` in errors) and fits the model to
/// them; the caller writes [`TrainedLightMaps::blob`].
pub fn train_light_maps(
    rig: &dyn Rig,
    what: &str,
    clips: Vec<Clip>,
    training: &LightMapTraining<'_>,
    reporter: &dyn Reporter,
) -> Result<TrainedLightMaps> {
    let clip = joined(clips);
    let layout = PoseLayout::from_training(&rig.angle_names(), &clip.frames)
        .with_context(|| format!("clip {}", clip.name))?;
    let baked = bake_light_maps(
        rig,
        what,
        &clip,
        training.atlas,
        &training.bake,
        &training.checkpoint,
        reporter,
    )?;
    let fitting = Instant::now();
    // The texels lie on the character's surface: the rig is fitted over it as for vertices.
    let rig_section = match training.irradiance_rig {
        Some(kind) => Some(fit_irradiance_rig(
            kind,
            &rig_fitting_surfaces(rig, std::slice::from_ref(&clip))?,
            training.bake.order,
        )?),
        None => None,
    };
    let rig_seconds = fitting.elapsed().as_secs_f64();
    let (blob, report, fit_seconds) = fit_light_maps_with_rig(
        rig,
        &layout,
        &clip,
        &baked,
        &training.model,
        rig_section.as_deref(),
    )?;
    Ok(TrainedLightMaps {
        info: describe(&blob)?,
        blob,
        report,
        frames: clip.frames.len(),
        seconds: (baked.seconds, rig_seconds + fit_seconds),
    })
}

/// Fits the light-map model to `baked`, the maps of every frame of `clip` of `rig`, on
/// `layout`'s pose entries ([`fit_light_map_model`]), and encodes it: the blob, the fit's
/// report and the seconds the fit took (with the frame change, without encoding).
pub fn fit_light_maps(
    rig: &dyn Rig,
    layout: &PoseLayout,
    clip: &Clip,
    baked: &BakedMaps,
    model: &LightMapFit<'_>,
) -> Result<(Vec<u8>, FitReport, f64)> {
    fit_light_maps_with_rig(rig, layout, clip, baked, model, None)
}

/// [`fit_light_maps`], storing the irradiance rig section `irradiance_rig` in the blob.
pub fn fit_light_maps_with_rig(
    rig: &dyn Rig,
    layout: &PoseLayout,
    clip: &Clip,
    baked: &BakedMaps,
    model: &LightMapFit<'_>,
    irradiance_rig: Option<&[u8]>,
) -> Result<(Vec<u8>, FitReport, f64)> {
    let start = Instant::now();
    let fitted = fit_light_map_model(rig, layout, clip, baked, model.options, model.frame)?;
    let seconds = start.elapsed().as_secs_f64();
    let blob = encode_light_map(&fitted, &baked.sequence, model.precision, irradiance_rig)?;
    Ok((blob, fitted.report, seconds))
}

/// A light-map model fitted and not yet encoded: the linear model and which texel each of its
/// rows is.
pub struct FittedLightMap {
    /// The model, its rows the filled texels.
    pub model: LinearModel,
    /// The texel index of each row, ascending.
    pub rows: Vec<u32>,
    /// The fit's choices.
    pub report: FitReport,
}

/// Fits the light-map model to `baked`, the maps of every frame of `clip` of `rig`, on
/// `layout`'s pose entries, with `options`, in `frame`. In bone frames each frame's rows are
/// moved into their texel's bone frame (by the bone's rotation in that frame) before the fit,
/// and the model records each row's bone as it does a vertex's.
pub fn fit_light_map_model(
    rig: &dyn Rig,
    layout: &PoseLayout,
    clip: &Clip,
    baked: &BakedMaps,
    options: &FitOptions,
    frame: ModelFrame,
) -> Result<FittedLightMap> {
    let sequence = &baked.sequence;
    let (rows, world) = filled_rows(sequence);
    let bones = (frame == ModelFrame::Bone)
        .then(|| dominant_texel_bones(rig.skin(), rig.bind_mesh(), &baked.atlas));
    let transfers = match &bones {
        Some(b) => {
            let rotations = all_rotations(rig, &clip.frames)?;
            change_frames(&world, &rotations, b, FrameChange::WorldToBone)?
        }
        None => world,
    };
    let angles: Vec<Vec<f64>> = clip.frames.iter().map(|p| layout.reduce(p)).collect();
    let a = DMatrix::from_fn(angles.len(), layout.names().len(), |i, j| angles[i][j]);
    let mut fitted = fit(&a, &transfers, sequence.order, options)?;
    fitted.model.angle_names = layout.names().to_vec();
    fitted.model.bones = bones;
    Ok(FittedLightMap {
        model: fitted.model,
        rows,
        report: fitted.report,
    })
}

/// `fitted` encoded in `precision` with the texel atlas of `sequence` (its resolution, the
/// rows' texels and any generated UVs) and the irradiance rig section `irradiance_rig`.
pub fn encode_light_map(
    fitted: &FittedLightMap,
    sequence: &MapSequence,
    precision: Precision,
    irradiance_rig: Option<&[u8]>,
) -> Result<Vec<u8>> {
    Ok(encode_model_with(
        &fitted.model,
        precision,
        &Extras {
            irradiance_rig,
            texel_atlas: Some(TexelAtlasExtra {
                resolution: sequence.resolution as u32,
                texels: &fitted.rows,
                corner_uvs: sequence.layout.as_ref().map(|l| l.corners.as_slice()),
            }),
        },
    )?)
}

/// The light-map UVs a light-map model `blob` (called `model_name`) records in its texel
/// atlas, when it was trained on generated UVs; `None` when its texels lie on the character's
/// texture UVs (or it has no texel atlas).
pub fn model_layout(blob: &[u8], model_name: &str) -> Result<Option<UvLayout>> {
    let model =
        aprt_core::Model::parse(blob).with_context(|| format!("{model_name}: invalid model"))?;
    let Some(atlas) = model.texel_atlas().filter(|a| a.triangles() > 0) else {
        return Ok(None);
    };
    let corners = (0..atlas.triangles())
        .map(|t| atlas.corner_uvs(t))
        .collect::<Result<_, _>>()?;
    Ok(Some(UvLayout { corners }))
}

/// A light-map model `blob` ready to predict the frames of a clip of `rig`: which texel each
/// row stands for, and each frame's pose vector and bone rotations.
pub struct ModelFrames<'b> {
    blob: &'b [u8],
    /// The texel index of each row, ascending.
    pub texels: Vec<usize>,
    /// The atlas is `resolution`² texels.
    pub resolution: usize,
    /// SH order n.
    pub order: usize,
    angles: Vec<Vec<f64>>,
    rotations: Vec<Vec<DMat3>>,
}

impl<'b> ModelFrames<'b> {
    /// Reads `blob` (called `model_name` in errors) for `clip` of `rig`: refused when it is not a
    /// light-map model or does not fit the character.
    pub fn new(blob: &'b [u8], model_name: &str, rig: &dyn Rig, clip: &Clip) -> Result<Self> {
        let info = describe(blob).with_context(|| format!("{model_name}: invalid model"))?;
        let model = aprt_core::Model::parse(blob)?;
        let Some(atlas) = model.texel_atlas() else {
            bail!("{model_name} is not a light-map model (it has no texel atlas): use aprt eval");
        };
        let layout = PoseLayout::from_names(&rig.angle_names(), &info.angle_names)
            .with_context(|| format!("{model_name} does not fit this character"))?;
        let texels = (0..atlas.rows())
            .map(|row| atlas.texel(row).map(|t| t as usize))
            .collect::<Result<Vec<usize>, _>>()?;
        Ok(ModelFrames {
            blob,
            texels,
            resolution: atlas.resolution() as usize,
            order: info.order,
            angles: clip.frames.iter().map(|p| layout.reduce(p)).collect(),
            rotations: all_rotations(rig, &clip.frames)?,
        })
    }

    /// Each of `frames`' rows (`n²` values per row, world frame), through aprt-core (a
    /// bone-frame model's rows turned by their bones' rotations in each frame).
    pub fn predict(&self, frames: Range<usize>) -> Result<Vec<Vec<f32>>> {
        let rotations = &self.rotations[frames.clone()];
        crate::model::predict::predict_world(self.blob, &self.angles[frames], rotations, None)
    }
}

/// The light maps (`resolution`² texels × n², texel-major, zero at unfilled texels) a
/// light-map model `blob` predicts for every frame of `clip` of `rig` ([`ModelFrames`]), with
/// the resolution and the SH order. Holds every frame's whole map: for a few frames.
pub fn predict_maps(
    blob: &[u8],
    model_name: &str,
    rig: &dyn Rig,
    clip: &Clip,
) -> Result<(usize, usize, Vec<Vec<f32>>)> {
    let model = ModelFrames::new(blob, model_name, rig, clip)?;
    let (r, n2) = (model.resolution, model.order * model.order);
    let maps = model
        .predict(0..clip.frames.len())?
        .iter()
        .map(|v| to_map(v, &model.texels, r, n2))
        .collect();
    Ok((r, model.order, maps))
}

/// A model's per-row output (`n2` values per row) scattered onto an `resolution`² map, zero at
/// texels no row stands for.
pub fn to_map(values: &[f32], texels: &[usize], resolution: usize, n2: usize) -> Vec<f32> {
    let mut map = vec![0.0f32; resolution * resolution * n2];
    for (&t, v) in texels.iter().zip(values.chunks_exact(n2)) {
        map[t * n2..][..n2].copy_from_slice(v);
    }
    map
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rig::bone_frames::bone_rotations;
    use crate::rig::character::Character;
    use crate::rig::uv::Atlas;

    /// Maps of the built-in character whose every texel's transfer rotates rigidly with its
    /// texel's bone: a clamped-cosine lobe about that bone's rotation of one fixed direction,
    /// in each of `clip`'s frames (computed from the lobe's axis, not by rotating SH).
    fn rigid_maps(rig: &Character, atlas: &Atlas, clip: &Clip, order: usize) -> Vec<Vec<f32>> {
        let bones = dominant_texel_bones(rig.skin(), rig.bind_mesh(), atlas);
        let filled = atlas.filled();
        let n2 = order * order;
        let axis = glam::DVec3::new(0.6, 0.0, 0.8);
        clip.frames
            .iter()
            .map(|pose| {
                let rotations = bone_rotations(rig, pose).unwrap();
                let mut map = vec![0.0f32; filled.len() * n2];
                let texels = filled.iter().enumerate().filter(|(_, f)| **f);
                for ((t, _), &b) in texels.zip(&bones.vertex_bone) {
                    let normal = (rotations[b as usize] * axis).as_vec3().to_array();
                    aprt_core::clamped_cosine(order, normal, &mut map[t * n2..][..n2]).unwrap();
                }
                map
            })
            .collect()
    }

    fn relative(a: &[Vec<f32>], b: &[Vec<f32>]) -> f64 {
        let d: f64 = a
            .iter()
            .flatten()
            .zip(b.iter().flatten())
            .map(|(x, y)| f64::from(x - y).powi(2))
            .sum();
        let n: f64 = b.iter().flatten().map(|y| f64::from(*y).powi(2)).sum();
        (d / n).sqrt()
    }

    /// Transfer that turns rigidly with each texel's bone is constant in bone frames: the
    /// bone-frame light-map model reproduces its training maps, and the maps of poses it was
    /// not trained on, through aprt-core; the world-frame model, linear in the angles, cannot.
    #[test]
    fn a_bone_frame_light_map_model_turns_texels_with_their_bones() {
        let rig = Character::builtin();
        let whole = rig.training_clip();
        let every = |start: usize| Clip {
            frames: whole
                .frames
                .iter()
                .skip(start)
                .step_by(7)
                .take(16)
                .cloned()
                .collect(),
            ..whole.clone()
        };
        let (clip, novel) = (every(0), every(3));
        let layout = PoseLayout::from_training(&rig.angle_names(), &clip.frames).unwrap();
        let order = 3;
        let atlas = Atlas::build(rig.uv_layout().unwrap(), &rig.bind_mesh().triangles, 24).unwrap();
        let baked = BakedMaps {
            sequence: MapSequence {
                resolution: atlas.resolution(),
                atlas: None,
                order,
                filled: atlas.filled(),
                positions: Vec::new(),
                layout: None,
                frames: rigid_maps(&rig, &atlas, &clip, order),
            },
            atlas,
            layout: rig.uv_layout().unwrap().clone(),
            seconds: 0.0,
        };
        let truth = rigid_maps(&rig, &baked.atlas, &novel, order);
        let mut errors = Vec::new();
        for frame in [ModelFrame::Bone, ModelFrame::World] {
            let model = LightMapFit {
                options: &FitOptions::default(),
                precision: Precision::F32,
                frame,
            };
            let (blob, _, _) = fit_light_maps(&rig, &layout, &clip, &baked, &model).unwrap();
            let bones = describe(&blob).unwrap().bones;
            assert_eq!(
                bones,
                usize::from(frame == ModelFrame::Bone) * rig.skin().joint_count()
            );
            let (_, _, trained) = predict_maps(&blob, "the model", &rig, &clip).unwrap();
            let (_, _, unseen) = predict_maps(&blob, "the model", &rig, &novel).unwrap();
            if frame == ModelFrame::Bone {
                shaded_by_the_core(&blob, &rig, &layout, &novel.frames[0], &truth[0]);
            }
            errors.push((
                relative(&trained, &baked.sequence.frames),
                relative(&unseen, &truth),
            ));
        }
        let (bone, world) = (errors[0], errors[1]);
        assert!(bone.0 < 1e-4 && bone.1 < 1e-4, "bone frames: {bone:?}");
        assert!(world.1 > 100.0 * bone.1, "world {world:?}, bone {bone:?}");
    }

    /// The core shades a bone-frame light-map model's rows as an engine does, with fixed
    /// buffers and the bones' rotations (the lighting turned into each bone's frame): at
    /// `pose` each row's shading is its texel's `truth` transfer under the lighting.
    fn shaded_by_the_core(
        blob: &[u8],
        rig: &Character,
        layout: &PoseLayout,
        pose: &[f64],
        truth: &[f32],
    ) {
        use aprt_core::{LitWeights, PoseWeights};
        let core = aprt_core::Model::parse(blob).unwrap();
        let angles: Vec<f32> = layout.reduce(pose).iter().map(|&a| a as f32).collect();
        let rotations: Vec<[[f32; 3]; 3]> = bone_rotations(rig, pose)
            .unwrap()
            .into_iter()
            .map(crate::rig::transfer_rotation::row_major)
            .collect();
        let n2 = core.info().coeffs();
        let lighting: Vec<f32> = (0..n2).map(|c| 1.0 / (1.0 + c as f32)).collect();
        let (mut weights, mut lit) = (PoseWeights::new(), LitWeights::new());
        core.set_pose(&angles, &mut weights).unwrap();
        core.light(&weights, &lighting, &rotations, &mut lit)
            .unwrap();
        let atlas = core.texel_atlas().unwrap();
        let mut shading = vec![0.0f32; atlas.rows()];
        core.shade(&lit, 0, &mut shading).unwrap();
        for (row, s) in shading.iter().enumerate() {
            let t = atlas.texel(row).unwrap() as usize;
            let expected: f32 = truth[t * n2..][..n2]
                .iter()
                .zip(&lighting)
                .map(|(a, b)| a * b)
                .sum();
            assert!((s - expected).abs() < 1e-3, "row {row}: {s} vs {expected}");
        }
    }

    /// The rows of a sequence are its filled texels in texel order, and scattering a frame's
    /// rows gives the frame back, zero where no texel is filled; with n² values per row each
    /// lands on its texel's slots.
    #[test]
    fn rows_are_the_filled_texels_and_scatter_back() {
        let r = 3;
        let filled = vec![false, true, true, false, false, true, false, false, true];
        let frame: Vec<f32> = (0..r * r).map(|t| t as f32).collect();
        let sequence = MapSequence {
            resolution: r,
            atlas: None,
            order: 1,
            filled: filled.clone(),
            positions: vec![[0.0; 3]; 4],
            layout: None,
            frames: vec![frame.clone()],
        };
        let (rows, transfers) = filled_rows(&sequence);
        assert_eq!(rows, vec![1, 2, 5, 8]);
        assert_eq!(transfers, vec![vec![1.0, 2.0, 5.0, 8.0]]);
        let expect: Vec<f32> = (0..r * r)
            .map(|t| if filled[t] { frame[t] } else { 0.0 })
            .collect();
        let texels: Vec<usize> = rows.iter().map(|&t| t as usize).collect();
        assert_eq!(to_map(&transfers[0], &texels, r, 1), expect);
        let two = to_map(&[1.0, 2.0, 3.0, 4.0], &[0, 2], r, 2);
        assert_eq!(&two[..6], &[1.0, 2.0, 0.0, 0.0, 3.0, 4.0]);
        assert!(two[6..].iter().all(|&v| v == 0.0));
    }
}
