//! The step's fast paths: [`SpecialForm::rate`]'s numbers with the six legs side by side in
//! vector registers; for the paper's massless, frictionless legs the definition's bits (pinned
//! by a test), for the machine's (legs with mass, friction, drives) its numbers to round-off.

use super::machine::{InertiaSums, Loads, MachineLoad, solve_spd6};
use super::*;

/// The fast path's joint check counts a joint within this of its limit's cosine as touching.
const JOINT_CHECK_MARGIN: f64 = 1e-9;

impl SpecialForm {
    /// The right-hand side `dy/dt` for leg forces given by `law` at time `t`, and the leg
    /// powers: [`SpecialForm::rate`]'s numbers, computed in vector registers: its bits for
    /// massless, frictionless legs, to round-off for the machine's legs
    /// (`SpecialForm::derivative_machine_in`).
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
            // The machine's legs: rarer, and out of the paper's legs' way.
            std::hint::cold_path();
            return self.derivative_machine_of::<V>(y, Actuation::Forces(&u), dy).power;
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

    /// [`SpecialForm::derivative_machine_in`] in lanes `V`, compiled once per register width
    /// and called: inlined into every force law's step (as the paper's legs' path is) it made
    /// the test build several times slower. Every width gives the same bits (tested).
    #[inline(always)]
    pub(crate) fn derivative_machine_of<V: Lanes>(
        &self,
        y: &StateVector,
        actuation: Actuation<'_, f64>,
        dy: &mut StateVector,
    ) -> MachineRates {
        #[cfg(all(target_arch = "x86_64", feature = "avx2"))]
        if V::AVX {
            // SAFETY: lanes in AVX registers run only where `crate::simd::wide_available()`
            // found AVX2 and FMA.
            return unsafe { self.derivative_machine_avx(y, actuation, dy) };
        }
        self.derivative_machine(y, actuation, dy)
    }

    /// [`SpecialForm::derivative_machine_in`] in AVX registers.
    ///
    /// # Safety
    /// AVX2 and FMA must be available ([`crate::simd::wide_available`]).
    #[cfg(all(target_arch = "x86_64", feature = "avx2"))]
    #[target_feature(enable = "avx,avx2,fma")]
    #[inline(never)]
    unsafe fn derivative_machine_avx(
        &self,
        y: &StateVector,
        actuation: Actuation<'_, f64>,
        dy: &mut StateVector,
    ) -> MachineRates {
        self.derivative_machine_in::<crate::simd::Wide>(y, actuation, dy)
    }

    /// [`SpecialForm::derivative_machine_in`] in [`Narrow`] lanes.
    #[inline(never)]
    fn derivative_machine(&self, y: &StateVector, actuation: Actuation<'_, f64>, dy: &mut StateVector) -> MachineRates {
        self.derivative_machine_in::<Narrow>(y, actuation, dy)
    }

