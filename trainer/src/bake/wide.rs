//! A four-wide BVH with plain `f32` child boxes, collapsed from obvhs' binary BVH and traversed
//! here, four boxes per SSE instruction.
//!
//! obvhs' CWBVH spends most of a node visit decompressing its 8-bit child boxes; with exact
//! boxes a visit is a dozen vector instructions. Culling is conservative by construction (see
//! [`Bvh4::new`]), so [`Bvh4::occluded`] answers exactly what a test of every triangle would.
//!
//! The walk is compiled once per octant of the ray direction (no per-node choice of the box
//! plane a ray enters through), visits the last child it enters without a stack push, and
//! keeps its stack in the caller's [`TraversalStack`] (no array to zero per ray): together
//! 8.25 → 6.74 G instructions per pose of the bake benchmark (callgrind).
//!
//! The bake's shadow rays walk it in packets of one vertex's rays (the `packet` module), which
//! reuse the one-ray slab test as it is: 1.38× the rays per second of the one-ray walk on the
//! benchmark scene (6.62 against 4.49 Mrays/s) and 1.34× on the demo's bake (6.76 against
//! 4.97), median of five alternating pairs in `cargo bench -p aprt-trainer --bench bake` on 2
//! shared cores; earlier runs 1.36–1.39× and 1.28–1.31×.

mod packet;

pub(crate) use packet::{PACKET, Packet, octant_of};

use glam::Vec3A;
use obvhs::{
    aabb::Aabb,
    bvh2::Bvh2,
    ray::{Ray, RayHit},
    triangle::Triangle,
};

/// Child boxes grow by this fraction of the scene scale (largest absolute coordinate plus the
/// bounding-box diagonal). A ray that the f32 ray–triangle test accepts passes within a few
/// dozen ulps of scene scale (≈ 1e-6) of the triangle, and the slab test's own rounding is
/// smaller still; 1e-5 covers both, so no box rejects a ray one of its triangles accepts.
const BOX_PADDING: f32 = 1e-5;

/// Four children: boxes as `[axis][lane]`, empty lanes an inverted (never hit) box.
#[derive(Clone, Copy)]
#[repr(C, align(16))]
struct Node {
    lo: [[f32; 4]; 3],
    hi: [[f32; 4]; 3],
    /// An inner child's node index, or a leaf's first triangle.
    index: [u32; 4],
    /// A leaf's triangle count; 0 for an inner child (and for empty lanes).
    count: [u32; 4],
}

const EMPTY: Node = Node {
    lo: [[f32::INFINITY; 4]; 3],
    hi: [[f32::NEG_INFINITY; 4]; 3],
    index: [0; 4],
    count: [0; 4],
};

/// The four-wide hierarchy over triangles already laid out in the binary BVH's leaf order.
pub(crate) struct Bvh4 {
    nodes: Vec<Node>,
}

impl Bvh4 {
    /// Collapses `bvh` (whose leaves index `tris` directly) into four-wide nodes, each absorbing
    /// the largest-area inner children of the binary node until it has four. Boxes are
    /// recomputed from the triangles rather than taken from `bvh`, then padded by
    /// [`BOX_PADDING`], so culling never depends on how the binary builder rounded.
    pub fn new(bvh: &Bvh2, tris: &[Triangle]) -> Self {
        let mut out = Bvh4 { nodes: Vec::new() };
        let Some(root) = bvh.nodes.first() else {
            return out;
        };
        let scene = leaf_box(tris, 0, tris.len() as u32);
        let scale = scene.min.abs().max(scene.max.abs()).max_element() + scene.diagonal().length();
        let pad = Vec3A::splat(BOX_PADDING * scale);
        if root.is_leaf() {
            let mut node = EMPTY;
            set_lane(
                &mut node,
                0,
                &leaf_box(tris, root.first_index, root.prim_count),
                pad,
            );
            node.index[0] = root.first_index;
            node.count[0] = root.prim_count;
            out.nodes.push(node);
        } else {
            out.collapse(bvh, tris, 0, pad);
        }
        out
    }

