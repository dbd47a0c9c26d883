//! The step's fast path: [`SpecialForm::rate`]'s numbers with the six legs side by side in
//! vector registers, for massless, frictionless legs (pinned to the definition by a test).

use super::machine::{Loads, solve_spd6};
use super::*;

/// The fast path's joint check counts a joint within this of its limit's cosine as touching.
const JOINT_CHECK_MARGIN: f64 = 1e-9;

impl SpecialForm {
    /// The right-hand side `dy/dt` for leg forces given by `law` at time `t`, and the leg
    /// powers: [`SpecialForm::rate`]'s numbers, computed in vector registers where the legs are
    /// massless and frictionless (the step's fast path), by the definition otherwise.
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

    /// [`SpecialForm::derivative`] in lanes `V` (see [`Lanes`]): the same bits in each.
    #[inline(always)]
    pub(crate) fn derivative_in<L: LegForceLaw + ?Sized, V: Lanes>(
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
        if !self.fast {
            let (rate, power) = self.rate(y, &u);
            *dy = rate;
            return power;
        }
        let w = self.wrench_in::<V>(&state, &u);
        let (e, e_dot) = (AxisRows::<V::Axes>::of(&state.e), AxisRows::of(&state.e_dot));
        let power = LegPower {
            actuator: w.force.dot(&state.v) + e.cross_sum_dot(&e_dot, &w.moment) * 0.5,
            dissipation: w.dissipation(),
        };
        let (a, e_dd) = self.body.accelerations_in(&state, &e, &e_dot, &w.total_force(), &w.total_moment());
        // One array written whole, not piece by piece: the method reads it back at once in
        // wide loads, which a load spanning several smaller stores would stall.
        let [e1, e2, e3] = e_dd;
        let [d1, d2, d3, d4, d5, d6, d7, d8, d9] = *axes_rates(y);
        *dy = [
            state.v.x, state.v.y, state.v.z, a.x, a.y, a.z, d1, d2, d3, d4, d5, d6, d7, d8, d9, e1.x, e1.y, e1.z, e2.x,
            e2.y, e2.z, e3.x, e3.y, e3.z,
        ];
        power
    }

    /// The legs' wrench with the six legs side by side. The end stops' and the joint limits'
    /// loads are computed only when a leg may touch them, by the one law leg by leg.
    #[inline(always)]
    fn wrench_in<V: Lanes>(&self, state: &BodyState, u: &[f64; LEG_COUNT]) -> LegWrench {
        let LegLanes { arm, leg, length } = self.joints.legs::<V>(state);
        let scale = length.where_positive(PerLeg::new(u) / length);
        let f = components!(|c| leg[c] * scale);
        let moment = PerLeg::cross(&arm, &f);
        let touches = length.any_outside(PerLeg::new(&self.stroke[0]), PerLeg::new(&self.stroke[1]));
        let stop = match &self.stops {
            Some(stops) if touches => {
                // Contact is rare: keep the hot path's registers for the free motion.
                std::hint::cold_path();
                self.stop_wrench_in(stops, state, &arm, &leg, length)
            }
            _ => StopWrench::default(),
        };
        let machine = match &self.joint_limits {
            Some(_) if self.joints_may_touch(state, &leg, length) => {
                std::hint::cold_path();
                self.machine_wrench(state)
            }
            _ => None,
        };
        LegWrench {
            force: Vector3::new(f[0].sum(), f[1].sum(), f[2].sum()),
            moment: Vector3::new(moment[0].sum(), moment[1].sum(), moment[2].sum()),
            stop,
            machine,
        }
    }

