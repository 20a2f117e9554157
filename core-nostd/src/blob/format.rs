//! The model blob layout: the single definition shared by the trainer's writer and the
//! core's reader. See `FORMAT.md` at the repository root for the byte tables.
//!
//! ```text
//! offset  size  field
//! 0       8     magic  "APRTMDL\0"
//! 8       4     format version, u32 LE
//! 12      4     header length H, u32 LE
//! 16      4     CRC-32 of the header bytes, u32 LE
//! 20      H     header, postcard-encoded `Header`
//! ...           sections, each at a multiple of SECTION_ALIGN, raw little-endian arrays
//! ```

use serde::{Deserialize, Serialize};

/// First eight bytes of every model blob.
pub const MAGIC: [u8; 8] = *b"APRTMDL\0";
/// The format version this crate reads and writes. Breaking changes bump it.
pub const VERSION: u32 = 1;
/// Bytes before the header: magic, version, header length, header CRC.
pub const PREAMBLE_LEN: usize = 20;
/// Sections start at multiples of this many bytes, so arrays can be read in place by SIMD.
pub const SECTION_ALIGN: u64 = 16;
/// Most sections a header may list.
pub const MAX_SECTIONS: usize = 16;
/// Largest header accepted; a real header is well under 200 bytes.
pub const MAX_HEADER_LEN: u32 = 1024;

/// Most entries of a pose vector (joint angles) the evaluator accepts, and most pose features
/// (the angles and their flagged cosines).
pub const MAX_POSE_LEN: usize = 512;
/// Most pose dimensions k_a after projection: room for a local model on every entry of a
/// 40-joint skeleton's rotation vectors (it keeps one dimension per entry).
pub const MAX_POSE_DIMS: usize = 128;
/// Most vertex-basis vectors k_v.
pub const MAX_COEF_DIMS: usize = 96;
/// Vertices per block of the per-vertex sections. Within a block the values are stored
/// value-major (`[value][lane]`), so one lighting weight multiplies eight vertices at once
/// and the per-frame loops vectorise with no horizontal sums. The last block is zero-padded.
pub const VERTEX_BLOCK: usize = 8;

/// Vertices rounded up to whole blocks: the per-vertex sections store this many.
pub const fn padded_vertices(vertices: usize) -> usize {
    vertices.div_ceil(VERTEX_BLOCK) * VERTEX_BLOCK
}

/// Most vertices a model may have (keeps every byte count below 2³² on 32-bit targets
/// for orders ≤ 6 and the identity basis with few pose dimensions).
pub const MAX_VERTICES: usize = 1 << 22;

/// Most bones a skinned-frame model may have.
pub const MAX_BONES: usize = 256;
/// Most lighting weights a model may need per frame: bones × row width for bone-frame models,
/// the row width for world-frame ones. The default capacity of [`LitWeights`](crate::LitWeights).
pub const MAX_LIT: usize = 16384;

/// The frame the model's transfer is expressed in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Frame {
    /// World space: one lighting vector shades every vertex.
    World,
    /// Each vertex's bone frame: transfer moves rigidly with the bone, so the model only has
    /// to learn how shadowing changes with the pose. Lighting is rotated into each bone once
    /// per frame. Every block of the per-vertex section then starts with one extra row: the
    /// bone index of each of its eight vertices, as an exact small integer.
    Bones {
        /// Number of bones.
        count: u16,
    },
}

impl Frame {
    /// The bone count: 0 for world space.
    pub const fn bones(self) -> usize {
        match self {
            Frame::World => 0,
            Frame::Bones { count } => count as usize,
        }
    }
}

/// How the vertex side of the model is represented.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Basis {
    /// A stored basis of k_v vectors over the vertices (`VertexBasis` + `Weights` sections).
    Stored,
    /// No vertex reduction, the paper's full linear model (`VertexWeights` section).
    Identity,
}

/// Element encoding of a section.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum Encoding {
    /// IEEE 754 binary32, little-endian.
    F32 = 0,
    /// IEEE 754 binary16, little-endian.
    F16 = 1,
    /// Signed bytes with one f32 scale per vector, for the per-vertex sections only
    /// ([`SectionKind::allows_i8`]): value `r` of a vertex row is `scale_r · q` with `q` the
    /// byte read as `i8`, and the scales are the [`SectionKind::RowScales`] section. The
    /// evaluator folds `scale_r` into the per-frame weight of row `r` (pose weights for a
    /// stored basis, `z'` per coefficient for the identity basis), so the per-vertex loops
    /// read the bytes in place and pay nothing for the scale. In a bone-frame model the lead
    /// row of every block holds the eight bone indices as unsigned bytes.
    I8 = 2,
}

