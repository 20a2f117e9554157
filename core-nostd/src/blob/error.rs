//! The one error type of the core: small, `Copy`, no heap payload, one variant per way a blob
//! or a call can be wrong, each saying where.

use super::format::{MAX_POSE_LEN, SectionKind, VERSION};
use crate::light::LightError;

/// Which header dimension was out of range.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Dim {
    /// SH order (1..=6).
    Order,
    /// Vertex count.
    Vertices,
    /// Entries of the pose vector.
    PoseLen,
    /// Pose dimensions k_a after projection.
    PoseDims,
    /// Vertex-basis dimensions k_v.
    CoefDims,
    /// Bones of a bone-frame model.
    Bones,
}

/// Which slice argument of a call had the wrong length.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Input {
    /// The pose vector of `set_pose`.
    Angles,
    /// The SH lighting of `light` (n² values).
    Lighting,
    /// The bone rotations of `light` (one per bone of a bone-frame model).
    BoneRotations,
    /// The output of `transfer` (n² values per vertex).
    Transfer,
    /// The rig vectors of `light_rig` (K n² RGB values).
    RigVectors,
    /// The vertex positions of `shade_rig` and `shade_lights` (one per vertex shaded).
    Positions,
    /// The per-light weights of `shade_lights` (one per light).
    LightWeights,
    /// The decoded light maps of [`LightMap`](crate::LightMap)'s calls (n² values per texel
    /// of the chunk).
    LightMap,
    /// The R × R map [`TexelAtlas::scatter`](crate::TexelAtlas::scatter) writes into.
    AtlasMap,
    /// The bones' skinning matrices of `pose_proxies` (one per bone).
    Skinning,
    /// The vertex normals of `occlude` and `occlude_transfer` (one per vertex).
    Normals,
}

