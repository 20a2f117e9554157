//! What the fit learns from (the training poses and their transfer, the clips, the anchor and
//! the held-out clips), the checks it passes before any solver, and the entries it pins.

use nalgebra::DMatrix;

use super::{Alpha, CoefDims, Dims, EntryGroup, FitError, FitOptions, Locality};
use crate::model::features::PoseFeatures;

/// A pose whose transfer is known and that the model tends to as α grows: for bone-frame
/// models the rest pose, whose bone-frame transfer is the rest transfer carried by the skin.
#[derive(Clone, Copy, Debug)]
pub struct Anchor<'a> {
    /// Its pose vector (a values).
    pub angles: &'a [f64],
    /// Its transfer, `v × n²` vertex-major, in the frame the model learns.
    pub transfer: &'a [f32],
}

/// A clip held out whole to choose the model by (`--validate`, or the validation poses).
#[derive(Clone, Copy, Debug)]
pub struct Validation<'a> {
    /// Its name, for the selection report.
    pub name: &'a str,
    /// `p_h × a` pose vectors.
    pub angles: &'a DMatrix<f64>,
    /// Transfer of each pose, in the frame the model learns.
    pub transfers: &'a [Vec<f32>],
}

/// What the fit learns from: the training poses and their transfer, how they split into
/// clips, the anchor and the held-out clips.
#[derive(Clone, Debug)]
pub struct FitInput<'a> {
    /// `p × a`, one row of pose entries per pose.
    pub angles: &'a DMatrix<f64>,
    /// `transfers[i]` is pose i's transfer, `v × n²` vertex-major (`[j·n² + c]`).
    pub transfers: &'a [Vec<f32>],
    /// SH order n.
    pub order: usize,
    /// Poses per clip, in order (held-out segments never straddle two clips); empty: one clip.
    pub clips: Vec<usize>,
    /// The prior pose, if the model has one besides the mean.
    pub anchor: Option<Anchor<'a>>,
    /// Clips held out whole: when given, they alone choose α, k_a and the prior.
    pub validation: Vec<Validation<'a>>,
    /// The vertex groups of the local model (needs the anchor), when the caller offers one.
    pub locality: Option<&'a Locality>,
}

impl<'a> FitInput<'a> {
    /// Poses of one clip, no anchor, no held-out clips.
    pub fn new(angles: &'a DMatrix<f64>, transfers: &'a [Vec<f32>], order: usize) -> Self {
        Self {
            angles,
            transfers,
            order,
            clips: Vec::new(),
            anchor: None,
            validation: Vec::new(),
            locality: None,
        }
    }
}

/// The pose entries no vertex group depends on (none without a locality).
pub(super) fn unused_entries(input: &FitInput<'_>) -> Vec<usize> {
    let Some(locality) = input.locality else {
        return Vec::new();
    };
    (0..input.angles.ncols())
        .filter(|&i| !locality.groups.iter().any(|g| g.entries.contains(&i)))
        .collect()
}

/// The training and validation poses with `entries` set to the anchor's values; `None` when
/// there is nothing to pin (no entries, or no anchor).
pub(super) fn pin_entries(
    input: &FitInput<'_>,
    entries: &[usize],
) -> Option<(DMatrix<f64>, Vec<DMatrix<f64>>)> {
    let anchor = input.anchor.filter(|_| !entries.is_empty())?;
    let pin = |angles: &DMatrix<f64>| {
        let mut pinned = angles.clone();
        for &i in entries {
            pinned.column_mut(i).fill(anchor.angles[i]);
        }
        pinned
    };
    let held = input.validation.iter().map(|v| pin(v.angles)).collect();
    Some((pin(input.angles), held))
}

/// Checks shapes, finiteness and options; returns the vertex count.
pub(super) fn validate(input: &FitInput<'_>, options: &FitOptions) -> Result<usize, FitError> {
    let len0 = check_training(input)?;
    let expected = (input.angles.ncols(), len0);
    if let Some(anchor) = &input.anchor {
        let a = DMatrix::from_row_slice(1, anchor.angles.len(), anchor.angles);
        check_held_out(
            "the rest pose".into(),
            &a,
            &[anchor.transfer.to_vec()],
            expected,
        )?;
    }
    for (i, v) in input.validation.iter().enumerate() {
        check_held_out(
            format!("validation clip {i}"),
            v.angles,
            v.transfers,
            expected,
        )?;
    }
    let p = input.transfers.len();
    if !input.clips.is_empty() && input.clips.iter().sum::<usize>() != p {
        return Err(FitError::HeldOutShape {
            what: "the training clips".into(),
            found: format!("{} poses in all", input.clips.iter().sum::<usize>()),
            expected: format!("{p} poses"),
        });
    }
    check_options(options)?;
    Ok(len0 / (input.order * input.order))
}

