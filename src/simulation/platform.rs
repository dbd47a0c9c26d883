//! [`PlatformSimulation`]: one stand, one state, one integrator.

use crate::integration::{IntegrationError, Integrator, OdeSystem, SolverSettings};
use crate::physics::body_state::{BodyState, STATE_DIM, StateVector};
use crate::physics::configuration::ConfigurationGuard;
use crate::physics::error::{ParameterError, PhysicsFault};
use crate::physics::forces::LegForceLaw;
use crate::physics::projection::project_onto_constraints;
use crate::physics::special_form::SpecialForm;
use crate::physics::stand::Stand;

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

/// The special-form equations with a force law, as an ODE system for the integrators.
pub struct PlatformDynamics<'a, L: ?Sized> {
    pub form: &'a SpecialForm,
    pub law: &'a L,
    pub stabilisation: Stabilisation,
    pub guard: &'a ConfigurationGuard,
}

impl<L: LegForceLaw + ?Sized> OdeSystem<STATE_DIM> for PlatformDynamics<'_, L> {
    type Fault = PhysicsFault;

    #[inline(always)]
    fn derivative(&self, t: f64, y: &StateVector, dy: &mut StateVector) {
        self.form.derivative(t, y, self.law, dy);
    }

    #[inline]
    fn after_step(&self, y: &mut StateVector) {
        if self.stabilisation == Stabilisation::Projection {
            project_onto_constraints(y);
        }
    }

    fn modifies_state_after_step(&self) -> bool {
        self.stabilisation == Stabilisation::Projection
    }

    #[inline]
    fn check(&self, _t: f64, y: &StateVector) -> Result<(), PhysicsFault> {
        self.guard.check(&self.form.stand, &BodyState::from_vector(y))
    }
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

impl std::fmt::Display for StepFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            StepFailure::Physics { t, fault } => write!(f, "at t = {t}: {fault}"),
            StepFailure::Solver(e) => write!(f, "{e}"),
        }
    }
}

/// One stand in motion.
#[derive(Clone, Debug, PartialEq)]
pub struct PlatformSimulation {
    pub form: SpecialForm,
    pub guard: ConfigurationGuard,
    pub stabilisation: Stabilisation,
    pub integrator: Integrator,
    pub time: f64,
    pub state: StateVector,
}

impl PlatformSimulation {
    /// Validates the stand and the initial state and sets up the simulation at time `t0`.
    pub fn new(
        stand: Stand,
        initial: BodyState,
        settings: SolverSettings,
        stabilisation: Stabilisation,
        t0: f64,
    ) -> Result<Self, ParameterError> {
        stand.validate()?;
        let guard = ConfigurationGuard::for_initial_state(&stand, &initial)?;
        Ok(PlatformSimulation {
            form: SpecialForm::new(stand),
            guard,
            stabilisation,
            integrator: Integrator::new(settings),
            time: t0,
            state: initial.to_vector(),
        })
    }

    pub fn stand(&self) -> &Stand {
        &self.form.stand
    }

    pub fn body_state(&self) -> BodyState {
        BodyState::from_vector(&self.state)
    }

    /// Integrates to `t1` (> current time) with leg forces from `law`. On failure nothing
    /// changes: state, time and integrator memory are rolled back.
    pub fn advance<L: LegForceLaw + ?Sized>(&mut self, law: &L, t1: f64) -> Result<(), StepFailure> {
        let saved_state = self.state;
        let saved_integrator = self.integrator;
        let dynamics =
            PlatformDynamics { form: &self.form, law, stabilisation: self.stabilisation, guard: &self.guard };
        let result = self.integrator.integrate(&dynamics, self.time, &mut self.state, t1);
        let result = result.map_err(|e| match e {
            IntegrationError::Fault { t, fault } => StepFailure::Physics { t, fault },
            other => StepFailure::Solver(other),
        });
        let result = result.and_then(|()| {
            self.guard
                .check_singularity(&self.form.stand, &BodyState::from_vector(&self.state))
                .map_err(|fault| StepFailure::Physics { t: t1, fault })
        });
        match result {
            Ok(()) => {
                self.time = t1;
                Ok(())
            }
            Err(e) => {
                self.state = saved_state;
                self.integrator = saved_integrator;
                Err(e)
            }
        }
    }

    /// `dy/dt` at the current state for the force law (for output derivatives).
    pub fn derivative<L: LegForceLaw + ?Sized>(&self, law: &L) -> StateVector {
        let mut dy = [0.0; STATE_DIM];
        self.form.derivative(self.time, &self.state, law, &mut dy);
        dy
    }
}
