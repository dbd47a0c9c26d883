//! [`PlatformSimulation`]: one stand, one state, one integrator.

use crate::integration::{
    Crossing, CrossingLog, IntegrationError, Integrator, LinearDecay, MAX_SWITCHING, OdeSystem, SolverSettings,
    SwitchingKind, SwitchingSides,
};
use crate::physics::actuators::HeldForces;
use crate::physics::actuators::drives::{DriveRate, ElectricDrives};
use crate::physics::actuators::hydraulics::{Chambers, HydraulicActuators};
use crate::physics::body::state::{BodyState, STATE_DIM, StateVector, all_finite};
use crate::physics::number::Real;
use std::cell::Cell;

use super::outputs::LegOutputs;
use crate::physics::actuators::LegForceLaw;
use crate::physics::body::projection::project_onto_constraints_in;
use crate::physics::configuration::ConfigurationGuard;
use crate::physics::direct_problem::{force_moment_determinant, singular_legs};
use crate::physics::error::{ParameterError, PhysicsFault};
use crate::physics::legs::bodies::LegBodies;
use crate::physics::legs::end_stops::{EndStops, STROKE_LIMITS};
use crate::physics::legs::friction::Friction;
use crate::physics::legs::geometry::{LegGeometry, LegKinematics};
use crate::physics::legs::joint_limits::JointLimits;
use crate::physics::legs::per_leg::{Lanes, Narrow};
use crate::physics::special_form::{Actuation, SpecialForm, sum_over_legs};
use crate::physics::stand::{LEG_COUNT, Stand};
use std::marker::PhantomData;

use super::vector::VectorPath;

/// Length of the simulation state: the 24 special-form coordinates, the work of the
/// actuator forces and the energy dissipated (quadratures integrated with the motion, so that
/// the energy balance holds to the integration tolerance), the drives' six armature currents
/// and the electric energy supplied, then the hydraulic legs' 12 chamber pressures, 6 spool
/// positions and rates and the hydraulic and compression work (each 0 and constant when its
/// actuator is off).
pub const SIMULATION_DIM: usize = STATE_DIM + 35;

/// The length of the state without drives or hydraulics: the trailing components stay 0, and
/// the methods step as they would without them ([`OdeSystem::active_dimension`]).
const WITHOUT_DRIVES: usize = STATE_DIM + 2;
/// The length of the state with drives (the hydraulic components stay 0), and the length the
/// integrators step without hydraulic legs ([`MECHANICAL_DIM`]).
const WITH_DRIVES: usize = STATE_DIM + 9;

/// The leading part of a [`SimulationState`] the integrators step when the hydraulic legs are
/// off (their components are then 0 and constant): the shorter arrays keep the force inputs'
/// and the drives' steps as cheap as before the hydraulics ([`PlatformSimulation::advance`]).
pub const MECHANICAL_DIM: usize = WITH_DRIVES;
const _: () = assert!(MECHANICAL_DIM <= SIMULATION_DIM, "the leading part of the state");

/// The simulation state, `r, v, e1, e2, e3, e1', e2', e3', W_F, W_d, I_1..I_6, W_e, p_A1..6,
/// p_B1..6, s_1..6, s_1'..6', W_h, W_c`.
pub type SimulationState = [f64; SIMULATION_DIM];

/// Offsets of the quadratures in a [`SimulationState`].
pub mod quadrature {
    /// `work.F = integral of sum_k F_k ldot_k dt`, J.
    pub const WORK_F: usize = super::STATE_DIM;
    /// `work.dissipated = integral of P_d dt`, J.
    pub const WORK_DISSIPATED: usize = super::STATE_DIM + 1;
    /// `work.electric = integral of sum_k U_k I_k dt`, J.
    pub const WORK_ELECTRIC: usize = super::STATE_DIM + 8;
    /// `work.hydraulic = integral of sum_k P_S,k dt`, J.
    pub const WORK_HYDRAULIC: usize = super::STATE_DIM + 33;
    /// `work.compression = integral of sum_k (p_A V_A p_A' + p_B V_B p_B') / beta dt`, J.
    pub const WORK_COMPRESSION: usize = super::STATE_DIM + 34;
}

/// Offsets of the hydraulic legs' states in a [`SimulationState`]: `p_A`, `p_B` (Pa), the
/// spools' positions `s` and rates `s'` (1/s), six each.
pub mod hydraulic {
    pub const PA: usize = super::STATE_DIM + 9;
    pub const PB: usize = PA + 6;
    pub const SPOOL: usize = PB + 6;
    pub const SPOOL_RATE: usize = SPOOL + 6;
}

/// Offset of the drives' armature currents `I_1..I_6` (A) in a [`SimulationState`].
pub const CURRENTS: usize = STATE_DIM + 2;

/// The drives' forces and rates at the simulation state `y` and voltages `inputs` (`None`
/// without drives).
fn drive_rates<T: Real>(
    form: &SpecialForm,
    y: &[T; SIMULATION_DIM],
    inputs: &[T; LEG_COUNT],
) -> Option<[DriveRate<T>; LEG_COUNT]> {
    form.drives()?;
    let zero = [T::zero(); STATE_DIM];
    let currents: [T; LEG_COUNT] = std::array::from_fn(|k| y[CURRENTS + k]);
    form.drive_rates(&BodyState::from_vector(y.first_chunk::<STATE_DIM>().unwrap_or(&zero)), &currents, inputs)
}

