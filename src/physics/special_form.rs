//! The special form of the rigid-body equations (paper eqs. 1.4-1.6, docs/model.md §1):
//!
//! ```text
//! M r''  = sum_k F_k - M g ez
//! e1'' = -|e1'|² e1 - 2 I2/(I1+I2) (e1'.e2') e2 - 2 I3/(I3+I1) (e3'.e1') e3 + L3/(I1+I2) e2 - L2/(I3+I1) e3
//! e2'' = -|e2'|² e2 - 2 I3/(I2+I3) (e2'.e3') e3 - 2 I1/(I1+I2) (e1'.e2') e1 + L1/(I2+I3) e3 - L3/(I1+I2) e1
//! e3'' = -|e3'|² e3 - 2 I1/(I3+I1) (e3'.e1') e1 - 2 I2/(I2+I3) (e2'.e3') e2 + L2/(I3+I1) e1 - L1/(I2+I3) e2
//! ```
//!
//! with `L_a = L . e_a` the moment about the centre of mass projected on the body axes. Note
//! `I1 + I2 = J3`, `I2 + I3 = J1`, `I3 + I1 = J2`.
//!
//! The leg forces are the actuator forces `F_k` plus, for a leg outside its stroke, the end
//! stop's force ([`super::end_stops`]), both along the leg. With the forces given, nothing
//! here is singular at a singular leg arrangement: only a collapsed leg (no direction) is.

use nalgebra::Vector3;

use super::body_state::{BodyState, STATE_DIM, StateVector, axes_rates, layout};
use super::end_stops::EndStops;
use super::forces::LegForceLaw;
use super::legs::{JointArrays, LegGeometry, LegLanes};
use super::per_axis::{AxisLanes, AxisRows};
use super::per_leg::{Lanes, Narrow, PerLeg, Wide, components};
use super::stand::{LEG_COUNT, Stand};

/// The stand-dependent coefficients of the special form, computed once per parameter set so
/// that a right-hand-side evaluation does no divisions by inertias.
#[derive(Clone, Debug, PartialEq)]
pub struct SpecialForm {
    pub stand: Stand,
    /// The legs' end stops, or `None` for the paper's idealised legs of unlimited stroke.
    stops: Option<EndStops>,
    /// The strokes `[lmin, lmax]` (`[-inf, inf]` without stops), kept beside `stops` (written
    /// only by [`SpecialForm::set_end_stops`]) so that the right-hand side tests all six legs
    /// with one comparison and no branch on the option: 11 instructions per RK4 cycle for
    /// stops that are on and untouched, against 87 when the bounds are read from `stops`
    /// (callgrind, `benches/cycle_bench.py`).
    stroke: [[f64; LEG_COUNT]; 2],
    inverse_mass: f64,
    /// The coefficients per axis ([`AxisRows`]: axis `a` in lane `a`, indices mod 3; a fourth
    /// lane 0, so that each loads whole): `1/(I_a + I_(a+1))`, i.e. `1/(I1+I2) = 1/J3`,
    /// `1/(I2+I3) = 1/J1`, `1/(I3+I1) = 1/J2`...
    inverse_pair_axes: [f64; 4],
    /// ... `c_a = 2 I_(a+1)/(I_a + I_(a+1))`, the coupling of `e_a'.e_(a+1)'` into `e_a''`
    /// (`2 I2/(I1+I2)`, `2 I3/(I2+I3)`, `2 I1/(I3+I1)`) ...
    coupling_next: [f64; 4],
    /// ... and `-c'_a`, with `c'_a = 2 I_a/(I_a + I_(a+1))` its coupling into `e_(a+1)''`
    /// (`2 I1/(I1+I2)`, `2 I2/(I2+I3)`, `2 I3/(I3+I1)`); kept negative, as it enters.
    minus_coupling_previous: [f64; 4],
    /// Baumgarte stabilisation rate `alpha` (1/s): `e_a'' -= 1/2 sum_b K_ab e_b` with
    /// `K = 2 alpha dC/dt + alpha² C`, `C_ab = e_a.e_b - delta_ab`, so that the constraint
    /// residual obeys `C'' + 2 alpha C' + alpha² C = 0` near the manifold (critically damped
    /// decay). 0 = off (the default: the co-simulation projects instead).
    pub baumgarte_rate: f64,
    /// The joints as arrays over the legs, so that the six legs of a right-hand side are
    /// computed side by side in vector registers.
    pub joints: JointArrays,
}

