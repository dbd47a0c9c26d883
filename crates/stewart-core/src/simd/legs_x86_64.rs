//! The six legs' lanes in x86-64 registers: `Narrow` (SSE2) and `Wide` (AVX).

use core::arch::x86_64::{
    __m128d, __m256d, _CMP_GT_OQ, _CMP_LT_OQ, _mm_add_pd, _mm_and_pd, _mm_andnot_pd, _mm_cmpgt_pd, _mm_cmplt_pd,
    _mm_cvtsd_f64, _mm_div_pd, _mm_max_pd, _mm_min_pd, _mm_movemask_pd, _mm_mul_pd, _mm_or_pd, _mm_set_pd, _mm_set1_pd,
    _mm_setzero_pd, _mm_sqrt_pd, _mm_sub_pd, _mm_unpackhi_pd, _mm256_add_pd, _mm256_and_pd, _mm256_andnot_pd,
    _mm256_castpd256_pd128, _mm256_cmp_pd, _mm256_div_pd, _mm256_extractf128_pd, _mm256_hadd_pd, _mm256_max_pd,
    _mm256_min_pd, _mm256_movemask_pd, _mm256_mul_pd, _mm256_or_pd, _mm256_permute2f128_pd, _mm256_set_pd,
    _mm256_set1_pd, _mm256_setzero_pd, _mm256_sqrt_pd, _mm256_storeu_pd, _mm256_sub_pd,
};

/// Legs 1-2, 3-4 and 5-6 in three SSE2 registers.
#[derive(Clone, Copy)]
pub struct Narrow([__m128d; 3]);

impl Narrow {
    #[inline(always)]
    fn map2(self, other: Self, op: impl Fn(__m128d, __m128d) -> __m128d) -> Self {
        let (a, b) = (self.0, other.0);
        Narrow([op(a[0], b[0]), op(a[1], b[1]), op(a[2], b[2])])
    }
}

impl super::Lanes for Narrow {
    type Axes = super::Pair;
    // SSE2 pairs cost the checks more than plain arrays (see JointArrays::kinematics).
    type Checks = super::Plain;
    const AVX: bool = false;
    #[inline(always)]
    fn new(x: &[f64; 6]) -> Self {
        // SAFETY (here and below): SSE2 is part of the x86-64 baseline.
        unsafe { Narrow([_mm_set_pd(x[1], x[0]), _mm_set_pd(x[3], x[2]), _mm_set_pd(x[5], x[4])]) }
    }

    #[inline(always)]
    fn splat(x: f64) -> Self {
        Narrow([unsafe { _mm_set1_pd(x) }; 3])
    }

    #[inline(always)]
    fn add(self, other: Self) -> Self {
        self.map2(other, |a, b| unsafe { _mm_add_pd(a, b) })
    }

    #[inline(always)]
    fn sub(self, other: Self) -> Self {
        self.map2(other, |a, b| unsafe { _mm_sub_pd(a, b) })
    }

    #[inline(always)]
    fn mul(self, other: Self) -> Self {
        self.map2(other, |a, b| unsafe { _mm_mul_pd(a, b) })
    }

    #[inline(always)]
    fn div(self, other: Self) -> Self {
        self.map2(other, |a, b| unsafe { _mm_div_pd(a, b) })
    }

    #[inline(always)]
    fn sqrt(self) -> Self {
        let a = self.0;
        unsafe { Narrow([_mm_sqrt_pd(a[0]), _mm_sqrt_pd(a[1]), _mm_sqrt_pd(a[2])]) }
    }

    #[inline(always)]
    fn greater(self, other: Self) -> Self {
        self.map2(other, |a, b| unsafe { _mm_cmpgt_pd(a, b) })
    }

    #[inline(always)]
    fn select(self, yes: Self, no: Self) -> Self {
        let (m, y, n) = (self.0, yes.0, no.0);
        let lane = |k: usize| unsafe { _mm_or_pd(_mm_and_pd(m[k], y[k]), _mm_andnot_pd(m[k], n[k])) };
        Narrow([lane(0), lane(1), lane(2)])
    }

    /// `value` where `self > 0`, else 0 (also where `self` is NaN).
    #[inline(always)]
    fn where_positive(self, value: Self) -> Self {
        self.map2(value, |a, v| unsafe { _mm_and_pd(_mm_cmpgt_pd(a, _mm_setzero_pd()), v) })
    }

    /// `positive` where `self > 0`, else `otherwise`.
    #[inline(always)]
    fn select_positive(self, positive: Self, otherwise: Self) -> Self {
        let (a, p, o) = (self.0, positive.0, otherwise.0);
        let lane = |k: usize| unsafe {
            let mask = _mm_cmpgt_pd(a[k], _mm_setzero_pd());
            _mm_or_pd(_mm_and_pd(mask, p[k]), _mm_andnot_pd(mask, o[k]))
        };
        Narrow([lane(0), lane(1), lane(2)])
    }

