//! [`Lanes`] in one AVX2 register, and the proxies' occlusion kernel run in it: the portable
//! kernel's generic code, compiled where AVX2 is enabled, so each lane operation is one AVX
//! instruction with the IEEE result the portable lanes compute one lane at a time.

use core::arch::x86_64::{
    __m256, _CMP_LE_OQ, _CMP_LT_OQ, _mm_cvtss_f32, _mm_max_ps, _mm_max_ss, _mm_min_ps, _mm_min_ss,
    _mm_movehl_ps, _mm_shuffle_ps, _mm256_add_ps, _mm256_and_ps, _mm256_and_si256, _mm256_blend_ps,
    _mm256_blendv_ps, _mm256_castps256_ps128, _mm256_castsi256_ps, _mm256_cmp_ps,
    _mm256_cmpeq_epi32, _mm256_div_ps, _mm256_extractf128_ps, _mm256_loadu_ps, _mm256_max_ps,
    _mm256_min_ps, _mm256_movemask_ps, _mm256_mul_ps, _mm256_or_ps, _mm256_permutevar8x32_ps,
    _mm256_set1_epi32, _mm256_set1_ps, _mm256_setr_epi32, _mm256_sqrt_ps, _mm256_storeu_ps,
    _mm256_sub_ps,
};
use core::ops::{Add, Div, Mul, Sub};

use super::Avx2;
use crate::blob::format::VERTEX_BLOCK;
use crate::lanes::Lanes;
use crate::proxies::{Block, Output, ProxyFrame, occlusion_kernel};

/// Eight lanes in an AVX register. Exists only inside functions compiled with AVX2 (below),
/// which [`Avx2`] proves the CPU runs.
#[derive(Clone, Copy)]
pub(crate) struct Wide(__m256);

macro_rules! wide_op {
    ($trait:ident, $method:ident, $intrinsic:ident) => {
        impl $trait for Wide {
            type Output = Wide;
            #[inline(always)]
            fn $method(self, other: Wide) -> Wide {
                // SAFETY: `Wide` values exist only on a CPU with AVX2 (see the type).
                Wide(unsafe { $intrinsic(self.0, other.0) })
            }
        }
    };
}

wide_op!(Add, add, _mm256_add_ps);
wide_op!(Sub, sub, _mm256_sub_ps);
wide_op!(Mul, mul, _mm256_mul_ps);
wide_op!(Div, div, _mm256_div_ps);

// SAFETY (every block below): `Wide` values exist only on a CPU with AVX2 (see the type); the
// loads and stores are of arrays of exactly eight f32s.
impl Lanes for Wide {
    type Mask = __m256;

    #[inline(always)]
    fn splat(x: f32) -> Self {
        Wide(unsafe { _mm256_set1_ps(x) })
    }

    #[inline(always)]
    fn from_array(a: [f32; VERTEX_BLOCK]) -> Self {
        Wide(unsafe { _mm256_loadu_ps(a.as_ptr()) })
    }

    #[inline(always)]
    fn to_array(self) -> [f32; VERTEX_BLOCK] {
        let mut a = [0.0f32; VERTEX_BLOCK];
        unsafe { _mm256_storeu_ps(a.as_mut_ptr(), self.0) };
        a
    }

    /// Three loads and, per axis, two blends and a permutation: the eight points' 24 values
    /// in memory hold `x` at every third position from 0, `y` from 1 and `z` from 2.
    #[inline(always)]
    fn from_points(points: &[[f32; 3]; VERTEX_BLOCK]) -> [Self; 3] {
        let p = points.as_flattened().as_ptr();
        unsafe {
            let (a, b, c) = (
                _mm256_loadu_ps(p),
                _mm256_loadu_ps(p.add(8)),
                _mm256_loadu_ps(p.add(16)),
            );
            // Value 3l + k sits in register (3l + k) / 8, lane (3l + k) % 8: blend each lane
            // from the register holding one of the axis's values there, then put them in order.
            let x = _mm256_blend_ps::<0b0100_1001>(_mm256_blend_ps::<0b1001_0010>(c, b), a);
            let y = _mm256_blend_ps::<0b1001_0010>(_mm256_blend_ps::<0b0010_0100>(c, b), a);
            let z = _mm256_blend_ps::<0b0010_0100>(_mm256_blend_ps::<0b0100_1001>(c, b), a);
            [
                Wide(_mm256_permutevar8x32_ps(
                    x,
                    _mm256_setr_epi32(0, 3, 6, 1, 4, 7, 2, 5),
                )),
                Wide(_mm256_permutevar8x32_ps(
                    y,
                    _mm256_setr_epi32(1, 4, 7, 2, 5, 0, 3, 6),
                )),
                Wide(_mm256_permutevar8x32_ps(
                    z,
                    _mm256_setr_epi32(2, 5, 0, 3, 6, 1, 4, 7),
                )),
            ]
        }
    }

