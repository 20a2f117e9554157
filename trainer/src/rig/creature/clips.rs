//! The creature's clips: the training clip (the shared random walk of
//! [`crate::rig::procedural::clips`], with its own seed), the novel test clips `prowl` and
//! `lash`, and the validation clip `crouch`.

use std::f64::consts::{PI, TAU};

use super::skeleton::{LEGS, joint::TAIL_JOINTS};
use crate::rig::Clip;
use crate::rig::procedural::JointAngle;
use crate::rig::procedural::clips::{ease, scripted};

/// Seed of the training clip's random walk.
pub(crate) const TRAINING_SEED: u64 = 0x5EED_7A11_C0DE_D1A0;

/// Names of tail joint `k`'s angles (0 at the base): pitch and yaw.
fn tail(k: usize) -> [String; 2] {
    [
        format!("tail_{}_pitch", k + 1),
        format!("tail_{}_yaw", k + 1),
    ]
}

/// Three strides of a prowl in place (1.2 s cycle): diagonal legs move together (fore left
/// with hind right), the back sways, and a wave runs down the tail, each joint behind the one
/// before it, growing toward the tip; the head stays level and low.
fn prowl(angles: &[JointAngle]) -> Clip {
    scripted(angles, "prowl", 96, |t, set| {
        let w = TAU * t / 1.2;
        for leg in &LEGS {
            // Fore left and hind right in phase; the other diagonal half a cycle later.
            let phase = if (leg.side > 0.0) != leg.hind {
                0.0
            } else {
                PI
            };
            let [swing, _, bend] = leg.angles;
            set(swing, 0.35 * (w + phase).sin());
            set(bend, 0.35 + 0.3 * (w + phase + 1.3).sin());
        }
        set("spine_yaw", 0.08 * w.sin());
        set("chest_yaw", -0.06 * w.sin());
        set("neck_1_pitch", -0.15);
        set("neck_1_yaw", -0.08 * w.sin());
        set("head_pitch", 0.1);
        for k in 0..TAIL_JOINTS {
            let [pitch, yaw] = tail(k);
            set(&pitch, if k == 0 { 0.1 } else { -0.02 });
            set(&yaw, (0.12 + 0.03 * k as f64) * (w - 0.6 * k as f64).sin());
        }
    })
}

/// The tail whips side to side (1.2 Hz, a wave running to the tip), then curls up beside the
/// left flank while the neck turns to look at it: the tail shadows the body and the body the
/// tail, a self-shadowing the training clip's independent angles rarely line up.
fn lash(angles: &[JointAngle]) -> Clip {
    scripted(angles, "lash", 90, |t, set| {
        let whip = 0.45 * ease(t, 0.0, 0.5);
        let curl = ease(t, 1.5, 2.3);
        let w = TAU * 1.2 * t;
        for k in 0..TAIL_JOINTS {
            let [pitch, yaw] = tail(k);
            let side = whip * (w - 0.7 * k as f64).sin();
            set(&yaw, (1.0 - curl) * side + curl * 0.5);
            set(&pitch, 0.15 * curl);
        }
        set("spine_yaw", 0.15 * curl);
        set("chest_yaw", 0.1 * curl);
        set("neck_1_yaw", 0.4 * curl);
        set("neck_2_yaw", 0.4 * curl);
        set("head_yaw", 0.3 * curl);
        set("neck_1_pitch", -0.1 * curl);
    })
}

/// Crouches (legs folded under the body, the neck low), sweeps the head from side to side,
/// then rises halfway; the tail lifts and bends to the right. The validation clip: held out of
/// training to choose the model by (`--validate crouch`), never a test clip.
pub(crate) fn crouch(angles: &[JointAngle]) -> Clip {
    scripted(angles, "crouch", 96, |t, set| {
        let down = ease(t, 0.0, 1.2) * (1.0 - 0.5 * ease(t, 2.4, 3.2));
        for leg in &LEGS {
            let [swing, splay, bend] = leg.angles;
            // Hind thighs swing forward and fore upper legs back, so the feet stay under.
            set(swing, if leg.hind { 0.5 } else { -0.45 } * down);
            set(splay, 0.15 * down);
            set(bend, 1.1 * down);
        }
        set("spine_pitch", 0.1 * down);
        set("neck_1_pitch", -0.45 * down);
        set("head_pitch", 0.3 * down);
        let sweep = 0.5 * (TAU * 0.5 * t).sin() * ease(t, 0.8, 1.4);
        set("neck_2_yaw", sweep);
        set("head_yaw", 0.5 * sweep);
        for k in 0..TAIL_JOINTS {
            let [pitch, yaw] = tail(k);
            set(&pitch, if k == 0 { 0.25 } else { 0.05 } * down);
            set(&yaw, -0.2 * down);
        }
    })
}

/// The novel test clips, in a fixed order.
pub(crate) fn novel(angles: &[JointAngle]) -> Vec<Clip> {
    vec![prowl(angles), lash(angles)]
}
