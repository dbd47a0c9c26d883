//! The `StewartCueing` model: the classical washout with a workspace limiter (SPEC §11,
//! docs/cueing.md). Inputs: the vehicle's specific force and angular velocity at the head;
//! outputs: the pose command for the controller's `programme = 3` with its exact first and
//! second derivatives, and what the driver would feel (`fsim`, `omegasim`). Co-Simulation steps
//! the washout's 21 linear-filter states with a fixed-step RK4, the inputs held; Model Exchange
//! gives the same states and derivatives to the host's integrator.

pub mod variables;

use nalgebra::Vector3;

use super::declare::{Binding, Variables, cache_block_of};
use super::snapshot::{ByteReader, ByteWriter, SnapshotError};
use super::variables::VariableRef;
use super::{Capabilities, DefaultExperiment, FmuModel, Initialised, ModelInfo, StepError, StepReport};
use crate::physics::cueing::jet::Jet;
use crate::physics::cueing::limiter::Workspace;
use crate::physics::cueing::washout::{
    DEFAULT_WASHOUT, STATE_DIM, VehicleMotion, WashoutParameters, body_rates, layout, rotation,
};
use crate::physics::legs::end_stops::EndStops;
use crate::physics::stand::{LEG_COUNT, Stand};
use variables::BINDINGS;

pub static INFO: ModelInfo = ModelInfo {
    model_name: "StewartCueing",
    model_identifier: "StewartCueing",
    description: "Motion cueing for a Stewart platform motion simulator: classical washout (scaling, tilt \
                  coordination, rotational and translational high-pass) and a workspace limiter over the six leg \
                  strokes; outputs the pose command for StewartController's programme 3",
    groups: variables::GROUPS,
    enumerations: &[],
    units: super::units::UNITS,
    default_experiment: DefaultExperiment { start_time: 0.0, stop_time: 20.0, step_size: 1e-3 },
    documentation: include_str!("documentation.html"),
    states: variables::STATES,
    // Co-Simulation takes the inputs' first derivatives (a first-order hold: a sampled
    // sinusoid drives the filters without the staircase of a held input).
    capabilities: Capabilities { model_exchange: true, can_interpolate_inputs: true, ..Capabilities::NONE },
};

/// Default head point, m, body frame from the centre of mass: the driver of the default
/// truck cabin sits forward and on the left, about a metre above the loaded platform's centre
/// of mass (docs/cueing.md).
pub const DEFAULT_HEAD: [f64; 3] = [0.5, 0.4, 1.0];
/// Default stroke kept free at each end, m: the controller's following error (mm) and room for
/// the end stops' reach.
pub const DEFAULT_MARGIN: f64 = 0.03;
/// Default limiter onset (workspace usage).
pub const DEFAULT_ONSET: f64 = 0.8;
/// Default largest internal step, s: a thousandth of a second against the fastest rate of the
/// default equations (the tilt's catch-up, 20 1/s; the filters up to 4 rad/s).
pub const DEFAULT_MAX_STEP: f64 = 1e-3;
/// Smallest `solver.maxStep`, s: below it a long communication step would take millions of
/// sub-steps.
pub const MIN_MAX_STEP: f64 = 1e-6;
/// Largest commanded pitch, rad (80 deg): the Euler-angle rates of the 1-2-3 sequence are
/// singular at 90 deg, so a washout that gets there (a slow rotational high-pass with a large
/// `omegamax`) stops with a message instead.
pub const MAX_PITCH: f64 = 1.396;

/// The parameters of the cueing FMU.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CueingParameters {
    pub washout: WashoutParameters,
    pub head: [f64; 3],
    pub margin: f64,
    pub onset: f64,
    pub neutral: [f64; 3],
    pub max_step: f64,
    pub base_joints: [Vector3<f64>; LEG_COUNT],
    pub platform_joints: [Vector3<f64>; LEG_COUNT],
    pub lmin: [f64; LEG_COUNT],
    pub lmax: [f64; LEG_COUNT],
}

