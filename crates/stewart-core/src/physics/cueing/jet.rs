//! A value with its first and second time derivatives: `Jet { v, d1, d2 }` is the truncated
//! Taylor series `v + d1 t + d2 t²/2`. Arithmetic on jets carries the chain rule to second
//! order, so a pose computed from jets of the washout's states comes with its exact velocity
//! and acceleration (the pose command's `v`, `a`, `angleRates`, `angleAccelerations`), never
//! a difference quotient.

use std::ops::{Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign};

use num_traits::{One, Zero};

use crate::maths;
use crate::physics::number::{Number, Real};

/// `v + d1 t + d2 t²/2`: a value, its first and its second derivative.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Jet {
    pub v: f64,
    pub d1: f64,
    pub d2: f64,
}

impl Jet {
    pub const fn new(v: f64, d1: f64, d2: f64) -> Self {
        Jet { v, d1, d2 }
    }

    /// `f(self)` from `f`, `f'` and `f''` at the value.
    #[inline(always)]
    fn compose(self, f: f64, df: f64, ddf: f64) -> Jet {
        Jet::new(f, df * self.d1, ddf * self.d1 * self.d1 + df * self.d2)
    }

    #[inline]
    pub fn cos(self) -> Jet {
        let (s, c) = maths::sin_cos(self.v);
        self.compose(c, -s, -c)
    }
}

/// Ordered by value only (what a branch needs).
impl PartialOrd for Jet {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        self.v.partial_cmp(&other.v)
    }
}

impl Zero for Jet {
    fn zero() -> Self {
        Jet::new(0.0, 0.0, 0.0)
    }
    fn is_zero(&self) -> bool {
        *self == Jet::zero()
    }
}

impl One for Jet {
    fn one() -> Self {
        Jet::new(1.0, 0.0, 0.0)
    }
}

impl Neg for Jet {
    type Output = Jet;
    fn neg(self) -> Jet {
        Jet::new(-self.v, -self.d1, -self.d2)
    }
}

impl Add for Jet {
    type Output = Jet;
    fn add(self, o: Jet) -> Jet {
        Jet::new(self.v + o.v, self.d1 + o.d1, self.d2 + o.d2)
    }
}

impl Sub for Jet {
    type Output = Jet;
    fn sub(self, o: Jet) -> Jet {
        Jet::new(self.v - o.v, self.d1 - o.d1, self.d2 - o.d2)
    }
}

impl Mul for Jet {
    type Output = Jet;
    fn mul(self, o: Jet) -> Jet {
        Jet::new(self.v * o.v, self.d1 * o.v + self.v * o.d1, self.d2 * o.v + 2.0 * self.d1 * o.d1 + self.v * o.d2)
    }
}

impl Div for Jet {
    type Output = Jet;
    fn div(self, o: Jet) -> Jet {
        let q = self.v / o.v;
        let q1 = (self.d1 - q * o.d1) / o.v;
        let q2 = (self.d2 - 2.0 * q1 * o.d1 - q * o.d2) / o.v;
        Jet::new(q, q1, q2)
    }
}

impl Add<f64> for Jet {
    type Output = Jet;
    fn add(self, c: f64) -> Jet {
        Jet::new(self.v + c, self.d1, self.d2)
    }
}

impl Sub<f64> for Jet {
    type Output = Jet;
    fn sub(self, c: f64) -> Jet {
        Jet::new(self.v - c, self.d1, self.d2)
    }
}

impl Mul<f64> for Jet {
    type Output = Jet;
    fn mul(self, c: f64) -> Jet {
        Jet::new(self.v * c, self.d1 * c, self.d2 * c)
    }
}

impl Div<f64> for Jet {
    type Output = Jet;
    fn div(self, c: f64) -> Jet {
        Jet::new(self.v / c, self.d1 / c, self.d2 / c)
    }
}

macro_rules! assign_from_binary {
    ($($assign:ident $method:ident $op:tt),*) => {$(
        impl $assign for Jet {
            fn $method(&mut self, o: Jet) {
                *self = *self $op o;
            }
        }
    )*};
}

assign_from_binary!(AddAssign add_assign +, SubAssign sub_assign -, MulAssign mul_assign *, DivAssign div_assign /);

impl Number for Jet {
    type Mask = bool;
    fn constant(x: f64) -> Self {
        Jet::new(x, 0.0, 0.0)
    }
    fn sqrt(self) -> Self {
        let s = self.v.sqrt();
        let s1 = self.d1 / (2.0 * s);
        Jet::new(s, s1, (self.d2 - 2.0 * s1 * s1) / (2.0 * s))
    }
    fn greater(self, other: Self) -> bool {
        self.v > other.v
    }
    fn select(mask: bool, yes: Self, no: Self) -> Self {
        if mask { yes } else { no }
    }
    fn powf(self, y: f64) -> Self {
        // f = x^y, f' = y x^(y-1), f'' = y (y - 1) x^(y-2).
        let p = maths::pow(self.v, y);
        let d = y * p / self.v;
        self.compose(p, d, (y - 1.0) * d / self.v)
    }
}

