//! The fixed 64-byte header of a `.shlm` file (56 in version 3, 52 before): dimensions, codec
//! parameters, section sizes, the atlas fingerprint, the light-map UVs' triangle count, and
//! the limits every reader enforces before trusting them.

use super::shared_exp::{Grouping, PlaneSettings, SignMode};
use super::{CodecError, CodecKind};
use crate::bake::budget::bytes as show_bytes;
use crate::limits::MAX_BYTES;

/// The file's first eight bytes.
pub const MAGIC: &[u8; 8] = b"APRTSHLM";
/// The layout version this module writes: 3 records the atlas fingerprint, 4 the light-map
/// UVs the maps were baked on when they are not the character's texture UVs.
pub const VERSION: u32 = 4;
/// The version with the atlas fingerprint but no light-map UVs.
const FINGERPRINTED: u32 = 3;
/// The version of a header without the atlas fingerprint.
const UNFINGERPRINTED: u32 = 2;
/// The oldest layout version this module reads (version 1 lacks sign mode 3).
pub const MIN_VERSION: u32 = 1;
/// Header bytes before version 3; version 3 adds the 4-byte atlas fingerprint, version 4 the
/// light-map UVs' triangle count and section bytes.
const OLD_HEADER_LEN: usize = 52;
/// Most triangles of stored light-map UVs: ten million, far beyond a character.
pub const MAX_UV_TRIANGLES: usize = 10_000_000;
/// Largest resolution `R`.
pub const MAX_RESOLUTION: usize = 8192;
/// Largest SH order `n`.
pub const MAX_ORDER: usize = 6;
/// Largest frame count.
pub const MAX_FRAMES: usize = 1_000_000;

/// The codec kind as stored: [`CodecKind`] without the encoder-only targets.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StoredKind {
    /// Every frame a plane set.
    Frames,
    /// Keyframes every `interval` frames.
    Keyframes {
        /// Frames between keyframes.
        interval: usize,
    },
    /// PCA with `components` components.
    Pca {
        /// `k`.
        components: usize,
    },
}

/// The parsed header.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Header {
    /// `R`.
    pub resolution: usize,
    /// `n`.
    pub order: usize,
    /// `F`.
    pub frames: usize,
    /// `T`.
    pub texels: usize,
    /// The temporal scheme.
    pub kind: StoredKind,
    /// The quantiser.
    pub planes: PlaneSettings,
    /// Section sizes: mask, positions, shared, light-map UVs (0 before version 4).
    pub sections: [usize; 4],
    /// The fingerprint of the UV atlas the maps were baked on; `None` in (and written as) a
    /// version-2 header.
    pub atlas: Option<u32>,
    /// Triangles of the stored light-map UVs: 0 when the maps lie on the character's own
    /// texture UVs (and before version 4).
    pub uv_triangles: usize,
    /// The layout version read, or to write: 2 without an atlas fingerprint, else 4 (3 read).
    pub version: u32,
}

impl Header {
    /// `n²`.
    pub fn n2(&self) -> usize {
        self.order * self.order
    }

    /// Header bytes: where the mask section starts.
    pub fn header_len(&self) -> usize {
        match self.version {
            VERSION => OLD_HEADER_LEN + 12,
            FINGERPRINTED => OLD_HEADER_LEN + 4,
            _ => OLD_HEADER_LEN,
        }
    }

    /// The version a header with (or without) an atlas fingerprint is written as.
    pub fn version_for(atlas: Option<u32>) -> u32 {
        if atlas.is_some() {
            VERSION
        } else {
            UNFINGERPRINTED
        }
    }

