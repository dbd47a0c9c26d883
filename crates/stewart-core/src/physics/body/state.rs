//! The state in the special form's redundant coordinates: centre of mass `r`, its velocity
//! `v`, the body axis unit vectors `e1, e2, e3` and their time derivatives (24 numbers, twice
//! the six degrees of freedom).

use nalgebra::{Matrix3, Scalar, Vector3};

use crate::physics::number::Real;

/// Length of the special-form state vector.
pub const STATE_DIM: usize = 24;

/// The special-form state packed for the integrators, in the order
/// `r, v, e1, e2, e3, e1', e2', e3'` (three components each, inertial frame).
pub type StateVector = [f64; STATE_DIM];

/// Offsets of the blocks in a [`StateVector`].
pub mod layout {
    pub const R: usize = 0;
    pub const V: usize = 3;
    /// `e_a` starts at `E + 3 a` (a = 0, 1, 2).
    pub const E: usize = 6;
    /// `e_a'` starts at `E_DOT + 3 a`.
    pub const E_DOT: usize = 15;
}

/// Whether every value is finite. `x * 0` is `±0` for a finite `x` and NaN (all exponent bits
/// set) for an infinite or NaN one, so the bitwise OR of all the products is `±0` exactly when
/// every value is finite: an OR needs no order, so the compiler checks four values per vector
/// instruction, without a branch (a fold of `is_finite` does not vectorise).
///
/// From 4 to 8 values of a length known only at run time (a set of the six leg forces): two
/// overlapping fixed-size halves, which the compiler unrolls, instead of a loop and its
/// set-up.
#[inline(always)]
pub fn all_finite(values: &[f64]) -> bool {
    let bits = |v: &[f64]| v.iter().fold(0u64, |bits, x| bits | (x * 0.0).to_bits());
    let or = match (values.len(), values.first_chunk::<4>(), values.last_chunk::<4>()) {
        (4..=8, Some(head), Some(tail)) => bits(head) | bits(tail),
        _ => bits(values),
    };
    or & !(1u64 << 63) == 0
}

/// The components of `e1, e2, e3` in a state vector, one axis after another.
#[inline(always)]
pub fn axes(y: &StateVector) -> &[f64; 9] {
    let [_, _, _, _, _, _, e @ .., _, _, _, _, _, _, _, _, _] = y;
    e
}

/// The components of `e1', e2', e3'` in a state vector, one axis after another.
#[inline(always)]
pub fn axes_rates(y: &StateVector) -> &[f64; 9] {
    let [_, _, _, _, _, _, _, _, _, _, _, _, _, _, _, rates @ ..] = y;
    rates
}

// The patterns above, and the whole-array writes of the right-hand side and the projection,
// spell the layout out.
const _: () = assert!(layout::E == 6 && layout::E_DOT == 15 && STATE_DIM == 24);

/// The rigid body's state, unpacked, in the number type `T` (`f64`, or
/// [`crate::physics::number::Dual`] for derivatives).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BodyState<T: Scalar = f64> {
    /// Centre of mass `r`, m.
    pub r: Vector3<T>,
    /// Centre-of-mass velocity `dr/dt`, m/s.
    pub v: Vector3<T>,
    /// Body axis unit vectors `e1, e2, e3` (principal central axes), inertial components.
    pub e: [Vector3<T>; 3],
    /// Their time derivatives `de_a/dt = Ω × e_a`, 1/s.
    pub e_dot: [Vector3<T>; 3],
}

#[inline(always)]
fn read3<T: Real>(y: &[T; STATE_DIM], at: usize) -> Vector3<T> {
    Vector3::new(y[at], y[at + 1], y[at + 2])
}

#[inline(always)]
fn write3<T: Real>(y: &mut [T; STATE_DIM], at: usize, v: &Vector3<T>) {
    y[at] = v.x;
    y[at + 1] = v.y;
    y[at + 2] = v.z;
}

impl BodyState {
    /// A body at `r` with velocity `v`, orientation `rotation` (body -> inertial, columns are
    /// `e1, e2, e3`) and angular velocity `w_body` in body components.
    pub fn from_pose(r: Vector3<f64>, v: Vector3<f64>, rotation: &Matrix3<f64>, w_body: &Vector3<f64>) -> Self {
        let omega = rotation * w_body;
        let e = [rotation.column(0).into_owned(), rotation.column(1).into_owned(), rotation.column(2).into_owned()];
        let e_dot = [omega.cross(&e[0]), omega.cross(&e[1]), omega.cross(&e[2])];
        BodyState { r, v, e, e_dot }
    }

    /// Largest violation of the velocity constraints `d/dt (e_a . e_b) = 0`.
    pub fn velocity_constraint_residual(&self) -> f64 {
        let mut worst: f64 = 0.0;
        for a in 0..3 {
            for b in a..3 {
                worst = worst.max((self.e_dot[a].dot(&self.e[b]) + self.e[a].dot(&self.e_dot[b])).abs());
            }
        }
        worst
    }

    /// Every coordinate finite ([`all_finite`]).
    #[inline(always)]
    pub fn is_finite(&self) -> bool {
        all_finite(&self.to_vector())
    }
}

