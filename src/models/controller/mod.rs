//! The `StewartController` model: the paper's programme motion control (section 7) as a
//! component. A programme pose (the paper's heave, a six-degree-of-freedom sinusoid, or a
//! pose from inputs) goes through the direct problem and inverse kinematics of the same
//! physics core as the platform; the leg forces are `F = F^p + G (l^p - l) + D (ldot^p -
//! ldot)` (+ an optional disturbance). With electric drives (`drive = 1`, docs/model.md §9)
//! it also gives the voltages `U = R F / (N k_t) + k_e N ldot^p`: the force command through
//! the drive's static model. No states: outputs are functions of time, inputs and parameters
//! (direct feed-through from `l`, `ldot` to `F` and `U`).

//!
//! | module | what it holds |
//! |---|---|
//! | [`outputs`] | what it reports: the commands, the programme and its angles |
//! | [`parameters`] | the programmes, the feedback, the hydraulic loop: parameters and defaults |
//! | [`variables`] | every variable, declared once with where its value lives |

pub mod outputs;
pub mod parameters;
pub mod variables;

use crate::models::Initialised;
use crate::models::machine::Drive;
use nalgebra::Vector3;

use super::declare::{Binding, Variables, cache_block_of};
use super::snapshot::{ByteReader, ByteWriter, SnapshotError};
use super::variables::VariableRef;
use super::{DefaultExperiment, FmuModel, ModelInfo, StepError, StepReport};
use crate::physics::body::kinematics::{PoseTrajectoryPoint, angles_from_rotation};
use crate::physics::direct_problem::{DirectProblemSolution, solve_direct_problem};
use crate::physics::programme::{PoseProgramme, SafeLanding, SoftStartSinusoid, StartUp};
use crate::physics::stand::{LEG_COUNT, MAX_COORDINATE};
pub use outputs::*;
pub use parameters::*;
use variables::BINDINGS;

pub static INFO: ModelInfo = ModelInfo {
    model_name: "StewartController",
    model_identifier: "StewartController",
    description: "Programme motion control of a Stewart platform (Zegzhda, Petrova, Yushkov 2020, section 7): \
                  programme forces from the direct problem plus leg-length feedback F = F^p + G (l^p - l) + \
                  D (ldot^p - ldot)",
    groups: variables::GROUPS,
    enumerations: &[],
    units: super::units::UNITS,
    default_experiment: DefaultExperiment { start_time: 0.0, stop_time: 3.0, step_size: 1e-3 },
    documentation: include_str!("documentation.html"),
    states: &[],
    // No dynamics: outputs follow the inputs at the communication points; input and output
    // derivatives are not provided.
    capabilities: super::Capabilities::NONE,
};

/// The controller FMU model.
#[derive(Clone, Debug, PartialEq)]
pub struct ControllerModel {
    pub parameters: ControllerParameters,
    pub l: [f64; LEG_COUNT],
    pub ldot: [f64; LEG_COUNT],
    /// The measured chamber pressures `pA`, `pB`, Pa (inputs when `drive = 2`).
    pub pa: [f64; LEG_COUNT],
    pub pb: [f64; LEG_COUNT],
    /// The measured supply pressure `supply.pressure`, Pa (input when `drive = 2`).
    pub supply_pressure: f64,
    /// The input `landing.command` (1: land now).
    pub landing_command: f64,
    /// The safe landing under way: when it started and the programme point it started from
    /// (programme 5 from the start; any programme on a trigger).
    pub landing: Option<(f64, PoseTrajectoryPoint)>,
    /// Inputs `pose.*`.
    pub pose: ExternalPose,
    pub time: f64,
    commands: Option<Commands>,
    programme_outputs: Option<ProgrammeOutputs>,
    angles: Option<ProgrammeAngles>,
    /// The programme's direct problem at `time`, kept while only the measured legs `l`,
    /// `ldot` change: it depends on the time, the parameters and the `pose.*` inputs alone, and
    /// its 6x6 solve is most of a step's cost (a closed loop sets `l`, `ldot` after every step).
    programme: Option<(PoseTrajectoryPoint, DirectProblemSolution)>,
}

