//! The `StewartPlatform` model: the stand's parameters and initial pose as FMI parameters,
//! the six leg forces (or with electric drives the six voltages) as inputs, the pose, legs
//! and energy as outputs (docs/model.md §5).
//!
//! | module | what it holds |
//! |---|---|
//! | [`variables`] | every variable, declared once with where its value lives; `variables/dependencies.rs`: what the unknowns depend on, each concern's knowns once, the lists composed |
//! | [`parameters`] | the parameters, their checks, the simulation they describe |
//! | [`exchange`] | Model Exchange: states, derivatives, event indicators, directional derivatives |
//! | `outputs.rs` | the outputs by cache block, each computed on its first read after a change |
//! | `messages.rs` | what a failed step or an event is, in words |

pub mod exchange;
mod messages;
mod outputs;
pub mod parameters;
pub mod variables;

use crate::models::Initialised;

use super::declare::{Binding, Variables, cache_block_of};
use super::snapshot::{ByteReader, ByteWriter, SnapshotError};
use super::variables::VariableRef;
use super::{DefaultExperiment, FmuModel, ModelInfo, StepError, StepReport};
use crate::integration::dopri5::Dopri5Memory;
use crate::integration::{IntegratorStats, SwitchingSides};
use crate::models::machine::Drive;
use crate::physics::actuators::HeldForces;
use crate::physics::actuators::PerActuator;
use crate::physics::actuators::hydraulics::CAVITATION_PRESSURE;
use crate::physics::stand::LEG_COUNT;
use crate::simulation::outputs::{ActuatorStateOutputs, LegLoadOutputs, PoseOutputs, StateOutputs};
use crate::simulation::platform::Reached;
use crate::simulation::state::{SIMULATION_DIM, state_rate, switching};
use crate::simulation::{LegOutputs, PlatformSimulation};
pub use outputs::{Condition, InputDependentOutputs};
pub use parameters::{Experiment, PlatformParameters, default_leg_force, holding_pressures};
use variables::{BINDINGS, group};

pub static INFO: ModelInfo = ModelInfo {
    model_name: "StewartPlatform",
    model_identifier: "StewartPlatform",
    description: "Loaded Stewart platform (hexapod): rigid-body dynamics in the special form of Zegzhda, Petrova and \
                  Yushkov (2020), six axial leg forces (or drive voltages) in, pose and leg lengths out",
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
        event_indicators: switching::EVENT_INDICATORS,
    },
};

/// The platform FMU model.
#[derive(Clone, Debug)]
pub struct PlatformModel {
    pub parameters: PlatformParameters,
    /// Each actuator's inputs (the leg forces `F`, N; the drives' voltages `U`, V; the servo
    /// valves' commands `valve`): those of kind `drive` move the legs.
    pub inputs: PerActuator<[f64; LEG_COUNT]>,
    /// Their time derivatives for the next step (cleared after each step).
    pub input_rates: PerActuator<[f64; LEG_COUNT]>,
    /// Whether this run logged its warning of a chamber below the cavitation pressure.
    cavitation_reported: bool,
    /// Present after Initialization Mode, with the experiment it was built for.
    pub simulation: Option<(PlatformSimulation, Experiment)>,
    /// The pose, the legs' other values and the values read off the state, each computed on
    /// its first read after a change (by group: a host pays for what it reads).
    pose: Option<PoseOutputs>,
    leg_loads: Option<LegLoadOutputs>,
    state_values: Option<StateOutputs>,
    /// Leg lengths and rates of the current state: what a controller reads every step, so
    /// they are computed alone (the leg geometry) rather than with every other output.
    legs: Option<LegOutputs>,
    /// `kappa` of the current state, computed on its first read after a change.
    kappa: Option<Condition>,
    /// The actuators' states of the current state (a hydraulic controller reads the pressures
    /// every step: a copy of states, apart from the other outputs).
    actuator_states: Option<ActuatorStateOutputs>,
    /// The actuators' and the joints' forces of the current state and inputs, computed on the
    /// first read after a change.
    input_dependent: Option<InputDependentOutputs>,
    /// Whether passages through singular arrangements are reported (see
    /// [`FmuModel::set_event_reporting`]).
    events_reported: bool,
    /// Model Exchange: the time of the host's last completed integrator step, and the length of
    /// that step (a fault's message gives the host's step).
    last_completed_step: f64,
    host_step: f64,
}

