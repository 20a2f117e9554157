//! Reading a map back at a UV: bilinear filtering as a GPU samples a texture with clamp to edge.

/// Bilinear sample of an `R²·n2` map (texel-major, `[texel·n2 + c]`) at `uv`, into `out` (`n2`
/// values): [`sample_bilinear_by`] reading the map.
///
/// # Panics
/// If `map` is not `resolution²·n2` long or `out` not `n2`.
pub fn sample_bilinear(map: &[f32], resolution: usize, n2: usize, uv: [f32; 2], out: &mut [f32]) {
    assert_eq!(map.len(), resolution * resolution * n2, "map size");
    assert_eq!(out.len(), n2, "output size");
    sample_bilinear_by(resolution, uv, |t| Some(&map[t * n2..][..n2]), out);
}

/// Bilinear sample at `uv` into `out` of the `R²` map whose texel `t` holds `texel(t)` (`None`:
/// zeros, a texel no transfer is stored for): the four texels whose centres
/// `((x+½)/R, (y+½)/R)` surround `uv`, clamped to the edge. Written as two nested lerps
/// `a + (b − a)·t`, so a footprint of equal values returns that value exactly. A NaN
/// coordinate samples as 0.
///
/// # Panics
/// If a texel's values are not `out.len()` long.
pub fn sample_bilinear_by<'m>(
    resolution: usize,
    uv: [f32; 2],
    texel: impl Fn(usize) -> Option<&'m [f32]>,
    out: &mut [f32],
) {
    if resolution == 0 {
        return;
    }
    let last = resolution - 1;
    let axis = |c: f32| {
        let c = if c.is_nan() { 0.0 } else { c };
        let x = (f64::from(c) * resolution as f64 - 0.5).clamp(0.0, last as f64);
        let i = (x.floor() as usize).min(last);
        (i, (i + 1).min(last), (x - i as f64) as f32)
    };
    let ((x0, x1, fx), (y0, y1, fy)) = (axis(uv[0]), axis(uv[1]));
    let taps = [(x0, y0), (x1, y0), (x0, y1), (x1, y1)].map(|(x, y)| texel(y * resolution + x));
    assert!(
        taps.iter().flatten().all(|v| v.len() == out.len()),
        "texel size"
    );
    let value = |tap: usize, k: usize| taps[tap].map_or(0.0, |v| v[k]);
    let lerp = |p: f32, q: f32, t: f32| p + (q - p) * t;
    for (k, o) in out.iter_mut().enumerate() {
        *o = lerp(
            lerp(value(0, k), value(1, k), fx),
            lerp(value(2, k), value(3, k), fx),
            fy,
        );
    }
}