impl Default for ControllerModel {
    fn default() -> Self {
        let parameters = ControllerParameters::default();
        let centre = parameters.heave_centre;
        let neutral = solve_direct_problem(
            &parameters.stand,
            &parameters.leg_bodies(),
            &PoseTrajectoryPoint::at_rest(centre, nalgebra::Matrix3::identity()),
        )
        .map(|s| s.lengths)
        .unwrap_or([0.0; LEG_COUNT]);
        ControllerModel {
            parameters,
            l: neutral,
            ldot: [0.0; LEG_COUNT],
            pa: [crate::models::platform::holding_pressures().0; LEG_COUNT],
            pb: [crate::models::platform::holding_pressures().1; LEG_COUNT],
            supply_pressure: crate::physics::actuators::hydraulics::DEFAULT_SUPPLY_PRESSURE,
            landing_command: 0.0,
            landing: None,
            pose: ExternalPose { r: [centre.x, centre.y, centre.z], ..Default::default() },
            time: 0.0,
            commands: None,
            programme_outputs: None,
            angles: None,
            programme: None,
        }
    }
}

impl ControllerModel {
    /// The programme pose with its derivatives at time `t`.
    pub fn programme_point(&self, t: f64) -> PoseTrajectoryPoint {
        let p = &self.parameters;
        let landing = |from| SafeLanding { from, speed: p.landing.speed, floor: p.landing.floor };
        if let Some((start, from)) = self.landing {
            return landing(from).point(t - start);
        }
        let heave = PoseProgramme::heave(p.heave_centre, p.heave.amplitude, p.heave.frequency, p.heave.time_constant);
        match p.programme {
            ProgrammeKind::Landing => {
                landing(PoseTrajectoryPoint::at_rest(p.heave_centre, nalgebra::Matrix3::identity())).point(t)
            }
            ProgrammeKind::Heave => heave.point(t),
            ProgrammeKind::StartUp => {
                StartUp { from: p.startup_position, to: p.heave_centre, duration: p.startup_duration, then: heave }
                    .point(t)
            }
            ProgrammeKind::Sinusoid => {
                let s = &p.sine;
                let offset = [s.offset, s.angle_offset].concat();
                let amplitude = [s.amplitude, s.angle_amplitude].concat();
                PoseProgramme {
                    dof: std::array::from_fn(|i| SoftStartSinusoid {
                        offset: offset[i],
                        amplitude: amplitude[i],
                        frequency: s.frequency[i],
                        phase: s.phase[i],
                        time_constant: s.time_constant,
                    }),
                }
                .point(t)
            }
            ProgrammeKind::External => {
                let q = &self.pose;
                let v = Vector3::from;
                PoseTrajectoryPoint::from_angles(
                    v(q.r),
                    v(q.v),
                    v(q.a),
                    &v(q.angles),
                    &v(q.angle_rates),
                    &v(q.angle_accelerations),
                )
            }
        }
    }

