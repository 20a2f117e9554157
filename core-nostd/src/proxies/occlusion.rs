//! The occlusion of a block's eight vertices by the proxies that may touch them (see the
//! module above), lane-wise: each proxy is tested against the eight lanes at once, and its
//! caps are computed for all of them together ([`caps`]), so a proxy costs one pass over the
//! block however many of its vertices it reaches. Where only shading is wanted the lighting is
//! folded in: a cap's occlusion dotted with the lighting is `F Σ_l ratio_l Σ_m L_lm y_lm(axis)`,
//! one value per lane instead of n².
//!
//! Every lane sums its caps in proxy order with the same operations whatever the other lanes
//! hold, so a vertex's bits do not depend on its block, and [`ProxyFrame::occlusion`] (one
//! vertex, what the trainer's targets are made with) runs this kernel with one lane.

use core::f32::consts::PI;

use super::MAX_PROXIES;
use super::caps::{Fade, Receivers, band_ratios, caps, offsets};
use super::frame::ProxyFrame;
use crate::blob::format::VERTEX_BLOCK;
use crate::lanes::{Lanes, Portable};
use crate::rotation::Rotation;
use crate::sh::{BasisSink, MAX_COEFFS, MAX_ORDER, basis_lanes};

/// A block's vertices as the kernel takes them: lane `l` is occluded by the proxies of
/// `masks[l]` (none for a lane outside the range); its vertex is at `positions[l]` with normal
/// `normals[l]` (any length; a zero or non-finite one sees no proxy), posed, world space, read
/// in place from the caller's arrays.
#[derive(Clone, Copy)]
pub(crate) struct Block<'a> {
    pub(crate) masks: [u64; VERTEX_BLOCK],
    pub(crate) positions: &'a [[f32; 3]; VERTEX_BLOCK],
    pub(crate) normals: &'a [[f32; 3]; VERTEX_BLOCK],
    /// Each lane's bone rotation, where the occlusion is wanted in the vertices' bone frames.
    pub(crate) rotations: Option<[&'a Rotation; VERTEX_BLOCK]>,
}

/// What the kernel writes for the lanes some proxy reaches.
pub(crate) enum Output<'a> {
    /// The occlusion dotted with world SH `lighting` (n² values), one value per lane.
    Shading {
        lighting: &'a [f32],
        out: &'a mut [f32; VERTEX_BLOCK],
    },
    /// The occlusion's n² coefficients per lane.
    Transfer(&'a mut [[f32; MAX_COEFFS]; VERTEX_BLOCK]),
}

/// The occlusion of `block` by `frame`'s proxies at SH `order` (1..=6) into `output`; returns
/// the lanes some proxy reached (bit `l`; the others' outputs are untouched). Runs in AVX2
/// where the CPU has it, with the portable kernel's bits.
pub(crate) fn block_occlusion(
    frame: &ProxyFrame,
    order: usize,
    block: &Block,
    output: Output<'_>,
) -> u8 {
    #[cfg(target_arch = "x86_64")]
    if let Some(avx2) = crate::eval::Avx2::get() {
        return avx2.occlusion(frame, order, block, output);
    }
    occlusion_kernel::<Portable>(frame, order, block, output)
}

/// [`block_occlusion`] in the lanes `V`.
#[inline(always)]
pub(crate) fn occlusion_kernel<V: Lanes>(
    frame: &ProxyFrame,
    order: usize,
    block: &Block,
    output: Output<'_>,
) -> u8 {
    match order {
        1 => kernel::<V, 1>(frame, block, output),
        2 => kernel::<V, 2>(frame, block, output),
        3 => kernel::<V, 3>(frame, block, output),
        4 => kernel::<V, 4>(frame, block, output),
        5 => kernel::<V, 5>(frame, block, output),
        _ => kernel::<V, 6>(frame, block, output),
    }
}