/// Everything that can go wrong reading a blob or evaluating a model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Error {
    /// The blob ends before byte `needed`.
    Truncated {
        /// Bytes the blob would need to hold what it announces.
        needed: u64,
    },
    /// The first eight bytes are not the aprt magic.
    BadMagic,
    /// The format version is not one this reader understands.
    UnsupportedVersion {
        /// Version found in the blob.
        found: u32,
    },
    /// The header announces more bytes than any valid header needs.
    HeaderTooLarge {
        /// Announced header length.
        len: u32,
    },
    /// The header bytes do not match their checksum.
    HeaderChecksum,
    /// The header bytes do not decode, or hold a non-finite α.
    HeaderMalformed,
    /// Bytes follow the header encoding or the last section.
    TrailingBytes {
        /// Number of unexpected bytes.
        extra: u64,
    },
    /// A header dimension is zero, too large for this build, or inconsistent.
    BadDimension {
        /// Which dimension.
        what: Dim,
        /// Its value.
        value: u64,
    },
    /// A section lies outside the blob or inside the header.
    SectionOutOfRange {
        /// The section.
        section: SectionKind,
    },
    /// A section does not start on a multiple of the section alignment.
    SectionMisaligned {
        /// The section.
        section: SectionKind,
    },
    /// Two sections share bytes.
    SectionOverlap {
        /// The later of the two in the section table.
        section: SectionKind,
    },
    /// A section's length differs from what the header dimensions require.
    SectionLength {
        /// The section.
        section: SectionKind,
        /// Bytes required by the dimensions.
        expected: u64,
        /// Bytes announced.
        found: u64,
    },
    /// A product of dimensions overflows.
    LengthOverflow,
    /// The same section kind appears twice.
    DuplicateSection {
        /// The section.
        section: SectionKind,
    },
    /// A section the model needs is absent.
    MissingSection {
        /// The missing section.
        section: SectionKind,
    },
    /// A section marked required has a kind this reader does not know.
    UnknownRequiredSection {
        /// The section ([`SectionKind::Unknown`]).
        section: SectionKind,
    },
    /// A section uses an encoding not allowed for it.
    BadEncoding {
        /// The section.
        section: SectionKind,
    },
    /// A section's bytes do not match its checksum.
    ChecksumMismatch {
        /// The section.
        section: SectionKind,
    },
    /// A section holds NaN or infinity.
    NonFinite {
        /// The section.
        section: SectionKind,
    },
    /// A vertex's bone index is not an integer below the bone count.
    BadBoneIndex,
    /// The angle-names section is not UTF-8, or not one non-empty `\n`-terminated line per
    /// pose entry.
    BadAngleNames,
    /// The pose-bounds section has `lo > hi`, a prior outside `[lo, hi]` or a negative scale.
    BadPoseBounds,
    /// A pose-features flag is not 0 or 1, or the features outnumber the evaluator's limit.
    BadPoseFeatures,
    /// An irradiance rig's shape, counts, box, radius or error table is not valid.
    BadIrradianceRig,
    /// The texel-atlas section has a resolution outside 1..=8192, texel indices that are not
    /// strictly increasing or not below the resolution squared, or a corner-UV trailer whose
    /// triangle count is out of range or whose UVs are not in `[0, 1]`.
    BadTexelAtlas,
    /// A call needs the model's irradiance rig and the model has none.
    NoIrradianceRig,
    /// The proxies section has a bad count, cull threshold, bone, centre, radius, mask or
    /// length, or a world-frame model has one.
    BadProxies,
    /// A call needs the model's occluder proxies and the model has none.
    NoProxies,
    /// A bone's skinning matrix holds NaN or infinity.
    BadSkinning {
        /// Index of the bone.
        bone: usize,
    },
    /// A vertex normal is NaN or infinite.
    NonFiniteNormal {
        /// Index of the vertex in the call's range.
        index: usize,
    },
    /// Rig lighting weights were computed for a rig of another size.
    WeightsForOtherRig,
    /// The caller's buffer is too small; `needed` bytes would do.
    BufferTooSmall {
        /// Minimum size in bytes.
        needed: usize,
    },
    /// The pose or lighting weights have too small a capacity for this model.
    WeightsTooSmall {
        /// Values this model needs.
        needed: usize,
        /// Values the weights hold.
        capacity: usize,
    },
    /// A slice argument has the wrong length.
    WrongLength {
        /// Which argument.
        what: Input,
        /// Length required.
        expected: usize,
        /// Length given.
        found: usize,
    },
    /// A pose-vector entry is NaN or infinite.
    NonFiniteAngle {
        /// Index of the entry.
        index: usize,
    },
    /// A lighting coefficient is NaN or infinite.
    NonFiniteLighting {
        /// Index of the coefficient.
        index: usize,
    },
    /// A light-map coefficient is NaN or infinite.
    NonFiniteLightMap {
        /// Index of the texel in the call's chunk.
        texel: usize,
    },
    /// A vertex position is NaN or infinite.
    NonFinitePosition {
        /// Index of the vertex in the call's range.
        index: usize,
    },
    /// A bone rotation is not a proper rotation (orthonormal within 10⁻³, determinant +1) or
    /// holds NaN or infinity.
    BadRotation {
        /// Index of the bone.
        bone: usize,
    },
    /// A light of `shade_lights` fails [`Light::validate`](crate::Light::validate).
    BadLight {
        /// Index of the light.
        index: usize,
        /// Why it was refused.
        reason: LightError,
    },
    /// A light's weight in `shade_lights` is negative, NaN or infinite.
    BadLightWeight {
        /// Index of the light.
        index: usize,
    },
    /// The vertex range runs past the model's vertices.
    VertexRange {
        /// First vertex requested.
        first: usize,
        /// Number of vertices requested.
        count: usize,
    },
    /// The triangle is past the last one whose corner UVs the texel atlas records.
    TriangleRange {
        /// Triangle requested.
        triangle: usize,
        /// Triangles the atlas records.
        triangles: usize,
    },
    /// The pose or lighting weights hold nothing: they are new, or the call that was to fill
    /// them failed.
    WeightsNotSet,
    /// The pose or lighting weights were computed for another model.
    WeightsForOtherModel,
    /// The [`BlobSource`](super::BlobSource) failed to read.
    Source,
    /// A result overflowed to infinity or NaN: the inputs, or the blob's values, are too
    /// large for f32. The call's outputs are zeroed (weights are left unset); no call returns
    /// `Ok` with a non-finite output.
    Overflow,
}

