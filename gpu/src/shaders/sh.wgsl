// The real orthonormal SH basis up to order 6, as aprt-core evaluates it (`sh.rs`,
// `basis_lanes`): column m at a time, the associated Legendre recurrence with its weights
// tabulated, no Condon-Shortley phase, coefficient (l, m) at index l² + l + m. The tables are
// aprt-core's, printed in f64 and rounded to f32 as the core rounds them.

const MAX_ORDER: u32 = 6u;
const MAX_COEFFS: u32 = 36u;

// K_l^m at [l · 6 + m].
var<private> SH_NORMS: array<f32, 36> = array<f32, 36>(
    0.28209479177387814, 0.0, 0.0, 0.0, 0.0, 0.0,
    0.4886025119029199, 0.3454941494713355, 0.0, 0.0, 0.0, 0.0,
    0.6307831305050401, 0.25751613468212636, 0.12875806734106318, 0.0, 0.0, 0.0,
    0.7463526651802308, 0.21545345607610045, 0.06813236509555216, 0.02781492157551894, 0.0, 0.0,
    0.8462843753216345, 0.18923493915151202, 0.044603102903819275, 0.011920680675222404, 0.004214597070904597, 0.0,
    0.9356025796273888, 0.17081687924064806, 0.03228135587163618, 0.006589404174225528, 0.0015531374585246044, 0.000491145188826305,
);

// The recurrence P_l^m = a z P_{l-1}^m − b P_{l-2}^m at [l · 6 + m]: a = (2l − 1)/(l − m),
// b = (l + m − 1)/(l − m).
var<private> SH_A: array<f32, 36> = array<f32, 36>(
    0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    1.5, 0.0, 0.0, 0.0, 0.0, 0.0,
    1.6666666666666667, 2.5, 0.0, 0.0, 0.0, 0.0,
    1.75, 2.3333333333333335, 3.5, 0.0, 0.0, 0.0,
    1.8, 2.25, 3.0, 4.5, 0.0, 0.0,
);
var<private> SH_B: array<f32, 36> = array<f32, 36>(
    0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0.5, 0.0, 0.0, 0.0, 0.0, 0.0,
    0.6666666666666666, 1.5, 0.0, 0.0, 0.0, 0.0,
    0.75, 1.3333333333333333, 2.5, 0.0, 0.0, 0.0,
    0.8, 1.25, 2.0, 3.5, 0.0, 0.0,
);

// (2m − 1)!!, P_m^m without its phase.
var<private> SH_DOUBLE_FACTORIAL: array<f32, 6> = array<f32, 6>(1.0, 1.0, 3.0, 15.0, 105.0, 945.0);

// The basis at the unit direction `d`, bands 0 .. order − 1 (the rest 0).
fn sh_basis(d: vec3<f32>, order: u32) -> array<f32, 36> {
    var y: array<f32, 36>;
    // Re and Im of (x + iy)^m.
    var cm = 1.0;
    var sm = 0.0;
    for (var m = 0u; m < order; m++) {
        if m > 0u {
            let c = cm * d.x - sm * d.y;
            sm = cm * d.y + sm * d.x;
            cm = c;
        }
        let pmm = SH_DOUBLE_FACTORIAL[m];
        var p_prev2 = 0.0;
        var p_prev = pmm;
        for (var l = m; l < order; l++) {
            var p: f32;
            if l == m {
                p = pmm;
            } else if l == m + 1u {
                p = f32(2u * m + 1u) * d.z * pmm;
            } else {
                p = SH_A[l * 6u + m] * d.z * p_prev - SH_B[l * 6u + m] * p_prev2;
            }
            if l > m {
                p_prev2 = p_prev;
                p_prev = p;
            }
            let k = SH_NORMS[l * 6u + m];
            let centre = l * l + l;
            if m == 0u {
                y[centre] = k * p;
            } else {
                let k2 = (1.4142135623730951 * k) * p;
                y[centre + m] = k2 * cm;
                y[centre - m] = k2 * sm;
            }
        }
    }
    return y;
}
