//! [`PlatformSimulation`]: one stand, one state, one integrator.

use crate::integration::{
    Crossing, CrossingLog, IntegrationError, Integrator, OdeSystem, SolverSettings, SwitchingSides,
};
use crate::physics::actuators::drives::ElectricDrives;
use crate::physics::actuators::forces::ForceInputs;
use crate::physics::actuators::hydraulics::HydraulicActuators;
use crate::physics::actuators::{ActiveActuator, Actuator, with_actuator};
use crate::physics::body::state::{BodyState, STATE_DIM};

use crate::physics::actuators::LegForceLaw;
use crate::physics::configuration::ConfigurationGuard;
use crate::physics::direct_problem::force_moment_determinant;
use crate::physics::error::{ParameterError, PhysicsFault};
use crate::physics::legs::bodies::LegBodies;
use crate::physics::legs::end_stops::EndStops;
use crate::physics::legs::friction::Friction;
use crate::physics::legs::geometry::LegGeometry;
use crate::physics::legs::joint_limits::JointLimits;
use crate::physics::special_form::SpecialForm;
use crate::physics::stand::{LEG_COUNT, Stand};

use super::dynamics::{LegOutputs, PlatformDynamics, Stabilisation};
use super::state::{CURRENTS, MECHANICAL_DIM, SIMULATION_DIM, SimulationState, body, hydraulic, quadrature, switching};
use super::vector::VectorPath;

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

    /// The same simulation with the actuator `actuator` in the legs (validated), its states at
    /// the start from its parameters ([`Actuator::initial_state`], checked against the initial
    /// legs), the other actuators' states 0.
    pub fn with_actuator(mut self, actuator: ActiveActuator) -> Result<Self, ParameterError> {
        actuator.validate()?;
        let mut state = self.state;
        actuator.initial_state(&mut state);
        let l = LegGeometry::new(self.stand(), &self.body_state()).length;
        actuator.check_start(&state, &l)?;
        let mut lowest = f64::INFINITY;
        let x = state.get(actuator.kind().block()).unwrap_or(&[]);
        // What the actuator tracks from the start (the lowest chamber pressure); its start was
        // checked just above.
        let _ = with_actuator!(&actuator, a => a.check(x, &l, &mut lowest));
        self.lowest_pressure = lowest;
        self.form = self.form.clone().with_actuator(actuator);
        self.state = state;
        Ok(self)
    }

    /// The same simulation with electric drives in the legs (validated) and their initial
    /// armature currents `I0`, A (`None`: the leg forces are given).
    pub fn with_drives(
        self,
        drives: Option<ElectricDrives>,
        initial_currents: [f64; LEG_COUNT],
    ) -> Result<Self, ParameterError> {
        match drives {
            Some(d) => self.with_actuator(ActiveActuator::Electric(ElectricDrives { initial_currents, ..d })),
            None if self.form.drives().is_some() => self.with_actuator(ActiveActuator::Forces(ForceInputs)),
            None => Ok(self),
        }
    }

    /// The same simulation with hydraulic servo legs (validated) and their initial chamber
    /// pressures `p_A0`, `p_B0` (Pa; the spools start centred and at rest), or `None`.
    pub fn with_hydraulics(
        self,
        hydraulics: Option<HydraulicActuators>,
        initial_pa: [f64; LEG_COUNT],
        initial_pb: [f64; LEG_COUNT],
    ) -> Result<Self, ParameterError> {
        match hydraulics {
            Some(h) => {
                self.with_actuator(ActiveActuator::Hydraulic(HydraulicActuators { initial_pa, initial_pb, ..h }))
            }
            None if self.form.hydraulics().is_some() => self.with_actuator(ActiveActuator::Forces(ForceInputs)),
            None => Ok(self),
        }
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

    #[inline]
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
        // The whole state where the legs' actuator has its block past the leading part (the
        // hydraulic legs, and any actuator listed after them).
        let result = if self.form.actuator().kind().block().end > MECHANICAL_DIM {
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
            // Otherwise the later blocks stay 0: the integrators step the shorter leading
            // part, in place.
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
