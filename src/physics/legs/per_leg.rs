//! A value per leg, the six legs side by side: [`PerLeg`].
//!
//! The right-hand side computes the six legs with the same arithmetic, so it is written once
//! over `PerLeg` values, generic over how the six are held ([`Lanes`]): [`Narrow`] is three
//! pairs in SSE2 registers, which every x86-64 processor has; `Wide` is legs 1-4 and 5-6 in
//! two AVX registers, used only on the steps' AVX2 path (`crate::simulation::vector`, chosen at
//! run time where the processor has it). Elsewhere both are six plain values. Every operation is per leg and
//! exactly rounded (IEEE 754 `+ - * / sqrt`), and [`PerLeg::sum`] adds in one fixed order, so
//! all forms give the same bits.
//!
//! Writing the lanes out by hand, rather than leaving loops over arrays to the compiler, is
//! what keeps them in registers: the compiler's vectoriser splits such loops into scalars and
//! shuffles as soon as a branch or a padded lane appears (the measurements are in the git log
//! and `benches/results/`).

use crate::physics::body::per_axis::AxisLanes;
use crate::physics::stand::LEG_COUNT;

#[cfg(target_arch = "x86_64")]
mod lanes {
    use core::arch::x86_64::{
        __m128d, __m256d, _CMP_GT_OQ, _CMP_LT_OQ, _mm_add_pd, _mm_and_pd, _mm_andnot_pd, _mm_cmpgt_pd, _mm_cmplt_pd,
        _mm_cvtsd_f64, _mm_div_pd, _mm_max_pd, _mm_min_pd, _mm_movemask_pd, _mm_mul_pd, _mm_or_pd, _mm_set_pd,
        _mm_set1_pd, _mm_setzero_pd, _mm_sqrt_pd, _mm_sub_pd, _mm_unpackhi_pd, _mm256_add_pd, _mm256_and_pd,
        _mm256_andnot_pd, _mm256_castpd256_pd128, _mm256_cmp_pd, _mm256_div_pd, _mm256_extractf128_pd, _mm256_hadd_pd,
        _mm256_max_pd, _mm256_min_pd, _mm256_movemask_pd, _mm256_mul_pd, _mm256_or_pd, _mm256_permute2f128_pd,
        _mm256_set_pd, _mm256_set1_pd, _mm256_setzero_pd, _mm256_sqrt_pd, _mm256_storeu_pd, _mm256_sub_pd,
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
        type Axes = crate::physics::body::per_axis::Pair;
        const FOR_CHECKS: bool = false;
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
    /// AVX2 path (`crate::simulation::vector`, behind an `unsafe fn` with that contract).
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
        type Axes = crate::physics::body::per_axis::Quad;
        const FOR_CHECKS: bool = true;
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
}

#[cfg(not(target_arch = "x86_64"))]
mod lanes {
    /// Six plain values, with the operations and the order of the sum of the x86-64 form.
    #[derive(Clone, Copy)]
    pub struct Narrow([f64; 6]);

    impl Narrow {
        #[inline(always)]
        fn map2(self, other: Self, op: impl Fn(f64, f64) -> f64) -> Self {
            Narrow(std::array::from_fn(|k| op(self.0[k], other.0[k])))
        }
    }

    /// No wider registers here: the same six values.
    #[allow(dead_code)] // named only by the AVX2 path, which is x86-64 only
    pub type Wide = Narrow;

    impl super::Lanes for Narrow {
        type Axes = crate::physics::body::per_axis::Pair;
        const FOR_CHECKS: bool = false;
        #[inline(always)]
        fn new(x: &[f64; 6]) -> Self {
            Narrow(*x)
        }

        #[inline(always)]
        fn splat(x: f64) -> Self {
            Narrow([x; 6])
        }

        #[inline(always)]
        fn add(self, other: Self) -> Self {
            self.map2(other, |a, b| a + b)
        }

        #[inline(always)]
        fn sub(self, other: Self) -> Self {
            self.map2(other, |a, b| a - b)
        }

        #[inline(always)]
        fn mul(self, other: Self) -> Self {
            self.map2(other, |a, b| a * b)
        }

        #[inline(always)]
        fn div(self, other: Self) -> Self {
            self.map2(other, |a, b| a / b)
        }

        #[inline(always)]
        fn sqrt(self) -> Self {
            Narrow(self.0.map(f64::sqrt))
        }

        #[inline(always)]
        fn where_positive(self, value: Self) -> Self {
            self.map2(value, |a, v| if a > 0.0 { v } else { 0.0 })
        }

        #[inline(always)]
        fn select_positive(self, positive: Self, otherwise: Self) -> Self {
            Narrow(std::array::from_fn(|k| if self.0[k] > 0.0 { positive.0[k] } else { otherwise.0[k] }))
        }

        #[inline(always)]
        fn clamp(self, lower: Self, upper: Self) -> Self {
            self.map2(upper, f64::min).map2(lower, f64::max)
        }

        #[inline(always)]
        fn any_outside(self, lower: Self, upper: Self) -> bool {
            (0..6).any(|k| self.0[k] < lower.0[k] || self.0[k] > upper.0[k])
        }

