//! A value per leg, the six legs side by side: [`PerLeg`], a [`Number`] like `f64` and
//! [`crate::physics::number::Dual`], so the per-leg laws written over `Number` run on the six
//! legs at once. How the six are held is [`Lanes`] (`crate::simd`: SSE2 pairs, AVX registers on
//! the steps' AVX2 path, plain arrays elsewhere); every operation is per leg and exactly
//! rounded, and [`PerLeg::sum`] adds in one fixed order, so all forms give the same bits.

use crate::physics::number::Number;
use crate::physics::stand::LEG_COUNT;
pub use crate::simd::{Lanes, Narrow};

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

/// The sum over the six legs in the fixed order `((x1 + x3) + x5) + ((x2 + x4) + x6)`, that of
/// [`PerLeg::sum`], in any number type.
#[inline(always)]
pub fn sum_over_legs<T: Number>(x: &[T; LEG_COUNT]) -> T {
    ((x[0] + x[2]) + x[4]) + ((x[1] + x[3]) + x[5])
}

/// One value per leg (legs 1..6), for arithmetic on all six at once. Every operation acts leg
/// by leg with the rounding of the scalar operation.
#[derive(Clone, Copy)]
pub struct PerLeg<L: Lanes = Narrow>(L);

const _: () = assert!(LEG_COUNT == crate::simd::LANES, "PerLeg holds one lane per leg");

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

/// An `f64` operand is the same value in every leg (what the scalar law computes leg by leg).
macro_rules! per_leg_constant_operator {
    ($trait:ident, $method:ident) => {
        impl<L: Lanes> std::ops::$trait<f64> for PerLeg<L> {
            type Output = PerLeg<L>;
            #[inline(always)]
            fn $method(self, other: f64) -> PerLeg<L> {
                PerLeg(self.0.$method(L::splat(other)))
            }
        }
    };
}

per_leg_constant_operator!(Add, add);
per_leg_constant_operator!(Sub, sub);
per_leg_constant_operator!(Mul, mul);
per_leg_constant_operator!(Div, div);

impl<L: Lanes> Number for PerLeg<L> {
    /// Set bits in the legs where the comparison holds.
    type Mask = PerLeg<L>;
    #[inline(always)]
    fn constant(x: f64) -> Self {
        PerLeg::splat(x)
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        PerLeg(self.0.sqrt())
    }
    #[inline(always)]
    fn greater(self, other: Self) -> Self {
        PerLeg(self.0.greater(other.0))
    }
    #[inline(always)]
    fn select(mask: Self, yes: Self, no: Self) -> Self {
        PerLeg(mask.0.select(yes.0, no.0))
    }
    /// One mask operation (no blend with zero).
    #[inline(always)]
    fn where_positive(self, value: Self) -> Self {
        PerLeg(self.0.where_positive(value.0))
    }
    /// Leg by leg (libm has no vector form): the scalar `pow`'s bits.
    #[inline(always)]
    fn powf(self, y: f64) -> Self {
        let mut x = self.to_array();
        for v in &mut x {
            *v = crate::maths::pow(*v, y);
        }
        PerLeg::new(&x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every operation equals the scalar one leg by leg, to the bit, and the sum adds in its
    /// documented order: for the SSE2 pairs, and for the AVX registers where the processor
    /// has AVX.
    #[test]
    fn operations_are_the_scalar_ones_leg_by_leg() {
        operations_leg_by_leg::<Narrow>();
        if crate::simd::wide_testable() {
            operations_leg_by_leg::<crate::simd::Wide>();
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
        assert_eq!(bits(PerLeg::select(pa.greater(pb), pa, pb).to_array()), scalar(|x, y| if x > y { x } else { y }));
        assert_eq!(bits((pa * 2.5 - 1.0).to_array()), bits(a.map(|x| x * 2.5 - 1.0)));
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