impl Encoding {
    /// Decodes the tag stored in a section entry.
    pub const fn from_tag(tag: u8) -> Option<Encoding> {
        match tag {
            0 => Some(Encoding::F32),
            1 => Some(Encoding::F16),
            2 => Some(Encoding::I8),
            _ => None,
        }
    }

    /// Bytes per element.
    pub const fn size(self) -> usize {
        match self {
            Encoding::F32 => 4,
            Encoding::F16 => 2,
            Encoding::I8 => 1,
        }
    }
}

/// What a section holds, from its tag in the section table. Tags this version does not know
/// are [`SectionKind::Unknown`]: skipped when the entry is optional, refused when required.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum SectionKind {
    /// Tag 1. Mean pose features μ: `feature_len` values, f32 (`feature_len` is `pose_len`
    /// plus the entries flagged in [`SectionKind::PoseFeatures`]).
    PoseMean,
    /// Tag 2. Pose projection P: `pose_dims × feature_len` row-major, f32.
    PoseProjection,
    /// Tag 3, stored basis only: `n² × (1 + pose_dims) × coef_dims`; `[c][0][k]` is the
    /// intercept.
    Weights,
    /// Tag 4, stored basis only: U, `coef_dims` values per vertex, in blocks of
    /// [`VERTEX_BLOCK`] vertices: value `(j, k)` at `(j / 8) · 8 k_v + 8 k + j % 8`.
    VertexBasis,
    /// Tag 5, identity basis only: `n² × (1 + pose_dims)` values `(c, i)` per vertex, blocked
    /// like `VertexBasis` with row index `r = c (1 + k_a) + i`.
    VertexWeights,
    /// Tag 6, optional: the names of the pose vector's entries, UTF-8, one `\n`-terminated
    /// non-empty name per entry (`pose_len` lines), so an engine can bind its joints by name.
    AngleNames,
    /// Tag 7, optional for the writer, required once written: the pose bound, `4 × pose_len`
    /// f32 rows `lo`, `hi`, `scale`, `prior`. A pose is clamped into `[lo, hi]` per entry and
    /// blended towards `prior` by `β = max(0, 1 − d)`, `d² = Σ ((a − clamp(a)) · scale)²`, so a
    /// pose far outside the training poses gets the prior's transfer (see
    /// [`Model::set_pose`](crate::Model::set_pose)). `lo ≤ prior ≤ hi`, `scale ≥ 0`.
    PoseBounds,
    /// Tag 8, optional for the writer, required once written: the pose features, `pose_len`
    /// f32 flags, each 0 or 1. The projection sees the bounded angles `a`, then `1 − cos a_i`
    /// for each flagged entry i in order: an even feature, for occlusion that is the same
    /// whichever way a joint turns, which a model linear in the angles cannot represent.
    /// Without this section the features are the angles.
    PoseFeatures,
    /// Tag 9, optional: an irradiance rig fitted to the character (*Irradiance Rigs*), its
    /// own little layout of a 16-byte prelude and f32 arrays, described and validated by
    /// [`IrradianceRig`](crate::IrradianceRig). Readers that predate it skip it.
    IrradianceRig,
    /// Tag 10, optional: the texel atlas of a light-map model, whose rows are the texels of
    /// an R × R map: R (`u32`), then each row's texel index `y · R + x` (`u32`, strictly
    /// increasing, below R²), so an engine can scatter the rows into the map. Read by
    /// [`TexelAtlas`](crate::TexelAtlas); readers that predate it skip it.
    TexelAtlas,
    /// Tag 11, required with an [`Encoding::I8`] per-vertex section (and only read then):
    /// one f32 scale per value of a vertex row (`row_width` values, finite; the writer stores
    /// `max_j |v_jr| / 127`, 0 for a zero vector), so the row `r` of vertex `j` is
    /// `scale_r · q_jr`.
    RowScales,
    /// Tag 12, optional for the writer, required once written: occluder proxies, spheres that
    /// move with the bones and occlude the vertices of other parts (bone-frame models only);
    /// the model's transfer is then `model(pose) − occlusion(pose)`, so a reader that does
    /// not subtract the occlusion must refuse the model. Its own little layout, described and
    /// validated in `proxies/section.rs` (FORMAT.md).
    Proxies,
    /// A tag this version does not know.
    Unknown(u16),
}

impl SectionKind {
    /// The kinds this version knows, in tag order.
    const KNOWN: [SectionKind; 12] = [
        SectionKind::PoseMean,
        SectionKind::PoseProjection,
        SectionKind::Weights,
        SectionKind::VertexBasis,
        SectionKind::VertexWeights,
        SectionKind::AngleNames,
        SectionKind::PoseBounds,
        SectionKind::PoseFeatures,
        SectionKind::IrradianceRig,
        SectionKind::TexelAtlas,
        SectionKind::RowScales,
        SectionKind::Proxies,
    ];

