//! Choosing a blob's precision from what it costs in shading: the smallest encoding whose
//! shading, through aprt-core, stays within a share of the error target of the f32 blob's.

use anyhow::Result;
use aprt_core::Rotation;

use crate::lighting::GREY_PER_IRRADIANCE;
use crate::model::LinearModel;
use crate::model::export::{Precision, encode_model_with_rig};
use crate::model::runtime::predict_shading;

/// The share of the error target quantisation may cost: the rest is the model's own.
pub const QUANTISATION_SHARE: f32 = 0.25;

/// The precisions tried before f32, smallest first.
pub const SMALLER: [Precision; 2] = [Precision::I8, Precision::F16];

/// The precision of a blob: fixed, or the smallest that costs at most
/// [`QUANTISATION_SHARE`] of `target` grey levels against f32 under `lighting` (one SH channel
/// per RGB channel, each `order²` values) over `poses` (angles and the bones' rotations, empty
/// for world-frame models).
#[derive(Clone, Debug, PartialEq)]
pub enum PrecisionChoice {
    /// This precision.
    Fixed(Precision),
    /// The smallest within the share of the target.
    Auto {
        /// Grey levels of shading error the model may cost.
        target: f32,
        /// SH lighting per RGB channel.
        lighting: [Vec<f32>; 3],
    },
}

/// The chosen precision, its blob and why.
pub struct Chosen {
    /// The precision.
    pub precision: Precision,
    /// The blob in it.
    pub blob: Vec<u8>,
    /// Why, in one sentence.
    pub reason: String,
}

/// Encodes `model` (with `rig` as its irradiance-rig section) at the precision `choice`
/// asks for, measuring the candidates on `poses` when it is automatic.
pub fn encode_chosen(
    model: &LinearModel,
    rig: Option<&[u8]>,
    choice: &PrecisionChoice,
    poses: &[(Vec<f64>, Vec<Rotation>)],
) -> Result<Chosen> {
    let (target, lighting) = match choice {
        PrecisionChoice::Fixed(p) => {
            return Ok(Chosen {
                precision: *p,
                blob: encode_model_with_rig(model, *p, rig)?,
                reason: format!("{} as asked", p.name()),
            });
        }
        PrecisionChoice::Auto { target, lighting } => (*target, lighting),
    };
    let reference = encode_model_with_rig(model, Precision::F32, rig)?;
    let allowed = QUANTISATION_SHARE * target;
    let mut misses = Vec::new();
    for precision in SMALLER {
        let blob = encode_model_with_rig(model, precision, rig)?;
        let error = worst_difference(&blob, &reference, lighting, poses)?;
        if error <= allowed {
            return Ok(Chosen {
                precision,
                reason: format!(
                    "{}: its shading differs from f32 by at most {error:.3} grey levels over {} poses, within {allowed:.2} (a quarter of the target)",
                    precision.name(),
                    poses.len()
                ),
                blob,
            });
        }
        misses.push(format!("{} {error:.2}", precision.name()));
    }
    Ok(Chosen {
        precision: Precision::F32,
        blob: reference,
        reason: format!(
            "f32: the smaller encodings miss a quarter of the target ({allowed:.2} grey levels): {}",
            misses.join(", ")
        ),
    })
}

/// The largest shading difference between two blobs of one model, in grey levels, over every
/// pose, vertex and channel.
fn worst_difference(
    blob: &[u8],
    reference: &[u8],
    lighting: &[Vec<f32>; 3],
    poses: &[(Vec<f64>, Vec<Rotation>)],
) -> Result<f32> {
    let mut worst = 0.0f32;
    for (angles, rotations) in poses {
        for channel in lighting {
            let a = predict_shading(blob, angles, rotations, channel)?;
            let b = predict_shading(reference, angles, rotations, channel)?;
            for (x, y) in a.iter().zip(&b) {
                worst = worst.max((x - y).abs() * GREY_PER_IRRADIANCE as f32);
            }
        }
    }
    Ok(worst)
}