    /// Bytes a reader holds at once: two decoded frames of `R² · n²` f32 (`inspect` times a
    /// copy, keyframes interpolate between two), the PCA basis of `k + 1` plane sets of
    /// `T · n²` f32 (two plane sets otherwise), and each texel's index, position and its
    /// decompressed bytes, and the mask. A header that claims more than the run's budget is
    /// refused before any of it is allocated.
    pub fn reader_bytes(&self) -> u64 {
        let r2 = (self.resolution as u64).pow(2);
        let (n2, t) = (self.n2() as u64, self.texels as u64);
        let plane_sets = match self.kind {
            StoredKind::Pca { components } => components as u64 + 1,
            _ => 2,
        };
        (2 * r2 * n2 * 4)
            .saturating_add(plane_sets.saturating_mul(t * n2 * 4))
            .saturating_add(t * (8 + 12 + 12))
            .saturating_add(r2.div_ceil(8))
            .saturating_add(self.uv_triangles as u64 * 24 * 2)
    }

    /// Appends the header's bytes (version 4 with an atlas fingerprint, 2 without); fails if a
    /// field does not fit its `u32`, or the version is one this module only reads.
    pub fn write(&self, out: &mut Vec<u8>) -> Result<(), CodecError> {
        let u32_of = |v: usize, what: &str| {
            u32::try_from(v).map_err(|_| CodecError::Input(format!("{what} {v} exceeds u32")))
        };
        let (kind, param) = match self.kind {
            StoredKind::Frames => (0u8, 0),
            StoredKind::Keyframes { interval } => (1, interval),
            StoredKind::Pca { components } => (2, components),
        };
        if self.version != Header::version_for(self.atlas) {
            return Err(CodecError::Input(format!(
                "a version-{} header with atlas {:?}",
                self.version, self.atlas
            )));
        }
        out.extend_from_slice(MAGIC);
        for v in [
            self.version as usize,
            self.resolution,
            self.order,
            self.frames,
            self.texels,
        ] {
            out.extend_from_slice(&u32_of(v, "header field")?.to_le_bytes());
        }
        let sign = match self.planes.sign {
            SignMode::OffsetScale => 0,
            SignMode::SignPlane => 1,
            SignMode::Band0Ratio => 2,
            SignMode::Uniform => 3,
        };
        let grouping = u8::from(self.planes.grouping == Grouping::Triples);
        let p = &self.planes;
        out.extend_from_slice(&[
            kind,
            sign,
            grouping,
            p.mantissa_bits,
            u8::from(p.spatial_delta),
        ]);
        out.extend_from_slice(&[0; 3]);
        out.extend_from_slice(&u32_of(param, "kind parameter")?.to_le_bytes());
        for len in &self.sections[..3] {
            out.extend_from_slice(&u32_of(*len, "section")?.to_le_bytes());
        }
        if let Some(atlas) = self.atlas {
            out.extend_from_slice(&atlas.to_le_bytes());
            out.extend_from_slice(&u32_of(self.uv_triangles, "UV triangles")?.to_le_bytes());
            out.extend_from_slice(&u32_of(self.sections[3], "section")?.to_le_bytes());
        }
        Ok(())
    }