/// The axial forces the actuators exert at the simulation state `y` for the inputs: the
/// inputs themselves (leg forces `F`), with drives the forces of their currents, with
/// hydraulic legs those of their chamber pressures.
pub fn actuator_forces<T: Real>(
    form: &SpecialForm,
    y: &[T; SIMULATION_DIM],
    inputs: &[T; LEG_COUNT],
) -> [T; LEG_COUNT] {
    if let Some(h) = form.hydraulics() {
        let (area_a, area_b) = h.legs.areas();
        return std::array::from_fn(|k| y[hydraulic::PA + k] * area_a - y[hydraulic::PB + k] * area_b);
    }
    drive_rates(form, y, inputs).map_or(*inputs, |d| d.map(|k| k.force))
}

/// `Qsupply`, m³/s: the flow the six valves draw from the supply at the simulation state `y`
/// (0 without hydraulic legs).
pub fn supply_flow(form: &SpecialForm, y: &SimulationState) -> f64 {
    let Some(h) = form.hydraulics() else { return 0.0 };
    let state = BodyState::from_vector(body(y));
    let legs = LegGeometry::new(&form.stand, &state);
    let l_dot = legs.length_rates(&form.stand, &state);
    let flows: [f64; LEG_COUNT] = std::array::from_fn(|k| {
        let chambers = Chambers {
            pa: y[hydraulic::PA + k],
            pb: y[hydraulic::PB + k],
            spool: y[hydraulic::SPOOL + k],
            spool_rate: y[hydraulic::SPOOL_RATE + k],
        };
        h.legs.rate(&chambers, &h.piston(k, legs.length[k], l_dot[k]), 0.0, h.supply).supply_flow
    });
    sum_over_legs(&flows)
}

/// The hydraulic legs' rates at the simulation state `y` (legs of lengths `l`, rates `l_dot`)
/// for the valve commands `valves` and the supply pressure `supply`, written into `dy`; returns
/// the forces `u_k` and the sums of the supply power, the compression power and the losses.
#[inline(always)]
fn hydraulic_rates<T: Real>(
    h: &HydraulicActuators,
    y: &[T; SIMULATION_DIM],
    l: &[T; LEG_COUNT],
    l_dot: &[T; LEG_COUNT],
    valves: &[T; LEG_COUNT],
    supply: T,
    dy: &mut [T; SIMULATION_DIM],
) -> ([T; LEG_COUNT], [T; 3]) {
    let mut u = [T::zero(); LEG_COUNT];
    let mut powers = [[T::zero(); LEG_COUNT]; 3];
    for k in 0..LEG_COUNT {
        let chambers = Chambers {
            pa: y[hydraulic::PA + k],
            pb: y[hydraulic::PB + k],
            spool: y[hydraulic::SPOOL + k],
            spool_rate: y[hydraulic::SPOOL_RATE + k],
        };
        let command = valves[k].clamp_to(T::constant(-1.0), T::constant(1.0));
        let r = h.legs.rate(&chambers, &h.piston(k, l[k], l_dot[k]), command, supply);
        dy[hydraulic::PA + k] = r.pa_rate;
        dy[hydraulic::PB + k] = r.pb_rate;
        dy[hydraulic::SPOOL + k] = r.spool_rate;
        dy[hydraulic::SPOOL_RATE + k] = r.spool_acceleration;
        u[k] = r.force;
        powers[0][k] = r.supply_power;
        powers[1][k] = r.compression_power;
        powers[2][k] = r.dissipation;
    }
    (u, powers.map(|p| sum_over_legs(&p)))
}

/// The rate of a simulation state `y` for the inputs `inputs` (the leg forces `F`, N, with
/// drives the voltages `U`, V, with hydraulic legs the valve commands), in any number type:
/// the definition Model Exchange and the exact derivatives use, and the steps' fast paths
/// follow (bit for bit or to round-off: `crate::physics::special_form`). With drives or
/// hydraulics, `work.F` stays 0: their forces are internal, their energy comes in as
/// `work.electric` or `work.hydraulic`.
pub fn state_rate<T: Real>(
    form: &SpecialForm,
    y: &[T; SIMULATION_DIM],
    inputs: &[T; LEG_COUNT],
) -> [T; SIMULATION_DIM] {
    let supply = T::constant(form.hydraulics().map_or(0.0, |h| h.supply));
    state_rate_supplied(form, y, inputs, supply)
}

/// [`state_rate`] with the hydraulic supply pressure `supply` (Pa) in the number type (for
/// derivatives with respect to `pS`); without hydraulics it is not used.
pub fn state_rate_supplied<T: Real>(
    form: &SpecialForm,
    y: &[T; SIMULATION_DIM],
    inputs: &[T; LEG_COUNT],
    supply: T,
) -> [T; SIMULATION_DIM] {
    let zero = [T::zero(); STATE_DIM];
    let b = y.first_chunk::<STATE_DIM>().unwrap_or(&zero);
    let mut dy = [T::zero(); SIMULATION_DIM];
    if let Some(h) = form.hydraulics() {
        let state = BodyState::from_vector(b);
        let legs = LegGeometry::new(&form.stand, &state);
        let l_dot = legs.length_rates(&form.stand, &state);
        let (u, [supplied, compression, losses]) = hydraulic_rates(h, y, &legs.length, &l_dot, inputs, supply, &mut dy);
        let (rate, power) = form.rate(b, &u);
        if let Some(head) = dy.first_chunk_mut::<STATE_DIM>() {
            *head = rate;
        }
        dy[quadrature::WORK_DISSIPATED] = power.dissipation + losses;
        dy[quadrature::WORK_HYDRAULIC] = supplied;
        dy[quadrature::WORK_COMPRESSION] = compression;
        return dy;
    }
    if form.drives().is_none() {
        let (rate, power) = form.rate(b, inputs);
        if let Some(head) = dy.first_chunk_mut::<STATE_DIM>() {
            *head = rate;
        }
        dy[quadrature::WORK_F] = power.actuator;
        dy[quadrature::WORK_DISSIPATED] = power.dissipation;
        return dy;
    }
    let currents: [T; LEG_COUNT] = std::array::from_fn(|k| y[CURRENTS + k]);
    let (rate, power, drives) = form.rate_driven(b, &currents, inputs);
    if let Some(head) = dy.first_chunk_mut::<STATE_DIM>() {
        *head = rate;
    }
    dy[quadrature::WORK_DISSIPATED] = power.dissipation + sum_over_legs(&drives.map(|d| d.dissipation));
    dy[quadrature::WORK_ELECTRIC] = sum_over_legs(&drives.map(|d| d.electric_power));
    for k in 0..LEG_COUNT {
        dy[CURRENTS + k] = drives[k].current_rate;
    }
    dy
}

