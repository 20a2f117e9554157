//! Fitting-stage benchmark on the built-in character at the paper's scale: 250 training
//! poses, 23 joint angles, SH order 6 (36 coefficients), 13,022 vertices (Master Pai: 11.5k
//! vertices; fitting 73 s + PCA 324 s in the paper).
//!
//! The transfer is baked with 32 rays per vertex (not timed: the fit's cost does not depend on
//! the ray count) and expressed in each vertex's bone frame, as the demo fits it. Run with
//! `cargo bench -p aprt-trainer --bench fit`. The table prints seconds per stage, the energy
//! fraction the vertex basis captures, and the held-out error at the chosen α as a mean
//! squared error per transfer value.

use std::time::Instant;

use aprt_trainer::cli::Terminal;
use aprt_trainer::{
    Alpha, BakeSettings, Character, CoefDims, Dims, FitOptions, Rig, bake_poses, fit,
};
use nalgebra::DMatrix;

const ORDER: usize = 6;

fn main() {
    let clock = Instant::now();
    let character = Character::builtin();
    let clip = character.training_clip();
    let meshes: Vec<_> = clip
        .frames
        .iter()
        .map(|a| character.pose(a).expect("clip poses are valid"))
        .collect();
    let settings = BakeSettings {
        order: ORDER,
        rays: 32,
        bounces: 0,
        albedo: 0.0,
        shadows: true,
    };
    let world = bake_poses(&meshes, &settings, &Terminal).expect("the character bakes");
    let transfers = aprt_trainer::bone_frames::change_rig_frames(
        &character,
        &clip.frames,
        &world,
        aprt_trainer::bone_frames::FrameChange::WorldToBone,
    )
    .expect("clip poses are valid");
    let angles = DMatrix::from_fn(clip.frames.len(), character.pose_len(), |i, j| {
        clip.frames[i][j]
    });
    let vertices = character.bind_mesh().vertex_count();
    println!(
        "data: built-in character, {} poses × {} angles, order {ORDER}, {vertices} vertices ({:.1} s to bake, {} threads)",
        angles.nrows(),
        angles.ncols(),
        clock.elapsed().as_secs_f64(),
        rayon::current_num_threads()
    );
    let configs = [
        ("k_v=22, LOO", CoefDims::Count(22), Alpha::Loo),
        (
            "k_v=22, LOSO",
            CoefDims::Count(22),
            Alpha::Loso { segment: None },
        ),
        ("var 0.999, LOO", CoefDims::Variance(0.999), Alpha::Loo),
        (
            "var 0.999, LOSO",
            CoefDims::Variance(0.999),
            Alpha::Loso { segment: None },
        ),
        // The full model: 432 000 outputs per pose, where the p × p Gram keeps CV cheap.
        ("full, LOSO", CoefDims::Full, Alpha::Loso { segment: None }),
    ];
    println!(
        "{:<16} {:>4} {:>5} {:>9} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>10} {:>10}",
        "config",
        "k_a",
        "k_v",
        "captured",
        "pca s",
        "basis s",
        "proj s",
        "cv s",
        "solve s",
        "total s",
        "alpha",
        "cv mse/val"
    );
    for (name, coef_dims, alpha) in configs {
        let options = FitOptions {
            pose_dims: Dims::All,
            coef_dims,
            alpha,
            ..FitOptions::paper()
        };
        let clock = Instant::now();
        let fit = fit(&angles, &transfers, ORDER, &options).expect("baked data is valid");
        let total = clock.elapsed().as_secs_f64();
        let s = fit.report.seconds;
        let kv = fit.model.coef_dims();
        // Energy fraction of ‖R‖_F² the basis keeps (1 for the identity basis).
        let captured = match coef_dims {
            CoefDims::Full => 1.0,
            _ => fit.report.coef_energy[..kv].iter().sum::<f64>() / fit.report.coef_total_energy,
        };
        let best = fit
            .report
            .cv_curve
            .iter()
            .find(|c| c.alpha == fit.report.alpha);
        println!(
            "{:<16} {:>4} {:>5} {:>9.6} {:>8.3} {:>8.3} {:>8.3} {:>8.3} {:>8.3} {:>8.3} {:>10.3e} {:>10.3e}",
            name,
            fit.model.pose_dims(),
            fit.model.coef_dims(),
            captured,
            s.pose_pca,
            s.vertex_basis,
            s.projection,
            s.cross_validation,
            s.solve,
            total,
            fit.report.alpha,
            best.map_or(f64::NAN, |b| b.cv_error) * kv as f64 / vertices as f64,
        );
    }
}
