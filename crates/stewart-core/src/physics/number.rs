//! The number types the physics is written in.
//!
//! - [`Number`]: what every one has: arithmetic, constants, `sqrt`, comparisons as masks and
//!   `select`. Implemented by `f64`, by [`Dual`], and by the six legs side by side
//!   (`crate::physics::legs::per_leg::PerLeg`, in vector registers). A per-leg law written
//!   over `Number` (the drive law, the leg kinematics) is written once and runs on all three.
//! - [`Real`]: a `Number` that is one value (`f64`, or [`Dual`]: a value and one directional
//!   derivative, forward-mode automatic differentiation): ordered, held in `nalgebra`
//!   vectors, with the elementary functions. The right-hand side, the end-stop law and the
//!   outputs are written once, generic over `Real`; evaluated on duals seeded with a
//!   direction they give the exact directional derivative along it (Model Exchange
//!   Jacobians, FMI 3 adjoints, output derivatives), with no hand-derived tangent to keep in
//!   step with the physics.
//!
//! Branches compare values only (`PartialOrd` of a dual is its value's): at a kink (an end
//! stop's onset, the clamp of its damper) the derivative is that of the branch taken.

use std::ops::{Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign};

use nalgebra::{ClosedAddAssign, ClosedDivAssign, ClosedMulAssign, ClosedSubAssign, Scalar, Vector3};
use num_traits::{One, Zero};

use crate::maths;

/// A number of the physics: one value (`f64`, [`Dual`]) or one per lane (the six legs side by
/// side). Every operation acts lane by lane with the rounding of the `f64` operation, and
/// none fuses a multiply-add, so a law gives the same bits in every form.
pub trait Number:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Add<f64, Output = Self>
    + Sub<f64, Output = Self>
    + Mul<f64, Output = Self>
    + Div<f64, Output = Self>
{
    /// The result of a comparison: `bool` for one value, a lane mask for lanes.
    type Mask: Copy;
    /// A constant (derivative zero; the same in every lane).
    fn constant(x: f64) -> Self;
    fn sqrt(self) -> Self;
    /// `self > other` (false where either is NaN), by value.
    fn greater(self, other: Self) -> Self::Mask;
    /// `yes` where `mask` holds, else `no`.
    fn select(mask: Self::Mask, yes: Self, no: Self) -> Self;
    /// `self` to the constant power `y` (`self > 0`; libm's `pow`, in each lane).
    fn powf(self, y: f64) -> Self;
    /// `value` where `self > 0`, else 0 (also where `self` is NaN): a leg's direction and
    /// its other quantities that vanish with a collapsed leg.
    #[inline(always)]
    fn where_positive(self, value: Self) -> Self {
        let zero = Self::constant(0.0);
        Self::select(self.greater(zero), value, zero)
    }
}

/// A real number of the physics: `f64`, or a [`Dual`] carrying a directional derivative.
pub trait Real:
    Number<Mask = bool>
    + Scalar
    + PartialOrd
    + Zero
    + One
    + ClosedAddAssign
    + ClosedSubAssign
    + ClosedMulAssign
    + ClosedDivAssign
    + Neg<Output = Self>
{
    /// The value (a dual's real part).
    fn value(self) -> f64;
    fn abs(self) -> Self;
    fn asin(self) -> Self;
    fn acos(self) -> Self;
    fn sin(self) -> Self;
    fn atan2(self, x: Self) -> Self;
    fn exp(self) -> Self;
    /// The natural logarithm (`self > 0`).
    fn ln(self) -> Self;
    fn tanh(self) -> Self;

    /// `self` limited to `[lower, upper]` by value (`lower <= upper`).
    #[inline(always)]
    fn clamp_to(self, lower: Self, upper: Self) -> Self {
        if self > upper {
            upper
        } else if self < lower {
            lower
        } else {
            self
        }
    }

    /// The larger by value (`self` if equal).
    #[inline(always)]
    fn max_of(self, other: Self) -> Self {
        if other > self { other } else { self }
    }
}

impl Number for f64 {
    type Mask = bool;
    #[inline(always)]
    fn constant(x: f64) -> Self {
        x
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
    #[inline(always)]
    fn greater(self, other: Self) -> bool {
        self > other
    }
    #[inline(always)]
    fn select(mask: bool, yes: Self, no: Self) -> Self {
        if mask { yes } else { no }
    }
    #[inline(always)]
    fn powf(self, y: f64) -> Self {
        maths::pow(self, y)
    }
}

impl Real for f64 {
    #[inline(always)]
    fn value(self) -> f64 {
        self
    }
    #[inline(always)]
    fn abs(self) -> Self {
        f64::abs(self)
    }
    #[inline(always)]
    fn asin(self) -> Self {
        maths::asin(self)
    }
    #[inline(always)]
    fn acos(self) -> Self {
        maths::acos(self)
    }
    #[inline(always)]
    fn sin(self) -> Self {
        maths::sin(self)
    }
    #[inline(always)]
    fn atan2(self, x: Self) -> Self {
        maths::atan2(self, x)
    }
    #[inline(always)]
    fn exp(self) -> Self {
        maths::exp(self)
    }
    #[inline(always)]
    fn ln(self) -> Self {
        maths::ln(self)
    }
    #[inline(always)]
    fn tanh(self) -> Self {
        maths::tanh(self)
    }
}

/// A value and its derivative along one direction: `re + eps ε` with `ε² = 0`. Arithmetic on
/// duals carries the chain rule, so a function written for [`Real`] and evaluated at
/// `x + dx ε` returns `f(x) + (J dx) ε`.
#[derive(Clone, Copy, Debug, Default)]
pub struct Dual {
    /// The value.
    pub re: f64,
    /// The derivative along the seeded direction.
    pub eps: f64,
}

impl Dual {
    pub const fn new(re: f64, eps: f64) -> Self {
        Dual { re, eps }
    }