/// The switching functions of a platform: where the motion is not smooth or is worth
/// reporting.
pub mod switching {
    /// `l_k - lmin_k`, k = 0..5 (a sign change is a contact onset or release at a lower stop).
    pub const LOWER: usize = 0;
    /// `lmax_k - l_k`, k = 0..5.
    pub const UPPER: usize = 6;
    /// Determinant of the force/moment matrix: a sign change is a passage through a singular
    /// leg arrangement.
    pub const DETERMINANT: usize = 12;
    /// `cos thetaB_k - cos thetaMax_B`, k = 0..5 (a sign change is a base joint reaching or
    /// leaving its angle limit).
    pub const BASE_JOINT: usize = 13;
    /// `cos thetaA_k - cos thetaMax_A`, k = 0..5 (the platform joints).
    pub const PLATFORM_JOINT: usize = 19;
    pub const COUNT: usize = 25;
}

/// The special-form body coordinates of a simulation state.
#[inline(always)]
pub fn body<const N: usize>(y: &[f64; N]) -> &StateVector {
    y.first_chunk::<STATE_DIM>().unwrap_or(&[0.0; STATE_DIM])
}

/// How the constraints `e_a . e_b = delta_ab` are kept during integration.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stabilisation {
    /// None: the constraint residual drifts with the integration error (to show the drift).
    None,
    /// Project the state onto the constraint manifold and its tangent space after every
    /// internal step (the default).
    Projection,
    /// Baumgarte terms in the derivatives (`SpecialForm::baumgarte_rate`), no projection:
    /// what Model Exchange uses, where the host's integrator owns the state.
    Baumgarte,
}

impl Stabilisation {
    /// FMI enumeration value (`solver.stabilisation`).
    pub fn code(self) -> i32 {
        match self {
            Stabilisation::None => 1,
            Stabilisation::Projection => 2,
            Stabilisation::Baumgarte => 3,
        }
    }

    pub fn from_code(code: i32) -> Option<Self> {
        match code {
            1 => Some(Stabilisation::None),
            2 => Some(Stabilisation::Projection),
            3 => Some(Stabilisation::Baumgarte),
            _ => None,
        }
    }
}

/// The special-form equations with a force law, plus the work quadratures, as an ODE system
/// for the integrators, computed in lanes `V` ([`Lanes`]: the same numbers in each; which one
/// a step uses is chosen in [`super::vector`]).
pub struct PlatformDynamics<'a, L: ?Sized, V: Lanes = Narrow> {
    pub form: &'a SpecialForm,
    pub law: &'a L,
    pub stabilisation: Stabilisation,
    pub guard: &'a ConfigurationGuard,
    /// Whether a passage through a singular leg arrangement stops the integration.
    pub stop_at_singularity: bool,
    /// Whether the determinant switching function is evaluated (see
    /// [`PlatformSimulation::track_singularities`]); the stroke margins always are.
    pub track_singularities: bool,
    /// Lengths and rates of the legs of the last state [`OdeSystem::check`] accepted: after an
    /// integration, those of its end state (the check is the last thing a step does), so that
    /// the outputs `l` and `ldot` cost no second computation of the legs.
    pub checked_legs: Cell<Option<LegOutputs>>,
    /// The lowest chamber pressure (Pa) of the states [`OdeSystem::check`] accepted (hydraulic
    /// legs; `+inf` before any).
    pub lowest_pressure: Cell<f64>,
    lanes: PhantomData<V>,
}

/// The fraction of RK4's real stability interval (2.785) a hydraulic step may use: the fast
/// rates grow within a step as a land's drop shrinks.
const STABLE_STEP_FACTOR: f64 = 2.0;

impl<'a, L: ?Sized> PlatformDynamics<'a, L> {
    /// Dynamics that evaluate every switching function (singular arrangements tracked).
    pub fn new(
        form: &'a SpecialForm,
        law: &'a L,
        stabilisation: Stabilisation,
        guard: &'a ConfigurationGuard,
        stop_at_singularity: bool,
    ) -> Self {
        PlatformDynamics {
            form,
            law,
            stabilisation,
            guard,
            stop_at_singularity,
            track_singularities: true,
            checked_legs: Cell::new(None),
            lowest_pressure: Cell::new(f64::INFINITY),
            lanes: PhantomData,
        }
    }
}