impl Real for Jet {
    fn value(self) -> f64 {
        self.v
    }
    fn abs(self) -> Self {
        if self.v < 0.0 { -self } else { self }
    }
    fn asin(self) -> Self {
        // The slopes are infinite at |x| = 1: 0 there, never NaN (callers keep |x| < 1).
        let q = 1.0 - self.v * self.v;
        let (df, ddf) = if q > 0.0 { (1.0 / q.sqrt(), self.v / (q * q.sqrt())) } else { (0.0, 0.0) };
        self.compose(maths::asin(self.v), df, ddf)
    }
    fn acos(self) -> Self {
        let a = self.asin();
        Jet::new(maths::acos(self.v), -a.d1, -a.d2)
    }
    #[inline]
    fn sin(self) -> Self {
        let (s, c) = maths::sin_cos(self.v);
        self.compose(s, c, -s)
    }
    fn atan2(self, x: Self) -> Self {
        let (y, d) = (self, x.v * x.v + self.v * self.v);
        if d == 0.0 {
            return Jet::new(maths::atan2(y.v, x.v), 0.0, 0.0);
        }
        let num = x.v * y.d1 - y.v * x.d1;
        let d1 = num / d;
        let num1 = x.v * y.d2 - y.v * x.d2;
        let den1 = 2.0 * (x.v * x.d1 + y.v * y.d1);
        Jet::new(maths::atan2(y.v, x.v), d1, (num1 - d1 * den1) / d)
    }
    fn exp(self) -> Self {
        let e = maths::exp(self.v);
        self.compose(e, e, e)
    }
    fn ln(self) -> Self {
        let inverse = 1.0 / self.v;
        self.compose(maths::ln(self.v), inverse, -inverse * inverse)
    }
    fn tanh(self) -> Self {
        let t = maths::tanh(self.v);
        let dt = 1.0 - t * t;
        self.compose(t, dt, -2.0 * t * dt)
    }
}

/// Trigonometry the cueing laws need on `f64` and on jets alike.
pub trait Trig: Real {
    fn cos(self) -> Self;
}

impl Trig for f64 {
    #[inline]
    fn cos(self) -> Self {
        maths::cos(self)
    }
}

impl Trig for Jet {
    #[inline]
    fn cos(self) -> Self {
        Jet::cos(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each operation's first and second derivatives against central differences of the
    /// value along `x(t) = x0 + x1 t + x2 t²/2`.
    #[test]
    fn jets_carry_two_derivatives() {
        let along = |x: Jet, t: f64| x.v + x.d1 * t + 0.5 * x.d2 * t * t;
        let x = Jet::new(0.3, -0.7, 1.9);
        let y = Jet::new(1.4, 0.5, -0.8);
        type F = fn(Jet, Jet) -> Jet;
        type G = fn(f64, f64) -> f64;
        let cases: [(&str, F, G); 9] = [
            ("mul", |a, b| a * b, |a, b| a * b),
            ("div", |a, b| a / b, |a, b| a / b),
            ("sqrt", |_, b| Number::sqrt(b), |_, b| b.sqrt()),
            ("sin", |a, _| Real::sin(a), |a, _| a.sin()),
            ("cos", |a, _| Jet::cos(a), |a, _| a.cos()),
            ("asin", |a, _| Real::asin(a), |a, _| a.asin()),
            ("atan2", |a, b| Real::atan2(a, b), |a, b| a.atan2(b)),
            ("tanh", |a, _| Real::tanh(a), |a, _| a.tanh()),
            ("exp", |a, _| Real::exp(a), |a, _| a.exp()),
        ];
        let h = 1e-4;
        for (name, f, g) in cases {
            let jet = f(x, y);
            let at = |t: f64| g(along(x, t), along(y, t));
            let d1 = (at(h) - at(-h)) / (2.0 * h);
            let d2 = (at(h) - 2.0 * at(0.0) + at(-h)) / (h * h);
            assert!((jet.v - at(0.0)).abs() < 1e-15, "{name} value");
            assert!((jet.d1 - d1).abs() < 1e-7 * (1.0 + d1.abs()), "{name}: d1 {} against {d1}", jet.d1);
            assert!((jet.d2 - d2).abs() < 1e-5 * (1.0 + d2.abs()), "{name}: d2 {} against {d2}", jet.d2);
        }
    }
}
