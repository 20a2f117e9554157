// Transfer: n² values per vertex, vertex-major (in its bone's frame for a bone-frame model);
// follows rows.wgsl and weights.wgsl. One invocation per vertex.

@group(0) @binding(3) var<storage, read_write> transfer: array<f32>;

@compute @workgroup_size(64)
fn transfer_values(
    @builtin(global_invocation_id) id: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    let v = invocation(id, groups);
    if v >= shape.vertices {
        return;
    }
    let n2 = shape.coeffs;
    let t = vertex_transfer(v);
    for (var c = 0u; c < n2; c++) {
        transfer[v * n2 + c] = t[c];
    }
}
