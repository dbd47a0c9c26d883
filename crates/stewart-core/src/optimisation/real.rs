//! `Libm64`: an `f64` whose elementary functions are the crate's own ([`crate::maths`], the
//! `libm` crate), the number type the QP solver runs on.
//!
//! Clarabel is generic over its float type. On `f64` its exponential and power cones (linked
//! in although the cueing never builds them) would import `exp`, `log` and `pow` from the
//! platform's C library, which `build-fmu` refuses: the platforms' C libraries differ in their
//! last bits. On `Libm64` every operation is `f64`'s (`+ - * /` and `sqrt` are exactly rounded
//! everywhere) and every other function is `libm`'s: the solver computes the same bits on
//! every platform, and the binary imports no maths.

use std::fmt;
use std::num::FpCategory;
use std::ops::{Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Rem, RemAssign, Sub, SubAssign};

use num_traits::{Float, FloatConst, FromPrimitive, Num, NumCast, One, ToPrimitive, Zero};

/// An `f64` with the crate's elementary functions (see the module's documentation).
#[derive(Clone, Copy, Debug, Default, PartialEq, PartialOrd)]
#[repr(transparent)]
pub struct Libm64(pub f64);

macro_rules! binary_operators {
    ($($trait:ident $method:ident $assign_trait:ident $assign:ident;)*) => {$(
        impl $trait for Libm64 {
            type Output = Libm64;
            #[inline(always)]
            fn $method(self, o: Libm64) -> Libm64 {
                Libm64(self.0.$method(o.0))
            }
        }
        impl $assign_trait for Libm64 {
            #[inline(always)]
            fn $assign(&mut self, o: Libm64) {
                self.0.$assign(o.0)
            }
        }
    )*};
}

binary_operators! {
    Add add AddAssign add_assign;
    Sub sub SubAssign sub_assign;
    Mul mul MulAssign mul_assign;
    Div div DivAssign div_assign;
    Rem rem RemAssign rem_assign;
}

impl Neg for Libm64 {
    type Output = Libm64;
    #[inline(always)]
    fn neg(self) -> Libm64 {
        Libm64(-self.0)
    }
}

impl fmt::Display for Libm64 {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Display::fmt(&self.0, f)
    }
}

impl fmt::LowerExp for Libm64 {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::LowerExp::fmt(&self.0, f)
    }
}

impl Zero for Libm64 {
    fn zero() -> Self {
        Libm64(0.0)
    }
    fn is_zero(&self) -> bool {
        self.0 == 0.0
    }
}

impl One for Libm64 {
    fn one() -> Self {
        Libm64(1.0)
    }
}

impl Num for Libm64 {
    type FromStrRadixErr = <f64 as Num>::FromStrRadixErr;
    fn from_str_radix(s: &str, radix: u32) -> Result<Self, Self::FromStrRadixErr> {
        f64::from_str_radix(s, radix).map(Libm64)
    }
}

impl ToPrimitive for Libm64 {
    fn to_i64(&self) -> Option<i64> {
        self.0.to_i64()
    }
    fn to_u64(&self) -> Option<u64> {
        self.0.to_u64()
    }
    fn to_f64(&self) -> Option<f64> {
        Some(self.0)
    }
}

impl NumCast for Libm64 {
    fn from<T: ToPrimitive>(n: T) -> Option<Self> {
        n.to_f64().map(Libm64)
    }
}

impl FromPrimitive for Libm64 {
    fn from_i64(n: i64) -> Option<Self> {
        Some(Libm64(n as f64))
    }
    fn from_u64(n: u64) -> Option<Self> {
        Some(Libm64(n as f64))
    }
    fn from_f64(n: f64) -> Option<Self> {
        Some(Libm64(n))
    }
    fn from_f32(n: f32) -> Option<Self> {
        Some(Libm64(<f64 as From<f32>>::from(n)))
    }
}

impl FloatConst for Libm64 {
    fn E() -> Self {
        Libm64(std::f64::consts::E)
    }
    fn FRAC_1_PI() -> Self {
        Libm64(std::f64::consts::FRAC_1_PI)
    }
    fn FRAC_1_SQRT_2() -> Self {
        Libm64(std::f64::consts::FRAC_1_SQRT_2)
    }
    fn FRAC_2_PI() -> Self {
        Libm64(std::f64::consts::FRAC_2_PI)
    }
    fn FRAC_2_SQRT_PI() -> Self {
        Libm64(std::f64::consts::FRAC_2_SQRT_PI)
    }
    fn FRAC_PI_2() -> Self {
        Libm64(std::f64::consts::FRAC_PI_2)
    }
    fn FRAC_PI_3() -> Self {
        Libm64(std::f64::consts::FRAC_PI_3)
    }
    fn FRAC_PI_4() -> Self {
        Libm64(std::f64::consts::FRAC_PI_4)
    }
    fn FRAC_PI_6() -> Self {
        Libm64(std::f64::consts::FRAC_PI_6)
    }
    fn FRAC_PI_8() -> Self {
        Libm64(std::f64::consts::FRAC_PI_8)
    }
    fn LN_10() -> Self {
        Libm64(std::f64::consts::LN_10)
    }
    fn LN_2() -> Self {
        Libm64(std::f64::consts::LN_2)
    }
    fn LOG10_E() -> Self {
        Libm64(std::f64::consts::LOG10_E)
    }
    fn LOG2_E() -> Self {
        Libm64(std::f64::consts::LOG2_E)
    }
    fn PI() -> Self {
        Libm64(std::f64::consts::PI)
    }
    fn SQRT_2() -> Self {
        Libm64(std::f64::consts::SQRT_2)
    }
}

