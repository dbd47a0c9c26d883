//! The machine's loads leg by leg (friction, joint limits, the legs' weight and inertia) and
//! the 6x6 solve heavy legs need: the definition's part of [`SpecialForm::rate`].

use super::*;
use crate::physics::legs::geometry::joint_rate;

impl SpecialForm {
    /// Each leg's load on the platform, by cause, leg by leg. A collapsed (or non-finite) leg
    /// carries nothing.
    pub(super) fn loads<T: Real>(&self, state: &BodyState<T>, actuation: Actuation<'_, T>) -> Loads<T> {
        let legs = LegGeometry::new(&self.stand, state);
        let mut loads = Loads::new(legs.arm);
        let mut inertia = [None; LEG_COUNT];
        let drives = match actuation {
            Actuation::Drives { currents, voltages } => self.drives().map(|d| (*d, currents, voltages)),
            Actuation::Forces(_) => None,
        };
        for k in 0..LEG_COUNT {
            let (leg, l) = (legs.leg[k], legs.length[k]);
            if !(l > T::zero()) {
                continue;
            }
            let joint = &self.stand.platform_joints[k];
            let motion = (!self.fast || self.joint_limits.is_some()).then(|| LegMotion::at(state, joint, &leg, l));
            let u = match (actuation, &drives, &motion) {
                (Actuation::Forces(u), _, _) => u[k],
                (_, Some((d, currents, voltages)), Some(motion)) => {
                    loads.drives[k] = d.rate(voltages[k], currents[k], motion.l_dot);
                    loads.drives[k].force
                }
                _ => T::zero(),
            };
            loads.actuator[k] = leg * (u / l);
            if let Some(stops) = &self.stops
                && stops.is_outside(k, l.value())
            {
                let n = leg * (T::one() / l);
                let (ldot, _) = joint_rate(state, joint, &n);
                let contact = stops.contact(k, l, ldot);
                loads.stop[k] = n * contact.force;
                loads.stop_dissipation[k] = contact.dissipation;
            }
            if let Some(motion) = &motion {
                let leg_inertia = self.legs.has_mass().then(|| self.legs.inertia(motion, self.stand.gravity));
                let machine = self.machine_load(k, state, motion, leg_inertia.as_ref());
                loads.add_machine(k, &machine);
                inertia[k] = leg_inertia.map(|m| (m, motion.n));
            }
        }
        if self.legs.has_mass() {
            self.solve_inertia(state, &mut loads, &inertia);
        }
        loads
    }

    /// Friction, the joint limits and the leg's weight and motion (`inertia`'s bias, without
    /// the inertia itself) on the platform, for leg `k` in motion `leg`.
    #[inline]
    pub(super) fn machine_load<T: Real>(
        &self,
        k: usize,
        state: &BodyState<T>,
        leg: &LegMotion<T>,
        inertia: Option<&LegInertia<T>>,
    ) -> MachineLoad<T> {
        let mut load = MachineLoad::none();
        if !self.friction.is_zero() {
            let f = self.friction.force(leg.l_dot);
            load.force += leg.n * f;
            load.dissipation -= f * leg.l_dot;
            load.acts = true;
        }
        self.add_joint_limits(k, state, leg, &mut load);
        if let Some(inertia) = inertia {
            load.force += inertia.bias;
            load.acts = true;
        }
        load
    }

    /// The joint limits' loads on the platform for leg `k` in motion `leg`, added to `load`.
    #[inline]
    pub(super) fn add_joint_limits<T: Real>(
        &self,
        k: usize,
        state: &BodyState<T>,
        leg: &LegMotion<T>,
        load: &mut MachineLoad<T>,
    ) {
        let Some(limits) = &self.joint_limits else { return };
        if let Some(c) = limits.base(k, &leg.n, &leg.n_dot) {
            load.force += c.on_leg / leg.l;
            load.dissipation += c.dissipation;
            load.acts = true;
        }
        let m0 = &limits.platform_reference[k];
        if let Some(c) = limits.platform(&leg.n, &leg.n_dot, &state.body_vector(m0), || state.body_vector_rate(m0)) {
            load.force += c.on_leg / leg.l;
            load.moment += c.on_platform;
            load.dissipation += c.dissipation;
            load.acts = true;
        }
    }

