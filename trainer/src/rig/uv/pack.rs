//! Packing rectangular charts into the unit square, for characters that make their own UV
//! layout (the lathe bodies of the built-in characters and the mannequin).
//!
//! A shelf packer: charts sorted by height (tallest first) are placed left to right on
//! shelves, a new shelf starting above the last when a chart no longer fits across. All
//! charts share one scale from their physical size (metres, say) to UV, so texel density is
//! uniform over the character; the scale is the largest (to a bisection's precision) at which
//! the shelves fit. Charts are [`CHART_PADDING`] apart and half that from the square's edges.
//! Shelf packing wastes the space above shorter charts on a shelf, which for a few dozen
//! body parts costs little; it is simple, deterministic and never overlaps.

use super::GUTTER;

/// The resolution [`CHART_PADDING`] is stated at: the coarsest a light map is expected to
/// be baked at. Finer maps have proportionally more texels between charts.
pub const PADDING_RESOLUTION: usize = 256;

/// The gap between charts, in UV: `2·GUTTER + 2` texels at [`PADDING_RESOLUTION`]². Two
/// islands `2·GUTTER + 1` texels apart never share a texel or mix in their gutters (each
/// island's conservative coverage reaches less than one texel past its edge, then `GUTTER`
/// rings); the extra texel absorbs the rounding of UVs to f32.
pub const CHART_PADDING: f64 = (2 * GUTTER + 2) as f64 / PADDING_RESOLUTION as f64;

/// Where the charts go: chart `i` of physical size `[w, h]` covers
/// `[offsets[i], offsets[i] + scale·[w, h]]` in UV.
#[derive(Clone, Debug, PartialEq)]
pub struct Placement {
    /// Physical size to UV, the same for every chart.
    pub scale: f64,
    /// The UV of each chart's corner nearest `(0, 0)`.
    pub offsets: Vec<[f64; 2]>,
}

/// Packs charts of physical `sizes` (`[width, height]`, non-negative and finite) into
/// `[0,1]²` as large as the shelves allow. `None` when even vanishingly small charts do not
/// fit: more charts than [`CHART_PADDING`] leaves room for (about 1,600), or a size that is
/// not a non-negative finite number.
pub fn shelf_pack(sizes: &[[f64; 2]]) -> Option<Placement> {
    if sizes
        .iter()
        .flatten()
        .any(|s| !(s.is_finite() && *s >= 0.0))
    {
        return None;
    }
    let largest = sizes.iter().flatten().fold(0.0f64, |m, &s| m.max(s));
    let room = 1.0 - CHART_PADDING;
    if largest == 0.0 {
        return shelves(sizes, 0.0).map(|offsets| Placement {
            scale: 0.0,
            offsets,
        });
    }
    // No chart can be larger than the square, so this scale is an upper bound.
    let (mut lo, mut hi) = (0.0, room / largest);
    let mut best = (0.0, shelves(sizes, 0.0)?);
    if let Some(offsets) = shelves(sizes, hi) {
        return Some(Placement { scale: hi, offsets });
    }
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        match shelves(sizes, mid) {
            Some(offsets) => {
                lo = mid;
                best = (mid, offsets);
            }
            None => hi = mid,
        }
    }
    Some(Placement {
        scale: best.0,
        offsets: best.1,
    })
}

/// The chart offsets of a shelf packing at `scale`, or `None` if it does not fit.
fn shelves(sizes: &[[f64; 2]], scale: f64) -> Option<Vec<[f64; 2]>> {
    let border = 0.5 * CHART_PADDING;
    let end = 1.0 - border;
    let mut order: Vec<usize> = (0..sizes.len()).collect();
    order.sort_by(|&a, &b| sizes[b][1].total_cmp(&sizes[a][1]).then(a.cmp(&b)));
    let mut offsets = vec![[0.0; 2]; sizes.len()];
    let (mut x, mut y, mut shelf) = (border, border, 0.0f64);
    for i in order {
        let [w, h] = sizes[i].map(|s| s * scale);
        if x + w > end && x > border {
            y += shelf + CHART_PADDING;
            (x, shelf) = (border, 0.0);
        }
        if x + w > end {
            return None;
        }
        offsets[i] = [x, y];
        x += w + CHART_PADDING;
        shelf = shelf.max(h);
    }
    (y + shelf <= end).then_some(offsets)
}
