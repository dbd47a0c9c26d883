//! The platform's parameters (docs/model.md §5), their checks, and the simulation they
//! describe.

use nalgebra::Vector3;

use crate::integration::{Method, SolverSettings};
use crate::models::declare::IntegerStorage;
use crate::physics::body::kinematics::rotation_from_angles;
use crate::physics::body::state::{BodyState, STATE_DIM};
use crate::physics::direct_problem::SINGULAR_CONDITION_NUMBER;
use crate::physics::legs::end_stops::EndStops;
use crate::physics::special_form::SpecialForm;
use crate::physics::stand::{LEG_COUNT, PAPER_EQUILIBRIUM_LEG_FORCE, Stand};
use crate::simulation::outputs::condition_number;
use crate::simulation::{PlatformSimulation, SIMULATION_DIM, SimulationState, Stabilisation};

/// Everything set through parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct PlatformParameters {
    pub stand: Stand,
    pub r0: Vector3<f64>,
    pub angles0: Vector3<f64>,
    pub v0: Vector3<f64>,
    pub w0: Vector3<f64>,
    pub settings: SolverSettings,
    pub stabilisation: Stabilisation,
    /// Baumgarte rate (1/s) for Model Exchange and `Stabilisation::Baumgarte`.
    pub baumgarte_rate: f64,
    /// `stops`: whether the end stops act.
    pub stops_enabled: bool,
    /// `lmin`, `lmax`, `stops.stiffness`, `stops.damping`.
    pub stops: EndStops,
    /// `stopAtSingularity`.
    pub stop_at_singularity: bool,
}

impl Default for PlatformParameters {
    /// The default stand at rest in its neutral pose (docs/model.md §3, §5).
    fn default() -> Self {
        PlatformParameters {
            stand: Stand::truck_cabin(),
            r0: Stand::truck_cabin_neutral_position(),
            angles0: Vector3::zeros(),
            v0: Vector3::zeros(),
            w0: Vector3::zeros(),
            settings: SolverSettings::default(),
            stabilisation: Stabilisation::Projection,
            baumgarte_rate: DEFAULT_BAUMGARTE_RATE,
            stops_enabled: true,
            stops: EndStops::default(),
            stop_at_singularity: false,
        }
    }
}

/// Smallest `solver.relTol` (or importer tolerance): below it the error estimate is round-off.
pub const MIN_REL_TOL: f64 = 1e-15;
/// Smallest nonzero `solver.fixedStep`, s: a nanosecond, far below any mechanical time scale
/// of a stand; with the limit of internal steps per call it still allows 1 ms communication
/// steps.
pub const MIN_FIXED_STEP: f64 = 1e-9;

/// Default Baumgarte rate, 1/s: the constraint residual decays with a 0.1 s time constant,
/// faster than the stand's own motion (sqrt(R_b/g) = 0.39 s) and slow enough not to make the
/// equations stiff for an explicit integrator at millisecond steps.
pub const DEFAULT_BAUMGARTE_RATE: f64 = 10.0;

/// Default leg force input: the paper's equilibrium force `0.2005 M g` of the default stand.
pub fn default_leg_force() -> f64 {
    let s = Stand::truck_cabin();
    PAPER_EQUILIBRIUM_LEG_FORCE * s.mass * s.gravity
}

/// How the model left Initialization Mode: with the parameters, all a simulation is built
/// from (so that a restored FMU state builds it again rather than storing it twice).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Experiment {
    pub start_time: f64,
    /// The importer's tolerance, which replaces `solver.relTol`.
    pub tolerance: Option<f64>,
    pub model_exchange: bool,
}

impl PlatformParameters {
    pub fn initial_state(&self) -> BodyState {
        BodyState::from_pose(self.r0, self.v0, &rotation_from_angles(&self.angles0), &self.w0)
    }

    /// The end stops if they are on.
    pub fn end_stops(&self) -> Option<EndStops> {
        self.stops_enabled.then_some(self.stops)
    }

    /// The special form these parameters describe (before initialisation).
    pub fn special_form(&self) -> SpecialForm {
        SpecialForm::new(self.stand.clone()).with_end_stops(self.end_stops())
    }

    /// The simulation state these parameters describe (before initialisation).
    pub fn initial_simulation_state(&self) -> SimulationState {
        let mut y = [0.0; SIMULATION_DIM];
        if let Some(b) = y.first_chunk_mut::<STATE_DIM>() {
            *b = self.initial_state().to_vector();
        }
        y
    }