/// Checks the training poses and their transfer; returns the transfer's length.
fn check_training(input: &FitInput<'_>) -> Result<usize, FitError> {
    let (angles, transfers, order) = (input.angles, input.transfers, input.order);
    let p = transfers.len();
    if p == 0 && angles.nrows() == 0 {
        return Err(FitError::NoPoses);
    }
    if angles.nrows() != p {
        return Err(FitError::PoseCountMismatch {
            angles: angles.nrows(),
            transfers: p,
        });
    }
    if order == 0 {
        return Err(FitError::ZeroOrder);
    }
    let n2 = order * order;
    let len0 = transfers[0].len();
    if !len0.is_multiple_of(n2) {
        return Err(FitError::TransferLength {
            pose: 0,
            len: len0,
            expected: len0.next_multiple_of(n2),
            coefs: n2,
        });
    }
    if len0 == 0 {
        return Err(FitError::NoVertices);
    }
    for (pose, t) in transfers.iter().enumerate() {
        if t.len() != len0 {
            return Err(FitError::TransferLength {
                pose,
                len: t.len(),
                expected: len0,
                coefs: n2,
            });
        }
        if let Some(index) = t.iter().position(|x| !x.is_finite()) {
            return Err(FitError::NonFiniteTransfer { pose, index });
        }
        if let Some(joint) = angles.row(pose).iter().position(|x| !x.is_finite()) {
            return Err(FitError::NonFiniteAngle { pose, joint });
        }
        // Squares of larger angles overflow in the solvers, and the runtime could not take them.
        let largest = f64::from(f32::MAX);
        if let Some(joint) = angles.row(pose).iter().position(|x| x.abs() > largest) {
            let value = angles[(pose, joint)];
            return Err(FitError::AngleOutOfRange { pose, joint, value });
        }
    }
    Ok(len0)
}

/// Checks that the anchor or a validation clip (`what`) has the training poses' `entries`
/// and transfer length, and only finite values.
fn check_held_out(
    what: String,
    rows: &DMatrix<f64>,
    transfers: &[Vec<f32>],
    (entries, len0): (usize, usize),
) -> Result<(), FitError> {
    let found = (
        rows.ncols(),
        transfers.iter().map(Vec::len).find(|&l| l != len0),
    );
    if rows.nrows() != transfers.len() || found.0 != entries || found.1.is_some() {
        return Err(FitError::HeldOutShape {
            what,
            found: format!(
                "{} poses of {} entries, {} transfers{}",
                rows.nrows(),
                found.0,
                transfers.len(),
                found
                    .1
                    .map_or(String::new(), |l| format!(" (one of {l} values)"))
            ),
            expected: format!("{entries} entries and {len0} transfer values"),
        });
    }
    if rows.iter().any(|x| !x.is_finite()) || transfers.iter().flatten().any(|x| !x.is_finite()) {
        return Err(FitError::HeldOutShape {
            what,
            found: "a value that is not finite".into(),
            expected: "finite pose entries and transfer".into(),
        });
    }
    Ok(())
}

/// Checks a fixed α and the energy fractions.
fn check_options(options: &FitOptions) -> Result<(), FitError> {
    match options.alpha {
        Alpha::Fixed(alpha) if !(alpha.is_finite() && alpha >= 0.0) => {
            return Err(FitError::InvalidAlpha(alpha));
        }
        _ => {}
    }
    let fractions = [
        match options.pose_dims {
            Dims::Variance(f) => Some(f),
            _ => None,
        },
        match options.coef_dims {
            CoefDims::Variance(f) => Some(f),
            _ => None,
        },
    ];
    if let Some(f) = fractions
        .into_iter()
        .flatten()
        .find(|f| !(*f > 0.0 && *f <= 1.0))
    {
        return Err(FitError::InvalidFraction(f));
    }
    Ok(())
}

/// The training, anchor and validation poses as pose features, and the vertex groups on the
/// features: everything but the bound sees the features; the bound stays on the angles the
/// runtime is given.
pub(super) struct Featured {
    x: DMatrix<f64>,
    held_x: Vec<DMatrix<f64>>,
    anchor_x: Option<Vec<f64>>,
    locality: Option<Locality>,
}

impl Featured {
    /// `features` of `pinned`'s poses.
    pub fn of(pinned: &FitInput<'_>, features: &PoseFeatures) -> Self {
        Self {
            x: features.of_rows(pinned.angles),
            held_x: pinned
                .validation
                .iter()
                .map(|v| features.of_rows(v.angles))
                .collect(),
            anchor_x: pinned.anchor.map(|a| features.of(a.angles)),
            locality: pinned.locality.map(|l| Locality {
                groups: l
                    .groups
                    .iter()
                    .map(|g| EntryGroup {
                        entries: features.of_entries(&g.entries),
                        vertices: g.vertices.clone(),
                    })
                    .collect(),
            }),
        }
    }

    /// `pinned` with its poses replaced by their features.
    pub fn input<'a>(&'a self, pinned: &FitInput<'a>) -> FitInput<'a> {
        FitInput {
            angles: &self.x,
            validation: pinned
                .validation
                .iter()
                .zip(&self.held_x)
                .map(|(v, angles)| Validation { angles, ..*v })
                .collect(),
            anchor: pinned
                .anchor
                .zip(self.anchor_x.as_deref())
                .map(|(a, angles)| Anchor {
                    angles,
                    transfer: a.transfer,
                }),
            locality: self.locality.as_ref(),
            ..pinned.clone()
        }
    }
}

/// `input` with its training and validation poses replaced by `pinned`'s.
pub(super) fn with_poses<'a>(
    input: &FitInput<'a>,
    (angles, held): &'a (DMatrix<f64>, Vec<DMatrix<f64>>),
) -> FitInput<'a> {
    FitInput {
        angles,
        validation: input
            .validation
            .iter()
            .zip(held)
            .map(|(v, angles)| Validation { angles, ..*v })
            .collect(),
        ..input.clone()
    }
}
