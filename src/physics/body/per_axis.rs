//! A value per body axis, the three axes side by side: [`AxisLanes`] and [`AxisRows`].
//!
//! The special form's axis accelerations (paper 1.5-1.6) are, per axis `a`, dot products
//! (`L.e_a`, `|e_a'|²`, `e_a'.e_(a+1)'`) and a combination of the three axes; so are the
//! actuator power's `L.omega` (cross products `e_a x e_a'`) and the projection onto the
//! constraints (`e_a.e_b`, `e_a.e_b'`, Newton-Schulz combinations). Held as rows
//! (lane `a` holds axis `a+1`'s value), the dot products are lanewise products and sums,
//! and the combination is lane rotations: no sums across a register (fewer instructions than
//! `nalgebra` three-vectors or plain arrays, which the compiler splits into scalars, shuffles
//! and spills). As for [`crate::physics::legs::per_leg`], the lanes are written out by hand:
//! `Pair` holds the three lanes (and a padding lane) in two SSE2 registers, for every x86-64;
//! `Quad` in one AVX register, for the steps' AVX2 path only. Every operation is
//! lanewise and exactly rounded, and [`AxisLanes::sum3`] adds in one fixed order, so both
//! give the same bits.

use nalgebra::Vector3;

#[cfg(target_arch = "x86_64")]
mod lanes {
    use core::arch::x86_64::{
        __m128d, __m256d, _mm_add_pd, _mm_cvtsd_f64, _mm_loadu_pd, _mm_mul_pd, _mm_set_pd, _mm_set1_pd, _mm_shuffle_pd,
        _mm_storeu_pd, _mm_sub_pd, _mm_unpackhi_pd, _mm256_add_pd, _mm256_loadu_pd, _mm256_mul_pd,
        _mm256_permute4x64_pd, _mm256_set_pd, _mm256_set1_pd, _mm256_storeu_pd, _mm256_sub_pd,
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
    /// AVX2 path (see `crate::physics::legs::per_leg::Wide`, which names this type as its
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
}

#[cfg(not(target_arch = "x86_64"))]
mod lanes {
    /// Four plain values, with the operations and the order of the sum of the x86-64 forms.
    #[derive(Clone, Copy)]
    pub struct Pair([f64; 4]);

    /// No wider registers here: the same four values.
    #[allow(dead_code)] // named only by the AVX2 path, which is x86-64 only
    pub type Quad = Pair;

    impl super::AxisLanes for Pair {
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

/// How three per-axis values (lane `a` for axis `a+1`, and a padding lane that takes part in
/// the arithmetic and is never read) are held and operated on: `Pair` (SSE2, every x86-64)
/// or `Quad` (AVX2). Both give the same bits.
pub trait AxisLanes: Copy {
    fn new(x: [f64; 3]) -> Self;
    /// Four lanes read as they are stored (for per-axis constants kept padded).
    fn load(x: &[f64; 4]) -> Self;
    fn splat(x: f64) -> Self;
    fn add(self, other: Self) -> Self;
    fn sub(self, other: Self) -> Self;
    fn mul(self, other: Self) -> Self;
    /// Lane `a` takes the value of axis `a+1` (mod 3): `[x2, x3, x1]` for axes 1, 2, 3.
    fn next(self) -> Self;
    /// Lane `a` takes the value of axis `a-1` (mod 3): `[x3, x1, x2]`.
    fn previous(self) -> Self;
    /// `(x1 + x2) + x3`.
    fn sum3(self) -> f64;
    /// The lanes, padding last.
    fn to_array(self) -> [f64; 4];
}

pub use lanes::Pair;
// Crate-private: its operations execute AVX2 instructions.
#[cfg_attr(not(all(target_arch = "x86_64", feature = "avx2")), allow(unused_imports))]
pub(crate) use lanes::Quad;

/// Three vectors given one per axis (`e1, e2, e3`, or their rates) as rows: `x` holds their
/// three x components, lane `a` for axis `a+1` (a 3x3 transpose).
#[derive(Clone, Copy)]
pub struct AxisRows<A: AxisLanes> {
    pub x: A,
    pub y: A,
    pub z: A,
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

