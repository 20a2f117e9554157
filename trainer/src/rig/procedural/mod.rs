//! What the built-in procedural characters share: the human of [`character`](super::character)
//! and the long-tailed creature of [`creature`](super::creature) are both a chain of joints
//! posed by named angles about fixed bind-space axes, covered by closed lathes
//! ([`crate::rig::lathe`]) with smooth weights, and both give scripted clips ([`clips`]).
//!
//! [`Articulated`] holds what a built-in character is once built (bind mesh, skin, joints,
//! angles, parts) and does the work of its [`Rig`](crate::rig::Rig) implementation, so each
//! character only lays out its joints, its surface and its clips.

pub(crate) mod clips;

use std::ops::Range;

use glam::{DMat4, DQuat, DVec3, Mat4};

use crate::rig::character::{CharacterError, JointAngle};
use crate::rig::lathe::Body;
use crate::rig::mesh::Mesh;
use crate::rig::skin::Skin;
use crate::rig::{Clip, RigError, check_pose};

/// One joint angle: a rotation of `joint` about a bind-space `axis` by `angle − rest`.
#[derive(Clone, Debug)]
pub(crate) struct Dof {
    pub name: &'static str,
    pub joint: usize,
    pub axis: DVec3,
    pub rest: f64,
    pub min: f64,
    pub max: f64,
}

/// A [`Dof`] about `axis` (normalised here).
pub(crate) fn dof(
    name: &'static str,
    joint: usize,
    axis: DVec3,
    rest: f64,
    min: f64,
    max: f64,
) -> Dof {
    Dof {
        name,
        joint,
        axis: axis.normalize(),
        rest,
        min,
        max,
    }
}

/// A built-in character once built: its bind mesh and skin, its joints (bind positions and
/// parents, parents before children), the angles that pose them, and its named parts.
#[derive(Clone, Debug)]
pub(crate) struct Articulated {
    pub bind: Mesh,
    pub skin: Skin,
    parents: Vec<Option<usize>>,
    joints: Vec<DVec3>,
    dofs: Vec<Dof>,
    pub angles: Vec<JointAngle>,
    pub parts: Vec<(&'static str, Range<usize>)>,
}

impl Articulated {
    /// Assembles the character from its joints (`parents[j]` precedes `j`), the angles that
    /// drive them, and its lathe surface with one name per part. Deterministic: the geometry
    /// is computed in f64 and rounded once to f32.
    pub fn new(
        parents: &[Option<usize>],
        joints: &[DVec3],
        dofs: Vec<Dof>,
        body: Body,
        names: Vec<&'static str>,
    ) -> Articulated {
        debug_assert!(
            parents
                .iter()
                .enumerate()
                .all(|(j, p)| p.is_none_or(|p| p < j))
        );
        let bind = Mesh::with_area_weighted_normals(body.positions, body.triangles);
        let skin = Skin::from_influences(&body.influences).unwrap_or_else(|e| {
            unreachable!("built-in weights are positive partitions of unity: {e}")
        });
        let angles = dofs
            .iter()
            .map(|d| JointAngle {
                name: d.name,
                rest: d.rest,
                min: d.min,
                max: d.max,
            })
            .collect();
        Articulated {
            bind,
            skin,
            parents: parents.to_vec(),
            joints: joints.to_vec(),
            dofs,
            angles,
            parts: names.into_iter().zip(body.parts).collect(),
        }
    }

    /// `(min, max)` of each joint angle, in pose order.
    pub fn limits(&self) -> Vec<(f64, f64)> {
        self.angles.iter().map(|a| (a.min, a.max)).collect()
    }

    /// The angles' names, in pose order.
    pub fn angle_names(&self) -> Vec<String> {
        self.angles.iter().map(|a| a.name.to_owned()).collect()
    }

    /// The bind pose's angles.
    pub fn rest_pose(&self) -> Vec<f64> {
        self.angles.iter().map(|a| a.rest).collect()
    }

    /// Skinning matrices for the angles `pose`, checked first (count, NaN).
    pub fn joint_matrices(&self, pose: &[f64]) -> Result<Vec<Mat4>, RigError> {
        check_pose(pose, self.angles.len(), |i| self.angles[i].name.to_owned())
            .map_err(CharacterError::Pose)?;
        Ok(joint_matrices(
            &self.parents,
            &self.joints,
            &self.dofs,
            pose,
        ))
    }
}

/// The clip called `name` among `clips`; the error lists every name.
pub(crate) fn find_clip(clips: Vec<Clip>, name: &str) -> Result<Clip, RigError> {
    let available = clips
        .iter()
        .map(|c| c.name.as_str())
        .collect::<Vec<_>>()
        .join(", ");
    clips.into_iter().find(|c| c.name == name).ok_or_else(|| {
        RigError::from(CharacterError::UnknownClip {
            name: name.into(),
            available,
        })
    })
}

/// Forward kinematics: one skinning matrix per joint, mapping bind-space positions to posed
/// ones. Within a joint, earlier angles are applied after later ones
/// (`R = R_first · R_second`). Computed in f64 and rounded once, so long chains (a tail) do
/// not accumulate f32 error. `angles` has one value per entry of `dofs` (checked by the
/// caller); parents precede their children.
fn joint_matrices(
    parents: &[Option<usize>],
    bind: &[DVec3],
    dofs: &[Dof],
    angles: &[f64],
) -> Vec<Mat4> {
    let mut local = vec![DQuat::IDENTITY; bind.len()];
    for (dof, &angle) in dofs.iter().zip(angles) {
        local[dof.joint] *= DQuat::from_axis_angle(dof.axis, angle - dof.rest);
    }
    let mut world_rot = vec![DQuat::IDENTITY; bind.len()];
    let mut world_pos = bind.to_vec();
    // Parents precede children in the joint table, so one pass suffices.
    for j in 0..bind.len() {
        match parents[j] {
            None => world_rot[j] = local[j],
            Some(p) => {
                world_rot[j] = world_rot[p] * local[j];
                world_pos[j] = world_pos[p] + world_rot[p] * (bind[j] - bind[p]);
            }
        }
    }
    (0..bind.len())
        .map(|j| {
            let m = DMat4::from_rotation_translation(world_rot[j], world_pos[j])
                * DMat4::from_translation(-bind[j]);
            m.as_mat4()
        })
        .collect()
}

/// Asserts that each of `parts` (name and triangle range of `mesh`) is closed and consistently
/// wound (each directed edge once, its reverse once), encloses a positive volume (faces
/// outward), and that together they cover every triangle.
#[cfg(test)]
pub(crate) fn assert_parts_closed_and_outward(
    mesh: &Mesh,
    parts: impl Iterator<Item = (&'static str, Range<usize>)>,
) {
    let mut covered = 0;
    for (name, range) in parts {
        let triangles = &mesh.triangles[range.clone()];
        let mut directed: std::collections::HashMap<(u32, u32), usize> = Default::default();
        for t in triangles {
            for k in 0..3 {
                *directed.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
            }
        }
        for (&(a, b), &count) in &directed {
            assert_eq!(count, 1, "{name}: edge {a}->{b} used {count} times");
            assert_eq!(
                directed.get(&(b, a)),
                Some(&1),
                "{name}: {a}->{b} has no twin"
            );
        }
        let volume: f64 = triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| glam::Vec3::from(mesh.positions[i as usize]).as_dvec3());
                a.dot(b.cross(c)) / 6.0
            })
            .sum();
        assert!(volume > 0.0, "{name}: signed volume {volume}");
        covered += range.len();
    }
    assert_eq!(covered, mesh.triangles.len());
}