impl SpecialForm {
    /// Precomputes the coefficients. The stand should have passed [`Stand::validate`];
    /// otherwise the coefficients may be infinite.
    pub fn new(stand: Stand) -> Self {
        let [i1, i2, i3] = stand.second_moments();
        SpecialForm {
            inverse_mass: 1.0 / stand.mass,
            inverse_pair_axes: [1.0 / (i1 + i2), 1.0 / (i2 + i3), 1.0 / (i3 + i1), 0.0],
            coupling_next: [2.0 * i2 / (i1 + i2), 2.0 * i3 / (i2 + i3), 2.0 * i1 / (i3 + i1), 0.0],
            minus_coupling_previous: [-2.0 * i1 / (i1 + i2), -2.0 * i2 / (i2 + i3), -2.0 * i3 / (i3 + i1), 0.0],
            baumgarte_rate: 0.0,
            stops: None,
            stroke: [[f64::NEG_INFINITY; LEG_COUNT], [f64::INFINITY; LEG_COUNT]],
            joints: JointArrays::new(&stand),
            stand,
        }
    }

    /// The same form with end stops (`None`: without).
    pub fn with_end_stops(mut self, stops: Option<EndStops>) -> Self {
        self.set_end_stops(stops);
        self
    }

    /// Replaces the end stops (`None`: without).
    pub fn set_end_stops(&mut self, stops: Option<EndStops>) {
        self.stroke = match &stops {
            Some(s) => [s.lower, s.upper],
            None => [[f64::NEG_INFINITY; LEG_COUNT], [f64::INFINITY; LEG_COUNT]],
        };
        self.stops = stops;
    }

    /// The legs' end stops, or `None` for the paper's idealised legs.
    pub fn stops(&self) -> Option<&EndStops> {
        self.stops.as_ref()
    }

    /// The same form with Baumgarte stabilisation at `rate` (1/s; 0 = off).
    pub fn with_baumgarte_rate(mut self, rate: f64) -> Self {
        self.baumgarte_rate = rate;
        self
    }

    /// Second derivatives `(r'', [e1'', e2'', e3''])` for the resultant leg force `force` and
    /// leg moment `moment` about the centre of mass (both inertial components), the axes and
    /// their rates given as rows.
    ///
    /// The module's formula grouped per axis (indices mod 3):
    /// `e_a'' = k_a e_a + n_a e_(a+1) + p_a e_(a-1)` with
    /// - `k_a = -|e_a'|²`,
    /// - `n_a = L_(a-1)/(I_a + I_(a+1)) - c_a (e_a'.e_(a+1)')`,
    /// - `p_a = -(c'_(a-1) (e_(a-1)'.e_a') + L_(a+1)/(I_(a-1) + I_a))`,
    ///
    /// where `c_a = 2 I_(a+1)/(I_a + I_(a+1))` and `c'_a = 2 I_a/(I_a + I_(a+1))`; each
    /// coefficient computed for the three axes side by side.
    #[inline(always)]
    fn accelerations<A: AxisLanes>(
        &self,
        state: &BodyState,
        e: &AxisRows<A>,
        e_dot: &AxisRows<A>,
        force: &Vector3<f64>,
        moment: &Vector3<f64>,
    ) -> (Vector3<f64>, [Vector3<f64>; 3]) {
        let mut a = force * self.inverse_mass;
        a.z -= self.stand.gravity;

        let l = e.dot_with(moment);
        let pairs = e_dot.dot(&e_dot.next());
        let inverse = A::load(&self.inverse_pair_axes);
        let own = A::splat(0.0).sub(e_dot.dot(e_dot));
        let next = l.previous().mul(inverse).sub(A::load(&self.coupling_next).mul(pairs));
        let previous =
            A::load(&self.minus_coupling_previous).mul(pairs).previous().sub(l.next().mul(inverse.previous()));
        let mut e_dd = e.combine(own, next, previous).vectors();
        if self.baumgarte_rate > 0.0 {
            let correction = self.baumgarte_correction(&state.to_vector());
            for (e_dd_a, c) in e_dd.iter_mut().zip(correction) {
                *e_dd_a -= c;
            }
        }
        (a, e_dd)
    }