    /// [`SpecialForm::rate`]'s and [`SpecialForm::rate_driven`]'s numbers for the machine (legs
    /// with mass, friction, electric drives, each optional), the six legs side by side: the
    /// definition's laws ([`LegBodies::inertia_terms`], [`ElectricDrives::rate`],
    /// [`Friction::force`], the end stops' and joint limits' contact laws) with the sums in
    /// another order (equal to round-off, tested). Each leg's force on the platform is
    /// `f_k = s_k n_k + b_k - M_k a_k''` with `s_k` its axial force (actuator, end stop,
    /// friction), `M_k = along n n^T + across_k P` and `a_k'' = r'' + omega' x rho_k + omega x
    /// (omega x rho_k)`, so that the platform's accelerations solve
    /// `[diag(M, J_w) + sum_k (along - across_k) S_k S_k^T + across_k [[I, -[rho]x], [[rho]x,
    /// |rho|^2 I - rho rho^T]]] (r'', omega') = sum_k (f0_k, rho_k x f0_k) + gravity, gyroscopic
    /// and joint-limit terms` (`S_k = (n_k, rho_k x n_k)`, `f0_k` the force without `r''` and
    /// `omega'`).
    #[inline(always)]
    pub(crate) fn derivative_machine_in<V: Lanes>(
        &self,
        y: &StateVector,
        actuation: Actuation<'_, f64>,
        dy: &mut StateVector,
    ) -> MachineRates {
        let state = BodyState::from_vector(y);
        let LegLanes { arm, leg, length } = self.joints.legs::<V>(&state);
        let inverse_length = PerLeg::splat(1.0) / length;
        let (n, l_dot, velocity) = self.joints.directions_rates_and_velocities(&state, &leg, length, inverse_length);
        // The actuators' axial forces: given, or the drive law's, six legs at once.
        let (actuator, drive) = match (actuation, self.drives()) {
            (Actuation::Forces(u), _) => (PerLeg::<V>::new(u), None),
            (Actuation::Drives { currents, voltages }, Some(drives)) => {
                let rate = drives.rate(PerLeg::<V>::new(voltages), PerLeg::new(currents), l_dot);
                (rate.force, Some(rate))
            }
            (Actuation::Drives { .. }, None) => (PerLeg::splat(0.0), None),
        };
        // (A collapsed leg's direction is 0: it carries nothing.)
        let mut axial = actuator;
        let mut dissipation = 0.0;
        // The end stops (rare: cold), friction, and the joint limits (only where one may touch).
        if let Some(stops) = &self.stops
            && length.any_outside(PerLeg::new(&self.stroke[0]), PerLeg::new(&self.stroke[1]))
        {
            std::hint::cold_path();
            let (stop, stop_dissipation) = self.stop_forces(stops, &length.to_array(), &l_dot.to_array());
            axial = axial + PerLeg::new(&stop);
            dissipation += stop_dissipation;
        }
        if !self.friction.is_zero() {
            let rates = l_dot.to_array();
            let friction = PerLeg::<V>::new(&std::array::from_fn(|k| self.friction.force(rates[k])));
            axial = axial + friction;
            dissipation -= (friction * l_dot).sum();
        }
        let machine = match &self.joint_limits {
            Some(_) if self.joints_may_touch(&state, &leg, length) => {
                std::hint::cold_path();
                self.machine_wrench(&state)
            }
            _ => None,
        };
        // The legs' inertia: `across_k`, `along - across_k` and each leg's force without the
        // platform's accelerations, `f0_k = s_k n_k + b_k - M_k (omega x (omega x rho_k))`.
        let omega = state.angular_velocity_inertial();
        let w = components!(|c| PerLeg::<V>::splat(omega[c]));
        let whirl = PerLeg::cross(&w, &PerLeg::cross(&w, &arm));
        let n_dot = components!(|c| (velocity[c] - n[c] * l_dot) * inverse_length);
        let along = PerLeg::splat(self.legs.rod_mass + self.legs.axial_mass);
        let n_whirl = n[0] * whirl[0] + n[1] * whirl[1] + n[2] * whirl[2];
        let g = self.stand.gravity;
        let (across, weight, f0) = if self.legs_turn {
            let (across, bias) = self.legs.inertia_terms(length, &n, l_dot, &n_dot, g);
            let across = length.where_positive(across);
            let weight = along - across;
            let along_force = axial - weight * n_whirl;
            (across, weight, components!(|c| length.where_positive(n[c] * along_force + bias[c] - across * whirl[c])))
        } else {
            // `across` is 0 and `b` is along the leg: the inertia acts along the legs only.
            let along_force =
                length.where_positive(axial - along * n_whirl + self.legs.axial_force(length, &n, &n_dot, g));
            (PerLeg::splat(0.0), along, components!(|c| n[c] * along_force))
        };
        let sum4 = PerLeg::<V>::sum4;
        let (force, moment) = if self.legs_mass {
            // The legs' wrench with their inertia is what moves the platform as the 6x6 system
            // says: `(M (r'' + g ez), J_w omega' + omega x J_w omega)` (the system's rows).
            self.legs_wrench_with_inertia(&state, &arm, &n, across, weight, &f0, machine.as_ref())
        } else {
            let moment = PerLeg::cross(&arm, &f0);
            let [f1, f2, f3, m1] = sum4([f0[0], f0[1], f0[2], moment[0]]);
            let [m2, m3, _, _] = sum4([moment[1], moment[2], PerLeg::splat(0.0), PerLeg::splat(0.0)]);
            let (mut force, mut moment) = (Vector3::new(f1, f2, f3), Vector3::new(m1, m2, m3));
            if let Some(m) = &machine {
                force += m.force;
                moment += m.moment;
            }
            (force, moment)
        };
        if let Some(m) = &machine {
            dissipation += m.dissipation;
        }
        let (e_rows, e_dot) = (AxisRows::<V::Axes>::of(&state.e), AxisRows::of(&state.e_dot));
        // The given forces' power as the definition takes it, from their wrench (`F.v + L.omega`,
        // which off the constraint manifold is not quite `sum u_k l_k'`); the drives' work is
        // electric.
        let actuator_power = match actuation {
            Actuation::Forces(_) => {
                let u = components!(|c| n[c] * actuator);
                let u_moment = PerLeg::cross(&arm, &u);
                let [u1, u2, u3, um1] = sum4([u[0], u[1], u[2], u_moment[0]]);
                let [um2, um3, _, _] = sum4([u_moment[1], u_moment[2], PerLeg::splat(0.0), PerLeg::splat(0.0)]);
                Vector3::new(u1, u2, u3).dot(&state.v)
                    + e_rows.cross_sum_dot(&e_dot, &Vector3::new(um1, um2, um3)) * 0.5
            }
            Actuation::Drives { .. } => 0.0,
        };
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
        let power = LegPower { actuator: actuator_power, dissipation };
        match drive {
            Some(d) => {
                let [electric_power, drive_dissipation, _, _] =
                    sum4([d.electric_power, d.dissipation, PerLeg::splat(0.0), PerLeg::splat(0.0)]);
                MachineRates { power, current_rate: d.current_rate.to_array(), electric_power, drive_dissipation }
            }
            None => MachineRates { power, ..MachineRates::default() },
        }
    }