    /// Reads and validates the header: magic, version, limits, codec bytes.
    pub fn read(bytes: &[u8]) -> Result<Header, CodecError> {
        if bytes.len() < MAGIC.len() || &bytes[..MAGIC.len()] != MAGIC {
            return Err(CodecError::BadMagic);
        }
        let truncated = |needed: usize| CodecError::Truncated {
            what: "header",
            needed: needed as u64,
            len: bytes.len() as u64,
        };
        if bytes.len() < OLD_HEADER_LEN {
            return Err(truncated(OLD_HEADER_LEN));
        }
        let word = |at: usize| {
            u32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]])
        };
        let version = word(8);
        if !(MIN_VERSION..=VERSION).contains(&version) || (version == 1 && bytes[29] == 3) {
            return Err(CodecError::Version(version));
        }
        let extra = match version {
            VERSION => 12,
            FINGERPRINTED => 4,
            _ => 0,
        };
        if bytes.len() < OLD_HEADER_LEN + extra {
            return Err(truncated(OLD_HEADER_LEN + extra));
        }
        let atlas = (extra > 0).then(|| word(OLD_HEADER_LEN));
        let (uv_triangles, uv_len) = match version {
            VERSION => (
                word(OLD_HEADER_LEN + 4) as usize,
                word(OLD_HEADER_LEN + 8) as usize,
            ),
            _ => (0, 0),
        };
        let field = |at: usize| word(at) as usize;
        let bad = |m: String| Err(CodecError::Header(m));
        let (resolution, order, frames, texels) = (field(12), field(16), field(20), field(24));
        if !(1..=MAX_RESOLUTION).contains(&resolution) {
            return bad(format!(
                "resolution {resolution} outside 1..={MAX_RESOLUTION}"
            ));
        }
        if !(1..=MAX_ORDER).contains(&order) {
            return bad(format!("SH order {order} outside 1..={MAX_ORDER}"));
        }
        if !(1..=MAX_FRAMES).contains(&frames) {
            return bad(format!("frame count {frames} outside 1..={MAX_FRAMES}"));
        }
        if texels > resolution * resolution {
            return bad(format!("{texels} filled texels in a {resolution}² map"));
        }
        if uv_triangles > MAX_UV_TRIANGLES || (uv_triangles == 0) != (uv_len == 0) {
            return bad(format!(
                "{uv_triangles} triangles of light-map UVs in {uv_len} bytes (at most {MAX_UV_TRIANGLES}, both or neither zero)"
            ));
        }
        let planes = read_planes(&bytes[29..36])?;
        let param = field(36);
        let kind = match bytes[28] {
            0 if param == 0 => StoredKind::Frames,
            1 if (1..=frames.max(1)).contains(&param) => StoredKind::Keyframes { interval: param },
            2 if param <= frames => StoredKind::Pca { components: param },
            k => return bad(format!("codec kind {k} with parameter {param}")),
        };
        let header = Header {
            resolution,
            order,
            frames,
            texels,
            kind,
            planes,
            sections: [field(40), field(44), field(48), uv_len],
            atlas,
            uv_triangles,
            version,
        };
        let needed = header.reader_bytes();
        if needed > MAX_BYTES {
            let components = match kind {
                StoredKind::Pca { components } => format!(" and {components} PCA components"),
                _ => String::new(),
            };
            return bad(format!(
                "a {resolution}² map of {texels} filled texels at SH order {order}{components} needs {} to read; a run holds at most {}",
                show_bytes(needed),
                show_bytes(MAX_BYTES)
            ));
        }
        Ok(header)
    }
}

/// Bytes 29..36: sign mode, grouping, mantissa bits, spatial delta, three zeros.
fn read_planes(b: &[u8]) -> Result<PlaneSettings, CodecError> {
    let sign = match b[0] {
        0 => SignMode::OffsetScale,
        1 => SignMode::SignPlane,
        2 => SignMode::Band0Ratio,
        3 => SignMode::Uniform,
        s => return Err(CodecError::Header(format!("sign mode {s}"))),
    };
    let grouping = match b[1] {
        0 => Grouping::Texel,
        1 => Grouping::Triples,
        g => return Err(CodecError::Header(format!("exponent grouping {g}"))),
    };
    if !(2..=8).contains(&b[2]) || b[3] > 1 || b[4..7] != [0; 3] {
        return Err(CodecError::Header(format!(
            "quantiser bytes {:?}",
            &b[2..7]
        )));
    }
    Ok(PlaneSettings {
        mantissa_bits: b[2],
        sign,
        grouping,
        spatial_delta: b[3] == 1,
    })
}

/// The stored form of an encoder's kind, once `k` is known.
pub fn stored_kind(kind: &CodecKind, components: usize) -> StoredKind {
    match *kind {
        CodecKind::Frames => StoredKind::Frames,
        CodecKind::Keyframes { interval } => StoredKind::Keyframes { interval },
        CodecKind::Pca { .. } => StoredKind::Pca { components },
    }
}