#[inline(always)]
fn kernel<V: Lanes, const N: usize>(frame: &ProxyFrame, block: &Block, output: Output<'_>) -> u8 {
    let positions = V::from_points(block.positions);
    let near = near_proxies(frame, positions, &block.masks);
    if near == 0 {
        return 0;
    }
    let (receivers, valid) = receivers::<V>(block, positions);
    let mut masks = block.masks;
    for (l, mask) in masks.iter_mut().enumerate() {
        *mask &= near;
        if valid & (1 << l) == 0 {
            *mask = 0;
        }
    }
    let (lanes_of, proxies) = lanes_of_proxies(&masks);
    if proxies == 0 {
        return 0;
    }
    // A match, not `Option::map`: a function passed to `map` is compiled apart from the AVX2
    // kernel, and its lane loads would be calls.
    #[allow(clippy::manual_map)]
    let rotations = match block.rotations {
        Some(r) => Some(rotation_lanes::<V>(r)),
        None => None,
    };
    let pass = Pass {
        frame,
        receivers,
        rotations,
        lanes_of: &lanes_of,
        proxies,
    };
    match output {
        Output::Shading { lighting, out } => {
            let mut sum = ShadingSum {
                lighting,
                sum: V::splat(0.0),
            };
            let union = pass.run::<N>(&mut sum);
            let (reached, scale) = union.finish();
            let shading = (sum.sum * scale).to_array();
            for l in (0..VERTEX_BLOCK).filter(|l| reached & (1 << l) != 0) {
                out[l] = shading[l];
            }
            reached
        }
        Output::Transfer(out) => {
            let mut sum = TransferSum {
                sums: [V::splat(0.0); MAX_COEFFS],
            };
            let union = pass.run::<N>(&mut sum);
            let (reached, scale) = union.finish();
            for (c, s) in sum.sums.iter().enumerate().take(N * N) {
                let lanes = (*s * scale).to_array();
                for l in (0..VERTEX_BLOCK).filter(|l| reached & (1 << l) != 0) {
                    out[l][c] = lanes[l];
                }
            }
            reached
        }
    }
}

/// The block's positions and unit normals in lanes, and the lanes whose normal has a direction.
#[inline(always)]
fn receivers<V: Lanes>(block: &Block, positions: [V; 3]) -> (Receivers<V>, u8) {
    let n = V::from_points(block.normals);
    let length = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    let valid = V::and(
        V::splat(1e-20).lt(length),
        length.lt(V::splat(f32::INFINITY)),
    );
    let zero = V::splat(0.0);
    let receivers = Receivers {
        positions,
        normals: [
            V::select(valid, n[0] / length, zero),
            V::select(valid, n[1] / length, zero),
            V::select(valid, n[2] / length, zero),
        ],
    };
    (receivers, V::bits(valid))
}

/// The proxies of the lanes' masks that may reach some lane: those whose reach meets the
/// bound of the lanes' positions (the centre of their box and the largest distance from it),
/// eight proxies a test. A lane within a proxy's reach is within reach plus bound of the
/// centre, so no cap is lost (the bound is widened by a part in a thousand against rounding);
/// the lanes are tested exactly afterwards.
#[inline(always)]
fn near_proxies<V: Lanes>(frame: &ProxyFrame, p: [V; 3], masks: &[u64; VERTEX_BLOCK]) -> u64 {
    let candidates = masks.iter().fold(0, |all, m| all | m);
    let active = lanes_where(masks, |m| m != 0);
    let (on, big) = (V::mask_of(active), V::splat(f32::INFINITY));
    let small = V::splat(f32::NEG_INFINITY);
    let centre = [
        0.5 * (V::select(on, p[0], big).reduce_min() + V::select(on, p[0], small).reduce_max()),
        0.5 * (V::select(on, p[1], big).reduce_min() + V::select(on, p[1], small).reduce_max()),
        0.5 * (V::select(on, p[2], big).reduce_min() + V::select(on, p[2], small).reduce_max()),
    ];
    let d = [
        p[0] - V::splat(centre[0]),
        p[1] - V::splat(centre[1]),
        p[2] - V::splat(centre[2]),
    ];
    let spread = V::select(on, d[0] * d[0] + d[1] * d[1] + d[2] * d[2], V::splat(0.0));
    // The lanes' square root, not libm's: its scalar `sqrtss` in AVX code would cost a
    // transition between the SSE and AVX register states on some CPUs.
    let bound = V::splat(spread.sqrt().reduce_max() * 1.001);
    let mut near = 0u64;
    for g in 0..MAX_PROXIES / 8 {
        let group = (candidates >> (8 * g)) as u8;
        if group == 0 {
            continue;
        }
        let [x, y, z, reach] = &frame.groups;
        let v = [
            V::from_array(x[g]) - V::splat(centre[0]),
            V::from_array(y[g]) - V::splat(centre[1]),
            V::from_array(z[g]) - V::splat(centre[2]),
        ];
        let gap = V::from_array(reach[g]) + bound;
        let meets = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).lt(gap * gap);
        near |= u64::from(V::bits(meets) & group) << (8 * g);
    }
    near
}

