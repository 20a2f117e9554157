//! Which entries of a rig's pose vector a model takes. Joints that never move in the training
//! clip carry no information a fit could use (their column of the pose matrix is constant),
//! so they are dropped and reported; a model records the names of the entries it kept, and
//! any later clip of the same rig is mapped onto them by name.

use anyhow::{Result, bail};

/// A joint whose every entry stays within this many radians of its first value over the
/// training clip counts as not moving. Far below any visible rotation (1e-6 rad moves a
/// point 1 m from the joint by a micrometre), far above the rounding of sampled keyframes.
pub const STILL_TOLERANCE: f64 = 1e-6;

/// The kept entries of a rig's pose vector, in rig order.
#[derive(Clone, Debug, PartialEq)]
pub struct PoseLayout {
    /// Index into the rig's pose vector of each kept entry.
    indices: Vec<usize>,
    /// Names of the kept entries.
    names: Vec<String>,
    /// Joints whose entries were all dropped, in rig order.
    dropped: Vec<String>,
}

/// The joint an entry belongs to: the name before its last `.` (`LeftArm.x` → `LeftArm`), or
/// the whole name for single-value joints such as the built-in character's `l_elbow_flex`.
fn joint_of(name: &str) -> &str {
    name.rsplit_once('.').map_or(name, |(joint, _)| joint)
}

/// Joints, in rig order, none of whose entries is among `kept` (indices into `names`).
fn dropped_joints(names: &[String], kept: &[usize]) -> Vec<String> {
    let mut dropped: Vec<String> = Vec::new();
    for name in names {
        let joint = joint_of(name);
        let is_kept = kept.iter().any(|&i| joint_of(&names[i]) == joint);
        if !is_kept && !dropped.iter().any(|d| d == joint) {
            dropped.push(joint.to_owned());
        }
    }
    dropped
}

impl PoseLayout {
    /// Keeps every entry of every joint that moves in `frames` (by more than
    /// [`STILL_TOLERANCE`] in any entry). Errors if no joint moves: there is nothing to learn.
    pub fn from_training(names: &[String], frames: &[Vec<f64>]) -> Result<PoseLayout> {
        let moves = |i: usize| {
            frames
                .iter()
                .any(|f| (f[i] - frames[0][i]).abs() > STILL_TOLERANCE)
        };
        let moving_joints: Vec<&str> = (0..names.len())
            .filter(|&i| moves(i))
            .map(|i| joint_of(&names[i]))
            .collect();
        let indices: Vec<usize> = (0..names.len())
            .filter(|&i| moving_joints.contains(&joint_of(&names[i])))
            .collect();
        let layout = PoseLayout {
            names: indices.iter().map(|&i| names[i].clone()).collect(),
            dropped: dropped_joints(names, &indices),
            indices,
        };
        if layout.indices.is_empty() {
            bail!(
                "no joint moves in the {} training frames: there is nothing to learn",
                frames.len()
            );
        }
        Ok(layout)
    }

    /// The layout of a model that kept `kept` (its recorded names) on a rig whose pose vector
    /// is named `names`. Errors name the entries the rig lacks.
    pub fn from_names(names: &[String], kept: &[String]) -> Result<PoseLayout> {
        let mut indices = Vec::with_capacity(kept.len());
        let mut missing = Vec::new();
        for want in kept {
            match names.iter().position(|n| n == want) {
                Some(i) => indices.push(i),
                None => missing.push(want.as_str()),
            }
        }
        if !missing.is_empty() {
            bail!(
                "the model takes pose entries this character does not have: {}",
                crate::text::shown_list(&missing)
            );
        }
        Ok(PoseLayout {
            names: kept.to_vec(),
            dropped: dropped_joints(names, &indices),
            indices,
        })
    }

    /// Names of the kept entries: the model's pose vector.
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// Index into the rig's pose vector of each kept entry.
    pub fn indices(&self) -> &[usize] {
        &self.indices
    }

    /// Joints that were dropped.
    pub fn dropped(&self) -> &[String] {
        &self.dropped
    }

    /// A rig pose vector reduced to the kept entries.
    pub fn reduce(&self, pose: &[f64]) -> Vec<f64> {
        self.indices.iter().map(|&i| pose[i]).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(list: &[&str]) -> Vec<String> {
        list.iter().map(|s| (*s).to_owned()).collect()
    }

    #[test]
    fn a_joint_is_kept_whole_when_any_of_its_entries_moves() {
        let names = names(&["hip.x", "hip.y", "hip.z", "toe.x", "toe.y", "toe.z", "knee"]);
        // hip moves only about y; toe is constant but not zero; knee moves.
        let frames = vec![
            vec![0.1, 0.0, 0.0, 0.5, 0.5, 0.5, 0.0],
            vec![0.1, 0.3, 0.0, 0.5, 0.5, 0.5, 1.0],
        ];
        let layout = PoseLayout::from_training(&names, &frames).unwrap();
        assert_eq!(layout.names(), ["hip.x", "hip.y", "hip.z", "knee"]);
        assert_eq!(layout.dropped(), ["toe"]);
        assert_eq!(layout.reduce(&frames[1]), [0.1, 0.3, 0.0, 1.0]);
    }

    #[test]
    fn motion_below_the_tolerance_is_still() {
        let names = names(&["a", "b"]);
        let frames = vec![vec![0.0, 0.0], vec![0.5 * STILL_TOLERANCE, 1.0]];
        let layout = PoseLayout::from_training(&names, &frames).unwrap();
        assert_eq!(layout.names(), ["b"]);
        let err = PoseLayout::from_training(&names, &[vec![0.0, 0.0]]).unwrap_err();
        assert!(err.to_string().contains("no joint moves"), "{err}");
    }

    #[test]
    fn a_model_layout_maps_by_name_and_names_what_is_missing() {
        let rig = names(&["a.x", "a.y", "b.x", "b.y"]);
        let layout = PoseLayout::from_names(&rig, &names(&["b.y", "a.x"])).unwrap();
        assert_eq!(layout.reduce(&[1.0, 2.0, 3.0, 4.0]), [4.0, 1.0]);
        assert!(layout.dropped().is_empty());
        let only_b = PoseLayout::from_names(&rig, &names(&["b.x"])).unwrap();
        assert_eq!(only_b.dropped(), ["a"]);
        let err = PoseLayout::from_names(&rig, &names(&["c.z", "a.x", "d"])).unwrap_err();
        assert!(err.to_string().contains("c.z, d"), "{err}");
    }
}