    /// Why a programme pose cannot be a stand's pose (not numbers, or beyond any stand), naming
    /// where it comes from; `None` if it can.
    fn implausible(&self, time: f64, point: &PoseTrajectoryPoint) -> Option<String> {
        let numbers = [point.r, point.v, point.a, point.w, point.w_dot].iter().all(|v| v.iter().all(|x| x.is_finite()))
            && point.rotation.iter().all(|x| x.is_finite());
        if numbers && point.r.amax() <= MAX_COORDINATE {
            return None;
        }
        let p = &self.parameters;
        let source = match p.programme {
            _ if self.landing.is_some() || p.programme == ProgrammeKind::Landing => format!(
                "the safe landing (landing.speed {:?} m/s, landing.floor {:?} m)",
                p.landing.speed, p.landing.floor
            ),
            ProgrammeKind::Heave | ProgrammeKind::StartUp => format!(
                "the parameters heave.* (heave.centre {:?} m, heave.amplitude {:?} m, heave.frequency {:?} rad/s, \
                 heave.timeConstant {:?} s){}",
                p.heave_centre.as_slice(),
                p.heave.amplitude,
                p.heave.frequency,
                p.heave.time_constant,
                if p.programme == ProgrammeKind::StartUp {
                    format!(" and startup.* (startup.position {:?} m)", p.startup_position.as_slice())
                } else {
                    String::new()
                }
            ),
            ProgrammeKind::Sinusoid => format!(
                "the parameters sine.* (amplitudes {:?} m, {:?} rad, frequencies {:?} rad/s)",
                p.sine.amplitude, p.sine.angle_amplitude, p.sine.frequency
            ),
            ProgrammeKind::External | ProgrammeKind::Landing => format!(
                "the inputs pose.* (pose.r {:?} m, pose.v {:?} m/s, pose.a {:?} m/s2, pose.angles {:?} rad)",
                self.pose.r, self.pose.v, self.pose.a, self.pose.angles
            ),
        };
        Some(format!(
            "the programme pose at t = {:?} is {} (its centre of mass at {:?} m, acceleration {:?} m/s2): it comes \
             from {source}",
            time,
            if numbers { "beyond any stand" } else { "not a number" },
            point.r.as_slice(),
            point.a.as_slice()
        ))
    }

    /// Direct problem and feedback at the current time and inputs.
    pub fn compute(&self) -> Result<ControllerOutputs, String> {
        let (point, solution) = self.direct_problem(self.time)?;
        Ok(ControllerOutputs { commands: self.feedback(&solution), programme: ProgrammeOutputs::of(&point, &solution) })
    }

    /// The programme's direct problem at the current time, kept in `programme` (the same
    /// numbers as [`ControllerModel::compute`]'s); `None` where it has none (the reason:
    /// [`FmuModel::undefined_reason`]).
    fn kept_programme(&mut self) -> Option<&(PoseTrajectoryPoint, DirectProblemSolution)> {
        if self.programme.is_none() {
            self.programme = self.direct_problem(self.time).ok();
        }
        self.programme.as_ref()
    }

    /// The programme point and its direct problem at time `time`.
    fn direct_problem(&self, time: f64) -> Result<(PoseTrajectoryPoint, DirectProblemSolution), String> {
        let point = self.programme_point(time);
        if let Some(why) = self.implausible(time, &point) {
            return Err(why);
        }
        let solution = solve_direct_problem(&self.parameters.stand, &self.parameters.leg_bodies(), &point)
            .map_err(|e| format!("the programme pose at t = {time:?} cannot be produced by the legs: {e}"))?;
        Ok((point, solution))
    }

    /// The feedback about the programme: leg forces (and voltages, with drives) for the
    /// measured legs.
    fn feedback(&self, solution: &DirectProblemSolution) -> Commands {
        let mut f = self.parameters.feedback.leg_forces(solution, &self.l, &self.ldot);
        let d = self.parameters.disturbance.at(self.time);
        let (f_min, f_max) = (self.parameters.f_min, self.parameters.f_max);
        for fk in f.iter_mut() {
            *fk = (*fk + d).clamp(f_min, f_max);
        }
        let p = &self.parameters;
        let u = if p.drive == Drive::Electric {
            std::array::from_fn(|k| {
                let (_, voltage) = p.drives.static_current_and_voltage(f[k], solution.rates[k]);
                voltage.clamp(-p.u_max, p.u_max)
            })
        } else {
            [0.0; LEG_COUNT]
        };
        let valve = if p.drive == Drive::Hydraulic {
            std::array::from_fn(|k| {
                let error = solution.lengths[k] - self.l[k];
                p.hydraulic.valve(f[k], self.pa[k], self.pb[k], self.supply_pressure, solution.rates[k], error)
            })
        } else {
            [0.0; LEG_COUNT]
        };
        Commands { f, u, valve }
    }

