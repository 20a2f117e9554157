//! The fitted pose-driven linear PRT model in trainer precision (f64), before quantisation.
//!
//! Runtime semantics, shared with `aprt-core`'s evaluator:
//! `z = P (φ(a) − μ)` (k_a values, over the pose features φ: the angles and, for the entries
//! the model flags, `1 − cos a`), `z' = [1, z]`, per SH coefficient `c`:
//! `w^c_k = Σ_i z'_i W[c][i][k]`, and per vertex `j`: `t_jc = Σ_k w^c_k U[j][k]` with a stored
//! vertex basis, or `t_jc = w^c_j` with the identity basis (the full linear model, `k_v = v`).
//!
//! [`fit`] learns it from poses and baked transfer, [`export`] quantises it into a blob, and
//! [`runtime`] evaluates a written blob through `aprt-core`. [`proxies`] fits occluder spheres
//! per bone to the parts of the bind mesh, for the runtime's shadows between parts, and
//! [`locality`] finds which pose entries can shadow each vertex.

pub mod export;
pub mod features;
pub mod fit;
pub mod locality;
pub mod occluders;
pub mod precision;
pub mod predict;
pub mod proxies;
pub mod runtime;

use features::PoseFeatures;

use crate::rig::bone_frames::BoneFrames;

/// The vertex side of the model.
#[derive(Clone, Debug, PartialEq)]
pub enum VertexBasis {
    /// No reduction: the weights are per-vertex transfer directly (`k_v = v`).
    Identity,
    /// `coef_dims` orthonormal basis vectors over vertices, stored vertex-major: `data[j * coef_dims + k]`.
    Stored {
        /// k_v, the number of basis vectors.
        coef_dims: usize,
        /// `v × k_v` values, vertex-major.
        data: Vec<f64>,
    },
}

/// The frame a model learns each vertex's transfer in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ModelFrame {
    /// The frame of the vertex's most influential bone: rigid limb motion needs no learning, at
    /// the cost of rotating the lighting into every bone at runtime.
    Bone,
    /// World space: no bone rotations at runtime.
    World,
}

/// The pose bound of a model, in the runtime's form (aprt-core's `PoseBounds` section): each
/// entry clamped into `[lo, hi]`, then the pose blended towards `prior` by
/// `β = max(0, 1 − ‖(a − clamp(a)) · scale‖)`.
#[derive(Clone, Debug, PartialEq)]
pub struct PoseBounds {
    /// Lowest value of each entry over the training poses and the prior's pose.
    pub lo: Vec<f64>,
    /// Highest value of each entry.
    pub hi: Vec<f64>,
    /// `1 / (falloff · width)` per entry (0: clamped only).
    pub scale: Vec<f64>,
    /// The prior's pose: the rest pose, or the mean pose.
    pub prior: Vec<f64>,
}

impl PoseBounds {
    /// The bound of the training poses `angles` (`p × a`) and the prior's pose, reaching the
    /// prior `falloff` widths outside the box (infinite: clamped only). An entry's width is
    /// its range, but at least the mean range of all entries: an entry that barely moved in
    /// training does not make the smallest turn of its joint a distant pose.
    pub fn of(angles: &nalgebra::DMatrix<f64>, prior: &[f64], falloff: f64) -> Self {
        let a = angles.ncols();
        let lo: Vec<f64> = (0..a)
            .map(|j| angles.column(j).iter().fold(prior[j], |m, &x| m.min(x)))
            .collect();
        let hi: Vec<f64> = (0..a)
            .map(|j| angles.column(j).iter().fold(prior[j], |m, &x| m.max(x)))
            .collect();
        let widths: Vec<f64> = lo.iter().zip(&hi).map(|(l, h)| h - l).collect();
        let floor = widths.iter().sum::<f64>() / a.max(1) as f64;
        let scale = widths
            .iter()
            .map(|&w| {
                let w = w.max(floor);
                if falloff.is_finite() && w > 0.0 {
                    1.0 / (falloff * w)
                } else {
                    0.0
                }
            })
            .collect();
        Self {
            lo,
            hi,
            scale,
            prior: prior.to_vec(),
        }
    }

    /// The bound with `entries` held at the prior's value and left out of the blend factor
    /// (scale 0): entries that move no geometry relative to its neighbours (a root turn, for
    /// bone-frame models) cannot change the transfer, so whatever a model learnt from them
    /// is chance, and they must not pull the pose towards the prior either.
    pub fn ignoring(mut self, entries: impl IntoIterator<Item = usize>) -> Self {
        for entry in entries {
            self.lo[entry] = self.prior[entry];
            self.hi[entry] = self.prior[entry];
            self.scale[entry] = 0.0;
        }
        self
    }

