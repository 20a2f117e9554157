//! Encoding and compressing a sequence of SH light maps: the `.shlm` file.
//!
//! A frame is `R × R` texels of `n²` transfer coefficients. Each frame's filled texels go
//! through a quantiser ([`shared_exp`]: shared-exponent RGBE-style mantissas, or by default a
//! uniform absolute step per map, [`uniform`]), laid out as byte planes (one per coefficient
//! map, the paper's tiles, masked texels dropped), predicted along the plane or over the grid
//! and compressed with zstd. Three ways of using the clip's temporal coherence are
//! measured by [`compare`]: every frame independent, keyframes with interpolated in-betweens,
//! and PCA over the frames (the default, which wins on bytes against error by a wide margin:
//! a clip of smooth motion lives in a handful of components, and bake noise falls in the
//! discarded ones).
//!
//! # Byte layout (little endian)
//!
//! | offset | size | field |
//! | --- | --- | --- |
//! | 0 | 8 | magic `APRTSHLM` |
//! | 8 | 4 | version (4; versions 1 to 3 are read too: version 3 without the light-map UV fields, 2 also without the atlas fingerprint, 1 also without sign mode 3) |
//! | 12 | 4 | resolution `R` (1..=8192) |
//! | 16 | 4 | SH order `n` (1..=6); `n2 = n²` |
//! | 20 | 4 | frames `F` (1..=1 000 000) |
//! | 24 | 4 | filled texels `T` (≤ `R²`) |
//! | 28 | 1 | codec kind: 0 frames, 1 keyframes, 2 PCA |
//! | 29 | 1 | sign mode: 0 offset per map, 1 sign plane, 2 band-0 ratio, 3 uniform step |
//! | 30 | 1 | exponent grouping: 0 per texel, 1 triples |
//! | 31 | 1 | mantissa bits `m` (2..=8) |
//! | 32 | 1 | spatial delta (0 or 1) |
//! | 33 | 3 | zero |
//! | 36 | 4 | kind parameter: keyframe interval `K`, PCA components `k`, or 0 |
//! | 40 | 4 | mask section bytes |
//! | 44 | 4 | positions section bytes |
//! | 48 | 4 | shared section bytes |
//! | 52 | 4 | atlas fingerprint: CRC-32 of the UV layout's corners (`UvLayout::fingerprint`); absent before version 3, where the sections start at 52 |
//! | 56 | 4 | light-map UV triangles `U` (≤ 10 000 000; 0: the maps lie on the character's texture UVs); absent before version 4 |
//! | 60 | 4 | light-map UVs section bytes (0 exactly when `U` is); absent before version 4, where the sections start at 56 |
//! | 64 | … | mask: zstd of `⌈R²/8⌉` bytes, texel `t` at bit `t % 8` of byte `t / 8` |
//! | | … | positions: zstd of `T × 3` f32, bind-pose point of each filled texel in texel order |
//! | | … | shared: PCA only: `u32` count (`k + 1`), `count` × `u32` lengths, then zstd plane sets of the mean and the `k` components |
//! | | … | light-map UVs (`U > 0`): zstd of `U × 3` corners' `(u, v)` f32, each in `[0, 1]`, whose CRC-32 is the atlas fingerprint (`uvs.rs`) |
//! | | `8(F+1)` | frame offset table: `u64` offsets into the chunk area, non-decreasing, last = its size |
//! | | … | chunk area: frame `f`'s chunk is `[off[f], off[f+1])` |
//! | end−4 | 4 | CRC-32 of every byte before it |
//!
//! A chunk is a zstd plane set (kind 0; kind 1 at keyframes `f % K == 0` and the last frame,
//! empty between them), or `k` f32 weights (kind 2). A plane set of `T` texels is, in order:
//! `n2` f32 map offsets (sign mode 0 only); `G` exponent planes of `T` bytes (`G = 1`, or
//! `⌈n2/3⌉` for triples; byte `e + 126`, 0..=254); `n2` mantissa planes of `T` bytes (sign
//! mode 2: band 0's mantissa, then the ratio planes, `q + 2^(m−1) − 1`); `n2` sign planes of
//! `⌈T/8⌉` bytes (sign mode 1 only). With spatial delta, exponent and mantissa planes hold
//! wrapping differences to the previous byte of the same plane.
//!
//! Sign mode 3 ([`uniform`]) has no exponents: a plane set is `n2` f32 steps (finite, ≥ 0),
//! `n2` low-byte planes of `T` bytes, then `n2` high-byte planes of `T` bytes, the zigzagged
//! 16-bit residuals of `round(v / step)` against a median-edge prediction from the texel's
//! filled left, up and up-left neighbours on the `R × R` grid (grouping and the spatial-delta
//! byte are ignored).