    /// [`SpecialForm::rate_driven`]'s numbers for drives on otherwise massless, frictionless
    /// legs (see [`SpecialForm::has_driven_fast_path`]), the six legs side by side: the leg's
    /// axial force `f_k = s_k - m_a l_k''` with `s_k` the drive's and the end stop's force and
    /// `l_k'' = S_k . (r'', omega') + c_k` (`S_k = (n_k, rho_k x n_k)`, `c_k = l_k |n_k'|^2 +
    /// n_k . (omega x (omega x rho_k))`), so that the platform's accelerations solve
    /// `[diag(M, J_w) + m_a sum S_k S_k^T] (r'', omega') = sum (s_k - m_a c_k) S_k + gravity,
    /// gyroscopic and joint-limit terms`; the definition's arithmetic in another order (equal to
    /// round-off, tested). Returns the currents' rates and the powers.
    #[inline(always)]
    pub(crate) fn derivative_driven_in<V: Lanes>(
        &self,
        y: &StateVector,
        currents: &[f64; LEG_COUNT],
        voltages: &[f64; LEG_COUNT],
        dy: &mut StateVector,
    ) -> DrivenRates {
        let Some(drives) = &self.drives else {
            let (rate, power, d) = self.rate_driven(y, currents, voltages);
            *dy = rate;
            return DrivenRates {
                current_rate: d.map(|k| k.current_rate),
                electric_power: sum_over_legs(&d.map(|k| k.electric_power)),
                dissipation: power.dissipation + sum_over_legs(&d.map(|k| k.dissipation)),
            };
        };
        let state = BodyState::from_vector(y);
        let LegLanes { arm, leg, length } = self.joints.legs::<V>(&state);
        let inverse_length = PerLeg::splat(1.0) / length;
        // The joints' directions, length rates, velocities, and the centripetal part of their
        // accelerations.
        let (n, l_dot, velocity) = self.joints.directions_rates_and_velocities(&state, &leg, length, inverse_length);
        let omega = state.angular_velocity_inertial();
        let w = components!(|c| PerLeg::<V>::splat(omega[c]));
        let whirl = PerLeg::cross(&w, &PerLeg::cross(&w, &arm));
        let speed2 = velocity[0] * velocity[0] + velocity[1] * velocity[1] + velocity[2] * velocity[2];
        let c = length.where_positive((speed2 - l_dot * l_dot) * inverse_length)
            + (n[0] * whirl[0] + n[1] * whirl[1] + n[2] * whirl[2]);
        // The drives: the one drive law, six legs at once.
        let drive = drives.rate(PerLeg::<V>::new(voltages), PerLeg::new(currents), l_dot);
        let (drive_force, current_rate) = (drive.force, drive.current_rate);
        let (electric, lost) = (drive.electric_power, drive.dissipation);
        // The end stops (rare: cold) and the joint limits (only where one may touch).
        let m_a = self.legs.axial_mass;
        // The legs' axial forces without their inertia, `b = s - m_a c`.
        let free = drive_force - c * PerLeg::splat(m_a);
        let (free, stop_dissipation) = match &self.stops {
            Some(stops) if length.any_outside(PerLeg::new(&self.stroke[0]), PerLeg::new(&self.stroke[1])) => {
                std::hint::cold_path();
                let (stop, dissipation) = self.stop_forces(stops, &length.to_array(), &l_dot.to_array());
                (drive_force + PerLeg::new(&stop) - c * PerLeg::splat(m_a), dissipation)
            }
            _ => (free, 0.0),
        };
        let machine = match &self.joint_limits {
            Some(_) if self.joints_may_touch(&state, &leg, length) => {
                std::hint::cold_path();
                self.machine_wrench(&state)
            }
            _ => None,
        };
        let b = length.where_positive(free);
        let rn = PerLeg::cross(&arm, &n);
        let s = [n[0], n[1], n[2], rn[0], rn[1], rn[2]];
        // The system's lower triangle (`sum S_k S_k^T`, row by row) and `sum b_k S_k`, four
        // sums at a time.
        let [g00, g10, g11, g20] = PerLeg::sum4_times([s[0] * s[0], s[1] * s[0], s[1] * s[1], s[2] * s[0]], m_a);
        let [g21, g22, g30, g31] = PerLeg::sum4_times([s[2] * s[1], s[2] * s[2], s[3] * s[0], s[3] * s[1]], m_a);
        let [g32, g33, g40, g41] = PerLeg::sum4_times([s[3] * s[2], s[3] * s[3], s[4] * s[0], s[4] * s[1]], m_a);
        let [g42, g43, g44, g50] = PerLeg::sum4_times([s[4] * s[2], s[4] * s[3], s[4] * s[4], s[5] * s[0]], m_a);
        let [g51, g52, g53, g54] = PerLeg::sum4_times([s[5] * s[1], s[5] * s[2], s[5] * s[3], s[5] * s[4]], m_a);
        let sum4 = PerLeg::<V>::sum4;
        let [g55, bs0, bs1, bs2] = sum4([s[5] * s[5], b * s[0], b * s[1], b * s[2]]);
        let g55 = g55 * m_a;
        let [bs3, bs4, bs5, _] = sum4([b * s[3], b * s[4], b * s[5], PerLeg::splat(0.0)]);
        let (mass, j, e) = (self.stand.mass, &self.stand.inertia, &state.e);
        // `J_w = sum_a J_a e_a e_a^T`, from `J_a e_a`.
        let je = [e[0] * j[0], e[1] * j[1], e[2] * j[2]];
        let j_w = |r: usize, col: usize| je[0][r] * e[0][col] + je[1][r] * e[1][col] + je[2][r] * e[2][col];
        let matrix = [
            [g00 + mass, 0.0, 0.0, 0.0, 0.0, 0.0],
            [g10, g11 + mass, 0.0, 0.0, 0.0, 0.0],
            [g20, g21, g22 + mass, 0.0, 0.0, 0.0],
            [g30, g31, g32, g33 + j_w(0, 0), 0.0, 0.0],
            [g40, g41, g42, g43 + j_w(1, 0), g44 + j_w(1, 1), 0.0],
            [g50, g51, g52, g53 + j_w(2, 0), g54 + j_w(2, 1), g55 + j_w(2, 2)],
        ];
        let j_omega = je[0] * e[0].dot(&omega) + je[1] * e[1].dot(&omega) + je[2] * e[2].dot(&omega);
        let mut force = Vector3::new(bs0, bs1, bs2 - mass * self.stand.gravity);
        let mut moment = Vector3::new(bs3, bs4, bs5) - omega.cross(&j_omega);
        if let Some(m) = &machine {
            force += m.force;
            moment += m.moment;
        }
        let q = solve_spd6(matrix, [force.x, force.y, force.z, moment.x, moment.y, moment.z]);
        let along = s[0] * PerLeg::splat(q[0])
            + s[1] * PerLeg::splat(q[1])
            + s[2] * PerLeg::splat(q[2])
            + s[3] * PerLeg::splat(q[3])
            + s[4] * PerLeg::splat(q[4])
            + s[5] * PerLeg::splat(q[5]);
        let f = b - along * PerLeg::splat(m_a);
        let [f0, f1, f2, f3] = sum4([f * s[0], f * s[1], f * s[2], f * s[3]]);
        let [f4, f5, electric_power, lost_power] = sum4([f * s[4], f * s[5], electric, lost]);
        // The legs' wrench and the machine's (the end stops act through `b`).
        let (mut force, mut moment, mut dissipation) =
            (Vector3::new(f0, f1, f2), Vector3::new(f3, f4, f5), stop_dissipation);
        if let Some(m) = &machine {
            force += m.force;
            moment += m.moment;
            dissipation += m.dissipation;
        }
        let (e_rows, e_dot) = (AxisRows::<V::Axes>::of(&state.e), AxisRows::of(&state.e_dot));
        let (acceleration, e_dd) = self.body.accelerations_in(&state, &e_rows, &e_dot, &force, &moment);
        let [e1, e2, e3] = e_dd;
        let [r1, r2, r3, r4, r5, r6, r7, r8, r9] = *axes_rates(y);
        *dy = [
            state.v.x,
            state.v.y,
            state.v.z,
            acceleration.x,
            acceleration.y,
            acceleration.z,
            r1,
            r2,
            r3,
            r4,
            r5,
            r6,
            r7,
            r8,
            r9,
            e1.x,
            e1.y,
            e1.z,
            e2.x,
            e2.y,
            e2.z,
            e3.x,
            e3.y,
            e3.z,
        ];
        DrivenRates { current_rate: current_rate.to_array(), electric_power, dissipation: dissipation + lost_power }
    }

