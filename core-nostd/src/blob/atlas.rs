//! The optional texel-atlas section: a light-map model is an ordinary pose-driven model whose
//! rows ("vertices") are the texels of a character's UV atlas, and this section says which
//! texel of the R × R map each row is, so an engine can scatter the rows' shading into it. An
//! optional trailer holds the light-map UVs of every triangle corner, so an engine can draw
//! the map on the mesh with them (a second UV set).
//!
//! ```text
//! offset     size    field
//! 0          4       R, the map's resolution, u32 LE, 1..=8192
//! 4          4 v     each row's texel index y · R + x, u32 LE, strictly increasing, below R²
//! optional trailer:
//! 4 (1 + v)  4       T, the triangle count, u32 LE, 1..=MAX_ATLAS_TRIANGLES
//! 4 (2 + v)  24 T    each triangle's 3 corners' (u, v), f32 LE, each in [0, 1]
//! ```

use super::{Error, Input};

/// Largest atlas resolution R: an 8192 × 8192 map, whose texel indices fit a `u32`.
pub const MAX_ATLAS_RESOLUTION: u32 = 8192;

/// Most triangles the corner-UV trailer may hold: 2²² (96 MiB of UVs), so a whole section
/// stays below 2³² bytes and its length is computed without overflow on 32-bit targets.
pub const MAX_ATLAS_TRIANGLES: u32 = 1 << 22;

/// Bytes of one triangle's corner UVs: 3 corners of 2 f32.
const TRIANGLE_BYTES: usize = 24;

/// Bytes of a texel-atlas section for a model of `rows` rows without the corner-UV trailer,
/// `None` on overflow.
pub(crate) fn atlas_len(rows: usize) -> Option<u64> {
    (rows as u64).checked_add(1)?.checked_mul(4)
}

/// Bytes of a corner-UV trailer of `triangles` triangles: its count, then the UVs (below 2⁴⁰
/// for any `u32`, so a `u64` holds it).
pub(crate) fn trailer_len(triangles: u32) -> u64 {
    4 + TRIANGLE_BYTES as u64 * u64::from(triangles)
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
    /// Each triangle's corner UVs, empty without the trailer.
    corners: &'a [[u8; TRIANGLE_BYTES]],
}

