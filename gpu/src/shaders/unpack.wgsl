// Widens packed rows to f32, as a model's f16 and i8 sections are stored: each invocation
// takes one u32 word of each input, two f16 values (`unpack2x16float`, exact) and four i8
// values (sign-extended with `extractBits` on i32, then times their row's scale: one rounding,
// as on the CPU). The Rust side is `aprt_gpu::unpack`.

struct Params {
    // Words in `halves`, two f16 values each (the first in the low 16 bits).
    half_words: u32,
    // Words in `quads`, four i8 values each (the first in the low byte).
    quad_words: u32,
    // The i8 values in `quads`: the last word may hold fewer than four.
    quad_values: u32,
    // i8 values per row; row r is scaled by `scales[r]`.
    row_len: u32,
    // Invocations per row of the dispatch grid: a large input is dispatched in 2D, since one
    // dimension holds at most 65,535 workgroups.
    grid_width: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> halves: array<u32>;
@group(0) @binding(2) var<storage, read> quads: array<u32>;
@group(0) @binding(3) var<storage, read> scales: array<f32>;
@group(0) @binding(4) var<storage, read_write> from_f16: array<vec2<f32>>;
@group(0) @binding(5) var<storage, read_write> from_i8: array<f32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let word = id.x + id.y * params.grid_width;
    if word < params.half_words {
        from_f16[word] = unpack2x16float(halves[word]);
    }
    if word < params.quad_words {
        let packed = bitcast<i32>(quads[word]);
        for (var k = 0u; k < 4u; k++) {
            let i = word * 4u + k;
            if i < params.quad_values {
                from_i8[i] = f32(extractBits(packed, k * 8u, 8u)) * scales[i / params.row_len];
            }
        }
    }
}
