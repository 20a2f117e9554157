//! The BVH reader and mannequin on the real CMU motion capture in `shared/assets/bvh`.

use crate::common;

use std::path::{Path, PathBuf};
use std::time::Instant;

use aprt_trainer::{
    Mocap, MocapOptions, MocapRig, Rig, View, lambert, render_scalar, save_png_atomic,
};
use glam::{DQuat, Vec3};

fn walk(dir: &Path) -> PathBuf {
    dir.join("bvh/cmu_walk_delfem2.bvh")
}

fn subject_01(dir: &Path) -> PathBuf {
    dir.join("bvh/cmu_01_01.bvh")
}

#[test]
fn cmu_files_parse_quickly_with_the_documented_shape() {
    let Some(dir) = common::assets("cmu_files_parse_quickly_with_the_documented_shape") else {
        return;
    };
    for (path, frames) in [(walk(&dir), 344), (subject_01(&dir), 2752)] {
        let start = Instant::now();
        let mocap = Mocap::read(&path).unwrap();
        let elapsed = start.elapsed();
        eprintln!("{}: parsed in {elapsed:?}", path.display());
        assert_eq!(mocap.joints().len(), 31);
        assert_eq!(mocap.frame_count(), frames);
        assert!((mocap.fps() - 120.0).abs() < 0.01, "{} fps", mocap.fps());
        assert_eq!(
            mocap
                .joints()
                .iter()
                .map(|j| j.channels.len())
                .sum::<usize>(),
            96
        );
        assert_eq!(
            mocap
                .joints()
                .iter()
                .map(|j| j.end_sites.len())
                .sum::<usize>(),
            7
        );
        if !cfg!(debug_assertions) {
            assert!(elapsed.as_secs_f64() < 0.5, "parsing took {elapsed:?}");
        }
    }
}

#[test]
fn mannequin_is_a_sound_smoothly_skinned_mesh() {
    let Some(dir) = common::assets("mannequin_is_a_sound_smoothly_skinned_mesh") else {
        return;
    };
    let rig = MocapRig::from_file(&walk(&dir), &MocapOptions::default()).unwrap();
    let mesh = rig.bind_mesh();
    let v = mesh.vertex_count();
    eprintln!(
        "walk mannequin: {v} vertices, {} triangles, height {:.2}",
        mesh.triangles.len(),
        rig.height()
    );
    assert!((5_000..=15_000).contains(&v), "{v} vertices");
    assert!(
        (20.0..40.0).contains(&rig.height()),
        "height {}",
        rig.height()
    );
    for (p, n) in mesh.positions.iter().zip(&mesh.normals) {
        assert!(p.iter().all(|c| c.is_finite()));
        assert!((Vec3::from(*n).length() - 1.0).abs() < 1e-5);
    }
    let skin = rig.skin();
    let mut blended = 0;
    for v in 0..skin.vertex_count() {
        let sum: f32 = skin.influences(v).map(|(_, w)| w).sum();
        assert!((sum - 1.0).abs() < 1e-5);
        blended += usize::from(skin.influences(v).filter(|&(_, w)| w >= 0.2).count() >= 2);
    }
    let share = blended as f64 / v as f64;
    eprintln!("{share:.3} of vertices blend two joints at >= 0.2");
    assert!(share > 0.1, "only {share:.3} blend");
    // Every part is closed and consistently wound (each directed edge once, its twin once).
    for (name, range) in rig.parts() {
        let mut edges = std::collections::HashMap::new();
        for t in &mesh.triangles[range] {
            for k in 0..3 {
                *edges.entry((t[k], t[(k + 1) % 3])).or_insert(0) += 1;
            }
        }
        for (&(a, b), &n) in &edges {
            assert!(
                n == 1 && edges.get(&(b, a)) == Some(&1),
                "{name}: edge {a}->{b}"
            );
        }
    }
    // No part around a zero-length bone (LHipJoint, LeftShoulder, ... sit on their parent).
    assert!(rig.parts().all(|(name, _)| !name.starts_with("Hips-")));
    // Deterministic.
    let again = MocapRig::from_file(&walk(&dir), &MocapOptions::default()).unwrap();
    assert_eq!(again.bind_mesh(), mesh);
    assert_eq!(again.skin(), skin);
}

#[test]
fn pose_vectors_reproduce_forward_kinematics_from_the_raw_channels() {
    let Some(dir) =
        common::assets("pose_vectors_reproduce_forward_kinematics_from_the_raw_channels")
    else {
        return;
    };
    let to_mesh = DQuat::from_rotation_x(std::f64::consts::FRAC_PI_2);
    for root_translation in [false, true] {
        let options = MocapOptions {
            root_translation,
            ..MocapOptions::default()
        };
        let rig = MocapRig::from_file(&walk(&dir), &options).unwrap();
        let mocap = rig.mocap();
        let rest = mocap.rest_positions();
        let names = rig.angle_names();
        assert_eq!(names.len(), 3 * 31 + if root_translation { 3 } else { 0 });
        assert_eq!(names[names.len() - 3], "RThumb.x");
        for f in [0, 100, 343] {
            let world = mocap.world_transforms(mocap.frame(f));
            let matrices = rig.joint_matrices(&rig.frame_pose(f)).unwrap();
            for j in 0..31 {
                let posed = matrices[j]
                    .transform_point3((to_mesh * rest[j]).as_vec3())
                    .as_dvec3();
                let mut expected = to_mesh * world[j].translation;
                if !root_translation {
                    // Without root translation the root stays at its rest position.
                    expected -= to_mesh * (world[0].translation - rest[0]);
                }
                assert!(
                    posed.distance(expected) < 1e-3,
                    "frame {f} joint {j}: {posed} vs {expected}"
                );
                // Rotations too: the posed frame of each joint.
                let m = glam::DMat3::from_mat4(matrices[j].as_dmat4());
                let r = glam::DMat3::from_quat(to_mesh)
                    * world[j].matrix3
                    * glam::DMat3::from_quat(to_mesh.inverse());
                assert!(m.abs_diff_eq(r, 1e-5), "frame {f} joint {j}");
            }
        }
    }
}

