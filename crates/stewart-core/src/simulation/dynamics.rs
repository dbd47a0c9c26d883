//! [`PlatformDynamics`]: the special-form equations with a force law, plus the work
//! quadratures, as an ODE system for the integrators; and the legs it measured last.

use crate::integration::{LinearDecay, MAX_SWITCHING, OdeSystem, SwitchingKind};
use crate::physics::actuators::HeldForces;
use crate::physics::actuators::hydraulics::{Chambers, HydraulicActuators};
use crate::physics::body::state::{BodyState, STATE_DIM, StateVector, all_finite};
use std::cell::Cell;

use crate::physics::actuators::LegForceLaw;
use crate::physics::body::projection::project_onto_constraints_in;
use crate::physics::configuration::ConfigurationGuard;
use crate::physics::direct_problem::{force_moment_determinant, singular_legs};
use crate::physics::error::PhysicsFault;
use crate::physics::legs::end_stops::STROKE_LIMITS;
use crate::physics::legs::geometry::{LegGeometry, LegKinematics};
use crate::physics::legs::per_leg::{Lanes, Narrow};
use crate::physics::special_form::{Actuation, SpecialForm};
use crate::physics::stand::LEG_COUNT;
use std::marker::PhantomData;

use super::state::{
    CURRENTS, SIMULATION_DIM, SimulationState, WITH_DRIVES, WITHOUT_DRIVES, body, hydraulic, hydraulic_rates,
    quadrature, switching,
};

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
    /// [`PlatformSimulation::track_singularities`](super::PlatformSimulation::track_singularities));
    /// the stroke margins always are.
    pub track_singularities: bool,
    /// Lengths and rates of the legs of the last state [`OdeSystem::check`] accepted: after an
    /// integration, those of its end state (the check is the last thing a step does), so that
    /// the outputs `l` and `ldot` cost no second computation of the legs.
    pub checked_legs: Cell<Option<LegOutputs>>,
    /// The lowest chamber pressure (Pa) of the states [`OdeSystem::check`] accepted (hydraulic
    /// legs; `+inf` before any).
    pub lowest_pressure: Cell<f64>,
    pub(super) lanes: PhantomData<V>,
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
                self.form.joint_margins::<V::Checks>(state, legs, base, platform);
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
/// over its leading [`MECHANICAL_DIM`](super::state::MECHANICAL_DIM) components when the
/// hydraulic legs are off (the integrators' arrays are then shorter;
/// [`PlatformSimulation::advance`](super::PlatformSimulation::advance) chooses).
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

/// Leg lengths and rates alone: what a controller reads every step, computed without the
/// other outputs (the same numbers as the fields of the same names of
/// [`PlatformOutputs`](super::PlatformOutputs)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LegOutputs {
    pub l: [f64; LEG_COUNT],
    pub ldot: [f64; LEG_COUNT],
}

impl LegOutputs {
    pub fn compute(form: &SpecialForm, y: &SimulationState) -> Self {
        let state = BodyState::from_vector(body(y));
        let legs = LegGeometry::new(&form.stand, &state);
        LegOutputs { ldot: legs.length_rates(&form.stand, &state), l: legs.length }
    }
}
