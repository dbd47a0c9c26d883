//! The loaded platform's equations of motion: the special form of the rigid body
//! ([`super::body::accelerations`]) driven by the legs. Each leg acts on the body at `A_k`
//! along its direction with the actuator force `u_k` plus, outside its stroke, its end stop's
//! force ([`super::legs::end_stops`]); the machine adds cylinder friction along the leg
//! ([`super::legs::friction`]), the joint limits' moments ([`super::legs::joint_limits`]) and
//! the legs' inertia and weight ([`super::legs::bodies`]). Legs with mass make the joints'
//! forces depend on the platform's accelerations: those then solve a 6x6 linear system (the
//! platform's Newton-Euler equations with the legs' inertia at the joints), and the wrench of
//! the legs' forces goes into the special form. With the forces given, nothing here is
//! singular at a singular leg arrangement: only a collapsed leg (no direction) is, and it
//! carries nothing.
//!
//! [`SpecialForm::rate`] is the definition, written once and generic over the number type:
//! in `f64` it is the right-hand side, in [`Dual`] its exact directional derivative
//! ([`SpecialForm::derivative_tangent`]). [`SpecialForm::derivative`] is the step's fast
//! path for massless legs without friction: the same operations in the same order with the six
//! legs side by side in vector registers ([`PerLeg`]) and the three axes likewise
//! ([`AxisRows`]), pinned to the definition bit for bit by a test; other machines take the
//! definition itself.

use nalgebra::Vector3;

use super::actuators::LegForceLaw;
use super::actuators::drives::{DriveRate, ElectricDrives};
use super::body::accelerations::RigidBody;
use super::body::per_axis::AxisRows;
use super::body::state::{BodyState, STATE_DIM, StateVector, axes_rates};
use super::legs::bodies::{LegBodies, LegInertia, LegMotion};
use super::legs::end_stops::EndStops;
use super::legs::friction::Friction;
use super::legs::geometry::{JointArrays, LegGeometry, LegKinematics, LegLanes};
use super::legs::joint_limits::JointLimits;
use super::legs::per_leg::{Lanes, Narrow, PerLeg, components};
use super::number::{Dual, Real};
use super::stand::{LEG_COUNT, Stand};

/// A stand with its legs' end stops, and the coefficients a right-hand side needs.
#[derive(Clone, Debug, PartialEq)]
pub struct SpecialForm {
    pub stand: Stand,
    /// The special form's coefficients (and the Baumgarte rate).
    pub body: RigidBody,
    /// The legs' end stops, or `None` for the paper's idealised legs of unlimited stroke.
    stops: Option<EndStops>,
    /// The strokes `[lmin, lmax]` (`[-inf, inf]` without stops), kept beside `stops` (written
    /// only by [`SpecialForm::set_end_stops`]) so that the fast path tests all six legs with
    /// one comparison and no branch on the option.
    stroke: [[f64; LEG_COUNT]; 2],
    /// The joints as arrays over the legs, for the fast path.
    pub joints: JointArrays,
    /// The legs as bodies (massless: the paper's).
    legs: LegBodies,
    /// Cylinder friction (none: the paper's).
    friction: Friction,
    /// The joint limits, or `None` (the paper's).
    joint_limits: Option<JointLimits>,
    /// Electric drives in the legs, or `None`: the actuator forces are given (the paper's).
    drives: Option<ElectricDrives>,
    /// For the fast path's check and the switching functions of the joint limits: `n0_k` and
    /// `m0_k` as `[component][leg]`, and the reference pose's axes `e0_a`.
    base_reference: [[f64; LEG_COUNT]; 3],
    platform_reference: [[f64; LEG_COUNT]; 3],
    reference_axes: [Vector3<f64>; 3],
    /// `cos thetaMax` of the base joints, `cos` and `sin thetaMax` of the platform joints.
    joint_cosines: [f64; 3],
    /// Whether the fast path applies: massless legs without friction, forces given.
    fast: bool,
    /// Whether the drives' fast path applies: drives on legs otherwise massless, without
    /// friction (the rotors' inertia along the legs is the only inertia they add).
    fast_driven: bool,
}

/// The sum over the six legs in the fixed order `((x1 + x3) + x5) + ((x2 + x4) + x6)`, that of
/// [`PerLeg::sum`].
#[inline(always)]
pub(crate) fn sum_over_legs<T: Real>(x: &[T; LEG_COUNT]) -> T {
    ((x[0] + x[2]) + x[4]) + ((x[1] + x[3]) + x[5])
}

/// [`sum_over_legs`] of each component.
#[inline(always)]
fn sum_vectors<T: Real>(v: &[Vector3<T>; LEG_COUNT]) -> Vector3<T> {
    Vector3::new(sum_over_legs(&v.map(|x| x.x)), sum_over_legs(&v.map(|x| x.y)), sum_over_legs(&v.map(|x| x.z)))
}