impl Default for PlatformModel {
    fn default() -> Self {
        PlatformModel {
            parameters: PlatformParameters::default(),
            inputs: PerActuator { forces: [default_leg_force(); LEG_COUNT], ..PerActuator::default() },
            input_rates: PerActuator::default(),
            cavitation_reported: false,
            simulation: None,
            pose: None,
            leg_loads: None,
            state_values: None,
            legs: None,
            kappa: None,
            actuator_states: None,
            input_dependent: None,
            events_reported: true,
            last_completed_step: 0.0,
            host_step: 0.0,
        }
    }
}

impl PlatformModel {
    /// The simulation, after Initialization Mode.
    pub fn sim(&self) -> Option<&PlatformSimulation> {
        self.simulation.as_ref().map(|(sim, _)| sim)
    }

    fn sim_mut(&mut self) -> Option<&mut PlatformSimulation> {
        self.simulation.as_mut().map(|(sim, _)| sim)
    }

    /// The inputs in use: the leg forces `F`, with drives the voltages `U`, with hydraulic legs
    /// the valve commands.
    pub fn inputs(&self) -> [f64; LEG_COUNT] {
        *self.inputs.get(self.parameters.drive)
    }

    /// The inputs over the next step: the leg forces, or with drives the voltages, with
    /// their rates.
    fn held_inputs(&self, t0: f64) -> HeldForces {
        let drive = self.parameters.drive;
        HeldForces { value: *self.inputs.get(drive), slope: *self.input_rates.get(drive), t0 }
    }

    /// The kind of actuator whose inputs group `group` is.
    fn actuator_of_inputs(group: usize) -> Option<Drive> {
        Drive::ALL.into_iter().find(|&k| *variables::ACTUATOR_INPUTS.get(k) == group)
    }

    /// A simulation for the parameters and `experiment`, told what the instance reports, with
    /// the switching functions' sides at its start.
    fn start(&self, experiment: &Experiment) -> Result<PlatformSimulation, String> {
        let mut sim = self.parameters.simulation(experiment)?;
        sim.set_track_singularities(self.events_reported);
        sim.integrator.sides = crate::integration::switching_sides(
            &sim.dynamics(&HeldForces::constant(self.inputs())),
            experiment.start_time,
            &sim.state,
        );
        Ok(sim)
    }
}

