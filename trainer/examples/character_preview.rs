//! Renders a built-in character for a visual check: the bind pose from four sides, frames of
//! every clip, the smooth skinning weights of a few joints, and a pose bent near its limits.
//!
//! `cargo run -p aprt-trainer --example character_preview [human|creature] [OUT_DIR]`
//! (default the human, into `/tmp/aprt-character` or `/tmp/aprt-creature`).

use std::path::PathBuf;

use aprt_trainer::{
    Character, Colormap, Creature, Mesh, Rig, View, lambert, render_scalar, save_png_atomic,
    side_by_side,
};
use glam::Vec3;

/// What differs between the characters: the rig, the panel size, the view of each clip, the
/// joints whose weights are drawn, and the angles of the bent pose.
struct Preview {
    rig: Box<dyn Rig>,
    size: (u32, u32),
    clip_view: fn(&str) -> View,
    weight_joints: [u32; 4],
    bent: &'static [(&'static str, f64)],
}

const FRONT: View = View {
    yaw: 0.0,
    pitch: 0.15,
};
const THREE_QUARTER: View = View {
    yaw: 0.8,
    pitch: 0.25,
};

fn human() -> Preview {
    Preview {
        rig: Box::new(Character::builtin()),
        size: (320, 400),
        // Side-on shows the stride; front-on shows the waving forearm.
        clip_view: |clip| match clip {
            "walk" | "reach" => View {
                yaw: 1.2,
                pitch: 0.15,
            },
            "wave" => FRONT,
            _ => THREE_QUARTER,
        },
        // Joint indices follow the skeleton: 2 chest, 6 left elbow, 12 left knee, 3 neck.
        weight_joints: [2, 6, 12, 3],
        // Bent elbows and knees near their limits, to look for collapse at the joints.
        bent: &[
            ("l_elbow_flex", 2.0),
            ("r_elbow_flex", 1.2),
            ("l_knee_flex", 1.8),
            ("r_hip_flex", 1.2),
            ("r_knee_flex", 1.0),
            ("neck_flex", 0.5),
        ],
    }
}

fn creature() -> Preview {
    Preview {
        rig: Box::new(Creature::builtin()),
        size: (480, 300),
        // From above the left flank, where the lash curls the tail.
        clip_view: |_| View {
            yaw: 0.7,
            pitch: 0.5,
        },
        // 0 pelvis, 2 chest, 8 the third tail joint, 13 the fore left knee.
        weight_joints: [0, 2, 8, 13],
        // A tail curled near its limits, a folded hind knee and a lowered neck.
        bent: &[
            ("tail_2_yaw", 0.6),
            ("tail_3_yaw", 0.6),
            ("tail_4_yaw", 0.6),
            ("tail_2_pitch", 0.3),
            ("hl_knee_bend", 1.4),
            ("fl_knee_bend", 1.0),
            ("neck_1_pitch", -0.6),
        ],
    }
}

fn shaded(mesh: &Mesh, view: View, size: (u32, u32)) -> anyhow::Result<image::RgbImage> {
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
        size.0,
        size.1,
        Colormap::Grey,
    )?)
}

fn main() -> anyhow::Result<()> {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let which = match args.first().map(String::as_str) {
        Some(name @ ("human" | "creature")) => {
            let name = name.to_owned();
            args.remove(0);
            name
        }
        _ => "human".to_owned(),
    };
    let preview = if which == "creature" {
        creature()
    } else {
        human()
    };
    let out = PathBuf::from(args.first().cloned().unwrap_or_else(|| {
        format!(
            "/tmp/aprt-{}",
            if which == "human" {
                "character"
            } else {
                "creature"
            }
        )
    }));
    std::fs::create_dir_all(&out)?;
    let rig = preview.rig.as_ref();
    let size = preview.size;
    let bind = rig.bind_mesh();
    println!(
        "{} vertices, {} triangles, {} joint angles",
        bind.vertex_count(),
        bind.triangles.len(),
        rig.angle_names().len()
    );
    let views = [
        FRONT,
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
        .map(|&v| shaded(bind, v, size))
        .collect::<anyhow::Result<Vec<_>>>()?;
    save_png_atomic(&out.join("bind.png"), &side_by_side(&panels))?;

    for name in rig.clip_names() {
        let clip = rig.clip(&name)?;
        let n = clip.frames.len();
        let mut panels = Vec::new();
        for f in [0, n / 4, n / 2, 3 * n / 4, n - 1] {
            let mesh = rig.pose(&clip.frames[f])?;
            panels.push(shaded(&mesh, (preview.clip_view)(&name), size)?);
        }
        save_png_atomic(&out.join(format!("{name}.png")), &side_by_side(&panels))?;
    }

    let joint_weight = |joint: u32| -> Vec<f32> {
        (0..bind.vertex_count())
            .map(|v| {
                rig.skin()
                    .influences(v)
                    .filter(|&(j, _)| j == joint)
                    .map(|(_, w)| w)
                    .sum()
            })
            .collect()
    };
    let panels = preview
        .weight_joints
        .into_iter()
        .map(|j| {
            render_scalar(
                bind,
                &joint_weight(j),
                THREE_QUARTER,
                size.0,
                size.1,
                Colormap::Error { max: 1.0 },
            )
        })
        .collect::<Result<Vec<_>, _>>()?;
    save_png_atomic(&out.join("weights.png"), &side_by_side(&panels))?;

    let names = rig.angle_names();
    let mut bent = rig.rest_pose();
    for &(name, value) in preview.bent {
        let i = names
            .iter()
            .position(|n| *n == name)
            .ok_or_else(|| anyhow::anyhow!("no angle {name}"))?;
        bent[i] = value;
    }
    let mesh = rig.pose(&bent)?;
    let panels = [
        View {
            yaw: 1.4,
            pitch: 0.1,
        },
        THREE_QUARTER,
        View {
            yaw: -1.4,
            pitch: 0.1,
        },
    ]
    .into_iter()
    .map(|v| shaded(&mesh, v, size))
    .collect::<anyhow::Result<Vec<_>>>()?;
    save_png_atomic(&out.join("bent.png"), &side_by_side(&panels))?;
    println!("wrote pictures to {}", out.display());
    Ok(())
}
