//! The `StewartPlatform` model: the stand's parameters and initial pose as FMI parameters,
//! the six leg forces as inputs, the pose, legs and energy as outputs (docs/model.md §5).

pub mod variables;

use crate::models::Initialised;
use nalgebra::Vector3;

use super::snapshot::{ByteReader, ByteWriter, SnapshotError};
use super::variables::VariableRef;
use super::{DefaultExperiment, EventUpdate, FmuModel, ModelInfo, StepError, StepReport, fill_group};
use crate::integration::dopri5::Dopri5Memory;
use crate::integration::{Crossing, Integrator, IntegratorStats, Method, SolverSettings, SwitchingSides};
use crate::physics::body_state::{BodyState, STATE_DIM, layout};
use crate::physics::configuration::ConfigurationGuard;
use crate::physics::direct_problem::{SINGULAR_CONDITION_NUMBER, singular_legs};
use crate::physics::end_stops::EndStops;
use crate::physics::error::leg_list;
use crate::physics::forces::HeldForces;
use crate::physics::kinematics::rotation_from_angles;
use crate::physics::legs::LegGeometry;
use crate::physics::special_form::SpecialForm;
use crate::physics::stand::{LEG_COUNT, PAPER_EQUILIBRIUM_LEG_FORCE, Stand};
use crate::simulation::outputs::{condition_number, condition_number_tangent};
use crate::simulation::platform::{Reached, SIMULATION_DIM, SimulationState, body, quadrature, switching};
use crate::simulation::{LegOutputs, PlatformOutputs, PlatformSimulation, Stabilisation};
use variables::group;

pub static INFO: ModelInfo = ModelInfo {
    model_name: "StewartPlatform",
    model_identifier: "StewartPlatform",
    description: "Loaded Stewart platform (hexapod): rigid-body dynamics in the special form of Zegzhda, Petrova and \
                  Yushkov (2020), six axial leg forces in, pose and leg lengths out",
    groups: variables::GROUPS,
    enumerations: &[],
    units: super::units::UNITS,
    default_experiment: DefaultExperiment { start_time: 0.0, stop_time: 3.0, step_size: 1e-2 },
    documentation: include_str!("documentation.html"),
    states: variables::STATES,
    capabilities: super::Capabilities {
        model_exchange: true,
        directional_derivatives: true,
        adjoint_derivatives: true,
        can_interpolate_inputs: true,
        max_output_derivative_order: 1,
        event_indicators: switching::COUNT,
    },
};

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

impl PlatformParameters {
    pub fn initial_state(&self) -> BodyState {
        BodyState::from_pose(self.r0, self.v0, &rotation_from_angles(&self.angles0), &self.w0)
    }

    /// The end stops if they are on.
    pub fn end_stops(&self) -> Option<EndStops> {
        self.stops_enabled.then_some(self.stops)
    }

    /// The special form these parameters describe (before initialisation).
    fn special_form(&self) -> SpecialForm {
        SpecialForm::new(self.stand.clone()).with_end_stops(self.end_stops())
    }

    /// The simulation state these parameters describe (before initialisation).
    fn initial_simulation_state(&self) -> SimulationState {
        let mut y = [0.0; SIMULATION_DIM];
        if let Some(b) = y.first_chunk_mut::<STATE_DIM>() {
            *b = self.initial_state().to_vector();
        }
        y
    }

