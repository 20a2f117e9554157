//! The per-frame state a caller owns: pose weights and lighting weights. Both are plain
//! fixed-size arrays with a `const fn` constructor, so they can live in a `static`, on the
//! heap or on the stack, and a capacity parameter sizes them for the models an engine loads.

use crate::blob::format::{MAX_COEF_DIMS, MAX_LIT, MAX_POSE_DIMS};
use crate::blob::{Error, ModelInfo};
use crate::sh::MAX_COEFFS;

/// Values of the largest pose weights any model needs at the limits: n² k_v for a stored
/// basis, n²(1 + k_a) for an identity basis with scaled-byte rows.
pub const MAX_POSE_WEIGHTS: usize = if MAX_COEF_DIMS > MAX_POSE_DIMS + 1 {
    MAX_COEFFS * MAX_COEF_DIMS
} else {
    MAX_COEFFS * (MAX_POSE_DIMS + 1)
};

/// The model a set of weights was computed for.
pub(crate) type Stamp = Option<u32>;

/// Checks that weights stamped `stamp` belong to `info`.
pub(crate) fn check_stamp(stamp: Stamp, info: &ModelInfo) -> Result<(), Error> {
    match stamp {
        None => Err(Error::WeightsNotSet),
        Some(id) if id != info.id => Err(Error::WeightsForOtherModel),
        Some(_) => Ok(()),
    }
}

/// Checks that a capacity of `capacity` values holds the `needed` ones of a model.
pub(crate) fn check_capacity(needed: usize, capacity: usize) -> Result<(), Error> {
    if needed > capacity {
        return Err(Error::WeightsTooSmall { needed, capacity });
    }
    Ok(())
}

/// The pose state of one frame: the projected pose `z' = [1, P(a − μ)]` and, for a stored
/// basis, the per-coefficient weights `w^c = W^c z'` (times each basis vector's scale for
/// scaled-byte rows; for an identity basis with such rows, `z'` times each row's scale). Filled by `set_pose`, read by `light`
/// and `transfer`, stamped with the model it was computed for.
///
/// `N` is the capacity in values; the default holds any model (about 18 KiB), and
/// [`ModelInfo::pose_weights_len`] tells what a given model needs.
///
/// ```
/// use aprt_core::{Error, Model, PoseWeights};
///
/// // `new` is a `const fn`: an engine can build the state at compile time in a static of its
/// // own, behind whatever lock it uses, so the 18 KiB never sit on the stack.
/// struct Character {
///     pose: PoseWeights,
/// }
/// const AT_START: Character = Character { pose: PoseWeights::new() };
///
/// let model = Model::parse(include_bytes!("../../../fixtures/golden/v1-world.aprt"))?;
/// let mut hero = AT_START;
/// model.set_pose(&[0.0; 4], &mut hero.pose)?;
///
/// // Sized for the model: 9 coefficients × 3 basis vectors.
/// assert_eq!(model.info().pose_weights_len(), 27);
/// let mut small = PoseWeights::<27>::sized();
/// model.set_pose(&[0.0; 4], &mut small)?;
/// let mut tiny = PoseWeights::<8>::sized();
/// assert_eq!(
///     model.set_pose(&[0.0; 4], &mut tiny),
///     Err(Error::WeightsTooSmall { needed: 27, capacity: 8 })
/// );
/// # Ok::<(), Error>(())
/// ```
#[derive(Clone, Debug)]
pub struct PoseWeights<const N: usize = MAX_POSE_WEIGHTS> {
    pub(crate) stamp: Stamp,
    /// k_a of the model it was computed for.
    pub(crate) pose_dims: usize,
    /// `z' = [1, z]`.
    pub(crate) z: [f32; MAX_POSE_DIMS + 1],
    /// Stored basis: `w[k * n² + c]`, coefficient-contiguous so transfer is a sum of vectors.
    /// Identity basis with scaled-byte rows: `w[c (1 + k_a) + i] = z'_i scale_{c (1 + k_a) + i}`.
    pub(crate) w: [f32; N],
}

impl PoseWeights {
    /// Empty weights that hold any model, usable in a `static`.
    pub const fn new() -> Self {
        Self::sized()
    }
}

impl<const N: usize> PoseWeights<N> {
    /// Empty weights of capacity `N`, usable in a `static`:
    /// `PoseWeights::<{ 9 * 22 }>::sized()` holds an order-3 model with k_v = 22.
    pub const fn sized() -> Self {
        PoseWeights {
            stamp: None,
            pose_dims: 0,
            z: [0.0; MAX_POSE_DIMS + 1],
            w: [0.0; N],
        }
    }

    /// The projected pose `z` (k_a values) of the last successful `set_pose`; empty before.
    pub fn projected(&self) -> &[f32] {
        match self.stamp {
            Some(_) => self.z.get(1..=self.pose_dims).unwrap_or(&[]),
            None => &[],
        }
    }
}

impl<const N: usize> Default for PoseWeights<N> {
    fn default() -> Self {
        Self::sized()
    }
}

/// Lighting pushed through the pose weights: one weight per value of a vertex row, per bone
/// for bone-frame models. Filled by `light`, read by `shade`.
///
/// `N` is the capacity in values; the default, [`MAX_LIT`], holds any model (64 KiB) and
/// [`ModelInfo::lit_weights_len`] tells what a given model needs (a world-frame PCA(8, 22)
/// model: 22).
///
/// ```
/// use aprt_core::{LitWeights, Model, PoseWeights};
///
/// let model = Model::parse(include_bytes!("../../../fixtures/golden/v1-bones.aprt"))?;
/// // 3 bones × 4 basis vectors.
/// assert_eq!(model.info().lit_weights_len(), 12);
/// let (mut pose, mut lit) = (PoseWeights::new(), LitWeights::<12>::sized());
/// model.set_pose(&[0.0; 5], &mut pose)?;
/// let identity = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
/// model.light(&pose, &[1.0; 9], &[identity; 3], &mut lit)?;
/// # Ok::<(), aprt_core::Error>(())
/// ```
#[derive(Clone, Debug)]
pub struct LitWeights<const N: usize = MAX_LIT> {
    pub(crate) stamp: Stamp,
    pub(crate) q: [f32; N],
}

impl LitWeights {
    /// Empty weights that hold any model, usable in a `static`.
    pub const fn new() -> Self {
        Self::sized()
    }
}

impl<const N: usize> LitWeights<N> {
    /// Empty weights of capacity `N`, usable in a `static`: `LitWeights::<22>::sized()` holds
    /// a world-frame model with k_v = 22.
    pub const fn sized() -> Self {
        LitWeights {
            stamp: None,
            q: [0.0; N],
        }
    }
}

impl<const N: usize> Default for LitWeights<N> {
    fn default() -> Self {
        Self::sized()
    }
}
