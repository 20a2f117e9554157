// The occluder proxies' correction (aprt-core's `proxies/`, `Model::occlude` and
// `Model::occlude_transfer`): each vertex loses the caps of the posed spheres its bone's mask
// holds, within their reach, summed in proxy order and combined by their visible fractions.
// One invocation per vertex; this file follows rows.wgsl and sh.wgsl. The `acos` and `atan`
// are aprt-core's polynomials (Abramowitz and Stegun 4.4.46 and 4.4.49, within 2e-8), not
// WGSL's built-ins, whose error a device chooses (1.3e-4 measured on lavapipe).

const PI: f32 = 3.14159265358979;
const MAX_PROXIES: u32 = 64u;

struct Proxies {
    // sin²α below which a cap is dropped; caps fade in over [cull, 2 cull].
    cull: f32,
    // SH order of the model.
    order: u32,
    pad: vec2<u32>,
    // Proxy i: [2i] = posed centre and radius, [2i + 1].x = reach.
    spheres: array<vec4<f32>, 128>,
}

@group(0) @binding(2) var<uniform> proxies: Proxies;
// Per bone, the proxies that may reach its vertices (bit i of the 64: word i / 32).
@group(0) @binding(3) var<storage, read> masks: array<vec2<u32>>;
// Per vertex, its posed world position then its normal (six values).
@group(0) @binding(4) var<storage, read> vertices: array<f32>;

var<private> ACOS: array<f32, 8> = array<f32, 8>(
    1.570796305, -0.2145988016, 0.0889789874, -0.0501743046,
    0.0308918810, -0.0170881256, 0.0066700901, -0.0012624911,
);
var<private> ATAN: array<f32, 9> = array<f32, 9>(
    1.0, -0.3333314528, 0.1999355085, -0.1420889944, 0.1065626393,
    -0.0752896400, 0.0429096138, -0.0161657367, 0.0028662257,
);

fn acos_poly(x: f32) -> f32 {
    let a = abs(x);
    var p = 0.0;
    for (var k = 8u; k > 0u; k--) {
        p = p * a + ACOS[k - 1u];
    }
    p = sqrt(max(1.0 - a, 0.0)) * p;
    return select(p, PI - p, x < 0.0);
}

// atan2(y, x) for y, x ≥ 0, in [0, π/2].
fn atan2_positive(y: f32, x: f32) -> f32 {
    let lo = min(y, x);
    let hi = max(y, x);
    let t = select(0.0, lo / hi, 0.0 < hi);
    let t2 = t * t;
    var p = 0.0;
    for (var k = 9u; k > 0u; k--) {
        p = p * t2 + ATAN[k - 1u];
    }
    p = t * p;
    return select(p, 1.5707963267948966 - p, x < y);
}

// The irradiance of a unit-radiance sphere's cap of sin²α = s2 at cos β: π sin²α cos β
// above the horizon, Snyder's horizon-clipped form below it.
fn form_factor(s2: f32, cot_alpha: f32, cos_beta: f32) -> f32 {
    if s2 < cos_beta * cos_beta {
        return PI * s2 * max(cos_beta, 0.0);
    }
    let sin_beta = sqrt(max(1.0 - cos_beta * cos_beta, 0.0));
    let y = clamp(-(cot_alpha * cos_beta / sin_beta), -1.0, 1.0);
    let w = sin_beta * sqrt(max(1.0 - y * y, 0.0));
    let clipped = (cos_beta * acos_poly(y) - cot_alpha * w) * s2 + atan2_positive(w, cot_alpha);
    return max(clipped, 0.0);
}

// The cosine-weighted cap's zonal bands relative to band 0, from c = cos α.
fn band_ratios(c: f32) -> array<f32, 6> {
    let c2 = c * c;
    let c3 = c * c * c;
    return array<f32, 6>(
        1.0,
        (1.0 + c + c2) * (2.0 / 3.0) / (1.0 + c),
        (3.0 * c2 + 1.0) * 0.25,
        c3,
        (35.0 * c2 * c2 - 10.0 * c2 - 1.0) * (1.0 / 24.0),
        c3 * (9.0 * c2 - 5.0) * 0.25,
    );
}

