//! Pose-driven light maps: the linear model of the pose-driven paper fitted with texels in
//! place of vertices. The training clip's light maps are baked, the filled texels become the
//! model's rows, and the blob records which texel each row is ([`aprt_core::TexelAtlas`]), so
//! a novel pose gets its light map from a model of a few megabytes instead of a stored
//! sequence. Rows are in the character's world (root) frame: a texel has no single bone.

use anyhow::{Context, Result, bail};
use nalgebra::DMatrix;

use super::bake::{BakedMaps, CheckpointSettings, bake_light_maps};
use super::codec::MapSequence;
use super::layout::AtlasSpec;
use crate::bake::BakeSettings;
use crate::io::source::joined;
use crate::model::export::{Extras, Precision, TexelAtlasExtra, encode_model_with};
use crate::model::fit::{FitOptions, FitReport, fit};
use crate::model::runtime::{BlobInfo, describe};
use crate::progress::Reporter;
use crate::rig::pose_layout::PoseLayout;
use crate::rig::{Clip, Rig};

/// What a pose-driven light-map model is trained with.
pub struct LightMapTraining<'a> {
    /// The atlas the maps are baked on.
    pub atlas: AtlasSpec,
    /// How each frame's texels are baked.
    pub bake: BakeSettings,
    /// The model's shape and regularisation.
    pub fit: &'a FitOptions,
    /// Precision of the blob's large sections.
    pub precision: Precision,
    /// Where the bake keeps its finished frames.
    pub checkpoint: CheckpointSettings<'a>,
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
    let BakedMaps {
        sequence, seconds, ..
    } = bake_light_maps(
        rig,
        what,
        &clip,
        training.atlas,
        &training.bake,
        &training.checkpoint,
        reporter,
    )?;
    let start = std::time::Instant::now();
    let (rows, transfers) = filled_rows(&sequence);
    let angles: Vec<Vec<f64>> = clip.frames.iter().map(|p| layout.reduce(p)).collect();
    let a = DMatrix::from_fn(angles.len(), layout.names().len(), |i, j| angles[i][j]);
    let mut fitted = fit(&a, &transfers, training.bake.order, training.fit)?;
    fitted.model.angle_names = layout.names().to_vec();
    let fit_seconds = start.elapsed().as_secs_f64();
    let blob = encode_model_with(
        &fitted.model,
        training.precision,
        &Extras {
            irradiance_rig: None,
            texel_atlas: Some(TexelAtlasExtra {
                resolution: training.atlas.resolution as u32,
                texels: &rows,
                corner_uvs: sequence.layout.as_ref().map(|l| l.corners.as_slice()),
            }),
        },
    )?;
    Ok(TrainedLightMaps {
        info: describe(&blob)?,
        blob,
        report: fitted.report,
        frames: clip.frames.len(),
        seconds: (seconds, fit_seconds),
    })
}

/// The light maps (`resolution`² texels × n², texel-major, zero at unfilled texels) a
/// light-map model `blob` predicts for every frame of `clip` of `rig`, through aprt-core, with
/// the resolution and the SH order.
pub fn predict_maps(
    blob: &[u8],
    model_name: &str,
    rig: &dyn Rig,
    clip: &Clip,
) -> Result<(usize, usize, Vec<Vec<f32>>)> {
    let info = describe(blob).with_context(|| format!("{model_name}: invalid model"))?;
    let model = aprt_core::Model::parse(blob)?;
    let Some(atlas) = model.texel_atlas() else {
        bail!("{model_name} is not a light-map model (it has no texel atlas): use aprt eval");
    };
    let layout = PoseLayout::from_names(&rig.angle_names(), &info.angle_names)
        .with_context(|| format!("{model_name} does not fit this character"))?;
    let angles: Vec<Vec<f64>> = clip.frames.iter().map(|p| layout.reduce(p)).collect();
    let rows = crate::model::predict::predict_world(blob, &angles, &[], None)?;
    let texels = (0..atlas.rows())
        .map(|row| atlas.texel(row))
        .collect::<Result<Vec<u32>, _>>()?;
    let r = atlas.resolution() as usize;
    let n2 = info.order * info.order;
    let maps = rows.iter().map(|v| to_map(v, &texels, r, n2)).collect();
    Ok((r, info.order, maps))
}

/// A model's per-row output (`n2` values per row) scattered onto an `resolution`² map, zero at
/// texels no row stands for.
pub fn to_map(values: &[f32], texels: &[u32], resolution: usize, n2: usize) -> Vec<f32> {
    let mut map = vec![0.0f32; resolution * resolution * n2];
    for (&t, v) in texels.iter().zip(values.chunks_exact(n2)) {
        map[t as usize * n2..][..n2].copy_from_slice(v);
    }
    map
}

#[cfg(test)]
mod tests {
    use super::*;

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
        assert_eq!(to_map(&transfers[0], &rows, r, 1), expect);
        let two = to_map(&[1.0, 2.0, 3.0, 4.0], &[0, 2], r, 2);
        assert_eq!(&two[..6], &[1.0, 2.0, 0.0, 0.0, 3.0, 4.0]);
        assert!(two[6..].iter().all(|&v| v == 0.0));
    }
}