    /// Validates the parameters and builds the simulation of an experiment.
    pub fn simulation(&self, experiment: &Experiment) -> Result<PlatformSimulation, String> {
        let mut settings = self.settings;
        if let Some(tol) = experiment.tolerance {
            settings.rel_tol = tol;
        }
        self.validate_settings(&settings, experiment.tolerance.is_some())?;
        let mut sim = PlatformSimulation::new(
            self.stand.clone(),
            self.initial_state(),
            settings,
            self.stabilisation,
            experiment.start_time,
        )
        .and_then(|sim| sim.with_end_stops(self.end_stops()))
        .map_err(|e| e.to_string())?;
        sim.stop_at_singularity = self.stop_at_singularity;
        if self.stop_at_singularity {
            let kappa = condition_number(sim.stand(), &sim.state);
            if !(kappa < SINGULAR_CONDITION_NUMBER) {
                return Err(format!(
                    "parameter r0: the initial pose is a singular leg arrangement (force/moment matrix condition \
                     number {kappa:e}, limit {SINGULAR_CONDITION_NUMBER:e}) and stopAtSingularity is on"
                ));
            }
        }
        // Model Exchange cannot project (the host's integrator owns the state): Baumgarte
        // terms keep the constraints unless stabilisation is off.
        let baumgarte = if experiment.model_exchange {
            self.stabilisation != Stabilisation::None
        } else {
            self.stabilisation == Stabilisation::Baumgarte
        };
        sim.form.body.baumgarte_rate = if baumgarte { self.baumgarte_rate } else { 0.0 };
        Ok(sim)
    }

    /// The solver settings in use (`solver.relTol` possibly replaced by the importer's
    /// tolerance, which the messages then name).
    fn validate_settings(&self, s: &SolverSettings, importer_tolerance: bool) -> Result<(), String> {
        let rel_tol = if importer_tolerance {
            "the importer's tolerance (fmi2SetupExperiment / fmi3EnterInitializationMode, which replaces solver.relTol)"
        } else {
            "parameter solver.relTol"
        };
        if !(s.rel_tol > 0.0 && s.rel_tol < 1.0) {
            return Err(format!("{rel_tol}: must be in (0, 1), got {:e}", s.rel_tol));
        }
        if s.rel_tol < MIN_REL_TOL {
            return Err(format!(
                "{rel_tol}: {:e} is below what double precision can meet (minimum {MIN_REL_TOL:e})",
                s.rel_tol
            ));
        }
        if !(s.abs_tol > 0.0) || !s.abs_tol.is_finite() {
            return Err(format!(
                "parameter solver.absTol: must be > 0, got {:e}: with pure relative error control a state component \
                 that is exactly zero (the neutral pose has several) admits no error at all, so no step could be \
                 accepted",
                s.abs_tol
            ));
        }
        if !(s.max_step >= 0.0) {
            return Err(format!("parameter solver.maxStep: must be >= 0 s (0 = no limit), got {}", s.max_step));
        }
        if !(s.fixed_step == 0.0 || (s.fixed_step >= MIN_FIXED_STEP && s.fixed_step.is_finite())) {
            return Err(format!(
                "parameter solver.fixedStep: must be 0 (one RK4 step per communication step) or at least \
                 {MIN_FIXED_STEP:e} s, got {:e} s",
                s.fixed_step
            ));
        }
        if !(self.baumgarte_rate >= 0.0) {
            return Err(format!("parameter solver.baumgarteRate: must be >= 0 1/s, got {}", self.baumgarte_rate));
        }
        Ok(())
    }

    /// The parameters in use, for `logEvents`.
    pub fn summary(&self, sim: &PlatformSimulation, experiment: &Experiment, legs: &[f64; LEG_COUNT]) -> String {
        let stops = match self.end_stops() {
            Some(s) => format!(
                "end stops on (stiffness {} N/m, damping {} N.s/m, strokes {:?} .. {:?} m)",
                s.stiffness, s.damping, s.lower, s.upper
            ),
            None => "end stops off".to_string(),
        };
        let p = self;
        format!(
            "initialised at t = {}: M = {} kg, J = {:?} kg.m2, g = {} m/s2, leg lengths {:?} m, kappa {:.4}, \
             {stops}, stopAtSingularity {}, method {:?}, relTol {:e}{}, stabilisation {}",
            experiment.start_time,
            p.stand.mass,
            p.stand.inertia,
            p.stand.gravity,
            legs,
            condition_number(sim.stand(), &sim.state),
            p.stop_at_singularity,
            sim.integrator.settings.method,
            sim.integrator.settings.rel_tol,
            if experiment.tolerance.is_some() { " (the importer's tolerance)" } else { "" },
            if sim.form.body.baumgarte_rate > 0.0 {
                format!("Baumgarte {} 1/s", sim.form.body.baumgarte_rate)
            } else {
                format!("{:?}", p.stabilisation)
            }
        )
    }
}

impl IntegerStorage for Method {
    fn code(&self) -> i32 {
        Method::code(*self)
    }
    fn set_code(&mut self, code: i32) -> Result<(), String> {
        *self = Method::from_code(code)
            .ok_or_else(|| format!("{code} is not a method (1 = Dormand-Prince 5(4), 2 = Runge-Kutta 4)"))?;
        Ok(())
    }
}

impl IntegerStorage for Stabilisation {
    fn code(&self) -> i32 {
        Stabilisation::code(*self)
    }
    fn set_code(&mut self, code: i32) -> Result<(), String> {
        *self = Stabilisation::from_code(code)
            .ok_or_else(|| format!("{code} is not a stabilisation (1 = none, 2 = projection, 3 = Baumgarte)"))?;
        Ok(())
    }
}