    /// The legs' inertia: the platform's accelerations `(r'', omega')` from its Newton-Euler
    /// equations with each joint's force `F0_k - M_k a_k''` (`a_k'' = r'' + omega' x rho_k +
    /// omega x (omega x rho_k)`), a symmetric positive definite 6x6 system; each leg's inertial
    /// force `-M_k a_k''` then joins its load.
    pub(super) fn solve_inertia<T: Real>(
        &self,
        state: &BodyState<T>,
        loads: &mut Loads<T>,
        inertia: &[Option<(LegInertia<T>, Vector3<T>)>; LEG_COUNT],
    ) {
        let omega = state.angular_velocity_inertial();
        let j = &self.stand.inertia;
        let e = &state.e;
        let j_w =
            |x: &Vector3<T>| e[0] * (e[0].dot(x) * j[0]) + e[1] * (e[1].dot(x) * j[1]) + e[2] * (e[2].dot(x) * j[2]);
        let zero = T::zero();
        // Each leg's terms of the system's sums (`InertiaSums`), summed below in the fast path's
        // order; a leg without inertia adds nothing.
        let mut terms = [([zero; 21], [zero; 11]); LEG_COUNT];
        let mut force = Vector3::new(zero, zero, -T::constant(self.stand.mass * self.stand.gravity));
        let mut moment = -omega.cross(&j_w(&omega));
        for k in 0..LEG_COUNT {
            let rho = loads.arm[k];
            let f0 = loads.actuator[k] + loads.stop[k] + loads.machine[k];
            let Some((m, n)) = &inertia[k] else {
                force += f0;
                moment += rho.cross(&f0) + loads.machine_moment[k];
                continue;
            };
            let f = f0 - m.times(n, &omega.cross(&omega.cross(&rho)));
            force += f;
            moment += rho.cross(&f) + loads.machine_moment[k];
            terms[k] = InertiaSums::leg_terms(&rho, n, m.along - m.across, m.across);
        }
        let sums = InertiaSums::over_legs(&terms);
        let q = solve_spd6(self.inertia_matrix(e, &sums), [force.x, force.y, force.z, moment.x, moment.y, moment.z]);
        let (alpha, beta) = (Vector3::new(q[0], q[1], q[2]), Vector3::new(q[3], q[4], q[5]));
        for k in 0..LEG_COUNT {
            if let Some((m, n)) = &inertia[k] {
                let rho = loads.arm[k];
                let acceleration = alpha + beta.cross(&rho) + omega.cross(&omega.cross(&rho));
                loads.machine[k] -= m.times(n, &acceleration);
            }
        }
    }