    /// The commands for the current time and measured legs, computed on the first read after
    /// a change (not numbers where the programme cannot be produced).
    fn commands(&mut self) -> &Commands {
        if self.commands.is_none() {
            self.kept_programme();
            self.commands = Some(self.programme.as_ref().map_or(Commands::UNDEFINED, |(_, s)| self.feedback(s)));
        }
        self.commands.as_ref().unwrap_or(&Commands::UNDEFINED)
    }

    /// The programme's outputs at the current time, computed on their first read.
    fn programme_outputs(&mut self) -> &ProgrammeOutputs {
        if self.programme_outputs.is_none() {
            let outputs =
                self.kept_programme().map_or(ProgrammeOutputs::UNDEFINED, |(p, s)| ProgrammeOutputs::of(p, s));
            self.programme_outputs = Some(outputs);
        }
        self.programme_outputs.as_ref().unwrap_or(&ProgrammeOutputs::UNDEFINED)
    }

    /// The programme's angles at the current time, computed on their first read.
    fn programme_angles(&mut self) -> &ProgrammeAngles {
        if self.angles.is_none() {
            let angles = self.kept_programme().map_or(ProgrammeAngles::UNDEFINED, |(point, _)| ProgrammeAngles {
                anglesp: angles_from_rotation(&point.rotation),
            });
            self.angles = Some(angles);
        }
        self.angles.as_ref().unwrap_or(&ProgrammeAngles::UNDEFINED)
    }

    /// The safe landing at the start of a step at time `t`: the one under way, or one that
    /// starts now from the programme's point (the input `landing.command` at 1, or the measured
    /// supply pressure below `landing.pressure`), with the message that says so.
    fn landing_trigger(&self, t: f64) -> (Option<(f64, PoseTrajectoryPoint)>, Option<String>) {
        let p = &self.parameters;
        if self.landing.is_some() || p.programme == ProgrammeKind::Landing {
            return (self.landing, None);
        }
        let why = if self.landing_command >= 0.5 {
            "landing.command is 1".to_string()
        } else if p.drive == Drive::Hydraulic && self.supply_pressure < p.landing.pressure {
            format!(
                "the supply pressure {:.4e} Pa fell below landing.pressure = {:.4e} Pa",
                self.supply_pressure, p.landing.pressure
            )
        } else {
            return (None, None);
        };
        let from = self.programme_point(t);
        let message = format!(
            "t = {t:?}: safe landing started ({why}): descending at {} m/s from z = {:.4} m to landing.floor = {} m",
            p.landing.speed, from.r.z, p.landing.floor
        );
        (Some((t, from)), Some(message))
    }

    /// The time, a parameter or a `pose.*` input changed: the programme and every output
    /// follow.
    fn programme_changed(&mut self) {
        self.programme = None;
        self.commands = None;
        self.programme_outputs = None;
        self.angles = None;
    }

