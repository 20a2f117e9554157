//! A glTF animation as per-node curves: sampled into local transforms of every node, and
//! summarised as the channels a rotation-only pose vector leaves out.

use glam::{DQuat, DVec3};

use super::HeldChannel;
use super::curve::Curve;
use super::skeleton::{Skeleton, Trs};

/// One animated property of one node.
#[derive(Clone, Debug, PartialEq)]
pub enum Track {
    /// Local translation.
    Translation(Curve<DVec3>),
    /// Local rotation.
    Rotation(Curve<DQuat>),
    /// Local scale.
    Scale(Curve<DVec3>),
}

/// A named animation: tracks with the node each one drives. Later tracks on the same node and
/// property override earlier ones.
#[derive(Clone, Debug, PartialEq)]
pub struct Animation {
    /// Clip name (the glTF name, or `animation<i>`).
    pub name: String,
    /// `(node, track)` pairs in channel order.
    pub tracks: Vec<(usize, Track)>,
}

impl Animation {
    /// Time of the last key of any track (0 for an animation without tracks).
    pub fn end(&self) -> f64 {
        self.tracks
            .iter()
            .map(|(_, track)| match track {
                Track::Translation(c) | Track::Scale(c) => c.end(),
                Track::Rotation(c) => c.end(),
            })
            .fold(0.0, f64::max)
    }

    /// Local transform of every node at time `t`: the animated properties sampled, every other
    /// property at its rest value.
    pub fn locals_at(&self, rest: &[Trs], t: f64) -> Vec<Trs> {
        let mut locals = rest.to_vec();
        for (node, track) in &self.tracks {
            let local = &mut locals[*node];
            match track {
                Track::Translation(c) => local.translation = c.sample(t),
                Track::Rotation(c) => local.rotation = c.sample(t),
                Track::Scale(c) => local.scale = c.sample(t),
            }
        }
        locals
    }

    /// The tracks whose motion the pose vector does not carry (see [`HeldChannel`]), with how
    /// far their keys stray from the rest value.
    pub fn held_channels(&self, skeleton: &Skeleton, node_names: &[String]) -> Vec<HeldChannel> {
        self.tracks
            .iter()
            .filter(|(node, _)| skeleton.moves_the_mesh(*node))
            .filter_map(|(node, track)| {
                let rest = skeleton.rest[*node];
                let (property, max_deviation) = match track {
                    Track::Translation(c) => ("translation", max_distance(c, rest.translation)),
                    Track::Scale(c) => ("scale", max_distance(c, rest.scale)),
                    Track::Rotation(_) if skeleton.is_joint(*node) => return None,
                    Track::Rotation(c) => (
                        "rotation",
                        c.key_values()
                            .map(|q| rest.rotation.angle_between(q))
                            .fold(0.0, f64::max),
                    ),
                };
                Some(HeldChannel {
                    animation: self.name.clone(),
                    node: *node,
                    node_name: node_names[*node].clone(),
                    property,
                    max_deviation,
                })
            })
            .collect()
    }
}

fn max_distance(curve: &Curve<DVec3>, rest: DVec3) -> f64 {
    curve
        .key_values()
        .map(|v| v.distance(rest))
        .fold(0.0, f64::max)
}