    /// The Baumgarte terms `1/2 sum_b K_ab e_b` of the axis accelerations. Out of line and
    /// from the state vector, so that the right-hand side without them keeps its state in
    /// registers.
    #[inline(never)]
    fn baumgarte_correction(&self, y: &StateVector) -> [Vector3<f64>; 3] {
        let state = BodyState::from_vector(y);
        let k = self.baumgarte_matrix(&state);
        std::array::from_fn(|a| {
            let mut c = Vector3::zeros();
            for b in 0..3 {
                c += state.e[b] * (0.5 * k[a][b]);
            }
            c
        })
    }

    /// `K_ab = 2 alpha (e_a'.e_b + e_a.e_b') + alpha² (e_a.e_b - delta_ab)`.
    fn baumgarte_matrix(&self, state: &BodyState) -> [[f64; 3]; 3] {
        let alpha = self.baumgarte_rate;
        let mut k = [[0.0; 3]; 3];
        for a in 0..3 {
            for b in 0..3 {
                let c = state.e[a].dot(&state.e[b]) - if a == b { 1.0 } else { 0.0 };
                let c_dot = state.e_dot[a].dot(&state.e[b]) + state.e[a].dot(&state.e_dot[b]);
                k[a][b] = 2.0 * alpha * c_dot + alpha * alpha * c;
            }
        }
        k
    }

