//! The special form of the rigid-body equations (paper eqs. 1.4-1.6, docs/model.md §1): the
//! accelerations of the centre of mass and of the body axes for a given force and moment.
//!
//! ```text
//! M r''  = F - M g ez
//! e1'' = -|e1'|² e1 - 2 I2/(I1+I2) (e1'.e2') e2 - 2 I3/(I3+I1) (e3'.e1') e3 + L3/(I1+I2) e2 - L2/(I3+I1) e3
//! e2'' = -|e2'|² e2 - 2 I3/(I2+I3) (e2'.e3') e3 - 2 I1/(I1+I2) (e1'.e2') e1 + L1/(I2+I3) e3 - L3/(I1+I2) e1
//! e3'' = -|e3'|² e3 - 2 I1/(I3+I1) (e3'.e1') e1 - 2 I2/(I2+I3) (e2'.e3') e2 + L2/(I3+I1) e1 - L1/(I2+I3) e2
//! ```
//!
//! with `L_a = L . e_a` the moment about the centre of mass projected on the body axes
//! (`I1 + I2 = J3`, `I2 + I3 = J1`, `I3 + I1 = J2`). Grouped per axis (indices mod 3):
//! `e_a'' = k_a e_a + n_a e_(a+1) + p_a e_(a-1)` with `k_a = -|e_a'|²`,
//! `n_a = L_(a-1)/(I_a + I_(a+1)) - c_a (e_a'.e_(a+1)')` and
//! `p_a = -(c'_(a-1) (e_(a-1)'.e_a') + L_(a+1)/(I_(a-1) + I_a))`, where
//! `c_a = 2 I_(a+1)/(I_a + I_(a+1))` and `c'_a = 2 I_a/(I_a + I_(a+1))`.
//!
//! [`RigidBody::axis_accelerations`] is the law, written once over [`AxisValues`]: the three
//! axes as a [`crate::physics::body::per_axis::Triple`] of any number type
//! ([`RigidBody::accelerations`], values and derivatives) or side by side in vector registers
//! (`RigidBody::accelerations_in`, the step's fast path); the same operations in the same
//! order, so the same bits (tested).

use nalgebra::Vector3;

use super::per_axis::{AxisLanes, AxisRows, AxisValues};
use super::state::BodyState;
use crate::physics::number::{Number, Real};
use crate::physics::stand::Stand;

/// The stand-dependent coefficients of the special form, computed once per parameter set so
/// that an evaluation does no divisions by inertias. Per axis `a` (lane `a`, a fourth lane 0
/// so that each loads whole into vector registers).
#[derive(Clone, Debug, PartialEq)]
pub struct RigidBody {
    pub inverse_mass: f64,
    /// `g`, m/s².
    pub gravity: f64,
    /// `1/(I_a + I_(a+1))`: `1/(I1+I2) = 1/J3`, `1/(I2+I3) = 1/J1`, `1/(I3+I1) = 1/J2`.
    inverse_pair: [f64; 4],
    /// `1/(I_(a-1) + I_a)`: [`RigidBody::inverse_pair`] of the previous axis, stored rather
    /// than rotated from it: `mul_constants` takes constants as stored. (An arrangement of
    /// this law that rotated the loaded register made LLVM emit a `vmovq` form, 66 0F D6
    /// register to register, that valgrind 3.19 cannot decode: the cycle bench died there.)
    inverse_pair_previous: [f64; 4],
    /// `c_a = 2 I_(a+1)/(I_a + I_(a+1))`, the coupling of `e_a'.e_(a+1)'` into `e_a''`.
    coupling_next: [f64; 4],
    /// `-c'_a`, `c'_a = 2 I_a/(I_a + I_(a+1))` its coupling into `e_(a+1)''`; kept negative,
    /// as it enters.
    minus_coupling_previous: [f64; 4],
    /// Baumgarte stabilisation rate `alpha` (1/s): `e_a'' -= 1/2 sum_b K_ab e_b` with
    /// `K = 2 alpha dC/dt + alpha² C`, `C_ab = e_a.e_b - delta_ab`, so that the constraint
    /// residual obeys `C'' + 2 alpha C' + alpha² C = 0` near the manifold (critically damped
    /// decay). 0 = off (Co-Simulation projects instead; Model Exchange uses it).
    pub baumgarte_rate: f64,
}