mod compare;
mod entropy;
mod error;
mod file;
mod header;
mod pca;
mod sequence;
pub mod shared_exp;
pub mod synth;
#[cfg(test)]
mod tests;
pub mod uniform;
mod uvs;

pub use compare::{CodecReport, compare};
pub use error::CodecError;
pub use file::{ShlmFile, atlas_record};
pub use header::MAGIC;
pub use sequence::encode;
pub use shared_exp::{Grouping, PlaneSettings, SignMode};

/// A baked clip of SH light maps, as the bake hands it to the codec.
#[derive(Debug, Clone, PartialEq)]
pub struct MapSequence {
    /// `R`: the maps are `R × R` texels.
    pub resolution: usize,
    /// The fingerprint of the UV layout the maps were baked on
    /// ([`crate::rig::uv::UvLayout::fingerprint`]), which readers compare with the
    /// character's; `None` writes a version-2 file, which records none.
    pub atlas: Option<u32>,
    /// SH order `n`; each texel holds `n²` coefficients.
    pub order: usize,
    /// `R²` flags: which texels lie inside a UV chart and hold transfer.
    pub filled: Vec<bool>,
    /// The bind-pose surface point of each filled texel, in texel order (stored in the file
    /// for lighting at runtime).
    pub positions: Vec<[f32; 3]>,
    /// The light-map UVs the maps were baked on, stored in the file when they are not the
    /// character's texture UVs (then `atlas` is their fingerprint).
    pub layout: Option<crate::rig::uv::UvLayout>,
    /// Each frame's `R² · n²` coefficients, texel-major (`[texel * n2 + c]`), zero where
    /// `!filled`.
    pub frames: Vec<Vec<f32>>,
}

/// How frames use the clip's temporal coherence.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CodecKind {
    /// Every frame its own plane set: any frame decodes alone, nothing shared.
    Frames,
    /// A plane set every `interval` frames (and at the last); the frames between are linear
    /// interpolations of their two keyframes (the paper's §6 suggestion; error grows with
    /// motion between keyframes).
    Keyframes {
        /// Frames from one keyframe to the next (≥ 1).
        interval: usize,
    },
    /// PCA over the frames (the paper's §7 suggestion): a mean and `k` components stored as
    /// plane sets, `k` f32 weights per frame.
    Pca {
        /// The relative error the discarded components may cost (`k` is the smallest that
        /// meets it, before quantisation).
        target_error: f32,
        /// An upper bound on `k`.
        max_components: usize,
    },
}

/// Everything the encoder chooses. The default is PCA to a 1.5 % target, quantised with the
/// uniform step per map ([`SignMode::Uniform`]) at `m = 7` (quantisation error about `2^−7` of
/// the clip), zstd 15. Measured on real bakes (256², order 4, 256 rays per texel; ratio
/// against raw f32 maps, relative error of the decoded maps against the f32 maps over filled
/// texels, median decode time of one frame on a shared 2-core machine, components combined
/// from their 16-bit integers):
///
/// | clip | default | PCA 2 %, uniform m6 | PCA 1 %, uniform m7 | PCA 2 %, shared exp. m7 | old default: PCA 1 %, shared exp. m8 |
/// | --- | --- | --- | --- | --- | --- |
/// | Fox `Walk`, 23 frames | 41.6:1, 1.44 %, 5.7 ms | 60.9:1, 2.14 % | 38.2:1, 1.06 % | 35.9:1, 2.40 % | 24.5:1, 1.20 % |
/// | CesiumMan, 59 frames | 58.0:1, 1.64 %, 8.6 ms | 92.6:1, 2.34 % | 44.1:1, 1.18 %, 12.8 ms | 48.9:1, 2.57 % | 22.3:1, 1.31 % |
///
/// The lowest error that keeps ≥ 30:1 with room to spare and one frame within ~10 ms: a 1 %
/// target keeps more components (CesiumMan: 12.8 ms a frame) for 0.3 % less error; 2 % and
/// `m = 6` nearly doubles the ratio at 2.1–2.3 %. Bake noise is not low-rank, so the PCA
/// target, not the quantiser, sets most of the error.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CodecSettings {
    /// Temporal scheme.
    pub kind: CodecKind,
    /// Quantiser: mantissa bits (the quantisation step), sign handling, exponent grouping,
    /// spatial delta.
    pub planes: PlaneSettings,
    /// zstd level (1..=22): higher is smaller and slower to encode; decoding speed barely
    /// changes.
    pub zstd_level: i32,
}

impl Default for CodecSettings {
    fn default() -> Self {
        CodecSettings {
            kind: CodecKind::Pca {
                target_error: 0.015,
                max_components: 32,
            },
            planes: PlaneSettings {
                mantissa_bits: 7,
                sign: SignMode::Uniform,
                grouping: Grouping::Texel,
                spatial_delta: true,
            },
            zstd_level: 15,
        }
    }
}