    /// Directional derivative (Jacobian-vector product) of the right-hand side for leg
    /// forces `u` held constant: the change of `dy/dt` and of the leg powers for a change `dy`
    /// of the state and `du` of the forces. Exact (the chain rule written out, term by term
    /// with [`SpecialForm::derivative`], end stops included), for
    /// `fmi2GetDirectionalDerivative` and linearisation.
    pub fn derivative_tangent(
        &self,
        y: &StateVector,
        u: &[f64; LEG_COUNT],
        dy: &StateVector,
        du: &[f64; LEG_COUNT],
    ) -> (StateVector, LegPower) {
        let s = BodyState::from_vector(y);
        let ds = BodyState::from_vector(dy);
        let stand = &self.stand;
        // Leg forces and their resultant, with tangents; actuator and stop parts apart.
        let (mut force, mut moment) = (Vector3::zeros(), Vector3::zeros());
        let (mut dforce, mut dmoment) = (Vector3::zeros(), Vector3::zeros());
        let (mut stop_force, mut stop_moment) = (Vector3::zeros(), Vector3::zeros());
        let (mut dstop_force, mut dstop_moment) = (Vector3::zeros(), Vector3::zeros());
        let mut d_dissipation = 0.0;
        for k in 0..LEG_COUNT {
            let p = &stand.platform_joints[k];
            let arm = s.body_vector(p);
            let darm = ds.body_vector(p);
            let q = s.r + arm - stand.base_joints[k];
            let dq = ds.r + darm;
            let l = q.norm();
            if l <= 0.0 {
                continue;
            }
            let n = q / l;
            let dn = (dq - n * n.dot(&dq)) / l;
            let f = n * u[k];
            let df = n * du[k] + dn * u[k];
            force += f;
            dforce += df;
            moment += arm.cross(&f);
            dmoment += darm.cross(&f) + arm.cross(&df);
            if let Some(stops) = &self.stops
                && stops.is_outside(k, l)
            {
                let rate = s.v + s.body_vector_rate(p);
                let drate = ds.v + ds.body_vector_rate(p);
                let ldot = n.dot(&rate);
                let (dl, dldot) = (n.dot(&dq), dn.dot(&rate) + n.dot(&drate));
                let c = stops.contact(k, l, ldot);
                let dc = stops.contact_tangent(k, l, ldot, dl, dldot);
                let fs = n * c.force;
                let dfs = dn * c.force + n * dc.force;
                stop_force += fs;
                dstop_force += dfs;
                stop_moment += arm.cross(&fs);
                dstop_moment += darm.cross(&fs) + arm.cross(&dfs);
                d_dissipation += dc.dissipation;
            }
        }
        let omega = s.angular_velocity_inertial();
        let domega = ds_angular_velocity_inertial(&s, &ds);
        let d_actuator = dforce.dot(&s.v) + force.dot(&ds.v) + dmoment.dot(&omega) + moment.dot(&domega);
        let moment = moment + stop_moment;
        let (dforce, dmoment) = (dforce + dstop_force, dmoment + dstop_moment);
        let da = dforce * self.inverse_mass;
        let [e1, e2, e3] = &s.e;
        let [d1, d2, d3] = &s.e_dot;
        let [de1, de2, de3] = &ds.e;
        let [dd1, dd2, dd3] = &ds.e_dot;
        let (l1, l2, l3) = (moment.dot(e1), moment.dot(e2), moment.dot(e3));
        let (dl1, dl2, dl3) =
            (dmoment.dot(e1) + moment.dot(de1), dmoment.dot(e2) + moment.dot(de2), dmoment.dot(e3) + moment.dot(de3));
        let [inv12, inv23, inv31, _] = self.inverse_pair_axes;
        let [c12_0, c23_0, c31_0, _] = self.coupling_next;
        let [c12_1, c23_1, c31_1, _] = self.minus_coupling_previous.map(|c| -c);
        let (p12, p23, p31) = (d1.dot(d2), d2.dot(d3), d3.dot(d1));
        let (dp12, dp23, dp31) = (dd1.dot(d2) + d1.dot(dd2), dd2.dot(d3) + d2.dot(dd3), dd3.dot(d1) + d3.dot(dd1));
        let (n1, n2, n3) = (d1.norm_squared(), d2.norm_squared(), d3.norm_squared());
        let (dn1, dn2, dn3) = (2.0 * d1.dot(dd1), 2.0 * d2.dot(dd2), 2.0 * d3.dot(dd3));
        // d(c x) = dc x + c dx for every term of the special form.
        let de1_dd = -(e1 * dn1 + de1 * n1) - (e2 * dp12 + de2 * p12) * c12_0 - (e3 * dp31 + de3 * p31) * c31_1
            + (e2 * dl3 + de2 * l3) * inv12
            - (e3 * dl2 + de3 * l2) * inv31;
        let de2_dd = -(e2 * dn2 + de2 * n2) - (e3 * dp23 + de3 * p23) * c23_0 - (e1 * dp12 + de1 * p12) * c12_1
            + (e3 * dl1 + de3 * l1) * inv23
            - (e1 * dl3 + de1 * l3) * inv12;
        let de3_dd = -(e3 * dn3 + de3 * n3) - (e1 * dp31 + de1 * p31) * c31_0 - (e2 * dp23 + de2 * p23) * c23_1
            + (e1 * dl2 + de1 * l2) * inv31
            - (e2 * dl1 + de2 * l1) * inv23;
        let mut de_dd = [de1_dd, de2_dd, de3_dd];
        if self.baumgarte_rate > 0.0 {
            let alpha = self.baumgarte_rate;
            let k = self.baumgarte_matrix(&s);
            for a in 0..3 {
                for b in 0..3 {
                    let dc = ds.e[a].dot(&s.e[b]) + s.e[a].dot(&ds.e[b]);
                    let dc_dot = ds.e_dot[a].dot(&s.e[b])
                        + s.e_dot[a].dot(&ds.e[b])
                        + ds.e[a].dot(&s.e_dot[b])
                        + s.e[a].dot(&ds.e_dot[b]);
                    let dk = 2.0 * alpha * dc_dot + alpha * alpha * dc;
                    de_dd[a] -= (s.e[b] * dk + ds.e[b] * k[a][b]) * 0.5;
                }
            }
        }
        let mut out = [0.0; STATE_DIM];
        out[layout::R..layout::R + 3].copy_from_slice(&dy[layout::V..layout::V + 3]);
        out[layout::V..layout::V + 3].copy_from_slice(da.as_slice());
        out[layout::E..layout::E + 9].copy_from_slice(&dy[layout::E_DOT..layout::E_DOT + 9]);
        for (i, v) in de_dd.iter().enumerate() {
            out[layout::E_DOT + 3 * i..layout::E_DOT + 3 * i + 3].copy_from_slice(v.as_slice());
        }
        (out, LegPower { actuator: d_actuator, dissipation: d_dissipation })
    }

