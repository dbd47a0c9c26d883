//! The `StewartController` model: the paper's programme motion control (section 7) as a
//! component. A programme pose (the paper's heave, a six-degree-of-freedom sinusoid, or a
//! pose from inputs) goes through the direct problem and inverse kinematics of the same
//! physics core as the platform; the leg forces are `F = F^p + G (l^p - l) + D (ldot^p -
//! ldot)` (+ an optional disturbance). No states: outputs are functions of time, inputs and
//! parameters (direct feed-through from `l`, `ldot` to `F`).

pub mod variables;

use crate::models::Initialised;
use nalgebra::Vector3;

use super::snapshot::{ByteReader, ByteWriter, SnapshotError};
use super::variables::VariableRef;
use super::{DefaultExperiment, FmuModel, ModelInfo, StepError, StepReport};
use crate::control::{Disturbance, LegFeedback};
use crate::physics::direct_problem::solve_direct_problem;
use crate::physics::end_stops::EndStops;
use crate::physics::kinematics::{PoseTrajectoryPoint, angles_from_rotation};
use crate::physics::programme::{PoseProgramme, SoftStartSinusoid, StartUp};
use crate::physics::stand::{LEG_COUNT, Stand};
use variables::group;

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

/// Default feedback gain, N/m: with the default stand and a 1 ms communication step it keeps
/// every leg within a millimetre of its programme length on the default heave programme
/// (about 10 M g / R_b; tested).
pub const DEFAULT_GAIN: f64 = 2.0e5;
/// Default rate gain, N s/m: a damping ratio near 0.8 for the heave mode with
/// [`DEFAULT_GAIN`].
pub const DEFAULT_DAMPING: f64 = 2.0e4;
/// Default actuator saturation, N: each drive can push or pull the whole default platform's
/// weight (29.4 kN); the default heave programme needs at most 7.7 kN per leg.
pub const DEFAULT_FORCE_LIMIT: f64 = 3.0e4;
/// Default lift duration of the start-up programme, s.
pub const DEFAULT_STARTUP_DURATION: f64 = 3.0;

/// Which programme motion the controller follows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ProgrammeKind {
    Heave = 1,
    Sinusoid = 2,
    External = 3,
    StartUp = 4,
}

impl ProgrammeKind {
    fn from_code(code: i32) -> Option<Self> {
        match code {
            1 => Some(ProgrammeKind::Heave),
            2 => Some(ProgrammeKind::Sinusoid),
            3 => Some(ProgrammeKind::External),
            4 => Some(ProgrammeKind::StartUp),
            _ => None,
        }
    }
}

/// Everything set through parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct ControllerParameters {
    pub stand: Stand,
    pub feedback: LegFeedback,
    pub programme: ProgrammeKind,
    pub heave_centre: Vector3<f64>,
    /// `a` (m), `Omega` (rad/s), `T` (s).
    pub heave: [f64; 3],
    pub sine_offset: [f64; 6],
    pub sine_amplitude: [f64; 6],
    pub sine_frequency: [f64; 6],
    pub sine_phase: [f64; 6],
    pub sine_time_constant: f64,
    pub disturbance: Disturbance,
    /// Programme 4: parked centre of mass (m) and lift duration (s).
    pub startup_position: Vector3<f64>,
    pub startup_duration: f64,
    /// `Fmin`, `Fmax`, N.
    pub force_limits: [f64; 2],
}

impl Default for ControllerParameters {
    /// The paper's heave programme scaled to the default stand: `a = 0.2 R_b`,
    /// `Omega = sqrt(g / R_b)`, `T = 2 / Omega`.
    fn default() -> Self {
        let stand = Stand::truck_cabin();
        let centre = Stand::truck_cabin_neutral_position();
        let r_b = stand.base_radius();
        let omega = (stand.gravity / r_b).sqrt();
        ControllerParameters {
            feedback: LegFeedback { gain: DEFAULT_GAIN, damping: DEFAULT_DAMPING, feedforward: true },
            programme: ProgrammeKind::Heave,
            heave_centre: centre,
            heave: [0.2 * r_b, omega, 2.0 / omega],
            sine_offset: [centre.x, centre.y, centre.z, 0.0, 0.0, 0.0],
            sine_amplitude: [0.0; 6],
            sine_frequency: [omega; 6],
            sine_phase: [0.0; 6],
            sine_time_constant: 2.0 / omega,
            disturbance: Disturbance { amplitude: 0.0, frequency: 2.0 * omega, time_constant: 2.0 / omega },
            startup_position: Vector3::new(
                centre.x,
                centre.y,
                EndStops::default().level_rest_height(&stand).unwrap_or(centre.z),
            ),
            startup_duration: DEFAULT_STARTUP_DURATION,
            force_limits: [-DEFAULT_FORCE_LIMIT, DEFAULT_FORCE_LIMIT],
            stand,
        }
    }
}