impl RigidBody {
    /// The coefficients of a stand (which should have passed [`Stand::validate`]; otherwise
    /// they may be infinite).
    pub fn new(stand: &Stand) -> Self {
        let [i1, i2, i3] = stand.second_moments();
        RigidBody {
            inverse_mass: 1.0 / stand.mass,
            gravity: stand.gravity,
            inverse_pair: [1.0 / (i1 + i2), 1.0 / (i2 + i3), 1.0 / (i3 + i1), 0.0],
            inverse_pair_previous: [1.0 / (i3 + i1), 1.0 / (i1 + i2), 1.0 / (i2 + i3), 0.0],
            coupling_next: [2.0 * i2 / (i1 + i2), 2.0 * i3 / (i2 + i3), 2.0 * i1 / (i3 + i1), 0.0],
            minus_coupling_previous: [-2.0 * i1 / (i1 + i2), -2.0 * i2 / (i2 + i3), -2.0 * i3 / (i3 + i1), 0.0],
            baumgarte_rate: 0.0,
        }
    }

    /// `(r'', [e1'', e2'', e3''])` for the force `force` and the moment `moment` about the
    /// centre of mass (inertial components): the module's formula, axis by axis.
    #[inline(always)]
    pub fn accelerations<T: Real>(
        &self,
        state: &BodyState<T>,
        force: &Vector3<T>,
        moment: &Vector3<T>,
    ) -> (Vector3<T>, [Vector3<T>; 3]) {
        let (e, e_dot) = (AxisRows::of_vectors(&state.e), AxisRows::of_vectors(&state.e_dot));
        let mut e_dd = self.axis_accelerations(&e, &e_dot, &[moment.x, moment.y, moment.z]).to_vectors();
        if self.baumgarte_rate > 0.0 {
            for (e_dd_a, c) in e_dd.iter_mut().zip(self.baumgarte_terms(state)) {
                *e_dd_a -= c;
            }
        }
        (self.translational(force), e_dd)
    }

    /// [`RigidBody::accelerations`] for `f64` with the axes and their rates given as rows in
    /// vector registers (lanes `A`): the same law, so the same bits.
    #[inline(always)]
    pub(crate) fn accelerations_in<A: AxisLanes>(
        &self,
        state: &BodyState,
        e: &AxisRows<A>,
        e_dot: &AxisRows<A>,
        force: &Vector3<f64>,
        moment: &Vector3<f64>,
    ) -> (Vector3<f64>, [Vector3<f64>; 3]) {
        let a = self.translational(force);
        let mut e_dd = self.axis_accelerations(e, e_dot, &[moment.x, moment.y, moment.z]).vectors();
        if self.baumgarte_rate > 0.0 {
            for (e_dd_a, c) in e_dd.iter_mut().zip(self.baumgarte_terms_out_of_line(state)) {
                *e_dd_a -= c;
            }
        }
        (a, e_dd)
    }

    /// `r'' = F / M - g ez`.
    #[inline(always)]
    fn translational<T: Real>(&self, force: &Vector3<T>) -> Vector3<T> {
        let mut a = force * T::constant(self.inverse_mass);
        a.z -= T::constant(self.gravity);
        a
    }

    /// The axes' accelerations without the Baumgarte terms, `e_a'' = k_a e_a + n_a e_(a+1) +
    /// p_a e_(a-1)` (the module's formula), for the axes `e` and their rates `e_dot` as rows
    /// and the moment `moment`: the one law for every number type and every register.
    #[inline(always)]
    pub fn axis_accelerations<X: AxisValues>(
        &self,
        e: &AxisRows<X>,
        e_dot: &AxisRows<X>,
        moment: &[X::Scalar; 3],
    ) -> AxisRows<X> {
        let l = e.dot_with(moment);
        let pairs = e_dot.dot(&e_dot.next());
        let own = X::splat(X::Scalar::constant(0.0)).sub(e_dot.dot(e_dot));
        let next = l.previous().mul_constants(&self.inverse_pair).sub(pairs.mul_constants(&self.coupling_next));
        let previous = pairs
            .mul_constants(&self.minus_coupling_previous)
            .previous()
            .sub(l.next().mul_constants(&self.inverse_pair_previous));
        e.combine(own, next, previous)
    }