    /// The legs' resultant for actuator forces `u`: `sum_k u_k n_k` and its moment
    /// `sum_k (R A_k) x (u_k n_k)`, the six legs side by side ([`PerLeg`]) and summed in
    /// [`PerLeg::sum`]'s order. A collapsed (or non-finite) leg carries nothing. The end
    /// stops' forces are computed (side by side too) only when a leg is outside its stroke.
    #[inline(always)]
    fn wrench_of<V: Lanes>(&self, state: &BodyState, u: &[f64; LEG_COUNT]) -> LegWrench {
        let LegLanes { arm, leg, length } = self.joints.legs::<V>(state);
        let scale = length.where_positive(PerLeg::new(u) / length);
        let f = components!(|c| leg[c] * scale);
        let moment = PerLeg::cross(&arm, &f);
        let touches = length.any_outside(PerLeg::new(&self.stroke[0]), PerLeg::new(&self.stroke[1]));
        let stop = match &self.stops {
            Some(stops) if touches => {
                // Contact is rare: keep the hot path's registers for the free motion.
                std::hint::cold_path();
                Self::stop_wrench(stops, &self.joints, state, &arm, &leg, length)
            }
            _ => StopWrench::default(),
        };
        LegWrench {
            force: Vector3::new(f[0].sum(), f[1].sum(), f[2].sum()),
            moment: Vector3::new(moment[0].sum(), moment[1].sum(), moment[2].sum()),
            stop,
        }
    }

    /// The end stops' forces ([`EndStops::contact`]) for the six legs side by side; 0 for a
    /// leg inside its stroke or collapsed.
    #[inline(always)]
    fn stop_wrench<V: Lanes>(
        stops: &EndStops,
        joints: &JointArrays,
        state: &BodyState,
        arm: &[PerLeg<V>; 3],
        leg: &[PerLeg<V>; 3],
        length: PerLeg<V>,
    ) -> StopWrench {
        let (n, ldot) = joints.directions_and_rates(state, leg, length, PerLeg::splat(1.0) / length);
        // Penetration delta and the sign s of the stop force: +1 at the lower stop, -1 at the
        // upper one; delta' = -s ldot.
        let below = PerLeg::new(&stops.lower) - length;
        let delta = below.select_positive(below, length - PerLeg::new(&stops.upper));
        let s = below.select_positive(PerLeg::splat(1.0), PerLeg::splat(-1.0));
        let delta_rate = below.select_positive(PerLeg::splat(-1.0), PerLeg::splat(1.0)) * ldot;
        let spring = PerLeg::splat(stops.stiffness) * delta;
        let damper = (PerLeg::splat(stops.damping) * delta_rate).clamp(PerLeg::splat(0.0) - spring, spring);
        let in_contact = length.where_positive(delta);
        let force = in_contact.where_positive(s * (spring + damper));
        let fs = components!(|c| n[c] * force);
        let moment = PerLeg::cross(arm, &fs);
        StopWrench {
            force: Vector3::new(fs[0].sum(), fs[1].sum(), fs[2].sum()),
            moment: Vector3::new(moment[0].sum(), moment[1].sum(), moment[2].sum()),
            dissipation: in_contact.where_positive(damper * delta_rate).sum(),
        }
    }

