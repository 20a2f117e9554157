//! The fixed direction pattern of the transfer estimator and its placement on a vertex.
//!
//! One cosine-weighted low-discrepancy pattern (Hammersley points mapped by Malley's method)
//! is generated once per bake and rotated into every vertex's tangent frame. Cosine-weighted
//! sampling makes the estimator `t_c ≈ (π/N) Σ V(ω_i) y_c(ω_i)`: the `max(n·ω, 0)` factor of
//! the transfer integral cancels against the sample density `cos θ / π`, so an unoccluded
//! vertex gets a DC term of exactly `π·y_00`, and Hammersley points converge at close to
//! `O(log N / N)` instead of the `O(1/√N)` of random rays.

use glam::DVec3;

/// `N` cosine-weighted directions in the local frame (z = normal), unit length, `z > 0`.
///
/// Point `i` is the Hammersley point `((i + ½)/N, radical_inverse₂(i))`, mapped by Malley's
/// method: the first coordinate is the squared radius on the unit disc (so equal areas on the
/// disc, hence density `cos θ / π` on the hemisphere), the second the azimuth. The half-cell
/// offset keeps every direction strictly above the horizon (`z ≥ √(1/(2N))`) and strictly
/// off the pole's degenerate azimuth.
pub(crate) fn cosine_hammersley(n: usize) -> Vec<DVec3> {
    (0..n)
        .map(|i| {
            let r2 = (i as f64 + 0.5) / n as f64;
            let phi = std::f64::consts::TAU * radical_inverse_base2(i as u32);
            let r = r2.sqrt();
            DVec3::new(r * phi.cos(), r * phi.sin(), (1.0 - r2).sqrt())
        })
        .collect()
}

/// The indices of `pattern` in Morton (Z-curve) order of their position on the unit disc (the
/// local `x, y`): consecutive entries point in similar directions, in every vertex's frame
/// alike, since placing the pattern is a rotation. The packet walk (`wide::packet`) groups
/// consecutive rays into packets, and the closer a packet's rays, the more nodes they share.
pub(crate) fn coherent_order(pattern: &[DVec3]) -> Vec<u32> {
    // 16 bits per coordinate: far finer than 4096 directions need.
    let cell = |x: f64| (((x + 1.0) * 0.5).clamp(0.0, 1.0) * 65535.0) as u32;
    let spread = |v: u32| (0..16).fold(0u64, |acc, bit| acc | u64::from(v >> bit & 1) << (2 * bit));
    let mut order: Vec<u32> = (0..pattern.len() as u32).collect();
    order.sort_by_key(|&i| {
        let d = pattern[i as usize];
        spread(cell(d.x)) | spread(cell(d.y)) << 1
    });
    order
}

/// Van der Corput radical inverse in base 2: the bits of `i` mirrored about the binary point.
fn radical_inverse_base2(i: u32) -> f64 {
    f64::from(i.reverse_bits()) / 4_294_967_296.0
}

/// A right-handed orthonormal frame `(t, b, n)` around the unit vector `n`.
///
/// Duff et al. 2017, "Building an Orthonormal Basis, Revisited": branch-free apart from the
/// sign, continuous everywhere except across `n.z = 0⁻/0⁺`, and exact at both poles (the
/// classic Frisvad construction loses all precision near `n.z = −1`).
pub(crate) fn tangent_frame(n: DVec3) -> (DVec3, DVec3) {
    let sign = 1.0f64.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    let t = DVec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
    let bt = DVec3::new(b, sign + n.y * n.y * a, -n.y);
    (t, bt)
}

/// A deterministic rotation angle about the normal for vertex `j`, in radians.
///
/// Every vertex would otherwise use the same pattern in the same orientation, so the QMC error
/// of neighbouring vertices would be correlated and show up as structured banding across the
/// surface. A hash of the vertex index (SplitMix64 finaliser) decorrelates them while keeping
/// the bake a pure function of the input: no thread or run dependence.
pub(crate) fn vertex_rotation(j: usize) -> f64 {
    let mut z = (j as u64).wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    std::f64::consts::TAU * ((z >> 11) as f64 / (1u64 << 53) as f64)
}