    /// The bounded pose, in f64 (the reference of aprt-core's f32 evaluation).
    pub fn apply(&self, angles: &[f64]) -> Vec<f64> {
        let clamped: Vec<f64> = angles
            .iter()
            .zip(self.lo.iter().zip(&self.hi))
            .map(|(x, (lo, hi))| x.max(*lo).min(*hi))
            .collect();
        let d = angles
            .iter()
            .zip(&clamped)
            .zip(&self.scale)
            .map(|((x, c), s)| ((x - c) * s).powi(2))
            .sum::<f64>()
            .sqrt();
        let beta = (1.0 - d).max(0.0);
        clamped
            .iter()
            .zip(&self.prior)
            .map(|(c, p)| p + beta * (c - p))
            .collect()
    }

    /// The four rows as the blob stores them: lo, hi, scale, prior.
    pub fn rows(&self) -> Vec<f64> {
        [&self.lo, &self.hi, &self.scale, &self.prior]
            .into_iter()
            .flatten()
            .copied()
            .collect()
    }
}

/// A fitted model: everything the blob stores, in f64.
#[derive(Clone, Debug, PartialEq)]
pub struct LinearModel {
    /// SH order n (n² coefficients per vertex).
    pub order: usize,
    /// Number of mesh vertices v.
    pub vertices: usize,
    /// Length a of the pose vector: entries per pose (joint angles, rotation-vector components).
    pub pose_len: usize,
    /// Mean pose features μ ([`LinearModel::feature_len`] values).
    pub pose_mean: Vec<f64>,
    /// Pose projection P, `k_a × f` row-major over the f pose features.
    pub pose_projection: Vec<f64>,
    /// `n² × (1 + k_a) × k_v` weights; entry `[c][0][k]` is the unpenalised intercept.
    pub weights: Vec<f64>,
    /// The vertex basis.
    pub basis: VertexBasis,
    /// The Tikhonov parameter the fit used.
    pub alpha: f64,
    /// `None`: transfer in world space; otherwise in each vertex's bone frame, and
    /// [`LinearModel::predict`] gives bone-frame transfer.
    pub bones: Option<BoneFrames>,
    /// Names of the `pose_len` pose entries, so tools can map a clip onto the model's pose
    /// vector; empty when the source had none (an unnamed angle CSV).
    pub angle_names: Vec<String>,
    /// The pose bound; `None`: the paper's unbounded linear model.
    pub bounds: Option<PoseBounds>,
    /// Per pose entry, whether `1 − cos a` is a pose feature besides `a` (see
    /// [`PoseFeatures`]); empty or all false: the features are the angles, as in the paper.
    pub cosines: Vec<bool>,
    /// Occluder proxies (the `Proxies` section's bytes, [`occluders`]): the model was fitted
    /// to its transfer plus their occlusion, which the runtime subtracts. Bone-frame models
    /// only; `None`: none.
    pub proxies: Option<Vec<u8>>,
}

impl LinearModel {
    /// k_a, the pose dimensions after projection.
    pub fn pose_dims(&self) -> usize {
        self.pose_projection
            .len()
            .checked_div(self.feature_len())
            .unwrap_or(0)
    }

    /// The pose features the projection sees: the angles and their flagged cosines.
    pub fn features(&self) -> PoseFeatures {
        PoseFeatures::new(self.pose_len, &self.cosines)
    }

    /// f, the number of pose features.
    pub fn feature_len(&self) -> usize {
        self.features().count()
    }

    /// k_v, the number of vertex basis vectors (`v` for the identity basis).
    pub fn coef_dims(&self) -> usize {
        match &self.basis {
            VertexBasis::Identity => self.vertices,
            VertexBasis::Stored { coef_dims, .. } => *coef_dims,
        }
    }

    /// Reference prediction in f64: per-vertex transfer, `v × n²` vertex-major.
    pub fn predict(&self, angles: &[f64]) -> Vec<f64> {
        let (f, ka, kv, n2) = (
            self.feature_len(),
            self.pose_dims(),
            self.coef_dims(),
            self.order * self.order,
        );
        let bounded = self.bounds.as_ref().map(|b| b.apply(angles));
        let x = self.features().of(bounded.as_deref().unwrap_or(angles));
        let mut z = vec![1.0; ka + 1];
        for (i, zi) in z[1..].iter_mut().enumerate() {
            *zi = (0..f)
                .map(|j| self.pose_projection[i * f + j] * (x[j] - self.pose_mean[j]))
                .sum();
        }
        let mut w = vec![0.0; n2 * kv];
        for c in 0..n2 {
            for (i, zi) in z.iter().enumerate() {
                let row = &self.weights[(c * (ka + 1) + i) * kv..][..kv];
                for (wk, x) in w[c * kv..(c + 1) * kv].iter_mut().zip(row) {
                    *wk += zi * x;
                }
            }
        }
        let mut t = vec![0.0; self.vertices * n2];
        for j in 0..self.vertices {
            for c in 0..n2 {
                t[j * n2 + c] = match &self.basis {
                    VertexBasis::Identity => w[c * kv + j],
                    VertexBasis::Stored { data, .. } => {
                        (0..kv).map(|k| w[c * kv + k] * data[j * kv + k]).sum()
                    }
                };
            }
        }
        t
    }
}