impl<'a, L: ?Sized, V: Lanes> PlatformDynamics<'a, L, V> {
    /// The same dynamics computed in lanes `W`.
    #[cfg_attr(not(all(target_arch = "x86_64", feature = "avx2")), allow(dead_code))]
    pub(crate) fn in_lanes<W: Lanes>(&self) -> PlatformDynamics<'a, L, W> {
        PlatformDynamics {
            form: self.form,
            law: self.law,
            stabilisation: self.stabilisation,
            guard: self.guard,
            stop_at_singularity: self.stop_at_singularity,
            track_singularities: self.track_singularities,
            checked_legs: Cell::new(None),
            lowest_pressure: Cell::new(f64::INFINITY),
            lanes: PhantomData,
        }
    }

    /// The hydraulic legs' chambers at an accepted state: each volume must stay positive (a
    /// leg far beyond its stroke, through its stop); the lowest pressure is recorded.
    #[inline(never)]
    fn check_chambers(&self, h: &HydraulicActuators, y: &[f64], l: &[f64; LEG_COUNT]) -> Result<(), PhysicsFault> {
        let mut lowest = self.lowest_pressure.get();
        for k in 0..LEG_COUNT {
            let (va, vb) = h.legs.volumes(&h.piston(k, l[k], 0.0));
            if !(va > 0.0 && vb > 0.0) {
                return Err(PhysicsFault::ChamberEmptied { leg: k + 1, length: l[k] });
            }
            let pressure = |i: usize| y.get(i).copied().unwrap_or(f64::NAN);
            lowest = lowest.min(pressure(hydraulic::PA + k)).min(pressure(hydraulic::PB + k));
        }
        self.lowest_pressure.set(lowest);
        Ok(())
    }

    fn tracks_singularities(&self) -> bool {
        self.track_singularities || self.stop_at_singularity
    }
}

impl<L: LegForceLaw + ?Sized, V: Lanes> PlatformDynamics<'_, L, V> {
    /// The values of all switching functions of a body state (see [`switching`]), the
    /// determinant included whether it is tracked or not (Model Exchange event indicators).
    #[inline(always)]
    pub fn switching_values(&self, y: &StateVector, g: &mut [f64]) {
        let state = BodyState::from_vector(y);
        let legs = self.form.joints.kinematics(&state);
        self.switching_of(&state, &legs, g, true);
    }

    #[inline(always)]
    fn switching_of(&self, state: &BodyState, legs: &LegKinematics, g: &mut [f64], with_determinant: bool) {
        match self.form.stops() {
            Some(stops) => stops.stroke_margins(&legs.lengths(), g),
            None => {
                for x in g.iter_mut().take(STROKE_LIMITS) {
                    *x = 1.0;
                }
            }
        }
        if let Some(x) = g.get_mut(switching::DETERMINANT) {
            *x = if with_determinant { force_moment_determinant(legs, self.guard.characteristic_length) } else { 1.0 };
        }
        if let Some(joints) = g.get_mut(switching::BASE_JOINT..switching::COUNT)
            && let Some((base, platform)) = joints.split_first_chunk_mut::<LEG_COUNT>()
            && let Some(platform) = platform.first_chunk_mut::<LEG_COUNT>()
        {
            if self.form.joint_limits().is_some() {
                self.form.joint_margins(state, legs, base, platform);
            } else {
                *base = [1.0; LEG_COUNT];
                *platform = [1.0; LEG_COUNT];
            }
        }
    }

    /// The rate with hydraulic legs: the valve commands from the law, the legs' lengths and
    /// rates, the hydraulic law leg by leg, and the body under the resulting forces (the force
    /// inputs' fast path where it applies). Inlined into the caller, which is compiled for the
    /// lanes' registers (the intrinsics would otherwise be calls); `cold_path` there keeps it out
    /// of the force inputs' way.
    #[inline(always)]
    fn hydraulic_derivative(&self, h: &HydraulicActuators, t: f64, y: &SimulationState, dy: &mut SimulationState) {
        let state = BodyState::from_vector(body(y));
        let valves = if self.law.depends_on_state() {
            self.law.leg_forces(t, &state, &LegGeometry::new(&self.form.stand, &state))
        } else {
            self.law.leg_forces_at(t)
        };
        let legs = self.form.joints.kinematics_in::<V>(&state);
        let l_dot = self.form.joints.length_rates_in::<V>(&state, &legs);
        let (u, [supplied, compression, losses]) =
            hydraulic_rates(h, y, &legs.lengths(), &l_dot, &valves, h.supply, dy);
        let forces = HeldForces::constant(u);
        if let Some(body_rate) = dy.first_chunk_mut::<STATE_DIM>() {
            let power = self.form.derivative_in::<HeldForces, V>(t, body(y), &forces, body_rate);
            dy[quadrature::WORK_DISSIPATED] = power.dissipation + losses;
        }
        dy[quadrature::WORK_F] = 0.0;
        for x in &mut dy[CURRENTS..hydraulic::PA] {
            *x = 0.0;
        }
        dy[quadrature::WORK_HYDRAULIC] = supplied;
        dy[quadrature::WORK_COMPRESSION] = compression;
    }

    /// The guard, the switching functions and the leg outputs from one computation of the
    /// legs (in lanes `V`: see `JointArrays::kinematics_in`).
    #[inline(always)]
    fn check_and_switching_in<const N: usize>(
        &self,
        y: &[f64; N],
        g: Option<&mut [f64; MAX_SWITCHING]>,
    ) -> Result<(), PhysicsFault> {
        if !all_finite(body(y)) {
            return Err(PhysicsFault::NonFiniteState);
        }
        let state = BodyState::from_vector(body(y));
        let legs = self.form.joints.kinematics_in::<V>(&state);
        self.guard.check_legs(&state, &legs)?;
        let ldot = self.form.joints.length_rates_in::<V>(&state, &legs);
        if let Some(h) = self.form.hydraulics() {
            std::hint::cold_path();
            self.check_chambers(h, y, &legs.lengths())?;
        }
        self.checked_legs.set(Some(LegOutputs { l: legs.lengths(), ldot }));
        if let Some(g) = g {
            self.switching_of(&state, &legs, g, self.tracks_singularities());
        }
        Ok(())
    }
}

