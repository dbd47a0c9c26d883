//! The three axes' lanes in x86-64 registers: `Pair` (SSE2) and `Quad` (AVX2).

use core::arch::x86_64::{
    __m128d, __m256d, _mm_add_pd, _mm_cvtsd_f64, _mm_loadu_pd, _mm_mul_pd, _mm_set_pd, _mm_set1_pd, _mm_shuffle_pd,
    _mm_storeu_pd, _mm_sub_pd, _mm_unpackhi_pd, _mm256_add_pd, _mm256_loadu_pd, _mm256_mul_pd, _mm256_permute4x64_pd,
    _mm256_set_pd, _mm256_set1_pd, _mm256_storeu_pd, _mm256_sub_pd,
};

/// Axes 1-2 and 3 (and the padding lane) in two SSE2 registers.
#[derive(Clone, Copy)]
pub struct Pair(__m128d, __m128d);

// SAFETY (every `unsafe` block of this impl): SSE2 is part of the x86-64 baseline.
impl super::AxisLanes for Pair {
    #[inline(always)]
    fn new(x: [f64; 3]) -> Self {
        unsafe { Pair(_mm_set_pd(x[1], x[0]), _mm_set_pd(0.0, x[2])) }
    }

    #[inline(always)]
    fn load(x: &[f64; 4]) -> Self {
        unsafe { Pair(_mm_loadu_pd(x.as_ptr()), _mm_loadu_pd(x.as_ptr().add(2))) }
    }

    #[inline(always)]
    fn splat(x: f64) -> Self {
        unsafe { Pair(_mm_set1_pd(x), _mm_set1_pd(x)) }
    }

    #[inline(always)]
    fn add(self, o: Self) -> Self {
        unsafe { Pair(_mm_add_pd(self.0, o.0), _mm_add_pd(self.1, o.1)) }
    }

    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        unsafe { Pair(_mm_sub_pd(self.0, o.0), _mm_sub_pd(self.1, o.1)) }
    }

    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        unsafe { Pair(_mm_mul_pd(self.0, o.0), _mm_mul_pd(self.1, o.1)) }
    }

    /// `[x1, x2, x0, x3]`: `_mm_shuffle_pd(a, b, m)` is `[a[m & 1], b[m >> 1]]`.
    #[inline(always)]
    fn next(self) -> Self {
        unsafe { Pair(_mm_shuffle_pd::<0b01>(self.0, self.1), _mm_shuffle_pd::<0b10>(self.0, self.1)) }
    }

    /// `[x2, x0, x1, x3]`.
    #[inline(always)]
    fn previous(self) -> Self {
        unsafe { Pair(_mm_shuffle_pd::<0b00>(self.1, self.0), _mm_shuffle_pd::<0b11>(self.0, self.1)) }
    }

    #[inline(always)]
    fn sum3(self) -> f64 {
        unsafe { (_mm_cvtsd_f64(self.0) + _mm_cvtsd_f64(_mm_unpackhi_pd(self.0, self.0))) + _mm_cvtsd_f64(self.1) }
    }

    #[inline(always)]
    fn to_array(self) -> [f64; 4] {
        let mut x = [0.0; 4];
        unsafe {
            _mm_storeu_pd(x.as_mut_ptr(), self.0);
            _mm_storeu_pd(x.as_mut_ptr().add(2), self.1);
        }
        x
    }
}

/// The three axes (and the padding lane) in one AVX register.
///
/// Only for code compiled with AVX2 enabled and run where the processor has it: the steps'
/// AVX2 path (see [`super::Wide`], which names this type as its
/// axes). Written without closures, so that all of it inlines there.
#[derive(Clone, Copy)]
#[cfg_attr(not(feature = "avx2"), allow(dead_code))]
pub struct Quad(__m256d);

// SAFETY (every `unsafe` block of this impl): a `Quad` exists only where AVX2 runs (above).
impl super::AxisLanes for Quad {
    #[inline(always)]
    fn new(x: [f64; 3]) -> Self {
        unsafe { Quad(_mm256_set_pd(0.0, x[2], x[1], x[0])) }
    }

    #[inline(always)]
    fn load(x: &[f64; 4]) -> Self {
        unsafe { Quad(_mm256_loadu_pd(x.as_ptr())) }
    }

    #[inline(always)]
    fn splat(x: f64) -> Self {
        unsafe { Quad(_mm256_set1_pd(x)) }
    }

    #[inline(always)]
    fn add(self, o: Self) -> Self {
        unsafe { Quad(_mm256_add_pd(self.0, o.0)) }
    }

    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        unsafe { Quad(_mm256_sub_pd(self.0, o.0)) }
    }

    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        unsafe { Quad(_mm256_mul_pd(self.0, o.0)) }
    }

    /// Lanes `[1, 2, 0, 3]`.
    #[inline(always)]
    fn next(self) -> Self {
        unsafe { Quad(_mm256_permute4x64_pd::<0b11_00_10_01>(self.0)) }
    }

    /// Lanes `[2, 0, 1, 3]`.
    #[inline(always)]
    fn previous(self) -> Self {
        unsafe { Quad(_mm256_permute4x64_pd::<0b11_01_00_10>(self.0)) }
    }

    #[inline(always)]
    fn sum3(self) -> f64 {
        let x = self.to_array();
        (x[0] + x[1]) + x[2]
    }

    #[inline(always)]
    fn to_array(self) -> [f64; 4] {
        let mut x = [0.0; 4];
        unsafe { _mm256_storeu_pd(x.as_mut_ptr(), self.0) };
        x
    }
}