    fn validate(&self) -> Result<(), String> {
        let p = &self.parameters;
        p.stand.validate().map_err(|e| e.to_string())?;
        p.legs.validate().map_err(|e| e.to_string())?;
        if p.drive == Drive::Electric {
            p.drives.validate().map_err(|e| e.to_string())?;
        }
        if p.drive == Drive::Hydraulic {
            p.hydraulic.validate()?;
        }
        if !(p.u_max > 0.0 && p.u_max.is_finite()) {
            return Err(format!("parameter Umax: must be a positive number of volts, got {:e}", p.u_max));
        }
        for (name, value) in [
            ("heave.timeConstant", p.heave.time_constant),
            ("sine.timeConstant", p.sine.time_constant),
            ("disturbance.timeConstant", p.disturbance.time_constant),
        ] {
            if value < 0.0 {
                return Err(format!("parameter {name}: must be >= 0 s (0 = no soft start), got {value:?}"));
            }
        }
        if !(p.landing.speed > 0.0 && p.landing.speed.is_finite()) {
            return Err(format!("parameter landing.speed: must be a positive number of m/s, got {:e}", p.landing.speed));
        }
        for (name, value) in [("landing.floor", p.landing.floor), ("landing.pressure", p.landing.pressure)] {
            if !value.is_finite() {
                return Err(format!("parameter {name}: must be a number, got {value:e}"));
            }
        }
        if p.programme == ProgrammeKind::StartUp && !(p.startup_duration > 0.0) {
            return Err(format!("parameter startup.duration: must be > 0 s, got {:?}", p.startup_duration));
        }
        let (f_min, f_max) = (p.f_min, p.f_max);
        if !(f_min < f_max) {
            return Err(format!("parameter Fmin: must be less than Fmax = {f_max:?} N, got {f_min:?} N"));
        }
        self.compute().map(|_| ()).map_err(|e| format!("programme: {e}"))
    }
}