    /// The legs' wrench on the platform with their inertia (see
    /// [`SpecialForm::derivative_machine_in`]), `(M (r'' + g ez), J_w omega' + omega x J_w
    /// omega)` from the platform's accelerations `(r'', omega')`: the 6x6 system's lower
    /// triangle from sums over the legs, four at a time, and its Cholesky solve.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn legs_wrench_with_inertia<V: Lanes>(
        &self,
        state: &BodyState,
        arm: &[PerLeg<V>; 3],
        n: &[PerLeg<V>; 3],
        across: PerLeg<V>,
        weight: PerLeg<V>,
        f0: &[PerLeg<V>; 3],
        machine: Option<&MachineWrench>,
    ) -> (Vector3<f64>, Vector3<f64>) {
        let sum4 = PerLeg::<V>::sum4;
        let rn = PerLeg::cross(arm, n);
        let s = [n[0], n[1], n[2], rn[0], rn[1], rn[2]];
        let ws = [s[0] * weight, s[1] * weight, s[2] * weight, s[3] * weight, s[4] * weight, s[5] * weight];
        // `sum (along - across_k) S_k S_k^T`, row by row.
        let [g00, g10, g11, g20] = sum4([ws[0] * s[0], ws[1] * s[0], ws[1] * s[1], ws[2] * s[0]]);
        let [g21, g22, g30, g31] = sum4([ws[2] * s[1], ws[2] * s[2], ws[3] * s[0], ws[3] * s[1]]);
        let [g32, g33, g40, g41] = sum4([ws[3] * s[2], ws[3] * s[3], ws[4] * s[0], ws[4] * s[1]]);
        let [g42, g43, g44, g50] = sum4([ws[4] * s[2], ws[4] * s[3], ws[4] * s[4], ws[5] * s[0]]);
        let [g51, g52, g53, g54] = sum4([ws[5] * s[1], ws[5] * s[2], ws[5] * s[3], ws[5] * s[4]]);
        // The point masses `across_k` at the joints (`sum a`, `sum a rho`, `sum a |rho|^2` and
        // `sum a rho rho^T`; none where `across` vanishes, the drives' rotors alone), and the
        // legs' wrench without the accelerations, `sum (f0_k, rho_k x f0_k)`.
        let moment = PerLeg::cross(arm, f0);
        let zero = PerLeg::splat(0.0);
        let ([g55, a, ax, ay, az, a_rho2, p00, p10, p11, p20, p21, p22], [b0, b1, b2, b3, b4, b5]) = if self.legs_turn {
            let a_rho = components!(|c| across * arm[c]);
            let rho2 = arm[0] * arm[0] + arm[1] * arm[1] + arm[2] * arm[2];
            let [g55, a, ax, ay] = sum4([ws[5] * s[5], across, a_rho[0], a_rho[1]]);
            let [az, a_rho2, p00, p10] = sum4([a_rho[2], across * rho2, a_rho[0] * arm[0], a_rho[1] * arm[0]]);
            let [p11, p20, p21, p22] =
                sum4([a_rho[1] * arm[1], a_rho[2] * arm[0], a_rho[2] * arm[1], a_rho[2] * arm[2]]);
            let [b0, b1, b2, b3] = sum4([f0[0], f0[1], f0[2], moment[0]]);
            let [b4, b5, _, _] = sum4([moment[1], moment[2], zero, zero]);
            ([g55, a, ax, ay, az, a_rho2, p00, p10, p11, p20, p21, p22], [b0, b1, b2, b3, b4, b5])
        } else {
            let [g55, b0, b1, b2] = sum4([ws[5] * s[5], f0[0], f0[1], f0[2]]);
            let [b3, b4, b5, _] = sum4([moment[0], moment[1], moment[2], zero]);
            let mut point_masses = [0.0; 12];
            point_masses[0] = g55;
            (point_masses, [b0, b1, b2, b3, b4, b5])
        };
        let sums = InertiaSums {
            along: [
                g00, g10, g11, g20, g21, g22, g30, g31, g32, g33, g40, g41, g42, g43, g44, g50, g51, g52, g53, g54, g55,
            ],
            across: a,
            across_arm: [ax, ay, az],
            across_arm2: a_rho2,
            across_arm_arm: [p00, p10, p11, p20, p21, p22],
        };
        let matrix = self.inertia_matrix(&state.e, &sums);
        let (mass, j, e) = (self.stand.mass, &self.stand.inertia, &state.e);
        // `J_w = sum_a J_a e_a e_a^T`, from `J_a e_a`.
        let je = [e[0] * j[0], e[1] * j[1], e[2] * j[2]];
        let omega = state.angular_velocity_inertial();
        let j_omega = je[0] * e[0].dot(&omega) + je[1] * e[1].dot(&omega) + je[2] * e[2].dot(&omega);
        let mut force = Vector3::new(b0, b1, b2 - mass * self.stand.gravity);
        let mut moment = Vector3::new(b3, b4, b5) - omega.cross(&j_omega);
        if let Some(m) = machine {
            force += m.force;
            moment += m.moment;
        }
        let q = solve_spd6(matrix, [force.x, force.y, force.z, moment.x, moment.y, moment.z]);
        let beta = Vector3::new(q[3], q[4], q[5]);
        let j_beta = je[0] * e[0].dot(&beta) + je[1] * e[1].dot(&beta) + je[2] * e[2].dot(&beta);
        (Vector3::new(q[0] * mass, q[1] * mass, (q[2] + self.stand.gravity) * mass), j_beta + omega.cross(&j_omega))
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

    /// The joint limits' loads leg by leg, as [`SpecialForm::loads`] computes them, summed as
    /// [`Loads::wrench`] does; `None` if none acts.
    #[inline(never)]
    fn machine_wrench(&self, state: &BodyState) -> Option<MachineWrench> {
        let legs = LegGeometry::new(&self.stand, state);
        let mut loads = Loads::new(legs.arm);
        for k in 0..LEG_COUNT {
            let (leg, l) = (legs.leg[k], legs.length[k]);
            if l > 0.0 {
                let mut load = MachineLoad::none();
                self.add_joint_limits(
                    k,
                    state,
                    &LegMotion::at(state, &self.stand.platform_joints[k], &leg, l),
                    &mut load,
                );
                loads.add_machine(k, &load);
            }
        }
        loads.machine_wrench()
    }
}
