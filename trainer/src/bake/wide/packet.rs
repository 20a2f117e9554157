//! Shadow rays of one origin walking [`Bvh4`] together, [`PACKET`] at a time.
//!
//! The bake shoots hundreds of rays from each vertex, and the vertex's pattern is ordered so
//! that consecutive directions are close (`directions::coherent_order`): the nodes around the
//! origin, which every ray of the vertex enters, are fetched once per packet instead of once
//! per ray, with one stack entry and one round of branches per node for all the rays that
//! enter it. A node is entered with the mask of the rays whose own slab test entered it, so
//! every ray visits exactly the nodes its one-ray walk would have (minus those after it is
//! blocked), with the same slab test (the one-ray code itself) and the same ray–triangle test:
//! the answer is the one-ray answer, bit for bit. Once a single ray is left in a subtree,
//! packet bookkeeping is pure overhead, so that ray finishes the subtree with the one-ray walk.
//!
//! Tried and dropped (alternating before/after pairs of `cargo bench -p aprt-trainer --bench
//! bake`, after/before rays per second on the scene, then the demo's bake): packets of 8 with a
//! lane-wise box test across rays, 0.99× / 0.96× (the select-based lane-wise `max`/`min` cost
//! more than the node fetches it saved); packets of 64, 1.32× / 1.21× against 16's 1.39× /
//! 1.31× (bigger packets mix less similar directions); a lane-wise Möller–Trumbore across the
//! packet's rays in the leaves, bit-exact but a wash (1.36× / 1.28–1.36×: some 330 SSE
//! instructions per triangle and 16 lanes, where a one-ray test is some 45); obvhs'
//! `slow_build` tree (1.37× / 1.32×, its longer build eating its faster walk).

use glam::Vec3A;
use obvhs::{ray::Ray, triangle::Triangle};

use super::{Bvh4, Node, Slabs, TraversalStack};

/// Rays per packet. 16 shares the nodes around the origin among more rays than 8 and keeps
/// each lane's mask of rays in 16 bits of one `u64` ([`SPREAD`]).
pub(crate) const PACKET: usize = 16;

/// `SPREAD[m]` has bit `16·lane` set for every lane bit of the 4-bit mask `m`: shifting it by
/// ray `r` and or-ing over the rays turns per-ray lane masks into per-lane ray masks.
const SPREAD: [u64; 16] = {
    let mut table = [0; 16];
    let mut m = 0;
    while m < 16 {
        let mut lane = 0;
        while lane < 4 {
            table[m] |= ((m as u64 >> lane) & 1) << (16 * lane);
            lane += 1;
        }
        m += 1;
    }
    table
};

/// Up to [`PACKET`] rays sharing origin, `[tmin, tmax]` and direction octant.
pub(crate) struct Packet {
    rays: [Ray; PACKET],
    /// Each ray prepared for the one-ray slab test, which the packet walk reuses as it is.
    slabs: [Slabs; PACKET],
    octant: u8,
    /// Bit `r` set for every ray `r` in use.
    live: u32,
}

impl Packet {
    /// The rays from `origin` along `dirs` (1 to [`PACKET`] of them, no −0 components, all
    /// with the same signs) within `[tmin, tmax]`.
    pub fn new(origin: Vec3A, dirs: &[Vec3A], tmin: f32, tmax: f32) -> Self {
        debug_assert!((1..=PACKET).contains(&dirs.len()));
        let octant = octant_of(dirs[0]);
        debug_assert!(dirs.iter().all(|&d| octant_of(d) == octant));
        // Unused lanes repeat the first ray: they are never in a mask.
        let rays: [Ray; PACKET] =
            std::array::from_fn(|r| Ray::new(origin, dirs[r.min(dirs.len() - 1)], tmin, tmax));
        Packet {
            slabs: std::array::from_fn(|r| Slabs::new(&rays[r])),
            rays,
            octant,
            live: (1 << dirs.len()) - 1,
        }
    }
}

/// Bit `k` set when component `k` of `d` is negative: the walk's compiled-in entry planes.
pub(crate) fn octant_of(d: Vec3A) -> u8 {
    u8::from(d.x < 0.0) | u8::from(d.y < 0.0) << 1 | u8::from(d.z < 0.0) << 2
}

impl Bvh4 {
    /// Which rays of `packet` have something of `tris` on them, a bit per ray: each bit is
    /// what [`Bvh4::occluded`] answers for that ray.
    pub fn occluded_packet(
        &self,
        tris: &[Triangle],
        packet: &Packet,
        stack: &mut TraversalStack,
    ) -> u32 {
        match packet.octant {
            0 => self.packet_octant::<0>(tris, packet, stack),
            1 => self.packet_octant::<1>(tris, packet, stack),
            2 => self.packet_octant::<2>(tris, packet, stack),
            3 => self.packet_octant::<3>(tris, packet, stack),
            4 => self.packet_octant::<4>(tris, packet, stack),
            5 => self.packet_octant::<5>(tris, packet, stack),
            6 => self.packet_octant::<6>(tris, packet, stack),
            _ => self.packet_octant::<7>(tris, packet, stack),
        }
    }

    /// [`Bvh4::occluded_packet`] compiled for one octant, like [`Bvh4::walk_octant`].
    fn packet_octant<const OCTANT: u8>(
        &self,
        tris: &[Triangle],
        packet: &Packet,
        stack: &mut TraversalStack,
    ) -> u32 {
        let TraversalStack {
            single,
            packet: waiting,
        } = stack;
        waiting.clear();
        let mut blocked = 0;
        let mut next = (!self.nodes.is_empty()).then_some((0, packet.live));
        while let Some((id, entered)) = next.take().or_else(|| waiting.pop()) {
            let rays = entered & !blocked;
            if rays == 0 {
                continue;
            }
            if rays.is_power_of_two() {
                let r = rays.trailing_zeros() as usize;
                if self.occluded_below(tris, &packet.rays[r], id, single) {
                    blocked |= rays;
                }
                continue;
            }
            let node = &self.nodes[id as usize];
            let lanes = entered_lanes::<OCTANT>(packet, node, rays);
            for lane in 0..4 {
                let mut enter = (lanes >> (16 * lane)) as u32 & 0xffff & !blocked;
                if enter == 0 {
                    continue;
                }
                let (index, count) = (node.index[lane], node.count[lane]);
                if count == 0 {
                    if let Some(previous) = next.replace((index, enter)) {
                        waiting.push(previous);
                    }
                    continue;
                }
                while enter != 0 {
                    let r = enter.trailing_zeros() as usize;
                    enter &= enter - 1;
                    let ray = &packet.rays[r];
                    if (index..index + count).any(|k| tris[k as usize].intersect(ray) < ray.tmax) {
                        blocked |= 1 << r;
                    }
                }
                if blocked == packet.live {
                    return blocked;
                }
            }
        }
        blocked
    }
}

/// For each lane of `node`, the mask of the rays in `rays` whose own slab test enters it, in
/// bits `16·lane..16·lane + 16`: one fetch of the node serves all of them.
#[inline(always)]
fn entered_lanes<const OCTANT: u8>(packet: &Packet, node: &Node, mut rays: u32) -> u64 {
    let mut lanes = 0;
    while rays != 0 {
        let r = rays.trailing_zeros() as usize;
        rays &= rays - 1;
        lanes |= SPREAD[packet.slabs[r].enter::<OCTANT>(node) as usize] << r;
    }
    lanes
}