    /// Emits the four-wide node for binary inner node `id` and its subtree; returns the box.
    fn collapse(&mut self, bvh: &Bvh2, tris: &[Triangle], id: usize, pad: Vec3A) -> Aabb {
        let first = bvh.nodes[id].first_index as usize;
        let mut lanes = vec![first, first + 1];
        while lanes.len() < 4 {
            let widest = lanes
                .iter()
                .enumerate()
                .filter(|&(_, &c)| !bvh.nodes[c].is_leaf())
                .max_by(|a, b| {
                    let area = |&(_, &c): &(usize, &usize)| bvh.nodes[c].aabb().half_area();
                    area(a).total_cmp(&area(b))
                });
            let Some((k, &c)) = widest else { break };
            let grandchild = bvh.nodes[c].first_index as usize;
            lanes[k] = grandchild;
            lanes.push(grandchild + 1);
        }
        let slot = self.nodes.len();
        self.nodes.push(EMPTY);
        let mut node = EMPTY;
        let mut total = Aabb::empty();
        for (lane, &c) in lanes.iter().enumerate() {
            let child = &bvh.nodes[c];
            let bounds = if child.is_leaf() {
                node.index[lane] = child.first_index;
                node.count[lane] = child.prim_count;
                leaf_box(tris, child.first_index, child.prim_count)
            } else {
                node.index[lane] = self.nodes.len() as u32;
                self.collapse(bvh, tris, c, pad)
            };
            set_lane(&mut node, lane, &bounds, pad);
            total = total.union(&bounds);
        }
        self.nodes[slot] = node;
        total
    }

    /// Whether any of `tris` lies on `ray` within `[tmin, tmax]`: the first hit found ends the
    /// walk. Children are not sorted by entry distance: sorting cost more than the earlier hits
    /// saved (10–25% more traversal instructions on the benchmark scene).
    pub fn occluded(&self, tris: &[Triangle], ray: &Ray, stack: &mut TraversalStack) -> bool {
        self.occluded_below(tris, ray, 0, &mut stack.single)
    }

    /// [`Bvh4::occluded`] within the subtree of node `root` only.
    fn occluded_below(
        &self,
        tris: &[Triangle],
        ray: &Ray,
        root: u32,
        stack: &mut Vec<u32>,
    ) -> bool {
        self.walk(&mut Slabs::new(ray), stack, root, |_, first, count| {
            (first..first + count).any(|k| tris[k as usize].intersect(ray) < ray.tmax)
        })
    }

    /// The nearest of `tris` on `ray`, written to `hit` (index into `tris` and distance) as
    /// obvhs' `ray_traverse` does; returns whether there is one. Each hit shortens the ray, so
    /// boxes beyond it are skipped.
    pub fn closest(
        &self,
        tris: &[Triangle],
        ray: Ray,
        hit: &mut RayHit,
        stack: &mut TraversalStack,
    ) -> bool {
        let mut shortened = ray;
        self.walk(
            &mut Slabs::new(&ray),
            &mut stack.single,
            0,
            |slabs, first, count| {
                for k in first..first + count {
                    let t = tris[k as usize].intersect(&shortened);
                    if t < shortened.tmax {
                        hit.t = t;
                        hit.primitive_id = k;
                        shortened.tmax = t;
                        slabs.tmax = [t; 4];
                    }
                }
                false
            },
        );
        hit.t < ray.tmax
    }

