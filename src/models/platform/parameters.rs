//! The platform's parameters (docs/model.md §5), their checks, and the simulation they
//! describe.

use nalgebra::Vector3;

use crate::integration::{Method, SolverSettings};
use crate::models::declare::IntegerStorage;
use crate::models::machine::Drive;
use crate::physics::actuators::{ActiveActuator, Actuators};
use crate::physics::body::kinematics::rotation_from_angles;
use crate::physics::body::state::{BodyState, STATE_DIM};
use crate::physics::direct_problem::SINGULAR_CONDITION_NUMBER;
use crate::physics::legs::bodies::LegBodies;
use crate::physics::legs::end_stops::EndStops;
use crate::physics::legs::friction::Friction;
use crate::physics::legs::joint_limits::{self, JointLimits};
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
    /// `leg.*`: the legs as bodies.
    pub legs: LegBodies,
    /// `friction.*`.
    pub friction: Friction,
    /// `joints`: whether the joint limits act.
    pub joints_enabled: bool,
    /// `joints.*`.
    pub joints: JointParameters,
    /// `drive`: what moves the legs (forces, electric drives, hydraulic servo legs).
    pub drive: Drive,
    /// Every actuator's parameters and initial states (`motor.*`, `gear.ratio`, `screw.lead`,
    /// `I0`; `hydraulic.*`, `valve.*`, `pA0`, `pB0`, and the input `pS` the hydraulic legs hold):
    /// the one of kind `drive` is the legs'.
    pub actuators: Actuators,
}

/// The joint-limit parameters (`joints.*`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointParameters {
    /// `joints.baseMaxAngle`, rad.
    pub base_max: f64,
    /// `joints.platformMaxAngle`, rad.
    pub platform_max: f64,
    /// `joints.stiffness`, N m/rad.
    pub stiffness: f64,
    /// `joints.damping`, N m s/rad.
    pub damping: f64,
    /// `joints.r0`: the reference pose's centre of mass, m.
    pub r0: Vector3<f64>,
    /// `joints.angles0`: the reference pose's roll, pitch, yaw, rad.
    pub angles0: Vector3<f64>,
}

impl Default for JointParameters {
    /// The default limits about the default stand's neutral pose.
    fn default() -> Self {
        JointParameters {
            base_max: joint_limits::DEFAULT_BASE_MAX_ANGLE,
            platform_max: joint_limits::DEFAULT_PLATFORM_MAX_ANGLE,
            stiffness: joint_limits::DEFAULT_STIFFNESS,
            damping: joint_limits::DEFAULT_DAMPING,
            r0: Stand::truck_cabin_neutral_position(),
            angles0: Vector3::zeros(),
        }
    }
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
            legs: LegBodies::default(),
            friction: Friction::default(),
            joints_enabled: true,
            joints: JointParameters::default(),
            drive: Drive::Forces,
            actuators: Actuators::default(),
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

pub use crate::physics::actuators::hydraulics::holding_pressures;

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

    /// The joint limits if they are on (about the reference pose; `None` where a leg
    /// collapses at the reference pose, which [`PlatformParameters::simulation`] refuses).
    pub fn joint_limits(&self) -> Option<JointLimits> {
        if !self.joints_enabled {
            return None;
        }
        let j = &self.joints;
        let rotation0 = rotation_from_angles(&j.angles0);
        let mut n0 = [Vector3::zeros(); LEG_COUNT];
        for k in 0..LEG_COUNT {
            let leg = j.r0 + rotation0 * self.stand.platform_joints[k] - self.stand.base_joints[k];
            n0[k] = leg.try_normalize(0.0)?;
        }
        Some(JointLimits::new(j.base_max, j.platform_max, j.stiffness, j.damping, n0, &rotation0))
    }

    /// The actuator of kind `drive` with its parameters, on the end stops' strokes.
    pub fn actuator(&self) -> ActiveActuator {
        self.actuators.active(self.drive).on_strokes(&self.stops.lower, &self.stops.upper)
    }