/// Everything the controller reports at one instant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ControllerOutputs {
    pub f: [f64; LEG_COUNT],
    pub fp: [f64; LEG_COUNT],
    pub lp: [f64; LEG_COUNT],
    pub ldotp: [f64; LEG_COUNT],
    pub rp: Vector3<f64>,
    pub anglesp: Vector3<f64>,
}

/// The controller FMU model.
#[derive(Clone, Debug, PartialEq)]
pub struct ControllerModel {
    pub parameters: ControllerParameters,
    pub l: [f64; LEG_COUNT],
    pub ldot: [f64; LEG_COUNT],
    /// Inputs `pose.r, pose.v, pose.a, pose.angles, pose.angleRates, pose.angleAccelerations`.
    pub pose: [[f64; 3]; 6],
    pub time: f64,
    outputs: Option<ControllerOutputs>,
}

impl Default for ControllerModel {
    fn default() -> Self {
        let parameters = ControllerParameters::default();
        let centre = parameters.heave_centre;
        let neutral = solve_direct_problem(
            &parameters.stand,
            &PoseTrajectoryPoint::at_rest(centre, nalgebra::Matrix3::identity()),
        )
        .map(|s| s.lengths)
        .unwrap_or([0.0; LEG_COUNT]);
        ControllerModel {
            parameters,
            l: neutral,
            ldot: [0.0; LEG_COUNT],
            pose: [[centre.x, centre.y, centre.z], [0.0; 3], [0.0; 3], [0.0; 3], [0.0; 3], [0.0; 3]],
            time: 0.0,
            outputs: None,
        }
    }
}

impl ControllerModel {
    /// The programme pose with its derivatives at time `t`.
    pub fn programme_point(&self, t: f64) -> PoseTrajectoryPoint {
        let p = &self.parameters;
        let heave = PoseProgramme::heave(p.heave_centre, p.heave[0], p.heave[1], p.heave[2]);
        match p.programme {
            ProgrammeKind::Heave => heave.point(t),
            ProgrammeKind::StartUp => {
                StartUp { from: p.startup_position, to: p.heave_centre, duration: p.startup_duration, then: heave }
                    .point(t)
            }
            ProgrammeKind::Sinusoid => PoseProgramme {
                dof: std::array::from_fn(|i| SoftStartSinusoid {
                    offset: p.sine_offset[i],
                    amplitude: p.sine_amplitude[i],
                    frequency: p.sine_frequency[i],
                    phase: p.sine_phase[i],
                    time_constant: p.sine_time_constant,
                }),
            }
            .point(t),
            ProgrammeKind::External => {
                let v = |i: usize| Vector3::from(self.pose[i]);
                PoseTrajectoryPoint::from_angles(v(0), v(1), v(2), &v(3), &v(4), &v(5))
            }
        }
    }

    /// Direct problem and feedback at the current time and inputs.
    pub fn compute(&self) -> Result<ControllerOutputs, String> {
        let point = self.programme_point(self.time);
        let solution = solve_direct_problem(&self.parameters.stand, &point)
            .map_err(|e| format!("the programme pose at t = {} cannot be produced by the legs: {e}", self.time))?;
        let mut f = self.parameters.feedback.leg_forces(&solution, &self.l, &self.ldot);
        let d = self.parameters.disturbance.at(self.time);
        let [f_min, f_max] = self.parameters.force_limits;
        for fk in f.iter_mut() {
            *fk = (*fk + d).clamp(f_min, f_max);
        }
        Ok(ControllerOutputs {
            f,
            fp: solution.forces,
            lp: solution.lengths,
            ldotp: solution.rates,
            rp: point.r,
            anglesp: angles_from_rotation(&point.rotation),
        })
    }

    fn outputs(&mut self) -> Option<ControllerOutputs> {
        if self.outputs.is_none() {
            self.outputs = self.compute().ok();
        }
        self.outputs
    }

