//! A value per body axis, the three axes side by side: [`AxisLanes`] and [`AxisRows`].
//!
//! The special form's axis accelerations (paper 1.5-1.6) are, per axis `a`, dot products
//! (`L.e_a`, `|e_a'|²`, `e_a'.e_(a+1)'`) and a combination of the three axes; so are the
//! actuator power's `L.omega` (cross products `e_a x e_a'`) and the projection onto the
//! constraints (`e_a.e_b`, `e_a.e_b'`, Newton-Schulz combinations). Held as rows
//! (lane `a` holds axis `a+1`'s value), the dot products are lanewise products and sums,
//! and the combination is lane rotations: no sums across a register (fewer instructions than
//! `nalgebra` three-vectors or plain arrays, which the compiler splits into scalars, shuffles
//! and spills). The lanes are `crate::simd`'s: `Pair` (two SSE2 registers, every x86-64),
//! `Quad` (one AVX register, the steps' AVX2 path only); every operation is lanewise and
//! exactly rounded, and [`AxisLanes::sum3`] adds in one fixed order, so both give the same bits.

use nalgebra::Vector3;

use crate::physics::number::{Number, Real};

pub use crate::simd::{AxisLanes, Pair};

/// Three per-axis values (lane `a` for axis `a+1`) as the special form's per-axis law needs
/// them: lanewise arithmetic and the rotations to the next and previous axis. Implemented by
/// the registers ([`AxisLanes`], `f64`) and by [`Triple`] (any [`Real`], duals included), so
/// the law is written once ([`crate::physics::body::accelerations::RigidBody::axis_accelerations`]).
pub trait AxisValues: Copy {
    /// The number of one lane.
    type Scalar: Number;
    fn splat(x: Self::Scalar) -> Self;
    fn add(self, other: Self) -> Self;
    fn sub(self, other: Self) -> Self;
    fn mul(self, other: Self) -> Self;
    /// Lane `a` times the constant `c[a]` (the fourth, padding, lane of `c` ignored).
    fn mul_constants(self, c: &[f64; 4]) -> Self;
    /// Lane `a` takes the value of axis `a+1` (mod 3).
    fn next(self) -> Self;
    /// Lane `a` takes the value of axis `a-1` (mod 3).
    fn previous(self) -> Self;
}

impl<A: AxisLanes> AxisValues for A {
    type Scalar = f64;
    #[inline(always)]
    fn splat(x: f64) -> Self {
        AxisLanes::splat(x)
    }
    #[inline(always)]
    fn add(self, other: Self) -> Self {
        AxisLanes::add(self, other)
    }
    #[inline(always)]
    fn sub(self, other: Self) -> Self {
        AxisLanes::sub(self, other)
    }
    #[inline(always)]
    fn mul(self, other: Self) -> Self {
        AxisLanes::mul(self, other)
    }
    #[inline(always)]
    fn mul_constants(self, c: &[f64; 4]) -> Self {
        AxisLanes::mul(self, A::load(c))
    }
    #[inline(always)]
    fn next(self) -> Self {
        AxisLanes::next(self)
    }
    #[inline(always)]
    fn previous(self) -> Self {
        AxisLanes::previous(self)
    }
}

/// Three per-axis values of one number type, one after the other.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triple<T>(pub [T; 3]);

impl<T: Real> AxisValues for Triple<T> {
    type Scalar = T;
    #[inline(always)]
    fn splat(x: T) -> Self {
        Triple([x; 3])
    }
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        Triple(std::array::from_fn(|a| self.0[a] + o.0[a]))
    }
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        Triple(std::array::from_fn(|a| self.0[a] - o.0[a]))
    }
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        Triple(std::array::from_fn(|a| self.0[a] * o.0[a]))
    }
    #[inline(always)]
    fn mul_constants(self, c: &[f64; 4]) -> Self {
        Triple(std::array::from_fn(|a| self.0[a] * c[a]))
    }
    #[inline(always)]
    fn next(self) -> Self {
        let [x1, x2, x3] = self.0;
        Triple([x2, x3, x1])
    }
    #[inline(always)]
    fn previous(self) -> Self {
        let [x1, x2, x3] = self.0;
        Triple([x3, x1, x2])
    }
}

/// Three vectors given one per axis (`e1, e2, e3`, or their rates) as rows: `x` holds their
/// three x components, lane `a` for axis `a+1` (a 3x3 transpose).
#[derive(Clone, Copy)]
pub struct AxisRows<A: AxisValues> {
    pub x: A,
    pub y: A,
    pub z: A,
}

