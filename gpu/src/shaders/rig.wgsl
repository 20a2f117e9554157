// Shading under an irradiance rig's lighting at each vertex's own position (aprt-core's
// `Model::shade_rig`, *Irradiance Rigs*): `rgb_v = Σ_k φ_k(p_v) (t_v · C_k)`, each `t_v · C_k`
// the ordinary shading of the pose model under the rig's vector k (weights from
// `Model::light_rig`), at most eight φ_k non-zero at a point. One invocation per vertex;
// follows rows.wgsl.

// The rig's place and shape (aprt-core's `IrradianceRig`, `Placement`).
struct Rig {
    // Root → world rotation, row-major, one row per vec4.
    rotation: array<vec4<f32>, 3>,
    // The root's origin in the world.
    translation: vec4<f32>,
    // The rig box's centre and half-widths, in the root frame.
    centre: vec4<f32>,
    half: vec4<f32>,
    // Each axis's code (0 constant, 1 linear, n ≥ 2 a lattice of n nodes); a gradient rig
    // when `gradient` is 1.
    axes: vec4<u32>,
    gradient: u32,
    // Values of one set of lighting weights (aprt-core's `ModelInfo::lit_weights_len`).
    lit_len: u32,
}

@group(0) @binding(2) var<storage, read> rig_lit: array<f32>;
@group(0) @binding(3) var<storage, read_write> rig_rgb: array<f32>;
@group(0) @binding(4) var<storage, read> rig_positions: array<f32>;
@group(0) @binding(5) var<uniform> rig: Rig;

// The functions of an axis non-zero at `x` (metres from the centre) on half-width `half`:
// their indices (xy) and values (zw), and how many there are.
struct AxisWeights {
    index: vec2<u32>,
    value: vec2<f32>,
    count: u32,
}

fn axis_at(code: u32, x: f32, half: f32) -> AxisWeights {
    if code == 0u {
        return AxisWeights(vec2<u32>(0u, 0u), vec2<f32>(1.0, 0.0), 1u);
    }
    if code == 1u {
        return AxisWeights(vec2<u32>(0u, 1u), vec2<f32>(1.0, x), 2u);
    }
    let cells = f32(code - 1u);
    let t = clamp((x / half + 1.0) * 0.5 * cells, 0.0, cells);
    let i = min(u32(t), code - 2u);
    let f = t - f32(i);
    return AxisWeights(vec2<u32>(i, i + 1u), vec2<f32>(1.0 - f, f), 2u);
}

fn functions(code: u32) -> u32 {
    return select(code, code + 1u, code < 2u);
}

@compute @workgroup_size(64)
fn shade_rig(
    @builtin(global_invocation_id) id: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    let v = invocation(id, groups);
    if v >= shape.vertices {
        return;
    }
    // The position in the root frame (the rotation's transpose), from the rig's centre.
    let world = vec3<f32>(rig_positions[3u * v], rig_positions[3u * v + 1u], rig_positions[3u * v + 2u]);
    let d = world - rig.translation.xyz;
    let r = rig.rotation;
    let p = vec3<f32>(
        r[0].x * d.x + r[1].x * d.y + r[2].x * d.z,
        r[0].y * d.x + r[1].y * d.y + r[2].y * d.z,
        r[0].z * d.x + r[1].z * d.y + r[2].z * d.z,
    ) - rig.centre.xyz;
    // The non-zero φ_k, in ascending k as aprt-core sums them.
    var index: array<u32, 8>;
    var phi: array<f32, 8>;
    var count = 0u;
    if rig.gradient == 1u {
        index = array<u32, 8>(0u, 1u, 2u, 3u, 0u, 0u, 0u, 0u);
        phi = array<f32, 8>(1.0, p.x, p.y, p.z, 0.0, 0.0, 0.0, 0.0);
        count = 4u;
    } else {
        let ax = axis_at(rig.axes.x, p.x, rig.half.x);
        let ay = axis_at(rig.axes.y, p.y, rig.half.y);
        let az = axis_at(rig.axes.z, p.z, rig.half.z);
        let nx = functions(rig.axes.x);
        let ny = functions(rig.axes.y);
        for (var z = 0u; z < az.count; z++) {
            for (var y = 0u; y < ay.count; y++) {
                for (var x = 0u; x < ax.count; x++) {
                    index[count] = ax.index[x] + nx * (ay.index[y] + ny * az.index[z]);
                    phi[count] = ax.value[x] * ay.value[y] * az.value[z];
                    count++;
                }
            }
        }
    }
    // t_v · C_k per vector and channel, each row value decoded once.
    let width = shape.row_width;
    let bone = vertex_bone(v) * width;
    var dots: array<vec3<f32>, 8>;
    for (var row = 0u; row < width; row++) {
        let u = row_value(v, shape.lead_rows + row);
        for (var j = 0u; j < count; j++) {
            let q = 3u * index[j] * rig.lit_len + bone + row;
            dots[j] += u * vec3<f32>(rig_lit[q], rig_lit[q + rig.lit_len], rig_lit[q + 2u * rig.lit_len]);
        }
    }
    var acc = vec3<f32>(0.0);
    for (var j = 0u; j < count; j++) {
        acc += phi[j] * dots[j];
    }
    rig_rgb[3u * v] = acc.x;
    rig_rgb[3u * v + 1u] = acc.y;
    rig_rgb[3u * v + 2u] = acc.z;
}