    fn slot(&mut self, var: VariableRef) -> Option<&mut f64> {
        let p = &mut self.parameters;
        let i = var.index;
        Some(match var.group {
            group::L => self.l.get_mut(i)?,
            group::LDOT => self.ldot.get_mut(i)?,
            g @ group::POSE_R..=group::POSE_ANGLE_ACCELERATIONS => self.pose.get_mut(g - group::POSE_R)?.get_mut(i)?,
            group::M => &mut p.stand.mass,
            group::J => p.stand.inertia.get_mut(i)?,
            group::G_GRAVITY => &mut p.stand.gravity,
            group::B => p.stand.base_joints.get_mut(i / 3)?.get_mut(i % 3)?,
            group::A => p.stand.platform_joints.get_mut(i / 3)?.get_mut(i % 3)?,
            group::GAIN => &mut p.feedback.gain,
            group::DAMPING => &mut p.feedback.damping,
            group::HEAVE_CENTRE => p.heave_centre.get_mut(i)?,
            group::HEAVE_AMPLITUDE => &mut p.heave[0],
            group::HEAVE_FREQUENCY => &mut p.heave[1],
            group::HEAVE_TIME_CONSTANT => &mut p.heave[2],
            group::SINE_OFFSET => p.sine_offset.get_mut(i)?,
            group::SINE_ANGLE_OFFSET => p.sine_offset.get_mut(3 + i)?,
            group::SINE_AMPLITUDE => p.sine_amplitude.get_mut(i)?,
            group::SINE_ANGLE_AMPLITUDE => p.sine_amplitude.get_mut(3 + i)?,
            group::SINE_FREQUENCY => p.sine_frequency.get_mut(i)?,
            group::SINE_PHASE => p.sine_phase.get_mut(i)?,
            group::SINE_TIME_CONSTANT => &mut p.sine_time_constant,
            group::DISTURBANCE_AMPLITUDE => &mut p.disturbance.amplitude,
            group::DISTURBANCE_FREQUENCY => &mut p.disturbance.frequency,
            group::DISTURBANCE_TIME_CONSTANT => &mut p.disturbance.time_constant,
            group::STARTUP_POSITION => p.startup_position.get_mut(i)?,
            group::STARTUP_DURATION => &mut p.startup_duration,
            group::FMIN => &mut p.force_limits[0],
            group::FMAX => &mut p.force_limits[1],
            _ => return None,
        })
    }

    fn validate(&self) -> Result<(), String> {
        let p = &self.parameters;
        p.stand.validate().map_err(|e| e.to_string())?;
        for (name, value) in [
            ("heave.timeConstant", p.heave[2]),
            ("sine.timeConstant", p.sine_time_constant),
            ("disturbance.timeConstant", p.disturbance.time_constant),
        ] {
            if value < 0.0 {
                return Err(format!("parameter {name}: must be >= 0 s (0 = no soft start), got {value}"));
            }
        }
        if p.programme == ProgrammeKind::StartUp && !(p.startup_duration > 0.0) {
            return Err(format!("parameter startup.duration: must be > 0 s, got {}", p.startup_duration));
        }
        let [f_min, f_max] = p.force_limits;
        if !(f_min < f_max) {
            return Err(format!("parameter Fmin: must be less than Fmax = {f_max} N, got {f_min} N"));
        }
        self.compute().map(|_| ()).map_err(|e| format!("programme: {e}"))
    }
}