// One sphere's cap seen from a vertex: its form factor (0: nothing), the world axis its
// bands are taken about, and cos α.
struct Cap {
    f: f32,
    axis: vec3<f32>,
    cos_alpha: f32,
}

fn cap(i: u32, p: vec3<f32>, n: vec3<f32>) -> Cap {
    let sphere = proxies.spheres[2u * i];
    let reach = proxies.spheres[2u * i + 1u].x;
    let v = sphere.xyz - p;
    let d2 = v.x * v.x + v.y * v.y + v.z * v.z;
    let nothing = Cap(0.0, vec3<f32>(0.0, 0.0, 1.0), 0.0);
    if !(d2 < reach * reach) {
        return nothing;
    }
    let radius = sphere.w;
    let r2 = radius * radius;
    if d2 <= r2 {
        // Inside the sphere: the whole lobe, about the normal.
        return Cap(PI, n, 0.0);
    }
    let inverse_d = 1.0 / sqrt(d2);
    let s2 = r2 * (inverse_d * inverse_d);
    var weight = 1.0;
    if proxies.cull > 0.0 {
        let t = clamp((s2 - proxies.cull) * (1.0 / proxies.cull), 0.0, 1.0);
        weight = t * t * (3.0 - 2.0 * t);
    }
    let a = v * inverse_d;
    let cos_beta = a.x * n.x + a.y * n.y + a.z * n.z;
    let root = sqrt(max(d2 - r2, 0.0));
    let cos_alpha = root * inverse_d;
    let cot_alpha = root * (1.0 / radius);
    let unweighted = form_factor(s2, cot_alpha, cos_beta);
    let f = weight * unweighted;
    if !(0.0 < f) {
        return nothing;
    }
    // The cap's centre of weight: its axis moved towards the normal by the cosine's tilt.
    let inverse_f = 1.0 / unweighted;
    let kept = clamp(PI * s2 * cos_beta * inverse_f, 0.0, 1.0);
    let gap = 1.0 - cos_alpha;
    let shift = kept * PI * gap * gap * inverse_f;
    return Cap(f, a + shift * (n - cos_beta * a), cos_alpha);
}

// A vertex's position, unit normal and proxy mask; `valid` false when no proxy can reach it
// (no mask, or a normal without a direction).
struct Receiver {
    p: vec3<f32>,
    n: vec3<f32>,
    mask: vec2<u32>,
    valid: bool,
}

fn receiver(v: u32) -> Receiver {
    let base = v * 6u;
    let p = vec3<f32>(vertices[base], vertices[base + 1u], vertices[base + 2u]);
    let n = vec3<f32>(vertices[base + 3u], vertices[base + 4u], vertices[base + 5u]);
    let length = sqrt(n.x * n.x + n.y * n.y + n.z * n.z);
    // `vertex_bone` is below the bone count (1 for a world-frame model): one mask each.
    let mask = masks[vertex_bone(v)];
    // A finite length: at most f32's largest.
    let valid = 1e-20 < length && length <= 3.4028234e38 && any(mask != vec2<u32>(0u));
    return Receiver(p, n / length, mask, valid);
}

// The next proxy of `mask` (its lowest bit), cleared from it; MAX_PROXIES when none is left.
fn next_proxy(mask: ptr<function, vec2<u32>>) -> u32 {
    if (*mask).x != 0u {
        let i = firstTrailingBit((*mask).x);
        (*mask).x &= (*mask).x - 1u;
        return i;
    }
    if (*mask).y != 0u {
        let i = firstTrailingBit((*mask).y);
        (*mask).y &= (*mask).y - 1u;
        return 32u + i;
    }
    return MAX_PROXIES;
}

// The union of a vertex's caps: their form factors' sum and the share of the lobe none of
// them blocks.
struct Union {
    total: f32,
    visible: f32,
}

fn union_add(u: ptr<function, Union>, f: f32) {
    (*u).total += f;
    (*u).visible *= max(1.0 - f * (1.0 / PI), 0.0);
}

// The scale that takes the summed caps to their union, π (1 − Π (1 − F_i/π)) / Σ F_i.
fn union_scale(u: Union) -> f32 {
    return PI * (1.0 - u.visible) / u.total;
}

