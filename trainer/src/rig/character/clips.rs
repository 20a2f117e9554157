//! Animation clips for the built-in character: the novel test clips, with motions the training
//! clip (the shared random walk of [`crate::rig::procedural::clips`], seeded with
//! [`TRAINING_SEED`]) never performs, and the validation clip.

use super::JointAngle;
use crate::rig::Clip;
use crate::rig::procedural::clips::{ease, index_of, scripted};

/// Seed of the training clip's random walk ([`crate::rig::procedural::clips::training`]).
pub(crate) const TRAINING_SEED: u64 = 0x0A9B_7C0D_E5F1_2345;

/// Raises the right arm high and waves the forearm at 1.5 Hz while the head turns toward it.
/// Training never holds one arm high while the other rests, nor oscillates this fast.
fn wave(angles: &[JointAngle]) -> Clip {
    let abduct_rest = angles[index_of(angles, "r_shoulder_abduct")].rest;
    scripted(angles, "wave", 90, |t, set| {
        let up = ease(t, 0.0, 0.7);
        let w = std::f64::consts::TAU * 1.5 * t;
        set("r_shoulder_abduct", abduct_rest + (1.95 - abduct_rest) * up);
        set("r_shoulder_flex", 0.45 * up);
        set("r_elbow_flex", up * (0.8 + 0.45 * w.sin()));
        set("r_wrist_flex", up * 0.3 * (w + 0.5).sin());
        set("neck_twist", -0.35 * up);
        set("head_flex", -0.12 * up);
        set("chest_twist", -0.15 * up);
        set("spine_lean", 0.08 * up);
    })
}

/// Three strides of a walk in place (1.07 s cycle): legs and arms swing in opposition, the
/// chest counter-rotates, arms hang near the body.
fn walk(angles: &[JointAngle]) -> Clip {
    scripted(angles, "walk", 96, |t, set| {
        let w = std::f64::consts::TAU * t / 1.07;
        for (side, sign) in [("l", 1.0), ("r", -1.0)] {
            let phase = if sign > 0.0 {
                0.0
            } else {
                std::f64::consts::PI
            };
            set(&format!("{side}_hip_flex"), 0.1 + 0.45 * (w + phase).sin());
            set(
                &format!("{side}_knee_flex"),
                0.45 + 0.4 * (w + phase + 1.3).sin(),
            );
            set(
                &format!("{side}_ankle_flex"),
                0.15 * (w + phase + 2.0).sin(),
            );
            set(&format!("{side}_shoulder_flex"), -0.35 * (w + phase).sin());
            set(&format!("{side}_shoulder_abduct"), 0.2);
            set(
                &format!("{side}_elbow_flex"),
                0.3 + 0.15 * (w + phase + 0.4).sin(),
            );
        }
        set("chest_twist", 0.12 * w.sin());
        set("spine_flex", 0.05);
        set("spine_lean", 0.03 * (2.0 * w).sin());
    })
}

/// Bends forward and reaches down and ahead with the left arm, bending the knees, then holds.
/// (Shoulder flex is relative to the chest, so it must exceed the 0.75 rad forward bend for
/// the arm to point ahead of vertical.)
fn reach(angles: &[JointAngle]) -> Clip {
    let abduct_rest = angles[index_of(angles, "l_shoulder_abduct")].rest;
    scripted(angles, "reach", 72, |t, set| {
        let e = ease(t, 0.0, 1.8);
        set("spine_flex", 0.45 * e);
        set("chest_flex", 0.3 * e);
        set("l_shoulder_flex", 1.5 * e);
        set("l_shoulder_abduct", abduct_rest + (0.35 - abduct_rest) * e);
        set("l_elbow_flex", 0.25 * e);
        set("r_shoulder_flex", -0.2 * e);
        set("head_flex", -0.2 * e);
        set("neck_twist", 0.2 * e);
        set("l_hip_flex", 0.3 * e);
        set("r_hip_flex", 0.3 * e);
        set("l_knee_flex", 0.35 * e);
        set("r_knee_flex", 0.35 * e);
    })
}

/// Stretches: both arms out to the sides while the chest twists, then a squat with the arms
/// forward and the head down. The validation clip: held out of training to choose the model
/// by (`--validate stretch`), never a test clip.
pub(crate) fn stretch(angles: &[JointAngle]) -> Clip {
    let rest = |name: &str| angles[index_of(angles, name)].rest;
    let abduct_rest = [rest("l_shoulder_abduct"), rest("r_shoulder_abduct")];
    scripted(angles, "stretch", 96, |t, set| {
        let out = ease(t, 0.0, 0.6) * (1.0 - ease(t, 1.6, 2.0));
        let squat = ease(t, 1.8, 2.6);
        let twist = 0.45 * (std::f64::consts::TAU * 0.6 * t).sin() * out;
        for (side, abduct_rest) in ["l", "r"].into_iter().zip(abduct_rest) {
            let joint = |name: &str| format!("{side}_{name}");
            set(
                &joint("shoulder_abduct"),
                abduct_rest + (1.45 - abduct_rest) * out,
            );
            set(&joint("shoulder_flex"), 1.2 * squat);
            set(&joint("elbow_flex"), 0.2 * out + 0.4 * squat);
            set(&joint("hip_flex"), 1.0 * squat);
            set(&joint("knee_flex"), 1.4 * squat);
            set(&joint("ankle_flex"), 0.35 * squat);
        }
        set("chest_twist", twist);
        set("spine_lean", 0.1 * twist);
        set("spine_flex", 0.25 * squat);
        set("neck_flex", 0.3 * squat);
    })
}

/// The novel test clips, in a fixed order.
pub(crate) fn novel(angles: &[JointAngle]) -> Vec<Clip> {
    vec![wave(angles), walk(angles), reach(angles)]
}