impl SpecialForm {
    /// The equations of a stand (which should have passed [`Stand::validate`]; otherwise the
    /// coefficients may be infinite), without end stops.
    pub fn new(stand: Stand) -> Self {
        SpecialForm {
            body: RigidBody::new(&stand),
            stops: None,
            stroke: [[f64::NEG_INFINITY; LEG_COUNT], [f64::INFINITY; LEG_COUNT]],
            joints: JointArrays::new(&stand),
            legs: LegBodies::default(),
            friction: Friction::default(),
            joint_limits: None,
            drives: None,
            base_reference: [[0.0; LEG_COUNT]; 3],
            platform_reference: [[0.0; LEG_COUNT]; 3],
            reference_axes: [Vector3::x(), Vector3::y(), Vector3::z()],
            joint_cosines: [-1.0, -1.0, 0.0],
            fast: true,
            fast_driven: false,
            stand,
        }
    }

    /// The same form with the machine's legs: bodies, friction and joint limits (`None`:
    /// without).
    pub fn with_machine(mut self, legs: LegBodies, friction: Friction, joint_limits: Option<JointLimits>) -> Self {
        // The drives' reflected rotor mass stays (set by `with_drives`).
        self.legs = LegBodies { axial_mass: self.legs.axial_mass, ..legs };
        self.friction = friction;
        if let Some(j) = &joint_limits {
            self.base_reference = std::array::from_fn(|c| j.base_reference.map(|n| n[c]));
            self.platform_reference = std::array::from_fn(|c| j.platform_reference.map(|m| m[c]));
            self.reference_axes = j.reference_axes;
            self.joint_cosines = [j.base_max.cos(), j.platform_max.cos(), j.platform_max.sin()];
        }
        self.joint_limits = joint_limits;
        self.fast = self.takes_fast_path();
        self.fast_driven = self.takes_driven_fast_path();
        self
    }

    /// The same form with electric drives in the legs (`None`: the actuator forces are given);
    /// their rotors join the legs' inertia.
    pub fn with_drives(mut self, drives: Option<ElectricDrives>) -> Self {
        self.legs.axial_mass = drives.map_or(0.0, |d| d.reflected_mass());
        self.drives = drives;
        self.fast = self.takes_fast_path();
        self.fast_driven = self.takes_driven_fast_path();
        self
    }

    /// The electric drives, if on.
    pub fn drives(&self) -> Option<&ElectricDrives> {
        self.drives.as_ref()
    }

    /// Whether the step's fast path applies: massless legs without friction, forces given.
    fn takes_fast_path(&self) -> bool {
        !self.legs.has_mass() && self.friction.is_zero() && self.drives.is_none()
    }

    /// Whether the drives' fast path applies ([`SpecialForm::derivative_driven_in`]).
    fn takes_driven_fast_path(&self) -> bool {
        let bodies = LegBodies { axial_mass: 0.0, ..self.legs };
        self.drives.is_some() && !bodies.has_mass() && self.friction.is_zero()
    }

    /// Whether [`SpecialForm::derivative_driven_in`] applies to this form.
    pub fn has_driven_fast_path(&self) -> bool {
        self.fast_driven
    }

    /// The drives' axial forces and rates at a body state: each leg's rate `l'_k` from the
    /// state, its current `I_k` and voltage `U_k` (docs/model.md §9). `None` without drives.
    pub fn drive_rates<T: Real>(
        &self,
        state: &BodyState<T>,
        currents: &[T; LEG_COUNT],
        voltages: &[T; LEG_COUNT],
    ) -> Option<[DriveRate<T>; LEG_COUNT]> {
        let drives = self.drives.as_ref()?;
        let legs = LegGeometry::new(&self.stand, state);
        Some(std::array::from_fn(|k| {
            let l = legs.length[k];
            // A collapsed leg has no rate (it carries nothing either: see `loads`).
            let l_dot = if l > T::zero() {
                legs.leg[k].dot(&(state.v + state.body_vector_rate(&self.stand.platform_joints[k]))) / l
            } else {
                T::zero()
            };
            drives.rate(voltages[k], currents[k], l_dot)
        }))
    }

    /// The legs as bodies.
    pub fn legs(&self) -> &LegBodies {
        &self.legs
    }

    /// The cylinder friction.
    pub fn friction(&self) -> &Friction {
        &self.friction
    }

    /// The joint limits, if on.
    pub fn joint_limits(&self) -> Option<&JointLimits> {
        self.joint_limits.as_ref()
    }

