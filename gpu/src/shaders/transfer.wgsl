// Transfer: n² values per vertex, vertex-major (in its bone's frame for a bone-frame model),
// from the weights aprt-core's `ModelInfo::transfer_weights` wrote this frame. Stored basis:
// `t_c = Σ_k w[k n² + c] U_k`; identity basis: row `c (1 + k_a) + i` feeds coefficient c
// alone, `t_c = Σ_i w[r] X_r`. One invocation per vertex and coefficient.

@group(0) @binding(2) var<storage, read> weights: array<f32>;
@group(0) @binding(3) var<storage, read_write> transfer: array<f32>;

@compute @workgroup_size(64)
fn transfer_values(@builtin(global_invocation_id) id: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    let n2 = shape.coeffs;
    let index = invocation(id, groups);
    let v = index / n2;
    let c = index % n2;
    if v >= shape.vertices {
        return;
    }
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
    transfer[v * n2 + c] = sum;
}