    /// Duals `x[i] + dx[i] ε`.
    pub fn seeded<const N: usize>(x: &[f64; N], dx: &[f64; N]) -> [Dual; N] {
        std::array::from_fn(|i| Dual::new(x[i], dx[i]))
    }

    /// The derivative parts.
    pub fn tangents<const N: usize>(x: &[Dual; N]) -> [f64; N] {
        x.map(|d| d.eps)
    }
}

/// Equal when value and derivative are (what `nalgebra` needs); ordered by value only (what
/// a branch of the physics needs).
impl PartialEq for Dual {
    fn eq(&self, other: &Self) -> bool {
        self.re == other.re && self.eps == other.eps
    }
}

impl PartialOrd for Dual {
    #[inline(always)]
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        self.re.partial_cmp(&other.re)
    }
}

impl Zero for Dual {
    fn zero() -> Self {
        Dual::new(0.0, 0.0)
    }
    fn is_zero(&self) -> bool {
        self.re == 0.0 && self.eps == 0.0
    }
}

impl One for Dual {
    fn one() -> Self {
        Dual::new(1.0, 0.0)
    }
}

impl Neg for Dual {
    type Output = Dual;
    #[inline(always)]
    fn neg(self) -> Dual {
        Dual::new(-self.re, -self.eps)
    }
}

impl Add for Dual {
    type Output = Dual;
    #[inline(always)]
    fn add(self, o: Dual) -> Dual {
        Dual::new(self.re + o.re, self.eps + o.eps)
    }
}

impl Sub for Dual {
    type Output = Dual;
    #[inline(always)]
    fn sub(self, o: Dual) -> Dual {
        Dual::new(self.re - o.re, self.eps - o.eps)
    }
}

impl Mul for Dual {
    type Output = Dual;
    #[inline(always)]
    fn mul(self, o: Dual) -> Dual {
        Dual::new(self.re * o.re, self.eps * o.re + self.re * o.eps)
    }
}

impl Div for Dual {
    type Output = Dual;
    #[inline(always)]
    fn div(self, o: Dual) -> Dual {
        let q = self.re / o.re;
        Dual::new(q, (self.eps - q * o.eps) / o.re)
    }
}

impl Add<f64> for Dual {
    type Output = Dual;
    #[inline(always)]
    fn add(self, c: f64) -> Dual {
        Dual::new(self.re + c, self.eps)
    }
}

impl Sub<f64> for Dual {
    type Output = Dual;
    #[inline(always)]
    fn sub(self, c: f64) -> Dual {
        Dual::new(self.re - c, self.eps)
    }
}

impl Mul<f64> for Dual {
    type Output = Dual;
    #[inline(always)]
    fn mul(self, c: f64) -> Dual {
        Dual::new(self.re * c, self.eps * c)
    }
}

impl Div<f64> for Dual {
    type Output = Dual;
    #[inline(always)]
    fn div(self, c: f64) -> Dual {
        Dual::new(self.re / c, self.eps / c)
    }
}

macro_rules! assign_from_binary {
    ($($assign:ident $method:ident $op:tt),*) => {$(
        impl $assign for Dual {
            #[inline(always)]
            fn $method(&mut self, o: Dual) {
                *self = *self $op o;
            }
        }
    )*};
}

assign_from_binary!(AddAssign add_assign +, SubAssign sub_assign -, MulAssign mul_assign *, DivAssign div_assign /);

impl Number for Dual {
    type Mask = bool;
    #[inline(always)]
    fn constant(x: f64) -> Self {
        Dual::new(x, 0.0)
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        let s = self.re.sqrt();
        Dual::new(s, self.eps / (2.0 * s))
    }
    #[inline(always)]
    fn greater(self, other: Self) -> bool {
        self.re > other.re
    }
    #[inline(always)]
    fn select(mask: bool, yes: Self, no: Self) -> Self {
        if mask { yes } else { no }
    }
    #[inline(always)]
    fn powf(self, y: f64) -> Self {
        // d(x^y) = y x^(y - 1) dx = y x^y / x dx.
        let p = maths::pow(self.re, y);
        Dual::new(p, y * p / self.re * self.eps)
    }
}