        #[inline(always)]
        fn sum(self) -> f64 {
            let x = self.0;
            ((x[0] + x[2]) + x[4]) + ((x[1] + x[3]) + x[5])
        }

        #[inline(always)]
        fn to_array(self) -> [f64; 6] {
            self.0
        }
    }
}

/// How six per-leg values are held and operated on: [`Narrow`] (SSE2 pairs, every x86-64)
/// or `Wide` (AVX: legs 1-4 and 5-6 in two 256-bit registers). Both give the same bits:
/// every operation is per leg, and the sum adds in one fixed order.
pub trait Lanes: Copy {
    /// The same registers for three per-axis values ([`super::per_axis`]).
    type Axes: AxisLanes;
    /// Whether the checks at the end of a step compute the legs in these lanes too (see
    /// [`crate::physics::legs::geometry::JointArrays::kinematics_in`]).
    const FOR_CHECKS: bool;
    fn new(x: &[f64; LEG_COUNT]) -> Self;
    fn splat(x: f64) -> Self;
    fn add(self, other: Self) -> Self;
    fn sub(self, other: Self) -> Self;
    fn mul(self, other: Self) -> Self;
    fn div(self, other: Self) -> Self;
    fn sqrt(self) -> Self;
    fn where_positive(self, value: Self) -> Self;
    fn select_positive(self, positive: Self, otherwise: Self) -> Self;
    fn clamp(self, lower: Self, upper: Self) -> Self;
    fn any_outside(self, lower: Self, upper: Self) -> bool;
    fn sum(self) -> f64;
    /// Four sums at once, each in [`Lanes::sum`]'s order (so the same bits).
    #[inline(always)]
    fn sum4(values: [Self; 4]) -> [f64; 4] {
        values.map(Self::sum)
    }
    /// [`Lanes::sum4`], each sum then multiplied by `factor`.
    #[inline(always)]
    fn sum4_times(values: [Self; 4], factor: f64) -> [f64; 4] {
        Self::sum4(values).map(|x| x * factor)
    }
    fn to_array(self) -> [f64; LEG_COUNT];
}

pub use lanes::Narrow;
// Crate-private: its operations execute AVX instructions, so only the steps' AVX2 path
// (behind `unsafe fn integrate_avx2`) may make one.
#[cfg_attr(not(all(target_arch = "x86_64", feature = "avx2")), allow(unused_imports))]
pub(crate) use lanes::Wide;

/// `components!(|c| expr)` is `[expr with c = 0, 1, 2]`: a vector's three components, each
/// given per leg, written out. A macro rather than an array `map` or a closure: the AVX2 path
/// needs all of it inlined, and the compiler does not inline a closure full of AVX intrinsics
/// into it.
macro_rules! components {
    (|$c:ident| $e:expr) => {
        [
            {
                let $c = 0;
                $e
            },
            {
                let $c = 1;
                $e
            },
            {
                let $c = 2;
                $e
            },
        ]
    };
}
pub(crate) use components;

/// One value per leg (legs 1..6), for arithmetic on all six at once. Every operation acts leg
/// by leg with the rounding of the scalar operation.
#[derive(Clone, Copy)]
pub struct PerLeg<L: Lanes = Narrow>(L);

const _: () = assert!(LEG_COUNT == 6, "PerLeg holds six legs");

impl<L: Lanes> PerLeg<L> {
    #[inline(always)]
    pub fn new(per_leg: &[f64; LEG_COUNT]) -> Self {
        PerLeg(L::new(per_leg))
    }

    /// The same value for every leg.
    #[inline(always)]
    pub fn splat(x: f64) -> Self {
        PerLeg(L::splat(x))
    }

    #[inline(always)]
    pub fn sqrt(self) -> Self {
        PerLeg(self.0.sqrt())
    }

    /// `value` for the legs where `self > 0`, 0 for the others (and where `self` is NaN).
    #[inline(always)]
    pub fn where_positive(self, value: Self) -> Self {
        PerLeg(self.0.where_positive(value.0))
    }

    /// `positive` for the legs where `self > 0`, `otherwise` for the others.
    #[inline(always)]
    pub fn select_positive(self, positive: Self, otherwise: Self) -> Self {
        PerLeg(self.0.select_positive(positive.0, otherwise.0))
    }

    /// Each leg's value limited to `[lower, upper]` (for finite values with `lower <= upper`,
    /// as `f64::clamp`).
    #[inline(always)]
    pub fn clamp(self, lower: Self, upper: Self) -> Self {
        PerLeg(self.0.clamp(lower.0, upper.0))
    }

    /// Whether any leg lies below its `lower` or above its `upper` bound.
    #[inline(always)]
    pub fn any_outside(self, lower: Self, upper: Self) -> bool {
        self.0.any_outside(lower.0, upper.0)
    }

    /// The sum over the legs, in the fixed order `((x1 + x3) + x5) + ((x2 + x4) + x6)`.
    #[inline(always)]
    pub fn sum(self) -> f64 {
        self.0.sum()
    }