#[test]
fn clips_cover_frame_ranges_resample_and_report_bad_ranges() {
    let Some(dir) = common::assets("clips_cover_frame_ranges_resample_and_report_bad_ranges")
    else {
        return;
    };
    let rig = MocapRig::from_file(&walk(&dir), &MocapOptions::default()).unwrap();
    assert_eq!(rig.clip_names(), ["cmu_walk_delfem2"]);
    let full = rig.clip("cmu_walk_delfem2").unwrap();
    assert_eq!((full.frames.len(), full.fps.round()), (344, 120.0));
    let err = rig.clip_range(300..400).unwrap_err().to_string();
    assert_eq!(
        err,
        "frames 300..400 of \"cmu_walk_delfem2\": the motion has 344 frames (0..344)"
    );
    assert!(rig.clip_range(5..5).is_err());
    let part = rig.clip_range(10..20).unwrap();
    assert!(
        part.frames == full.frames[10..20],
        "a range is a slice of the clip"
    );

    let thirty = MocapRig::from_file(
        &walk(&dir),
        &MocapOptions {
            fps: Some(30.0),
            ..MocapOptions::default()
        },
    )
    .unwrap();
    let sub = thirty.clip("cmu_walk_delfem2").unwrap();
    assert_eq!(sub.fps, 30.0);
    assert_eq!(sub.frames.len(), 86, "frames 0, 4, ..., 340");
    for (k, frame) in sub.frames.iter().enumerate() {
        assert!(
            frame == &full.frames[4 * k],
            "30 fps frame {k} is 120 fps frame {}",
            4 * k
        );
    }
}

#[test]
fn motion_retargets_between_cmu_subjects_by_joint_name() {
    let Some(dir) = common::assets("motion_retargets_between_cmu_subjects_by_joint_name") else {
        return;
    };
    let rig = MocapRig::from_file(&subject_01(&dir), &MocapOptions::default()).unwrap();
    let walk = Mocap::read(&walk(&dir)).unwrap();
    let moved = rig.retarget(&walk, "walk", 0..walk.frame_count()).unwrap();
    assert_eq!(moved.missing, ["LFingers", "RFingers"]);
    assert_eq!(moved.extra, ["LeftHandIndex1", "RightHandIndex1"]);
    assert_eq!(moved.clip.frames.len(), 344);
    assert_eq!(moved.clip.frames[0].len(), rig.angle_names().len());
    // Shared joints carry the source's rotations exactly.
    let names = rig.angle_names();
    let knee = names.iter().position(|n| n == "LeftLeg.x").unwrap();
    let own = MocapRig::from_file(
        &dir.join("bvh/cmu_walk_delfem2.bvh"),
        &MocapOptions::default(),
    )
    .unwrap();
    let own_knee = own
        .angle_names()
        .iter()
        .position(|n| n == "LeftLeg.x")
        .unwrap();
    let walk_clip = own.clip("cmu_walk_delfem2").unwrap();
    for (a, b) in moved.clip.frames.iter().zip(&walk_clip.frames) {
        assert_eq!(a[knee..knee + 3], b[own_knee..own_knee + 3]);
    }
    rig.pose(&moved.clip.frames[200]).unwrap();
}

/// Renders the bind pose and a mid-walk frame to PNGs in the temporary directory for a person
/// to look at; asserts only that the mannequin fills a good part of each picture.
#[test]
fn mannequin_renders_in_bind_pose_and_mid_walk() {
    let Some(dir) = common::assets("mannequin_renders_in_bind_pose_and_mid_walk") else {
        return;
    };
    let rig = MocapRig::from_file(&walk(&dir), &MocapOptions::default()).unwrap();
    let mid = rig.clip("cmu_walk_delfem2").unwrap().frames[172].clone();
    let light = Vec3::new(0.4, -1.0, 0.8);
    for (name, mesh) in [
        ("bind", rig.bind_mesh().clone()),
        ("mid", rig.pose(&mid).unwrap()),
    ] {
        for (view_name, view) in [
            (
                "front",
                View {
                    yaw: 0.0,
                    pitch: 0.1,
                },
            ),
            (
                "side",
                View {
                    yaw: std::f32::consts::FRAC_PI_2,
                    pitch: 0.1,
                },
            ),
        ] {
            let image = render_scalar(
                &mesh,
                &lambert(&mesh, light),
                view,
                320,
                400,
                aprt_trainer::Colormap::Grey,
            )
            .unwrap();
            let filled = image.pixels().filter(|p| p.0 != [24, 24, 28]).count();
            assert!(
                filled > 320 * 400 / 20,
                "{name} {view_name}: {filled} pixels"
            );
            let path = std::env::temp_dir().join(format!("aprt-bvh-{name}-{view_name}.png"));
            save_png_atomic(&path, &image).unwrap();
        }
    }
}