/// For each proxy, the lanes whose mask holds it; and every proxy some lane's mask holds.
/// Lanes of one bone share a mask, so this walks each distinct mask once.
fn lanes_of_proxies(masks: &[u64; VERTEX_BLOCK]) -> ([u8; MAX_PROXIES], u64) {
    let mut lanes_of = [0u8; MAX_PROXIES];
    let mut all = 0u64;
    let mut left = lanes_where(masks, |m| m != 0);
    while left != 0 {
        let mask = masks[left.trailing_zeros() as usize];
        let lanes = lanes_where(masks, |m| m == mask);
        left &= !lanes;
        all |= mask;
        let mut proxies = mask;
        while proxies != 0 {
            lanes_of[proxies.trailing_zeros() as usize] |= lanes;
            proxies &= proxies - 1;
        }
    }
    (lanes_of, all)
}

/// The lanes whose mask passes `test`, as bits.
#[inline(always)]
fn lanes_where(masks: &[u64; VERTEX_BLOCK], test: impl Fn(u64) -> bool) -> u8 {
    let mut bits = 0u8;
    for (l, &m) in masks.iter().enumerate() {
        bits |= u8::from(test(m)) << l;
    }
    bits
}

/// A rotation per lane, as nine lanes `r[row][column]`.
#[inline(always)]
fn rotation_lanes<V: Lanes>(rotations: [&Rotation; VERTEX_BLOCK]) -> [[V; 3]; 3] {
    let mut r = [[[0.0f32; VERTEX_BLOCK]; 3]; 3];
    for (l, rotation) in rotations.iter().enumerate() {
        for i in 0..3 {
            for j in 0..3 {
                r[i][j][l] = rotation[i][j];
            }
        }
    }
    let row = |i: usize| [r[i][0], r[i][1], r[i][2]];
    let [a, b, c] = [row(0), row(1), row(2)];
    [
        [
            V::from_array(a[0]),
            V::from_array(a[1]),
            V::from_array(a[2]),
        ],
        [
            V::from_array(b[0]),
            V::from_array(b[1]),
            V::from_array(b[2]),
        ],
        [
            V::from_array(c[0]),
            V::from_array(c[1]),
            V::from_array(c[2]),
        ],
    ]
}

/// One block's pass over the proxies its lanes may meet.
struct Pass<'a, V: Lanes> {
    frame: &'a ProxyFrame,
    receivers: Receivers<V>,
    rotations: Option<[[V; 3]; 3]>,
    lanes_of: &'a [u8; MAX_PROXIES],
    proxies: u64,
}

impl<V: Lanes> Pass<'_, V> {
    /// Adds every cap to `sum` in proxy order; returns the lanes' union of caps.
    #[inline(always)]
    fn run<const N: usize>(&self, sum: &mut impl CapSum<V>) -> Union<V> {
        let fade = Fade::new(self.frame.cull);
        let mut union = Union::none();
        let mut left = self.proxies;
        while left != 0 {
            let i = left.trailing_zeros() as usize;
            left &= left - 1;
            let sphere = self.frame.sphere(i);
            let offsets = offsets(sphere, self.receivers.positions);
            let within = offsets.1.lt(V::splat(sphere.reach * sphere.reach));
            let hit = V::and(V::mask_of(self.lanes_of[i]), within);
            if V::bits(hit) == 0 {
                continue;
            }
            let caps = caps(sphere, fade, &self.receivers, offsets, hit);
            let axis = self.unit_axis(caps.axis);
            sum.add::<N>(caps.f, &band_ratios(caps.cos_alpha), axis);
            union.add(caps.f);
        }
        union
    }

    /// The axis in the frame of the output (each lane's bone, or world), unit length. The
    /// centre of weight is at least 1 long (its shift is perpendicular to the unit axis), and
    /// so is the `+z` of lanes without a cap, so the division is safe.
    #[inline(always)]
    fn unit_axis(&self, axis: [V; 3]) -> [V; 3] {
        let axis = match &self.rotations {
            // `Rᵀ a`: a world direction in the bone's frame.
            Some(r) => [
                r[0][0] * axis[0] + r[1][0] * axis[1] + r[2][0] * axis[2],
                r[0][1] * axis[0] + r[1][1] * axis[1] + r[2][1] * axis[2],
                r[0][2] * axis[0] + r[1][2] * axis[1] + r[2][2] * axis[2],
            ],
            None => axis,
        };
        let length = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
        let inverse = V::splat(1.0) / length;
        [axis[0] * inverse, axis[1] * inverse, axis[2] * inverse]
    }
}