    /// Lane `a`: `v_a . w_a`, summed `(x + y) + z` as `nalgebra`'s `dot`.
    #[inline(always)]
    pub fn dot(&self, w: &Self) -> A {
        self.x.mul(w.x).add(self.y.mul(w.y)).add(self.z.mul(w.z))
    }

    /// Lane `a`: `v_a . m` for one vector `m`.
    #[inline(always)]
    pub fn dot_with(&self, m: &Vector3<f64>) -> A {
        self.x.mul(A::splat(m.x)).add(self.y.mul(A::splat(m.y))).add(self.z.mul(A::splat(m.z)))
    }

    /// The rows of `v_(a+1)`: lane `a` holds the next axis's vector.
    #[inline(always)]
    pub fn next(&self) -> Self {
        AxisRows { x: self.x.next(), y: self.y.next(), z: self.z.next() }
    }

    /// `m . sum_a (v_a x w_a)`: the three cross products lanewise (as `nalgebra`'s), dotted
    /// with `m` lanewise, then one sum over the axes (one sum across the lanes, where summing
    /// the cross products first takes three).
    #[inline(always)]
    pub fn cross_sum_dot(&self, w: &Self, m: &Vector3<f64>) -> f64 {
        let x = self.y.mul(w.z).sub(self.z.mul(w.y));
        let y = self.z.mul(w.x).sub(self.x.mul(w.z));
        let z = self.x.mul(w.y).sub(self.y.mul(w.x));
        x.mul(A::splat(m.x)).add(y.mul(A::splat(m.y))).add(z.mul(A::splat(m.z))).sum3()
    }

    /// Rows of `u_a = own_a v_a + next_a v_(a+1) + previous_a v_(a-1)`: each axis's
    /// combination of the three vectors, with per-axis coefficients.
    #[inline(always)]
    pub fn combine(&self, own: A, next: A, previous: A) -> Self {
        AxisRows {
            x: self.x.mul(own).add(self.x.next().mul(next)).add(self.x.previous().mul(previous)),
            y: self.y.mul(own).add(self.y.next().mul(next)).add(self.y.previous().mul(previous)),
            z: self.z.mul(own).add(self.z.next().mul(next)).add(self.z.previous().mul(previous)),
        }
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
        let with = rv.dot_with(&m).to_array();
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
    #[cfg(target_arch = "x86_64")]
    fn quad_lanes_equal_pair_lanes() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            return;
        }
        let v = vectors();
        let w = [v[2], v[0] * 3.0, v[1] - v[2]];
        let (pv, pw) = (AxisRows::<Pair>::of(&v), AxisRows::<Pair>::of(&w));
        // AVX2 detected above: `Quad`'s operations may run.
        let (qv, qw) = (AxisRows::<Quad>::of(&v), AxisRows::<Quad>::of(&w));
        assert_eq!(pv.dot(&pw).to_array()[..3], qv.dot(&qw).to_array()[..3]);
        assert_eq!(pv.next().x.to_array()[..3], qv.next().x.to_array()[..3]);
        assert_eq!(pv.x.previous().to_array()[..3], qv.x.previous().to_array()[..3]);
        let m = Vector3::new(0.25, -1.5, 3.0);
        assert_eq!(pv.cross_sum_dot(&pw, &m), qv.cross_sum_dot(&qw, &m));
        let c = [0.5, -2.0, 1.25];
        let (p, q) = (
            pv.combine(Pair::new(c), Pair::splat(0.75), pw.x).vectors(),
            qv.combine(Quad::new(c), Quad::splat(0.75), qw.x).vectors(),
        );
        assert_eq!(p, q);
    }
}