impl FmuModel for ControllerModel {
    fn info(&self) -> &'static ModelInfo {
        &INFO
    }

    fn get_real(&mut self, var: VariableRef) -> f64 {
        if var.group == group::TIME {
            return self.time;
        }
        if let Some(slot) = self.slot(var) {
            return *slot;
        }
        // NaN when the programme cannot be produced (only possible before initialisation;
        // the FMI layer turns it into an error naming the variable).
        let Some(o) = self.outputs() else { return f64::NAN };
        let i = var.index;
        let pick6 = |a: &[f64; LEG_COUNT]| a.get(i).copied().unwrap_or(f64::NAN);
        match var.group {
            group::F => pick6(&o.f),
            group::FP => pick6(&o.fp),
            group::LP => pick6(&o.lp),
            group::LDOTP => pick6(&o.ldotp),
            group::RP => o.rp.get(i).copied().unwrap_or(f64::NAN),
            group::ANGLESP => o.anglesp.get(i).copied().unwrap_or(f64::NAN),
            _ => f64::NAN,
        }
    }

    fn set_real(&mut self, var: VariableRef, value: f64) -> Result<(), String> {
        let slot = self.slot(var).ok_or("not a settable Real variable")?;
        *slot = value;
        self.outputs = None;
        Ok(())
    }

    fn get_integer(&mut self, var: VariableRef) -> i32 {
        match var.group {
            group::FEEDFORWARD => self.parameters.feedback.feedforward as i32,
            group::PROGRAMME => self.parameters.programme as i32,
            _ => 0,
        }
    }

    fn set_integer(&mut self, var: VariableRef, value: i32) -> Result<(), String> {
        match var.group {
            group::FEEDFORWARD => match value {
                0 | 1 => self.parameters.feedback.feedforward = value == 1,
                _ => return Err(format!("{value} is neither 0 (off) nor 1 (on)")),
            },
            group::PROGRAMME => {
                self.parameters.programme = ProgrammeKind::from_code(value).ok_or_else(|| {
                    format!("{value} is not a programme (1 = heave, 2 = sinusoid, 3 = external, 4 = start-up)")
                })?;
            }
            _ => return Err("not a settable Integer variable".into()),
        }
        self.outputs = None;
        Ok(())
    }

    fn exit_initialization(
        &mut self,
        start_time: f64,
        _tolerance: Option<f64>,
        _model_exchange: bool,
    ) -> Result<Initialised, String> {
        let before = self.time;
        self.time = start_time;
        self.outputs = None;
        if let Err(e) = self.validate() {
            self.time = before;
            return Err(e);
        }
        let p = &self.parameters;
        Ok(format!(
            "initialised at t = {start_time}: programme {:?}, G = {} N/m, D = {} N.s/m, feedforward {}",
            p.programme, p.feedback.gain, p.feedback.damping, p.feedback.feedforward
        )
        .into())
    }

    fn do_step(&mut self, t: f64, h: f64, _stop_at_event: bool) -> Result<StepReport, StepError> {
        let before = (self.time, self.outputs);
        self.time = t + h;
        self.outputs = None;
        match self.compute() {
            Ok(o) => {
                self.outputs = Some(o);
                Ok(StepReport { reached: t + h, event: false })
            }
            Err(message) => {
                (self.time, self.outputs) = before;
                Err(StepError {
                    message: format!("step from t = {t} to {} rolled back: {message}", t + h),
                    retry_shorter: false,
                })
            }
        }
    }

    fn set_input_derivative(&mut self, _var: VariableRef, _value: f64) {
        // The controller has no dynamics: its outputs follow its inputs at the communication
        // points, so input derivatives do not change them.
    }

    fn output_derivative(&mut self, _var: VariableRef) -> f64 {
        0.0
    }

    fn save(&self, w: &mut ByteWriter) {
        let p = &self.parameters;
        w.stand(&p.stand);
        w.f64s(&[p.feedback.gain, p.feedback.damping]);
        w.bool(p.feedback.feedforward);
        w.i32(p.programme as i32);
        w.f64s(p.heave_centre.as_slice());
        w.f64s(&p.heave);
        for a in [&p.sine_offset, &p.sine_amplitude, &p.sine_frequency, &p.sine_phase] {
            w.f64s(a);
        }
        w.f64(p.sine_time_constant);
        w.f64s(&[p.disturbance.amplitude, p.disturbance.frequency, p.disturbance.time_constant]);
        w.f64s(p.startup_position.as_slice());
        w.f64(p.startup_duration);
        w.f64s(&p.force_limits);
        w.f64s(&self.l);
        w.f64s(&self.ldot);
        for v in &self.pose {
            w.f64s(v);
        }
        w.f64(self.time);
    }

    fn restore(r: &mut ByteReader) -> Result<Self, SnapshotError> {
        let stand = r.stand()?;
        let [gain, damping] = r.finite_array::<2>("gains")?;
        let feedforward = r.bool()?;
        let code = r.i32()?;
        let programme =
            ProgrammeKind::from_code(code).ok_or_else(|| SnapshotError(format!("invalid programme {code}")))?;
        let heave_centre = Vector3::from(r.finite_array::<3>("heave.centre")?);
        let heave = r.finite_array::<3>("heave")?;
        let sine_offset = r.finite_array::<6>("sine.offset")?;
        let sine_amplitude = r.finite_array::<6>("sine.amplitude")?;
        let sine_frequency = r.finite_array::<6>("sine.frequency")?;
        let sine_phase = r.finite_array::<6>("sine.phase")?;
        let sine_time_constant = r.finite("sine.timeConstant")?;
        let [amplitude, frequency, time_constant] = r.finite_array::<3>("disturbance")?;
        let startup_position = Vector3::from(r.finite_array::<3>("startup.position")?);
        let startup_duration = r.finite("startup.duration")?;
        let force_limits = r.finite_array::<2>("Fmin, Fmax")?;
        let l = r.finite_array::<LEG_COUNT>("l")?;
        let ldot = r.finite_array::<LEG_COUNT>("ldot")?;
        let mut pose = [[0.0; 3]; 6];
        for v in pose.iter_mut() {
            *v = r.finite_array::<3>("pose")?;
        }
        let time = r.finite("time")?;
        Ok(ControllerModel {
            parameters: ControllerParameters {
                stand,
                feedback: LegFeedback { gain, damping, feedforward },
                programme,
                heave_centre,
                heave,
                sine_offset,
                sine_amplitude,
                sine_frequency,
                sine_phase,
                sine_time_constant,
                disturbance: Disturbance { amplitude, frequency, time_constant },
                startup_position,
                startup_duration,
                force_limits,
            },
            l,
            ldot,
            pose,
            time,
            outputs: None,
        })
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
        for k in 0..LEG_COUNT {
            assert!((o.fp[k] / mg - 0.2005).abs() < 1e-12);
            assert!((o.f[k] - o.fp[k]).abs() < 1e-6 * mg, "no feedback at the programme's start");
        }
    }
}
