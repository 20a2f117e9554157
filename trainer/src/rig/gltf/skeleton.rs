//! The node hierarchy a skin hangs from: rest transforms, parents, and the joint matrices of a
//! set of local transforms.
//!
//! Joint matrix `k` is `F · world(joint k) · inverseBind(k)`, where `world` composes the local
//! transforms from the scene root down (non-joint ancestors included, at their rest values)
//! and `F` is the inverse of the skinned mesh node's rest world matrix. glTF ignores the mesh
//! node's own transform when skinning (§3.7.3.3: the joints place the mesh in world space);
//! `F` only re-expresses that world-space result in the frame of the file's vertex data, so
//! that the rest pose reproduces the stored mesh and bind and posed meshes share one frame.

use glam::{DMat4, DQuat, DVec3, Mat4};

/// A node's local transform, decomposed as glTF animates it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Trs {
    /// Translation.
    pub translation: DVec3,
    /// Unit rotation.
    pub rotation: DQuat,
    /// Scale.
    pub scale: DVec3,
}

impl Trs {
    /// `T · R · S`, the order glTF composes them in.
    pub fn matrix(&self) -> DMat4 {
        DMat4::from_scale_rotation_translation(self.scale, self.rotation, self.translation)
    }
}

/// Nodes (indexed as in the file) with their parents and rest transforms, and the skin's joints.
#[derive(Clone, Debug, PartialEq)]
pub struct Skeleton {
    /// Parent of each node.
    pub parents: Vec<Option<usize>>,
    /// Rest (file) transform of each node.
    pub rest: Vec<Trs>,
    /// Node of each skin joint, in skin order.
    pub joints: Vec<usize>,
    /// Inverse bind matrix of each joint.
    pub inverse_bind: Vec<DMat4>,
    /// `F`: maps world space to the frame of the mesh data.
    pub world_to_mesh: DMat4,
    /// Joints and their ancestors, parents before children: the nodes whose world matrix
    /// the joint matrices need.
    order: Vec<usize>,
    /// Whether each node is in `order`.
    moves: Vec<bool>,
    /// Whether each node is a joint.
    is_joint: Vec<bool>,
}

impl Skeleton {
    /// Builds the skeleton; `parents` must be a forest (the file was checked for cycles).
    /// Linear in the number of nodes.
    pub fn new(
        parents: Vec<Option<usize>>,
        rest: Vec<Trs>,
        joints: Vec<usize>,
        inverse_bind: Vec<DMat4>,
        mesh_node: usize,
    ) -> Skeleton {
        let count = parents.len();
        let mut moves = vec![false; count];
        let mut is_joint = vec![false; count];
        for &joint in &joints {
            is_joint[joint] = true;
            let mut node = Some(joint);
            while let Some(n) = node.filter(|&n| !moves[n]) {
                moves[n] = true;
                node = parents[n];
            }
        }
        // Breadth first from the roots: every parent comes before its children.
        let mut children = vec![Vec::new(); count];
        for (n, parent) in parents.iter().enumerate() {
            if let Some(p) = parent {
                children[*p].push(n);
            }
        }
        let mut order: Vec<usize> = (0..count)
            .filter(|&n| parents[n].is_none() && moves[n])
            .collect();
        let mut next = 0;
        while let Some(&n) = order.get(next) {
            order.extend(children[n].iter().filter(|&&c| moves[c]));
            next += 1;
        }
        let mut skeleton = Skeleton {
            parents,
            rest,
            joints,
            inverse_bind,
            world_to_mesh: DMat4::IDENTITY,
            order,
            moves,
            is_joint,
        };
        skeleton.world_to_mesh = skeleton.rest_world(mesh_node).inverse();
        skeleton
    }

    /// Whether `node` is a joint or an ancestor of one, i.e. whether its transform moves the
    /// mesh.
    pub fn moves_the_mesh(&self, node: usize) -> bool {
        self.moves[node]
    }

    /// Whether `node` is one of the skin's joints.
    pub fn is_joint(&self, node: usize) -> bool {
        self.is_joint[node]
    }

    /// World matrix of `node` with every node at rest.
    fn rest_world(&self, node: usize) -> DMat4 {
        let mut m = self.rest[node].matrix();
        let mut n = node;
        while let Some(p) = self.parents[n] {
            m = self.rest[p].matrix() * m;
            n = p;
        }
        m
    }

    /// Joint matrices for the given local transform of every node (only the joints and their
    /// ancestors are read).
    pub fn joint_matrices(&self, locals: &[Trs]) -> Vec<Mat4> {
        let mut world = vec![DMat4::IDENTITY; self.parents.len()];
        for &n in &self.order {
            let parent = self.parents[n].map_or(DMat4::IDENTITY, |p| world[p]);
            world[n] = parent * locals[n].matrix();
        }
        self.joints
            .iter()
            .zip(&self.inverse_bind)
            .map(|(&n, ibm)| (self.world_to_mesh * world[n] * *ibm).as_mat4())
            .collect()
    }
}
