//! Reading a map back at a UV: bilinear filtering as a GPU samples a texture with clamp to edge.

/// Bilinear sample of an `R²·n2` map (texel-major, `[texel·n2 + c]`) at `uv`, into `out` (`n2`
/// values): the four texels whose centres `((x+½)/R, (y+½)/R)` surround `uv`, clamped to the
/// edge. Written as two nested lerps `a + (b − a)·t`, so a footprint of equal values returns
/// that value exactly. A NaN coordinate samples as 0.
///
/// # Panics
/// If `map` is not `resolution²·n2` long or `out` not `n2`.
pub fn sample_bilinear(map: &[f32], resolution: usize, n2: usize, uv: [f32; 2], out: &mut [f32]) {
    assert_eq!(map.len(), resolution * resolution * n2, "map size");
    assert_eq!(out.len(), n2, "output size");
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
    let texel = |x: usize, y: usize| &map[(y * resolution + x) * n2..][..n2];
    let (a, b, c, d) = (texel(x0, y0), texel(x1, y0), texel(x0, y1), texel(x1, y1));
    let lerp = |p: f32, q: f32, t: f32| p + (q - p) * t;
    for (k, o) in out.iter_mut().enumerate() {
        *o = lerp(lerp(a[k], b[k], fx), lerp(c[k], d[k], fx), fy);
    }
}
