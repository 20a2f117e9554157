//! Renders a posed frame of two real glTF characters (CesiumMan, the Fox) beside their bind
//! pose, from the front and the side, for looking at: that limbs stay attached when posed is a
//! visual check, so it is an example, not a test.
//!
//! `cargo run -p aprt-trainer --release --example gltf_posed_frames [ASSETS_DIR]` (default
//! `$APRT_ASSETS`, else `../shared/assets`); writes `/tmp/aprt-gltf-<file>.png`.

use std::path::PathBuf;

use aprt_trainer::{GltfRig, Mesh, Rig, View, lambert, render_scalar};
use glam::Vec3;

fn main() {
    let dir = std::env::args()
        .nth(1)
        .or_else(|| std::env::var("APRT_ASSETS").ok())
        .map_or_else(|| PathBuf::from("../shared/assets"), PathBuf::from);
    for (file, clip, frame) in [
        ("CesiumMan.gltf", "animation0", 15),
        ("Fox.gltf", "Run", 10),
    ] {
        let rig = GltfRig::load(&dir.join("gltf").join(file), 30.0).unwrap();
        let up = rig.up();
        // The renderer is z-up: rotate the rig's up onto +z.
        let to_z = glam::Quat::from_rotation_arc(up, Vec3::Z);
        let turn = |mut m: Mesh| {
            for p in m.positions.iter_mut().chain(m.normals.iter_mut()) {
                *p = (to_z * Vec3::from(*p)).to_array();
            }
            m
        };
        let mut panels = Vec::new();
        let pose = &rig.clip(clip).unwrap().frames[frame];
        for mesh in [rig.bind_mesh().clone(), rig.pose(pose).unwrap()] {
            let mesh = turn(mesh);
            for yaw in [0.0f32, 1.57] {
                let view = View { yaw, pitch: 0.2 };
                let shade = lambert(&mesh, Vec3::new(0.3, -1.0, 0.8));
                panels.push(
                    render_scalar(&mesh, &shade, view, 256, 256, aprt_trainer::Colormap::Grey)
                        .unwrap(),
                );
            }
        }
        let out = PathBuf::from("/tmp").join(format!("aprt-gltf-{file}.png"));
        aprt_trainer::save_png_atomic(&out, &aprt_trainer::side_by_side(&panels)).unwrap();
        println!("wrote {}", out.display());
    }
}
