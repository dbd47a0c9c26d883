//! Time integration of first-order systems `dy/dt = f(t, y)` of fixed size, with a hook after
//! every internal step (constraint projection) and an admissibility check that can stop the
//! integration. Nothing here knows about Stewart platforms or FMI.
//!
//! | module | what it holds |
//! |---|---|
//! | [`settings`] | method choice, tolerances, step limits |
//! | [`dopri5`] | adaptive Dormand-Prince 5(4) with PI step-size control |
//! | [`rk4`] | classical fixed-step Runge-Kutta 4 |
//!
//! Every call to [`Integrator::integrate`] ends exactly on the requested time, whatever the
//! ratio of the interval to the internal step: co-simulation masters rely on that.

pub mod dopri5;
pub mod rk4;
pub mod settings;

pub use settings::{Method, SolverSettings};

/// A system of `N` first-order ODEs.
pub trait OdeSystem<const N: usize> {
    /// Why a state is not admissible (see [`OdeSystem::check`]).
    type Fault: Copy + std::fmt::Debug;

    /// `dy = f(t, y)`.
    fn derivative(&self, t: f64, y: &[f64; N], dy: &mut [f64; N]);

    /// Called on every accepted step's end state; may move it (e.g. back onto constraints).
    fn after_step(&self, _y: &mut [f64; N]) {}

    /// Whether [`OdeSystem::after_step`] can change the state. If not, the adaptive method
    /// reuses its last stage as the next step's first (FSAL).
    fn modifies_state_after_step(&self) -> bool {
        false
    }

    /// Admissibility of an accepted step's end state; an error stops the integration there.
    fn check(&self, _t: f64, _y: &[f64; N]) -> Result<(), Self::Fault> {
        Ok(())
    }
}

/// Why an integration stopped before the requested time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum IntegrationError<F> {
    /// The system reported an inadmissible state at time `t`.
    Fault { t: f64, fault: F },
    /// The adaptive step size fell below what the time's precision can resolve.
    StepSizeUnderflow { t: f64, h: f64 },
    /// More internal steps than `SolverSettings::max_steps_per_call` were needed.
    TooManySteps { t: f64, steps: u64 },
}

impl<F: std::fmt::Display> std::fmt::Display for IntegrationError<F> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            IntegrationError::Fault { t, fault } => write!(f, "at t = {t}: {fault}"),
            IntegrationError::StepSizeUnderflow { t, h } => write!(
                f,
                "at t = {t}: the adaptive step size fell to {h:e} without meeting the tolerance (the solution is \
                 not smooth or diverges)"
            ),
            IntegrationError::TooManySteps { t, steps } => {
                write!(f, "at t = {t}: {steps} internal steps were not enough to finish the step")
            }
        }
    }
}

/// Counters of the work done, for benchmarks and diagnostics.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct IntegratorStats {
    pub accepted_steps: u64,
    pub rejected_steps: u64,
    pub rhs_evaluations: u64,
}

/// An integrator with its memory between calls (the adaptive method's proposed next step).
/// `Copy`, so that a caller can keep the value from before a step and roll back to it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Integrator {
    pub settings: SolverSettings,
    pub dopri5: dopri5::Dopri5Memory,
    pub stats: IntegratorStats,
}

impl Integrator {
    pub fn new(settings: SolverSettings) -> Self {
        Integrator { settings, dopri5: dopri5::Dopri5Memory::default(), stats: IntegratorStats::default() }
    }

    /// Advances `y` from `t0` to exactly `t1` (> `t0`).
    pub fn integrate<S: OdeSystem<N>, const N: usize>(
        &mut self,
        system: &S,
        t0: f64,
        y: &mut [f64; N],
        t1: f64,
    ) -> Result<(), IntegrationError<S::Fault>> {
        match self.settings.method {
            Method::DormandPrince45 => {
                dopri5::integrate(system, &self.settings, &mut self.dopri5, &mut self.stats, t0, y, t1)
            }
            Method::RungeKutta4 => rk4::integrate(system, &self.settings, &mut self.stats, t0, y, t1),
        }
    }
}
