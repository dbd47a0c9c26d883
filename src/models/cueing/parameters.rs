//! The cueing FMU's parameters: the classical washout's, the predictive method's, the head,
//! the workspace and the stand (docs/cueing.md gives every default and its reason).

use nalgebra::Vector3;

use crate::control::predictive_cueing::{DEFAULT_PREDICTIVE, PredictiveParameters, PredictiveStand};
use crate::models::declare::IntegerStorage;
use crate::physics::cueing::limiter::Workspace;
use crate::physics::cueing::washout::{DEFAULT_WASHOUT, WashoutParameters};
use crate::physics::legs::end_stops::EndStops;
use crate::physics::stand::{LEG_COUNT, Stand};

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
/// default washout (its filters up to 4 rad/s).
pub const DEFAULT_MAX_STEP: f64 = 1e-3;
/// Smallest `solver.maxStep`, s: below it a long communication step would take millions of
/// sub-steps.
pub const MIN_MAX_STEP: f64 = 1e-6;
/// Most internal steps one `doStep` may take (sub-steps of `solver.maxStep`, solves of the
/// predictive method): a longer communication step is refused with a message instead of
/// running for minutes (a step of 1e308 s would never end). 10^6 steps of 1 ms: 1000 s.
pub const MAX_STEPS_PER_CALL: f64 = 1e6;

/// The cueing method (`cueing.method`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Method {
    /// 0: the classical washout (SPEC §11).
    #[default]
    Classical,
    /// 1: predictive cueing (SPEC §12).
    Predictive,
}

impl IntegerStorage for Method {
    fn code(&self) -> i32 {
        match self {
            Method::Classical => 0,
            Method::Predictive => 1,
        }
    }
    fn set_code(&mut self, code: i32) -> Result<(), String> {
        *self = match code {
            0 => Method::Classical,
            1 => Method::Predictive,
            _ => return Err(format!("{code} is neither 0 (classical washout) nor 1 (predictive cueing)")),
        };
        Ok(())
    }
}

/// The QP's iteration budget as the Integer `mpc.maxIterations`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct IterationBudget(pub u32);

impl IntegerStorage for IterationBudget {
    fn code(&self) -> i32 {
        i32::try_from(self.0).unwrap_or(i32::MAX)
    }
    fn set_code(&mut self, code: i32) -> Result<(), String> {
        match u32::try_from(code) {
            Ok(n) if (1..=1000).contains(&n) => {
                self.0 = n;
                Ok(())
            }
            _ => Err(format!("{code} is not an iteration budget in 1..1000")),
        }
    }
}

/// The parameters of the cueing FMU.
#[derive(Clone, Debug, PartialEq)]
pub struct CueingParameters {
    pub method: Method,
    pub washout: WashoutParameters,
    pub predictive: PredictiveParameters,
    /// `mpc.maxIterations`.
    pub iterations: IterationBudget,
    /// `preview.file`: a CSV of the vehicle's future (`time, f[1..3], omega[1..3]`), or empty.
    pub preview_file: String,
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
            method: Method::Classical,
            washout: DEFAULT_WASHOUT,
            predictive: DEFAULT_PREDICTIVE,
            iterations: IterationBudget(DEFAULT_PREDICTIVE.max_iterations),
            preview_file: String::new(),
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
    /// The legs' margins and the workspace limiter's onset (the classical washout's; the
    /// predictive method's command only meets the limiter's net, `Workspace::net`).
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

    /// The predictive method's parameters as the FMU holds them (the tilt rate limit and the
    /// iteration budget live in their own variables).
    pub fn predictive(&self) -> PredictiveParameters {
        PredictiveParameters {
            tilt_rate_limit: self.washout.tilt_rate_limit,
            tilt_max: self.washout.tilt_max,
            max_iterations: self.iterations.0,
            ..self.predictive
        }
    }

    pub fn predictive_stand(&self) -> PredictiveStand {
        PredictiveStand { workspace: self.workspace(), head: Vector3::from(self.head), gravity: self.washout.gravity }
    }

    pub fn validate(&self) -> Result<(), String> {
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
        if self.method == Method::Predictive {
            self.predictive().validate()?;
        }
        self.workspace().validate()
    }
}
