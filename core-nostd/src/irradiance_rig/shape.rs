//! The shape of an irradiance rig: which basis functions of position its SH vectors are
//! weighted by, and the few of them that are non-zero at a point.

/// Most nodes of a lattice axis.
pub const MAX_LATTICE: usize = 16;
/// Most SH vectors a rig may have (an 8 × 4 × 2 lattice has 64).
pub const MAX_RIG_VECTORS: usize = 256;
/// Most basis functions non-zero at one point: two per axis.
pub const RIG_SUPPORT: usize = 8;

/// One axis of a product rig, in the character's own frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AxisKind {
    /// One function, 1: the lighting does not vary along the axis.
    Constant,
    /// Two functions, 1 and the coordinate (metres from the rig's centre): the lighting varies
    /// linearly along the axis (the paper's "gradient" axis of a mixed rig).
    Linear,
    /// `n` hat functions on nodes spread evenly over the rig's box (2 ≤ n ≤ [`MAX_LATTICE`]):
    /// the lighting is interpolated linearly between `n` samples along the axis.
    Lattice(u8),
}

impl AxisKind {
    /// Functions along the axis.
    pub const fn functions(self) -> usize {
        match self {
            AxisKind::Constant => 1,
            AxisKind::Linear => 2,
            AxisKind::Lattice(n) => n as usize,
        }
    }

    /// The byte stored in a rig section: 0 constant, 1 linear, n ≥ 2 a lattice of n nodes.
    pub const fn code(self) -> u8 {
        match self {
            AxisKind::Constant => 0,
            AxisKind::Linear => 1,
            AxisKind::Lattice(n) => n,
        }
    }

    /// The kind of a stored byte, `None` for a lattice above [`MAX_LATTICE`].
    pub const fn from_code(code: u8) -> Option<AxisKind> {
        match code {
            0 => Some(AxisKind::Constant),
            1 => Some(AxisKind::Linear),
            n if n as usize <= MAX_LATTICE => Some(AxisKind::Lattice(n)),
            _ => None,
        }
    }

    /// The (index, value) pairs of the functions non-zero at coordinate `x` (metres from the
    /// centre) on an axis of half-width `half`; the count in `.2`. A lattice clamps `x` into
    /// the box, so points beyond it take the nearest face's lighting.
    fn at(self, x: f32, half: f32) -> ([u16; 2], [f32; 2], usize) {
        match self {
            AxisKind::Constant => ([0, 0], [1.0, 0.0], 1),
            AxisKind::Linear => ([0, 1], [1.0, x], 2),
            AxisKind::Lattice(n) => {
                let cells = (n - 1) as f32;
                let t = ((x / half + 1.0) * 0.5 * cells).clamp(0.0, cells);
                // `t` is finite (clamp of a finite value) and within [0, n − 1].
                let i = (t as u16).min(n as u16 - 2);
                let f = t - i as f32;
                ([i, i + 1], [1.0 - f, f], 2)
            }
        }
    }
}

/// How a rig's SH vectors vary over space (*Irradiance Rigs*, section 2.1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RigShape {
    /// `l(p) = l_c + p_x g_x + p_y g_y + p_z g_z`: four vectors, p in metres from the centre.
    Gradient,
    /// The tensor product of one [`AxisKind`] per axis (x, y, z of the character's frame):
    /// all three constant is the centroid rig, all three lattices a trilinear lattice, and
    /// anything else a mixed rig (the paper's car: a three-node lattice along its length, a
    /// gradient up, constant across: six vectors). Vector `(i, j, k)` is index
    /// `i + n_x (j + n_y k)`.
    Product([AxisKind; 3]),
}

/// The basis functions non-zero at a point: `len` pairs of vector index and weight.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RigWeights {
    /// Indices of the rig's SH vectors.
    pub index: [u16; RIG_SUPPORT],
    /// Their weights `φ_k(p)`.
    pub weight: [f32; RIG_SUPPORT],
    /// How many of the pairs are used.
    pub len: usize,
}

impl RigWeights {
    /// The used (index, weight) pairs.
    pub fn pairs(&self) -> impl Iterator<Item = (usize, f32)> + '_ {
        self.index[..self.len]
            .iter()
            .zip(&self.weight[..self.len])
            .map(|(&k, &w)| (k as usize, w))
    }
}