impl Real for Dual {
    #[inline(always)]
    fn value(self) -> f64 {
        self.re
    }
    #[inline(always)]
    fn abs(self) -> Self {
        if self.re < 0.0 { -self } else { self }
    }
    #[inline(always)]
    fn asin(self) -> Self {
        // Infinite at |x| = 1 (pitch at the gimbal lock): 0 there, never NaN.
        let slope = if self.re.abs() < 1.0 { 1.0 / (1.0 - self.re * self.re).sqrt() } else { 0.0 };
        Dual::new(maths::asin(self.re), self.eps * slope)
    }
    #[inline(always)]
    fn acos(self) -> Self {
        // Infinite at |x| = 1: 0 there, never NaN.
        let slope = if self.re.abs() < 1.0 { -1.0 / (1.0 - self.re * self.re).sqrt() } else { 0.0 };
        Dual::new(maths::acos(self.re), self.eps * slope)
    }
    #[inline(always)]
    fn sin(self) -> Self {
        Dual::new(maths::sin(self.re), maths::cos(self.re) * self.eps)
    }
    #[inline(always)]
    fn atan2(self, x: Self) -> Self {
        let d = x.re * x.re + self.re * self.re;
        let eps = if d > 0.0 { (x.re * self.eps - self.re * x.eps) / d } else { 0.0 };
        Dual::new(maths::atan2(self.re, x.re), eps)
    }
    #[inline(always)]
    fn exp(self) -> Self {
        let e = maths::exp(self.re);
        Dual::new(e, e * self.eps)
    }
    #[inline(always)]
    fn ln(self) -> Self {
        Dual::new(maths::ln(self.re), self.eps / self.re)
    }
    #[inline(always)]
    fn tanh(self) -> Self {
        let t = maths::tanh(self.re);
        Dual::new(t, (1.0 - t * t) * self.eps)
    }
}

/// A vector of constants (stand geometry, parameters) in the number type `T`.
#[inline(always)]
pub fn lift<T: Real>(v: &Vector3<f64>) -> Vector3<T> {
    Vector3::new(T::constant(v.x), T::constant(v.y), T::constant(v.z))
}

/// The values of a vector of duals.
pub fn values(v: &Vector3<Dual>) -> Vector3<f64> {
    v.map(|d| d.re)
}

/// The derivative parts of a vector of duals.
pub fn tangents(v: &Vector3<Dual>) -> Vector3<f64> {
    v.map(|d| d.eps)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each elementary function's derivative against a central difference.
    #[test]
    fn dual_arithmetic_carries_the_chain_rule() {
        let x = 0.37;
        let h = 1e-6;
        type Case = (&'static str, fn(Dual) -> Dual, fn(f64) -> f64);
        let cases: [Case; 10] = [
            ("acos", |d| (d * 0.9).acos(), |v| (v * 0.9).acos()),
            ("sin", |d| (d * 3.0).sin(), |v| (v * 3.0).sin()),
            ("product and quotient", |d| d * d / (d + 2.0), |v| v * v / (v + 2.0)),
            ("sqrt", |d| (d * 3.0 + 1.0).sqrt(), |v| (v * 3.0 + 1.0).sqrt()),
            ("abs", |d| (d - 1.0).abs(), |v| (v - 1.0).abs()),
            ("asin", |d| (d * 0.5).asin(), |v| (v * 0.5).asin()),
            ("atan2", |d| (d - 0.2).atan2(-d * 2.0), |v| (v - 0.2).atan2(-v * 2.0)),
            ("exp", |d| (-d * d).exp(), |v| (-v * v).exp()),
            ("tanh", |d| (d * 4.0).tanh(), |v| (v * 4.0).tanh()),
            (
                "assign ops",
                |d| {
                    let mut a = d;
                    a *= d;
                    a -= d / 3.0;
                    a += Dual::constant(0.5);
                    a /= d + 1.0;
                    a
                },
                |v| (v * v - v / 3.0 + 0.5) / (v + 1.0),
            ),
        ];
        for (name, f, g) in cases {
            let exact = f(Dual::new(x, 1.0));
            let fd = (g(x + h) - g(x - h)) / (2.0 * h);
            assert_eq!(exact.re, g(x), "{name}: value");
            assert!((exact.eps - fd).abs() < 1e-8 * (1.0 + fd.abs()), "{name}: {} against {fd}", exact.eps);
        }
    }

    #[test]
    fn branches_compare_values() {
        let a = Dual::new(1.0, 100.0);
        let b = Dual::new(2.0, -100.0);
        assert!(a < b);
        assert_eq!(a.max_of(b), b);
        assert_eq!(Dual::new(5.0, 1.0).clamp_to(a, b), b);
        assert_eq!(Dual::new(0.0, 1.0).clamp_to(a, b), a);
        assert_eq!(Dual::new(1.5, 7.0).clamp_to(a, b), Dual::new(1.5, 7.0));
    }
}