/// The platform's ODE system over the whole [`SimulationState`] (`N = SIMULATION_DIM`), or
/// over its leading [`MECHANICAL_DIM`] components when the hydraulic legs are off (the
/// integrators' arrays are then shorter; [`PlatformSimulation::advance`] chooses).
impl<L: LegForceLaw + ?Sized, V: Lanes, const N: usize> OdeSystem<N> for PlatformDynamics<'_, L, V> {
    type Fault = PhysicsFault;

    #[inline(always)]
    fn derivative(&self, t: f64, y: &[f64; N], dy: &mut [f64; N]) {
        if let Some(h) = self.form.hydraulics() {
            std::hint::cold_path();
            // Only ever stepped over the whole state.
            if let (Ok(y), Ok(dy)) =
                (<&SimulationState>::try_from(&y[..]), <&mut SimulationState>::try_from(&mut dy[..]))
            {
                self.hydraulic_derivative(h, t, y, dy);
            }
            return;
        }
        if self.form.drives().is_some() {
            // Out of the force-input path's way (its code and registers stay as without drives).
            std::hint::cold_path();
            // The law gives the voltages.
            let inputs = if self.law.depends_on_state() {
                let state = BodyState::from_vector(body(y));
                self.law.leg_forces(t, &state, &LegGeometry::new(&self.form.stand, &state))
            } else {
                self.law.leg_forces_at(t)
            };
            let currents: [f64; LEG_COUNT] = std::array::from_fn(|k| y[CURRENTS + k]);
            let actuation = Actuation::Drives { currents: &currents, voltages: &inputs };
            if let Some((body_rate, rest)) = dy.split_first_chunk_mut::<STATE_DIM>() {
                let rates = self.form.derivative_machine_of::<V>(body(y), actuation, body_rate);
                if let Some([work, dissipated, currents @ .., electric]) = rest.first_chunk_mut::<9>() {
                    *work = 0.0;
                    *dissipated = rates.power.dissipation + rates.drive_dissipation;
                    currents.copy_from_slice(&rates.current_rate);
                    *electric = rates.electric_power;
                }
            }
            return;
        }
        if let Some((body_rate, rest)) = dy.split_first_chunk_mut::<STATE_DIM>() {
            let power = self.form.derivative_in::<L, V>(t, body(y), self.law, body_rate);
            if let [work, dissipated, drives @ ..] = rest {
                *work = power.actuator;
                *dissipated = power.dissipation;
                // No drives: the currents and the electric work stay as they are (0).
                for x in drives {
                    *x = 0.0;
                }
            }
        }
    }

    fn active_dimension(&self) -> usize {
        let n = if self.form.hydraulics().is_some() {
            SIMULATION_DIM
        } else if self.form.drives().is_some() {
            WITH_DRIVES
        } else {
            WITHOUT_DRIVES
        };
        n.min(N)
    }

    /// With hydraulic legs, the step the explicit fixed-step method stays stable for at `y`:
    /// the legs' fast modes ([`crate::physics::actuators::hydraulics::HydraulicLegs::stiffness`])
    /// against RK4's stability interval (2.78 on the negative real axis), with a margin for
    /// the rate's growth within the step.
    fn stable_step(&self, _t: f64, y: &[f64; N]) -> f64 {
        let Some(h) = self.form.hydraulics() else { return f64::INFINITY };
        let state = BodyState::from_vector(body(y));
        // SSE2 pairs, the baseline of x86-64: inlined wherever this is called from.
        let legs = self.form.joints.kinematics_in::<Narrow>(&state);
        let l = legs.lengths();
        let mut fastest = 0.0_f64;
        for k in 0..LEG_COUNT {
            let at = |i: usize| y.get(i).copied().unwrap_or(0.0);
            let chambers = Chambers {
                pa: at(hydraulic::PA + k),
                pb: at(hydraulic::PB + k),
                spool: at(hydraulic::SPOOL + k),
                spool_rate: at(hydraulic::SPOOL_RATE + k),
            };
            fastest = fastest.max(h.legs.stiffness(&chambers, &h.piston(k, l[k], 0.0), h.supply));
        }
        STABLE_STEP_FACTOR / fastest
    }

    fn linear_decay(&self) -> Option<LinearDecay> {
        self.form.drives().map(|d| LinearDecay { start: CURRENTS, len: LEG_COUNT, rate: d.current_decay_rate() })
    }

    #[inline(always)]
    fn after_step(&self, y: &mut [f64; N]) {
        if self.stabilisation == Stabilisation::Projection
            && let Some(b) = y.first_chunk_mut::<STATE_DIM>()
        {
            project_onto_constraints_in::<V::Axes>(b);
        }
    }

    fn modifies_state_after_step(&self) -> bool {
        self.stabilisation == Stabilisation::Projection
    }

    #[inline(always)]
    fn check(&self, t: f64, y: &[f64; N]) -> Result<(), PhysicsFault> {
        self.check_and_switching(t, y, None)
    }

    /// The guard, the switching functions and the leg outputs from one computation of the
    /// legs.
    #[inline(always)]
    fn check_and_switching(
        &self,
        _t: f64,
        y: &[f64; N],
        g: Option<&mut [f64; MAX_SWITCHING]>,
    ) -> Result<(), PhysicsFault> {
        self.check_and_switching_in(y, g)
    }

    fn switching_count(&self) -> usize {
        if self.form.joint_limits().is_some() {
            switching::COUNT
        } else if self.tracks_singularities() {
            switching::DETERMINANT + 1
        } else {
            switching::DETERMINANT
        }
    }

    #[inline(always)]
    fn switching(&self, _t: f64, y: &[f64; N], g: &mut [f64; MAX_SWITCHING]) {
        let state = BodyState::from_vector(body(y));
        let legs = self.form.joints.kinematics(&state);
        self.switching_of(&state, &legs, g, self.tracks_singularities());
    }

    fn switching_kind(&self, index: usize) -> SwitchingKind {
        match index {
            switching::DETERMINANT if self.stop_at_singularity => SwitchingKind::Stop,
            switching::DETERMINANT => SwitchingKind::Report,
            _ => SwitchingKind::Restart,
        }
    }

    fn switching_fault(&self, index: usize, _t: f64, y: &[f64; N]) -> Option<PhysicsFault> {
        (index == switching::DETERMINANT).then(|| {
            let legs = LegGeometry::new(&self.form.stand, &BodyState::from_vector(body(y)));
            PhysicsFault::PassedSingularConfiguration { legs: singular_legs(&self.form.stand, &legs) }
        })
    }
}