    /// The lower triangle of the 6x6 system `[[M I + sum M_k, -sum M_k [rho_k]x], [., J_w -
    /// sum [rho_k]x M_k [rho_k]x]]` in the platform's accelerations `(r'', omega')`, from the
    /// legs' sums and the body axes `e` (`J_w = sum_a J_a e_a e_a^T`). With `M_k = a_k I + c_k
    /// n_k n_k^T` (`a_k = I_t / l_k^2`, `c_k = m_r + m_a - a_k`) each leg adds `c_k S_k S_k^T`
    /// (`S_k = (n_k, rho_k x n_k)`) and its point mass `a_k [[I, -[rho_k]x], [[rho_k]x,
    /// |rho_k|^2 I - rho_k rho_k^T]]`. The one form of the system: the definition
    /// ([`SpecialForm::solve_inertia`]) and the fast path build it here, each with its own sums
    /// in the same order.
    #[inline(always)]
    #[rustfmt::skip]
    pub(super) fn inertia_matrix<T: Real>(&self, e: &[Vector3<T>; 3], sums: &InertiaSums<T>) -> [[T; 6]; 6] {
        let j = &self.stand.inertia;
        let je = [0, 1, 2].map(|a| [e[a].x * j[a], e[a].y * j[a], e[a].z * j[a]]);
        let j_w = |r: usize, c: usize| je[0][r] * e[0][c] + je[1][r] * e[1][c] + je[2][r] * e[2][c];
        let g = &sums.along;
        let [ax, ay, az] = sums.across_arm;
        let [p00, p10, p11, p20, p21, p22] = sums.across_arm_arm;
        let rr = sums.across_arm2;
        let linear = T::constant(self.stand.mass) + sums.across;
        let o = T::zero();
        [
            [g[0] + linear, o, o, o, o, o],
            [g[1], g[2] + linear, o, o, o, o],
            [g[3], g[4], g[5] + linear, o, o, o],
            [g[6], g[7] - az, g[8] + ay, g[9] + j_w(0, 0) + (rr - p00), o, o],
            [g[10] + az, g[11], g[12] - ax, g[13] + j_w(1, 0) - p10, g[14] + j_w(1, 1) + (rr - p11), o],
            [g[15] - ay, g[16] + ax, g[17], g[18] + j_w(2, 0) - p20, g[19] + j_w(2, 1) - p21, g[20] + j_w(2, 2) + (rr - p22)],
        ]
    }
}

/// The legs' sums in the 6x6 system of their inertia ([`SpecialForm::inertia_matrix`]), each
/// over the legs in [`sum_over_legs`]'s order (the fast path's lanes sum in it too): with
/// `S_k = (n_k, rho_k x n_k)`, `c_k = along_k - across_k` and `a_k = across_k` (kg).
pub(super) struct InertiaSums<T> {
    /// `sum c_k S_k S_k^T`, its lower triangle row by row (00; 10, 11; 20, 21, 22; ...; 50 .. 55).
    pub(super) along: [T; 21],
    /// `sum a_k`, kg.
    pub(super) across: T,
    /// `sum a_k rho_k`, kg m.
    pub(super) across_arm: [T; 3],
    /// `sum a_k |rho_k|^2`, kg m².
    pub(super) across_arm2: T,
    /// `sum a_k rho_k rho_k^T`, its lower triangle (00; 10, 11; 20, 21, 22), kg m².
    pub(super) across_arm_arm: [T; 6],
}

impl<T: Real> InertiaSums<T> {
    /// One leg's terms of the sums: with the arm `rho`, the direction `n`, `c = along -
    /// across` and `a = across`, `c S S^T`'s lower triangle (the order of
    /// [`InertiaSums::along`]) and `a`, `a rho` (3), `a |rho|^2`, `a rho rho^T`'s lower
    /// triangle (6), each product in the order the fast path's lanes take it.
    #[inline(always)]
    pub(super) fn leg_terms(rho: &Vector3<T>, n: &Vector3<T>, c: T, a: T) -> ([T; 21], [T; 11]) {
        let rn = rho.cross(n);
        let s = [n.x, n.y, n.z, rn.x, rn.y, rn.z];
        let mut along = [T::zero(); 21];
        let mut i = 0;
        for r in 0..6 {
            let cs = s[r] * c;
            for col in 0..=r {
                along[i] = cs * s[col];
                i += 1;
            }
        }
        let a_rho = [a * rho.x, a * rho.y, a * rho.z];
        let rho2 = rho.x * rho.x + rho.y * rho.y + rho.z * rho.z;
        let across = [
            a,
            a_rho[0],
            a_rho[1],
            a_rho[2],
            a * rho2,
            a_rho[0] * rho.x,
            a_rho[1] * rho.x,
            a_rho[1] * rho.y,
            a_rho[2] * rho.x,
            a_rho[2] * rho.y,
            a_rho[2] * rho.z,
        ];
        (along, across)
    }

