//! Solver settings. The FMU exposes each as a parameter (`solver.*`, see the variable table).

/// Integration method.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// Adaptive Dormand-Prince 5(4) with error control: the default, for accuracy.
    DormandPrince45,
    /// Classical Runge-Kutta 4 with a fixed internal step: for real time (a fixed cost per
    /// communication step).
    RungeKutta4,
}

impl Method {
    /// The FMI enumeration value (`solver.method`).
    pub fn code(self) -> i32 {
        match self {
            Method::DormandPrince45 => 1,
            Method::RungeKutta4 => 2,
        }
    }

    pub fn from_code(code: i32) -> Option<Self> {
        match code {
            1 => Some(Method::DormandPrince45),
            2 => Some(Method::RungeKutta4),
            _ => None,
        }
    }
}

/// How an integration is carried out.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolverSettings {
    pub method: Method,
    /// Relative tolerance of the adaptive method's local error estimate.
    pub rel_tol: f64,
    /// Absolute tolerance of the adaptive method's local error estimate, in the units of
    /// each state component.
    pub abs_tol: f64,
    /// Largest step of the adaptive method (time units); 0 = no limit beyond the interval.
    pub max_step: f64,
    /// RK4's internal step bound (time units): each interval is split into the fewest equal
    /// steps not longer than this. 0 = one step per interval.
    pub fixed_step: f64,
    /// Upper bound on internal steps in one call; guards against a stalled integration.
    pub max_steps_per_call: u64,
    /// Whether the adaptive method lands on the non-smooth points of the right-hand side
    /// (sign changes of [`crate::integration::SwitchingKind::Restart`] functions) instead of
    /// stepping across them. Always on in the FMU; off only to measure what it buys.
    pub locate_events: bool,
}

/// Default relative tolerance: 1e-8, about the accuracy a co-simulation needs and well below
/// the error a 1 ms zero-order hold of the forces causes.
pub const DEFAULT_REL_TOL: f64 = 1e-8;
/// Default absolute tolerance: 1e-10 (m, m/s, or the unit vectors' components).
pub const DEFAULT_ABS_TOL: f64 = 1e-10;
/// Default largest adaptive step: no limit; the error control chooses.
pub const DEFAULT_MAX_STEP: f64 = 0.0;
/// Default RK4 step: 1 ms, so that RK4 takes one step per 1 ms communication step (a
/// hardware-in-the-loop rate), far inside its stability region for the stand's
/// `sqrt(R_b/g) = 0.39 s` time scale.
pub const DEFAULT_FIXED_STEP: f64 = 1e-3;
/// Default limit of internal steps per call.
pub const DEFAULT_MAX_STEPS_PER_CALL: u64 = 1_000_000;

impl Default for SolverSettings {
    fn default() -> Self {
        SolverSettings {
            method: Method::DormandPrince45,
            rel_tol: DEFAULT_REL_TOL,
            abs_tol: DEFAULT_ABS_TOL,
            max_step: DEFAULT_MAX_STEP,
            fixed_step: DEFAULT_FIXED_STEP,
            max_steps_per_call: DEFAULT_MAX_STEPS_PER_CALL,
            locate_events: true,
        }
    }
}

impl SolverSettings {
    /// Tight settings for reference solutions in tests.
    pub fn tight() -> Self {
        SolverSettings { rel_tol: 1e-13, abs_tol: 1e-15, max_step: 0.0, ..Default::default() }
    }
}
