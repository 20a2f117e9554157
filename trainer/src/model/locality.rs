//! Which pose entries can change the shadowing at each vertex, from the rig alone.
//!
//! In its bone's frame a vertex's transfer changes only when geometry near it moves relative
//! to that bone. So a vertex depends on entry `i` when some bone with geometry within
//! `radius` of it (in the bind pose or any sampled pose) moves relative to the vertex's own
//! bone when `i` changes. Turning the root moves every bone alike and affects no vertex; a
//! shoulder affects the arm and the torso beside it, not the feet.

use std::collections::{BTreeMap, HashMap};

use anyhow::Result;
use glam::{DMat4, Vec3};
use rayon::prelude::*;

use crate::model::fit::{EntryGroup, Locality};
use crate::rig::Rig;
use crate::rig::bone_frames::dominant_bones;
use crate::rig::mesh::Mesh;
use crate::rig::pose_layout::PoseLayout;

/// The step each entry is turned by to see which bones it moves (radians).
const PROBE_STEP: f64 = 0.3;
/// Relative motion below this (matrix entries, translation in units of the diagonal) is none.
const MOTION_TOLERANCE: f64 = 1e-6;

/// Bitset over bones.
type Bones = Vec<u64>;

fn set(bits: &mut Bones, bone: usize) {
    bits[bone / 64] |= 1 << (bone % 64);
}

fn meets(a: &Bones, b: &Bones) -> bool {
    a.iter().zip(b).any(|(x, y)| x & y != 0)
}

/// The bind mesh's bounding-box diagonal: the unit of the locality radius.
pub fn diagonal(mesh: &Mesh) -> f64 {
    let (lo, hi) = mesh.positions.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(Vec3::from(*p)), hi.max(Vec3::from(*p))),
    );
    f64::from((hi - lo).length()).max(f64::MIN_POSITIVE)
}

/// For every vertex, the bones with geometry within `radius` of it in any of `meshes`:
/// each vertex is geometry of every bone that moves it (`vertex_bones`, its skin's
/// influences), so a vertex blended between two bones moves relative to its own bone when
/// the other turns.
fn near_bones(meshes: &[&Mesh], vertex_bones: &[Bones], bones: usize, radius: f32) -> Vec<Bones> {
    let words = bones.div_ceil(64);
    let cell = |p: [f32; 3]| p.map(|x| (x / radius).floor() as i32);
    let mut near = vec![vec![0u64; words]; vertex_bones.len()];
    for mesh in meshes {
        // A grid of cells one radius wide: every point within the radius is in the 27 cells
        // around a vertex's own. Each cell knows its bones, so cells with none new are skipped.
        let mut grid: HashMap<[i32; 3], (Bones, Vec<u32>)> = HashMap::new();
        for (j, p) in mesh.positions.iter().enumerate() {
            let entry = grid
                .entry(cell(*p))
                .or_insert_with(|| (vec![0; words], Vec::new()));
            entry
                .0
                .iter_mut()
                .zip(&vertex_bones[j])
                .for_each(|(cell, b)| *cell |= b);
            entry.1.push(j as u32);
        }
        near.par_iter_mut().enumerate().for_each(|(j, found)| {
            let p = Vec3::from(mesh.positions[j]);
            let c = cell(mesh.positions[j]);
            for dx in -1..=1 {
                for dy in -1..=1 {
                    for dz in -1..=1 {
                        let Some((cell_bones, points)) =
                            grid.get(&[c[0] + dx, c[1] + dy, c[2] + dz])
                        else {
                            continue;
                        };
                        if cell_bones
                            .iter()
                            .zip(found.iter())
                            .all(|(b, f)| b & !f == 0)
                        {
                            continue;
                        }
                        for &u in points {
                            let moved_by = &vertex_bones[u as usize];
                            let new = moved_by.iter().zip(found.iter()).any(|(b, f)| b & !f != 0);
                            if new && Vec3::from(mesh.positions[u as usize]).distance(p) <= radius {
                                found.iter_mut().zip(moved_by).for_each(|(f, b)| *f |= b);
                            }
                        }
                    }
                }
            }
        });
    }
    near
}