    /// The sums of the legs' terms ([`InertiaSums::leg_terms`], leg by leg), each in
    /// [`sum_over_legs`]' order.
    pub(super) fn over_legs(terms: &[([T; 21], [T; 11]); LEG_COUNT]) -> Self {
        let a: [T; 11] = std::array::from_fn(|i| sum_over_legs(&std::array::from_fn(|k| terms[k].1[i])));
        InertiaSums {
            along: std::array::from_fn(|i| sum_over_legs(&std::array::from_fn(|k| terms[k].0[i]))),
            across: a[0],
            across_arm: [a[1], a[2], a[3]],
            across_arm2: a[4],
            across_arm_arm: [a[5], a[6], a[7], a[8], a[9], a[10]],
        }
    }
}

/// Solves `A x = b` for a symmetric positive definite 6x6 `A` given by its lower triangle
/// (Cholesky `A = L L^T`, the diagonal's reciprocals `d_i` kept); not numbers if `A` is not
/// positive definite. Written out: with loops the trip counts and index checks cost more
/// than the arithmetic.
#[inline(always)]
#[rustfmt::skip]
pub(super) fn solve_spd6<T: Real>(a: [[T; 6]; 6], b: [T; 6]) -> [T; 6] {
    let [a0, a1, a2, a3, a4, a5] = a;
    let l00 = a0[0].sqrt();
    let d0 = T::one() / l00;
    let l10 = a1[0] * d0;
    let l11 = (a1[1] - l10 * l10).sqrt();
    let d1 = T::one() / l11;
    let l20 = a2[0] * d0;
    let l21 = (a2[1] - l20 * l10) * d1;
    let l22 = (a2[2] - l20 * l20 - l21 * l21).sqrt();
    let d2 = T::one() / l22;
    let l30 = a3[0] * d0;
    let l31 = (a3[1] - l30 * l10) * d1;
    let l32 = (a3[2] - l30 * l20 - l31 * l21) * d2;
    let l33 = (a3[3] - l30 * l30 - l31 * l31 - l32 * l32).sqrt();
    let d3 = T::one() / l33;
    let l40 = a4[0] * d0;
    let l41 = (a4[1] - l40 * l10) * d1;
    let l42 = (a4[2] - l40 * l20 - l41 * l21) * d2;
    let l43 = (a4[3] - l40 * l30 - l41 * l31 - l42 * l32) * d3;
    let l44 = (a4[4] - l40 * l40 - l41 * l41 - l42 * l42 - l43 * l43).sqrt();
    let d4 = T::one() / l44;
    let l50 = a5[0] * d0;
    let l51 = (a5[1] - l50 * l10) * d1;
    let l52 = (a5[2] - l50 * l20 - l51 * l21) * d2;
    let l53 = (a5[3] - l50 * l30 - l51 * l31 - l52 * l32) * d3;
    let l54 = (a5[4] - l50 * l40 - l51 * l41 - l52 * l42 - l53 * l43) * d4;
    let l55 = (a5[5] - l50 * l50 - l51 * l51 - l52 * l52 - l53 * l53 - l54 * l54).sqrt();
    let d5 = T::one() / l55;
    let y0 = b[0] * d0;
    let y1 = (b[1] - l10 * y0) * d1;
    let y2 = (b[2] - l20 * y0 - l21 * y1) * d2;
    let y3 = (b[3] - l30 * y0 - l31 * y1 - l32 * y2) * d3;
    let y4 = (b[4] - l40 * y0 - l41 * y1 - l42 * y2 - l43 * y3) * d4;
    let y5 = (b[5] - l50 * y0 - l51 * y1 - l52 * y2 - l53 * y3 - l54 * y4) * d5;
    let x5 = y5 * d5;
    let x4 = (y4 - l54 * x5) * d4;
    let x3 = (y3 - l43 * x4 - l53 * x5) * d3;
    let x2 = (y2 - l32 * x3 - l42 * x4 - l52 * x5) * d2;
    let x1 = (y1 - l21 * x2 - l31 * x3 - l41 * x4 - l51 * x5) * d1;
    let x0 = (y0 - l10 * x1 - l20 * x2 - l30 * x3 - l40 * x4 - l50 * x5) * d0;
    [x0, x1, x2, x3, x4, x5]
}