/// Where a lane's caps go: `F · ratio_l · y_lm(axis)` each.
trait CapSum<V: Lanes> {
    fn add<const N: usize>(&mut self, f: V, ratios: &[V; MAX_ORDER], axis: [V; 3]);
}

/// The caps' occlusion dotted with the lighting, `Σ F Σ_l ratio_l Σ_m L_lm y_lm`.
struct ShadingSum<'a, V> {
    lighting: &'a [f32],
    sum: V,
}

/// Each band's `Σ_m L_lm y_lm`, summed as the basis makes its values.
struct BandDots<'a, V> {
    lighting: &'a [f32],
    bands: [V; MAX_ORDER],
}

impl<V: Lanes> BasisSink<V> for BandDots<'_, V> {
    #[inline(always)]
    fn put(&mut self, l: usize, c: usize, y: V) {
        self.bands[l] = self.bands[l] + V::splat(self.lighting[c]) * y;
    }
}

impl<V: Lanes> CapSum<V> for ShadingSum<'_, V> {
    #[inline(always)]
    fn add<const N: usize>(&mut self, f: V, ratios: &[V; MAX_ORDER], axis: [V; 3]) {
        let mut dots = BandDots {
            lighting: self.lighting,
            bands: [V::splat(0.0); MAX_ORDER],
        };
        basis_lanes::<V, N>(axis, &mut dots);
        let mut bands = V::splat(0.0);
        for (&ratio, &band) in ratios.iter().zip(&dots.bands).take(N) {
            bands = bands + ratio * band;
        }
        self.sum = self.sum + f * bands;
    }
}

/// The caps' occlusion, n² coefficients per lane.
struct TransferSum<V> {
    sums: [V; MAX_COEFFS],
}

/// A cap's bands added to the sums as the basis makes them: `sums_c += weights_l · y_c`.
struct WeightedBasis<'a, V> {
    weights: [V; MAX_ORDER],
    sums: &'a mut [V; MAX_COEFFS],
}

impl<V: Lanes> BasisSink<V> for WeightedBasis<'_, V> {
    #[inline(always)]
    fn put(&mut self, l: usize, c: usize, y: V) {
        self.sums[c] = self.sums[c] + self.weights[l] * y;
    }
}

impl<V: Lanes> CapSum<V> for TransferSum<V> {
    #[inline(always)]
    fn add<const N: usize>(&mut self, f: V, ratios: &[V; MAX_ORDER], axis: [V; 3]) {
        let mut weights = [V::splat(0.0); MAX_ORDER];
        for (w, &ratio) in weights.iter_mut().zip(ratios).take(N) {
            *w = f * ratio;
        }
        let mut sink = WeightedBasis {
            weights,
            sums: &mut self.sums,
        };
        basis_lanes::<V, N>(axis, &mut sink);
    }
}

/// The union of each lane's caps: their form factors' sum, and the share of the lobe none of
/// them blocks.
struct Union<V> {
    total: V,
    visible: V,
}

impl<V: Lanes> Union<V> {
    #[inline(always)]
    fn none() -> Self {
        Union {
            total: V::splat(0.0),
            visible: V::splat(1.0),
        }
    }

    #[inline(always)]
    fn add(&mut self, f: V) {
        self.total = self.total + f;
        let open = V::splat(1.0) - f * V::splat(1.0 / PI);
        self.visible = self.visible * open.max(V::splat(0.0));
    }

    /// The lanes some cap reached, and the scale that takes their summed caps to their union:
    /// overlapping caps block `π (1 − Π (1 − F_i/π))` of the lobe, not `Σ F_i`.
    #[inline(always)]
    fn finish(self) -> (u8, V) {
        let reached = V::splat(0.0).lt(self.total);
        let scale = V::splat(PI) * (V::splat(1.0) - self.visible) / self.total;
        (V::bits(reached), scale)
    }
}

#[cfg(test)]
mod tests {
    use super::{Block, Output, occlusion_kernel};
    use crate::blob::format::VERTEX_BLOCK;
    use crate::lanes::Portable;
    use crate::proxies::ProxyFrame;
    use crate::rotation::Rotation;
    use crate::sh::MAX_COEFFS;
    use crate::test_values::weight;

