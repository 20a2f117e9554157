//! Eight f32 lanes, one per vertex of a block: the operations lane-wise kernels are written
//! in. Each is one IEEE-754 single-precision operation, correctly rounded (add, subtract,
//! multiply, divide, square root) or exact (absolute value, comparisons, selection), so
//! every implementation gives the same bits: [`Portable`] here, plain Rust the compiler
//! vectorises where the target has vectors, and on x86-64 the AVX2 registers of
//! `eval/kernels/x86`, which the same generic kernel runs in. There is no fused multiply-add
//! and no reciprocal estimate: those differ between instruction sets.
//!
//! `min` and `max` take the first operand where the comparison holds and the second
//! otherwise (a NaN gives the second), which is what `minps` and `maxps` do; `f32::min` would
//! take the other value for a NaN.

use core::ops::{Add, Div, Mul, Sub};

use crate::blob::format::VERTEX_BLOCK;
use crate::math;

/// The operations of eight f32 lanes (see the module doc). `Mask` holds one condition per
/// lane.
pub(crate) trait Lanes:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self>
{
    /// One condition per lane.
    type Mask: Copy;

    /// `x` in every lane.
    fn splat(x: f32) -> Self;
    /// The lanes of `a`.
    fn from_array(a: [f32; VERTEX_BLOCK]) -> Self;
    /// The lanes as an array.
    fn to_array(self) -> [f32; VERTEX_BLOCK];
    /// Eight points' coordinates, one lane each: `[x, y, z]`.
    #[inline(always)]
    fn from_points(points: &[[f32; 3]; VERTEX_BLOCK]) -> [Self; 3] {
        let axis = |k: usize| Self::from_array(core::array::from_fn(|l| points[l][k]));
        [axis(0), axis(1), axis(2)]
    }
    /// Correctly rounded square root.
    fn sqrt(self) -> Self;
    /// The smallest lane (of finite lanes: exact, whatever the order of comparisons).
    fn reduce_min(self) -> f32;
    /// The largest lane (likewise).
    fn reduce_max(self) -> f32;
    /// Absolute value (the sign bit cleared).
    fn abs(self) -> Self;
    /// `self < other ? self : other`.
    fn min(self, other: Self) -> Self;
    /// `self > other ? self : other`.
    fn max(self, other: Self) -> Self;
    /// `self < other`.
    fn lt(self, other: Self) -> Self::Mask;
    /// `self <= other`.
    fn le(self, other: Self) -> Self::Mask;
    /// Both conditions.
    fn and(a: Self::Mask, b: Self::Mask) -> Self::Mask;
    /// Either condition.
    fn or(a: Self::Mask, b: Self::Mask) -> Self::Mask;
    /// `a` where `mask` holds, `b` elsewhere.
    fn select(mask: Self::Mask, a: Self, b: Self) -> Self;
    /// Bit `l` set where lane `l`'s condition holds.
    fn bits(mask: Self::Mask) -> u8;
    /// The condition of lane `l` is bit `l` of `bits`.
    fn mask_of(bits: u8) -> Self::Mask;
}

/// Eight lanes in plain Rust: the reference every other implementation matches bit for bit.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Portable(pub(crate) [f32; VERTEX_BLOCK]);

/// Lane conditions as all-ones or all-zeros words, as vector compares make them.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PortableMask([u32; VERTEX_BLOCK]);

impl Portable {
    #[inline(always)]
    fn map(self, f: impl Fn(f32) -> f32) -> Self {
        Portable(self.0.map(f))
    }

    #[inline(always)]
    fn zip(self, other: Self, f: impl Fn(f32, f32) -> f32) -> Self {
        Portable(core::array::from_fn(|l| f(self.0[l], other.0[l])))
    }

    #[inline(always)]
    fn test(self, other: Self, f: impl Fn(f32, f32) -> bool) -> PortableMask {
        PortableMask(core::array::from_fn(|l| {
            if f(self.0[l], other.0[l]) { !0 } else { 0 }
        }))
    }
}

macro_rules! portable_op {
    ($trait:ident, $method:ident, $op:tt) => {
        impl $trait for Portable {
            type Output = Portable;
            #[inline(always)]
            fn $method(self, other: Portable) -> Portable {
                self.zip(other, |a, b| a $op b)
            }
        }
    };
}

portable_op!(Add, add, +);
portable_op!(Sub, sub, -);
portable_op!(Mul, mul, *);
portable_op!(Div, div, /);

impl Lanes for Portable {
    type Mask = PortableMask;

    #[inline(always)]
    fn splat(x: f32) -> Self {
        Portable([x; VERTEX_BLOCK])
    }

    #[inline(always)]
    fn from_array(a: [f32; VERTEX_BLOCK]) -> Self {
        Portable(a)
    }

    #[inline(always)]
    fn to_array(self) -> [f32; VERTEX_BLOCK] {
        self.0
    }

    #[inline(always)]
    fn sqrt(self) -> Self {
        self.map(math::sqrt)
    }

    #[inline(always)]
    fn reduce_min(self) -> f32 {
        self.0
            .iter()
            .fold(f32::INFINITY, |m, &x| if x < m { x } else { m })
    }

    #[inline(always)]
    fn reduce_max(self) -> f32 {
        self.0
            .iter()
            .fold(f32::NEG_INFINITY, |m, &x| if x > m { x } else { m })
    }

    #[inline(always)]
    fn abs(self) -> Self {
        self.map(|x| f32::from_bits(x.to_bits() & 0x7fff_ffff))
    }

    #[inline(always)]
    fn min(self, other: Self) -> Self {
        self.zip(other, |a, b| if a < b { a } else { b })
    }

    #[inline(always)]
    fn max(self, other: Self) -> Self {
        self.zip(other, |a, b| if a > b { a } else { b })
    }

    #[inline(always)]
    fn lt(self, other: Self) -> PortableMask {
        self.test(other, |a, b| a < b)
    }

    #[inline(always)]
    fn le(self, other: Self) -> PortableMask {
        self.test(other, |a, b| a <= b)
    }

    #[inline(always)]
    fn and(a: PortableMask, b: PortableMask) -> PortableMask {
        PortableMask(core::array::from_fn(|l| a.0[l] & b.0[l]))
    }

    #[inline(always)]
    fn or(a: PortableMask, b: PortableMask) -> PortableMask {
        PortableMask(core::array::from_fn(|l| a.0[l] | b.0[l]))
    }

    #[inline(always)]
    fn select(mask: PortableMask, a: Self, b: Self) -> Self {
        Portable(core::array::from_fn(|l| {
            f32::from_bits((a.0[l].to_bits() & mask.0[l]) | (b.0[l].to_bits() & !mask.0[l]))
        }))
    }

    #[inline(always)]
    fn bits(mask: PortableMask) -> u8 {
        (0..VERTEX_BLOCK).fold(0, |bits, l| bits | (((mask.0[l] & 1) as u8) << l))
    }

    #[inline(always)]
    fn mask_of(bits: u8) -> PortableMask {
        PortableMask(core::array::from_fn(|l| {
            0u32.wrapping_sub(u32::from(bits >> l & 1))
        }))
    }
}