impl Default for CueingParameters {
    fn default() -> Self {
        let stand = Stand::default();
        let stops = EndStops::default();
        CueingParameters {
            washout: DEFAULT_WASHOUT,
            head: DEFAULT_HEAD,
            margin: DEFAULT_MARGIN,
            onset: DEFAULT_ONSET,
            // The default stand's neutral pose (docs/model.md §3).
            neutral: Stand::truck_cabin_neutral_position().into(),
            max_step: DEFAULT_MAX_STEP,
            base_joints: stand.base_joints,
            platform_joints: stand.platform_joints,
            lmin: stops.lower,
            lmax: stops.upper,
        }
    }
}

impl CueingParameters {
    pub fn workspace(&self) -> Workspace {
        Workspace {
            base_joints: self.base_joints,
            platform_joints: self.platform_joints,
            lower: self.lmin.map(|l| l + self.margin),
            upper: self.lmax.map(|l| l - self.margin),
            neutral: Vector3::from(self.neutral),
            onset: self.onset,
        }
    }

    fn validate(&self) -> Result<(), String> {
        self.washout.validate()?;
        if !(self.margin >= 0.0 && self.margin.is_finite()) {
            return Err(format!("parameter margin: must be >= 0 m, got {:?}", self.margin));
        }
        if !(self.max_step >= MIN_MAX_STEP && self.max_step.is_finite()) {
            return Err(format!(
                "parameter solver.maxStep: must be at least {MIN_MAX_STEP:e} s, got {:?}",
                self.max_step
            ));
        }
        for k in 0..LEG_COUNT {
            if !(self.lmin[k] + 2.0 * self.margin < self.lmax[k]) {
                return Err(format!(
                    "parameter margin: {:?} m at both ends leaves no stroke on leg {} (lmin = {:?} m, lmax = {:?} m)",
                    self.margin,
                    k + 1,
                    self.lmin[k],
                    self.lmax[k]
                ));
            }
        }
        self.workspace().validate()
    }
}

/// The washout's states by name (the FMU's state variables `washout.*`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CueingStates {
    pub q: [f64; 3],
    pub r: [f64; 3],
    pub v: [f64; 3],
    pub fl: [f64; 2],
    pub fl_rate: [f64; 2],
    pub tilt: [f64; 2],
    pub z: [f64; 3],
    pub angles: [f64; 3],
}

impl CueingStates {
    pub fn to_vector(&self) -> [f64; STATE_DIM] {
        let mut x = [0.0; STATE_DIM];
        x[layout::TRANSLATION_Q..][..3].copy_from_slice(&self.q);
        x[layout::HEAD_R..][..3].copy_from_slice(&self.r);
        x[layout::HEAD_V..][..3].copy_from_slice(&self.v);
        x[layout::TILT_F..][..2].copy_from_slice(&self.fl);
        x[layout::TILT_FDOT..][..2].copy_from_slice(&self.fl_rate);
        x[layout::TILT_ANGLES..][..2].copy_from_slice(&self.tilt);
        x[layout::ROTATION_Q..][..3].copy_from_slice(&self.z);
        x[layout::ROTATION_ANGLES..][..3].copy_from_slice(&self.angles);
        x
    }

    pub fn from_vector(x: &[f64; STATE_DIM]) -> Self {
        let take = |at: usize| -> [f64; 3] { [x[at], x[at + 1], x[at + 2]] };
        let pair = |at: usize| -> [f64; 2] { [x[at], x[at + 1]] };
        CueingStates {
            q: take(layout::TRANSLATION_Q),
            r: take(layout::HEAD_R),
            v: take(layout::HEAD_V),
            fl: pair(layout::TILT_F),
            fl_rate: pair(layout::TILT_FDOT),
            tilt: pair(layout::TILT_ANGLES),
            z: take(layout::ROTATION_Q),
            angles: take(layout::ROTATION_ANGLES),
        }
    }
}