impl FmuModel for PlatformModel {
    fn info(&self) -> &'static ModelInfo {
        &INFO
    }

    fn get_real(&mut self, var: VariableRef) -> f64 {
        let value = match BINDINGS.get(var.group) {
            Some(Binding::Stored) => self.real_stored(var),
            Some(Binding::Cached { .. }) => self.output_value(var),
            Some(Binding::Derivative) => self.derivative_value(var),
            Some(Binding::Computed) => Some(match var.group {
                group::TIME => self.sim().map_or(0.0, |s| s.time),
                // Without hydraulic legs there are no chambers: 0, as pA and pB.
                group::PMIN if self.parameters.drive != Drive::Hydraulic => 0.0,
                group::PMIN => match self.sim() {
                    Some(s) => s.lowest_pressure,
                    None => {
                        let h = &self.parameters.actuators.hydraulic;
                        h.initial_pa.iter().chain(&h.initial_pb).fold(f64::INFINITY, |a, &b| a.min(b))
                    }
                },
                _ => {
                    let mut z = [0.0; switching::EVENT_INDICATORS];
                    self.event_indicators(&mut z);
                    z.get(var.index).copied().unwrap_or(f64::NAN)
                }
            }),
            None => None,
        };
        value.unwrap_or(f64::NAN)
    }

    fn set_event_reporting(&mut self, on: bool) {
        self.events_reported = on;
        if let Some(sim) = self.sim_mut() {
            sim.set_track_singularities(on);
        }
    }

    fn cache_block(&self, group: usize) -> Option<u8> {
        cache_block_of(BINDINGS, group)
    }

    /// The legs' block inline (a step's cycle fills it every time), the others each in a
    /// function of its own.
    #[inline]
    fn fill_cache(&mut self, block: u8, cache: &mut [f64]) -> bool {
        const LEGS: u8 = variables::cache_block::leg_outputs;
        if block == LEGS {
            return self.fill_block_values::<LEGS>(cache);
        }
        self.fill_block(block, cache)
    }

    fn set_real(&mut self, var: VariableRef, value: f64) -> Result<(), String> {
        let slot = self.real_slot(var).ok_or("not a settable Real variable")?;
        *slot = value;
        let actuators = self.parameters.actuators;
        if let Some(sim) = self.sim_mut() {
            // An input the actuator holds in its parameters (the hydraulic supply pressure),
            // held over the next step.
            sim.form.take_actuator_inputs(&actuators);
        }
        self.values_set();
        Ok(())
    }

    #[inline]
    fn set_real_run(&mut self, first: VariableRef, values: &[f64]) -> Result<(), String> {
        // An actuator's inputs, set every step: one copy.
        let inputs = Self::actuator_of_inputs(first.group).map(|k| self.inputs.get_mut(k));
        if let Some(inputs) = inputs.and_then(|v| v.get_mut(first.index..first.index + values.len())) {
            inputs.copy_from_slice(values);
            self.values_set();
            return Ok(());
        }
        super::set_one_by_one(self, first, values)
    }

    fn get_integer(&mut self, var: VariableRef) -> i32 {
        self.integer(var).unwrap_or(0)
    }

    fn set_integer(&mut self, var: VariableRef, value: i32) -> Result<(), String> {
        self.set_integer_code(var, value).unwrap_or_else(|| Err("not a settable Integer variable".into()))?;
        self.values_set();
        Ok(())
    }

    fn get_boolean(&mut self, var: VariableRef) -> bool {
        self.boolean_slot(var).is_some_and(|b| *b)
    }

    fn set_boolean(&mut self, var: VariableRef, value: bool) -> Result<(), String> {
        *self.boolean_slot(var).ok_or("not a settable Boolean variable")? = value;
        self.values_set();
        Ok(())
    }

    fn exit_initialization(
        &mut self,
        start_time: f64,
        tolerance: Option<f64>,
        model_exchange: bool,
    ) -> Result<Initialised, String> {
        super::check_start_time(start_time)?;
        let experiment = Experiment { start_time, tolerance, model_exchange };
        let sim = self.start(&experiment)?;
        let legs = LegOutputs::compute(&sim.form, &sim.state).l;
        let summary = self.parameters.summary(&sim, &experiment, &legs);
        // Legal (a suspended hexapod hangs under its base), but with the default stand it is
        // a mistyped height, and the pushing legs and gravity take the platform away.
        let warning = (sim.guard.side < 0.0).then(|| {
            format!(
                "all platform joints start below the base plane (z = {:?} m; r0[3] = {:?} m): the platform hangs under \
                 its base like a suspended hexapod, and legs that push (F > 0) drive it further down; raise r0[3] if \
                 it should stand on its legs",
                sim.guard.base_plane, self.parameters.r0[2]
            )
        });
        self.simulation = Some((sim, experiment));
        self.cavitation_reported = false;
        self.last_completed_step = start_time;
        self.invalidate_outputs();
        Ok(Initialised { summary, warning })
    }

    fn do_step(&mut self, t: f64, h: f64, stop_at_event: bool) -> Result<StepReport, StepError> {
        let law = self.held_inputs(t);
        let (inputs, unit) = self.parameters.drive.inputs();
        let values = self.inputs();
        let Some(sim) = self.sim_mut() else {
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
            sim.crossings.as_slice().iter().any(|c| c.index != switching::DETERMINANT) || sim.crossings.dropped > 0;
        let lowest = sim.lowest_pressure;
        self.input_rates = PerActuator::default();
        match result {
            Ok(reached) => {
                self.invalidate_outputs();
                // The step computed the legs of its end state already.
                self.legs = reached.legs;
                // Oil with air cannot reach zero absolute (docs/model.md §10b): the warning is
                // for oil without air, whose law has no pressure floor.
                let without_air = self.parameters.actuators.hydraulic.legs.air_fraction == 0.0;
                let warning = (without_air && lowest < CAVITATION_PRESSURE && !self.cavitation_reported).then(|| {
                    self.cavitation_reported = true;
                    format!(
                        "by t = {:?} a hydraulic chamber fell to {lowest:e} Pa, below -1 bar gauge: real oil would \
                         cavitate there and the model (no pressure floor) is no longer valid; pmin reports the lowest \
                         pressure (logged once per run)",
                        reached.t
                    )
                });
                Ok(StepReport { reached: reached.t, event, warning })
            }
            Err(failure) => Err(StepError {
                message: if failure.is_step_limit() {
                    format!(
                        "step from t = {t:?} to {t_end:?} rolled back: {failure}; retry from t = {t:?} with shorter \
                         communication steps"
                    )
                } else {
                    let hint = self.rk4_instability(h).unwrap_or_default();
                    format!("step from t = {t:?} to {t_end:?} rolled back: {failure}; {inputs} {values:?} {unit}{hint}")
                },
                retry_shorter: failure.is_step_limit(),
            }),
        }
    }

    fn report_events(&mut self, sink: &mut dyn FnMut(&str)) {
        let Some(sim) = self.sim() else { return };
        for c in sim.crossings.as_slice() {
            sink(&Self::describe_crossing(sim, c));
        }
        if sim.crossings.dropped > 0 {
            sink(&format!(
                "{} more contact, singularity or accumulator events in this step were not reported",
                sim.crossings.dropped
            ));
        }
    }

    fn set_input_derivative(&mut self, var: VariableRef, value: f64) {
        let Some(kind) = Self::actuator_of_inputs(var.group) else { return };
        let rates = self.input_rates.get_mut(kind);
        if let Some(slot) = rates.get_mut(var.index) {
            *slot = value;
        }
    }

    fn output_derivative(&mut self, var: VariableRef) -> f64 {
        self.output_time_derivative(var)
    }

    fn set_time(&mut self, t: f64) {
        if let Some(sim) = self.sim_mut() {
            sim.time = t;
        }
    }

    fn continuous_states(&self, x: &mut [f64]) {
        if let Some(sim) = self.sim() {
            for (xi, yi) in x.iter_mut().zip(sim.state.iter()) {
                *xi = *yi;
            }
        }
    }

    fn set_continuous_states(&mut self, x: &[f64]) {
        if let Some(sim) = self.sim_mut() {
            for (yi, xi) in sim.state.iter_mut().zip(x) {
                *yi = *xi;
            }
            self.invalidate_outputs();
        }
    }

    fn derivatives(&mut self, dx: &mut [f64]) {
        let Some(sim) = self.sim() else { return };
        let dy = state_rate(&sim.form, &sim.state, &self.inputs());
        for (d, v) in dx.iter_mut().zip(dy) {
            *d = v;
        }
    }

    fn event_indicators(&mut self, z: &mut [f64]) {
        self.switching_values(z);
    }

    fn event_update(&mut self, sink: &mut dyn FnMut(&str)) -> super::EventUpdate {
        self.update_events(sink)
    }

    fn completed_integrator_step(&mut self) -> Result<(), StepError> {
        let Some(sim) = self.sim() else { return Ok(()) };
        let time = sim.time;
        let checked = sim.guard.check(&sim.form.joints, &sim.body_state());
        self.host_step = time - self.last_completed_step;
        self.last_completed_step = time;
        // The hint is worded only for a failure: this runs after every step of the host.
        checked.map_err(|f| {
            let hint = self.host_step_hint().map(|h| format!("; {h}")).unwrap_or_default();
            StepError {
                message: format!("at t = {time:?}: {f}; the simulation cannot go on{hint}"),
                retry_shorter: false,
            }
        })
    }

    /// Model Exchange: a state the host's integrator reached that is not a motion.
    fn undefined_reason(&self) -> Option<String> {
        self.host_step_hint()
    }

    fn directional_derivative(
        &mut self,
        unknowns: &[VariableRef],
        knowns: &[VariableRef],
        seeds: &[f64],
        out: &mut [f64],
    ) -> Result<(), String> {
        self.jacobian_product(unknowns, knowns, seeds, out)
    }

    /// The stored variables (declaration order), the input derivatives, and, once
    /// initialised, the experiment and what changes as the simulation runs (its stand,
    /// stops, settings and guard are built again from the parameters on restore).
    fn save(&self, w: &mut ByteWriter) {
        self.save_variables(w);
        for kind in Drive::ALL {
            w.f64s(self.input_rates.get(kind));
        }
        w.bool(self.cavitation_reported);
        match &self.simulation {
            None => w.bool(false),
            Some((sim, experiment)) => {
                w.bool(true);
                w.f64(experiment.start_time);
                w.bool(experiment.tolerance.is_some());
                w.f64(experiment.tolerance.unwrap_or(0.0));
                w.bool(experiment.model_exchange);
                w.f64(sim.time);
                w.f64s(&sim.state);
                w.f64(sim.lowest_pressure);
                w.f64s(&[sim.integrator.dopri5.h_next, sim.integrator.dopri5.err_old]);
                let st = &sim.integrator.stats;
                for n in [st.accepted_steps, st.rejected_steps, st.rhs_evaluations, st.event_landings] {
                    w.u64(n);
                }
                w.u32(sim.integrator.sides.bits);
                w.bool(sim.integrator.sides.known);
            }
        }
    }

    fn restore(r: &mut ByteReader) -> Result<Self, SnapshotError> {
        let mut model = PlatformModel::default();
        model.restore_variables(r)?;
        for kind in Drive::ALL {
            let name = variables::GROUPS.get(*variables::ACTUATOR_INPUTS.get(kind)).map_or("", |g| g.name);
            *model.input_rates.get_mut(kind) = r.finite_array::<LEG_COUNT>(&format!("der({name})"))?;
        }
        model.cavitation_reported = r.bool()?;
        if r.bool()? {
            let start_time = r.finite("start time")?;
            let has_tolerance = r.bool()?;
            let tolerance = r.finite("tolerance")?;
            let experiment =
                Experiment { start_time, tolerance: has_tolerance.then_some(tolerance), model_exchange: r.bool()? };
            let mut sim = model
                .parameters
                .simulation(&experiment)
                .map_err(|e| SnapshotError(format!("the stored parameters are refused: {e}")))?;
            sim.time = r.finite("time")?;
            sim.state = r.finite_array::<SIMULATION_DIM>("state")?;
            sim.lowest_pressure = r.f64()?;
            let [h_next, err_old] = r.finite_array::<2>("integrator memory")?;
            sim.integrator.dopri5 = Dopri5Memory { h_next, err_old };
            sim.integrator.stats = IntegratorStats {
                accepted_steps: r.u64()?,
                rejected_steps: r.u64()?,
                rhs_evaluations: r.u64()?,
                event_landings: r.u64()?,
            };
            sim.integrator.sides = SwitchingSides { bits: r.u32()?, known: r.bool()? };
            // Off until the instance says whether passages are reported: switching it on
            // then takes the determinant's side afresh.
            sim.set_track_singularities(false);
            model.last_completed_step = sim.time;
            model.simulation = Some((sim, experiment));
        }
        Ok(model)
    }
}