impl<'a> TexelAtlas<'a> {
    /// The atlas in `bytes`, a section announced for `rows` rows, checked again (a streamed
    /// source may have changed since the model was opened).
    pub(crate) fn parse(bytes: &'a [u8], rows: usize) -> Result<TexelAtlas<'a>, Error> {
        let mut check = AtlasCheck::new(rows);
        check.feed(bytes);
        let (resolution, triangles) = check.finish().map_err(|_| Error::BadTexelAtlas)?;
        // `finish` checked the length: R and the rows, then the trailer when it has triangles.
        let texels = bytes.as_chunks::<4>().0.get(1..=rows);
        let corners = match triangles {
            0 => Some(&[][..]),
            _ => bytes.get(4 * (rows + 2)..).map(|t| t.as_chunks().0),
        };
        let (Some(texels), Some(corners)) = (texels, corners) else {
            return Err(Error::BadTexelAtlas);
        };
        Ok(TexelAtlas {
            resolution,
            texels,
            corners,
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

    /// Triangles of the mesh whose light-map UVs the atlas records, 0 when it records none
    /// (the trailer is optional).
    ///
    /// ```
    /// use aprt_core::{Error, Model};
    ///
    /// let plain = Model::parse(include_bytes!("../../../fixtures/golden/v1-atlas.aprt"))?;
    /// assert_eq!(plain.texel_atlas().map(|a| a.triangles()), Some(0));
    /// let with_uvs = Model::parse(include_bytes!("../../../fixtures/golden/v1-atlas-uvs.aprt"))?;
    /// assert_eq!(with_uvs.texel_atlas().map(|a| a.triangles()), Some(4));
    /// # Ok::<(), Error>(())
    /// ```
    pub fn triangles(&self) -> usize {
        self.corners.len()
    }

    /// The light-map UVs `[u, v]` of triangle `triangle`'s three corners, in the mesh's
    /// triangle and corner order: a second UV set, drawing the map on the mesh. u runs right
    /// and v down over the map, each in `[0, 1]`, texel `(x, y)` covering `[x/R, (x+1)/R] ×
    /// [y/R, (y+1)/R]`. [`Error::TriangleRange`] past the last triangle.
    ///
    /// ```
    /// use aprt_core::{Error, Model};
    ///
    /// let model = Model::parse(include_bytes!("../../../fixtures/golden/v1-atlas-uvs.aprt"))?;
    /// let atlas = model.texel_atlas().expect("a light-map model with its atlas");
    /// // The second UV set of a vertex buffer of unshared corners, three per triangle.
    /// let mut uv2 = Vec::new();
    /// for t in 0..atlas.triangles() {
    ///     uv2.extend(atlas.corner_uvs(t)?);
    /// }
    /// assert_eq!(uv2.len(), 3 * 4);
    /// // Triangle 2's first corner lies in texel (5, 4) of the 8 × 8 map.
    /// let r = atlas.resolution() as f32;
    /// let [u, v] = uv2[6];
    /// assert_eq!(((u * r) as u32, (v * r) as u32), (5, 4));
    /// assert_eq!(
    ///     atlas.corner_uvs(4),
    ///     Err(Error::TriangleRange { triangle: 4, triangles: 4 })
    /// );
    /// # Ok::<(), Error>(())
    /// ```
    pub fn corner_uvs(&self, triangle: usize) -> Result<[[f32; 2]; 3], Error> {
        let bytes = self.corners.get(triangle).ok_or(Error::TriangleRange {
            triangle,
            triangles: self.corners.len(),
        })?;
        let mut uvs = [[0.0; 2]; 3];
        for (uv, word) in uvs.as_flattened_mut().iter_mut().zip(bytes.as_chunks().0) {
            *uv = f32::from_le_bytes(*word);
        }
        Ok(uvs)
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
/// reader run the same checks: the resolution in range, every index strictly above the last
/// and below R², then, in a trailer, a triangle count in range and every UV in `[0, 1]`.
pub(crate) struct AtlasCheck {
    rows: usize,
    seen: usize,
    word: [u8; 4],
    resolution: u32,
    /// The least index the next row may have.
    next: u64,
    /// The trailer's triangle count, once read.
    triangles: Option<u32>,
    bad: bool,
}

/// Why [`AtlasCheck::finish`] refused an atlas.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum AtlasFailure {
    /// A value is out of range.
    Content,
    /// The bytes fed are not the length the row count and the trailer's count give.
    Length { expected: u64 },
}

impl AtlasCheck {
    /// A check for the atlas of a model of `rows` rows.
    pub(crate) fn new(rows: usize) -> AtlasCheck {
        AtlasCheck {
            rows,
            seen: 0,
            word: [0; 4],
            resolution: 0,
            next: 0,
            triangles: None,
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
            match self.seen / 4 - 1 {
                0 => {
                    self.resolution = value;
                    self.bad |= !(1..=MAX_ATLAS_RESOLUTION).contains(&value);
                }
                word if word <= self.rows => {
                    let squared = u64::from(self.resolution) * u64::from(self.resolution);
                    let index = u64::from(value);
                    self.bad |= index < self.next || index >= squared;
                    self.next = index + 1;
                }
                word if word - 1 == self.rows => {
                    self.triangles = Some(value);
                    self.bad |= !(1..=MAX_ATLAS_TRIANGLES).contains(&value);
                }
                _ => self.bad |= !(0.0..=1.0).contains(&f32::from_bits(value)),
            }
        }
    }

    /// The resolution and the trailer's triangle count (0 without one). A count out of range
    /// is [`AtlasFailure::Content`] before the length is judged, since it gives the length.
    pub(crate) fn finish(self) -> Result<(u32, usize), AtlasFailure> {
        let base = atlas_len(self.rows).unwrap_or(u64::MAX);
        let expected = match self.triangles {
            None => base,
            Some(t) if !(1..=MAX_ATLAS_TRIANGLES).contains(&t) => {
                return Err(AtlasFailure::Content);
            }
            Some(t) => base.saturating_add(trailer_len(t)),
        };
        if self.seen as u64 != expected {
            return Err(AtlasFailure::Length { expected });
        }
        if self.bad {
            return Err(AtlasFailure::Content);
        }
        Ok((self.resolution, self.triangles.unwrap_or(0) as usize))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Bytes of an atlas of 3 rows (R = 4, texels 1, 5, 15) with a trailer of 2 triangles.
    const LEN: usize = 4 * 4 + 4 + 2 * TRIANGLE_BYTES;
    const UVS: [f32; 12] = [
        0.0, 0.0, 1.0, 0.0, 0.5, 1.0, 0.125, 0.25, -0.0, 0.375, 1.0, 1.0,
    ];

    fn atlas_bytes() -> [u8; LEN] {
        let mut bytes = [0u8; LEN];
        let words = [4u32, 1, 5, 15, 2].into_iter();
        let floats = UVS.iter().map(|f| f.to_bits());
        for (dst, w) in bytes
            .as_chunks_mut::<4>()
            .0
            .iter_mut()
            .zip(words.chain(floats))
        {
            *dst = w.to_le_bytes();
        }
        bytes
    }

    /// What [`AtlasCheck::finish`] makes of an atlas.
    type Checked = Result<(u32, usize), AtlasFailure>;

    /// `bytes` fed whole, cut in two at every byte, and one byte at a time: the three agree
    /// and the result is returned.
    fn check(bytes: &[u8], rows: usize) -> Checked {
        let whole = {
            let mut check = AtlasCheck::new(rows);
            check.feed(bytes);
            check.finish()
        };
        for cut in 0..=bytes.len() {
            let mut check = AtlasCheck::new(rows);
            check.feed(&bytes[..cut]);
            check.feed(&bytes[cut..]);
            assert_eq!(check.finish(), whole, "cut at {cut}");
        }
        let mut check = AtlasCheck::new(rows);
        bytes.chunks(1).for_each(|b| check.feed(b));
        assert_eq!(check.finish(), whole, "bytewise");
        whole
    }

    #[test]
    fn corner_uvs_read_back_and_stop_at_the_last_triangle() {
        let bytes = atlas_bytes();
        let atlas = TexelAtlas::parse(&bytes, 3).unwrap();
        assert_eq!(
            (atlas.resolution(), atlas.rows(), atlas.triangles()),
            (4, 3, 2)
        );
        assert_eq!(atlas.texel(2), Ok(15));
        assert_eq!(
            atlas.texel(3),
            Err(Error::VertexRange { first: 3, count: 1 })
        );
        assert_eq!(
            atlas.corner_uvs(0),
            Ok([[0.0, 0.0], [1.0, 0.0], [0.5, 1.0]])
        );
        assert_eq!(
            atlas.corner_uvs(1),
            Ok([[0.125, 0.25], [-0.0, 0.375], [1.0, 1.0]])
        );
        for triangle in [2, usize::MAX] {
            assert_eq!(
                atlas.corner_uvs(triangle),
                Err(Error::TriangleRange {
                    triangle,
                    triangles: 2
                })
            );
        }
        assert_eq!(check(&bytes, 3), Ok((4, 2)));
        // Without the trailer: the same rows, no triangles.
        let plain = TexelAtlas::parse(&bytes[..16], 3).unwrap();
        assert_eq!((plain.rows(), plain.triangles()), (3, 0));
        assert_eq!(plain.texel(2), Ok(15));
        assert_eq!(
            plain.corner_uvs(0),
            Err(Error::TriangleRange {
                triangle: 0,
                triangles: 0
            })
        );
        assert_eq!(check(&bytes[..16], 3), Ok((4, 0)));
    }

    /// Labelled hard cases of the trailer: what both readers must refuse, and the length the
    /// streaming check reports when the count and the bytes disagree.
    #[test]
    fn malformed_trailers_are_refused() {
        let length = |expected: usize| {
            Err(AtlasFailure::Length {
                expected: expected as u64,
            })
        };
        let bad = Err(AtlasFailure::Content);
        let cases: [(&str, usize, u32, usize, Checked); 13] = [
            ("no triangles", 4, 0, 20, bad),
            ("no triangles, one's UVs", 4, 0, LEN - TRIANGLE_BYTES, bad),
            ("count past the limit", 4, MAX_ATLAS_TRIANGLES + 1, LEN, bad),
            ("count u32::MAX", 4, u32::MAX, LEN, bad),
            (
                "count one too many",
                4,
                3,
                LEN,
                length(LEN + TRIANGLE_BYTES),
            ),
            ("count one too few", 4, 1, LEN, length(LEN - TRIANGLE_BYTES)),
            (
                "largest count",
                4,
                MAX_ATLAS_TRIANGLES,
                LEN,
                length(20 + (24 << 22)),
            ),
            ("a UV NaN", 7, f32::NAN.to_bits(), LEN, bad),
            ("a UV below 0", 8, (-1e-7f32).to_bits(), LEN, bad),
            ("a UV above 1", 16, 1.0000001f32.to_bits(), LEN, bad),
            ("a UV infinite", 16, f32::INFINITY.to_bits(), LEN, bad),
            ("a UV cut short", 4, 2, LEN - 1, length(LEN)),
            ("the count cut short", 4, 2, 19, length(16)),
        ];
        for (label, word, value, len, want) in cases {
            let mut bytes = atlas_bytes();
            bytes[4 * word..4 * word + 4].copy_from_slice(&value.to_le_bytes());
            assert_eq!(check(&bytes[..len], 3), want, "{label}");
            assert_eq!(
                TexelAtlas::parse(&bytes[..len], 3).map(|a| a.triangles()),
                Err(Error::BadTexelAtlas),
                "{label}"
            );
        }
        // A bad row is still a bad row with a trailer; the atlas of a model of fewer rows
        // reads the last row as a count (15 triangles) and is refused for its length.
        let mut bytes = atlas_bytes();
        bytes[8..12].copy_from_slice(&1u32.to_le_bytes());
        assert_eq!(check(&bytes, 3), bad);
        assert_eq!(
            check(&atlas_bytes(), 2),
            length(12 + 4 + 15 * TRIANGLE_BYTES)
        );
    }
}