    /// The end stops' forces along the legs ([`EndStops::contact`], leg by leg: 0 inside the
    /// stroke, and for a collapsed leg) and their damping's power, leg by leg on plain arrays;
    /// the callers, already in a cold branch, keep the lanes.
    #[inline(always)]
    fn stop_forces(&self, stops: &EndStops, l: &[f64; LEG_COUNT], l_dot: &[f64; LEG_COUNT]) -> ([f64; LEG_COUNT], f64) {
        let (mut force, mut dissipation) = ([0.0; LEG_COUNT], [0.0; LEG_COUNT]);
        for k in 0..LEG_COUNT {
            if l[k] > 0.0 && stops.is_outside(k, l[k]) {
                let contact = stops.contact(k, l[k], l_dot[k]);
                force[k] = contact.force;
                dissipation[k] = contact.dissipation;
            }
        }
        (force, sum_over_legs(&dissipation))
    }

    /// The end stops' forces ([`EndStops::contact`], leg by leg) on the legs given side by side.
    #[inline(always)]
    fn stop_wrench_in<V: Lanes>(
        &self,
        stops: &EndStops,
        state: &BodyState,
        arm: &[PerLeg<V>; 3],
        leg: &[PerLeg<V>; 3],
        length: PerLeg<V>,
    ) -> StopWrench {
        let (n, ldot) = self.joints.directions_and_rates(state, leg, length, PerLeg::splat(1.0) / length);
        let (force, dissipation) = self.stop_forces(stops, &length.to_array(), &ldot.to_array());
        let force = PerLeg::new(&force);
        let fs = components!(|c| n[c] * force);
        let moment = PerLeg::cross(arm, &fs);
        StopWrench {
            force: Vector3::new(fs[0].sum(), fs[1].sum(), fs[2].sum()),
            moment: Vector3::new(moment[0].sum(), moment[1].sum(), moment[2].sum()),
            dissipation,
        }
    }

