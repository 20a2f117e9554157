//! The default model on novel poses of the built-in character, at a reduced scale (order 2,
//! 32 rays, every 10th training frame) so it runs in seconds: it must beat the mean-transfer
//! and nearest-training-pose baselines by a wide margin, through the blob and aprt-core.

use aprt_trainer::bone_frames::{FrameChange, change_rig_frames, dominant_bones};
use aprt_trainer::evaluate::{mean_transfer, nearest_pose, relative_error};
use aprt_trainer::runtime::predict_transfer;
use aprt_trainer::{
    BakeSettings, Character, FitOptions, Precision, Rig, Silent, bake_poses, encode_model, fit,
};
use nalgebra::DMatrix;

#[test]
fn default_model_beats_mean_and_nearest_baselines_on_novel_poses() {
    let character = Character::builtin();
    let settings = BakeSettings {
        order: 2,
        rays: 32,
        bounces: 0,
        albedo: 0.0,
        shadows: true,
    };
    let bake = |frames: &[Vec<f64>]| {
        let meshes: Vec<_> = frames.iter().map(|a| character.pose(a).unwrap()).collect();
        bake_poses(&meshes, &settings, &Silent).unwrap()
    };
    let train: Vec<Vec<f64>> = character
        .training_clip()
        .frames
        .into_iter()
        .step_by(10)
        .collect();
    let test: Vec<Vec<f64>> = character
        .clip("wave")
        .unwrap()
        .frames
        .into_iter()
        .step_by(6)
        .collect();
    let (train_truth, test_truth) = (bake(&train), bake(&test));

    let angles = DMatrix::from_fn(train.len(), train[0].len(), |i, j| train[i][j]);
    let local =
        change_rig_frames(&character, &train, &train_truth, FrameChange::WorldToBone).unwrap();
    let mut fitted = fit(&angles, &local, settings.order, &FitOptions::default()).unwrap();
    fitted.model.bones = Some(dominant_bones(&character));
    let blob = encode_model(&fitted.model, Precision::F32).unwrap();
    let predicted = change_rig_frames(
        &character,
        &test,
        &predict_transfer(&blob, &test).unwrap(),
        FrameChange::BoneToWorld,
    )
    .unwrap();
    let model_error = relative_error(&predicted, &test_truth);

    let mean = mean_transfer(&train_truth);
    let mean_error = relative_error(&vec![mean; test.len()], &test_truth);
    let nearest: Vec<Vec<f32>> = test
        .iter()
        .map(|a| train_truth[nearest_pose(&train, a)].clone())
        .collect();
    let nearest_error = relative_error(&nearest, &test_truth);
    eprintln!(
        "novel `wave` poses: model {model_error:.3}, mean {mean_error:.3}, nearest {nearest_error:.3}"
    );
    assert!(
        model_error < 0.7 * mean_error.min(nearest_error),
        "model {model_error:.3}, mean {mean_error:.3}, nearest {nearest_error:.3}"
    );
}