    /// `self` limited to `[lower, upper]` (finite values; `lower <= upper`).
    #[inline(always)]
    fn clamp(self, lower: Self, upper: Self) -> Self {
        self.map2(upper, |a, b| unsafe { _mm_min_pd(a, b) }).map2(lower, |a, b| unsafe { _mm_max_pd(a, b) })
    }

    /// Whether any lane lies below `lower` or above `upper`.
    #[inline(always)]
    fn any_outside(self, lower: Self, upper: Self) -> bool {
        unsafe {
            let outside =
                |k: usize| _mm_or_pd(_mm_cmplt_pd(self.0[k], lower.0[k]), _mm_cmpgt_pd(self.0[k], upper.0[k]));
            _mm_movemask_pd(_mm_or_pd(_mm_or_pd(outside(0), outside(1)), outside(2))) != 0
        }
    }

    /// `((x1 + x3) + x5) + ((x2 + x4) + x6)`.
    #[inline(always)]
    fn sum(self) -> f64 {
        unsafe {
            let s = _mm_add_pd(_mm_add_pd(self.0[0], self.0[1]), self.0[2]);
            _mm_cvtsd_f64(s) + _mm_cvtsd_f64(_mm_unpackhi_pd(s, s))
        }
    }

    #[inline(always)]
    fn to_array(self) -> [f64; 6] {
        let lane =
            |k: usize| unsafe { (_mm_cvtsd_f64(self.0[k]), _mm_cvtsd_f64(_mm_unpackhi_pd(self.0[k], self.0[k]))) };
        let ([x0, x1], [x2, x3], [x4, x5]) = (lane(0).into(), lane(1).into(), lane(2).into());
        [x0, x1, x2, x3, x4, x5]
    }
}

/// Legs 1-4 and 5-6 (and two unused lanes) in two AVX registers.
///
/// Only for code compiled with AVX enabled and run where the processor has it: the steps'
/// AVX2 path (`crate::simulation::vector`, behind an `unsafe fn` with that contract, after
/// [`super::wide_available`]).
/// Written without closures or loops, so that all of it inlines there (an intrinsic
/// inlines only into code compiled with AVX). The
/// unused lanes take part in the arithmetic (no trap: exceptions are masked) and are
/// ignored by `any_outside`, `sum` and `to_array`.
#[derive(Clone, Copy)]
#[cfg_attr(not(feature = "avx2"), allow(dead_code))]
pub struct Wide(__m256d, __m256d);

impl Wide {
    /// The sums of [`super::Lanes::sum4`] in one register, in the order `[a, c, b, d]`.
    ///
    /// # Safety
    /// AVX must be available (as wherever a `Wide` exists).
    #[inline(always)]
    unsafe fn sums(values: [Wide; 4]) -> __m256d {
        let [a, b, c, d] = values;
        unsafe { _mm256_hadd_pd(Wide::pair_sums(a, b), Wide::pair_sums(c, d)) }
    }

    /// `[(a1 + a3) + a5, (a2 + a4) + a6, the same of b]`: legs 1-4's halves and legs 5-6.
    /// (A function, not a closure: closures of intrinsics are not inlined into the AVX2
    /// path.)
    ///
    /// # Safety
    /// AVX must be available.
    #[inline(always)]
    unsafe fn pair_sums(a: Wide, b: Wide) -> __m256d {
        unsafe {
            let low = _mm256_permute2f128_pd::<0x20>(a.0, b.0);
            let high = _mm256_permute2f128_pd::<0x31>(a.0, b.0);
            let tail = _mm256_permute2f128_pd::<0x20>(a.1, b.1);
            _mm256_add_pd(_mm256_add_pd(low, high), tail)
        }
    }

    /// `[a, c, b, d]` in a register as `[a, b, c, d]`.
    #[inline(always)]
    fn in_order(sums: __m256d) -> [f64; 4] {
        let mut out = [0.0; 4];
        // SAFETY: AVX, as wherever a `Wide` exists.
        unsafe { _mm256_storeu_pd(out.as_mut_ptr(), sums) };
        [out[0], out[2], out[1], out[3]]
    }
}

// SAFETY (every `unsafe` block of this impl): a `Wide` exists only where AVX runs (above).
impl super::Lanes for Wide {
    type Axes = super::Quad;
    type Checks = Wide;
    const AVX: bool = true;
    #[inline(always)]
    fn new(x: &[f64; 6]) -> Self {
        unsafe { Wide(_mm256_set_pd(x[3], x[2], x[1], x[0]), _mm256_set_pd(0.0, 0.0, x[5], x[4])) }
    }

    #[inline(always)]
    fn splat(x: f64) -> Self {
        unsafe { Wide(_mm256_set1_pd(x), _mm256_set1_pd(x)) }
    }