/// What the cueing FMU reports at one instant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CueingOutputs {
    pub r: [f64; 3],
    pub v: [f64; 3],
    pub a: [f64; 3],
    pub angles: [f64; 3],
    pub angle_rates: [f64; 3],
    pub angle_accelerations: [f64; 3],
    pub fsim: [f64; 3],
    pub omegasim: [f64; 3],
    pub usage: f64,
    pub scale: f64,
    pub limited: bool,
}

impl CueingOutputs {
    /// The pose command and the motion felt for the washout's state `x` and the vehicle's
    /// motion `m`.
    pub fn compute(p: &CueingParameters, x: &[f64; STATE_DIM], m: &VehicleMotion) -> CueingOutputs {
        let pose = p.washout.pose(x, m);
        let head = Vector3::from(p.head);
        // The centre of mass's deviation from neutral: the head's displacement and the
        // rotation about the head, r - neutral = P + head - R head.
        let arm = rotated(&rotation(&pose.angles), &head);
        let dr: [Jet; 3] = std::array::from_fn(|i| pose.head[i] - arm[i] + head[i]);
        let limited = p.workspace().limit(&dr, &pose.angles);
        let (r, angles) = (limited.r, limited.angles);
        let rot = rotation(&angles);
        let arm = rotated(&rot, &head);
        let head_acceleration = Vector3::from_fn(|i, _| r[i].d2 + arm[i].d2);
        let felt = rot.map(|x| x.v).transpose() * (head_acceleration + Vector3::new(0.0, 0.0, p.washout.gravity));
        let omegasim = body_rates(&angles.map(|a| a.v), &angles.map(|a| a.d1));
        CueingOutputs {
            r: r.map(|x| x.v),
            v: r.map(|x| x.d1),
            a: r.map(|x| x.d2),
            angles: angles.map(|x| x.v),
            angle_rates: angles.map(|x| x.d1),
            angle_accelerations: angles.map(|x| x.d2),
            fsim: felt.into(),
            omegasim: omegasim.into(),
            usage: limited.usage,
            scale: limited.scale,
            limited: limited.scale < 1.0,
        }
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

fn rotated(rot: &nalgebra::Matrix3<Jet>, v: &Vector3<f64>) -> [Jet; 3] {
    std::array::from_fn(|i| rot[(i, 0)] * v.x + rot[(i, 1)] * v.y + rot[(i, 2)] * v.z)
}

/// The cueing FMU model.
#[derive(Clone, Debug, PartialEq)]
pub struct CueingModel {
    pub parameters: CueingParameters,
    /// Inputs `f`, `omega`.
    pub vehicle: VehicleMotion,
    /// The inputs' first derivatives for the next step (`fmi2SetRealInputDerivatives`; 0
    /// after each step): `f` then `omega`.
    pub input_rates: [f64; 6],
    pub state: CueingStates,
    pub time: f64,
    outputs: Option<CueingOutputs>,
}

impl Default for CueingModel {
    fn default() -> Self {
        let parameters = CueingParameters::default();
        CueingModel {
            vehicle: VehicleMotion { f: [0.0, 0.0, parameters.washout.gravity], omega: [0.0; 3] },
            parameters,
            input_rates: [0.0; 6],
            state: CueingStates::default(),
            time: 0.0,
            outputs: None,
        }
    }
}

impl CueingModel {
    fn outputs(&mut self) -> &CueingOutputs {
        let (p, x, m) = (&self.parameters, self.state.to_vector(), &self.vehicle);
        self.outputs.get_or_insert_with(|| CueingOutputs::compute(p, &x, m))
    }

    /// The washout's state rate now.
    pub fn rate(&self) -> [f64; STATE_DIM] {
        self.parameters.washout.rate(&self.state.to_vector(), &self.vehicle)
    }

    /// Advances the states by `h` with RK4 in equal sub-steps of at most `solver.maxStep`,
    /// the inputs following their derivatives from the step's start.
    fn integrate(&self, h: f64) -> [f64; STATE_DIM] {
        let w = &self.parameters.washout;
        let (m, rates) = (&self.vehicle, &self.input_rates);
        let at = |tau: f64| VehicleMotion {
            f: std::array::from_fn(|i| m.f[i] + rates[i] * tau),
            omega: std::array::from_fn(|i| m.omega[i] + rates[3 + i] * tau),
        };
        let n = (h / self.parameters.max_step).abs().ceil().max(1.0) as usize;
        let dt = h / n as f64;
        let mut x = self.state.to_vector();
        let shifted = |x: &[f64; STATE_DIM], k: &[f64; STATE_DIM], c: f64| std::array::from_fn(|i| x[i] + c * k[i]);
        for step in 0..n {
            let tau = step as f64 * dt;
            let (start, middle, end) = (at(tau), at(tau + 0.5 * dt), at(tau + dt));
            let k1 = w.rate(&x, &start);
            let k2 = w.rate(&shifted(&x, &k1, 0.5 * dt), &middle);
            let k3 = w.rate(&shifted(&x, &k2, 0.5 * dt), &middle);
            let k4 = w.rate(&shifted(&x, &k3, dt), &end);
            for i in 0..STATE_DIM {
                x[i] += dt / 6.0 * (k1[i] + 2.0 * (k2[i] + k3[i]) + k4[i]);
            }
        }
        x
    }
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

    fn get_integer(&mut self, _var: VariableRef) -> i32 {
        0
    }

    fn set_integer(&mut self, _var: VariableRef, _value: i32) -> Result<(), String> {
        Err("not a settable Integer variable".into())
    }

    fn get_boolean(&mut self, var: VariableRef) -> bool {
        var.group == variables::group::LIMITED && self.outputs().limited
    }

    fn exit_initialization(
        &mut self,
        start_time: f64,
        _tolerance: Option<f64>,
        _model_exchange: bool,
    ) -> Result<Initialised, String> {
        super::check_start_time(start_time)?;
        self.parameters.validate()?;
        self.time = start_time;
        self.outputs = None;
        let w = &self.parameters.washout;
        Ok(format!(
            "initialised at t = {start_time:?}: K_f = {:?}, K_w = {:?}, w_t = {:?} rad/s, w_b = {:?} rad/s, tilt \
             w_l = {:?} rad/s at most {:?} rad/s, w_r = {:?} rad/s, head {:?} m, margin {:?} m",
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
        let x = self.integrate(h);
        let pitch = x[layout::ROTATION_ANGLES + 1] + x[layout::TILT_ANGLES + 1];
        check_pitch(pitch).map_err(|why| StepError {
            message: format!("step from t = {t:?} to {:?} rolled back: {why}", t + h),
            retry_shorter: false,
        })?;
        if let Some(i) = x.iter().position(|v| !v.is_finite()) {
            return Err(StepError {
                message: format!(
                    "step from t = {t:?} to {:?} rolled back: state {} of the washout is not finite (check the \
                     filters' parameters and the inputs)",
                    t + h,
                    i + 1
                ),
                retry_shorter: false,
            });
        }
        self.state = CueingStates::from_vector(&x);
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
        x.copy_from_slice(&self.state.to_vector()[..x.len()]);
    }

    fn set_continuous_states(&mut self, x: &[f64]) {
        let mut full = self.state.to_vector();
        full[..x.len()].copy_from_slice(x);
        self.state = CueingStates::from_vector(&full);
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

    /// The stored variables (parameters, inputs, the washout's states), the inputs'
    /// derivatives and the time.
    fn save(&self, w: &mut ByteWriter) {
        self.save_variables(w);
        w.f64s(&self.input_rates);
        w.f64(self.time);
    }

    fn restore(r: &mut ByteReader) -> Result<Self, SnapshotError> {
        let mut model = CueingModel::default();
        model.restore_variables(r)?;
        model.input_rates = r.finite_array::<6>("der(f), der(omega)")?;
        model.time = r.finite("time")?;
        Ok(model)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The default washout after 1.5 s of braking in a left curve, or (`limited`) one that
    /// leaves the workspace on a sustained braking in a left curve (full scale,
    /// a slow return), so that the limiter acts.
    fn moving_model(limited: bool) -> CueingModel {
        let mut m = CueingModel::default();
        if limited {
            let w = &mut m.parameters.washout;
            w.scale_f = [1.0; 3];
            w.scale_omega = [1.0; 3];
            w.hp_f_break = [0.1; 3];
            w.hp_f_omega = [1.0, 1.0, 2.0];
        }
        m.vehicle = if limited {
            VehicleMotion { f: [-4.0, 3.0, 11.0], omega: [0.05, -0.04, 0.3] }
        } else {
            VehicleMotion { f: [-1.5, 1.0, 10.3], omega: [0.05, -0.04, 0.3] }
        };
        m.parameters.validate().unwrap();
        for _ in 0..150 {
            m.state = CueingStates::from_vector(&m.integrate(0.01));
        }
        m
    }

    /// The pose command's velocity and acceleration (through the washout's jets and the
    /// limiter's Newton steps on jets) against central differences of the command along the
    /// motion, the inputs held: the limiter acting, and not.
    #[test]
    fn the_command_carries_its_exact_derivatives() {
        for limited in [true, false] {
            let m = moving_model(limited);
            let now = CueingOutputs::compute(&m.parameters, &m.state.to_vector(), &m.vehicle);
            assert_eq!(now.limited, limited, "usage {}", now.usage);
            let d = 1e-4;
            let at = |h: f64| CueingOutputs::compute(&m.parameters, &m.integrate(h), &m.vehicle);
            let (ahead, behind) = (at(d), at(-d));
            for i in 0..3 {
                let v = (ahead.r[i] - behind.r[i]) / (2.0 * d);
                let a = (ahead.r[i] - 2.0 * now.r[i] + behind.r[i]) / (d * d);
                let rate = (ahead.angles[i] - behind.angles[i]) / (2.0 * d);
                let accel = (ahead.angles[i] - 2.0 * now.angles[i] + behind.angles[i]) / (d * d);
                assert!((now.v[i] - v).abs() < 1e-7, "limited {limited}: v[{i}] {} against {v}", now.v[i]);
                assert!((now.a[i] - a).abs() < 1e-3, "limited {limited}: a[{i}] {} against {a}", now.a[i]);
                assert!(
                    (now.angle_rates[i] - rate).abs() < 1e-8,
                    "angleRates[{i}] {} against {rate}",
                    now.angle_rates[i]
                );
                assert!(
                    (now.angle_accelerations[i] - accel).abs() < 1e-4,
                    "angleAccelerations[{i}] {} against {accel}",
                    now.angle_accelerations[i]
                );
            }
        }
    }

    /// Every leg of the limited command stays inside `[lmin + margin, lmax - margin]` while
    /// the washout's own pose would leave it.
    #[test]
    fn the_limited_command_keeps_the_legs_inside_their_margins() {
        let m = moving_model(true);
        let o = CueingOutputs::compute(&m.parameters, &m.state.to_vector(), &m.vehicle);
        assert!(o.usage > 1.0, "the washout's own pose leaves the workspace (usage {})", o.usage);
        let ws = m.parameters.workspace();
        let dr = [0, 1, 2].map(|i| o.r[i] - m.parameters.neutral[i]);
        for k in 0..LEG_COUNT {
            let l = ws.leg_length(k, &dr, &o.angles);
            assert!(
                l > ws.lower[k] && l < ws.upper[k],
                "leg {}: {l} outside [{}, {}]",
                k + 1,
                ws.lower[k],
                ws.upper[k]
            );
        }
    }
}
