//! [`PlatformDynamics`]: the special-form equations with a force law, plus the work
//! quadratures, as an ODE system for the integrators; and the legs it measured last.

use crate::integration::{LinearDecay, MAX_SWITCHING, OdeSystem, SwitchingKind};
use crate::physics::actuators::{Actuator, InState, LegMotion, with_actuator};
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
use crate::physics::special_form::{FastPath, SpecialForm};
use crate::physics::stand::LEG_COUNT;
use std::marker::PhantomData;

use super::state::{SimulationState, accumulator_switching, body, hydraulic, rate_in, switching};

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

    /// The actuator's check of its states at an accepted state ([`Actuator::check`]), what it
    /// tracks (the lowest chamber pressure) recorded; nothing to do for an actuator without one.
    #[inline(always)]
    fn check_actuator<A: Actuator + InState>(
        &self,
        a: &A,
        y: &[f64],
        l: &[f64; LEG_COUNT],
    ) -> Result<(), PhysicsFault> {
        if !A::CHECKS {
            return Ok(());
        }
        std::hint::cold_path();
        let mut lowest = self.lowest_pressure.get();
        a.check(y.get(A::BLOCK).unwrap_or(&[]), l, &mut lowest)?;
        self.lowest_pressure.set(lowest);
        Ok(())
    }

    /// [`OdeSystem::stable_step`] for actuator `A`: none asked for where it has no bound.
    #[inline(always)]
    fn stable_step_of<A: Actuator + InState, const N: usize>(&self, a: &A, y: &[f64; N]) -> f64 {
        if !A::BOUNDED {
            return f64::INFINITY;
        }
        std::hint::cold_path();
        let legs = |with_rates: bool| {
            let state = BodyState::from_vector(body(y));
            let kinematics = self.form.joints.kinematics_in::<Narrow>(&state);
            let rates = if with_rates {
                self.form.joints.length_rates_in::<Narrow>(&state, &kinematics)
            } else {
                [0.0; LEG_COUNT]
            };
            LegMotion { lengths: kinematics.lengths(), rates }
        };
        a.stable_step(y.get(A::BLOCK).unwrap_or(&[]), legs)
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
        with_actuator!(self.form.actuator(), a => self.check_actuator(a, y, &legs.lengths()))?;
        self.checked_legs.set(Some(LegOutputs { l: legs.lengths(), ldot }));
        if let Some(g) = g {
            self.switching_of(&state, &legs, g, self.tracks_singularities());
            if let Some(slot) = g.get_mut(switching::ACCUMULATOR) {
                *slot = accumulator_switching(self.form, y);
            }
        }
        Ok(())
    }
}

/// The platform's ODE system over the whole [`SimulationState`] (`N = SIMULATION_DIM`), or
/// over its leading [`MECHANICAL_DIM`](super::state::MECHANICAL_DIM) components when the legs'
/// actuator's block ends within them (the integrators' arrays are then shorter;
/// [`PlatformSimulation::advance`](super::PlatformSimulation::advance) chooses).
impl<L: LegForceLaw + ?Sized, V: Lanes, const N: usize> OdeSystem<N> for PlatformDynamics<'_, L, V> {
    type Fault = PhysicsFault;

    #[inline(always)]
    fn derivative(&self, t: f64, y: &[f64; N], dy: &mut [f64; N]) {
        let body = FastPath::<L, V> { form: self.form, t, body: body(y), law: self.law, lanes: PhantomData };
        rate_in(self.form, &body, y, dy);
    }

    /// Up to the end of the actuator's active states: the rest stay as they are (the later
    /// blocks 0; the power unit's states without it).
    fn active_dimension(&self) -> usize {
        self.form.actuator().active_end().min(N)
    }

    /// The actuator's bound ([`Actuator::stable_step`]: the hydraulic legs' fast modes), at the
    /// legs' lengths in SSE2 pairs (the baseline of x86-64: inlined wherever this is called
    /// from).
    fn stable_step(&self, _t: f64, y: &[f64; N]) -> f64 {
        with_actuator!(self.form.actuator(), a => self.stable_step_of(a, y))
    }

    /// The actuator's block decaying linearly ([`Actuator::linear_decay`]: the drives' currents).
    fn linear_decay(&self) -> Option<LinearDecay> {
        let start = self.form.actuator().kind().block().start;
        with_actuator!(self.form.actuator(), a => a.linear_decay()).map(|(first, len, rate)| LinearDecay {
            start: start + first,
            len,
            rate,
        })
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
        if self.form.hydraulics().is_some_and(|h| h.powered) && N > hydraulic::SUPPLY_PRESSURE {
            switching::EVENT_INDICATORS
        } else if self.form.joint_limits().is_some() {
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
        if let Some(slot) = g.get_mut(switching::ACCUMULATOR) {
            *slot = accumulator_switching(self.form, y);
        }
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