impl core::fmt::Display for Error {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Error::BadSkinning { bone } => {
                write!(f, "skinning matrix of bone {bone} is NaN or infinite")
            }
            Error::NonFiniteNormal { index } => {
                write!(f, "vertex normal {index} is NaN or infinite")
            }
            Error::WeightsForOtherRig => {
                write!(f, "rig lighting weights were computed for another rig")
            }
            Error::BufferTooSmall { needed } => write!(f, "buffer too small: needs {needed} bytes"),
            Error::WeightsTooSmall { needed, capacity } => write!(
                f,
                "weights hold {capacity} values, this model needs {needed}"
            ),
            Error::WrongLength {
                what,
                expected,
                found,
            } => write!(
                f,
                "{what:?}: {found} values given, the model needs {expected}"
            ),
            Error::NonFiniteAngle { index } => write!(f, "pose entry {index} is NaN or infinite"),
            Error::NonFiniteLighting { index } => {
                write!(f, "lighting coefficient {index} is NaN or infinite")
            }
            Error::NonFiniteLightMap { texel } => {
                write!(f, "light map of texel {texel} holds NaN or infinity")
            }
            Error::NonFinitePosition { index } => {
                write!(f, "vertex position {index} is NaN or infinite")
            }
            Error::BadRotation { bone } => {
                write!(
                    f,
                    "rotation of bone {bone} is not a rotation (orthonormal, not mirrored)"
                )
            }
            Error::BadLight { index, reason } => write!(f, "light {index} is invalid: {reason}"),
            Error::BadLightWeight { index } => {
                write!(f, "weight of light {index} is negative, NaN or infinite")
            }
            Error::VertexRange { first, count } => {
                write!(f, "vertex range {first}..{first}+{count} is out of bounds")
            }
            Error::TriangleRange {
                triangle,
                triangles,
            } => write!(
                f,
                "triangle {triangle} is past the atlas's {triangles} triangles"
            ),
            Error::WeightsNotSet => write!(f, "weights were not computed (or their call failed)"),
            Error::WeightsForOtherModel => write!(f, "weights were computed for another model"),
            Error::Source => write!(f, "blob source read failed"),
            Error::Overflow => write!(
                f,
                "a result overflowed f32 (inputs or blob values too large)"
            ),
            _ => self.fmt_blob_error(f),
        }
    }
}

impl Error {
    /// The messages of the errors a blob's layout or contents cause (the others are the
    /// caller's inputs, written by `Display::fmt` itself).
    fn fmt_blob_error(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Error::Truncated { needed } => {
                write!(f, "blob truncated: needs at least {needed} bytes")
            }
            Error::BadMagic => write!(f, "not an aprt model (bad magic)"),
            Error::UnsupportedVersion { found } => write!(
                f,
                "unsupported format version {found} (this reader knows {VERSION})"
            ),
            Error::HeaderTooLarge { len } => write!(f, "header length {len} exceeds the maximum"),
            Error::HeaderChecksum => write!(f, "header checksum mismatch"),
            Error::HeaderMalformed => {
                write!(f, "header does not decode or holds a non-finite alpha")
            }
            Error::TrailingBytes { extra } => write!(f, "{extra} unexpected trailing bytes"),
            Error::BadDimension { what, value } => {
                write!(f, "dimension {what:?} = {value} is out of range")
            }
            Error::SectionOutOfRange { section } => {
                write!(f, "section {section} lies outside the blob")
            }
            Error::SectionMisaligned { section } => write!(f, "section {section} is misaligned"),
            Error::SectionOverlap { section } => {
                write!(f, "section {section} overlaps another section")
            }
            Error::SectionLength {
                section,
                expected,
                found,
            } => write!(
                f,
                "section {section} is {found} bytes, dimensions need {expected}"
            ),
            Error::LengthOverflow => write!(f, "dimension product overflows"),
            Error::DuplicateSection { section } => write!(f, "section {section} appears twice"),
            Error::MissingSection { section } => {
                write!(f, "required section {section} is missing")
            }
            Error::UnknownRequiredSection { section } => {
                write!(f, "{section} is marked required")
            }
            Error::BadEncoding { section } => {
                write!(f, "section {section} has an unsupported encoding")
            }
            Error::ChecksumMismatch { section } => write!(f, "section {section} checksum mismatch"),
            Error::NonFinite { section } => write!(f, "section {section} holds NaN or infinity"),
            Error::BadBoneIndex => write!(f, "vertex bone index out of range"),
            Error::BadAngleNames => write!(f, "angle names are not one UTF-8 line per pose entry"),
            Error::BadPoseBounds => write!(
                f,
                "pose bounds need lo <= prior <= hi and a scale >= 0 for every entry"
            ),
            Error::BadPoseFeatures => write!(
                f,
                "pose features need a flag of 0 or 1 per entry and at most {MAX_POSE_LEN} features"
            ),
            Error::BadIrradianceRig => write!(
                f,
                "irradiance rig has a bad shape, count, box, radius or error table"
            ),
            Error::BadTexelAtlas => write!(
                f,
                "texel atlas needs a resolution in 1..=8192, increasing texels below its square and corner UVs in [0, 1]"
            ),
            Error::NoIrradianceRig => write!(f, "the model has no irradiance rig"),
            Error::BadProxies => write!(
                f,
                "occluder proxies have a bad count, cull, bone, centre, radius, mask or length"
            ),
            Error::NoProxies => write!(f, "the model has no occluder proxies"),
            // Every other variant is written by `Display::fmt`.
            _ => write!(f, "{self:?}"),
        }
    }
}

impl core::error::Error for Error {}