    /// Whether a joint may be beyond its limit: `false` proves that none is. Every base joint
    /// angle `thetaB_k` is checked side by side (`q_k . n0_k >= cos(thetaMax) l_k`), and the
    /// platform joints through the bound `thetaA_k <= thetaB_k + phi`, `phi` the angle of the
    /// platform's rotation from the reference pose (`cos phi = (trace(R R0^T) - 1) / 2`).
    #[inline(always)]
    fn joints_may_touch<V: Lanes>(&self, state: &BodyState, leg: &[PerLeg<V>; 3], length: PerLeg<V>) -> bool {
        let [cos_base, cos_platform, sin_platform] = self.joint_cosines;
        let trace = state.e[0].dot(&self.reference_axes[0])
            + state.e[1].dot(&self.reference_axes[1])
            + state.e[2].dot(&self.reference_axes[2]);
        let cos_phi = (trace - 1.0) * 0.5;
        if !(cos_phi > cos_platform) {
            return true;
        }
        let sin_phi = (1.0 - cos_phi * cos_phi).max(0.0).sqrt();
        // cos(thetaMax_A - phi), and a margin for round-off: near a limit the exact check runs.
        let threshold = cos_base.max(cos_platform * cos_phi + sin_platform * sin_phi) + JOINT_CHECK_MARGIN;
        let n0 = components!(|c| PerLeg::<V>::new(&self.base_reference[c]));
        let dot = leg[0] * n0[0] + leg[1] * n0[1] + leg[2] * n0[2];
        dot.any_outside(PerLeg::splat(threshold) * length, PerLeg::splat(f64::INFINITY))
    }

    /// The machine's loads (the joint limits here) leg by leg, as [`SpecialForm::loads`]
    /// computes them, summed as [`Loads::wrench`] does; `None` if none acts.
    #[inline(never)]
    fn machine_wrench(&self, state: &BodyState) -> Option<MachineWrench> {
        let legs = LegGeometry::new(&self.stand, state);
        let mut loads = Loads::new(legs.arm);
        for k in 0..LEG_COUNT {
            let (leg, l) = (legs.leg[k], legs.length[k]);
            if l > 0.0 {
                let a_dot = state.v + state.body_vector_rate(&self.stand.platform_joints[k]);
                loads.add_machine(k, &self.machine_load(k, state, &LegMotion::new(&leg, l, &a_dot), None));
            }
        }
        loads.machine_wrench()
    }
}