impl<T: Real> BodyState<T> {
    #[inline(always)]
    pub fn from_vector(y: &[T; STATE_DIM]) -> Self {
        BodyState {
            r: read3(y, layout::R),
            v: read3(y, layout::V),
            e: [read3(y, layout::E), read3(y, layout::E + 3), read3(y, layout::E + 6)],
            e_dot: [read3(y, layout::E_DOT), read3(y, layout::E_DOT + 3), read3(y, layout::E_DOT + 6)],
        }
    }

    #[inline(always)]
    pub fn to_vector(&self) -> [T; STATE_DIM] {
        let mut y = [T::zero(); STATE_DIM];
        write3(&mut y, layout::R, &self.r);
        write3(&mut y, layout::V, &self.v);
        for a in 0..3 {
            write3(&mut y, layout::E + 3 * a, &self.e[a]);
            write3(&mut y, layout::E_DOT + 3 * a, &self.e_dot[a]);
        }
        y
    }

    /// Rotation matrix body -> inertial, `R = [e1 e2 e3]` (columns).
    #[inline(always)]
    pub fn rotation(&self) -> Matrix3<T> {
        Matrix3::from_columns(&self.e)
    }

    /// Time derivative of the rotation matrix, `dR/dt = [e1' e2' e3']`.
    #[inline(always)]
    pub fn rotation_rate(&self) -> Matrix3<T> {
        Matrix3::from_columns(&self.e_dot)
    }

    /// Angular velocity in body components, `w1 = e2'.e3`, `w2 = e3'.e1`, `w3 = e1'.e2`.
    /// Each component is averaged with its antisymmetric partner (`w1 = -e3'.e2`, ...), which
    /// is exact on the constraint manifold and the best estimate off it.
    #[inline(always)]
    pub fn angular_velocity_body(&self) -> Vector3<T> {
        let [e1, e2, e3] = &self.e;
        let [d1, d2, d3] = &self.e_dot;
        Vector3::new((d2.dot(e3) - d3.dot(e2)) * 0.5, (d3.dot(e1) - d1.dot(e3)) * 0.5, (d1.dot(e2) - d2.dot(e1)) * 0.5)
    }

    /// Angular velocity in inertial components, `omega = 1/2 sum_a e_a x e_a'` (exact on the
    /// constraint manifold, where `e_a' = omega x e_a`).
    #[inline(always)]
    pub fn angular_velocity_inertial(&self) -> Vector3<T> {
        (self.e[0].cross(&self.e_dot[0]) + self.e[1].cross(&self.e_dot[1]) + self.e[2].cross(&self.e_dot[2]))
            * T::constant(0.5)
    }

    /// Position of a body-fixed point given in body coordinates, relative to the centre of
    /// mass, in inertial components: `R p = p1 e1 + p2 e2 + p3 e3`.
    #[inline(always)]
    pub fn body_vector(&self, p: &Vector3<f64>) -> Vector3<T> {
        self.e[0] * T::constant(p.x) + self.e[1] * T::constant(p.y) + self.e[2] * T::constant(p.z)
    }

    /// Velocity of that point relative to the centre of mass: `p1 e1' + p2 e2' + p3 e3'`.
    #[inline(always)]
    pub fn body_vector_rate(&self, p: &Vector3<f64>) -> Vector3<T> {
        self.e_dot[0] * T::constant(p.x) + self.e_dot[1] * T::constant(p.y) + self.e_dot[2] * T::constant(p.z)
    }

    /// Largest violation of the constraints `e_a . e_b = delta_ab` (paper eq. 1.2).
    pub fn constraint_residual(&self) -> T {
        let mut worst = T::zero();
        for a in 0..3 {
            for b in a..3 {
                let target = if a == b { 1.0 } else { 0.0 };
                worst = worst.max_of((self.e[a].dot(&self.e[b]) - target).abs());
            }
        }
        worst
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::body::kinematics::rotation_from_angles;

    #[test]
    fn all_finite_refuses_exactly_the_infinities_and_nans() {
        let finite = [0.0, -0.0, 1.5, -3e300, f64::MAX, f64::MIN, f64::MIN_POSITIVE, 5e-324, -5e-324];
        assert!(all_finite(&finite));
        assert!(all_finite(&[]));
        for bad in [f64::NAN, -f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            // Every length (the overlapping halves from 4 to 8), every place.
            for n in 1..=finite.len() {
                assert!(all_finite(&finite[..n]));
                for k in 0..n {
                    let mut v = finite[..n].to_vec();
                    v[k] = bad;
                    assert!(!all_finite(&v), "{bad} at {k} of {n}");
                }
            }
        }
    }

    #[test]
    fn pack_unpack_round_trip_and_angular_velocity() {
        let rot = rotation_from_angles(&Vector3::new(0.3, -0.2, 1.1));
        let w = Vector3::new(0.4, -1.5, 2.0);
        let s = BodyState::from_pose(Vector3::new(1.0, 2.0, 3.0), Vector3::new(-1.0, 0.5, 0.25), &rot, &w);
        assert_eq!(BodyState::from_vector(&s.to_vector()), s);
        assert!((s.angular_velocity_body() - w).norm() < 1e-15);
        assert!(s.constraint_residual() < 1e-15);
        assert!(s.velocity_constraint_residual() < 1e-15);
    }
}
