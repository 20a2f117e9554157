// Per-vertex lights through each vertex's own transfer (aprt-core's `Model::shade_lights`,
// *Irradiance Rigs*): a light's radiance seen from the vertex is zonal about the direction
// towards it, so `rgb_v = Σ_i w_i c_i Σ_l b_il Σ_m t_lm y_lm(R_bᵀ ω_iv)`. One invocation per
// vertex; follows rows.wgsl, sh.wgsl and weights.wgsl.

const PI: f32 = 3.14159265358979;
// y_00 = 1 / (2√π): the only basis value of uniform radiance (inside a sphere light).
const Y00: f32 = 0.2820948;

// One light as aprt-core's `Light::shape` gives it, with its colour and weight.
struct Light {
    // A sphere's centre, or towards a directional light.
    position: vec3<f32>,
    radius: f32,
    colour: vec3<f32>,
    // A sphere's radiance per unit colour.
    radiance: f32,
    weight: f32,
    directional: u32,
}

struct LightsInfo {
    count: u32,
    order: u32,
}

@group(0) @binding(3) var<storage, read_write> rgb: array<f32>;
@group(0) @binding(4) var<storage, read> lights: array<Light>;
@group(0) @binding(5) var<storage, read> positions: array<f32>;
// Each bone's rotation, row-major, nine values (none for a world-frame model).
@group(0) @binding(6) var<storage, read> rotations: array<f32>;
@group(0) @binding(7) var<uniform> info: LightsInfo;

// A sphere light's un-normalised zonal bands seen from `d` (aprt-core's
// `sphere_light_bands`): 2π ∫ P_l over the cap, uniform [4π, 0, …] inside.
fn sphere_bands(radius: f32, d: f32) -> array<f32, 6> {
    if d < radius {
        return array<f32, 6>(4.0 * PI, 0.0, 0.0, 0.0, 0.0, 0.0);
    }
    let s = radius / d;
    let c = sqrt(max(((d - radius) / d) * (1.0 + s), 0.0));
    let u = s * s;
    return array<f32, 6>(
        2.0 * PI * u / (1.0 + c),
        PI * u,
        PI * u * c,
        PI * u * (1.0 - 1.25 * u),
        0.25 * PI * u * (4.0 - 7.0 * u) * c,
        0.125 * PI * u * (8.0 + u * (-28.0 + 21.0 * u)),
    );
}

fn unit(d: vec3<f32>) -> vec3<f32> {
    return d * (1.0 / sqrt(d.x * d.x + d.y * d.y + d.z * d.z));
}

@compute @workgroup_size(64)
fn shade_lights(
    @builtin(global_invocation_id) id: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    let v = invocation(id, groups);
    if v >= shape.vertices {
        return;
    }
    let order = info.order;
    let t = vertex_transfer(v);
    let p = vec3<f32>(positions[3u * v], positions[3u * v + 1u], positions[3u * v + 2u]);
    let b = 9u * vertex_bone(v);
    var acc = vec3<f32>(0.0);
    for (var i = 0u; i < info.count; i++) {
        let light = lights[i];
        if light.weight == 0.0 {
            continue;
        }
        var bands = array<f32, 6>(1.0, 1.0, 1.0, 1.0, 1.0, 1.0);
        var omega = light.position;
        var inside = false;
        if light.directional == 0u {
            omega = light.position - p;
            let d = sqrt(omega.x * omega.x + omega.y * omega.y + omega.z * omega.z);
            bands = sphere_bands(light.radius, d);
            for (var l = 0u; l < 6u; l++) {
                bands[l] *= light.radiance;
            }
            inside = d < light.radius;
        }
        var seen: f32;
        if inside {
            seen = bands[0] * Y00 * t[0];
        } else {
            omega = unit(omega);
            if shape.lead_rows > 0u {
                // R_bᵀ ω: the direction in the vertex's bone frame.
                omega = vec3<f32>(
                    rotations[b] * omega.x + rotations[b + 3u] * omega.y + rotations[b + 6u] * omega.z,
                    rotations[b + 1u] * omega.x + rotations[b + 4u] * omega.y + rotations[b + 7u] * omega.z,
                    rotations[b + 2u] * omega.x + rotations[b + 5u] * omega.y + rotations[b + 8u] * omega.z,
                );
            }
            let y = sh_basis(unit(omega), order);
            seen = 0.0;
            for (var l = 0u; l < order; l++) {
                var band = 0.0;
                for (var c = l * l; c < (l + 1u) * (l + 1u); c++) {
                    band += t[c] * y[c];
                }
                seen += bands[l] * band;
            }
        }
        acc += (seen * light.weight) * light.colour;
    }
    rgb[3u * v] = acc.x;
    rgb[3u * v + 1u] = acc.y;
    rgb[3u * v + 2u] = acc.z;
}