    #[inline(always)]
    fn add(self, o: Self) -> Self {
        unsafe { Wide(_mm256_add_pd(self.0, o.0), _mm256_add_pd(self.1, o.1)) }
    }

    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        unsafe { Wide(_mm256_sub_pd(self.0, o.0), _mm256_sub_pd(self.1, o.1)) }
    }

    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        unsafe { Wide(_mm256_mul_pd(self.0, o.0), _mm256_mul_pd(self.1, o.1)) }
    }

    #[inline(always)]
    fn div(self, o: Self) -> Self {
        unsafe { Wide(_mm256_div_pd(self.0, o.0), _mm256_div_pd(self.1, o.1)) }
    }

    #[inline(always)]
    fn sqrt(self) -> Self {
        unsafe { Wide(_mm256_sqrt_pd(self.0), _mm256_sqrt_pd(self.1)) }
    }

    #[inline(always)]
    fn greater(self, o: Self) -> Self {
        unsafe { Wide(_mm256_cmp_pd::<_CMP_GT_OQ>(self.0, o.0), _mm256_cmp_pd::<_CMP_GT_OQ>(self.1, o.1)) }
    }

    #[inline(always)]
    fn select(self, y: Self, n: Self) -> Self {
        unsafe {
            Wide(
                _mm256_or_pd(_mm256_and_pd(self.0, y.0), _mm256_andnot_pd(self.0, n.0)),
                _mm256_or_pd(_mm256_and_pd(self.1, y.1), _mm256_andnot_pd(self.1, n.1)),
            )
        }
    }

    #[inline(always)]
    fn where_positive(self, v: Self) -> Self {
        unsafe {
            let zero = _mm256_setzero_pd();
            Wide(
                _mm256_and_pd(_mm256_cmp_pd::<_CMP_GT_OQ>(self.0, zero), v.0),
                _mm256_and_pd(_mm256_cmp_pd::<_CMP_GT_OQ>(self.1, zero), v.1),
            )
        }
    }

    #[inline(always)]
    fn select_positive(self, p: Self, o: Self) -> Self {
        unsafe {
            let zero = _mm256_setzero_pd();
            let (m0, m1) = (_mm256_cmp_pd::<_CMP_GT_OQ>(self.0, zero), _mm256_cmp_pd::<_CMP_GT_OQ>(self.1, zero));
            Wide(
                _mm256_or_pd(_mm256_and_pd(m0, p.0), _mm256_andnot_pd(m0, o.0)),
                _mm256_or_pd(_mm256_and_pd(m1, p.1), _mm256_andnot_pd(m1, o.1)),
            )
        }
    }

    #[inline(always)]
    fn clamp(self, lower: Self, upper: Self) -> Self {
        unsafe {
            Wide(
                _mm256_max_pd(_mm256_min_pd(self.0, upper.0), lower.0),
                _mm256_max_pd(_mm256_min_pd(self.1, upper.1), lower.1),
            )
        }
    }

    #[inline(always)]
    fn any_outside(self, lower: Self, upper: Self) -> bool {
        unsafe {
            let first = _mm256_or_pd(
                _mm256_cmp_pd::<_CMP_LT_OQ>(self.0, lower.0),
                _mm256_cmp_pd::<_CMP_GT_OQ>(self.0, upper.0),
            );
            let second = _mm256_or_pd(
                _mm256_cmp_pd::<_CMP_LT_OQ>(self.1, lower.1),
                _mm256_cmp_pd::<_CMP_GT_OQ>(self.1, upper.1),
            );
            (_mm256_movemask_pd(first) | (_mm256_movemask_pd(second) & 0b11)) != 0
        }
    }

    /// `((x1 + x3) + x5) + ((x2 + x4) + x6)`, as [`Narrow`]'s.
    #[inline(always)]
    fn sum(self) -> f64 {
        unsafe {
            let s = _mm_add_pd(
                _mm_add_pd(_mm256_castpd256_pd128(self.0), _mm256_extractf128_pd::<1>(self.0)),
                _mm256_castpd256_pd128(self.1),
            );
            _mm_cvtsd_f64(s) + _mm_cvtsd_f64(_mm_unpackhi_pd(s, s))
        }
    }

    /// Four sums at once: each value's pair sums `((x1 + x3) + x5, (x2 + x4) + x6)` side by
    /// side, two values to a register, then one horizontal add; four sums in about the
    /// instructions of two.
    #[inline(always)]
    fn sum4(values: [Self; 4]) -> [f64; 4] {
        Wide::in_order(unsafe { Wide::sums(values) })
    }

    /// [`Wide::sum4`] with the four products in one multiplication.
    #[inline(always)]
    fn sum4_times(values: [Self; 4], factor: f64) -> [f64; 4] {
        Wide::in_order(unsafe { _mm256_mul_pd(Wide::sums(values), _mm256_set1_pd(factor)) })
    }

    #[inline(always)]
    fn to_array(self) -> [f64; 6] {
        let mut x = [0.0; 8];
        unsafe {
            _mm256_storeu_pd(x.as_mut_ptr(), self.0);
            _mm256_storeu_pd(x.as_mut_ptr().add(4), self.1);
        }
        [x[0], x[1], x[2], x[3], x[4], x[5]]
    }
}