    /// `importer_tolerance`: `solver.relTol` was replaced by the importer's tolerance
    /// (`fmi2SetupExperiment`, `fmi3EnterInitializationMode`), so messages name that instead.
    fn validate_settings(&self, importer_tolerance: bool) -> Result<(), String> {
        let s = &self.settings;
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

/// The blocks of the platform's value cache ([`FmuModel::cache_block`]).
mod cache_block {
    /// `l`, `ldot`: what a controller reads every step, computed alone.
    pub const LEGS: u8 = 0;
    /// Every other output of [`super::PlatformOutputs`].
    pub const OUTPUTS: u8 = 1;
}

/// The outputs read through [`cache_block::OUTPUTS`] (all of [`PlatformOutputs`] but the legs).
const OUTPUT_GROUPS: [usize; 10] = [
    group::R,
    group::V,
    group::ROT,
    group::ANGLES,
    group::W,
    group::E,
    group::CONSTRAINT_ERROR,
    group::FSTOP,
    group::WORK_F,
    group::WORK_DISSIPATED,
];

/// The platform FMU model.
#[derive(Clone, Debug)]
pub struct PlatformModel {
    pub parameters: PlatformParameters,
    /// Leg forces `F[k]`, N.
    pub forces: [f64; LEG_COUNT],
    /// Their time derivatives for the next step, N/s (cleared after each step).
    pub force_rates: [f64; LEG_COUNT],
    /// Present after `fmi2ExitInitializationMode`.
    pub simulation: Option<PlatformSimulation>,
    /// Outputs of the current state, computed on the first read after a change.
    outputs: Option<PlatformOutputs>,
    /// Leg lengths and rates of the current state: what a controller reads every step, so
    /// they are computed alone (the leg geometry) rather than with every other output.
    legs: Option<LegOutputs>,
    /// `kappa` of the current state, computed on its first read after a change.
    kappa: Option<f64>,
    /// Whether passages through singular arrangements are reported (see
    /// [`FmuModel::set_event_reporting`]).
    events_reported: bool,
}

impl Default for PlatformModel {
    fn default() -> Self {
        PlatformModel {
            parameters: PlatformParameters::default(),
            forces: [default_leg_force(); LEG_COUNT],
            force_rates: [0.0; LEG_COUNT],
            simulation: None,
            outputs: None,
            legs: None,
            kappa: None,
            events_reported: true,
        }
    }
}

impl PlatformModel {
    /// The outputs of the current state, computed on the first read after a change.
    fn outputs(&mut self) -> &PlatformOutputs {
        let (simulation, parameters) = (&self.simulation, &self.parameters);
        self.outputs.get_or_insert_with(|| match simulation {
            Some(sim) => PlatformOutputs::compute(&sim.form, &sim.state),
            None => PlatformOutputs::compute(&parameters.special_form(), &parameters.initial_simulation_state()),
        })
    }

    /// `kappa` of the current state, computed on its first read after a change.
    fn kappa(&mut self) -> f64 {
        let (simulation, parameters) = (&self.simulation, &self.parameters);
        *self.kappa.get_or_insert_with(|| match simulation {
            Some(sim) => condition_number(sim.stand(), &sim.state),
            None => condition_number(&parameters.stand, &parameters.initial_simulation_state()),
        })
    }

    /// After a set of Real values: in Initialization Mode the outputs follow the parameters.
    fn values_set(&mut self) {
        if self.simulation.is_none() {
            self.invalidate_outputs();
        }
    }

    /// The current state changed: the cached outputs are stale.
    fn invalidate_outputs(&mut self) {
        self.outputs = None;
        self.legs = None;
        self.kappa = None;
    }

    fn leg_outputs(&mut self) -> &LegOutputs {
        let (simulation, parameters, outputs) = (&self.simulation, &self.parameters, &self.outputs);
        self.legs.get_or_insert_with(|| match (outputs, simulation) {
            (Some(o), _) => LegOutputs { l: o.l, ldot: o.ldot },
            (None, Some(sim)) => LegOutputs::compute(&sim.form, &sim.state),
            (None, None) => LegOutputs::compute(&parameters.special_form(), &parameters.initial_simulation_state()),
        })
    }

    fn held_forces(&self, t0: f64) -> HeldForces {
        HeldForces { value: self.forces, slope: self.force_rates, t0 }
    }

    fn parameter_slot(&mut self, var: VariableRef) -> Option<&mut f64> {
        let p = &mut self.parameters;
        let i = var.index;
        Some(match var.group {
            group::M => &mut p.stand.mass,
            group::J => p.stand.inertia.get_mut(i)?,
            group::G => &mut p.stand.gravity,
            group::B => p.stand.base_joints.get_mut(i / 3)?.get_mut(i % 3)?,
            group::A => p.stand.platform_joints.get_mut(i / 3)?.get_mut(i % 3)?,
            group::R0 => p.r0.get_mut(i)?,
            group::ANGLES0 => p.angles0.get_mut(i)?,
            group::V0 => p.v0.get_mut(i)?,
            group::W0 => p.w0.get_mut(i)?,
            group::REL_TOL => &mut p.settings.rel_tol,
            group::ABS_TOL => &mut p.settings.abs_tol,
            group::MAX_STEP => &mut p.settings.max_step,
            group::FIXED_STEP => &mut p.settings.fixed_step,
            group::BAUMGARTE_RATE => &mut p.baumgarte_rate,
            group::LMIN => p.stops.lower.get_mut(i)?,
            group::LMAX => p.stops.upper.get_mut(i)?,
            group::STOP_STIFFNESS => &mut p.stops.stiffness,
            group::STOP_DAMPING => &mut p.stops.damping,
            group::F => self.forces.get_mut(i)?,
            _ => return None,
        })
    }

    /// Runs `f` with the special form and the state the model is at: the simulation's, or
    /// before initialisation the one the parameters describe.
    fn with_current<R>(&self, f: impl FnOnce(&SpecialForm, &SimulationState, f64) -> R) -> R {
        match &self.simulation {
            Some(sim) => f(&sim.form, &sim.state, sim.time),
            None => f(&self.parameters.special_form(), &self.parameters.initial_simulation_state(), 0.0),
        }
    }

    /// The rate of the simulation state for the current (held) forces.
    fn state_rate(form: &SpecialForm, y: &SimulationState, t: f64, forces: [f64; LEG_COUNT]) -> SimulationState {
        let mut dy = [0.0; SIMULATION_DIM];
        let law = HeldForces::constant(forces);
        if let Some((db, dq)) = dy.split_first_chunk_mut::<STATE_DIM>() {
            let power = form.derivative(t, body(y), &law, db);
            if let [w, d] = dq {
                *w = power.actuator;
                *d = power.dissipation;
            }
        }
        dy
    }

    /// `der(v)`, `der(R)`, `der(R,2)`, `der(work.F)`, `der(work.dissipated)`: the derivative
    /// variables of Model Exchange.
    fn derivative_value(&self, var: VariableRef) -> f64 {
        let forces = self.forces;
        self.with_current(|form, y, t| {
            let dy = Self::state_rate(form, y, t, forces);
            let pick = |i: usize| dy.get(i).copied().unwrap_or(f64::NAN);
            match var.group {
                group::DER_V => pick(layout::V + var.index),
                group::DER_R => y.get(rotation_state_index(layout::E_DOT, var.index)).copied().unwrap_or(f64::NAN),
                group::DER2_R => pick(rotation_state_index(layout::E_DOT, var.index)),
                group::DER_WORK_F => pick(quadrature::WORK_F),
                _ => pick(quadrature::WORK_DISSIPATED),
            }
        })
    }

    /// [`FmuModel::fill_cache`] of the outputs block.
    #[inline(never)]
    fn fill_outputs(&mut self, cache: &mut [f64]) -> bool {
        let outputs = *self.outputs();
        let mut nan = false;
        for g in OUTPUT_GROUPS {
            let first = variables::GROUPS[g].first_vr as usize;
            for index in 0..variables::GROUPS[g].len() {
                if let Some(slot) = cache.get_mut(first + index) {
                    *slot = Self::output_value(&outputs, VariableRef { group: g, index });
                    nan |= slot.is_nan();
                }
            }
        }
        nan
    }

    fn output_value(o: &PlatformOutputs, var: VariableRef) -> f64 {
        let i = var.index;
        let pick3 = |v: &Vector3<f64>| v.get(i).copied().unwrap_or(0.0);
        let pick6 = |v: &[f64; LEG_COUNT]| v.get(i).copied().unwrap_or(0.0);
        match var.group {
            group::R => pick3(&o.r),
            group::V => pick3(&o.v),
            // R[a,b], row-major index a*3+b.
            group::ROT => o.rotation.get((i / 3, i % 3)).copied().unwrap_or(0.0),
            group::ANGLES => pick3(&o.angles),
            group::W => pick3(&o.w),
            group::L => pick6(&o.l),
            group::LDOT => pick6(&o.ldot),
            group::E => o.energy,
            group::CONSTRAINT_ERROR => o.constraint_error,
            group::FSTOP => pick6(&o.stop_force),
            group::WORK_F => o.work_of_forces,
            group::WORK_DISSIPATED => o.dissipated_energy,
            _ => 0.0,
        }
    }

    /// What a crossing of switching function `c.index` means, in words.
    fn describe_crossing(sim: &PlatformSimulation, c: &Crossing<SIMULATION_DIM>) -> String {
        let state = BodyState::from_vector(body(&c.y));
        let legs = LegGeometry::new(sim.stand(), &state);
        let rates = legs.length_rates(sim.stand(), &state);
        let (stop, k) = match c.index {
            i if i < switching::UPPER => ("lower", i - switching::LOWER),
            i if i < switching::DETERMINANT => ("upper", i - switching::UPPER),
            _ => {
                let involved = singular_legs(sim.stand(), &legs);
                return format!(
                    "t = {}: the legs passed through a singular arrangement (determinant of the force/moment matrix \
                     changed sign; legs {} form a force combination without resultant there)",
                    c.t,
                    leg_list(&involved)
                );
            }
        };
        let (Some(l), Some(ldot)) = (legs.length.get(k), rates.get(k)) else { return String::new() };
        let what = if c.rising { "left" } else { "reached" };
        format!("t = {}: leg {} {what} its {stop} end stop (l = {l} m, ldot = {ldot} m/s)", c.t, k + 1)
    }
}

impl FmuModel for PlatformModel {
    fn info(&self) -> &'static ModelInfo {
        &INFO
    }

    fn get_real(&mut self, var: VariableRef) -> f64 {
        if var.group == group::TIME {
            return self.simulation.as_ref().map_or(0.0, |s| s.time);
        }
        match var.group {
            group::DER_V | group::DER_R | group::DER2_R | group::DER_WORK_F | group::DER_WORK_DISSIPATED => {
                self.derivative_value(var)
            }
            group::KAPPA => self.kappa(),
            group::EVENT_INDICATORS => {
                let mut z = [0.0; switching::COUNT];
                self.event_indicators(&mut z);
                z.get(var.index).copied().unwrap_or(f64::NAN)
            }
            group::L => self.leg_outputs().l.get(var.index).copied().unwrap_or(f64::NAN),
            group::LDOT => self.leg_outputs().ldot.get(var.index).copied().unwrap_or(f64::NAN),
            g if variables::is_output_or_derivative(g) => Self::output_value(self.outputs(), var),
            _ => self.parameter_slot(var).map_or(f64::NAN, |slot| *slot),
        }
    }

    fn set_event_reporting(&mut self, on: bool) {
        self.events_reported = on;
        if let Some(sim) = self.simulation.as_mut() {
            sim.set_track_singularities(on);
        }
    }

    fn cache_block(&self, group: usize) -> Option<u8> {
        match group {
            group::L | group::LDOT => Some(cache_block::LEGS),
            g if OUTPUT_GROUPS.contains(&g) => Some(cache_block::OUTPUTS),
            _ => None,
        }
    }

    #[inline]
    fn fill_cache(&mut self, block: u8, cache: &mut [f64]) -> bool {
        if block == cache_block::LEGS {
            // Read every step by most hosts: kept small (the other block is out of line).
            let legs = self.leg_outputs();
            let nan_l = fill_group(cache, &variables::GROUPS[group::L], &legs.l);
            nan_l | fill_group(cache, &variables::GROUPS[group::LDOT], &legs.ldot)
        } else {
            self.fill_outputs(cache)
        }
    }

    fn set_real(&mut self, var: VariableRef, value: f64) -> Result<(), String> {
        let slot = self.parameter_slot(var).ok_or("not a settable Real variable")?;
        *slot = value;
        self.values_set();
        Ok(())
    }

    #[inline]
    fn set_real_run(&mut self, first: VariableRef, values: &[f64]) -> Result<(), String> {
        // The leg forces, set every step: one copy.
        if first.group == group::F
            && let Some(forces) = self.forces.get_mut(first.index..first.index + values.len())
        {
            forces.copy_from_slice(values);
            self.values_set();
            return Ok(());
        }
        super::set_one_by_one(self, first, values)
    }

    fn get_integer(&mut self, var: VariableRef) -> i32 {
        match var.group {
            group::METHOD => self.parameters.settings.method.code(),
            group::STABILISATION => self.parameters.stabilisation.code(),
            _ => 0,
        }
    }

    fn set_integer(&mut self, var: VariableRef, value: i32) -> Result<(), String> {
        match var.group {
            group::METHOD => {
                self.parameters.settings.method = Method::from_code(value)
                    .ok_or_else(|| format!("{value} is not a method (1 = Dormand-Prince 5(4), 2 = Runge-Kutta 4)"))?;
            }
            group::STABILISATION => {
                self.parameters.stabilisation = Stabilisation::from_code(value).ok_or_else(|| {
                    format!("{value} is not a stabilisation (1 = none, 2 = projection, 3 = Baumgarte)")
                })?;
            }
            _ => return Err("not a settable Integer variable".into()),
        }
        Ok(())
    }

    fn get_boolean(&mut self, var: VariableRef) -> bool {
        match var.group {
            group::STOPS => self.parameters.stops_enabled,
            group::STOP_AT_SINGULARITY => self.parameters.stop_at_singularity,
            _ => false,
        }
    }

    fn set_boolean(&mut self, var: VariableRef, value: bool) -> Result<(), String> {
        match var.group {
            group::STOPS => self.parameters.stops_enabled = value,
            group::STOP_AT_SINGULARITY => self.parameters.stop_at_singularity = value,
            _ => return Err("not a settable Boolean variable".into()),
        }
        if self.simulation.is_none() {
            self.invalidate_outputs();
        }
        Ok(())
    }

    fn exit_initialization(
        &mut self,
        start_time: f64,
        tolerance: Option<f64>,
        model_exchange: bool,
    ) -> Result<Initialised, String> {
        let mut p = self.parameters.clone();
        if let Some(tol) = tolerance {
            p.settings.rel_tol = tol;
        }
        p.validate_settings(tolerance.is_some())?;
        let mut sim =
            PlatformSimulation::new(p.stand.clone(), p.initial_state(), p.settings, p.stabilisation, start_time)
                .and_then(|sim| sim.with_end_stops(p.end_stops()))
                .map_err(|e| e.to_string())?;
        sim.stop_at_singularity = p.stop_at_singularity;
        sim.set_track_singularities(self.events_reported);
        let kappa = condition_number(sim.stand(), &sim.state);
        if p.stop_at_singularity && !(kappa < SINGULAR_CONDITION_NUMBER) {
            return Err(format!(
                "parameter r0: the initial pose is a singular leg arrangement (force/moment matrix condition number \
                 {kappa:e}, limit {SINGULAR_CONDITION_NUMBER:e}) and stopAtSingularity is on"
            ));
        }
        // Model Exchange cannot project (the host's integrator owns the state): Baumgarte
        // terms keep the constraints unless stabilisation is off.
        let baumgarte = if model_exchange {
            p.stabilisation != Stabilisation::None
        } else {
            p.stabilisation == Stabilisation::Baumgarte
        };
        sim.form.baumgarte_rate = if baumgarte { p.baumgarte_rate } else { 0.0 };
        // The sides of the switching functions at the start (Model Exchange's event
        // bookkeeping; the co-simulation integrator uses the same).
        sim.integrator.sides = crate::integration::switching_sides(
            &sim.dynamics(&HeldForces::constant(self.forces)),
            start_time,
            &sim.state,
        );
        let legs = PlatformOutputs::compute(&sim.form, &sim.state).l;
        let stops = match p.end_stops() {
            Some(s) => format!(
                "end stops on (stiffness {} N/m, damping {} N.s/m, strokes {:?} .. {:?} m)",
                s.stiffness, s.damping, s.lower, s.upper
            ),
            None => "end stops off".to_string(),
        };
        let summary = format!(
            "initialised at t = {start_time}: M = {} kg, J = {:?} kg.m2, g = {} m/s2, leg lengths {:?} m, \
             kappa {kappa:.4}, {stops}, stopAtSingularity {}, method {:?}, relTol {:e}{}, stabilisation {}",
            p.stand.mass,
            p.stand.inertia,
            p.stand.gravity,
            legs,
            p.stop_at_singularity,
            p.settings.method,
            p.settings.rel_tol,
            if tolerance.is_some() { " (the importer's tolerance)" } else { "" },
            if sim.form.baumgarte_rate > 0.0 {
                format!("Baumgarte {} 1/s", sim.form.baumgarte_rate)
            } else {
                format!("{:?}", p.stabilisation)
            }
        );
        let (sim_guard_side, sim_guard_plane) = (sim.guard.side, sim.guard.base_plane);
        self.simulation = Some(sim);
        self.invalidate_outputs();
        // Legal (a suspended hexapod hangs under its base), but with the default stand it is
        // a mistyped height, and the pushing legs and gravity take the platform away.
        let warning = (sim_guard_side < 0.0).then(|| {
            format!(
                "all platform joints start below the base plane (z = {sim_guard_plane} m; r0[3] = {} m): the \
                 platform hangs under its base like a suspended hexapod, and legs that push (F > 0) drive it \
                 further down; raise r0[3] if it should stand on its legs",
                p.r0[2]
            )
        });
        Ok(Initialised { summary, warning })
    }

    fn do_step(&mut self, t: f64, h: f64, stop_at_event: bool) -> Result<StepReport, StepError> {
        let law = self.held_forces(t);
        let Some(sim) = self.simulation.as_mut() else {
            return Err(StepError { message: "the model is not initialised".into(), retry_shorter: false });
        };
        let t_end = t + h;
        let result = if t_end > sim.time {
            sim.advance_until_event(&law, t_end, stop_at_event)
        } else {
            sim.crossings.clear();
            Ok(Reached { t: t_end, legs: None })
        };
        let event =
            sim.crossings.as_slice().iter().any(|c| c.index < switching::DETERMINANT) || sim.crossings.dropped > 0;
        self.force_rates = [0.0; LEG_COUNT];
        match result {
            Ok(reached) => {
                self.invalidate_outputs();
                // The step computed the legs of its end state already.
                self.legs = reached.legs;
                Ok(StepReport { reached: reached.t, event })
            }
            Err(failure) => Err(StepError {
                message: if failure.is_step_limit() {
                    format!(
                        "step from t = {t} to {t_end} rolled back: {failure}; retry from t = {t} with shorter \
                         communication steps"
                    )
                } else {
                    format!("step from t = {t} to {t_end} rolled back: {failure}; leg forces {:?} N", self.forces)
                },
                retry_shorter: failure.is_step_limit(),
            }),
        }
    }

    fn report_events(&mut self, sink: &mut dyn FnMut(&str)) {
        let Some(sim) = &self.simulation else { return };
        for c in sim.crossings.as_slice() {
            sink(&Self::describe_crossing(sim, c));
        }
        if sim.crossings.dropped > 0 {
            sink(&format!(
                "{} more contact or singularity events in this step were not reported",
                sim.crossings.dropped
            ));
        }
    }

    fn set_input_derivative(&mut self, var: VariableRef, value: f64) {
        if var.group == group::F
            && let Some(slot) = self.force_rates.get_mut(var.index)
        {
            *slot = value;
        }
    }

    fn output_derivative(&mut self, var: VariableRef) -> f64 {
        let Some(sim) = &self.simulation else {
            return 0.0;
        };
        let dy = Self::state_rate(&sim.form, &sim.state, sim.time, self.forces);
        if var.group == group::KAPPA {
            return condition_number_tangent(sim.stand(), &sim.state, &dy);
        }
        Self::output_value(&PlatformOutputs::tangent(&sim.form, &sim.state, &dy), var)
    }

    fn set_time(&mut self, t: f64) {
        if let Some(sim) = self.simulation.as_mut() {
            sim.time = t;
        }
    }

    fn continuous_states(&self, x: &mut [f64]) {
        if let Some(sim) = &self.simulation {
            for (xi, yi) in x.iter_mut().zip(sim.state.iter()) {
                *xi = *yi;
            }
        }
    }

    fn set_continuous_states(&mut self, x: &[f64]) {
        if let Some(sim) = self.simulation.as_mut() {
            for (yi, xi) in sim.state.iter_mut().zip(x) {
                *yi = *xi;
            }
            self.invalidate_outputs();
        }
    }

    fn derivatives(&mut self, dx: &mut [f64]) {
        let Some(sim) = &self.simulation else { return };
        let dy = Self::state_rate(&sim.form, &sim.state, sim.time, self.forces);
        for (d, v) in dx.iter_mut().zip(dy) {
            *d = v;
        }
    }

    fn event_indicators(&mut self, z: &mut [f64]) {
        let law = HeldForces::constant(self.forces);
        match &self.simulation {
            Some(sim) => sim.switching_values(&law, z),
            None => {
                // Before initialisation: the parameters' initial pose (for Initialization Mode).
                let form = self.parameters.special_form();
                let y = self.parameters.initial_simulation_state();
                let guard = ConfigurationGuard {
                    min_leg_length: 0.0,
                    base_plane: 0.0,
                    side: 1.0,
                    characteristic_length: form.stand.characteristic_length().max(f64::MIN_POSITIVE),
                };
                let dynamics =
                    crate::simulation::PlatformDynamics::new(&form, &law, Stabilisation::Projection, &guard, false);
                dynamics.switching_values(body(&y), z);
            }
        }
    }

    fn event_update(&mut self, sink: &mut dyn FnMut(&str)) -> EventUpdate {
        let forces = self.forces;
        let Some(sim) = self.simulation.as_mut() else { return EventUpdate::default() };
        let law = HeldForces::constant(forces);
        let now = crate::integration::switching_sides(&sim.dynamics(&law), sim.time, &sim.state);
        let changed = now.bits ^ sim.integrator.sides.bits;
        let mut update = EventUpdate::default();
        for i in (0..switching::COUNT).filter(|i| changed >> i & 1 == 1) {
            let c = Crossing { index: i, t: sim.time, rising: now.bits >> i & 1 == 1, y: sim.state };
            let message = Self::describe_crossing(sim, &c);
            if i == switching::DETERMINANT && sim.stop_at_singularity {
                update.terminate = Some(format!("{message}, and stopAtSingularity is on"));
            }
            sink(&message);
        }
        sim.integrator.sides = now;
        update
    }

    fn completed_integrator_step(&mut self) -> Result<(), StepError> {
        let Some(sim) = &self.simulation else { return Ok(()) };
        sim.guard.check(&sim.form.joints, &sim.body_state()).map_err(|f| StepError {
            message: format!("at t = {}: {f}; the simulation cannot go on", sim.time),
            retry_shorter: false,
        })
    }

    fn directional_derivative(
        &mut self,
        unknowns: &[VariableRef],
        knowns: &[VariableRef],
        seeds: &[f64],
        out: &mut [f64],
    ) -> Result<(), String> {
        let mut dy = [0.0; SIMULATION_DIM];
        let mut du = [0.0; LEG_COUNT];
        for (k, &seed) in knowns.iter().zip(seeds) {
            match seed_of(*k) {
                Some(Seed::State(i)) => {
                    if let Some(x) = dy.get_mut(i) {
                        *x += seed;
                    }
                }
                Some(Seed::Force(i)) => {
                    if let Some(x) = du.get_mut(i) {
                        *x += seed;
                    }
                }
                None => {
                    return Err(format!(
                        "known {} is neither a state nor an input (derivatives are with respect to r, v, R, der(R), \
                         work.F, work.dissipated and F)",
                        variables::GROUPS.get(k.group).map_or(String::new(), |g| g.element_name(k.index))
                    ));
                }
            }
        }
        let forces = self.forces;
        let (df, power, doutputs, dkappa) = self.with_current(|form, y, _t| {
            let (df, power) = form.derivative_tangent(body(y), &forces, body(&dy), &du);
            let o = PlatformOutputs::tangent(form, y, &dy);
            let needs_kappa = unknowns.iter().any(|u| u.group == group::KAPPA);
            let dk = if needs_kappa { condition_number_tangent(&form.stand, y, &dy) } else { 0.0 };
            (df, power, o, dk)
        });
        for (value, u) in out.iter_mut().zip(unknowns) {
            *value = match u.group {
                group::DER_V => df[layout::V + u.index % 3],
                group::DER_R => dy[rotation_state_index(layout::E_DOT, u.index)],
                group::DER2_R => df[rotation_state_index(layout::E_DOT, u.index)],
                group::DER_WORK_F => power.actuator,
                group::DER_WORK_DISSIPATED => power.dissipation,
                group::KAPPA => dkappa,
                g if variables::is_output_or_derivative(g) => Self::output_value(&doutputs, *u),
                _ => {
                    return Err(format!(
                        "unknown {} is not an output, state or derivative",
                        variables::GROUPS.get(u.group).map_or(String::new(), |g| g.element_name(u.index))
                    ));
                }
            };
        }
        Ok(())
    }

    fn save(&self, w: &mut ByteWriter) {
        let p = &self.parameters;
        w.stand(&p.stand);
        for v in [&p.r0, &p.angles0, &p.v0, &p.w0] {
            w.f64s(v.as_slice());
        }
        save_settings(w, &p.settings);
        w.i32(p.stabilisation.code());
        w.f64(p.baumgarte_rate);
        w.bool(p.stops_enabled);
        save_stops(w, &p.stops);
        w.bool(p.stop_at_singularity);
        w.f64s(&self.forces);
        w.f64s(&self.force_rates);
        match &self.simulation {
            None => w.bool(false),
            Some(sim) => {
                w.bool(true);
                // The stand and stabilisation equal the parameters'; the guard, integrator,
                // time and state are the simulation's own.
                w.stand(sim.stand());
                w.bool(sim.form.stops().is_some());
                save_stops(w, &sim.form.stops().copied().unwrap_or_default());
                w.bool(sim.stop_at_singularity);
                w.i32(sim.stabilisation.code());
                w.f64(sim.form.baumgarte_rate);
                save_settings(w, &sim.integrator.settings);
                w.f64(sim.integrator.dopri5.h_next);
                w.f64(sim.integrator.dopri5.err_old);
                let st = &sim.integrator.stats;
                for n in [st.accepted_steps, st.rejected_steps, st.rhs_evaluations, st.event_landings] {
                    w.u64(n);
                }
                w.u32(sim.integrator.sides.bits);
                w.bool(sim.integrator.sides.known);
                let g = &sim.guard;
                w.f64s(&[g.min_leg_length, g.base_plane, g.side, g.characteristic_length]);
                w.f64(sim.time);
                w.f64s(&sim.state);
            }
        }
    }

    fn restore(r: &mut ByteReader) -> Result<Self, SnapshotError> {
        let stand = r.stand()?;
        let r0 = Vector3::from(r.finite_array::<3>("r0")?);
        let angles0 = Vector3::from(r.finite_array::<3>("angles0")?);
        let v0 = Vector3::from(r.finite_array::<3>("v0")?);
        let w0 = Vector3::from(r.finite_array::<3>("w0")?);
        let settings = read_settings(r)?;
        let stabilisation = read_stabilisation(r)?;
        let baumgarte_rate = r.finite("solver.baumgarteRate")?;
        let stops_enabled = r.bool()?;
        let stops = read_stops(r)?;
        let stop_at_singularity = r.bool()?;
        let forces = r.finite_array::<LEG_COUNT>("F")?;
        let force_rates = r.finite_array::<LEG_COUNT>("der(F)")?;
        let simulation = if r.bool()? {
            let sim_stand = r.stand()?;
            let sim_stops_on = r.bool()?;
            let sim_stops = read_stops(r)?;
            let sim_stop_at_singularity = r.bool()?;
            let sim_stabilisation = read_stabilisation(r)?;
            let sim_baumgarte = r.finite("Baumgarte rate")?;
            let sim_settings = read_settings(r)?;
            let dopri5 = Dopri5Memory { h_next: r.finite("h_next")?, err_old: r.finite("err_old")? };
            let stats = IntegratorStats {
                accepted_steps: r.u64()?,
                rejected_steps: r.u64()?,
                rhs_evaluations: r.u64()?,
                event_landings: r.u64()?,
            };
            let sides = SwitchingSides { bits: r.u32()?, known: r.bool()? };
            let [min_leg_length, base_plane, side, characteristic_length] = r.finite_array::<4>("guard")?;
            let guard = ConfigurationGuard { min_leg_length, base_plane, side, characteristic_length };
            let time = r.finite("time")?;
            let state = r.finite_array::<SIMULATION_DIM>("state")?;
            Some(PlatformSimulation {
                form: SpecialForm::new(sim_stand)
                    .with_baumgarte_rate(sim_baumgarte)
                    .with_end_stops(sim_stops_on.then_some(sim_stops)),
                guard,
                stabilisation: sim_stabilisation,
                stop_at_singularity: sim_stop_at_singularity,
                // Off until the instance says whether passages are reported: switching it on
                // then takes the determinant's side afresh.
                track_singularities: false,
                integrator: Integrator { settings: sim_settings, dopri5, stats, sides, vector_extensions: true },
                time,
                state,
                crossings: Default::default(),
            })
        } else {
            None
        };
        Ok(PlatformModel {
            parameters: PlatformParameters {
                stand,
                r0,
                angles0,
                v0,
                w0,
                settings,
                stabilisation,
                baumgarte_rate,
                stops_enabled,
                stops,
                stop_at_singularity,
            },
            forces,
            force_rates,
            simulation,
            outputs: None,
            legs: None,
            kappa: None,
            events_reported: true,
        })
    }
}

fn save_stops(w: &mut ByteWriter, s: &EndStops) {
    w.f64s(&s.lower);
    w.f64s(&s.upper);
    w.f64s(&[s.stiffness, s.damping]);
}

fn read_stops(r: &mut ByteReader) -> Result<EndStops, SnapshotError> {
    let lower = r.finite_array::<LEG_COUNT>("lmin")?;
    let upper = r.finite_array::<LEG_COUNT>("lmax")?;
    let [stiffness, damping] = r.finite_array::<2>("stops")?;
    Ok(EndStops { lower, upper, stiffness, damping })
}

/// State-vector index of element `index` of the rotation matrix `R` (row-major `R[a,b]`,
/// column `b` is `e_b`) or of `der(R)`, counted from `first`.
fn rotation_state_index(first: usize, index: usize) -> usize {
    first + 3 * (index % 3) + index / 3
}

/// Where a known of a directional derivative sits: a state component or a leg force.
enum Seed {
    State(usize),
    Force(usize),
}

fn seed_of(var: VariableRef) -> Option<Seed> {
    Some(match var.group {
        group::R => Seed::State(layout::R + var.index),
        group::V => Seed::State(layout::V + var.index),
        group::ROT => Seed::State(rotation_state_index(layout::E, var.index)),
        group::DER_R => Seed::State(rotation_state_index(layout::E_DOT, var.index)),
        group::WORK_F => Seed::State(quadrature::WORK_F),
        group::WORK_DISSIPATED => Seed::State(quadrature::WORK_DISSIPATED),
        group::F => Seed::Force(var.index),
        _ => return None,
    })
}

fn save_settings(w: &mut ByteWriter, s: &SolverSettings) {
    w.i32(s.method.code());
    w.f64s(&[s.rel_tol, s.abs_tol, s.max_step, s.fixed_step]);
    w.u64(s.max_steps_per_call);
}

fn read_settings(r: &mut ByteReader) -> Result<SolverSettings, SnapshotError> {
    let code = r.i32()?;
    let method = Method::from_code(code).ok_or_else(|| SnapshotError(format!("invalid integration method {code}")))?;
    let [rel_tol, abs_tol, max_step, fixed_step] = r.finite_array::<4>("solver settings")?;
    Ok(SolverSettings {
        method,
        rel_tol,
        abs_tol,
        max_step,
        fixed_step,
        max_steps_per_call: r.u64()?,
        locate_events: true,
    })
}

fn read_stabilisation(r: &mut ByteReader) -> Result<Stabilisation, SnapshotError> {
    let code = r.i32()?;
    Stabilisation::from_code(code).ok_or_else(|| SnapshotError(format!("invalid stabilisation {code}")))
}