    /// Walks the subtree of node `root`, calling `leaf(slabs, first, count)` on every leaf whose
    /// box `slabs` enters (the callback may shorten `slabs`), until one returns true (which is
    /// returned).
    fn walk(
        &self,
        slabs: &mut Slabs,
        stack: &mut Vec<u32>,
        root: u32,
        leaf: impl FnMut(&mut Slabs, u32, u32) -> bool,
    ) -> bool {
        // One copy of the loop per octant of the ray direction, so which box plane a ray enters
        // through is known at compile time instead of selected at every node.
        match slabs.octant {
            0 => self.walk_octant::<0>(slabs, stack, root, leaf),
            1 => self.walk_octant::<1>(slabs, stack, root, leaf),
            2 => self.walk_octant::<2>(slabs, stack, root, leaf),
            3 => self.walk_octant::<3>(slabs, stack, root, leaf),
            4 => self.walk_octant::<4>(slabs, stack, root, leaf),
            5 => self.walk_octant::<5>(slabs, stack, root, leaf),
            6 => self.walk_octant::<6>(slabs, stack, root, leaf),
            _ => self.walk_octant::<7>(slabs, stack, root, leaf),
        }
    }

    /// [`Bvh4::walk`] for rays whose direction has a negative component along each axis `k`
    /// with bit `k` of `OCTANT` set.
    fn walk_octant<const OCTANT: u8>(
        &self,
        slabs: &mut Slabs,
        stack: &mut Vec<u32>,
        root: u32,
        mut leaf: impl FnMut(&mut Slabs, u32, u32) -> bool,
    ) -> bool {
        stack.clear();
        // The node to visit next: the last inner child a visit enters goes here, the others
        // wait on the stack.
        let mut next = (!self.nodes.is_empty()).then_some(root);
        while let Some(id) = next.take().or_else(|| stack.pop()) {
            let node = &self.nodes[id as usize];
            let mut mask = slabs.enter::<OCTANT>(node);
            while mask != 0 {
                let lane = mask.trailing_zeros() as usize;
                mask &= mask - 1;
                if node.count[lane] == 0 {
                    if let Some(waiting) = next.replace(node.index[lane]) {
                        stack.push(waiting);
                    }
                } else if leaf(slabs, node.index[lane], node.count[lane]) {
                    return true;
                }
            }
        }
        false
    }
}

fn leaf_box(tris: &[Triangle], first: u32, count: u32) -> Aabb {
    tris[first as usize..(first + count) as usize]
        .iter()
        .fold(Aabb::empty(), |b, t| b.union(&t.aabb()))
}

fn set_lane(node: &mut Node, lane: usize, bounds: &Aabb, pad: Vec3A) {
    let (lo, hi) = (bounds.min - pad, bounds.max + pad);
    for axis in 0..3 {
        node.lo[axis][lane] = lo[axis];
        node.hi[axis][lane] = hi[axis];
    }
}

/// Nodes waiting to be visited, kept by the caller so one allocation serves all its rays.
#[derive(Default)]
pub(crate) struct TraversalStack {
    /// Node indices of a one-ray walk.
    single: Vec<u32>,
    /// Node indices of a packet walk, each with the mask of the packet's rays that entered it.
    packet: Vec<(u32, u32)>,
}

/// A ray prepared for slab tests against four boxes at once.
struct Slabs {
    origin: [[f32; 4]; 3],
    /// `1/d` per axis, infinite for a zero component (directions carry no −0, see
    /// [`super::tracer::ray`]).
    inv: [[f32; 4]; 3],
    /// Bit `k` set when the direction's component `k` is negative.
    octant: u8,
    tmin: [f32; 4],
    tmax: [f32; 4],
}

impl Slabs {
    fn new(ray: &Ray) -> Self {
        let (o, d) = (ray.origin, ray.direction);
        // The packet walk (`packet` module) computes the same `1/d` per ray: both must cull
        // the same boxes.
        let inv = Vec3A::ONE / d;
        Slabs {
            origin: [[o.x; 4], [o.y; 4], [o.z; 4]],
            inv: [[inv.x; 4], [inv.y; 4], [inv.z; 4]],
            octant: octant_of(d),
            tmin: [ray.tmin; 4],
            tmax: [ray.tmax; 4],
        }
    }