/// The frame `[t, b, n]` of a vertex with unit normal `n`: the [`tangent_frame`] rotated by
/// `angle` about `n`. Its columns map the local pattern (z = normal) to world space, so it is
/// also the rotation that carries an SH vector accumulated in the local frame to world space.
pub(crate) fn vertex_frame(n: DVec3, angle: f64) -> [DVec3; 3] {
    let (t0, b0) = tangent_frame(n);
    let (s, c) = angle.sin_cos();
    [t0 * c + b0 * s, b0 * c - t0 * s, n]
}

/// `frame` as the row-major matrix whose columns are its axes: the rotation from the local
/// pattern's frame to world space, in the form SH rotations take.
pub(crate) fn frame_matrix(frame: &[DVec3; 3]) -> [[f64; 3]; 3] {
    std::array::from_fn(|row| frame.map(|axis| axis[row]))
}

/// Places the local pattern in `frame` (from [`vertex_frame`]). Writes world-space unit
/// directions into `out` (cleared first).
pub(crate) fn place_pattern(pattern: &[DVec3], frame: &[DVec3; 3], out: &mut Vec<DVec3>) {
    let [t, b, n] = *frame;
    out.clear();
    out.extend(
        pattern
            .iter()
            .map(|d| (t * d.x + b * d.y + n * d.z).normalize()),
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pattern_is_unit_and_strictly_above_the_horizon() {
        for n in [1, 7, 500, 4096] {
            let p = cosine_hammersley(n);
            assert_eq!(p.len(), n);
            for d in &p {
                assert!((d.length() - 1.0).abs() < 1e-12);
                assert!(d.z >= (0.5 / n as f64).sqrt() - 1e-12, "{d:?}");
            }
        }
    }

    #[test]
    fn pattern_has_the_cosine_moments() {
        // E[cos θ] under density cos θ/π is 2/3, E[cos² θ] is 1/2; E[x] = E[y] = 0.
        let p = cosine_hammersley(4096);
        let mean = |f: &dyn Fn(&DVec3) -> f64| p.iter().map(f).sum::<f64>() / p.len() as f64;
        assert!((mean(&|d| d.z) - 2.0 / 3.0).abs() < 1e-4);
        assert!((mean(&|d| d.z * d.z) - 0.5).abs() < 1e-6);
        assert!(mean(&|d| d.x).abs() < 1e-3 && mean(&|d| d.y).abs() < 1e-3);
    }

    #[test]
    fn coherent_order_is_a_permutation_of_close_neighbours() {
        let p = cosine_hammersley(500);
        let order = coherent_order(&p);
        let mut sorted = order.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..500).collect::<Vec<u32>>());
        // Consecutive directions in index order are far apart (the radical inverse jumps
        // round the circle); in coherent order they are close on average.
        let mean_gap = |ids: &mut dyn Iterator<Item = u32>| {
            let ids: Vec<u32> = ids.collect();
            let gaps = ids
                .windows(2)
                .map(|w| (p[w[0] as usize] - p[w[1] as usize]).length());
            gaps.sum::<f64>() / (ids.len() - 1) as f64
        };
        let (plain, coherent) = (mean_gap(&mut (0..500)), mean_gap(&mut order.into_iter()));
        assert!(coherent < plain / 4.0, "{coherent} vs {plain}");
    }

    #[test]
    fn frames_are_orthonormal_and_right_handed_everywhere() {
        let normals = [
            DVec3::Z,
            -DVec3::Z,
            DVec3::X,
            -DVec3::Y,
            DVec3::new(1e-9, 0.0, -1.0).normalize(),
            DVec3::new(0.3, -0.5, 0.8).normalize(),
        ];
        for n in normals {
            let (t, b) = tangent_frame(n);
            assert!((t.length() - 1.0).abs() < 1e-12 && (b.length() - 1.0).abs() < 1e-12);
            assert!(t.dot(b).abs() < 1e-12 && t.dot(n).abs() < 1e-12 && b.dot(n).abs() < 1e-12);
            assert!((t.cross(b) - n).length() < 1e-12, "{n:?}");
        }
    }

    #[test]
    fn placed_directions_keep_their_angle_to_the_normal() {
        let p = cosine_hammersley(64);
        let n = DVec3::new(-0.2, 0.9, -0.1).normalize();
        let mut out = Vec::new();
        place_pattern(&p, &vertex_frame(n, vertex_rotation(17)), &mut out);
        for (local, world) in p.iter().zip(&out) {
            assert!((world.dot(n) - local.z).abs() < 1e-12);
        }
        assert_ne!(vertex_rotation(0), vertex_rotation(1));
    }
}