impl RigShape {
    /// SH vectors of the rig.
    pub const fn vectors(&self) -> usize {
        match self {
            RigShape::Gradient => 4,
            RigShape::Product([x, y, z]) => x.functions() * y.functions() * z.functions(),
        }
    }

    /// The weights `φ_k(p)` at `p`, metres from the rig's centre along the character's axes,
    /// for a box of half-widths `half` (every component positive).
    pub fn weights(&self, p: [f32; 3], half: [f32; 3]) -> RigWeights {
        let mut out = RigWeights {
            index: [0; RIG_SUPPORT],
            weight: [0.0; RIG_SUPPORT],
            len: 0,
        };
        match self {
            RigShape::Gradient => {
                out.index[..4].copy_from_slice(&[0, 1, 2, 3]);
                out.weight[..4].copy_from_slice(&[1.0, p[0], p[1], p[2]]);
                out.len = 4;
            }
            RigShape::Product(axes) => {
                let [ax, ay, az] = [0, 1, 2].map(|a| axes[a].at(p[a], half[a]));
                let (nx, ny) = (axes[0].functions() as u16, axes[1].functions() as u16);
                for (iz, wz) in az.0.iter().zip(&az.1).take(az.2) {
                    for (iy, wy) in ay.0.iter().zip(&ay.1).take(ay.2) {
                        for (ix, wx) in ax.0.iter().zip(&ax.1).take(ax.2) {
                            out.index[out.len] = ix + nx * (iy + ny * iz);
                            out.weight[out.len] = wx * wy * wz;
                            out.len += 1;
                        }
                    }
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lattice_weights_interpolate_and_clamp() {
        let axis = AxisKind::Lattice(3);
        // Nodes at −1, 0, 1 of a half-width 1.
        assert_eq!(axis.at(-1.0, 1.0), ([0, 1], [1.0, 0.0], 2));
        assert_eq!(axis.at(0.5, 1.0), ([1, 2], [0.5, 0.5], 2));
        assert_eq!(axis.at(1.0, 1.0), ([1, 2], [0.0, 1.0], 2));
        // Beyond the box: the face's value.
        assert_eq!(axis.at(7.0, 1.0), ([1, 2], [0.0, 1.0], 2));
        assert_eq!(axis.at(-7.0, 1.0), ([0, 1], [1.0, 0.0], 2));
    }

    #[test]
    fn product_weights_are_a_partition_of_unity_on_lattices() {
        let shape = RigShape::Product([
            AxisKind::Lattice(8),
            AxisKind::Lattice(4),
            AxisKind::Lattice(2),
        ]);
        assert_eq!(shape.vectors(), 64);
        for p in [[0.3, -0.7, 0.1], [2.0, 0.0, -3.0], [-0.99, 0.99, 0.0]] {
            let w = shape.weights(p, [1.0, 0.5, 0.25]);
            assert_eq!(w.len, 8);
            let sum: f32 = w.pairs().map(|(_, w)| w).sum();
            assert!((sum - 1.0).abs() < 1e-6, "{sum}");
            assert!(w.pairs().all(|(k, _)| k < 64));
        }
    }

    #[test]
    fn mixed_rig_of_the_paper_has_six_vectors() {
        let car = RigShape::Product([AxisKind::Lattice(3), AxisKind::Linear, AxisKind::Constant]);
        assert_eq!(car.vectors(), 6);
        // At the middle node, height 0.5: node 1 with weight 1, its linear term 0.5.
        let w = car.weights([0.0, 0.5, 9.0], [1.0, 1.0, 1.0]);
        let dense: [f32; 6] =
            core::array::from_fn(|k| w.pairs().filter(|&(i, _)| i == k).map(|(_, w)| w).sum());
        assert_eq!(dense, [0.0, 1.0, 0.0, 0.0, 0.5, 0.0]);
    }

    #[test]
    fn codes_round_trip() {
        for kind in [AxisKind::Constant, AxisKind::Linear, AxisKind::Lattice(16)] {
            assert_eq!(AxisKind::from_code(kind.code()), Some(kind));
        }
        assert_eq!(AxisKind::from_code(17), None);
    }
}
