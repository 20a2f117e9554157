//! What a validated blob holds: its dimensions, its identity, and where its arrays are.

use super::format::{Basis, Encoding, Frame, VERTEX_BLOCK};
use crate::sh::coeff_count;

/// Where one validated section lives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Span {
    /// Byte offset in the blob.
    pub(crate) offset: u64,
    /// Byte length.
    pub(crate) len: u64,
    /// Element encoding.
    pub(crate) encoding: Encoding,
}

/// A validated model's dimensions and layout, shared by [`Model`](crate::Model) and
/// [`StreamedModel`](crate::StreamedModel). Small and `Copy`; the arrays stay in the blob.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModelInfo {
    pub(crate) id: u32,
    pub(crate) order: usize,
    pub(crate) vertices: usize,
    pub(crate) pose_len: usize,
    /// The angles and their flagged cosines: what the mean and the projection are over.
    pub(crate) feature_len: usize,
    pub(crate) pose_dims: usize,
    pub(crate) coef_dims: usize,
    pub(crate) basis: Basis,
    pub(crate) frame: Frame,
    pub(crate) alpha: f32,
    pub(crate) pose_mean: Span,
    pub(crate) pose_projection: Span,
    /// Stored basis: the `n² × (1 + k_a) × k_v` weights; identity basis: unused.
    pub(crate) weights: Option<Span>,
    /// Per-vertex rows: the vertex basis (stored) or the vertex weights (identity).
    pub(crate) rows: Span,
    /// The scale of each row value, when the rows are [`Encoding::I8`].
    pub(crate) row_scales: Option<Span>,
    pub(crate) angle_names: Option<Span>,
    /// The pose bound, when the model has one.
    pub(crate) pose_bounds: Option<Span>,
    /// The flags of the entries whose cosine is a feature, when any is.
    pub(crate) pose_features: Option<Span>,
    /// The irradiance rig, when the model has one (its bytes checksummed at open, its
    /// contents validated by [`IrradianceRig::parse`](crate::IrradianceRig::parse)).
    pub(crate) irradiance_rig: Option<Span>,
    /// The texel of every row of a light-map model, when the model has one (validated at
    /// open).
    pub(crate) texel_atlas: Option<Span>,
    /// The occluder proxies, when the model has them (validated at open).
    pub(crate) proxies: Option<Span>,
}

impl ModelInfo {
    /// The model's identity: the CRC-32 of its header, which covers every dimension and every
    /// section's CRC. Pose and lighting weights are stamped with it, so weights computed for
    /// one model are refused by another, even of the same shape.
    pub fn id(&self) -> u32 {
        self.id
    }
    /// SH order n (bands `0..n`).
    pub fn order(&self) -> usize {
        self.order
    }
    /// SH coefficients n² of the lighting and of each vertex's transfer.
    pub fn coeffs(&self) -> usize {
        coeff_count(self.order)
    }
    /// Vertex count v.
    pub fn vertices(&self) -> usize {
        self.vertices
    }
    /// Entries of the pose vector a (see [`Model::set_pose`](crate::Model::set_pose)).
    pub fn pose_len(&self) -> usize {
        self.pose_len
    }
    /// Pose features the projection sees: the `pose_len` angles, then the cosine features of
    /// the flagged entries (see [`SectionKind::PoseFeatures`](crate::SectionKind)).
    pub fn feature_len(&self) -> usize {
        self.feature_len
    }
    /// Pose dimensions k_a after projection.
    pub fn pose_dims(&self) -> usize {
        self.pose_dims
    }
    /// Vertex-basis dimensions k_v (`vertices` for the identity basis).
    pub fn coef_dims(&self) -> usize {
        self.coef_dims
    }
    /// Vertex side representation.
    pub fn basis(&self) -> Basis {
        self.basis
    }
    /// The frame transfer is expressed in.
    pub fn frame(&self) -> Frame {
        self.frame
    }
    /// Bone rotations the model's lighting needs per frame: the bone count of a bone-frame
    /// model, 0 for a world-frame one.
    pub fn bones(&self) -> usize {
        self.frame.bones()
    }
    /// The fit's Tikhonov parameter.
    pub fn alpha(&self) -> f32 {
        self.alpha
    }
    /// Encoding of the per-vertex rows.
    pub fn encoding(&self) -> Encoding {
        self.rows.encoding
    }

    /// Values per streamed vertex row: k_v (stored basis) or n²(1 + k_a) (identity basis).
    pub fn row_width(&self) -> usize {
        match self.basis {
            Basis::Stored => self.coef_dims,
            Basis::Identity => coeff_count(self.order) * (1 + self.pose_dims),
        }
    }

    /// Values [`PoseWeights`](crate::PoseWeights) must hold for this model: n² k_v for a
    /// stored basis; for the identity basis 0 (its pose weights are the projected pose), or
    /// n²(1 + k_a) with [`Encoding::I8`] rows (the projected pose times each row's scale).
    pub fn pose_weights_len(&self) -> usize {
        match (self.basis, self.row_scales) {
            (Basis::Stored, _) => coeff_count(self.order) * self.coef_dims,
            (Basis::Identity, None) => 0,
            (Basis::Identity, Some(_)) => self.row_width(),
        }
    }

    /// Values [`LitWeights`](crate::LitWeights) must hold for this model: one row width of
    /// weights per bone (one in all for a world-frame model).
    pub fn lit_weights_len(&self) -> usize {
        self.row_width() * self.bones().max(1)
    }

    /// Bytes of scratch a [`StreamedModel`](crate::StreamedModel) needs: one block of
    /// [`VERTEX_BLOCK`] vertex rows, or one row of the small sections if that is longer.
    pub fn scratch_bytes(&self) -> usize {
        let weights_row = self
            .weights
            .map_or(0, |w| self.coef_dims * w.encoding.size());
        self.block_bytes()
            .max(self.feature_len * Encoding::F32.size())
            .max(weights_row)
    }

    /// Whether poses are bounded: clamped into the training box and blended towards the
    /// prior outside it (see [`Model::set_pose`](crate::Model::set_pose)).
    pub fn bounded(&self) -> bool {
        self.pose_bounds.is_some()
    }

    /// Bytes of the angle-names section (0 when the blob records none): the buffer
    /// [`StreamedModel::angle_names`](crate::StreamedModel::angle_names) needs.
    pub fn angle_names_bytes(&self) -> usize {
        self.angle_names.map_or(0, |s| s.len as usize)
    }

    /// Bytes of the model's irradiance rig (0 without one): what
    /// [`StreamedModel::irradiance_rig`](crate::StreamedModel::irradiance_rig) reads it into.
    pub fn irradiance_rig_bytes(&self) -> usize {
        self.irradiance_rig.map_or(0, |s| s.len as usize)
    }

    /// Bytes of the model's texel atlas (0 without one): what
    /// [`StreamedModel::texel_atlas`](crate::StreamedModel::texel_atlas) reads it into.
    pub fn texel_atlas_bytes(&self) -> usize {
        self.texel_atlas.map_or(0, |s| s.len as usize)
    }

    /// Extra leading rows per block: 1 (the bone indices) for bone-frame models, else 0.
    pub(crate) fn lead_rows(&self) -> usize {
        match self.frame {
            Frame::World => 0,
            Frame::Bones { .. } => 1,
        }
    }

    /// Bytes of one streamed block of [`VERTEX_BLOCK`] vertex rows, the unit of streaming.
    pub(crate) fn block_bytes(&self) -> usize {
        VERTEX_BLOCK * (self.lead_rows() + self.row_width()) * self.rows.encoding.size()
    }
}