/// The crossings of a step over the shorter arrays (`mechanical`) into `log`, as whole
/// simulation states (the rest of `state`).
#[inline(never)]
fn record_mechanical_crossings(
    log: &mut CrossingLog<SIMULATION_DIM>,
    mechanical: &CrossingLog<MECHANICAL_DIM>,
    state: &SimulationState,
) {
    for c in mechanical.as_slice() {
        let mut y = *state;
        if let Some(head) = y.first_chunk_mut::<MECHANICAL_DIM>() {
            *head = c.y;
        }
        log.push(Crossing { index: c.index, t: c.t, rising: c.rising, y });
    }
    log.dropped += mechanical.dropped;
}

/// Where [`PlatformSimulation::advance_until_event`] ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reached {
    /// The time reached, s.
    pub t: f64,
    /// Lengths and rates of the legs of the state reached, if the integration computed them
    /// (it does whenever it took a step).
    pub legs: Option<LegOutputs>,
}

/// Why [`PlatformSimulation::advance`] did not reach the requested time. The simulation is
/// left exactly as it was before the call.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StepFailure {
    /// The motion reached an inadmissible configuration at time `t`.
    Physics { t: f64, fault: PhysicsFault },
    /// The integrator could not complete the step.
    Solver(IntegrationError<PhysicsFault>),
}

impl StepFailure {
    /// Whether shorter communication steps can get past it (only the limit of internal steps
    /// per call stopped the integrator).
    pub fn is_step_limit(&self) -> bool {
        matches!(self, StepFailure::Solver(e) if e.is_step_limit())
    }
}

impl std::fmt::Display for StepFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            StepFailure::Physics { t, fault } => write!(f, "at t = {t:?}: {fault}"),
            StepFailure::Solver(e) => write!(f, "{e}"),
        }
    }
}

/// One stand in motion.
#[derive(Clone, Debug)]
pub struct PlatformSimulation {
    pub form: SpecialForm,
    pub guard: ConfigurationGuard,
    pub stabilisation: Stabilisation,
    /// Discard a step that passes a singular leg arrangement (the FMU's `stopAtSingularity`).
    pub stop_at_singularity: bool,
    /// Record passages through singular leg arrangements in [`PlatformSimulation::crossings`]
    /// (default on). They change nothing in the motion; off (and `stop_at_singularity` off),
    /// the steps skip the 6x6 determinant at every internal step's end. Changed with
    /// [`PlatformSimulation::set_track_singularities`].
    pub(crate) track_singularities: bool,
    pub integrator: Integrator,
    pub time: f64,
    pub state: SimulationState,
    /// Sign changes of the switching functions during the last [`PlatformSimulation::advance`]
    /// (contacts, singular arrangements passed), in time order.
    pub crossings: CrossingLog<SIMULATION_DIM>,
    /// The same, as the integrators' shorter arrays without hydraulic legs record them (copied
    /// into `crossings` after the step).
    mechanical_crossings: CrossingLog<MECHANICAL_DIM>,
    /// The lowest chamber pressure of the hydraulic legs since the start, Pa (`pmin`; `+inf`
    /// without them).
    pub lowest_pressure: f64,
    /// The registers the steps compute in (the same numbers in each).
    vector_path: VectorPath,
}

impl PlatformSimulation {
    /// Validates the stand and the initial state and sets up the simulation at time `t0`
    /// (idealised legs, no end stops; see [`PlatformSimulation::with_end_stops`]).
    pub fn new(
        stand: Stand,
        initial: BodyState,
        settings: SolverSettings,
        stabilisation: Stabilisation,
        t0: f64,
    ) -> Result<Self, ParameterError> {
        stand.validate()?;
        let guard = ConfigurationGuard::for_initial_state(&stand, &initial)?;
        let mut state = [0.0; SIMULATION_DIM];
        if let Some(b) = state.first_chunk_mut::<STATE_DIM>() {
            *b = initial.to_vector();
        }
        Ok(PlatformSimulation {
            form: SpecialForm::new(stand),
            guard,
            stabilisation,
            stop_at_singularity: false,
            track_singularities: true,
            integrator: Integrator::new(settings),
            time: t0,
            state,
            crossings: CrossingLog::default(),
            mechanical_crossings: CrossingLog::default(),
            lowest_pressure: f64::INFINITY,
            vector_path: VectorPath::fastest(),
        })
    }

    /// The registers the steps compute in.
    pub fn vector_path(&self) -> VectorPath {
        self.vector_path
    }

    /// Chooses the registers the steps compute in (the baseline where `path` is not available
    /// here); the numbers are the same in each.
    pub fn set_vector_path(&mut self, path: VectorPath) {
        self.vector_path = VectorPath::checked(path);
    }

