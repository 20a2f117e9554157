//! Renders the built-in character for a visual check: the bind pose from four sides, frames
//! of every clip, and the smooth skinning weights of a few joints.
//!
//! `cargo run -p aprt-trainer --example character_preview [OUT_DIR]` (default
//! `/tmp/aprt-character`).

use std::path::PathBuf;

use aprt_trainer::{
    Character, Colormap, Mesh, Rig, View, lambert, render_scalar, save_png_atomic, side_by_side,
};
use glam::Vec3;

const SIZE: (u32, u32) = (320, 400);

fn shaded(mesh: &Mesh, view: View) -> anyhow::Result<image::RgbImage> {
    // Key light from the front, upper left of the character (its left is +x).
    let light = Vec3::new(0.5, -0.8, 0.9);
    let values: Vec<f32> = lambert(mesh, light)
        .into_iter()
        .map(|v| 0.1 + 0.9 * v)
        .collect();
    Ok(render_scalar(
        mesh,
        &values,
        view,
        SIZE.0,
        SIZE.1,
        Colormap::Grey,
    )?)
}

fn main() -> anyhow::Result<()> {
    let out = PathBuf::from(
        std::env::args()
            .nth(1)
            .unwrap_or_else(|| "/tmp/aprt-character".into()),
    );
    std::fs::create_dir_all(&out)?;
    let character = Character::builtin();
    println!(
        "{} vertices, {} triangles, {} joint angles",
        character.bind_mesh().vertex_count(),
        character.bind_mesh().triangles.len(),
        character.pose_len()
    );
    let front = View {
        yaw: 0.0,
        pitch: 0.15,
    };
    let three_quarter = View {
        yaw: 0.8,
        pitch: 0.25,
    };

    let bind = character.bind_mesh();
    let views = [
        front,
        View {
            yaw: std::f32::consts::FRAC_PI_2,
            pitch: 0.1,
        },
        View {
            yaw: 2.6,
            pitch: 0.3,
        },
        View {
            yaw: 0.3,
            pitch: 1.2,
        },
    ];
    let panels = views
        .iter()
        .map(|&v| shaded(bind, v))
        .collect::<anyhow::Result<Vec<_>>>()?;
    save_png_atomic(&out.join("bind.png"), &side_by_side(&panels))?;

    for clip in std::iter::once(character.training_clip()).chain(character.novel_clips()) {
        let n = clip.frames.len();
        let mut panels = Vec::new();
        for f in [0, n / 4, n / 2, 3 * n / 4, n - 1] {
            let mesh = character.pose(&clip.frames[f])?;
            panels.push(shaded(
                &mesh,
                match clip.name.as_str() {
                    // Side-on shows the stride; front-on shows the waving forearm.
                    "walk" | "reach" => View {
                        yaw: 1.2,
                        pitch: 0.15,
                    },
                    "wave" => front,
                    _ => three_quarter,
                },
            )?);
        }
        save_png_atomic(
            &out.join(format!("{}.png", clip.name)),
            &side_by_side(&panels),
        )?;
    }

    let names = character.angle_names();
    let joint_weight = |joint: u32| -> Vec<f32> {
        (0..bind.vertex_count())
            .map(|v| {
                character
                    .skin()
                    .influences(v)
                    .filter(|&(j, _)| j == joint)
                    .map(|(_, w)| w)
                    .sum()
            })
            .collect()
    };
    // Joint indices follow the skeleton: 2 chest, 6 left elbow, 12 left knee, 3 neck.
    let panels = [2, 6, 12, 3]
        .into_iter()
        .map(|j| {
            render_scalar(
                bind,
                &joint_weight(j),
                three_quarter,
                SIZE.0,
                SIZE.1,
                Colormap::Error { max: 1.0 },
            )
        })
        .collect::<Result<Vec<_>, _>>()?;
    save_png_atomic(&out.join("weights.png"), &side_by_side(&panels))?;

    // Bent elbows and knees near their limits, to look for collapse at the joints.
    let mut bent = character.rest_pose();
    for (name, value) in [
        ("l_elbow_flex", 2.0),
        ("r_elbow_flex", 1.2),
        ("l_knee_flex", 1.8),
        ("r_hip_flex", 1.2),
        ("r_knee_flex", 1.0),
        ("neck_flex", 0.5),
    ] {
        let i = names
            .iter()
            .position(|n| *n == name)
            .ok_or_else(|| anyhow::anyhow!("no angle {name}"))?;
        bent[i] = value;
    }
    let mesh = character.pose(&bent)?;
    let panels = [
        View {
            yaw: 1.4,
            pitch: 0.1,
        },
        three_quarter,
        View {
            yaw: -1.4,
            pitch: 0.1,
        },
    ]
    .into_iter()
    .map(|v| shaded(&mesh, v))
    .collect::<anyhow::Result<Vec<_>>>()?;
    save_png_atomic(&out.join("bent.png"), &side_by_side(&panels))?;
    println!("wrote pictures to {}", out.display());
    Ok(())
}
