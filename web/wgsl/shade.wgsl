// Shading: `out_v = Σ_r q[bone(v) · row_width + r] U_r(v)`, q the lighting weights aprt-core's
// `Model::light` computed this frame (`ModelInfo::lit_values`). One invocation per vertex.

@group(0) @binding(2) var<storage, read> lit: array<f32>;
@group(0) @binding(3) var<storage, read_write> shading: array<f32>;

@compute @workgroup_size(64)
fn shade(@builtin(global_invocation_id) id: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    let v = invocation(id, groups);
    if v >= shape.vertices {
        return;
    }
    let q0 = vertex_bone(v) * shape.row_width;
    var sum = 0.0;
    for (var r = 0u; r < shape.row_width; r++) {
        sum += lit[q0 + r] * row_value(v, shape.lead_rows + r);
    }
    shading[v] = sum;
}
