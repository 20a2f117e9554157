//! What occluder proxies cost per frame against the shading they correct, on the demo's
//! character: the built-in human (13,022 vertices) with the proxies the trainer fits to it and
//! a model of the demo's shape (order 4, k_v 22, bone frames), in the `wave` pose whose raised
//! arm meets the hat. Shading (pose, lighting, every vertex) and the proxies (posing them,
//! subtracting their occlusion from every vertex) run in interleaved batches; the ratio is the
//! median of per-round ratios. One core. The same again with the portable kernels alone
//! (`use_portable_kernels`), which every target without AVX2 runs.
//! `cargo bench -p aprt-tests --bench proxies`.

use std::hint::black_box;
use std::time::Duration;

use aprt_core::{
    LitWeights, Model, PoseWeights, ProxyFrame, project_directional, use_portable_kernels,
};
use aprt_tests::{interleaved_seconds, median_ratio, random_model};
use aprt_trainer::bone_frames::{bone_rotations, dominant_bones};
use aprt_trainer::model::occluders::{DEFAULT_CULL, rig_section, skinning_of};
use aprt_trainer::rig::transfer_rotation::row_major;
use aprt_trainer::{Character, Precision, Rig, encode_model};

fn main() {
    let rig = Character::builtin();
    let bones = dominant_bones(&rig);
    let cull = std::env::var("APRT_CULL")
        .ok()
        .and_then(|c| c.parse().ok())
        .unwrap_or(DEFAULT_CULL);
    let (section, fit) = rig_section(&rig, &bones, cull)
        .expect("fitted")
        .expect("the demo's character has proxies");
    let v = rig.bind_mesh().vertex_count();
    let mut model = random_model(4, v, rig.angle_names().len(), 4, Some(22));
    model.bones = Some(bones);
    model.proxies = Some(section);
    let blob = encode_model(&model, Precision::F32).expect("a valid model");
    let core = Model::parse(&blob).expect("it reads");
    let info = *core.info();

    let clip = rig.clip("wave").expect("the wave clip");
    let pose = &clip.frames[clip.frames.len() / 2];
    let mesh = rig.pose(pose).expect("posed");
    let skinning: Vec<_> = rig
        .joint_matrices(pose)
        .expect("joints")
        .iter()
        .map(skinning_of)
        .collect();
    let rotations: Vec<_> = bone_rotations(&rig, pose)
        .expect("rotations")
        .into_iter()
        .map(row_major)
        .collect();
    let angles = vec![0.1f32; info.pose_len()];
    let mut sky = [0.0f32; 16];
    project_directional(4, [0.3, -0.4, 0.9], 3.0, &mut sky).expect("a light");
    sky[0] += 1.0;

    let (mut weights, mut lit) = (Box::new(PoseWeights::new()), Box::new(LitWeights::new()));
    let mut frame = Box::new(ProxyFrame::new());
    let mut shading = vec![0.0f32; v];
    let mut shade = || {
        core.set_pose(&angles, &mut weights).unwrap();
        core.light(&weights, &sky, &rotations, &mut lit).unwrap();
        core.shade(&lit, 0, &mut shading).unwrap();
        black_box(&shading);
    };
    let mut occluded = vec![0.0f32; v];
    let mut proxies = || {
        core.pose_proxies(&skinning, &mut frame).unwrap();
        core.occlude(
            &frame,
            &sky,
            &mesh.positions,
            &mesh.normals,
            0,
            &mut occluded,
        )
        .unwrap();
        black_box(&occluded);
    };
    let mut measure = || {
        let times =
            interleaved_seconds(Duration::from_secs(4), 15, &mut [&mut shade, &mut proxies]);
        let median = |t: &[f64]| {
            let mut t = t.to_vec();
            t.sort_by(f64::total_cmp);
            t[t.len() / 2] * 1e6
        };
        format!(
            "shading {:.1} µs/frame, proxies {:.1} µs/frame: proxies / shading = {:.2}x",
            median(&times[0]),
            median(&times[1]),
            median_ratio(&times[1], &times[0])
        )
    };
    let dispatched = measure();
    use_portable_kernels(true);
    let portable = measure();
    use_portable_kernels(false);
    let contacts: u32 = (0..info.bones()).map(|b| frame.candidates(b)).sum();
    let mut vertex_bones = vec![0u16; v];
    core.vertex_bones(0, &mut vertex_bones).unwrap();
    let tests: u32 = vertex_bones
        .iter()
        .map(|&b| frame.candidates(usize::from(b)))
        .sum();
    let mut one = vec![0.0f32; 1];
    let touched = (0..v)
        .filter(|&j| {
            one[0] = 0.0;
            let (p, n) = (&mesh.positions[j..j + 1], &mesh.normals[j..j + 1]);
            core.occlude(&frame, &sky, p, n, j, &mut one).unwrap();
            one[0] != 0.0
        })
        .count();
    println!("{tests} vertex-proxy tests a frame; {touched} vertices occluded");
    println!(
        "built-in human, {v} vertices, {} bones, {} proxies culled below sin²α = {cull} ({} proxy-bone pairs in reach in `wave`)",
        info.bones(),
        fit.proxies.len(),
        contacts
    );
    println!("{dispatched}");
    println!("portable kernels: {portable}");
}