    /// A rotation about z by `angle`.
    fn turn(angle: f32) -> Rotation {
        let (s, c) = (libm::sinf(angle), libm::cosf(angle));
        [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
    }

    /// 24 proxies from the shared test sequence, culled at `sin²α = 0.05`.
    fn frame() -> ProxyFrame {
        let mut frame = ProxyFrame::new();
        frame.cull = 0.05;
        for i in 0..24 {
            let radius = 0.05 + 0.25 * (weight(100 + i) + 0.85);
            let centre = [0, 1, 2].map(|k| 1.2 * weight(3 * i + k));
            frame.set_sphere(i, centre, radius, radius / libm::sqrtf(frame.cull));
        }
        frame
    }

    /// A block's inputs, owned.
    struct Case {
        masks: [u64; VERTEX_BLOCK],
        positions: [[f32; 3]; VERTEX_BLOCK],
        normals: [[f32; 3]; VERTEX_BLOCK],
        rotations: Option<[Rotation; VERTEX_BLOCK]>,
    }

    impl Case {
        fn block(&self) -> Block<'_> {
            Block {
                masks: self.masks,
                positions: &self.positions,
                normals: &self.normals,
                rotations: self
                    .rotations
                    .as_ref()
                    .map(|r| core::array::from_fn(|l| &r[l])),
            }
        }

        /// Lane `lane` alone in an otherwise empty block.
        fn alone(&self, lane: usize) -> Case {
            let mut one = Case {
                masks: [0; VERTEX_BLOCK],
                positions: [[0.0; 3]; VERTEX_BLOCK],
                normals: [[0.0; 3]; VERTEX_BLOCK],
                rotations: self.rotations.map(|r| [r[lane]; VERTEX_BLOCK]),
            };
            one.masks[0] = self.masks[lane];
            one.positions[0] = self.positions[lane];
            one.normals[0] = self.normals[lane];
            one
        }
    }

    /// Block `b` of the cases: lanes with every mask, none and partial ones, zero normals, a
    /// vertex inside a sphere, and bone rotations (about z by a different angle each) or none.
    fn case(frame: &ProxyFrame, b: usize) -> Case {
        let draw =
            |i: usize, scale: f32| [0, 1, 2].map(|k| scale * weight(1000 + 24 * b + 3 * i + k));
        Case {
            masks: core::array::from_fn(|l| match (b + l) % 5 {
                0 => 0,
                1 => (1 << 24) - 1,
                _ => (weight(5000 + 8 * b + l).to_bits() as u64) & ((1 << 24) - 1),
            }),
            positions: core::array::from_fn(|l| match l {
                3 => frame.sphere(b % 24).centre,
                _ => draw(l, 1.4),
            }),
            normals: core::array::from_fn(|l| match (b + l) % 7 {
                0 => [0.0; 3],
                _ => draw(l + 8, 1.0),
            }),
            rotations: (!b.is_multiple_of(3))
                .then(|| core::array::from_fn(|l| turn(0.3 - 0.2 * l as f32))),
        }
    }

