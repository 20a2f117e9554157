// This frame's transfer weights (aprt-core's `ModelInfo::transfer_weights`) and a vertex's
// transfer from them; follows rows.wgsl. Stored basis: `t_c = Σ_k w[k n² + c] U_k`; identity
// basis: row `c (1 + k_a) + i` feeds coefficient c alone, `t_c = Σ_i w[r] X_r`.

@group(0) @binding(2) var<storage, read> weights: array<f32>;

// Coefficient `c` of vertex `v`'s transfer, in its bone's frame for a bone-frame model.
fn transfer_value(v: u32, c: u32) -> f32 {
    let n2 = shape.coeffs;
    var sum = 0.0;
    if shape.identity == 0u {
        for (var k = 0u; k < shape.row_width; k++) {
            sum += weights[k * n2 + c] * row_value(v, shape.lead_rows + k);
        }
    } else {
        let per = shape.row_width / n2;
        for (var i = 0u; i < per; i++) {
            let r = c * per + i;
            sum += weights[r] * row_value(v, shape.lead_rows + r);
        }
    }
    return sum;
}