    /// Which lanes of `node` the ray enters within `[tmin, tmax]`, a bit per lane.
    ///
    /// A zero direction component with the origin exactly on a box plane makes `0 · ∞ = NaN`;
    /// SSE `max`/`min` return their second operand when the first is NaN, so that axis then
    /// simply does not constrain the interval — the conservative answer.
    #[cfg(all(target_arch = "x86_64", target_feature = "sse2"))]
    fn enter<const OCTANT: u8>(&self, node: &Node) -> u32 {
        use safe_arch::*;
        let load = |v: &[f32; 4]| m128::from_array(*v);
        let mut near = load(&self.tmin);
        let mut far = load(&self.tmax);
        for axis in 0..3 {
            let (a, b) = if OCTANT >> axis & 1 != 0 {
                (&node.hi[axis], &node.lo[axis])
            } else {
                (&node.lo[axis], &node.hi[axis])
            };
            let (o, inv) = (load(&self.origin[axis]), load(&self.inv[axis]));
            near = max_m128(mul_m128(sub_m128(load(a), o), inv), near);
            far = min_m128(mul_m128(sub_m128(load(b), o), inv), far);
        }
        move_mask_m128(cmp_le_mask_m128(near, far)) as u32
    }

    /// Portable version of the SSE test above, with the same NaN rule written out.
    #[cfg(not(all(target_arch = "x86_64", target_feature = "sse2")))]
    fn enter<const OCTANT: u8>(&self, node: &Node) -> u32 {
        let mut near = self.tmin;
        let mut far = self.tmax;
        let mut mask = 0;
        for lane in 0..4 {
            for axis in 0..3 {
                let (a, b) = if OCTANT >> axis & 1 != 0 {
                    (node.hi[axis][lane], node.lo[axis][lane])
                } else {
                    (node.lo[axis][lane], node.hi[axis][lane])
                };
                let (o, inv) = (self.origin[axis][lane], self.inv[axis][lane]);
                let (t0, t1) = ((a - o) * inv, (b - o) * inv);
                if t0 > near[lane] {
                    near[lane] = t0;
                }
                if t1 < far[lane] {
                    far[lane] = t1;
                }
            }
            if near[lane] <= far[lane] {
                mask |= 1 << lane;
            }
        }
        mask
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use obvhs::{BvhBuildParams, bvh2::builder::build_bvh2_from_tris};
    use std::time::Duration;

    /// The six axis directions, along which box slabs and triangle planes are exactly hit.
    const AXES: [Vec3A; 6] = [
        Vec3A::X,
        Vec3A::NEG_X,
        Vec3A::Y,
        Vec3A::NEG_Y,
        Vec3A::Z,
        Vec3A::NEG_Z,
    ];

    /// Builds over `tris` (reordered to leaf order, as the tracer does).
    fn build(tris: &[Triangle]) -> (Bvh4, Vec<Triangle>) {
        let params = BvhBuildParams {
            max_prims_per_leaf: 1,
            ..BvhBuildParams::medium_build()
        };
        let bvh = build_bvh2_from_tris(tris, params, &mut Duration::default());
        let tris: Vec<Triangle> = bvh
            .primitive_indices
            .iter()
            .map(|&k| tris[k as usize])
            .collect();
        (Bvh4::new(&bvh, &tris), tris)
    }

    #[test]
    fn agrees_with_every_triangle_on_axis_aligned_and_grazing_rays() {
        // A 4 × 4 grid of unit squares at z = 0 and a wall at x = 2: boxes with zero extent
        // along an axis, rays parallel to them and starting in their planes.
        let mut tris = Vec::new();
        let v = |x: f32, y: f32, z: f32| Vec3A::new(x, y, z);
        for i in 0..4 {
            for j in 0..4 {
                let (x, y) = (i as f32, j as f32);
                tris.push(Triangle {
                    v0: v(x, y, 0.0),
                    v1: v(x + 1.0, y, 0.0),
                    v2: v(x + 1.0, y + 1.0, 0.0),
                });
                tris.push(Triangle {
                    v0: v(x, y, 0.0),
                    v1: v(x + 1.0, y + 1.0, 0.0),
                    v2: v(x, y + 1.0, 0.0),
                });
            }
        }
        tris.push(Triangle {
            v0: v(2.0, 0.0, 0.0),
            v1: v(2.0, 4.0, 0.0),
            v2: v(2.0, 2.0, 3.0),
        });
        let (bvh, tris) = build(&tris);
        let mut stack = TraversalStack::default();
        let dirs = AXES
            .into_iter()
            .chain([
                Vec3A::new(1.0, 1.0, -1.0).normalize(),
                Vec3A::new(-1.0, 0.0, -1e-9).normalize(),
            ])
            // Every octant of directions, each with its own copy of the walk.
            .chain((0..8).map(|octant| {
                let sign = |bit: u32| if octant >> bit & 1 == 1 { -1.0 } else { 1.0 };
                Vec3A::new(sign(0) * 0.3, sign(1) * 0.5, sign(2) * 0.8).normalize()
            }))
            .collect::<Vec<_>>();
        let mut hits = 0;
        for ox in [-1.0, 0.0, 0.5, 1.0, 2.0, 3.5, 4.0] {
            for oy in [0.0, 1.0, 2.5, 4.0] {
                for oz in [0.0, 1e-3, 1.0] {
                    for &d in &dirs {
                        let ray = Ray::new(v(ox, oy, oz), d + Vec3A::ZERO, 0.0, f32::INFINITY);
                        let every = tris.iter().any(|t| t.intersect(&ray) < f32::INFINITY);
                        assert_eq!(bvh.occluded(&tris, &ray, &mut stack), every, "{ray:?}");
                        let mut hit = RayHit::none();
                        assert_eq!(
                            bvh.closest(&tris, ray, &mut hit, &mut stack),
                            every,
                            "{ray:?}"
                        );
                        hits += usize::from(every);
                    }
                }
            }
        }
        assert!(
            hits > 100,
            "the rays exercise hits as well as misses ({hits})"
        );
    }

    /// Every direction in `dirs` from `origin`, traced in packets of one octant (in the order
    /// given, [`PACKET`] at a time) and one ray at a time, must agree with each other and with
    /// a test of every triangle.
    fn assert_packets_agree(bvh: &Bvh4, tris: &[Triangle], origin: Vec3A, dirs: &[Vec3A]) -> usize {
        let mut stack = TraversalStack::default();
        let mut blocked = 0;
        for octant in 0..8 {
            let group: Vec<Vec3A> = dirs
                .iter()
                .map(|&d| d + Vec3A::ZERO)
                .filter(|&d| octant_of(d) == octant)
                .collect();
            for chunk in group.chunks(PACKET) {
                let packet = Packet::new(origin, chunk, 1e-4, f32::INFINITY);
                let mask = bvh.occluded_packet(tris, &packet, &mut stack);
                for (r, &d) in chunk.iter().enumerate() {
                    let ray = Ray::new(origin, d, 1e-4, f32::INFINITY);
                    let every = tris.iter().any(|t| t.intersect(&ray) < f32::INFINITY);
                    assert_eq!(bvh.occluded(tris, &ray, &mut stack), every, "{ray:?}");
                    assert_eq!(
                        mask >> r & 1 == 1,
                        every,
                        "packet of {}: {ray:?}",
                        chunk.len()
                    );
                    blocked += usize::from(every);
                }
                assert_eq!(mask >> chunk.len(), 0, "no bits beyond the packet's rays");
            }
        }
        blocked
    }

    #[test]
    fn packets_agree_with_every_triangle_on_grazing_rays_degenerate_triangles_and_surfaces() {
        // The grid and wall of the one-ray test, plus degenerate triangles (collinear with a
        // box of non-zero size, and a needle) lying across the grid, and a sliver standing on
        // it: rays start on the grid's vertices, on its edges and inside its faces (on the
        // surface, where the slab test sees zero-extent boxes), and graze it.
        let v = |x: f32, y: f32, z: f32| Vec3A::new(x, y, z);
        let mut tris = Vec::new();
        for i in 0..4 {
            for j in 0..4 {
                let (x, y) = (i as f32, j as f32);
                let (a, b, c, d) = (
                    v(x, y, 0.0),
                    v(x + 1.0, y, 0.0),
                    v(x + 1.0, y + 1.0, 0.0),
                    v(x, y + 1.0, 0.0),
                );
                tris.push(Triangle {
                    v0: a,
                    v1: b,
                    v2: c,
                });
                tris.push(Triangle {
                    v0: a,
                    v1: c,
                    v2: d,
                });
            }
        }
        tris.extend([
            Triangle {
                v0: v(2.0, 0.0, 0.0),
                v1: v(2.0, 4.0, 0.0),
                v2: v(2.0, 2.0, 3.0),
            },
            Triangle {
                v0: v(0.0, 0.0, 0.5),
                v1: v(1.0, 1.0, 0.5),
                v2: v(3.0, 3.0, 0.5),
            },
            Triangle {
                v0: v(1.0, 3.0, 1.0),
                v1: v(1.0, 3.0, 1.0),
                v2: v(3.0, 1.0, 1.0),
            },
            Triangle {
                v0: v(0.5, 0.5, 0.0),
                v1: v(0.5, 0.5 + 1e-6, 0.0),
                v2: v(0.5, 0.5, 2.0),
            },
        ]);
        let (bvh, tris) = build(&tris);
        // A hemisphere-and-more of directions in coherent packets, plus axis-aligned ones,
        // ones parallel to the grid, and ones along its diagonals.
        let pattern = crate::bake::directions::cosine_hammersley(200);
        let order = crate::bake::directions::coherent_order(&pattern);
        let mut dirs: Vec<Vec3A> = order
            .iter()
            .flat_map(|&i| {
                let d = pattern[i as usize].as_vec3a();
                [d, v(d.x, d.y, -d.z)]
            })
            .collect();
        dirs.extend(AXES);
        dirs.extend(
            [
                v(1.0, 1.0, 0.0),
                v(-1.0, 1.0, 0.0),
                v(1.0, -1.0, 0.0),
                v(1.0, 1.0, -1e-7),
            ]
            .map(Vec3A::normalize),
        );
        let mut blocked = 0;
        for (x, y, z) in [
            (1.0, 1.0, 0.0),
            (2.0, 2.5, 0.0),
            (1.5, 2.5, 0.0),
            (0.25, 3.5, 1e-4),
            (2.0, 1.0, 1.0),
            (-1.0, 2.0, 0.0),
            (0.5, 0.5, 1.0),
        ] {
            blocked += assert_packets_agree(&bvh, &tris, v(x, y, z), &dirs);
        }
        let total = 7 * dirs.len();
        assert!(
            blocked > total / 10 && blocked < total * 9 / 10,
            "{blocked} of {total} blocked"
        );
    }

    #[test]
    fn a_single_triangle_is_a_root_leaf() {
        let tri = Triangle {
            v0: Vec3A::ZERO,
            v1: Vec3A::X,
            v2: Vec3A::Y,
        };
        let (bvh, tris) = build(&[tri]);
        let mut stack = TraversalStack::default();
        let up = Ray::new(Vec3A::new(0.2, 0.2, -1.0), Vec3A::Z, 0.0, f32::INFINITY);
        let mut hit = RayHit::none();
        assert!(
            bvh.occluded(&tris, &up, &mut stack) && bvh.closest(&tris, up, &mut hit, &mut stack)
        );
        assert_eq!((hit.primitive_id, hit.t), (0, 1.0));
        let away = Ray::new(Vec3A::new(0.2, 0.2, -1.0), -Vec3A::Z, 0.0, f32::INFINITY);
        assert!(!bvh.occluded(&tris, &away, &mut stack));
    }
}
