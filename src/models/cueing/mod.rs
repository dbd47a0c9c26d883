//! The `StewartCueing` model (SPEC §11-12, docs/cueing.md): the vehicle's specific force and
//! angular velocity at the head in; the pose command for the controller's `programme = 3`
//! with its exact first and second derivatives, what the driver would feel (`fsim`,
//! `omegasim`) and what they perceive (`perceived.*`) out. Two methods: the classical washout
//! and predictive cueing. Co-Simulation steps the washout's 21 states (RK4) and the
//! perception's 30 lags (exact over steps on which their inputs are linear); the predictive
//! method plans every `mpc.period` and its command moves with the planned jerks in between.
//! Model Exchange gives the classical method's 51 states and derivatives to the host.

mod outputs;
pub mod parameters;
mod states;
mod stepping;
pub mod variables;

use super::declare::{Binding, Variables, cache_block_of};
use super::snapshot::{ByteReader, ByteWriter, SnapshotError};
use super::variables::VariableRef;
use super::{Capabilities, DefaultExperiment, FmuModel, Initialised, ModelInfo, StepError, StepReport};
use crate::control::predictive_cueing::motion::CommandedMotion;
use crate::control::predictive_cueing::PredictiveCueing;
use crate::physics::cueing::perception::Perception;
use crate::physics::cueing::washout::{
    STATE_DIM, TILT_MODE_SWITCHES, TiltMode, TiltModes, VehicleMotion, WashoutPose,
};
pub use outputs::{Command, CueingOutputs};
pub use parameters::{CueingParameters, Method};
pub use states::{CueingStates, PerceptionStates, PredictiveState};
use states::perception_at_rest;
pub use stepping::Preview;
use variables::BINDINGS;

pub static INFO: ModelInfo = ModelInfo {
    model_name: "StewartCueing",
    model_identifier: "StewartCueing",
    description: "Motion cueing for a Stewart platform motion simulator: the classical washout (scaling, tilt \
                  coordination, rotational and translational high-pass) or predictive cueing (an optimal control \
                  problem over a horizon on a vestibular perception model, every leg within its stroke), a \
                  workspace limiter, and what the driver perceives; outputs the pose command for StewartController's \
                  programme 3",
    groups: variables::GROUPS,
    enumerations: &[],
    units: super::units::UNITS,
    default_experiment: DefaultExperiment { start_time: 0.0, stop_time: 20.0, step_size: 1e-3 },
    documentation: include_str!("documentation.html"),
    states: variables::STATES,
    // Co-Simulation takes the inputs' first derivatives (a first-order hold: a sampled
    // sinusoid drives the filters without the staircase of a held input).
    // Model Exchange locates the tilt limiter's switches as events: the modes' and the
    // targets' clips (four indicators).
    capabilities: Capabilities {
        model_exchange: true,
        can_interpolate_inputs: true,
        event_indicators: 4,
        ..Capabilities::NONE
    },
};

/// Largest commanded pitch, rad (80 deg): the Euler-angle rates of the 1-2-3 sequence are
/// singular at 90 deg, so a washout that gets there (a slow rotational high-pass with a large
/// `omegamax`) stops with a message instead.
pub const MAX_PITCH: f64 = 1.396;

/// Number of the model's continuous states (Model Exchange): the washout's and the lags.
pub const CONTINUOUS_STATES: usize = STATE_DIM + 30;

/// The cueing FMU model.
#[derive(Debug)]
pub struct CueingModel {
    pub parameters: CueingParameters,
    /// Inputs `f`, `omega`.
    pub vehicle: VehicleMotion,
    /// The inputs' first derivatives for the next step (`fmi2SetRealInputDerivatives`; 0
    /// after each step): `f` then `omega`.
    pub input_rates: [f64; 6],
    pub state: CueingStates,
    /// The tilt limiter's modes (discrete states).
    pub tilt_modes: TiltModes,
    pub perception: PerceptionStates,
    pub predictive_state: PredictiveState,
    pub time: f64,
    /// The start time (the predictive method's solves are at `start + k mpc.period`).
    pub start_time: f64,
    /// Whether the model left Initialization Mode (its parameters checked, the preview read).
    initialised: bool,
    /// The predictive method's solver (made when the method is, after initialisation).
    predictive: Option<Box<PredictiveCueing>>,
    /// The preview file's rows, read at initialisation.
    preview: Preview,
    outputs: Option<CueingOutputs>,
}