impl<X: AxisValues> AxisRows<X> {
    /// Lane `a`: `v_a . w_a`, summed `(x + y) + z` as `nalgebra`'s `dot`.
    #[inline(always)]
    pub fn dot(&self, w: &Self) -> X {
        self.x.mul(w.x).add(self.y.mul(w.y)).add(self.z.mul(w.z))
    }

    /// Lane `a`: `v_a . m` for one vector `m`.
    #[inline(always)]
    pub fn dot_with(&self, m: &[X::Scalar; 3]) -> X {
        self.x.mul(X::splat(m[0])).add(self.y.mul(X::splat(m[1]))).add(self.z.mul(X::splat(m[2])))
    }

    /// The rows of `v_(a+1)`: lane `a` holds the next axis's vector.
    #[inline(always)]
    pub fn next(&self) -> Self {
        AxisRows { x: self.x.next(), y: self.y.next(), z: self.z.next() }
    }

    /// Rows of `u_a = own_a v_a + next_a v_(a+1) + previous_a v_(a-1)`: each axis's
    /// combination of the three vectors, with per-axis coefficients.
    #[inline(always)]
    pub fn combine(&self, own: X, next: X, previous: X) -> Self {
        AxisRows {
            x: self.x.mul(own).add(self.x.next().mul(next)).add(self.x.previous().mul(previous)),
            y: self.y.mul(own).add(self.y.next().mul(next)).add(self.y.previous().mul(previous)),
            z: self.z.mul(own).add(self.z.next().mul(next)).add(self.z.previous().mul(previous)),
        }
    }
}

impl<T: Real> AxisRows<Triple<T>> {
    #[inline(always)]
    pub fn of_vectors(v: &[Vector3<T>; 3]) -> Self {
        AxisRows {
            x: Triple([v[0].x, v[1].x, v[2].x]),
            y: Triple([v[0].y, v[1].y, v[2].y]),
            z: Triple([v[0].z, v[1].z, v[2].z]),
        }
    }

    /// The three vectors back: `[v1, v2, v3]`.
    #[inline(always)]
    pub fn to_vectors(&self) -> [Vector3<T>; 3] {
        let (x, y, z) = (self.x.0, self.y.0, self.z.0);
        std::array::from_fn(|a| Vector3::new(x[a], y[a], z[a]))
    }
}

impl<A: AxisLanes> AxisRows<A> {
    #[inline(always)]
    pub fn of(v: &[Vector3<f64>; 3]) -> Self {
        AxisRows {
            x: A::new([v[0].x, v[1].x, v[2].x]),
            y: A::new([v[0].y, v[1].y, v[2].y]),
            z: A::new([v[0].z, v[1].z, v[2].z]),
        }
    }

    /// From three vectors stored one after another (`[v1x, v1y, v1z, v2x, ...]`, as the
    /// state vector holds `e1, e2, e3` and their rates).
    #[inline(always)]
    pub fn from_components(v: &[f64; 9]) -> Self {
        AxisRows { x: A::new([v[0], v[3], v[6]]), y: A::new([v[1], v[4], v[7]]), z: A::new([v[2], v[5], v[8]]) }
    }

    /// The three vectors stored one after another, as [`AxisRows::from_components`] reads them.
    #[inline(always)]
    pub fn components(&self) -> [f64; 9] {
        let (x, y, z) = (self.x.to_array(), self.y.to_array(), self.z.to_array());
        [x[0], y[0], z[0], x[1], y[1], z[1], x[2], y[2], z[2]]
    }

    /// The three vectors back: `[v1, v2, v3]`.
    #[inline(always)]
    pub fn vectors(&self) -> [Vector3<f64>; 3] {
        let (x, y, z) = (self.x.to_array(), self.y.to_array(), self.z.to_array());
        [Vector3::new(x[0], y[0], z[0]), Vector3::new(x[1], y[1], z[1]), Vector3::new(x[2], y[2], z[2])]
    }