    /// The same simulation with end stops (validated, and the initial pose checked against
    /// the strokes).
    pub fn with_end_stops(mut self, stops: Option<EndStops>) -> Result<Self, ParameterError> {
        if let Some(s) = &stops {
            s.validate()?;
            let legs = LegGeometry::new(self.stand(), &self.body_state());
            s.validate_initial_lengths(self.stand(), &legs.length)?;
        }
        self.form.set_end_stops(stops);
        self.integrator.sides = SwitchingSides::default();
        Ok(self)
    }

    /// The same simulation with the machine's legs: bodies, friction, joint limits (validated).
    pub fn with_machine(
        mut self,
        legs: LegBodies,
        friction: Friction,
        joint_limits: Option<JointLimits>,
    ) -> Result<Self, ParameterError> {
        legs.validate()?;
        friction.validate()?;
        if let Some(j) = &joint_limits {
            j.validate()?;
        }
        self.form = self.form.clone().with_machine(legs, friction, joint_limits);
        self.integrator.sides = SwitchingSides::default();
        Ok(self)
    }

    /// The same simulation with electric drives in the legs (validated) and their initial
    /// armature currents `I0`, A (`None`: the leg forces are given).
    pub fn with_drives(
        mut self,
        drives: Option<ElectricDrives>,
        initial_currents: [f64; LEG_COUNT],
    ) -> Result<Self, ParameterError> {
        if let Some(d) = &drives {
            d.validate()?;
            for (k, &i) in initial_currents.iter().enumerate() {
                crate::physics::stand::check_finite(&format!("I0[{}]", k + 1), i)?;
            }
        }
        self.form = self.form.clone().with_drives(drives);
        for k in 0..LEG_COUNT {
            self.state[CURRENTS + k] = if drives.is_some() { initial_currents[k] } else { 0.0 };
        }
        Ok(self)
    }

    /// The same simulation with hydraulic servo legs (validated) and their initial chamber
    /// pressures `p_A0`, `p_B0` (Pa; the spools start centred and at rest), or `None`.
    pub fn with_hydraulics(
        mut self,
        hydraulics: Option<HydraulicActuators>,
        initial_pa: [f64; LEG_COUNT],
        initial_pb: [f64; LEG_COUNT],
    ) -> Result<Self, ParameterError> {
        if let Some(h) = &hydraulics {
            h.validate()?;
            let legs = LegGeometry::new(self.stand(), &self.body_state());
            for k in 0..LEG_COUNT {
                crate::physics::stand::check_finite(&format!("pA0[{}]", k + 1), initial_pa[k])?;
                crate::physics::stand::check_finite(&format!("pB0[{}]", k + 1), initial_pb[k])?;
                let (va, vb) = h.legs.volumes(&h.piston(k, legs.length[k], 0.0));
                if !(va > 0.0 && vb > 0.0) {
                    return Err(ParameterError::new(
                        format!("lmin[{}]", k + 1),
                        format!(
                            "leg {} starts at {:e} m, where a hydraulic chamber has no volume (V_A = {va:e} m3, V_B = \
                             {vb:e} m3): the initial pose must put every piston within its stroke's dead volumes",
                            k + 1,
                            legs.length[k]
                        ),
                    ));
                }
            }
        }
        self.form = self.form.clone().with_hydraulics(hydraulics);
        let on = hydraulics.is_some();
        for k in 0..LEG_COUNT {
            self.state[hydraulic::PA + k] = if on { initial_pa[k] } else { 0.0 };
            self.state[hydraulic::PB + k] = if on { initial_pb[k] } else { 0.0 };
            self.state[hydraulic::SPOOL + k] = 0.0;
            self.state[hydraulic::SPOOL_RATE + k] = 0.0;
        }
        self.lowest_pressure =
            if on { self.pressures().iter().flatten().fold(f64::INFINITY, |a, &b| a.min(b)) } else { f64::INFINITY };
        Ok(self)
    }

    /// The chamber pressures `[p_A, p_B]`, Pa (0 without hydraulic legs).
    pub fn pressures(&self) -> [[f64; LEG_COUNT]; 2] {
        [std::array::from_fn(|k| self.state[hydraulic::PA + k]), std::array::from_fn(|k| self.state[hydraulic::PB + k])]
    }

    /// The spools' positions `s_k` (0 without hydraulic legs).
    pub fn spools(&self) -> [f64; LEG_COUNT] {
        std::array::from_fn(|k| self.state[hydraulic::SPOOL + k])
    }

    pub fn stand(&self) -> &Stand {
        &self.form.stand
    }

    /// The armature currents `I_k`, A (0 without drives).
    pub fn currents(&self) -> [f64; LEG_COUNT] {
        std::array::from_fn(|k| self.state[CURRENTS + k])
    }

    /// `work.electric`, J.
    pub fn electric_work(&self) -> f64 {
        self.state[quadrature::WORK_ELECTRIC]
    }

    /// Whether passages through singular arrangements are recorded (see the field).
    pub fn track_singularities(&self) -> bool {
        self.track_singularities
    }

    /// Switches the recording of singular passages. Switched on, the determinant's side is
    /// taken at the current state, so that only passages after now are recorded.
    pub fn set_track_singularities(&mut self, on: bool) {
        let was = self.track_singularities || self.stop_at_singularity;
        self.track_singularities = on;
        if on && !was && self.integrator.sides.known {
            let legs = self.form.joints.kinematics(&self.body_state());
            let determinant = force_moment_determinant(&legs, self.guard.characteristic_length);
            let bit = 1 << switching::DETERMINANT;
            let side = if determinant > 0.0 { bit } else { 0 };
            self.integrator.sides.bits = (self.integrator.sides.bits & !bit) | side;
        }
    }

    pub fn body_state(&self) -> BodyState {
        BodyState::from_vector(body(&self.state))
    }