/// Each leg's load on the platform at its joint, by cause.
pub(super) struct Loads<T: nalgebra::Scalar> {
    /// `rho_k = R A_k`.
    pub(super) arm: [Vector3<T>; LEG_COUNT],
    /// `u_k n_k`.
    pub(super) actuator: [Vector3<T>; LEG_COUNT],
    /// The end stops' forces.
    pub(super) stop: [Vector3<T>; LEG_COUNT],
    /// Each leg's stop damping power.
    pub(super) stop_dissipation: [T; LEG_COUNT],
    /// Friction, the joint limits' forces and the legs' weight and inertia.
    pub(super) machine: [Vector3<T>; LEG_COUNT],
    /// The platform joints' limit moments.
    pub(super) machine_moment: [Vector3<T>; LEG_COUNT],
    /// The drives' forces, current rates and powers (zero without drives).
    pub(super) drives: [DriveRate<T>; LEG_COUNT],
    pub(super) machine_dissipation: T,
    /// Whether any of the machine's loads acts.
    pub(super) machine_acts: bool,
}

/// One leg's machine load (see [`Loads::machine`]), without the leg's inertia.
pub(super) struct MachineLoad<T: nalgebra::Scalar> {
    pub(super) force: Vector3<T>,
    pub(super) moment: Vector3<T>,
    pub(super) dissipation: T,
    pub(super) acts: bool,
}

impl<T: Real> MachineLoad<T> {
    /// No load: what a leg without friction, joint limits or mass gives.
    pub(super) fn none() -> Self {
        MachineLoad { force: Vector3::zeros(), moment: Vector3::zeros(), dissipation: T::zero(), acts: false }
    }
}

impl<T: Real> Loads<T> {
    pub(super) fn new(arm: [Vector3<T>; LEG_COUNT]) -> Self {
        let zero = [Vector3::zeros(); LEG_COUNT];
        Loads {
            arm,
            actuator: zero,
            stop: zero,
            stop_dissipation: [T::zero(); LEG_COUNT],
            machine: zero,
            machine_moment: zero,
            drives: [DriveRate::zero(); LEG_COUNT],
            machine_dissipation: T::zero(),
            machine_acts: false,
        }
    }

    pub(super) fn add_machine(&mut self, k: usize, load: &MachineLoad<T>) {
        self.machine[k] += load.force;
        self.machine_moment[k] += load.moment;
        self.machine_dissipation += load.dissipation;
        self.machine_acts |= load.acts;
    }

    /// The machine's resultant, if it acts.
    pub(super) fn machine_wrench(&self) -> Option<MachineWrench<T>> {
        self.machine_acts.then(|| MachineWrench {
            force: sum_vectors(&self.machine),
            moment: sum_vectors(&std::array::from_fn(|k| self.arm[k].cross(&self.machine[k]) + self.machine_moment[k])),
            dissipation: self.machine_dissipation,
        })
    }

    /// The resultant about the centre of mass, by cause, each summed over the legs in
    /// [`sum_over_legs`]'s order.
    pub(super) fn wrench(&self) -> LegWrench<T> {
        let moments = |f: &[Vector3<T>; LEG_COUNT]| sum_vectors(&std::array::from_fn(|k| self.arm[k].cross(&f[k])));
        LegWrench {
            force: sum_vectors(&self.actuator),
            moment: moments(&self.actuator),
            stop: StopWrench {
                force: sum_vectors(&self.stop),
                moment: moments(&self.stop),
                dissipation: sum_over_legs(&self.stop_dissipation),
            },
            machine: self.machine_wrench(),
        }
    }
}
