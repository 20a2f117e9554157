//! Irradiance rigs (Yuan, Nowrouzezahrai and Sloan, *Irradiance Rigs*): SH lighting that
//! varies over a large character, as a handful of SH vectors `C_k` weighted by basis
//! functions of position, `l(p) = Σ_k φ_k(p) C_k`.
//!
//! The trainer fits a rig to the character's surface by least squares (the paper's section
//! 2.2): the rig stores N sample points in the character's root frame and the matrix `L`
//! (K × N) that maps the lighting sampled there to the K vectors, `C = L · l(samples)`. Per
//! frame an engine projects its lights at the N points (the root's placement moves them into
//! the world) and gets K SH vectors: what a GPU shader takes as uniforms. Lighting at any
//! point is then a sum of at most [`RIG_SUPPORT`] of them.
//!
//! The rig also carries the error table of the paper's section 3.1: the worst shading error
//! it makes, in 8-bit grey levels per unit of light strength, against normalised distance
//! from its centre. [`IrradianceRig::share_of`] turns it into the per-light choice between
//! the rig and per-vertex (analytic) evaluation, blended over a band so nothing pops.

mod check;
mod section;
mod shape;
mod split;

pub use check::{MAX_RIG_SAMPLES, MAX_RIG_TABLE};
pub(crate) use check::{RigCheck, RigFailure};
pub use section::{IrradianceRig, RigLayout};
pub use shape::{AxisKind, MAX_LATTICE, MAX_RIG_VECTORS, RIG_SUPPORT, RigShape, RigWeights};
pub use split::{DEFAULT_BAND, light_strength};

/// Where the character's root frame is in the world this frame: `world = rotation · p +
/// translation`, the rotation row-major and orthonormal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    /// Root → world rotation, row-major.
    pub rotation: [[f32; 3]; 3],
    /// The root's origin in the world.
    pub translation: [f32; 3],
}

impl Placement {
    /// The root frame is the world frame.
    pub const IDENTITY: Placement = Placement {
        rotation: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        translation: [0.0; 3],
    };

    /// A root-frame point in the world.
    pub fn to_world(&self, p: [f32; 3]) -> [f32; 3] {
        let r = &self.rotation;
        core::array::from_fn(|i| {
            r[i][0] * p[0] + r[i][1] * p[1] + r[i][2] * p[2] + self.translation[i]
        })
    }

    /// A world point in the root frame (the rotation's transpose).
    pub fn to_root(&self, p: [f32; 3]) -> [f32; 3] {
        let d: [f32; 3] = core::array::from_fn(|i| p[i] - self.translation[i]);
        let r = &self.rotation;
        core::array::from_fn(|j| r[0][j] * d[0] + r[1][j] * d[1] + r[2][j] * d[2])
    }
}

/// Lighting weights of a rig-lit frame: the rig's K SH vectors, per colour channel, pushed
/// through the pose weights (and each bone's rotation). Filled by
/// [`Model::light_rig`](crate::Model::light_rig), read by
/// [`Model::shade_rig`](crate::Model::shade_rig).
///
/// The values live in a buffer the caller lends (a `static` array, a heap allocation):
/// [`ModelInfo::rig_lit_weights_len`](crate::ModelInfo::rig_lit_weights_len) tells how many a
/// model and rig need, 3 K times what [`LitWeights`](crate::LitWeights) holds, which for a
/// 64-vector lattice on a 30-bone model is too much for a stack.
#[derive(Debug)]
pub struct RigLitWeights<'a> {
    pub(crate) stamp: Option<u32>,
    /// The rig's vector count K the weights were computed for.
    pub(crate) vectors: usize,
    /// `q[(k · 3 + channel) · lit_len + bone · width + i]`.
    pub(crate) q: &'a mut [f32],
}

impl<'a> RigLitWeights<'a> {
    /// Empty weights over `buffer`.
    pub fn new(buffer: &'a mut [f32]) -> Self {
        RigLitWeights {
            stamp: None,
            vectors: 0,
            q: buffer,
        }
    }
}