    /// The special form these parameters describe (before initialisation).
    pub fn special_form(&self) -> SpecialForm {
        SpecialForm::new(self.stand.clone())
            .with_end_stops(self.end_stops())
            .with_machine(self.legs, self.friction, self.joint_limits())
            .with_actuator(self.actuator())
    }

    /// The simulation state these parameters describe (before initialisation).
    pub fn initial_simulation_state(&self) -> SimulationState {
        let mut y = [0.0; SIMULATION_DIM];
        if let Some(b) = y.first_chunk_mut::<STATE_DIM>() {
            *b = self.initial_state().to_vector();
        }
        self.actuator().initial_state(&mut y);
        y
    }

    /// Validates the parameters and builds the simulation of an experiment.
    pub fn simulation(&self, experiment: &Experiment) -> Result<PlatformSimulation, String> {
        let mut settings = self.settings;
        if let Some(tol) = experiment.tolerance {
            settings.rel_tol = tol;
        }
        self.validate_settings(&settings, experiment.tolerance.is_some())?;
        let sim = PlatformSimulation::new(
            self.stand.clone(),
            self.initial_state(),
            settings,
            self.stabilisation,
            experiment.start_time,
        )
        .and_then(|sim| sim.with_end_stops(self.end_stops()))
        .map_err(|e| e.to_string())?;
        let joint_limits = if self.joints_enabled {
            Some(self.joint_limits().ok_or_else(|| {
                "parameter joints.r0: a leg has zero length in the joint limits' reference pose (joints.r0, \
                 joints.angles0)"
                    .to_string()
            })?)
        } else {
            None
        };
        let mut sim = sim
            .with_machine(self.legs, self.friction, joint_limits)
            .and_then(|sim| sim.with_actuator(self.actuator()))
            .map_err(|e| e.to_string())?;
        if let Some(limits) = &joint_limits {
            check_initial_joint_angles(limits, &sim)?;
        }
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
            return Err(format!("parameter solver.maxStep: must be >= 0 s (0 = no limit), got {:?}", s.max_step));
        }
        if !(s.fixed_step == 0.0 || (s.fixed_step >= MIN_FIXED_STEP && s.fixed_step.is_finite())) {
            return Err(format!(
                "parameter solver.fixedStep: must be 0 (one RK4 step per communication step) or at least \
                 {MIN_FIXED_STEP:e} s, got {:e} s",
                s.fixed_step
            ));
        }
        if !(self.baumgarte_rate >= 0.0) {
            return Err(format!("parameter solver.baumgarteRate: must be >= 0 1/s, got {:?}", self.baumgarte_rate));
        }
        Ok(())
    }

    /// The parameters in use, for `logEvents`.
    pub fn summary(&self, sim: &PlatformSimulation, experiment: &Experiment, legs: &[f64; LEG_COUNT]) -> String {
        let stops = match self.end_stops() {
            Some(s) => format!(
                "end stops on (stiffness {:?} N/m, damping {:?} N.s/m, strokes {:?} .. {:?} m)",
                s.stiffness, s.damping, s.lower, s.upper
            ),
            None => "end stops off".to_string(),
        };
        let drives = self.actuator().describe();
        let p = self;
        format!(
            "initialised at t = {:?}: M = {:?} kg, J = {:?} kg.m2, g = {:?} m/s2, leg lengths {:?} m, kappa {:.4}, \
             {stops}{drives}, stopAtSingularity {}, method {:?}, relTol {:e}{}, stabilisation {}",
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
                format!("Baumgarte {:?} 1/s", sim.form.body.baumgarte_rate)
            } else {
                format!("{:?}", p.stabilisation)
            }
        )
    }
}