    /// `work.F`, J.
    pub fn work_of_forces(&self) -> f64 {
        self.state[quadrature::WORK_F]
    }

    /// `work.dissipated`, J.
    pub fn dissipated_energy(&self) -> f64 {
        self.state[quadrature::WORK_DISSIPATED]
    }

    /// The ODE system for a force law.
    pub fn dynamics<'a, L: LegForceLaw + ?Sized>(&'a self, law: &'a L) -> PlatformDynamics<'a, L> {
        PlatformDynamics {
            track_singularities: self.track_singularities,
            ..PlatformDynamics::new(&self.form, law, self.stabilisation, &self.guard, self.stop_at_singularity)
        }
    }

    /// Integrates to `t1` (> current time) with leg forces from `law`. On failure nothing
    /// changes: state, time and integrator memory are rolled back. The crossings met on the
    /// way are in [`PlatformSimulation::crossings`].
    pub fn advance<L: LegForceLaw + ?Sized>(&mut self, law: &L, t1: f64) -> Result<(), StepFailure> {
        self.advance_until_event(law, t1, false).map(|_| ())
    }

    /// As [`PlatformSimulation::advance`]; with `stop_at_contact`, stops early at the first
    /// contact onset or release (located exactly by the adaptive method). Returns the time
    /// reached and the legs there.
    pub fn advance_until_event<L: LegForceLaw + ?Sized>(
        &mut self,
        law: &L,
        t1: f64,
        stop_at_contact: bool,
    ) -> Result<Reached, StepFailure> {
        let saved_integrator = self.integrator;
        self.crossings.clear();
        let dynamics = PlatformDynamics {
            track_singularities: self.track_singularities,
            ..PlatformDynamics::new(&self.form, law, self.stabilisation, &self.guard, self.stop_at_singularity)
        };
        let path = self.vector_path;
        let result = if self.form.hydraulics().is_some() {
            let saved = self.state;
            let call = super::vector::Call {
                t0: self.time,
                y: &mut self.state,
                t1,
                log: &mut self.crossings,
                stop_at_restart: stop_at_contact,
            };
            super::vector::integrate(path, &mut self.integrator, &dynamics, call).inspect_err(|_| self.state = saved)
        } else {
            // Without hydraulic legs their components stay 0: the integrators step the shorter
            // leading part, in place.
            // Always there (the assertion beside MECHANICAL_DIM).
            let Some(head) = self.state.first_chunk_mut::<MECHANICAL_DIM>() else { unreachable!() };
            let saved = *head;
            self.mechanical_crossings.clear();
            let call = super::vector::Call {
                t0: self.time,
                y: head,
                t1,
                log: &mut self.mechanical_crossings,
                stop_at_restart: stop_at_contact,
            };
            let result = super::vector::integrate(path, &mut self.integrator, &dynamics, call);
            if result.is_err() {
                *head = saved;
            }
            if !self.mechanical_crossings.is_empty() {
                std::hint::cold_path();
                record_mechanical_crossings(&mut self.crossings, &self.mechanical_crossings, &self.state);
            }
            result
        };
        match result {
            Ok(reached) => {
                self.time = reached;
                self.lowest_pressure = self.lowest_pressure.min(dynamics.lowest_pressure.get());
                Ok(Reached { t: reached, legs: dynamics.checked_legs.get() })
            }
            Err(e) => {
                // The state is back as it was (above); the integrator's memory too.
                self.integrator = saved_integrator;
                Err(match e {
                    IntegrationError::Fault { t, fault } => StepFailure::Physics { t, fault },
                    other => StepFailure::Solver(other),
                })
            }
        }
    }

    /// `dy/dt` at the current state for the force law (for output derivatives).
    pub fn derivative<L: LegForceLaw + ?Sized>(&self, law: &L) -> SimulationState {
        let mut dy = [0.0; SIMULATION_DIM];
        self.dynamics(law).derivative(self.time, &self.state, &mut dy);
        dy
    }

    /// The switching function values at the current state (Model Exchange event indicators).
    pub fn switching_values<L: LegForceLaw + ?Sized>(&self, law: &L, g: &mut [f64]) {
        self.dynamics(law).switching_values(body(&self.state), g);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integration::Method;
    use crate::physics::actuators::HeldForces;
    use crate::physics::body::kinematics::rotation_from_angles;
    use nalgebra::Vector3;

    /// The legs a step reports for its end state are those computed from that state alone.
    #[test]
    fn the_legs_of_a_step_are_those_of_its_end_state() {
        for method in [Method::RungeKutta4, Method::DormandPrince45] {
            let stand = Stand::truck_cabin();
            let start = BodyState::from_pose(
                Stand::truck_cabin_neutral_position() + Vector3::new(0.02, -0.01, 0.03),
                Vector3::new(0.1, 0.2, -0.3),
                &rotation_from_angles(&Vector3::new(0.05, -0.02, 0.1)),
                &Vector3::new(0.3, -0.2, 0.5),
            );
            let settings = SolverSettings { method, fixed_step: 2.5e-4, ..Default::default() };
            let mut sim = PlatformSimulation::new(stand, start, settings, Stabilisation::Projection, 0.0)
                .and_then(|s| s.with_end_stops(Some(EndStops::default())))
                .expect("valid");
            let law = HeldForces { value: [5000.0, 7000.0, 6000.0, 5500.0, 6500.0, 5900.0], slope: [1e3; 6], t0: 0.0 };
            let reached = sim.advance_until_event(&law, 3e-3, false).expect("steps");
            let legs = reached.legs.expect("the step computed the legs");
            assert_eq!(legs, LegOutputs::compute(&sim.form, &sim.state), "{method:?}");
        }
    }
}