    /// The kind of a section-table tag.
    pub const fn from_tag(tag: u16) -> SectionKind {
        match tag {
            1..=12 => Self::KNOWN[tag as usize - 1],
            other => SectionKind::Unknown(other),
        }
    }

    /// The tag written in the section table.
    pub const fn tag(self) -> u16 {
        match self {
            SectionKind::PoseMean => 1,
            SectionKind::PoseProjection => 2,
            SectionKind::Weights => 3,
            SectionKind::VertexBasis => 4,
            SectionKind::VertexWeights => 5,
            SectionKind::AngleNames => 6,
            SectionKind::PoseBounds => 7,
            SectionKind::PoseFeatures => 8,
            SectionKind::IrradianceRig => 9,
            SectionKind::TexelAtlas => 10,
            SectionKind::RowScales => 11,
            SectionKind::Proxies => 12,
            SectionKind::Unknown(tag) => tag,
        }
    }

    /// Index among the known kinds (for duplicate detection), `None` for unknown tags.
    pub(crate) const fn known_index(self) -> Option<usize> {
        match self {
            SectionKind::Unknown(_) => None,
            known => Some(known.tag() as usize - 1),
        }
    }

    /// Number of known kinds.
    pub(crate) const KNOWN_COUNT: usize = Self::KNOWN.len();

    /// Whether the kind may be stored in half precision (the big per-vertex arrays and weights).
    pub const fn allows_f16(self) -> bool {
        matches!(
            self,
            SectionKind::Weights | SectionKind::VertexBasis | SectionKind::VertexWeights
        )
    }

    /// Whether the kind may be stored as scaled bytes ([`Encoding::I8`]): the per-vertex
    /// sections, whose bytes are most of a blob and are read every frame. The weights stay
    /// f32 or f16: they are read once per frame and do not grow with the vertex count.
    pub const fn allows_i8(self) -> bool {
        matches!(self, SectionKind::VertexBasis | SectionKind::VertexWeights)
    }

    /// Whether a section of this kind may be stored in `encoding`.
    pub const fn allows(self, encoding: Encoding) -> bool {
        match encoding {
            Encoding::F32 => true,
            Encoding::F16 => self.allows_f16(),
            Encoding::I8 => self.allows_i8(),
        }
    }
}

impl core::fmt::Display for SectionKind {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            SectionKind::Unknown(tag) => write!(f, "unknown section kind {tag}"),
            known => write!(f, "{known:?}"),
        }
    }
}

/// One entry of the section table.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct SectionEntry {
    /// [`SectionKind::tag`], or a newer kind's tag.
    pub kind: u16,
    /// Readers that do not know `kind` must reject the blob when set, skip it otherwise.
    pub required: bool,
    /// [`Encoding`] tag.
    pub encoding: u8,
    /// Byte offset from the start of the blob; a multiple of [`SECTION_ALIGN`].
    pub offset: u64,
    /// Byte length.
    pub len: u64,
    /// CRC-32 (IEEE) of the section bytes.
    pub crc32: u32,
}

/// The postcard-encoded header.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Header {
    /// SH order n.
    pub order: u8,
    /// Vertex count v.
    pub vertices: u32,
    /// Entries of the pose vector a (joint angles).
    pub pose_len: u16,
    /// Pose dimensions k_a (0 allowed: an intercept-only model).
    pub pose_dims: u16,
    /// Vertex-basis dimensions k_v (equals `vertices` for the identity basis).
    pub coef_dims: u32,
    /// Vertex side representation.
    pub basis: Basis,
    /// The frame transfer is expressed in.
    pub frame: Frame,
    /// The Tikhonov parameter the fit chose (informational).
    pub alpha: f32,
    /// The section table.
    pub sections: heapless::Vec<SectionEntry, MAX_SECTIONS>,
}

/// Rounds `x` up to the next multiple of [`SECTION_ALIGN`], `None` on overflow.
#[cfg_attr(not(feature = "format"), allow(dead_code))]
pub const fn align_up(x: u64) -> Option<u64> {
    match x.checked_add(SECTION_ALIGN - 1) {
        Some(y) => Some(y / SECTION_ALIGN * SECTION_ALIGN),
        None => None,
    }
}

/// CRC-32 (IEEE 802.3) of `bytes`, the checksum of headers and sections.
pub fn crc32(bytes: &[u8]) -> u32 {
    crc32fast::hash(bytes)
}
