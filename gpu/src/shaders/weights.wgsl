// This frame's transfer weights (aprt-core's `ModelInfo::transfer_weights`) and a vertex's
// transfer from them; follows rows.wgsl. Stored basis: `t_c = Σ_k w[k n² + c] U_k`; identity
// basis: row `c (1 + k_a) + i` feeds coefficient c alone, `t_c = Σ_i w[r] X_r`.

@group(0) @binding(2) var<storage, read> weights: array<f32>;

// Vertex `v`'s n² transfer values (in its bone's frame for a bone-frame model; the rest 0).
// Each row value is decoded once; each coefficient sums its terms in row order, as aprt-core
// does.
fn vertex_transfer(v: u32) -> array<f32, 36> {
    let n2 = shape.coeffs;
    var t: array<f32, 36>;
    if shape.identity == 0u {
        for (var k = 0u; k < shape.row_width; k++) {
            let u = row_value(v, shape.lead_rows + k);
            for (var c = 0u; c < n2; c++) {
                t[c] += weights[k * n2 + c] * u;
            }
        }
    } else {
        let per = shape.row_width / n2;
        for (var c = 0u; c < n2; c++) {
            for (var i = 0u; i < per; i++) {
                let r = c * per + i;
                t[c] += weights[r] * row_value(v, shape.lead_rows + r);
            }
        }
    }
    return t;
}
