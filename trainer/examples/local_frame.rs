//! Experiment: fit in the skinned local frame vs the global frame.
use aprt_trainer::evaluate::relative_error;
use aprt_trainer::sh_rotate::{ShRotator, nearest_rotation};
use aprt_trainer::*;
use glam::DMat3;
use nalgebra::DMatrix;

fn main() {
    let ch = Character::builtin();
    let order = 4;
    let n2 = 16;
    let settings = BakeSettings { order, rays: 128, bounces: 0, albedo: 0.0 };
    let stride = 5;
    let rot = ShRotator::new(order);
    let skin = ch.skin();
    let prep = |clip: &Clip| {
        let angles: Vec<Vec<f64>> = clip.frames.iter().step_by(stride).cloned().collect();
        let meshes: Vec<Mesh> = angles.iter().map(|a| ch.pose(a).unwrap()).collect();
        let t = bake_poses(&meshes, &settings, false).unwrap();
        (angles, t)
    };
    let to_local = |angles: &[f64], t: &[f32], inverse: bool| -> Vec<f32> {
        let m = ch.joint_matrices(angles).unwrap();
        let mut out = vec![0.0f32; t.len()];
        for j in 0..t.len() / n2 {
            let mut blend = DMat3::ZERO;
            for (b, w) in skin.influences(j) {
                blend += DMat3::from_mat4(m[b as usize].as_dmat4()) * w as f64;
            }
            let r = nearest_rotation(blend);
            let r = if inverse { r.transpose() } else { r };
            rot.rotate(r, &t[j * n2..(j + 1) * n2], &mut out[j * n2..(j + 1) * n2]);
        }
        out
    };
    let (ta, tt) = prep(&ch.training_clip());
    let tests: Vec<_> = ch.novel_clips().iter().map(|c| prep(c)).collect();
    let local: Vec<Vec<f32>> = ta.iter().zip(&tt).map(|(a, t)| to_local(a, t, true)).collect();
    let angles = DMatrix::from_fn(ta.len(), ta[0].len(), |i, j| ta[i][j]);
    for (name, opts) in [
        ("default", FitOptions::default()),
        ("full", FitOptions { pose_dims: Dims::All, coef_dims: CoefDims::Full, ..FitOptions::default() }),
    ] {
        let g = fit(&angles, &tt, order, &opts).unwrap().model;
        let l = fit(&angles, &local, order, &opts).unwrap().model;
        let pred = |m: &LinearModel, a: &[f64], localf: bool| -> Vec<f32> {
            let p: Vec<f32> = m.predict(a).iter().map(|&x| x as f32).collect();
            if localf { to_local(a, &p, false) } else { p }
        };
        let err = |m: &LinearModel, set: &(Vec<Vec<f64>>, Vec<Vec<f32>>), localf: bool| {
            let p: Vec<Vec<f32>> = set.0.iter().map(|a| pred(m, a, localf)).collect();
            relative_error(&p, &set.1)
        };
        println!("{name} global: train {:.3} tests {:?}", err(&g, &(ta.clone(), tt.clone()), false), tests.iter().map(|s| err(&g, s, false)).collect::<Vec<_>>());
        println!("{name} local:  train {:.3} tests {:?} alpha {}", err(&l, &(ta.clone(), tt.clone()), true), tests.iter().map(|s| err(&l, s, true)).collect::<Vec<_>>(), l.alpha);
    }
}
