//! The light-map UVs section of a `.shlm` file (version 4): the UV layout the maps were baked
//! on when it is not the character's texture layout (`--uv generate`), so that readers sample
//! the maps where they were baked and an engine can draw with them.
//!
//! Its bytes are the zstd of every triangle's three corners' `(u, v)` as f32, triangle-major,
//! in the atlas's convention ([`crate::rig::uv`]); the header records the triangle count, and
//! the layout's fingerprint is the header's atlas fingerprint.

use super::CodecError;
use super::entropy::{compress, decompress_exact};
use crate::rig::uv::UvLayout;

/// The section's bytes for `layout`.
pub fn write_uvs(layout: &UvLayout, level: i32) -> Result<Vec<u8>, CodecError> {
    let raw: Vec<u8> = layout
        .corners
        .iter()
        .flatten()
        .flatten()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    compress(&raw, level)
}

/// The layout of `triangles` triangles in `section`: every UV finite and in `[0, 1]`, and its
/// fingerprint the header's `fingerprint` (which a reader pairs the maps with).
pub fn read_uvs(
    section: &[u8],
    triangles: usize,
    fingerprint: u32,
) -> Result<UvLayout, CodecError> {
    const WHAT: &str = "light-map UVs";
    let bytes = decompress_exact(section, triangles * 24, WHAT)?;
    let floats: Vec<f32> = bytes
        .as_chunks::<4>()
        .0
        .iter()
        .map(|b| f32::from_le_bytes(*b))
        .collect();
    let layout = UvLayout {
        corners: floats
            .as_chunks::<6>()
            .0
            .iter()
            .map(|t| [[t[0], t[1]], [t[2], t[3]], [t[4], t[5]]])
            .collect(),
    };
    if let Some((triangle, corner, x)) = layout.outside_unit_square() {
        return Err(CodecError::Invalid {
            what: WHAT,
            message: format!("triangle {triangle} corner {corner} has {x} outside [0, 1]"),
        });
    }
    if layout.fingerprint() != fingerprint {
        return Err(CodecError::Invalid {
            what: WHAT,
            message: format!(
                "fingerprint {:08x}, the header records {fingerprint:08x}",
                layout.fingerprint()
            ),
        });
    }
    Ok(layout)
}
