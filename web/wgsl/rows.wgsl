// The vertex rows as aprt-core stores them (`VertexRows`): blocks of 8 vertices, each
// `lead_rows` rows of bone indices then `row_width` rows, every row 8 values (one per vertex
// of the block) of one encoding, uploaded as they are in 32-bit words. Shared by every
// kernel that reads the rows.

struct Rows {
    // Vertices of the model.
    vertices: u32,
    // 0: f32, 1: f16, 2: scaled bytes (integers; the weights carry the scales).
    encoding: u32,
    // Rows of bone indices per block (1 for a bone-frame model, else 0).
    lead_rows: u32,
    // Rows of values per block.
    row_width: u32,
    // Words per block: 8 (lead_rows + row_width) values of 4, 2 or 1 bytes.
    block_words: u32,
    // Bones (1 for a world-frame model): bone indices are clamped below it.
    bones: u32,
    // Transfer coefficients n² (transfer kernels only).
    coeffs: u32,
    // 0: stored basis, 1: identity basis (transfer kernels only).
    identity: u32,
}

const VERTEX_BLOCK: u32 = 8u;

@group(0) @binding(0) var<uniform> shape: Rows;
@group(0) @binding(1) var<storage, read> rows: array<u32>;

// Row `row` (lead rows counted) of vertex `v`'s block, at its lane, as stored: f32, f16
// widened (exact), or the signed byte as an integer (exact).
fn row_value(v: u32, row: u32) -> f32 {
    let block = v / VERTEX_BLOCK;
    let lane = v % VERTEX_BLOCK;
    let base = block * shape.block_words;
    switch shape.encoding {
        case 0u: {
            return bitcast<f32>(rows[base + row * 8u + lane]);
        }
        case 1u: {
            let pair = unpack2x16float(rows[base + row * 4u + lane / 2u]);
            return pair[lane % 2u];
        }
        default: {
            let word = bitcast<i32>(rows[base + row * 2u + lane / 4u]);
            return f32(extractBits(word, (lane % 4u) * 8u, 8u));
        }
    }
}

// Vertex `v`'s bone: the lead row's value, an exact integer (unsigned for bytes), clamped
// below the bone count as aprt-core clamps it; 0 for a world-frame model.
fn vertex_bone(v: u32) -> u32 {
    if shape.lead_rows == 0u {
        return 0u;
    }
    var bone: u32;
    if shape.encoding == 2u {
        let lane = v % VERTEX_BLOCK;
        let word = rows[(v / VERTEX_BLOCK) * shape.block_words + lane / 4u];
        bone = extractBits(word, (lane % 4u) * 8u, 8u);
    } else {
        bone = u32(row_value(v, 0u));
    }
    return min(bone, shape.bones - 1u);
}

// The invocation's index in a dispatch of `groups` workgroups of 64, laid out in rows of at
// most 65535 workgroups (the per-dimension limit) when a frame needs more.
fn invocation(id: vec3<u32>, groups: vec3<u32>) -> u32 {
    return id.x + id.y * groups.x * 64u;
}