    /// The joint limits' switching functions `cos thetaB_k - cos thetaMax_B` into
    /// `base[k]` and `cos thetaA_k - cos thetaMax_A` into `platform[k]`, from the legs of a
    /// state (the leg by leg loops run side by side in vector registers).
    #[inline(always)]
    pub fn joint_margins(
        &self,
        state: &BodyState,
        legs: &LegKinematics,
        base: &mut [f64; LEG_COUNT],
        platform: &mut [f64; LEG_COUNT],
    ) {
        let [cos_base, cos_platform, _] = self.joint_cosines;
        let (n0, m0) = (&self.base_reference, &self.platform_reference);
        let [e1, e2, e3] = &state.e;
        for k in 0..LEG_COUNT {
            let q = [legs.leg[0][k], legs.leg[1][k], legs.leg[2][k]];
            let w: [f64; 3] = std::array::from_fn(|c| e1[c] * m0[0][k] + e2[c] * m0[1][k] + e3[c] * m0[2][k]);
            let along_n0 = q[0] * n0[0][k] + q[1] * n0[1][k] + q[2] * n0[2][k];
            let along_w = q[0] * w[0] + q[1] * w[1] + q[2] * w[2];
            base[k] = along_n0 * legs.inverse_length[k] - cos_base;
            platform[k] = along_w * legs.inverse_length[k] - cos_platform;
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
        self.body.baumgarte_rate = rate;
        self
    }

    /// The right-hand side `dy/dt` of the body state `y` for the leg forces `u`, and the leg
    /// powers (the integrands of `work.F` and `work.dissipated`): the definition.
    pub fn rate<T: Real>(&self, y: &[T; STATE_DIM], u: &[T; LEG_COUNT]) -> ([T; STATE_DIM], LegPower<T>) {
        let (rate, power, _) = self.rate_of(y, Actuation::Forces(u));
        (rate, power)
    }

    /// [`SpecialForm::rate`] with the legs driven by the electric drives (which must be on):
    /// the armature currents `I_k` (A) and voltages `U_k` (V) instead of the forces; also each
    /// drive's force, current rate and powers.
    pub fn rate_driven<T: Real>(
        &self,
        y: &[T; STATE_DIM],
        currents: &[T; LEG_COUNT],
        voltages: &[T; LEG_COUNT],
    ) -> ([T; STATE_DIM], LegPower<T>, [DriveRate<T>; LEG_COUNT]) {
        self.rate_of(y, Actuation::Drives { currents, voltages })
    }

    /// The definition, for either actuation.
    fn rate_of<T: Real>(
        &self,
        y: &[T; STATE_DIM],
        actuation: Actuation<'_, T>,
    ) -> ([T; STATE_DIM], LegPower<T>, [DriveRate<T>; LEG_COUNT]) {
        let state = BodyState::from_vector(y);
        let loads = self.loads(&state, actuation);
        let drives = loads.drives;
        let w = loads.wrench();
        let c = std::array::from_fn::<_, 3, _>(|a| state.e[a].cross(&state.e_dot[a]).dot(&w.moment));
        // `F.v + L.omega` of the actuator forces alone, with the inertial angular velocity
        // `omega = 1/2 sum_a e_a x e_a'`: `sum_k u_k ldot_k`.
        let power =
            LegPower { actuator: w.force.dot(&state.v) + (c[0] + c[1] + c[2]) * 0.5, dissipation: w.dissipation() };
        let (a, e_dd) = self.body.accelerations(&state, &w.total_force(), &w.total_moment());
        let mut dy = [T::zero(); STATE_DIM];
        let rates = [state.v, a, state.e_dot[0], state.e_dot[1], state.e_dot[2], e_dd[0], e_dd[1], e_dd[2]];
        for (i, v) in rates.iter().enumerate() {
            dy[3 * i..3 * i + 3].copy_from_slice(v.as_slice());
        }
        (dy, power, drives)
    }

    /// The force of each leg on the platform at its joint `A_k` (inertial components, N): what
    /// the joint must be sized for. `u`: the actuators' axial forces.
    pub fn joint_forces<T: Real>(&self, y: &[T; STATE_DIM], u: &[T; LEG_COUNT]) -> [Vector3<T>; LEG_COUNT] {
        let loads = self.loads(&BodyState::from_vector(y), Actuation::Forces(u));
        std::array::from_fn(|k| loads.actuator[k] + loads.stop[k] + loads.machine[k])
    }

    /// Each leg's load on the platform, by cause, leg by leg. A collapsed (or non-finite) leg
    /// carries nothing.
    fn loads<T: Real>(&self, state: &BodyState<T>, actuation: Actuation<'_, T>) -> Loads<T> {
        let legs = LegGeometry::new(&self.stand, state);
        let mut loads = Loads::new(legs.arm);
        let mut inertia = [None; LEG_COUNT];
        let drives = match actuation {
            Actuation::Drives { currents, voltages } => self.drives.map(|d| (d, currents, voltages)),
            Actuation::Forces(_) => None,
        };
        for k in 0..LEG_COUNT {
            let (leg, l) = (legs.leg[k], legs.length[k]);
            if !(l > T::zero()) {
                continue;
            }
            let a_dot = || state.v + state.body_vector_rate(&self.stand.platform_joints[k]);
            let motion = (!self.fast || self.joint_limits.is_some()).then(|| LegMotion::new(&leg, l, &a_dot()));
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
                let ldot = n.dot(&(state.v + state.body_vector_rate(&self.stand.platform_joints[k])));
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
    fn machine_load<T: Real>(
        &self,
        k: usize,
        state: &BodyState<T>,
        leg: &LegMotion<T>,
        inertia: Option<&LegInertia<T>>,
    ) -> MachineLoad<T> {
        let mut load =
            MachineLoad { force: Vector3::zeros(), moment: Vector3::zeros(), dissipation: T::zero(), acts: false };
        if !self.friction.is_zero() {
            let f = self.friction.force(leg.l_dot);
            load.force += leg.n * f;
            load.dissipation -= f * leg.l_dot;
            load.acts = true;
        }
        if let Some(limits) = &self.joint_limits {
            if let Some(c) = limits.base(k, &leg.n, &leg.n_dot) {
                load.force += c.on_leg / leg.l;
                load.dissipation += c.dissipation;
                load.acts = true;
            }
            let m0 = &limits.platform_reference[k];
            if let Some(c) = limits.platform(&leg.n, &leg.n_dot, &state.body_vector(m0), || state.body_vector_rate(m0))
            {
                load.force += c.on_leg / leg.l;
                load.moment += c.on_platform;
                load.dissipation += c.dissipation;
                load.acts = true;
            }
        }
        if let Some(inertia) = inertia {
            load.force += inertia.bias;
            load.acts = true;
        }
        load
    }

    /// The legs' inertia: the platform's accelerations `(r'', omega')` from its Newton-Euler
    /// equations with each joint's force `F0_k - M_k a_k''` (`a_k'' = r'' + omega' x rho_k +
    /// omega x (omega x rho_k)`), a symmetric positive definite 6x6 system; each leg's inertial
    /// force `-M_k a_k''` then joins its load.
    fn solve_inertia<T: Real>(
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
        // The system [[M I + sum M_k, -sum M_k [rho]x], [., J_w - sum [rho]x M_k [rho]x]], with
        // M_k = a I + c n n^T (a = I_t / l^2, c = m_r + m_a - a): each leg adds
        // c S S^T with S = (n, rho x n), and where a != 0 the point mass's
        // a [[I, -[rho]x], [[rho]x, |rho|^2 I - rho rho^T]]. Lower triangle only.
        let zero = T::zero();
        let mut a = [[zero; 6]; 6];
        for r in 0..3 {
            a[r][r] = T::constant(self.stand.mass);
            for c in 0..=r {
                a[3 + r][3 + c] = e[0][r] * e[0][c] * j[0] + e[1][r] * e[1][c] * j[1] + e[2][r] * e[2][c] * j[2];
            }
        }
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
            let (across, along) = (m.across, m.along - m.across);
            let rn = rho.cross(n);
            let s = [n.x, n.y, n.z, rn.x, rn.y, rn.z];
            for r in 0..6 {
                let sr = s[r] * along;
                for c in 0..=r {
                    a[r][c] += sr * s[c];
                }
            }
            if across.value() != 0.0 {
                // The point mass: a11 += a I, a21 += a [rho]x, a22 += a (|rho|^2 I - rho rho^T).
                let skew = [[zero, -rho.z, rho.y], [rho.z, zero, -rho.x], [-rho.y, rho.x, zero]];
                let rr = rho.dot(&rho);
                for r in 0..3 {
                    a[r][r] += across;
                    for c in 0..3 {
                        a[3 + r][c] += skew[r][c] * across;
                    }
                    for c in 0..=r {
                        let diagonal = if r == c { rr } else { zero };
                        a[3 + r][3 + c] += (diagonal - rho[r] * rho[c]) * across;
                    }
                }
            }
        }
        let q = solve_spd6(a, [force.x, force.y, force.z, moment.x, moment.y, moment.z]);
        let (alpha, beta) = (Vector3::new(q[0], q[1], q[2]), Vector3::new(q[3], q[4], q[5]));
        for k in 0..LEG_COUNT {
            if let Some((m, n)) = &inertia[k] {
                let rho = loads.arm[k];
                let acceleration = alpha + beta.cross(&rho) + omega.cross(&omega.cross(&rho));
                loads.machine[k] -= m.times(n, &acceleration);
            }
        }
    }

    /// Directional derivative (Jacobian-vector product) of [`SpecialForm::rate`]: the change
    /// of `dy/dt` and of the leg powers for a change `dy` of the state and `du` of the forces,
    /// exact (the definition evaluated on duals), for `fmi2GetDirectionalDerivative` and
    /// linearisation.
    pub fn derivative_tangent(
        &self,
        y: &StateVector,
        u: &[f64; LEG_COUNT],
        dy: &StateVector,
        du: &[f64; LEG_COUNT],
    ) -> (StateVector, LegPower) {
        let (rate, power) = self.rate(&Dual::seeded(y, dy), &Dual::seeded(u, du));
        (Dual::tangents(&rate), LegPower { actuator: power.actuator.eps, dissipation: power.dissipation.eps })
    }

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
        let (n, l_dot) = self.joints.directions_and_rates(&state, &leg, length, inverse_length);
        // The joints' velocities and the centripetal part of their accelerations.
        let [d1, d2, d3] = &state.e_dot;
        let a = components!(|c| PerLeg::<V>::new(&self.joints.platform[c]));
        let velocity = components!(|c| {
            PerLeg::splat(state.v[c])
                + (PerLeg::splat(d1[c]) * a[0] + PerLeg::splat(d2[c]) * a[1] + PerLeg::splat(d3[c]) * a[2])
        });
        let omega = state.angular_velocity_inertial();
        let w = components!(|c| PerLeg::<V>::splat(omega[c]));
        let whirl = PerLeg::cross(&w, &PerLeg::cross(&w, &arm));
        let speed2 = velocity[0] * velocity[0] + velocity[1] * velocity[1] + velocity[2] * velocity[2];
        let c = length.where_positive((speed2 - l_dot * l_dot) * inverse_length)
            + (n[0] * whirl[0] + n[1] * whirl[1] + n[2] * whirl[2]);
        // The drives.
        let ratio = drives.transmission();
        let (current, voltage) = (PerLeg::<V>::new(currents), PerLeg::<V>::new(voltages));
        let shaft = l_dot * PerLeg::splat(ratio);
        let drive_force =
            (current * PerLeg::splat(drives.kt) - shaft * PerLeg::splat(drives.damping)) * PerLeg::splat(ratio);
        let current_rate = (voltage - current * PerLeg::splat(drives.resistance) - shaft * PerLeg::splat(drives.ke))
            / PerLeg::splat(drives.inductance);
        let electric = voltage * current;
        let lost = current * current * PerLeg::splat(drives.resistance)
            + shaft * shaft * PerLeg::splat(drives.damping)
            + shaft * current * PerLeg::splat(drives.ke - drives.kt);
        // The end stops (rare: cold) and the joint limits (only where one may touch).
        let (stop, stop_dissipation) = match &self.stops {
            Some(stops) if length.any_outside(PerLeg::new(&self.stroke[0]), PerLeg::new(&self.stroke[1])) => {
                std::hint::cold_path();
                self.stop_forces_in(stops, &length, &l_dot)
            }
            _ => (PerLeg::splat(0.0), 0.0),
        };
        let machine = match &self.joint_limits {
            Some(_) if self.joints_may_touch(&state, &leg, length) => {
                std::hint::cold_path();
                self.machine_wrench(&state)
            }
            _ => None,
        };
        let m_a = self.legs.axial_mass;
        let b = length.where_positive(drive_force + stop - c * PerLeg::splat(m_a));
        let rn = PerLeg::cross(&arm, &n);
        let s = [n[0], n[1], n[2], rn[0], rn[1], rn[2]];
        // The system's lower triangle and right-hand side.
        let (mass, j, e) = (self.stand.mass, &self.stand.inertia, &state.e);
        let mut matrix = [[0.0; 6]; 6];
        for r in 0..6 {
            for col in 0..=r {
                matrix[r][col] = (s[r] * s[col]).sum() * m_a;
            }
        }
        for r in 0..3 {
            matrix[r][r] += mass;
            for col in 0..=r {
                matrix[3 + r][3 + col] +=
                    e[0][r] * e[0][col] * j[0] + e[1][r] * e[1][col] * j[1] + e[2][r] * e[2][col] * j[2];
            }
        }
        let j_w =
            |x: &Vector3<f64>| e[0] * (e[0].dot(x) * j[0]) + e[1] * (e[1].dot(x) * j[1]) + e[2] * (e[2].dot(x) * j[2]);
        let mut force = Vector3::new((b * n[0]).sum(), (b * n[1]).sum(), (b * n[2]).sum() - mass * self.stand.gravity);
        let mut moment =
            Vector3::new((b * rn[0]).sum(), (b * rn[1]).sum(), (b * rn[2]).sum()) - omega.cross(&j_w(&omega));
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
        let w = LegWrench {
            force: Vector3::new((f * n[0]).sum(), (f * n[1]).sum(), (f * n[2]).sum()),
            moment: Vector3::new((f * rn[0]).sum(), (f * rn[1]).sum(), (f * rn[2]).sum()),
            stop: StopWrench { dissipation: stop_dissipation, ..StopWrench::default() },
            machine,
        };
        let (e_rows, e_dot) = (AxisRows::<V::Axes>::of(&state.e), AxisRows::of(&state.e_dot));
        let (acceleration, e_dd) =
            self.body.accelerations_in(&state, &e_rows, &e_dot, &w.total_force(), &w.total_moment());
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
        DrivenRates {
            current_rate: current_rate.to_array(),
            electric_power: electric.sum(),
            dissipation: w.dissipation() + lost.sum(),
        }
    }

    /// The end stops' forces along the legs ([`EndStops::contact`], leg by leg: 0 inside the
    /// stroke) and their damping's power, for legs given side by side.
    #[inline(never)]
    fn stop_forces_in<V: Lanes>(&self, stops: &EndStops, length: &PerLeg<V>, l_dot: &PerLeg<V>) -> (PerLeg<V>, f64) {
        let (l, l_dot) = (length.to_array(), l_dot.to_array());
        let (mut force, mut dissipation) = ([0.0; LEG_COUNT], [0.0; LEG_COUNT]);
        for k in 0..LEG_COUNT {
            if l[k] > 0.0 && stops.is_outside(k, l[k]) {
                let contact = stops.contact(k, l[k], l_dot[k]);
                force[k] = contact.force;
                dissipation[k] = contact.dissipation;
            }
        }
        (PerLeg::new(&force), sum_over_legs(&dissipation))
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
        let (l, ldot) = (length.to_array(), ldot.to_array());
        let (mut force, mut dissipation) = ([0.0; LEG_COUNT], [0.0; LEG_COUNT]);
        for k in 0..LEG_COUNT {
            if l[k] > 0.0 && stops.is_outside(k, l[k]) {
                let contact = stops.contact(k, l[k], ldot[k]);
                force[k] = contact.force;
                dissipation[k] = contact.dissipation;
            }
        }
        let force = PerLeg::new(&force);
        let fs = components!(|c| n[c] * force);
        let moment = PerLeg::cross(arm, &fs);
        StopWrench {
            force: Vector3::new(fs[0].sum(), fs[1].sum(), fs[2].sum()),
            moment: Vector3::new(moment[0].sum(), moment[1].sum(), moment[2].sum()),
            dissipation: sum_over_legs(&dissipation),
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

/// What [`SpecialForm::derivative_driven_in`] gives besides the body's rates.
#[derive(Clone, Copy, Debug)]
pub(crate) struct DrivenRates {
    /// `I_k'`, A/s.
    pub current_rate: [f64; LEG_COUNT],
    /// `sum U_k I_k`, W.
    pub electric_power: f64,
    /// The stops', joint limits' and drives' losses, W.
    pub dissipation: f64,
}

/// What moves the legs: given forces, or the electric drives' currents and voltages.
#[derive(Clone, Copy)]
enum Actuation<'a, T> {
    Forces(&'a [T; LEG_COUNT]),
    Drives { currents: &'a [T; LEG_COUNT], voltages: &'a [T; LEG_COUNT] },
}

/// The fast path's joint check counts a joint within this of its limit's cosine as touching.
const JOINT_CHECK_MARGIN: f64 = 1e-9;

/// Solves `A x = b` for a symmetric positive definite 6x6 `A` given by its lower triangle
/// (Cholesky `A = L L^T`, the diagonal's reciprocals `d_i` kept); not numbers if `A` is not
/// positive definite. Written out: with loops the trip counts and index checks cost more
/// than the arithmetic.
#[inline(always)]
#[rustfmt::skip]
fn solve_spd6<T: Real>(a: [[T; 6]; 6], b: [T; 6]) -> [T; 6] {
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
struct Loads<T: nalgebra::Scalar> {
    /// `rho_k = R A_k`.
    arm: [Vector3<T>; LEG_COUNT],
    /// `u_k n_k`.
    actuator: [Vector3<T>; LEG_COUNT],
    /// The end stops' forces.
    stop: [Vector3<T>; LEG_COUNT],
    /// Each leg's stop damping power.
    stop_dissipation: [T; LEG_COUNT],
    /// Friction, the joint limits' forces and the legs' weight and inertia.
    machine: [Vector3<T>; LEG_COUNT],
    /// The platform joints' limit moments.
    machine_moment: [Vector3<T>; LEG_COUNT],
    /// The drives' forces, current rates and powers (zero without drives).
    drives: [DriveRate<T>; LEG_COUNT],
    machine_dissipation: T,
    /// Whether any of the machine's loads acts.
    machine_acts: bool,
}

/// One leg's machine load (see [`Loads::machine`]), without the leg's inertia.
struct MachineLoad<T: nalgebra::Scalar> {
    force: Vector3<T>,
    moment: Vector3<T>,
    dissipation: T,
    acts: bool,
}

impl<T: Real> Loads<T> {
    fn new(arm: [Vector3<T>; LEG_COUNT]) -> Self {
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

    fn add_machine(&mut self, k: usize, load: &MachineLoad<T>) {
        self.machine[k] += load.force;
        self.machine_moment[k] += load.moment;
        self.machine_dissipation += load.dissipation;
        self.machine_acts |= load.acts;
    }

    /// The machine's resultant, if it acts.
    fn machine_wrench(&self) -> Option<MachineWrench<T>> {
        self.machine_acts.then(|| MachineWrench {
            force: sum_vectors(&self.machine),
            moment: sum_vectors(&std::array::from_fn(|k| self.arm[k].cross(&self.machine[k]) + self.machine_moment[k])),
            dissipation: self.machine_dissipation,
        })
    }

    /// The resultant about the centre of mass, by cause, each summed over the legs in
    /// [`sum_over_legs`]'s order.
    fn wrench(&self) -> LegWrench<T> {
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

/// The powers of a right-hand-side evaluation (or their changes, from
/// [`SpecialForm::derivative_tangent`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LegPower<T = f64> {
    /// Power of the actuator forces, `sum_k F_k ldot_k = F.v + L.omega`, W.
    pub actuator: T,
    /// Power taken by the end stops' and joint limits' damping and by friction, W (>= 0).
    pub dissipation: T,
}

/// Resultant of the legs about the centre of mass: actuators, end stops and the machine
/// (friction, joint limits, the legs' weight and inertia) apart.
#[derive(Clone, Copy, Debug, Default)]
struct LegWrench<T: nalgebra::Scalar = f64> {
    force: Vector3<T>,
    moment: Vector3<T>,
    stop: StopWrench<T>,
    machine: Option<MachineWrench<T>>,
}

impl<T: Real> LegWrench<T> {
    /// `(actuators + stops) + machine`.
    #[inline(always)]
    fn total_force(&self) -> Vector3<T> {
        let f = self.force + self.stop.force;
        match &self.machine {
            Some(m) => f + m.force,
            None => f,
        }
    }

    #[inline(always)]
    fn total_moment(&self) -> Vector3<T> {
        let m = self.moment + self.stop.moment;
        match &self.machine {
            Some(machine) => m + machine.moment,
            None => m,
        }
    }

    #[inline(always)]
    fn dissipation(&self) -> T {
        match &self.machine {
            Some(m) => self.stop.dissipation + m.dissipation,
            None => self.stop.dissipation,
        }
    }
}

/// Resultant of the end stops' forces and the power their damping takes.
#[derive(Clone, Copy, Debug, Default)]
struct StopWrench<T: nalgebra::Scalar = f64> {
    force: Vector3<T>,
    moment: Vector3<T>,
    dissipation: T,
}

/// Resultant of the machine's loads and the power they take.
#[derive(Clone, Copy, Debug, Default)]
struct MachineWrench<T: nalgebra::Scalar = f64> {
    force: Vector3<T>,
    moment: Vector3<T>,
    dissipation: T,
}

#[cfg(test)]
mod tests {
    use nalgebra::Vector3;

    use super::*;
    use crate::physics::actuators::HeldForces;
    use crate::physics::body::kinematics::rotation_from_angles;
    use crate::physics::legs::end_stops::EndStops;
    use crate::physics::legs::per_leg::Wide;
    use crate::physics::legs::{bodies::LegBodies, friction::Friction, joint_limits::JointLimits};

    /// The same held forces seen as a law that depends on the state (through `LegGeometry`).
    struct ThroughGeometry(HeldForces);

    impl LegForceLaw for ThroughGeometry {
        fn leg_forces(&self, t: f64, _state: &BodyState, _legs: &LegGeometry) -> [f64; LEG_COUNT] {
            self.0.leg_forces_at(t)
        }
    }

    /// The fast path is the definition to the bit: legs and axes side by side in SSE2 (and,
    /// where the processor has it, AVX) registers against [`SpecialForm::rate`] leg by leg,
    /// inside the strokes and deep in both stops, on and beyond the joint limits, with and
    /// without Baumgarte terms, for held forces and for a law that depends on the state.
    #[test]
    fn the_fast_path_gives_the_bits_of_the_definition() {
        let stand = Stand::truck_cabin();
        let stops = EndStops::default();
        let law = HeldForces { value: [5900.0, -1200.0, 8000.0, 0.0, 3.5e4, 6100.0], slope: [10.0; 6], t0: 0.0 };
        let mut contacts = 0;
        let r0 = Stand::truck_cabin_neutral_position();
        let n0 = std::array::from_fn(|k| (r0 + stand.platform_joints[k] - stand.base_joints[k]).normalize());
        let limits = JointLimits::new(0.1, 0.15, 1e6, 5e4, n0, &nalgebra::Matrix3::identity());
        let mut joint_contacts = 0;
        for (rate, joints) in [(0.0, None), (10.0, None), (0.0, Some(limits)), (10.0, Some(limits))] {
            let form = SpecialForm::new(stand.clone())
                .with_end_stops(Some(stops))
                .with_baumgarte_rate(rate)
                .with_machine(LegBodies::default(), Friction::default(), joints);
            for (dz, roll, w) in [(0.0, 0.0, 0.0), (0.02, 0.05, 0.3), (-0.45, 0.1, -1.0), (0.45, -0.2, 2.0)] {
                let state = BodyState::from_pose(
                    Stand::truck_cabin_neutral_position() + Vector3::new(0.01, -0.02, dz),
                    Vector3::new(0.1, -0.3, 0.7),
                    &rotation_from_angles(&Vector3::new(roll, -0.04, 0.02)),
                    &Vector3::new(w, 0.2, -0.1),
                );
                let mut y = state.to_vector();
                y[10] += 1e-4; // off the constraint manifold: the Baumgarte terms act
                let legs = LegGeometry::new(&stand, &BodyState::from_vector(&y));
                contacts += (0..LEG_COUNT).filter(|&k| stops.is_outside(k, legs.length[k])).count();
                joint_contacts += usize::from(
                    form.loads(&BodyState::from_vector(&y), Actuation::Forces(&[0.0; LEG_COUNT])).machine_acts,
                );
                let (reference, p) = form.rate(&y, &law.leg_forces_at(0.3));
                let bits = |x: &[f64; 24]| x.map(f64::to_bits);
                for held in [true, false] {
                    let mut fast = [0.0; 24];
                    let q = if held {
                        form.derivative(0.3, &y, &law, &mut fast)
                    } else {
                        form.derivative(0.3, &y, &ThroughGeometry(law), &mut fast)
                    };
                    assert_eq!(bits(&fast), bits(&reference), "dz = {dz}, Baumgarte {rate}, held {held}");
                    assert_eq!(
                        (q.actuator.to_bits(), q.dissipation.to_bits()),
                        (p.actuator.to_bits(), p.dissipation.to_bits())
                    );
                }
                #[cfg(target_arch = "x86_64")]
                if std::arch::is_x86_feature_detected!("avx2") {
                    let mut wide = [0.0; 24];
                    // SAFETY: AVX2 detected just now.
                    let q = unsafe { wide_derivative(&form, &y, &law, &mut wide) };
                    assert_eq!(bits(&wide), bits(&reference), "AVX: dz = {dz}, Baumgarte {rate}");
                    assert_eq!(q, p);
                }
            }
        }
        assert!(contacts >= 12, "the end-stop branch was exercised ({contacts} legs in contact)");
        assert!(joint_contacts >= 2, "the joint-limit branch was exercised ({joint_contacts} states)");
    }

    /// The drives' fast path is the definition (`rate_driven`) to round-off: massless legs with
    /// the rotors' axial mass, on and off the end stops and the joint limits, with Baumgarte
    /// terms, in SSE2 and AVX2.
    #[test]
    fn the_drives_fast_path_is_the_definition_to_round_off() {
        use crate::physics::actuators::drives::ElectricDrives;
        let stand = Stand::truck_cabin();
        let stops = EndStops::default();
        let r0 = Stand::truck_cabin_neutral_position();
        let n0 = std::array::from_fn(|k| (r0 + stand.platform_joints[k] - stand.base_joints[k]).normalize());
        let limits = JointLimits::new(0.1, 0.15, 1e6, 5e4, n0, &nalgebra::Matrix3::identity());
        let currents = [18.0, -4.0, 25.0, 30.0, 11.0, 19.5];
        let voltages = [7.5, 120.0, -80.0, 0.0, 250.0, 40.0];
        let (mut worst, mut contacts, mut joint_contacts): (f64, usize, usize) = (0.0, 0, 0);
        for (rate, joints) in [(0.0, None), (10.0, Some(limits))] {
            let form = SpecialForm::new(stand.clone())
                .with_end_stops(Some(stops))
                .with_baumgarte_rate(rate)
                .with_machine(LegBodies::default(), Friction::default(), joints)
                .with_drives(Some(ElectricDrives::default()));
            assert!(form.has_driven_fast_path());
            for (dz, roll, w) in [(0.0, 0.0, 0.0), (0.02, 0.05, 0.3), (-0.45, 0.1, -1.0), (0.45, -0.2, 2.0)] {
                let state = BodyState::from_pose(
                    Stand::truck_cabin_neutral_position() + Vector3::new(0.01, -0.02, dz),
                    Vector3::new(0.1, -0.3, 0.7),
                    &rotation_from_angles(&Vector3::new(roll, -0.04, 0.02)),
                    &Vector3::new(w, 0.2, -0.1),
                );
                let mut y = state.to_vector();
                y[10] += 1e-4;
                let legs = LegGeometry::new(&stand, &BodyState::from_vector(&y));
                contacts += (0..LEG_COUNT).filter(|&k| stops.is_outside(k, legs.length[k])).count();
                joint_contacts += usize::from(
                    form.loads(&BodyState::from_vector(&y), Actuation::Forces(&[0.0; LEG_COUNT])).machine_acts,
                );
                let (reference, power, drives) = form.rate_driven(&y, &currents, &voltages);
                let mut fast = [0.0; 24];
                let rates = form.derivative_driven_in::<Narrow>(&y, &currents, &voltages, &mut fast);
                let scale = reference.iter().fold(1.0f64, |m, x| m.max(x.abs()));
                let mut error = (0..24).map(|i| (fast[i] - reference[i]).abs()).fold(0.0, f64::max) / scale;
                let lost = power.dissipation + sum_over_legs(&drives.map(|d| d.dissipation));
                let electric = sum_over_legs(&drives.map(|d| d.electric_power));
                error = error.max((rates.dissipation - lost).abs() / lost.abs().max(1.0));
                error = error.max((rates.electric_power - electric).abs() / electric.abs().max(1.0));
                for k in 0..LEG_COUNT {
                    let r = drives[k].current_rate;
                    error = error.max((rates.current_rate[k] - r).abs() / r.abs().max(1.0));
                }
                #[cfg(target_arch = "x86_64")]
                if std::arch::is_x86_feature_detected!("avx2") {
                    let mut wide = [0.0; 24];
                    // SAFETY: AVX2 detected just now.
                    unsafe { wide_driven(&form, &y, &currents, &voltages, &mut wide) };
                    error = error.max((0..24).map(|i| (wide[i] - reference[i]).abs()).fold(0.0, f64::max) / scale);
                }
                worst = worst.max(error);
            }
        }
        println!("drives' fast path against the definition: largest relative difference {worst:.1e}");
        assert!(worst < 1e-12, "{worst:e}");
        assert!(contacts >= 6 && joint_contacts >= 1, "contacts exercised: stops {contacts}, joints {joint_contacts}");
    }

    /// # Safety
    /// AVX2 must be available.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx,avx2,fma")]
    unsafe fn wide_driven(
        form: &SpecialForm,
        y: &StateVector,
        currents: &[f64; LEG_COUNT],
        voltages: &[f64; LEG_COUNT],
        dy: &mut StateVector,
    ) {
        form.derivative_driven_in::<Wide>(y, currents, voltages, dy);
    }

    /// # Safety
    /// AVX2 must be available.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx,avx2,fma")]
    unsafe fn wide_derivative(form: &SpecialForm, y: &StateVector, law: &HeldForces, dy: &mut StateVector) -> LegPower {
        form.derivative_in::<HeldForces, Wide>(0.3, y, law, dy)
    }
}