    /// `m . sum_a (v_a x w_a)`: the three cross products lanewise (as `nalgebra`'s), dotted
    /// with `m` lanewise, then one sum over the axes (one sum across the lanes, where summing
    /// the cross products first takes three).
    #[inline(always)]
    pub fn cross_sum_dot(&self, w: &Self, m: &Vector3<f64>) -> f64 {
        // The lanes' own operations (`AxisValues` names the same ones).
        let (mul, add, sub, splat) =
            (<A as AxisLanes>::mul, <A as AxisLanes>::add, <A as AxisLanes>::sub, <A as AxisLanes>::splat);
        let (u, v) = (self, w);
        let x = sub(mul(u.y, v.z), mul(u.z, v.y));
        let y = sub(mul(u.z, v.x), mul(u.x, v.z));
        let z = sub(mul(u.x, v.y), mul(u.y, v.x));
        add(add(mul(x, splat(m.x)), mul(y, splat(m.y))), mul(z, splat(m.z))).sum3()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vectors() -> [Vector3<f64>; 3] {
        [Vector3::new(0.3, -1.25, 2.0), Vector3::new(-0.7, 0.11, 0.5), Vector3::new(1.5, 0.25, -0.375)]
    }

    fn close(a: &Vector3<f64>, b: &Vector3<f64>) -> bool {
        (a - b).norm() <= 1e-15 * (1.0 + b.norm())
    }

    #[test]
    fn rows_give_the_dot_and_cross_products_and_combinations_of_the_vectors() {
        let v = vectors();
        let w = [v[1] * 2.0, v[2] - v[0], v[0] * -0.5 + v[1]];
        let (rv, rw) = (AxisRows::<Pair>::of(&v), AxisRows::<Pair>::of(&w));
        assert_eq!(rv.vectors(), v);
        let dots = rv.dot(&rw).to_array();
        let next = rv.dot(&rv.next()).to_array();
        let m = Vector3::new(0.9, -0.2, 0.4);
        let with = rv.dot_with(&[m.x, m.y, m.z]).to_array();
        for a in 0..3 {
            assert_eq!(dots[a], v[a].dot(&w[a]));
            assert_eq!(next[a], v[a].dot(&v[(a + 1) % 3]));
            assert_eq!(with[a], v[a].dot(&m));
        }
        let cross = v[0].cross(&w[0]) + v[1].cross(&w[1]) + v[2].cross(&w[2]);
        let m = Vector3::new(-0.3, 1.7, 0.6);
        assert!((rv.cross_sum_dot(&rw, &m) - m.dot(&cross)).abs() <= 1e-15 * m.norm() * cross.norm());
        let (own, nx, pv) = ([2.0, -1.0, 0.5], [0.25, 3.0, -2.0], [-0.125, 1.5, 4.0]);
        let combined = rv.combine(Pair::new(own), Pair::new(nx), Pair::new(pv)).vectors();
        for a in 0..3 {
            let expected = v[a] * own[a] + v[(a + 1) % 3] * nx[a] + v[(a + 2) % 3] * pv[a];
            assert!(close(&combined[a], &expected), "{a}: {} against {expected}", combined[a]);
        }
    }

    /// The AVX2 lanes give the bits of the SSE2 ones, where the processor has AVX2.
    #[test]
    fn quad_lanes_equal_pair_lanes() {
        use crate::simd::Quad;
        if !crate::simd::wide_testable() {
            return;
        }
        let v = vectors();
        let w = [v[2], v[0] * 3.0, v[1] - v[2]];
        let (pv, pw) = (AxisRows::<Pair>::of(&v), AxisRows::<Pair>::of(&w));
        // AVX2 checked above: `Quad`'s operations may run.
        let (qv, qw) = (AxisRows::<Quad>::of(&v), AxisRows::<Quad>::of(&w));
        assert_eq!(pv.dot(&pw).to_array()[..3], qv.dot(&qw).to_array()[..3]);
        assert_eq!(pv.next().x.to_array()[..3], qv.next().x.to_array()[..3]);
        assert_eq!(AxisLanes::previous(pv.x).to_array()[..3], AxisLanes::previous(qv.x).to_array()[..3]);
        let m = Vector3::new(0.25, -1.5, 3.0);
        assert_eq!(pv.cross_sum_dot(&pw, &m), qv.cross_sum_dot(&qw, &m));
        let c = [0.5, -2.0, 1.25];
        let (p, q) = (
            pv.combine(Pair::new(c), <Pair as AxisLanes>::splat(0.75), pw.x).vectors(),
            qv.combine(Quad::new(c), <Quad as AxisLanes>::splat(0.75), qw.x).vectors(),
        );
        assert_eq!(p, q);
    }
}