impl Clone for CueingModel {
    /// A copy without the solver, which `make_solver` makes again (after initialisation, after a restored state).
    fn clone(&self) -> Self {
        CueingModel {
            parameters: self.parameters.clone(),
            vehicle: self.vehicle,
            input_rates: self.input_rates,
            state: self.state,
            tilt_modes: self.tilt_modes,
            perception: self.perception,
            predictive_state: self.predictive_state,
            time: self.time,
            start_time: self.start_time,
            initialised: self.initialised,
            predictive: None,
            preview: self.preview.clone(),
            outputs: self.outputs,
        }
    }
}

impl Default for CueingModel {
    fn default() -> Self {
        let parameters = CueingParameters::default();
        CueingModel {
            vehicle: VehicleMotion { f: [0.0, 0.0, parameters.washout.gravity], omega: [0.0; 3] },
            perception: perception_at_rest(parameters.washout.gravity),
            parameters,
            input_rates: [0.0; 6],
            state: CueingStates::default(),
            tilt_modes: [TiltMode::Following; 2],
            predictive_state: PredictiveState::default(),
            time: 0.0,
            start_time: 0.0,
            initialised: false,
            predictive: None,
            preview: Preview::default(),
            outputs: None,
        }
    }
}

impl CueingModel {
    /// The pose of the method in use, before the limiter.
    pub fn pose(
        &self,
        x: &[f64; STATE_DIM],
        m: &VehicleMotion,
        modes: &TiltModes,
        motion: &CommandedMotion,
    ) -> WashoutPose {
        match self.parameters.method {
            Method::Classical => self.parameters.washout.pose(x, m, modes),
            Method::Predictive => stepping::predictive_pose(motion),
        }
    }

    fn command(&self, x: &[f64; STATE_DIM], m: &VehicleMotion, modes: &TiltModes, motion: &CommandedMotion) -> Command {
        Command::of(&self.parameters, &self.pose(x, m, modes, motion))
    }

    fn outputs(&mut self) -> &CueingOutputs {
        if self.outputs.is_none() {
            let command =
                self.command(&self.state.to_vector(), &self.vehicle, &self.tilt_modes, &self.predictive_state.motion);
            self.outputs = Some(CueingOutputs::of(&command, &self.perception.vehicle(), &self.perception.simulator()));
        }
        match &self.outputs {
            Some(o) => o,
            None => unreachable!("set above"),
        }
    }

    /// The continuous states' rate now (Model Exchange, the classical method): the washout's
    /// and the lags' (the simulator's driven by the command's cues).
    pub fn rate(&self) -> [f64; CONTINUOUS_STATES] {
        let x = self.state.to_vector();
        let mut dx = [0.0; CONTINUOUS_STATES];
        dx[..STATE_DIM].copy_from_slice(&self.parameters.washout.rate(&x, &self.vehicle, &self.tilt_modes));
        let command = self.command(&x, &self.vehicle, &self.tilt_modes, &self.predictive_state.motion);
        let vehicle = self.perception.vehicle().rate(&self.vehicle.f, &self.vehicle.omega);
        let simulator = self.perception.simulator().rate(&command.fsim, &command.omegasim);
        let mut lags = PerceptionStates::from_array(&[0.0; 30]);
        lags.set(&vehicle, &simulator);
        dx[STATE_DIM..].copy_from_slice(&lags.to_array());
        dx
    }

    /// The predictive method's solver, made after initialisation and after a restored state
    /// (allocations happen here, not in the steps).
    fn make_solver(&mut self) -> Result<(), String> {
        self.predictive = match self.parameters.method {
            Method::Classical => None,
            Method::Predictive => {
                Some(Box::new(PredictiveCueing::new(self.parameters.predictive(), self.parameters.predictive_stand())?))
            }
        };
        Ok(())
    }
}