    /// The full first-order right-hand side `dy/dt` for leg forces given by `law` at time `t`,
    /// end stops included. Returns the power of the actuator forces and the power the stops'
    /// damping takes (the integrands of `work.F` and `work.dissipated`).
    #[inline(always)]
    pub fn derivative<L: LegForceLaw + ?Sized>(
        &self,
        t: f64,
        y: &StateVector,
        law: &L,
        dy: &mut StateVector,
    ) -> LegPower {
        self.derivative_in::<L, Narrow>(t, y, law, dy)
    }

    /// [`SpecialForm::derivative`] with the legs in AVX registers (`Wide`): the same bits.
    ///
    /// # Safety
    /// The processor must support AVX, and the caller should be compiled with it (the
    /// integrators' AVX2 copy), or the lanes' operations are not inlined.
    #[inline(always)]
    pub unsafe fn derivative_wide<L: LegForceLaw + ?Sized>(
        &self,
        t: f64,
        y: &StateVector,
        law: &L,
        dy: &mut StateVector,
    ) -> LegPower {
        self.derivative_in::<L, Wide>(t, y, law, dy)
    }

    #[inline(always)]
    fn derivative_in<L: LegForceLaw + ?Sized, V: Lanes>(
        &self,
        t: f64,
        y: &StateVector,
        law: &L,
        dy: &mut StateVector,
    ) -> LegPower {
        let state = BodyState::from_vector(y);
        let u = if law.depends_on_state() {
            law.leg_forces(t, &state, &LegGeometry::new(&self.stand, &state))
        } else {
            law.leg_forces_at(t)
        };
        let w = self.wrench_of::<V>(&state, &u);
        let (e, e_dot) = (AxisRows::<V::Axes>::of(&state.e), AxisRows::of(&state.e_dot));
        // `F.v + L.omega` with the inertial angular velocity `omega = 1/2 sum_a e_a x e_a'`.
        let power = LegPower {
            actuator: w.force.dot(&state.v) + 0.5 * e.cross_sum_dot(&e_dot, &w.moment),
            dissipation: w.stop.dissipation,
        };
        let (a, e_dd) = self.accelerations(&state, &e, &e_dot, &(w.force + w.stop.force), &(w.moment + w.stop.moment));
        // One array written whole, not piece by piece: the method reads the derivative back at
        // once in 256-bit loads, and a load that spans several smaller stores cannot be served
        // from the store buffer; it waits for them to reach the cache. Measured with the C
        // host's RK4 cycle (`cycle_host ... rk4 latency 1000000`, three interleaved runs):
        // p50 0.488 us with the piecewise copies, 0.458 with this (3,469 and 3,463
        // instructions).
        let [e1, e2, e3] = e_dd;
        let [d1, d2, d3, d4, d5, d6, d7, d8, d9] = *axes_rates(y);
        *dy = [
            state.v.x, state.v.y, state.v.z, a.x, a.y, a.z, d1, d2, d3, d4, d5, d6, d7, d8, d9, e1.x, e1.y, e1.z, e2.x,
            e2.y, e2.z, e3.x, e3.y, e3.z,
        ];
        power
    }
}

/// The powers of a right-hand-side evaluation (or their changes, from
/// [`SpecialForm::derivative_tangent`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LegPower {
    /// Power of the actuator forces, `sum_k F_k ldot_k = F.v + L.omega`, W.
    pub actuator: f64,
    /// Power taken by the end stops' damping, W (>= 0).
    pub dissipation: f64,
}

/// Resultant of the legs about the centre of mass: actuators and end stops apart.
#[derive(Clone, Copy, Debug, Default)]
struct LegWrench {
    force: Vector3<f64>,
    moment: Vector3<f64>,
    stop: StopWrench,
}