    /// Four sums over the legs at once, each as [`PerLeg::sum`] adds (the same bits).
    #[inline(always)]
    pub fn sum4(values: [Self; 4]) -> [f64; 4] {
        L::sum4(values.map(|v| v.0))
    }

    /// [`PerLeg::sum4`], each sum multiplied by `factor` (the same bits as multiplying after).
    #[inline(always)]
    pub fn sum4_times(values: [Self; 4], factor: f64) -> [f64; 4] {
        L::sum4_times(values.map(|v| v.0), factor)
    }

    #[inline(always)]
    pub fn to_array(self) -> [f64; LEG_COUNT] {
        self.0.to_array()
    }

    /// The cross product `a x b` of two vectors given per leg by their components.
    #[inline(always)]
    pub fn cross(a: &[Self; 3], b: &[Self; 3]) -> [Self; 3] {
        [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    }
}

macro_rules! per_leg_operator {
    ($trait:ident, $method:ident) => {
        impl<L: Lanes> std::ops::$trait for PerLeg<L> {
            type Output = PerLeg<L>;
            #[inline(always)]
            fn $method(self, other: PerLeg<L>) -> PerLeg<L> {
                PerLeg(self.0.$method(other.0))
            }
        }
    };
}

per_leg_operator!(Add, add);
per_leg_operator!(Sub, sub);
per_leg_operator!(Mul, mul);
per_leg_operator!(Div, div);

#[cfg(test)]
mod tests {
    use super::*;

    /// Every operation equals the scalar one leg by leg, to the bit, and the sum adds in its
    /// documented order: for the SSE2 pairs, and for the AVX registers where the processor
    /// has AVX.
    #[test]
    fn operations_are_the_scalar_ones_leg_by_leg() {
        operations_leg_by_leg::<Narrow>();
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx") {
            operations_leg_by_leg::<Wide>();
        } else {
            println!("no AVX here: the Wide lanes are not tested");
        }
    }

    fn operations_leg_by_leg<L: Lanes>() {
        let a = [1.5, -2.25, 3.0e-7, 4.0e8, 0.1, f64::NAN];
        let b = [0.3, 7.0, -1.0e-3, 2.5, 0.0, 1.0];
        let (pa, pb) = (PerLeg::<L>::new(&a), PerLeg::<L>::new(&b));
        let bits = |x: [f64; 6]| x.map(f64::to_bits);
        let scalar = |op: fn(f64, f64) -> f64| bits(std::array::from_fn(|k| op(a[k], b[k])));
        assert_eq!(bits((pa + pb).to_array()), scalar(|x, y| x + y));
        assert_eq!(bits((pa - pb).to_array()), scalar(|x, y| x - y));
        assert_eq!(bits((pa * pb).to_array()), scalar(|x, y| x * y));
        assert_eq!(bits((pa / pb).to_array()), scalar(|x, y| x / y));
        assert_eq!(bits(pb.sqrt().to_array()), bits(b.map(f64::sqrt)));
        assert_eq!(bits(pa.where_positive(pb).to_array()), scalar(|x, y| if x > 0.0 { y } else { 0.0 }));
        assert_eq!(bits(pa.select_positive(pa, pb).to_array()), scalar(|x, y| if x > 0.0 { x } else { y }));
        let (lo, hi) = (PerLeg::splat(-1.0), PerLeg::splat(1.0));
        let finite = PerLeg::<L>::new(&[1.5, -2.25, 3.0e-7, -0.0, 0.99, -1.0]);
        assert_eq!(bits(finite.clamp(lo, hi).to_array()), bits(finite.to_array().map(|x| x.clamp(-1.0, 1.0))));
        assert_eq!(pb.sum().to_bits(), (((b[0] + b[2]) + b[4]) + ((b[1] + b[3]) + b[5])).to_bits());
        let c = [1.0e16, -3.5, 1.0, -1.0e16, 7.25e-3, 2.0];
        let d = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6];
        let ordered = |x: [f64; 6]| (((x[0] + x[2]) + x[4]) + ((x[1] + x[3]) + x[5])).to_bits();
        let four = PerLeg::<L>::sum4([pb, PerLeg::new(&c), PerLeg::new(&d), pb * PerLeg::new(&d)]);
        assert_eq!(
            four.map(f64::to_bits),
            [ordered(b), ordered(c), ordered(d), ordered(std::array::from_fn(|k| b[k] * d[k]))]
        );
        assert_eq!(PerLeg::<L>::splat(2.5).to_array(), [2.5; 6]);
        let (lo, hi) = (PerLeg::<L>::splat(-1.0), PerLeg::<L>::splat(1.0));
        assert!(!PerLeg::<L>::new(&[0.0, 0.5, -0.5, 1.0, -1.0, 0.9]).any_outside(lo, hi));
        for k in 0..6 {
            for x in [-1.5, 1.5] {
                let mut v = [0.0; 6];
                v[k] = x;
                assert!(PerLeg::<L>::new(&v).any_outside(lo, hi), "leg {k} at {x}");
            }
        }
    }
}