/// The stiffest of the contact and friction laws, as an explicit integrator sees it.
#[derive(Clone, Debug, PartialEq)]
pub struct StiffLaw {
    /// What it is, naming its parameters.
    pub what: String,
    /// Its time scale, s: a contact's period, or friction's time constant.
    pub time: f64,
    /// The largest step RK4 integrates it stably with, s.
    pub rk4_stable_step: f64,
}

impl PlatformParameters {
    /// The law that bounds an explicit integrator's step the most: the end stops' and joint
    /// limits' contact periods (`2 pi sqrt(mass / stiffness)`: the platform's mass on six
    /// stops, its smallest moment of inertia on a joint limit) and friction's time constant
    /// near rest (`(M/6) / (F_s / v_t)`). RK4 is stable below 0.45 of an undamped period
    /// (`omega h < 2.83`) and 2.78 time constants of a decay. `None` without any.
    pub fn stiffest_law(&self) -> Option<StiffLaw> {
        let tau = 2.0 * std::f64::consts::PI;
        let mut laws = vec![];
        if self.stops_enabled && self.stops.stiffness > 0.0 {
            let period = tau * (self.stand.mass / (6.0 * self.stops.stiffness)).sqrt();
            laws.push(StiffLaw {
                what: format!(
                    "the end stops' contact period (stops.stiffness = {:e} N/m under the platform's mass on six stops)",
                    self.stops.stiffness
                ),
                time: period,
                rk4_stable_step: 0.45 * period,
            });
        }
        if self.joints_enabled && self.joints.stiffness > 0.0 {
            let inertia = self.stand.inertia.iter().copied().fold(f64::INFINITY, f64::min);
            let period = tau * (inertia / self.joints.stiffness).sqrt();
            laws.push(StiffLaw {
                what: format!(
                    "the joint limits' contact period (joints.stiffness = {:e} N.m/rad under the platform's smallest \
                     moment of inertia)",
                    self.joints.stiffness
                ),
                time: period,
                rk4_stable_step: 0.45 * period,
            });
        }
        let grip = self.friction.static_.max(self.friction.coulomb);
        if grip > 0.0 && self.friction.smoothing > 0.0 {
            let time = self.stand.mass / 6.0 / (grip / self.friction.smoothing);
            laws.push(StiffLaw {
                what: format!(
                    "the cylinder friction's time constant near rest (friction.static = {:e} N over \
                     friction.smoothing = {:e} m/s, a sixth of the platform's mass)",
                    grip, self.friction.smoothing
                ),
                time,
                rk4_stable_step: 2.78 * time,
            });
        }
        laws.into_iter().min_by(|a, b| a.rk4_stable_step.total_cmp(&b.rk4_stable_step))
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

/// Refuses an initial pose with a joint beyond its limit by more than the angle at which one
/// joint's limit alone holds the platform's weight on a lever of the stand's characteristic
/// length (a pose at rest on its limits is allowed, as on the end stops).
fn check_initial_joint_angles(limits: &JointLimits, sim: &PlatformSimulation) -> Result<(), String> {
    let stand = sim.stand();
    let outputs = crate::simulation::outputs::LegLoadOutputs::at(&sim.form, &sim.state);
    let allowed = stand.mass * stand.gravity * stand.characteristic_length() / limits.stiffness;
    for k in 0..LEG_COUNT {
        for (which, name, theta, max) in [
            ("base", "joints.baseMaxAngle", outputs.theta_b[k], limits.base_max),
            ("platform", "joints.platformMaxAngle", outputs.theta_a[k], limits.platform_max),
        ] {
            if theta - max > allowed {
                return Err(format!(
                    "parameter r0: in the initial pose the {which} joint of leg {} is at {theta:e} rad from the \
                     reference pose (joints.r0, joints.angles0), beyond {name} = {max:e} rad by more than the \
                     static deflection M g / joints.stiffness x the stand's size ({allowed:e} rad): move the initial \
                     pose, the reference pose or the limit",
                    k + 1
                ));
            }
        }
    }
    Ok(())
}