/// Why the commanded pitch cannot go on (near the 1-2-3 angles' singularity), if it cannot.
fn check_pitch(pitch: f64) -> Result<(), String> {
    if pitch.abs() > MAX_PITCH {
        return Err(format!(
            "the commanded pitch would reach {:.1} deg, near the 90 deg where the 1-2-3 angles are singular (the \
             rotational high-pass is too slow for the angular velocity: raise hp.w.omega[2] or lower omegamax, \
             scale.omega[2])",
            pitch.to_degrees()
        ));
    }
    Ok(())
}

impl FmuModel for CueingModel {
    fn info(&self) -> &'static ModelInfo {
        &INFO
    }

    fn cache_block(&self, group: usize) -> Option<u8> {
        cache_block_of(BINDINGS, group)
    }

    fn fill_cache(&mut self, block: u8, cache: &mut [f64]) -> bool {
        self.fill_block(block, cache)
    }

    fn get_real(&mut self, var: VariableRef) -> f64 {
        let value = match BINDINGS.get(var.group) {
            Some(Binding::Stored) => self.real_stored(var),
            Some(Binding::Cached { .. }) => self.output_value(var),
            Some(Binding::Derivative) => INFO.derivative_state_index(var).map(|i| self.rate()[i]),
            Some(Binding::Computed) if var.group == variables::group::EVENT_INDICATORS => {
                let mut z = [0.0; 4];
                self.event_indicators(&mut z);
                z.get(var.index).copied()
            }
            Some(Binding::Computed) => Some(self.time),
            None => None,
        };
        value.unwrap_or(f64::NAN)
    }

    fn set_real(&mut self, var: VariableRef, value: f64) -> Result<(), String> {
        *self.real_slot(var).ok_or("not a settable Real variable")? = value;
        self.outputs = None;
        Ok(())
    }

    fn get_integer(&mut self, var: VariableRef) -> i32 {
        match var.group {
            variables::group::MPC_ITERATIONS => self.predictive_state.iterations,
            variables::group::MPC_FALLBACKS => self.predictive_state.fallbacks,
            variables::group::MPC_ACCEPTABLE => self.predictive_state.acceptable,
            _ => self.integer(var).unwrap_or(0),
        }
    }

    fn set_integer(&mut self, var: VariableRef, value: i32) -> Result<(), String> {
        let result = self.set_integer_code(var, value).unwrap_or_else(|| Err("not a settable Integer variable".into()));
        self.outputs = None;
        result
    }

    fn get_boolean(&mut self, var: VariableRef) -> bool {
        var.group == variables::group::LIMITED && self.outputs().limited
    }

    fn get_string(&mut self, var: VariableRef) -> Option<String> {
        self.string_value(var).map(str::to_string)
    }

    fn set_string(&mut self, var: VariableRef, value: &str) -> Result<(), String> {
        *self.string_slot(var).ok_or("not a settable String variable")? = value.to_string();
        Ok(())
    }

    fn exit_initialization(
        &mut self,
        start_time: f64,
        _tolerance: Option<f64>,
        model_exchange: bool,
    ) -> Result<Initialised, String> {
        super::check_start_time(start_time)?;
        self.parameters.validate()?;
        if model_exchange && self.parameters.method == Method::Predictive {
            return Err("cueing.method = 1 (predictive cueing) runs in Co-Simulation only: its plans are made every \
                        mpc.period, not by the host's integrator; use the classical washout (0) in Model Exchange"
                .into());
        }
        self.preview = Preview::read(&self.parameters.preview_file)?;
        self.make_solver()?;
        self.initialised = true;
        self.time = start_time;
        self.start_time = start_time;
        self.outputs = None;
        // Both perceptions start at rest under the vehicle's specific force as set.
        let rest = Perception::at_rest(self.vehicle.f);
        let mut simulator = Perception::at_rest([0.0, 0.0, self.parameters.washout.gravity]);
        simulator.canal = rest.canal;
        self.perception.set(&rest, &simulator);
        self.predictive_state = PredictiveState::default();
        self.tilt_modes = [TiltMode::Following; 2];
        let w = &self.parameters.washout;
        let method = match self.parameters.method {
            Method::Classical => "classical washout".to_string(),
            Method::Predictive => {
                let p = self.parameters.predictive();
                format!(
                    "predictive cueing: period {:?} s, horizon {:?} s, trust {:?} s, trend {:?} s, weights f {:?}, \
                     omega {:?}, neutral {:?}, input {:?}, leg speed {:?} m/s, preview {}",
                    p.period,
                    p.horizon,
                    p.trust,
                    p.trend,
                    p.weight_f,
                    p.weight_omega,
                    p.weight_neutral,
                    p.weight_input,
                    p.leg_speed,
                    if self.preview.is_empty() {
                        "none (the inputs guessed over the horizon: mpc.trend)".to_string()
                    } else {
                        format!("{} rows from {}", self.preview.len(), self.parameters.preview_file)
                    }
                )
            }
        };
        Ok(format!(
            "initialised at t = {start_time:?}: {method}; K_f = {:?}, K_w = {:?}, w_t = {:?} rad/s, w_b = {:?} rad/s, \
             tilt w_l = {:?} rad/s at most {:?} rad/s, w_r = {:?} rad/s, head {:?} m, margin {:?} m",
            w.scale_f,
            w.scale_omega,
            w.hp_f_omega,
            w.hp_f_break,
            w.tilt_omega,
            w.tilt_rate_limit,
            w.hp_w_omega,
            self.parameters.head,
            self.parameters.margin
        )
        .into())
    }

    fn do_step(&mut self, t: f64, h: f64, _stop_at_event: bool) -> Result<StepReport, StepError> {
        let after = stepping::step(self, t, h)?;
        self.state = after.washout;
        self.tilt_modes = after.tilt_modes;
        self.perception = after.perception;
        self.predictive_state = after.predictive;
        self.input_rates = [0.0; 6];
        self.time = t + h;
        self.outputs = None;
        Ok(StepReport { reached: t + h, event: false, warning: None })
    }

    fn set_input_derivative(&mut self, var: VariableRef, value: f64) {
        let first = match var.group {
            variables::group::F => 0,
            variables::group::OMEGA => 3,
            _ => return,
        };
        if let Some(slot) = self.input_rates.get_mut(first + var.index) {
            *slot = value;
        }
    }

    fn output_derivative(&mut self, _var: VariableRef) -> f64 {
        0.0
    }

    fn set_time(&mut self, t: f64) {
        self.time = t;
    }

    fn continuous_states(&self, x: &mut [f64]) {
        let mut all = [0.0; CONTINUOUS_STATES];
        all[..STATE_DIM].copy_from_slice(&self.state.to_vector());
        all[STATE_DIM..].copy_from_slice(&self.perception.to_array());
        x.copy_from_slice(&all[..x.len()]);
    }

    fn set_continuous_states(&mut self, x: &[f64]) {
        let mut all = [0.0; CONTINUOUS_STATES];
        self.continuous_states(&mut all);
        all[..x.len()].copy_from_slice(x);
        let washout: [f64; STATE_DIM] = std::array::from_fn(|i| all[i]);
        let lags: [f64; 30] = std::array::from_fn(|i| all[STATE_DIM + i]);
        self.state = CueingStates::from_vector(&washout);
        self.perception = PerceptionStates::from_array(&lags);
        self.outputs = None;
    }

    fn completed_integrator_step(&mut self) -> Result<(), StepError> {
        check_pitch(self.state.angles[1] + self.state.tilt[1])
            .map_err(|why| StepError { message: format!("t = {:?}: {why}", self.time), retry_shorter: false })
    }

    fn derivatives(&mut self, dx: &mut [f64]) {
        let rate = self.rate();
        dx.copy_from_slice(&rate[..dx.len()]);
    }

    /// The tilt limiter's switching functions: the roll's and the pitch's modes, then their
    /// targets' clips.
    fn event_indicators(&mut self, z: &mut [f64]) {
        let g = self.parameters.washout.tilt_switching(&self.state.to_vector(), &self.vehicle, &self.tilt_modes);
        for (slot, value) in z.iter_mut().zip(g) {
            *slot = value;
        }
    }

    /// A tilt whose switching function is not positive switches (its mode; a slewing angle
    /// that caught up takes its target's value, which it equals to the host's tolerance).
    fn event_update(&mut self, sink: &mut dyn FnMut(&str)) -> super::EventUpdate {
        let w = self.parameters.washout;
        let mut x = self.state.to_vector();
        let g = w.tilt_switching(&x, &self.vehicle, &self.tilt_modes);
        for i in 0..TILT_MODE_SWITCHES {
            if g[i] <= 0.0 {
                let before = self.tilt_modes[i];
                w.switch_tilt(&mut x, &self.vehicle, &mut self.tilt_modes, i);
                sink(&format!(
                    "t = {:?}: the {} tilt switches from {before:?} to {:?}",
                    self.time,
                    ["roll", "pitch"][i],
                    self.tilt_modes[i]
                ));
            }
        }
        self.state = CueingStates::from_vector(&x);
        self.outputs = None;
        super::EventUpdate::default()
    }

    /// The stored variables (parameters, inputs, the washout's states, the lags), the
    /// inputs' derivatives, the time and the predictive method's state.
    fn save(&self, w: &mut ByteWriter) {
        self.save_variables(w);
        w.f64s(&self.input_rates);
        w.f64(self.time);
        w.f64(self.start_time);
        let p = &self.predictive_state;
        w.f64s(&p.motion.to_array());
        for row in &p.plan {
            w.f64s(row);
        }
        w.f64s(&p.jerk);
        w.u64(p.solves);
        w.i32(p.iterations);
        w.i32(p.fallbacks);
        w.i32(p.acceptable);
        w.bool(p.falling_back);
        w.bool(p.last_vehicle.is_some());
        let last = p.last_vehicle.unwrap_or(VehicleMotion { f: [0.0; 3], omega: [0.0; 3] });
        w.f64s(&last.f);
        w.f64s(&last.omega);
        w.u8(self.tilt_modes[0].code());
        w.u8(self.tilt_modes[1].code());
        // After initialisation the preview's rows belong to the state: a restored state does
        // not read the file again.
        w.bool(self.initialised);
        self.preview.save(w);
    }

    fn restore(r: &mut ByteReader) -> Result<Self, SnapshotError> {
        let mut model = CueingModel::default();
        model.restore_variables(r)?;
        model.input_rates = r.finite_array::<6>("der(f), der(omega)")?;
        model.time = r.finite("time")?;
        model.start_time = r.finite("start time")?;
        let p = &mut model.predictive_state;
        p.motion = CommandedMotion::from_array(&r.finite_array("the commanded motion")?);
        for row in p.plan.iter_mut() {
            *row = r.finite_array("the plan")?;
        }
        p.jerk = r.finite_array("the jerks")?;
        p.solves = r.u64()?;
        p.iterations = r.i32()?;
        p.fallbacks = r.i32()?;
        p.acceptable = r.i32()?;
        p.falling_back = r.bool()?;
        let has_last = r.bool()?;
        let last = VehicleMotion { f: r.finite_array("the last solve's f")?, omega: r.finite_array("the last solve's omega")? };
        p.last_vehicle = has_last.then_some(last);
        for i in 0..2 {
            model.tilt_modes[i] =
                TiltMode::from_code(r.u8()?).ok_or(SnapshotError("a tilt mode out of range".into()))?;
        }
        model.initialised = r.bool()?;
        model.preview = Preview::restore(r)?;
        if model.initialised {
            model.make_solver().map_err(SnapshotError)?;
        }
        Ok(model)
    }
}

#[cfg(test)]
mod tests;