    /// The Baumgarte terms for the fast path, out of line so that the right-hand side without
    /// them keeps its state in registers.
    #[inline(never)]
    fn baumgarte_terms_out_of_line(&self, state: &BodyState) -> [Vector3<f64>; 3] {
        self.baumgarte_terms(state)
    }

    /// `1/2 sum_b K_ab e_b`, with `K_ab = 2 alpha (e_a'.e_b + e_a.e_b') + alpha² (e_a.e_b -
    /// delta_ab)`.
    fn baumgarte_terms<T: Real>(&self, state: &BodyState<T>) -> [Vector3<T>; 3] {
        let alpha = self.baumgarte_rate;
        let (e, d) = (&state.e, &state.e_dot);
        std::array::from_fn(|a| {
            let mut c = Vector3::zeros();
            for b in 0..3 {
                let residual = e[a].dot(&e[b]) - if a == b { 1.0 } else { 0.0 };
                let rate = d[a].dot(&e[b]) + e[a].dot(&d[b]);
                let k = rate * (2.0 * alpha) + residual * (alpha * alpha);
                c += e[b] * (k * 0.5);
            }
            c
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::body::kinematics::rotation_from_angles;
    use crate::physics::body::per_axis::Pair;

    /// The paper's formula written term by term with three-vectors, independently of the
    /// grouping per axis.
    fn paper(stand: &Stand, state: &BodyState, force: &Vector3<f64>, moment: &Vector3<f64>) -> [Vector3<f64>; 3] {
        let [i1, i2, i3] = stand.second_moments();
        let [e1, e2, e3] = &state.e;
        let [d1, d2, d3] = &state.e_dot;
        let _ = force;
        let (l1, l2, l3) = (moment.dot(e1), moment.dot(e2), moment.dot(e3));
        let (p12, p23, p31) = (d1.dot(d2), d2.dot(d3), d3.dot(d1));
        [
            -e1 * d1.norm_squared() - e2 * (2.0 * i2 / (i1 + i2) * p12) - e3 * (2.0 * i3 / (i3 + i1) * p31)
                + e2 * (l3 / (i1 + i2))
                - e3 * (l2 / (i3 + i1)),
            -e2 * d2.norm_squared() - e3 * (2.0 * i3 / (i2 + i3) * p23) - e1 * (2.0 * i1 / (i1 + i2) * p12)
                + e3 * (l1 / (i2 + i3))
                - e1 * (l3 / (i1 + i2)),
            -e3 * d3.norm_squared() - e1 * (2.0 * i1 / (i3 + i1) * p31) - e2 * (2.0 * i2 / (i2 + i3) * p23)
                + e1 * (l2 / (i3 + i1))
                - e2 * (l1 / (i2 + i3)),
        ]
    }

    /// The grouping per axis is the paper's formula (to rounding), and the lanes give the
    /// generic form's bits, with and without Baumgarte terms.
    #[test]
    fn per_axis_grouping_is_the_paper_formula_and_the_lanes_are_its_bits() {
        let stand = Stand { inertia: [1200.0, 1500.0, 2200.0], ..Stand::truck_cabin() };
        let state = BodyState::from_pose(
            Vector3::new(0.1, -0.2, 1.9),
            Vector3::new(0.3, 0.1, -0.2),
            &rotation_from_angles(&Vector3::new(0.2, -0.3, 0.7)),
            &Vector3::new(0.9, -1.3, 2.1),
        );
        let (force, moment) = (Vector3::new(100.0, -50.0, 3e4), Vector3::new(-700.0, 1200.0, 300.0));
        for rate in [0.0, 10.0] {
            let body = RigidBody { baumgarte_rate: rate, ..RigidBody::new(&stand) };
            let (a, e_dd) = body.accelerations(&state, &force, &moment);
            let (e, d) = (AxisRows::<Pair>::of(&state.e), AxisRows::<Pair>::of(&state.e_dot));
            let (a_lanes, e_dd_lanes) = body.accelerations_in(&state, &e, &d, &force, &moment);
            assert_eq!((a, e_dd), (a_lanes, e_dd_lanes), "Baumgarte rate {rate}");
            if rate == 0.0 {
                for (x, y) in e_dd.iter().zip(paper(&stand, &state, &force, &moment)) {
                    assert!((x - y).norm() <= 1e-14 * (1.0 + y.norm()), "{x} against {y}");
                }
            }
        }
    }
}
