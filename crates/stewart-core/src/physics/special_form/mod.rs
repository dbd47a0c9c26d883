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
//! path: for massless legs without friction the same operations in the same order with the six
//! legs side by side in vector registers ([`PerLeg`]) and the three axes likewise
//! ([`AxisRows`]), pinned to the definition bit for bit by a test; for the machine (legs with
//! mass, friction, drives) the same laws in lanes with the sums over the legs in another order
//! (`derivative_machine_in`), pinned to the definition to round-off.
//!
//! Files: this one holds the definition and the types; `machine.rs` the machine's loads leg
//! by leg and the heavy legs' 6x6 solve; `fast_path.rs` the lanes forms; `body_rate.rs` the
//! two ways an actuator's rate evaluates the body (the definition and the fast path:
//! [`super::actuators::BodyRate`]).

mod body_rate;
mod fast_path;
mod machine;
#[cfg(test)]
mod tests;

use nalgebra::Vector3;

use super::actuators::drives::{DriveRate, ElectricDrives};
use super::actuators::forces::ForceInputs;
use super::actuators::hydraulics::HydraulicActuators;
use super::actuators::{ActiveActuator, LegForceLaw};
pub use super::actuators::{DrivenRates, LegPower};
use super::body::accelerations::RigidBody;
use super::body::per_axis::AxisRows;
use super::body::state::{BodyState, STATE_DIM, StateVector, axes_rates};
use super::legs::bodies::{LegBodies, LegInertia, LegMotion};
use super::legs::end_stops::EndStops;
use super::legs::friction::Friction;
use super::legs::geometry::{JointArrays, LegGeometry, LegKinematics, LegLanes};
use super::legs::joint_limits::JointLimits;
use super::legs::per_leg::{Lanes, Narrow, PerLeg, components};
use super::number::{Dual, Number, Real};
use super::stand::{LEG_COUNT, Stand};
use crate::maths;
pub use body_rate::{Definition, FastPath};

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
    /// The actuator in the legs (the paper's: the forces are given). The electric drives' law
    /// runs at each leg's rate in the machine's path; the hydraulic legs' force comes from their
    /// chambers' pressures (states), a given force to the body.
    actuator: ActiveActuator,
    /// For the fast path's check and the switching functions of the joint limits: `n0_k` and
    /// `m0_k` as `[component][leg]`, and the reference pose's axes `e0_a`.
    base_reference: [[f64; LEG_COUNT]; 3],
    platform_reference: [[f64; LEG_COUNT]; 3],
    reference_axes: [Vector3<f64>; 3],
    /// `cos thetaMax` of the base joints, `cos` and `sin thetaMax` of the platform joints.
    joint_cosines: [f64; 3],
    /// Whether the legs have mass or inertia ([`LegBodies::has_mass`]) and whether they resist
    /// turning ([`LegBodies::has_transverse_inertia`]), kept beside `legs` for the fast path.
    legs_mass: bool,
    legs_turn: bool,
    /// Whether the paper's legs' fast path applies (massless legs without friction, forces
    /// given); otherwise the machine's takes the step.
    fast: bool,
}

