//! Biovision Hierarchy (BVH) motion capture: a joint hierarchy with rest offsets, then one line
//! of channel values per frame.
//!
//! Conventions, as the format's readers agree (Blender's importer, three.js `BVHLoader`,
//! Neil Lawrence's `bvh2xyz`):
//!
//! - A joint's local transform is `T(offset + p) · R`, where `p` is its position channels (any
//!   joint may have them; absent ones are 0) and `R` its rotation channels composed **in the
//!   order listed**: `CHANNELS 3 Zrotation Xrotation Yrotation` gives `R = Rz · Rx · Ry` acting
//!   on column vectors, so the last-listed axis is applied to a child first. Angles are degrees.
//! - A joint's world transform is its parent's world transform times its local transform; the
//!   rest pose is all channels zero, so rest rotations are the identity and a joint's rest
//!   position is the sum of the offsets down to it.
//! - BVH is y-up by convention; this module keeps the file's axes and units untouched.

mod parse;

use std::path::Path;

use glam::{DAffine3, DQuat, DVec3};

pub use parse::{MocapError, Problem};

/// One animation channel of a joint.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Channel {
    /// Translation along x, in the file's units.
    Xposition,
    /// Translation along y.
    Yposition,
    /// Translation along z.
    Zposition,
    /// Rotation about x, degrees.
    Xrotation,
    /// Rotation about y, degrees.
    Yrotation,
    /// Rotation about z, degrees.
    Zrotation,
}

impl Channel {
    /// The channel's axis.
    pub fn axis(self) -> DVec3 {
        match self {
            Channel::Xposition | Channel::Xrotation => DVec3::X,
            Channel::Yposition | Channel::Yrotation => DVec3::Y,
            Channel::Zposition | Channel::Zrotation => DVec3::Z,
        }
    }

    /// Whether it is a rotation (rather than a position) channel.
    pub fn is_rotation(self) -> bool {
        matches!(
            self,
            Channel::Xrotation | Channel::Yrotation | Channel::Zrotation
        )
    }
}

/// A `ROOT` or `JOINT` of the hierarchy.
#[derive(Clone, Debug, PartialEq)]
pub struct Joint {
    /// Name as written in the file (unique within it).
    pub name: String,
    /// Index of the parent joint; `None` for a root. Parents precede their children.
    pub parent: Option<usize>,
    /// Rest offset from the parent (from the origin for a root).
    pub offset: DVec3,
    /// Channels in the order the file lists them.
    pub channels: Vec<Channel>,
    /// Index of this joint's first channel within a frame's values.
    pub first_channel: usize,
    /// Offsets of this joint's `End Site`s, which carry the ends of leaf bones.
    pub end_sites: Vec<DVec3>,
}

impl Joint {
    /// Whether any of the joint's channels is a rotation.
    pub fn rotates(&self) -> bool {
        self.channels.iter().any(|c| c.is_rotation())
    }

    /// Whether any of the joint's channels is a position.
    pub fn translates(&self) -> bool {
        self.channels.iter().any(|c| !c.is_rotation())
    }

    /// The joint's local rotation and translation (`offset + position channels`) for one
    /// frame's `values` (all channels of the file).
    pub fn local(&self, values: &[f64]) -> (DQuat, DVec3) {
        let mut rotation = DQuat::IDENTITY;
        let mut translation = self.offset;
        for (k, &channel) in self.channels.iter().enumerate() {
            let value = values[self.first_channel + k];
            if channel.is_rotation() {
                rotation *= DQuat::from_axis_angle(channel.axis(), value.to_radians());
            } else {
                translation += channel.axis() * value;
            }
        }
        (rotation, translation)
    }
}

/// A parsed BVH file: the hierarchy, the frame rate and every frame's channel values.
#[derive(Clone, Debug, PartialEq)]
pub struct Mocap {
    joints: Vec<Joint>,
    frame_time: f64,
    channel_count: usize,
    frame_count: usize,
    /// Frame-major: frame `f` is `values[f * channel_count..][..channel_count]`.
    values: Vec<f64>,
}

impl Mocap {
    /// Reads and parses a BVH file. Errors name the file, the line and the problem.
    pub fn read(path: &Path) -> Result<Mocap, MocapError> {
        let text = crate::input::read_input_text(path, crate::input::InputKind::Bvh)?;
        Mocap::parse(&text, path)
    }

    /// Parses BVH text; `path` is only used to name the source in errors.
    pub fn parse(text: &str, path: &Path) -> Result<Mocap, MocapError> {
        parse::parse(text).map_err(|(line, problem)| MocapError::Parse {
            path: path.to_owned(),
            line,
            problem,
        })
    }

    /// The joints, parents before children, in file order.
    pub fn joints(&self) -> &[Joint] {
        &self.joints
    }

    /// Index of the joint called `name`.
    pub fn joint_index(&self, name: &str) -> Option<usize> {
        self.joints.iter().position(|j| j.name == name)
    }

    /// Seconds per frame (`Frame Time`).
    pub fn frame_time(&self) -> f64 {
        self.frame_time
    }

    /// Frames per second.
    pub fn fps(&self) -> f64 {
        1.0 / self.frame_time
    }

    /// Number of frames.
    pub fn frame_count(&self) -> usize {
        self.frame_count
    }

    /// Channel values of frame `f`, all joints in file order.
    ///
    /// # Panics
    /// If `f >= self.frame_count()`.
    pub fn frame(&self, f: usize) -> &[f64] {
        assert!(
            f < self.frame_count(),
            "frame {f} of {}",
            self.frame_count()
        );
        &self.values[f * self.channel_count..(f + 1) * self.channel_count]
    }

    /// Forward kinematics: every joint's world transform for one frame's channel `values`.
    pub fn world_transforms(&self, values: &[f64]) -> Vec<DAffine3> {
        self.chain(|j| self.joints[j].local(values))
    }

    /// World transforms of the joints from each joint's local `(rotation, translation)`,
    /// parents before children.
    pub fn chain(&self, local: impl Fn(usize) -> (DQuat, DVec3)) -> Vec<DAffine3> {
        let mut world: Vec<DAffine3> = Vec::with_capacity(self.joints.len());
        for (j, joint) in self.joints.iter().enumerate() {
            let (rotation, translation) = local(j);
            let local = DAffine3::from_rotation_translation(rotation, translation);
            world.push(joint.parent.map_or(local, |p| world[p] * local));
        }
        world
    }

    /// Rest-pose (all channels zero) world positions of the joints: sums of offsets.
    pub fn rest_positions(&self) -> Vec<DVec3> {
        let mut out: Vec<DVec3> = Vec::with_capacity(self.joints.len());
        for joint in &self.joints {
            let base = joint.parent.map_or(DVec3::ZERO, |p| out[p]);
            out.push(base + joint.offset);
        }
        out
    }
}

#[cfg(test)]
mod tests;