    #[inline(always)]
    fn sqrt(self) -> Self {
        Wide(unsafe { _mm256_sqrt_ps(self.0) })
    }

    #[inline(always)]
    fn reduce_min(self) -> f32 {
        unsafe {
            let m = _mm_min_ps(
                _mm256_castps256_ps128(self.0),
                _mm256_extractf128_ps::<1>(self.0),
            );
            let m = _mm_min_ps(m, _mm_movehl_ps(m, m));
            _mm_cvtss_f32(_mm_min_ss(m, _mm_shuffle_ps::<1>(m, m)))
        }
    }

    #[inline(always)]
    fn reduce_max(self) -> f32 {
        unsafe {
            let m = _mm_max_ps(
                _mm256_castps256_ps128(self.0),
                _mm256_extractf128_ps::<1>(self.0),
            );
            let m = _mm_max_ps(m, _mm_movehl_ps(m, m));
            _mm_cvtss_f32(_mm_max_ss(m, _mm_shuffle_ps::<1>(m, m)))
        }
    }

    #[inline(always)]
    fn abs(self) -> Self {
        Wide(unsafe { _mm256_and_ps(self.0, _mm256_castsi256_ps(_mm256_set1_epi32(0x7fff_ffff))) })
    }

    #[inline(always)]
    fn min(self, other: Self) -> Self {
        // `vminps a, b` is `a < b ? a : b`, the portable definition.
        Wide(unsafe { _mm256_min_ps(self.0, other.0) })
    }

    #[inline(always)]
    fn max(self, other: Self) -> Self {
        Wide(unsafe { _mm256_max_ps(self.0, other.0) })
    }

    #[inline(always)]
    fn lt(self, other: Self) -> __m256 {
        unsafe { _mm256_cmp_ps::<_CMP_LT_OQ>(self.0, other.0) }
    }

    #[inline(always)]
    fn le(self, other: Self) -> __m256 {
        unsafe { _mm256_cmp_ps::<_CMP_LE_OQ>(self.0, other.0) }
    }

    #[inline(always)]
    fn and(a: __m256, b: __m256) -> __m256 {
        unsafe { _mm256_and_ps(a, b) }
    }

    #[inline(always)]
    fn or(a: __m256, b: __m256) -> __m256 {
        unsafe { _mm256_or_ps(a, b) }
    }

    #[inline(always)]
    fn select(mask: __m256, a: Self, b: Self) -> Self {
        Wide(unsafe { _mm256_blendv_ps(b.0, a.0, mask) })
    }

    #[inline(always)]
    fn bits(mask: __m256) -> u8 {
        unsafe { _mm256_movemask_ps(mask) as u8 }
    }

    #[inline(always)]
    fn mask_of(bits: u8) -> __m256 {
        unsafe {
            let lane = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
            let set = _mm256_and_si256(_mm256_set1_epi32(i32::from(bits)), lane);
            _mm256_castsi256_ps(_mm256_cmpeq_epi32(set, lane))
        }
    }
}

impl Avx2 {
    /// [`crate::proxies::block_occlusion`] in AVX2.
    #[inline(always)]
    pub(crate) fn occlusion(
        self,
        frame: &ProxyFrame,
        order: usize,
        block: &Block,
        output: Output<'_>,
    ) -> u8 {
        // SAFETY: `self` exists only on a CPU with AVX2.
        unsafe { occlusion(frame, order, block, output) }
    }
}

#[target_feature(enable = "avx2")]
fn occlusion(frame: &ProxyFrame, order: usize, block: &Block, output: Output<'_>) -> u8 {
    occlusion_kernel::<Wide>(frame, order, block, output)
}
