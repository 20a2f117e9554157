//! The optional texel-atlas section: a light-map model is an ordinary pose-driven model whose
//! rows ("vertices") are the texels of a character's UV atlas, and this section says which
//! texel of the R × R map each row is, so an engine can scatter the rows' shading into it.
//!
//! ```text
//! offset  size  field
//! 0       4     R, the map's resolution, u32 LE, 1..=8192
//! 4       4 v   each row's texel index y · R + x, u32 LE, strictly increasing, below R²
//! ```

use super::{Error, Input};

/// Largest atlas resolution R: an 8192 × 8192 map, whose texel indices fit a `u32`.
pub const MAX_ATLAS_RESOLUTION: u32 = 8192;

/// Bytes of a texel-atlas section for a model of `rows` rows, `None` on overflow.
pub(crate) fn atlas_len(rows: usize) -> Option<u64> {
    (rows as u64).checked_add(1)?.checked_mul(4)
}

/// The texel of every row of a light-map model, validated when the model was opened:
/// [`Model::texel_atlas`](crate::Model::texel_atlas),
/// [`StreamedModel::texel_atlas`](crate::StreamedModel::texel_atlas).
///
/// A light-map model is shaded like any model, its rows being texels; the atlas then places
/// the rows in the map:
///
/// ```
/// use aprt_core::{Error, Input, LitWeights, Model, PoseWeights};
///
/// let model = Model::parse(include_bytes!("../../../fixtures/golden/v1-atlas.aprt"))?;
/// let atlas = model.texel_atlas().expect("a light-map model with its atlas");
/// let info = model.info();
/// let (mut pose, mut lit) = (PoseWeights::new(), LitWeights::new());
/// model.set_pose(&[0.1, 0.0, -0.2], &mut pose)?;
/// model.light(&pose, &[1.0, 0.0, 0.5, 0.0], &[], &mut lit)?;
/// let mut shading = vec![0.0; info.vertices()];
/// model.shade(&lit, 0, &mut shading)?;
///
/// let r = atlas.resolution() as usize; // an 8 × 8 map
/// let grey: Vec<[f32; 3]> = shading.iter().map(|&s| [s; 3]).collect();
/// let mut map = vec![[0.0f32; 3]; r * r];
/// atlas.scatter(0, &grey, &mut map)?; // any chunk of rows: scatter(first_row, ..)
/// assert_eq!(map[atlas.texel(3)? as usize], grey[3]);
/// assert_eq!(
///     atlas.scatter(0, &grey, &mut map[1..]),
///     Err(Error::WrongLength { what: Input::AtlasMap, expected: r * r, found: r * r - 1 })
/// );
/// # Ok::<(), Error>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TexelAtlas<'a> {
    resolution: u32,
    texels: &'a [[u8; 4]],
}

impl<'a> TexelAtlas<'a> {
    /// The atlas in `bytes`, a section announced for `rows` rows, checked again (a streamed
    /// source may have changed since the model was opened).
    pub(crate) fn parse(bytes: &'a [u8], rows: usize) -> Result<TexelAtlas<'a>, Error> {
        if atlas_len(rows) != Some(bytes.len() as u64) {
            return Err(Error::BadTexelAtlas);
        }
        let mut check = AtlasCheck::new();
        check.feed(bytes);
        let resolution = check.finish()?;
        Ok(TexelAtlas {
            resolution,
            texels: &bytes.as_chunks::<4>().0[1..],
        })
    }

    /// The map's resolution R: it is R × R texels.
    pub fn resolution(&self) -> u32 {
        self.resolution
    }

    /// Rows of the model, each one texel.
    pub fn rows(&self) -> usize {
        self.texels.len()
    }

    /// The texel index `y · R + x` of row `row`; [`Error::VertexRange`] past the last row.
    pub fn texel(&self, row: usize) -> Result<u32, Error> {
        self.texels
            .get(row)
            .map(|w| u32::from_le_bytes(*w))
            .ok_or(Error::VertexRange {
                first: row,
                count: 1,
            })
    }

    /// Writes the values of rows `first_row .. first_row + rows.len()` (a chunk of the
    /// model's shading, in row order) to their texels of `map`, the R² texels of the light
    /// map, row-major. Texels of no row are left as they are. A range past the last row is
    /// [`Error::VertexRange`], a map of another size [`Error::WrongLength`]; nothing is
    /// written then.
    pub fn scatter(
        &self,
        first_row: usize,
        rows: &[[f32; 3]],
        map: &mut [[f32; 3]],
    ) -> Result<(), Error> {
        let r = self.resolution as usize;
        if map.len() != r * r {
            return Err(Error::WrongLength {
                what: Input::AtlasMap,
                expected: r * r,
                found: map.len(),
            });
        }
        let range = first_row
            .checked_add(rows.len())
            .and_then(|end| self.texels.get(first_row..end))
            .ok_or(Error::VertexRange {
                first: first_row,
                count: rows.len(),
            })?;
        for (word, value) in range.iter().zip(rows) {
            // Every index is below R², checked at open.
            if let Some(texel) = map.get_mut(u32::from_le_bytes(*word) as usize) {
                *texel = *value;
            }
        }
        Ok(())
    }
}

/// Validates a texel atlas's bytes as they stream past, so the resident and the streamed
/// reader run the same checks: the resolution in range, then every index strictly above the
/// last and below R². The length is the caller's to check (it follows from the row count).
pub(crate) struct AtlasCheck {
    seen: usize,
    word: [u8; 4],
    resolution: u32,
    /// The least index the next row may have.
    next: u64,
    bad: bool,
}

impl AtlasCheck {
    pub(crate) fn new() -> AtlasCheck {
        AtlasCheck {
            seen: 0,
            word: [0; 4],
            resolution: 0,
            next: 0,
            bad: false,
        }
    }

    pub(crate) fn feed(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.word[self.seen % 4] = b;
            self.seen += 1;
            if !self.seen.is_multiple_of(4) {
                continue;
            }
            let value = u32::from_le_bytes(self.word);
            if self.seen == 4 {
                self.resolution = value;
                self.bad |= !(1..=MAX_ATLAS_RESOLUTION).contains(&value);
            } else {
                let squared = u64::from(self.resolution) * u64::from(self.resolution);
                let index = u64::from(value);
                self.bad |= index < self.next || index >= squared;
                self.next = index + 1;
            }
        }
    }

    /// The resolution, or [`Error::BadTexelAtlas`] (also when not even R was fed).
    pub(crate) fn finish(self) -> Result<u32, Error> {
        if self.bad || self.seen < 4 {
            return Err(Error::BadTexelAtlas);
        }
        Ok(self.resolution)
    }
}