/// Resultant of the end stops' forces and the power their damping takes.
#[derive(Clone, Copy, Debug, Default)]
struct StopWrench {
    force: Vector3<f64>,
    moment: Vector3<f64>,
    dissipation: f64,
}

/// Change of the inertial angular velocity `omega = 1/2 sum_a e_a x e_a'` for a change `ds`
/// of the state.
fn ds_angular_velocity_inertial(s: &BodyState, ds: &BodyState) -> Vector3<f64> {
    let mut d = Vector3::zeros();
    for a in 0..3 {
        d += ds.e[a].cross(&s.e_dot[a]) + s.e[a].cross(&ds.e_dot[a]);
    }
    d * 0.5
}

#[cfg(test)]
mod tests {
    use nalgebra::Vector3;

    use super::*;
    use crate::physics::end_stops::EndStops;
    use crate::physics::forces::HeldForces;
    use crate::physics::kinematics::rotation_from_angles;

    /// The right-hand side written leg by leg from the paper's formulas, independently of
    /// [`SpecialForm::derivative`]'s side-by-side pass: the leg and stop forces summed one leg
    /// after another, then the special-form accelerations.
    fn leg_by_leg(
        form: &SpecialForm,
        stops: &EndStops,
        y: &StateVector,
        u: &[f64; LEG_COUNT],
    ) -> ([f64; 24], LegPower) {
        let stand = &form.stand;
        let state = BodyState::from_vector(y);
        let legs = LegGeometry::new(stand, &state);
        let (mut force, mut moment, mut total_force, mut total_moment) =
            (Vector3::zeros(), Vector3::zeros(), Vector3::zeros(), Vector3::zeros());
        let mut dissipation = 0.0;
        for k in 0..LEG_COUNT {
            let (n, arm, l) = (legs.direction[k], legs.arm[k], legs.length[k]);
            let ldot = n.dot(&(state.v + state.body_vector_rate(&stand.platform_joints[k])));
            let c = if stops.is_outside(k, l) { stops.contact(k, l, ldot) } else { Default::default() };
            force += n * u[k];
            moment += arm.cross(&(n * u[k]));
            total_force += n * (u[k] + c.force);
            total_moment += arm.cross(&(n * (u[k] + c.force)));
            dissipation += c.dissipation;
        }
        let (a, e_dd) = paper_accelerations(form, &state, &total_force, &total_moment);
        let mut dy = [0.0; 24];
        dy[layout::R..layout::R + 3].copy_from_slice(state.v.as_slice());
        dy[layout::V..layout::V + 3].copy_from_slice(a.as_slice());
        for i in 0..3 {
            dy[layout::E + 3 * i..layout::E + 3 * i + 3].copy_from_slice(state.e_dot[i].as_slice());
            dy[layout::E_DOT + 3 * i..layout::E_DOT + 3 * i + 3].copy_from_slice(e_dd[i].as_slice());
        }
        let actuator = force.dot(&state.v) + moment.dot(&state.angular_velocity_inertial());
        (dy, LegPower { actuator, dissipation })
    }

    /// The module's formula (paper 1.4-1.6) term by term with three-vectors, independently of
    /// `SpecialForm::accelerations`'s grouping per axis in lanes.
    fn paper_accelerations(
        form: &SpecialForm,
        state: &BodyState,
        force: &Vector3<f64>,
        moment: &Vector3<f64>,
    ) -> (Vector3<f64>, [Vector3<f64>; 3]) {
        let mut a = force / form.stand.mass;
        a.z -= form.stand.gravity;
        let [i1, i2, i3] = form.stand.second_moments();
        let [e1, e2, e3] = &state.e;
        let [d1, d2, d3] = &state.e_dot;
        let (l1, l2, l3) = (moment.dot(e1), moment.dot(e2), moment.dot(e3));
        let (p12, p23, p31) = (d1.dot(d2), d2.dot(d3), d3.dot(d1));
        let e1_dd = -e1 * d1.norm_squared() - e2 * (2.0 * i2 / (i1 + i2) * p12) - e3 * (2.0 * i3 / (i3 + i1) * p31)
            + e2 * (l3 / (i1 + i2))
            - e3 * (l2 / (i3 + i1));
        let e2_dd = -e2 * d2.norm_squared() - e3 * (2.0 * i3 / (i2 + i3) * p23) - e1 * (2.0 * i1 / (i1 + i2) * p12)
            + e3 * (l1 / (i2 + i3))
            - e1 * (l3 / (i1 + i2));
        let e3_dd = -e3 * d3.norm_squared() - e1 * (2.0 * i1 / (i3 + i1) * p31) - e2 * (2.0 * i2 / (i2 + i3) * p23)
            + e1 * (l2 / (i3 + i1))
            - e2 * (l1 / (i2 + i3));
        (a, [e1_dd, e2_dd, e3_dd])
    }

