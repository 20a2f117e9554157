//! The joints of a built-in character: where they are in the bind pose, the named angles that
//! turn them, and the forward kinematics that turns a pose into skinning matrices.

use glam::{DMat4, DQuat, DVec3, Mat4};

/// Bind-pose joint positions and parents, parents before children. Each character places its
/// joints with [`Skeleton::set`], so the table is filled in one way for both.
// Nominally `pub` (the module is crate-private) because [`super::Spec`] names it.
#[derive(Clone, Debug)]
pub struct Skeleton {
    pub parents: Vec<Option<usize>>,
    pub bind: Vec<DVec3>,
}

impl Skeleton {
    /// `count` joints, all at the origin without a parent until [`Skeleton::set`] places them.
    pub fn with_joints(count: usize) -> Skeleton {
        Skeleton {
            parents: vec![None; count],
            bind: vec![DVec3::ZERO; count],
        }
    }

    /// Places joint `j` at bind position `p`, under `parent`.
    pub fn set(&mut self, j: usize, parent: Option<usize>, p: DVec3) {
        self.bind[j] = p;
        self.parents[j] = parent;
    }
}

/// One joint angle: a rotation of `joint` about a bind-space `axis` by `angle − rest`.
// Nominally `pub` (the module is crate-private) because [`super::Spec`] names it.
#[derive(Clone, Debug)]
pub struct Dof {
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

/// Forward kinematics: one skinning matrix per joint, mapping bind-space positions to posed
/// ones. Within a joint, earlier angles are applied after later ones
/// (`R = R_first · R_second`). Computed in f64 and rounded once, so long chains (a tail) do
/// not accumulate f32 error. `angles` has one value per entry of `dofs` (checked by the
/// caller); parents precede their children.
pub(super) fn joint_matrices(skeleton: &Skeleton, dofs: &[Dof], angles: &[f64]) -> Vec<Mat4> {
    let (parents, bind) = (&skeleton.parents, &skeleton.bind);
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