/// `Libm64` methods that are `f64`'s own (exact everywhere: no C library involved).
macro_rules! exact {
    ($($name:ident),*) => {$(
        #[inline(always)]
        fn $name(self) -> Self {
            Libm64(self.0.$name())
        }
    )*};
}

/// `Libm64` methods from the `libm` crate.
macro_rules! from_libm {
    ($($name:ident => $f:ident),*) => {$(
        #[inline]
        fn $name(self) -> Self {
            Libm64(libm::$f(self.0))
        }
    )*};
}

impl Float for Libm64 {
    fn nan() -> Self {
        Libm64(f64::NAN)
    }
    fn infinity() -> Self {
        Libm64(f64::INFINITY)
    }
    fn neg_infinity() -> Self {
        Libm64(f64::NEG_INFINITY)
    }
    fn neg_zero() -> Self {
        Libm64(-0.0)
    }
    fn min_value() -> Self {
        Libm64(f64::MIN)
    }
    fn min_positive_value() -> Self {
        Libm64(f64::MIN_POSITIVE)
    }
    fn epsilon() -> Self {
        Libm64(f64::EPSILON)
    }
    fn max_value() -> Self {
        Libm64(f64::MAX)
    }
    fn is_nan(self) -> bool {
        self.0.is_nan()
    }
    fn is_infinite(self) -> bool {
        self.0.is_infinite()
    }
    fn is_finite(self) -> bool {
        self.0.is_finite()
    }
    fn is_normal(self) -> bool {
        self.0.is_normal()
    }
    fn classify(self) -> FpCategory {
        self.0.classify()
    }
    fn is_sign_positive(self) -> bool {
        self.0.is_sign_positive()
    }
    fn is_sign_negative(self) -> bool {
        self.0.is_sign_negative()
    }
    exact!(abs, signum, sqrt, recip);
    /// `x - trunc(x)`.
    fn fract(self) -> Self {
        Libm64(self.0 - libm::trunc(self.0))
    }
    // Rounding from libm too: `f64::floor` and its kin are a C library's calls on x86-64
    // without SSE4.1.
    from_libm!(floor => floor, ceil => ceil, round => round, trunc => trunc, exp => exp, exp2 => exp2, ln => log, log2 => log2, log10 => log10, cbrt => cbrt, sin => sin,
        cos => cos, tan => tan, asin => asin, acos => acos, atan => atan, exp_m1 => expm1, ln_1p => log1p,
        sinh => sinh, cosh => cosh, tanh => tanh, asinh => asinh, acosh => acosh, atanh => atanh);
    /// Correctly rounded in software (`libm::fma`): the same bits with or without a hardware
    /// fused multiply-add.
    fn mul_add(self, a: Self, b: Self) -> Self {
        Libm64(libm::fma(self.0, a.0, b.0))
    }
    fn powi(self, n: i32) -> Self {
        Libm64(libm::pow(self.0, <f64 as From<i32>>::from(n)))
    }
    fn powf(self, n: Self) -> Self {
        Libm64(libm::pow(self.0, n.0))
    }
    fn log(self, base: Self) -> Self {
        Libm64(libm::log(self.0) / libm::log(base.0))
    }
    fn max(self, o: Self) -> Self {
        Libm64(self.0.max(o.0))
    }
    fn min(self, o: Self) -> Self {
        Libm64(self.0.min(o.0))
    }
    fn abs_sub(self, o: Self) -> Self {
        Libm64(if self.0 <= o.0 { 0.0 } else { self.0 - o.0 })
    }
    fn hypot(self, o: Self) -> Self {
        Libm64(libm::hypot(self.0, o.0))
    }
    fn atan2(self, o: Self) -> Self {
        Libm64(libm::atan2(self.0, o.0))
    }
    fn sin_cos(self) -> (Self, Self) {
        let (s, c) = libm::sincos(self.0);
        (Libm64(s), Libm64(c))
    }
    fn integer_decode(self) -> (u64, i16, i8) {
        self.0.integer_decode()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The exact operations are `f64`'s to the bit; the elementary functions `libm`'s.
    #[test]
    fn operations_are_f64s_and_functions_libms() {
        let (a, b) = (Libm64(1.2345678901234567), Libm64(-0.987654321));
        assert_eq!((a * b + a / b - a).0.to_bits(), (a.0 * b.0 + a.0 / b.0 - a.0).to_bits());
        assert_eq!(a.sqrt().0.to_bits(), a.0.sqrt().to_bits());
        assert_eq!(a.ln().0.to_bits(), libm::log(a.0).to_bits());
        assert_eq!(a.powf(b).0.to_bits(), libm::pow(a.0, b.0).to_bits());
        assert_eq!(a.powi(3).0.to_bits(), libm::pow(a.0, 3.0).to_bits());
        assert_eq!(b.exp().0.to_bits(), libm::exp(b.0).to_bits());
    }
}