/// For each kept entry and bone b, the bones that move relative to b when the entry turns
/// (from the rest pose).
fn relative_motion(rig: &dyn Rig, layout: &PoseLayout, scale: f64) -> Result<Vec<Vec<Bones>>> {
    let rest = rig.rest_pose();
    let before: Vec<DMat4> = rig
        .joint_matrices(&rest)?
        .iter()
        .map(|m| m.as_dmat4())
        .collect();
    let bones = before.len();
    let words = bones.div_ceil(64);
    layout
        .indices()
        .iter()
        .map(|&entry| {
            let mut turned = rest.clone();
            turned[entry] += PROBE_STEP;
            let motion: Vec<[f64; 16]> = rig
                .joint_matrices(&turned)?
                .iter()
                .zip(&before)
                .map(|(after, before)| {
                    let mut m = (after.as_dmat4() * before.inverse()).to_cols_array();
                    m[12..15].iter_mut().for_each(|t| *t /= scale);
                    m
                })
                .collect();
            Ok((0..bones)
                .map(|b| {
                    let mut moved = vec![0; words];
                    for (other, m) in motion.iter().enumerate() {
                        let differs = m
                            .iter()
                            .zip(&motion[b])
                            .any(|(x, y)| (x - y).abs() > MOTION_TOLERANCE);
                        if differs {
                            set(&mut moved, other);
                        }
                    }
                    moved
                })
                .collect())
        })
        .collect()
}

/// The vertices of `rig` grouped by the entries of `layout` their transfer may depend on:
/// those that move a bone with geometry within `radius` (a fraction of the bind mesh's
/// diagonal) of the vertex, in the bind pose or any of `poses`, relative to its own bone.
pub fn locality(
    rig: &dyn Rig,
    layout: &PoseLayout,
    poses: &[&Mesh],
    radius: f64,
) -> Result<Locality> {
    let bind = rig.bind_mesh();
    let scale = diagonal(bind);
    let frames = dominant_bones(rig);
    let mut meshes = vec![bind];
    meshes.extend_from_slice(poses);
    let skin = rig.skin();
    let words = frames.count.div_ceil(64);
    let vertex_bones: Vec<Bones> = (0..frames.vertex_bone.len())
        .map(|j| {
            let mut bits = vec![0; words];
            set(&mut bits, usize::from(frames.vertex_bone[j]));
            for (bone, weight) in skin.influences(j) {
                if weight > 0.0 && (bone as usize) < frames.count {
                    set(&mut bits, bone as usize);
                }
            }
            bits
        })
        .collect();
    let near = near_bones(
        &meshes,
        &vertex_bones,
        frames.count,
        (radius * scale) as f32,
    );
    let motion = relative_motion(rig, layout, scale)?;
    let mut groups: BTreeMap<Vec<usize>, Vec<usize>> = BTreeMap::new();
    for (j, near) in near.iter().enumerate() {
        let bone = usize::from(frames.vertex_bone[j]);
        let entries = (0..motion.len())
            .filter(|&i| meets(&motion[i][bone], near))
            .collect();
        groups.entry(entries).or_default().push(j);
    }
    Ok(Locality {
        groups: groups
            .into_iter()
            .map(|(entries, vertices)| EntryGroup { entries, vertices })
            .collect(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rig::character::Character;

    #[test]
    fn the_built_in_characters_groups_follow_its_geometry() {
        let character = Character::builtin();
        let training = character.training_clip();
        let layout = PoseLayout::from_training(&character.angle_names(), &training.frames).unwrap();
        let groups = locality(&character, &layout, &[], 0.1).unwrap().groups;
        // A partition of the vertices.
        let mut seen: Vec<usize> = groups.iter().flat_map(|g| g.vertices.clone()).collect();
        seen.sort_unstable();
        let vertices = character.bind_mesh().vertex_count();
        assert_eq!(seen, (0..vertices).collect::<Vec<_>>());
        let entry = |name: &str| layout.names().iter().position(|n| n == name).unwrap();
        let entries_of = |j: usize| {
            &groups
                .iter()
                .find(|g| g.vertices.contains(&j))
                .unwrap()
                .entries
        };
        let positions = &character.bind_mesh().positions;
        // The character's right is −x: the right fingertips, and the lowest point (a sole).
        let hand = (0..vertices)
            .min_by(|&a, &b| positions[a][0].total_cmp(&positions[b][0]))
            .unwrap();
        let sole = (0..vertices)
            .min_by(|&a, &b| positions[a][2].total_cmp(&positions[b][2]))
            .unwrap();
        assert!(!entries_of(sole).contains(&entry("r_elbow_flex")));
        assert!(!entries_of(sole).contains(&entry("neck_twist")));
        assert!(!entries_of(hand).contains(&entry("l_knee_flex")));
        // The hand's bone is the wrist's child: only joints near the hand can shadow it, and
        // the wrist is one of them.
        assert!(entries_of(hand).contains(&entry("r_wrist_flex")));
        assert!(entries_of(hand).len() < layout.names().len() / 2);
    }
}
