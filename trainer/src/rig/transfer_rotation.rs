//! Rotating per-vertex SH transfer: the rotation nearest a blended joint matrix (polar
//! decomposition), and every vertex's SH vector turned by its own rotation with the core's
//! Euler-angle SH rotation ([`aprt_core::ShRotation`]), as the bake and the runtime
//! rotate. Bone frames and the skinned-bind baseline move transfer this way.

use aprt_core::ShRotation;
use glam::DMat3;

/// The rotation nearest to `m` (polar decomposition by Newton iteration `Q ← (Q + Q⁻ᵀ)/2`),
/// for joint matrices that carry scale or shear.
pub fn nearest_rotation(m: DMat3) -> DMat3 {
    let mut q = m;
    for _ in 0..20 {
        let det = q.determinant();
        if !det.is_finite() || det.abs() < 1e-12 {
            return DMat3::IDENTITY;
        }
        let next = (q + q.inverse().transpose()) * 0.5;
        let change = (next - q)
            .to_cols_array()
            .iter()
            .map(|x| x.abs())
            .fold(0.0, f64::max);
        q = next;
        if change < 1e-12 {
            break;
        }
    }
    q
}

/// `r` as the core's row-major `[[f32; 3]; 3]`.
pub fn row_major(r: DMat3) -> [[f32; 3]; 3] {
    let t = r.transpose().to_cols_array_2d();
    t.map(|row| row.map(|x| x as f32))
}

/// Rotates every vertex's SH vector (`n²` values each) by its own rotation `rotations[j]`.
pub fn rotate_each(
    rotation: &ShRotation,
    transfer: &[f32],
    rotations: impl Fn(usize) -> DMat3 + Sync,
) -> Vec<f32> {
    use rayon::prelude::*;
    let n2 = rotation.order() * rotation.order();
    let mut out = vec![0.0f32; transfer.len()];
    out.par_chunks_mut(n2)
        .zip(transfer.par_chunks(n2))
        .enumerate()
        .for_each(|(j, (o, t))| {
            o.copy_from_slice(t);
            let r = rotations(j).transpose().to_cols_array_2d();
            rotation.apply(&r, o).expect("order matches the slices");
        });
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    #[test]
    fn nearest_rotation_recovers_a_rotation_from_a_blend() {
        let a = DMat3::from_axis_angle(DVec3::Y, 0.3);
        let b = DMat3::from_axis_angle(DVec3::Y, 0.7);
        let q = nearest_rotation(a * 0.5 + b * 0.5);
        let expect = DMat3::from_axis_angle(DVec3::Y, 0.5);
        assert!((q - expect).to_cols_array().iter().all(|x| x.abs() < 1e-9));
        assert_eq!(nearest_rotation(DMat3::ZERO), DMat3::IDENTITY);
    }

    #[test]
    fn row_major_matches_matrix_vector_products() {
        let r = DMat3::from_axis_angle(DVec3::new(1.0, 2.0, -0.5).normalize(), 0.7);
        let m = row_major(r);
        let v = DVec3::new(0.3, -0.2, 0.9);
        let expect = r * v;
        for i in 0..3 {
            let got = m[i][0] as f64 * v.x + m[i][1] as f64 * v.y + m[i][2] as f64 * v.z;
            assert!((got - expect[i]).abs() < 1e-6);
        }
    }
}