// The vertex of an invocation that some proxy may reach: `valid` false for any other (beyond
// the model's vertices, no mask, or a normal without a direction).
fn occluded_vertex(id: vec3<u32>, groups: vec3<u32>) -> Receiver {
    let v = invocation(id, groups);
    if v >= shape.vertices {
        return Receiver(vec3<f32>(0.0), vec3<f32>(0.0), vec2<u32>(0u), false);
    }
    return receiver(v);
}

@group(0) @binding(5) var<storage, read> lighting: array<f32>;
@group(0) @binding(6) var<storage, read_write> shading: array<f32>;

// Subtracts from each vertex's shading what the caps block under the world SH lighting.
@compute @workgroup_size(64)
fn occlude_shading(
    @builtin(global_invocation_id) id: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    let r = occluded_vertex(id, groups);
    if !r.valid {
        return;
    }
    let order = proxies.order;
    var mask = r.mask;
    var u = Union(0.0, 1.0);
    var sum = 0.0;
    for (var i = next_proxy(&mask); i < MAX_PROXIES; i = next_proxy(&mask)) {
        let c = cap(i, r.p, r.n);
        if c.f == 0.0 {
            continue;
        }
        let y = sh_basis(normalize_axis(c.axis), order);
        let ratios = band_ratios(c.cos_alpha);
        var bands = 0.0;
        for (var l = 0u; l < order; l++) {
            var band = 0.0;
            for (var k = l * l; k < (l + 1u) * (l + 1u); k++) {
                band += lighting[k] * y[k];
            }
            bands += ratios[l] * band;
        }
        sum += c.f * bands;
        union_add(&u, c.f);
    }
    if 0.0 < u.total {
        shading[invocation(id, groups)] -= sum * union_scale(u);
    }
}

// `axis` at unit length (it is at least 1 long: its shift is perpendicular to a unit vector).
fn normalize_axis(axis: vec3<f32>) -> vec3<f32> {
    let length = sqrt(axis.x * axis.x + axis.y * axis.y + axis.z * axis.z);
    return axis * (1.0 / length);
}

// Each bone's rotation, row-major, nine values: the occlusion is in the vertex's bone frame.
@group(0) @binding(7) var<storage, read> rotations: array<f32>;
@group(0) @binding(8) var<storage, read_write> transfer: array<f32>;

// Subtracts from each vertex's n² transfer values the caps' occlusion, in its bone's frame.
@compute @workgroup_size(64)
fn occlude_transfer(
    @builtin(global_invocation_id) id: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    let r = occluded_vertex(id, groups);
    if !r.valid {
        return;
    }
    let v = invocation(id, groups);
    let order = proxies.order;
    let b = 9u * vertex_bone(v);
    var mask = r.mask;
    var u = Union(0.0, 1.0);
    var sums: array<f32, 36>;
    for (var i = next_proxy(&mask); i < MAX_PROXIES; i = next_proxy(&mask)) {
        let c = cap(i, r.p, r.n);
        if c.f == 0.0 {
            continue;
        }
        // Rᵀ a: the world axis in the bone's frame.
        let a = c.axis;
        let local = vec3<f32>(
            rotations[b] * a.x + rotations[b + 3u] * a.y + rotations[b + 6u] * a.z,
            rotations[b + 1u] * a.x + rotations[b + 4u] * a.y + rotations[b + 7u] * a.z,
            rotations[b + 2u] * a.x + rotations[b + 5u] * a.y + rotations[b + 8u] * a.z,
        );
        let y = sh_basis(normalize_axis(local), order);
        let ratios = band_ratios(c.cos_alpha);
        for (var l = 0u; l < order; l++) {
            let weight = c.f * ratios[l];
            for (var k = l * l; k < (l + 1u) * (l + 1u); k++) {
                sums[k] += weight * y[k];
            }
        }
        union_add(&u, c.f);
    }
    if 0.0 < u.total {
        let scale = union_scale(u);
        let n2 = order * order;
        for (var k = 0u; k < n2; k++) {
            transfer[v * n2 + k] -= sums[k] * scale;
        }
    }
}