impl FmuModel for ControllerModel {
    fn info(&self) -> &'static ModelInfo {
        &INFO
    }

    fn cache_block(&self, group: usize) -> Option<u8> {
        cache_block_of(BINDINGS, group)
    }

    // Out of line: the instance's refresh dispatches to both models, and the platform's fill
    // is the one a step's cycle runs.
    #[inline(never)]
    fn fill_cache(&mut self, block: u8, cache: &mut [f64]) -> bool {
        self.fill_block(block, cache)
    }

    fn get_real(&mut self, var: VariableRef) -> f64 {
        let value = match BINDINGS.get(var.group) {
            Some(Binding::Stored) => self.real_stored(var),
            Some(Binding::Cached { .. }) => self.output_value(var),
            Some(Binding::Computed) => Some(self.time),
            _ => None,
        };
        value.unwrap_or(f64::NAN)
    }

    fn set_real(&mut self, var: VariableRef, value: f64) -> Result<(), String> {
        *self.real_slot(var).ok_or("not a settable Real variable")? = value;
        if [
            variables::group::L,
            variables::group::LDOT,
            variables::group::PA,
            variables::group::PB,
            variables::group::SUPPLY_PRESSURE,
            variables::group::LANDING_COMMAND,
        ]
        .contains(&var.group)
        {
            self.commands = None;
        } else {
            self.programme_changed();
        }
        Ok(())
    }

    #[inline]
    fn set_real_run(&mut self, first: VariableRef, values: &[f64]) -> Result<(), String> {
        // The measured legs, set every step: one copy, the programme kept.
        let measured = match first.group {
            variables::group::L => Some(&mut self.l),
            variables::group::LDOT => Some(&mut self.ldot),
            variables::group::PA => Some(&mut self.pa),
            variables::group::PB => Some(&mut self.pb),
            _ => None,
        };
        if let Some(slots) = measured.and_then(|m| m.get_mut(first.index..first.index + values.len())) {
            slots.copy_from_slice(values);
            self.commands = None;
            return Ok(());
        }
        super::set_one_by_one(self, first, values)
    }

    fn get_integer(&mut self, var: VariableRef) -> i32 {
        self.integer(var).unwrap_or(0)
    }

    fn set_integer(&mut self, var: VariableRef, value: i32) -> Result<(), String> {
        self.set_integer_code(var, value).unwrap_or_else(|| Err("not a settable Integer variable".into()))?;
        self.programme_changed();
        Ok(())
    }

    fn exit_initialization(
        &mut self,
        start_time: f64,
        _tolerance: Option<f64>,
        _model_exchange: bool,
    ) -> Result<Initialised, String> {
        super::check_start_time(start_time)?;
        let before = self.time;
        self.time = start_time;
        self.programme_changed();
        if let Err(e) = self.validate() {
            self.time = before;
            return Err(e);
        }
        let p = &self.parameters;
        Ok(format!(
            "initialised at t = {start_time:?}: programme {:?}, G = {:?} N/m, D = {:?} N.s/m, feedforward {}{}",
            p.programme,
            p.feedback.gain,
            p.feedback.damping,
            p.feedback.feedforward,
            match p.drive {
                Drive::Electric => format!(
                    ", voltage outputs U (drives: N = {:.4} rad/m, Umax = {:?} V)",
                    p.drives.transmission(),
                    p.u_max
                ),
                Drive::Hydraulic => format!(
                    ", valve outputs (force loop gain {:e} 1/N, flow feed-forward {:?} at pS = {:e} Pa)",
                    p.hydraulic.force_gain, p.hydraulic.flow_feedforward, p.hydraulic.supply
                ),
                // Force outputs: the force inputs', and any actuator without a command mode of
                // the controller's own.
                _ => String::new(),
            }
        )
        .into())
    }

    fn do_step(&mut self, t: f64, h: f64, _stop_at_event: bool) -> Result<StepReport, StepError> {
        // The programme's direct problem at the new time decides whether the step can be
        // taken; the feedback waits for the outputs' first read (a closed loop sets the
        // measured legs first).
        let time = t + h;
        let (landing, started) = self.landing_trigger(t);
        let before = std::mem::replace(&mut self.landing, landing);
        match self.direct_problem(time) {
            Ok(programme) => {
                self.time = time;
                self.programme_changed();
                self.programme = Some(programme);
                Ok(StepReport { reached: time, event: false, warning: started })
            }
            Err(message) => Err(StepError {
                message: {
                    self.landing = before;
                    format!("step from t = {t:?} to {time:?} rolled back: {message}")
                },
                retry_shorter: false,
            }),
        }
    }

    fn set_input_derivative(&mut self, _var: VariableRef, _value: f64) {
        // The controller has no dynamics: its outputs follow its inputs at the communication
        // points, so input derivatives do not change them.
    }

    fn output_derivative(&mut self, _var: VariableRef) -> f64 {
        0.0
    }

    fn undefined_reason(&self) -> Option<String> {
        self.compute().err()
    }

    /// The stored variables (declaration order), the time and the safe landing under way.
    fn save(&self, w: &mut ByteWriter) {
        self.save_variables(w);
        w.f64(self.time);
        match &self.landing {
            None => w.f64(f64::NAN),
            Some((start, from)) => {
                w.f64(*start);
                for x in from.r.iter().chain(&from.v).chain(&from.a).chain(from.rotation.iter()) {
                    w.f64(*x);
                }
            }
        }
    }

    fn restore(r: &mut ByteReader) -> Result<Self, SnapshotError> {
        let mut model = ControllerModel::default();
        model.restore_variables(r)?;
        model.time = r.finite("time")?;
        let start = r.f64()?;
        if !start.is_nan() {
            let mut values = [0.0; 18];
            for x in values.iter_mut() {
                *x = r.finite("landing")?;
            }
            let v = |i: usize| Vector3::new(values[i], values[i + 1], values[i + 2]);
            let from = PoseTrajectoryPoint {
                r: v(0),
                v: v(3),
                a: v(6),
                rotation: nalgebra::Matrix3::from_column_slice(&values[9..18]),
                w: Vector3::zeros(),
                w_dot: Vector3::zeros(),
            };
            model.landing = Some((start, from));
        }
        model.programme_changed();
        Ok(model)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_outputs_hold_the_neutral_pose_at_t0() {
        let c = ControllerModel::default();
        let o = c.compute().unwrap();
        let mg = c.parameters.stand.mass * c.parameters.stand.gravity;
        let (fp, f) = (o.programme.fp, o.commands.f);
        for k in 0..LEG_COUNT {
            assert!((fp[k] / mg - 0.2005).abs() < 1e-12);
            assert!((f[k] - fp[k]).abs() < 1e-6 * mg, "no feedback at the programme's start");
        }
    }
}