pub(crate) use super::legs::per_leg::sum_over_legs;

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
            actuator: ActiveActuator::Forces(ForceInputs),
            base_reference: [[0.0; LEG_COUNT]; 3],
            platform_reference: [[0.0; LEG_COUNT]; 3],
            reference_axes: [Vector3::x(), Vector3::y(), Vector3::z()],
            joint_cosines: [-1.0, -1.0, 0.0],
            fast: true,
            legs_mass: false,
            legs_turn: false,
            stand,
        }
    }

    /// The same form with the machine's legs: bodies, friction and joint limits (`None`:
    /// without).
    pub fn with_machine(mut self, legs: LegBodies, friction: Friction, joint_limits: Option<JointLimits>) -> Self {
        // The actuator's axial mass (the drives' rotors) stays (set by `with_actuator`).
        self.legs = LegBodies { axial_mass: self.legs.axial_mass, ..legs };
        self.friction = friction;
        if let Some(j) = &joint_limits {
            self.base_reference = std::array::from_fn(|c| j.base_reference.map(|n| n[c]));
            self.platform_reference = std::array::from_fn(|c| j.platform_reference.map(|m| m[c]));
            self.reference_axes = j.reference_axes;
            self.joint_cosines = [maths::cos(j.base_max), maths::cos(j.platform_max), maths::sin(j.platform_max)];
        }
        self.joint_limits = joint_limits;
        self.fast = self.takes_fast_path();
        (self.legs_mass, self.legs_turn) = (self.legs.has_mass(), self.legs.has_transverse_inertia());
        self
    }

    /// The same form with the actuator `actuator` in the legs; a mass moving with the legs'
    /// lengths (the drives' rotors) joins the legs' inertia.
    pub fn with_actuator(mut self, actuator: ActiveActuator) -> Self {
        self.legs.axial_mass = actuator.axial_mass();
        self.actuator = actuator;
        self.fast = self.takes_fast_path();
        (self.legs_mass, self.legs_turn) = (self.legs.has_mass(), self.legs.has_transverse_inertia());
        self
    }

    /// The actuator in the legs.
    pub fn actuator(&self) -> &ActiveActuator {
        &self.actuator
    }

    /// The same form with electric drives in the legs (`None`: without them, the forces given).
    pub fn with_drives(self, drives: Option<ElectricDrives>) -> Self {
        match drives {
            Some(d) => self.with_actuator(ActiveActuator::Electric(d)),
            None if self.drives().is_some() => self.with_actuator(ActiveActuator::Forces(ForceInputs)),
            None => self,
        }
    }

    /// The electric drives, if on.
    pub fn drives(&self) -> Option<&ElectricDrives> {
        match &self.actuator {
            ActiveActuator::Electric(d) => Some(d),
            _ => None,
        }
    }

    /// The same form with hydraulic servo legs (`None`: without them, the forces given).
    pub fn with_hydraulics(self, hydraulics: Option<HydraulicActuators>) -> Self {
        match hydraulics {
            Some(h) => self.with_actuator(ActiveActuator::Hydraulic(h)),
            None if self.hydraulics().is_some() => self.with_actuator(ActiveActuator::Forces(ForceInputs)),
            None => self,
        }
    }

    /// The hydraulic legs, if on.
    pub fn hydraulics(&self) -> Option<&HydraulicActuators> {
        match &self.actuator {
            ActiveActuator::Hydraulic(h) => Some(h),
            _ => None,
        }
    }

    /// The hydraulic supply's inputs held over a step (`pS`, `pump.speed`; 0 without hydraulic
    /// legs), in the number type `T`.
    #[inline(always)]
    pub fn supply<T: crate::physics::number::Real>(&self) -> crate::physics::actuators::Supply<T> {
        let (pressure, pump_speed) = self.hydraulics().map_or((0.0, 0.0), |h| (h.supply, h.pump_speed));
        crate::physics::actuators::Supply { pressure: T::constant(pressure), pump_speed: T::constant(pump_speed) }
    }

    /// Sets the power unit's `pump.speed` (1) of the hydraulic legs, if on: an input held over a
    /// step.
    pub fn set_pump_speed(&mut self, speed: f64) {
        if let ActiveActuator::Hydraulic(h) = &mut self.actuator {
            h.pump_speed = speed;
        }
    }

    /// Sets the supply pressure `p_S` (Pa) of the hydraulic legs, if on: an input held over a
    /// step.
    pub fn set_supply_pressure(&mut self, supply: f64) {
        if let ActiveActuator::Hydraulic(h) = &mut self.actuator {
            h.supply = supply;
        }
    }

    /// The actuator takes the inputs its parameters hold (the hydraulic supply pressure) from
    /// `from` ([`super::actuators::Actuator::take_inputs`]).
    pub fn take_actuator_inputs(&mut self, from: &super::actuators::Actuators) {
        self.actuator.take_inputs(from);
    }

    /// Whether the step's fast path applies: massless legs without friction, forces given (no
    /// actuator whose law runs at each leg's rate).
    fn takes_fast_path(&self) -> bool {
        !self.legs.has_mass() && self.friction.is_zero() && !self.actuator.at_leg_rates()
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
    /// state, the six legs side by side in lanes `V` (the checks take [`Lanes::Checks`]): the
    /// same bits in any.
    #[inline(always)]
    pub fn joint_margins<V: Lanes>(
        &self,
        state: &BodyState,
        legs: &LegKinematics,
        base: &mut [f64; LEG_COUNT],
        platform: &mut [f64; LEG_COUNT],
    ) {
        let [cos_base, cos_platform, _] = self.joint_cosines;
        let [e1, e2, e3] = &state.e;
        let q = components!(|c| PerLeg::<V>::new(&legs.leg[c]));
        let n0 = components!(|c| PerLeg::<V>::new(&self.base_reference[c]));
        let m0 = components!(|c| PerLeg::<V>::new(&self.platform_reference[c]));
        // The platform joints' reference axes `R m0_k`, inertial components.
        let w = components!(|c| m0[0] * e1[c] + m0[1] * e2[c] + m0[2] * e3[c]);
        let along_n0 = q[0] * n0[0] + q[1] * n0[1] + q[2] * n0[2];
        let along_w = q[0] * w[0] + q[1] * w[1] + q[2] * w[2];
        let inverse_length = PerLeg::<V>::new(&legs.inverse_length);
        *base = (along_n0 * inverse_length - cos_base).to_array();
        *platform = (along_w * inverse_length - cos_platform).to_array();
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
}

/// What [`SpecialForm::derivative_machine_in`] gives besides the body's rates.
pub(crate) type MachineRates = DrivenRates;

/// What moves the legs: given forces, or the electric drives' currents and voltages.
#[derive(Clone, Copy)]
pub(crate) enum Actuation<'a, T> {
    Forces(&'a [T; LEG_COUNT]),
    Drives { currents: &'a [T; LEG_COUNT], voltages: &'a [T; LEG_COUNT] },
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