    /// The same held forces seen as a law that depends on the state (through `LegGeometry`).
    struct ThroughGeometry(HeldForces);

    impl LegForceLaw for ThroughGeometry {
        fn leg_forces(&self, t: f64, _state: &BodyState, _legs: &LegGeometry) -> [f64; LEG_COUNT] {
            self.0.leg_forces_at(t)
        }
    }

    /// The six legs side by side ([`PerLeg`]) against the leg-by-leg formulas: the same terms,
    /// summed in another order, so equal up to the rounding of the sums (a few units in the
    /// last place of the largest term; a leg lost or counted twice would differ by whole
    /// m/s²). Both force laws: held (the co-simulation's path) and one that depends on the
    /// state (the same forces through the leg geometry).
    #[test]
    fn the_pass_over_the_six_legs_side_by_side_equals_the_leg_by_leg_pass() {
        let stand = Stand::truck_cabin();
        let stops = EndStops::default();
        let form = SpecialForm::new(stand.clone()).with_end_stops(Some(stops));
        let law = HeldForces { value: [5900.0, -1200.0, 8000.0, 0.0, 3.5e4, 6100.0], slope: [10.0; 6], t0: 0.0 };
        // Inside the strokes, and deep enough into the lower and the upper stops.
        let mut contacts = 0;
        for (dz, roll, w) in [(0.0, 0.0, 0.0), (0.02, 0.05, 0.3), (-0.45, 0.1, -1.0), (0.45, -0.2, 2.0)] {
            let state = BodyState::from_pose(
                Stand::truck_cabin_neutral_position() + Vector3::new(0.01, -0.02, dz),
                Vector3::new(0.1, -0.3, 0.7),
                &rotation_from_angles(&Vector3::new(roll, -0.04, 0.02)),
                &Vector3::new(w, 0.2, -0.1),
            );
            let y = state.to_vector();
            let legs = LegGeometry::new(&stand, &state);
            contacts += (0..LEG_COUNT).filter(|&k| stops.is_outside(k, legs.length[k])).count();
            let (reference, p2) = leg_by_leg(&form, &stops, &y, &law.leg_forces_at(0.3));
            let scale = reference.iter().fold(1.0_f64, |m, x| m.max(x.abs()));
            for held in [true, false] {
                let mut fast = [0.0; 24];
                let p1 = if held {
                    form.derivative(0.3, &y, &law, &mut fast)
                } else {
                    form.derivative(0.3, &y, &ThroughGeometry(law), &mut fast)
                };
                let worst = fast.iter().zip(&reference).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
                println!("dz = {dz}, held {held}: largest |dy/dt| {scale:.3e}, largest difference {worst:.3e}");
                assert!(worst <= 1e-14 * scale, "dz = {dz}: {worst:e} against {scale:e}");
                let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * (1.0 + b.abs());
                assert!(close(p1.dissipation, p2.dissipation) && close(p1.actuator, p2.actuator), "{p1:?} {p2:?}");
            }
        }
        assert!(contacts >= 6, "the end-stop branch was exercised ({contacts} legs in contact)");
    }
}
