//! Lanes as plain arrays, with the operations and the order of every sum of the x86-64 forms,
//! so the same bits (the compiler may still vectorise them): `Plain` everywhere (the checks at
//! the end of a step, where loops over arrays compile shorter), and on processors without the
//! x86-64 forms also the axes' `Pair`.

#[cfg(not(target_arch = "x86_64"))]
pub use axes::{Pair, Quad};
pub use legs::Plain;

mod legs {
    /// Six plain values, with the operations and the order of the sum of the x86-64 form.
    #[derive(Clone, Copy)]
    pub struct Plain([f64; 6]);

    impl Plain {
        #[inline(always)]
        fn map2(self, other: Self, op: impl Fn(f64, f64) -> f64) -> Self {
            Plain(std::array::from_fn(|k| op(self.0[k], other.0[k])))
        }
    }

    impl crate::simd::Lanes for Plain {
        type Axes = crate::simd::Pair;
        type Checks = Plain;
        const AVX: bool = false;
        #[inline(always)]
        fn new(x: &[f64; 6]) -> Self {
            Plain(*x)
        }

        #[inline(always)]
        fn splat(x: f64) -> Self {
            Plain([x; 6])
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
            Plain(self.0.map(f64::sqrt))
        }

        #[inline(always)]
        fn greater(self, other: Self) -> Self {
            self.map2(other, |a, b| if a > b { f64::from_bits(u64::MAX) } else { 0.0 })
        }

        #[inline(always)]
        fn select(self, yes: Self, no: Self) -> Self {
            Plain(std::array::from_fn(|k| if self.0[k].to_bits() != 0 { yes.0[k] } else { no.0[k] }))
        }

        #[inline(always)]
        fn where_positive(self, value: Self) -> Self {
            self.map2(value, |a, v| if a > 0.0 { v } else { 0.0 })
        }

        #[inline(always)]
        fn select_positive(self, positive: Self, otherwise: Self) -> Self {
            Plain(std::array::from_fn(|k| if self.0[k] > 0.0 { positive.0[k] } else { otherwise.0[k] }))
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

#[cfg(not(target_arch = "x86_64"))]
mod axes {
    /// Four plain values, with the operations and the order of the sum of the x86-64 forms.
    #[derive(Clone, Copy)]
    pub struct Pair([f64; 4]);

    /// No wider registers here: the same four values.
    #[allow(dead_code)] // named only by the AVX2 path, which is x86-64 only
    pub type Quad = Pair;

    impl crate::simd::AxisLanes for Pair {
        #[inline(always)]
        fn new(x: [f64; 3]) -> Self {
            Pair([x[0], x[1], x[2], 0.0])
        }

        #[inline(always)]
        fn load(x: &[f64; 4]) -> Self {
            Pair(*x)
        }

        #[inline(always)]
        fn splat(x: f64) -> Self {
            Pair([x; 4])
        }

        #[inline(always)]
        fn add(self, o: Self) -> Self {
            Pair(std::array::from_fn(|k| self.0[k] + o.0[k]))
        }

        #[inline(always)]
        fn sub(self, o: Self) -> Self {
            Pair(std::array::from_fn(|k| self.0[k] - o.0[k]))
        }

        #[inline(always)]
        fn mul(self, o: Self) -> Self {
            Pair(std::array::from_fn(|k| self.0[k] * o.0[k]))
        }

        #[inline(always)]
        fn next(self) -> Self {
            let x = self.0;
            Pair([x[1], x[2], x[0], x[3]])
        }

        #[inline(always)]
        fn previous(self) -> Self {
            let x = self.0;
            Pair([x[2], x[0], x[1], x[3]])
        }

        #[inline(always)]
        fn sum3(self) -> f64 {
            (self.0[0] + self.0[1]) + self.0[2]
        }

        #[inline(always)]
        fn to_array(self) -> [f64; 4] {
            self.0
        }
    }
}