    /// Both outputs of `kernel` for `block` at `order`: the lanes reached, the shading under a
    /// fixed lighting, and the coefficients.
    fn run(
        kernel: impl Fn(&ProxyFrame, usize, &Block, Output<'_>) -> u8,
        frame: &ProxyFrame,
        order: usize,
        block: &Block,
    ) -> (u8, [f32; VERTEX_BLOCK], [[f32; MAX_COEFFS]; VERTEX_BLOCK]) {
        let lighting: [f32; MAX_COEFFS] = core::array::from_fn(|c| weight(7000 + c));
        let mut shading = [0.0f32; VERTEX_BLOCK];
        let mut d = [[0.0f32; MAX_COEFFS]; VERTEX_BLOCK];
        let output = Output::Shading {
            lighting: &lighting[..order * order],
            out: &mut shading,
        };
        let reached = kernel(frame, order, block, output);
        assert_eq!(
            kernel(frame, order, block, Output::Transfer(&mut d)),
            reached
        );
        (reached, shading, d)
    }

    fn same_bits(a: &[f32], b: &[f32]) -> bool {
        a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
    }

    /// A vertex gets the same bits whatever the other lanes of its block hold, which is what
    /// lets the one-vertex call (the trainer's targets) and the block kernel agree.
    #[test]
    fn each_lane_gets_its_own_bits() {
        let frame = frame();
        let kernel = occlusion_kernel::<Portable>;
        let mut lanes_reached = 0;
        for order in 1..=6 {
            for b in 0..40 {
                let case = case(&frame, b);
                let block = case.block();
                let (reached, shading, d) = run(kernel, &frame, order, &block);
                for l in 0..VERTEX_BLOCK {
                    let (one, one_shading, one_d) =
                        run(kernel, &frame, order, &case.alone(l).block());
                    assert_eq!(
                        reached >> l & 1,
                        one & 1,
                        "order {order}, block {b}, lane {l}"
                    );
                    if one & 1 != 0 {
                        lanes_reached += 1;
                        assert_eq!(shading[l].to_bits(), one_shading[0].to_bits());
                        assert!(same_bits(
                            &d[l][..order * order],
                            &one_d[0][..order * order]
                        ));
                    }
                }
            }
        }
        // The cases reach: most lanes with proxies meet a cap.
        assert!(lanes_reached > 6 * 40 * 3, "{lanes_reached}");
    }

    /// Folding the lighting in gives the coefficients dotted with it, to f32 rounding.
    #[test]
    fn shading_is_the_occlusion_dotted_with_the_lighting() {
        let frame = frame();
        let lighting: [f32; MAX_COEFFS] = core::array::from_fn(|c| weight(7000 + c));
        for order in 1..=6 {
            for b in (0..40).filter(|b| b % 3 == 0) {
                let (reached, shading, d) = run(
                    occlusion_kernel::<Portable>,
                    &frame,
                    order,
                    &case(&frame, b).block(),
                );
                for l in (0..VERTEX_BLOCK).filter(|l| reached >> l & 1 != 0) {
                    let n2 = order * order;
                    let dot: f64 = (0..n2).map(|c| f64::from(d[l][c] * lighting[c])).sum();
                    let size: f64 = (0..n2)
                        .map(|c| f64::from((d[l][c] * lighting[c]).abs()))
                        .sum();
                    let error = (f64::from(shading[l]) - dot).abs();
                    assert!(
                        error <= 1e-5 * (1.0 + size),
                        "order {order}, block {b}, lane {l}"
                    );
                }
            }
        }
    }

    /// The AVX2 kernel gives the portable bits, in every lane, output and order.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn avx2_occlusion_gives_the_portable_bits() {
        let Some(avx2) = crate::eval::Avx2::get() else {
            return;
        };
        let frame = frame();
        let wide = |f: &ProxyFrame, order: usize, block: &Block, out: Output<'_>| {
            avx2.occlusion(f, order, block, out)
        };
        for order in 1..=6 {
            for b in 0..40 {
                let case = case(&frame, b);
                let block = case.block();
                let portable = run(occlusion_kernel::<Portable>, &frame, order, &block);
                let (reached, shading, d) = run(wide, &frame, order, &block);
                assert_eq!(reached, portable.0);
                for l in (0..VERTEX_BLOCK).filter(|l| reached >> l & 1 != 0) {
                    assert_eq!(
                        shading[l].to_bits(),
                        portable.1[l].to_bits(),
                        "{order} {b} {l}"
                    );
                    assert!(same_bits(
                        &d[l][..order * order],
                        &portable.2[l][..order * order]
                    ));
                }
            }
        }
    }

    /// FNV-1a over the bits of every case's outputs, from the kernel this target dispatches to.
    fn occlusion_bits_digest() -> u64 {
        let frame = frame();
        let mut digest = 0xcbf2_9ce4_8422_2325u64;
        let mut eat = |xs: &[f32]| {
            for byte in xs.iter().flat_map(|x| x.to_bits().to_le_bytes()) {
                digest = (digest ^ u64::from(byte)).wrapping_mul(0x0100_0000_01b3);
            }
        };
        for order in 1..=6 {
            for b in 0..40 {
                let (reached, shading, d) = run(
                    super::block_occlusion,
                    &frame,
                    order,
                    &case(&frame, b).block(),
                );
                for l in (0..VERTEX_BLOCK).filter(|l| reached >> l & 1 != 0) {
                    eat(&[shading[l]]);
                    eat(&d[l][..order * order]);
                }
            }
        }
        digest
    }

    /// The proxies' occlusion has the same bits on every target, as the shading kernels do
    /// (`kernel_bits_are_the_same_on_every_target`): x86-64 in AVX2 and in the portable
    /// kernel, aarch64 under qemu and wasm32 under Node gave this digest.
    #[test]
    fn occlusion_bits_are_the_same_on_every_target() {
        assert_eq!(occlusion_bits_digest(), 10_527_027_863_001_694_332);
    }
}
