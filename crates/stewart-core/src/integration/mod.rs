//! Time integration of first-order systems `dy/dt = f(t, y)` of fixed size, with a hook after
//! every internal step (constraint projection) and an admissibility check that can stop the
//! integration. Nothing here knows about Stewart platforms or FMI.
//!
//! | module | what it holds |
//! |---|---|
//! | [`settings`] | method choice, tolerances, step limits |
//! | [`dopri5`] | adaptive Dormand-Prince 5(4) with PI step-size control |
//! | [`rk4`] | classical fixed-step Runge-Kutta 4 (exponential for a system's [`LinearDecay`]) |
//!
//! Every call to [`Integrator::integrate`] ends exactly on the requested time, whatever the
//! ratio of the interval to the internal step: co-simulation masters rely on that.
//!
//! A system may declare *switching functions* `g_i(t, y)` whose sign changes matter: non-smooth
//! points of its right-hand side (contact onsets and releases), instants to report, or states
//! where the integration must stop. The adaptive method locates every sign change on its
//! dense output; at a non-smooth point it does not step across but lands on it and restarts
//! there, so that its accuracy through the point is that of its tolerance. The fixed-step
//! method steps across and reports the crossing at the linearly interpolated time (its local
//! error at such a step is first order in the step instead of fifth).

pub mod dopri5;
pub mod rk4;
pub mod settings;

pub use settings::{Method, SolverSettings};

/// Most switching functions a system may declare.
pub const MAX_SWITCHING: usize = 32;

/// What a sign change of a switching function means to the integrator.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SwitchingKind {
    /// A non-smooth point of the right-hand side: located, landed on, restarted from.
    Restart,
    /// An instant to report; the solution is smooth through it: located and recorded.
    Report,
    /// The integration must stop there: located, and [`OdeSystem::switching_fault`] of the
    /// state there is returned as the error.
    Stop,
}

/// A located sign change of switching function `index`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Crossing<const N: usize> {
    pub index: usize,
    /// Time of the sign change.
    pub t: f64,
    /// Sign after the crossing: `true` = positive.
    pub rising: bool,
    /// The state at `t` (from the method's interpolant).
    pub y: [f64; N],
}

/// Capacity of a [`CrossingLog`]; further crossings in one call are counted, not kept.
pub const CROSSING_LOG_CAPACITY: usize = 32;

/// The crossings of one [`Integrator::integrate`] call, in time order. Fixed size: no
/// allocation in the integration.
#[derive(Clone, Debug)]
pub struct CrossingLog<const N: usize> {
    entries: [Crossing<N>; CROSSING_LOG_CAPACITY],
    len: usize,
    /// Crossings that did not fit.
    pub dropped: u64,
}

impl<const N: usize> Default for CrossingLog<N> {
    fn default() -> Self {
        CrossingLog {
            entries: [Crossing { index: 0, t: 0.0, rising: false, y: [0.0; N] }; CROSSING_LOG_CAPACITY],
            len: 0,
            dropped: 0,
        }
    }
}

impl<const N: usize> CrossingLog<N> {
    pub fn clear(&mut self) {
        self.len = 0;
        self.dropped = 0;
    }

    pub fn push(&mut self, c: Crossing<N>) {
        match self.entries.get_mut(self.len) {
            Some(slot) => {
                *slot = c;
                self.len += 1;
            }
            None => self.dropped += 1,
        }
    }

    pub fn as_slice(&self) -> &[Crossing<N>] {
        self.entries.get(..self.len).unwrap_or(&[])
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0 && self.dropped == 0
    }
}

/// Which side of zero each switching function is on (bit `i` set: `g_i > 0`), carried from
/// call to call.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SwitchingSides {
    pub bits: u32,
    /// False until the first call has evaluated the functions at its start.
    pub known: bool,
}

impl SwitchingSides {
    /// The sides of the values `g[..count]`.
    #[inline]
    pub fn of(g: &[f64; MAX_SWITCHING], count: usize) -> Self {
        // Every value compared (no early exit, no branch: vector compares and a mask), the
        // functions past `count` masked off afterwards.
        let bits = g.iter().enumerate().fold(0u32, |bits, (i, x)| bits | (u32::from(*x > 0.0) << i));
        SwitchingSides { bits: bits & 1u32.checked_shl(count as u32).map_or(u32::MAX, |b| b - 1), known: true }
    }

    /// Bits of the functions whose side differs from `g`.
    #[inline]
    pub fn changed(&self, g: &[f64; MAX_SWITCHING], count: usize) -> u32 {
        // Functions past `count` are not evaluated: whatever side they had, they did not change.
        (Self::of(g, count).bits ^ self.bits) & 1u32.checked_shl(count as u32).map_or(u32::MAX, |b| b - 1)
    }
}

/// The array of `f(0), .., f(N - 1)`: a method's stage, in a loop inlined in the caller's
/// registers whatever `N` (`std::array::from_fn` is not inlined for every length).
#[inline(always)]
pub(crate) fn each<const N: usize>(f: impl Fn(usize) -> f64) -> [f64; N] {
    let mut out = [0.0; N];
    for (j, o) in out.iter_mut().enumerate() {
        *o = f(j);
    }
    out
}

/// A block of components whose rates are linear in themselves with one constant rate:
/// `y_i' = -rate y_i + n_i(t, y)` for `i` in `start..start + len`, with `n_i` not stiff. A fast
/// electric circuit is such a block (`rate = R / L`). The fixed-step method integrates the
/// linear part exactly (exponential time differencing, Krogstad's ETDRK4), so that its
/// step is not bound by `1 / rate`; the adaptive method treats the block like any other
/// component (its error control chooses steps that resolve or damp it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinearDecay {
    pub start: usize,
    pub len: usize,
    /// 1/s, >= 0.
    pub rate: f64,
}

/// A system of `N` first-order ODEs.
pub trait OdeSystem<const N: usize> {
    /// Why a state is not admissible (see [`OdeSystem::check`]).
    type Fault: Copy + std::fmt::Debug;

    /// `dy = f(t, y)`.
    fn derivative(&self, t: f64, y: &[f64; N], dy: &mut [f64; N]);

    /// `f(t, y)` returned by value, for a method's stages (an array declared for the whole
    /// call would be zeroed on every call).
    #[inline(always)]
    fn derivative_of(&self, t: f64, y: &[f64; N]) -> [f64; N] {
        let mut dy = [0.0; N];
        self.derivative(t, y, &mut dy);
        dy
    }

    /// Called on every accepted step's end state; may move it (e.g. back onto constraints).
    fn after_step(&self, _y: &mut [f64; N]) {}

    /// How many leading components the adaptive method's error norm averages over: a system
    /// of fixed size whose trailing components stay constant (a part that is switched off)
    /// steps as the smaller system would, to the bit.
    fn active_dimension(&self) -> usize {
        N
    }

    /// The block of components the fixed-step method integrates exponentially, if any.
    fn linear_decay(&self) -> Option<LinearDecay> {
        None
    }

    /// The longest step the fixed-step method is stable for at `(t, y)` (`inf`: no bound). A
    /// longer step is cut into equal sub-steps within it: the cost per interval is then bounded
    /// by the system's largest rate, known from its parameters.
    #[inline(always)]
    fn stable_step(&self, _t: f64, _y: &[f64; N]) -> f64 {
        f64::INFINITY
    }

    /// Whether [`OdeSystem::after_step`] can change the state. If not, the adaptive method
    /// reuses its last stage as the next step's first (FSAL).
    fn modifies_state_after_step(&self) -> bool {
        false
    }

    /// Admissibility of an accepted step's end state; an error stops the integration there.
    fn check(&self, _t: f64, _y: &[f64; N]) -> Result<(), Self::Fault> {
        Ok(())
    }

    /// [`OdeSystem::check`] of an accepted step's end state and, with `g`, its
    /// [`OdeSystem::switching`] values: one call, for systems that compute both from the same
    /// quantities.
    fn check_and_switching(
        &self,
        t: f64,
        y: &[f64; N],
        g: Option<&mut [f64; MAX_SWITCHING]>,
    ) -> Result<(), Self::Fault> {
        self.check(t, y)?;
        if let Some(g) = g {
            self.switching(t, y, g);
        }
        Ok(())
    }

    /// Number of switching functions (at most [`MAX_SWITCHING`]; 0 = none, no cost).
    fn switching_count(&self) -> usize {
        0
    }

    /// Values of the switching functions at `(t, y)` in `g[..switching_count()]`.
    fn switching(&self, _t: f64, _y: &[f64; N], _g: &mut [f64; MAX_SWITCHING]) {}

    /// What a sign change of function `index` means.
    fn switching_kind(&self, _index: usize) -> SwitchingKind {
        SwitchingKind::Report
    }

    /// The fault to stop with at a crossing of a [`SwitchingKind::Stop`] function (`None`:
    /// only report it).
    fn switching_fault(&self, _index: usize, _t: f64, _y: &[f64; N]) -> Option<Self::Fault> {
        None
    }
}

/// Sides of the switching functions of `system` at `(t, y)`.
pub fn switching_sides<S: OdeSystem<N>, const N: usize>(system: &S, t: f64, y: &[f64; N]) -> SwitchingSides {
    let n = system.switching_count().min(MAX_SWITCHING);
    let mut g = [0.0; MAX_SWITCHING];
    system.switching(t, y, &mut g);
    SwitchingSides::of(&g, n)
}

/// Why an integration stopped before the requested time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum IntegrationError<F> {
    /// The system reported an inadmissible state at time `t`.
    Fault { t: f64, fault: F },
    /// The adaptive step size fell below what the time's precision can resolve.
    StepSizeUnderflow { t: f64, h: f64 },
    /// The adaptive method took `SolverSettings::max_steps_per_call` steps and stopped at
    /// `t`, short of `t_end`.
    TooManySteps { t: f64, t_end: f64, steps: u64 },
    /// The fixed-step method would need `steps` steps of at most `fixed_step` for the
    /// interval from `t` to `t_end`, more than `limit`; nothing was computed.
    FixedStepsExceedLimit { t: f64, t_end: f64, fixed_step: f64, steps: f64, limit: u64 },
}

impl<F> IntegrationError<F> {
    /// Whether the same integration split into shorter intervals can succeed (the limit of
    /// internal steps per call was the only obstacle).
    pub fn is_step_limit(&self) -> bool {
        matches!(self, IntegrationError::TooManySteps { .. } | IntegrationError::FixedStepsExceedLimit { .. })
    }
}

impl<F: std::fmt::Display> std::fmt::Display for IntegrationError<F> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            IntegrationError::Fault { t, fault } => write!(f, "at t = {t:?}: {fault}"),
            IntegrationError::StepSizeUnderflow { t, h } => write!(
                f,
                "at t = {t:?}: the adaptive step size fell to {h:e} without meeting the tolerance (the solution is \
                 not smooth or diverges)"
            ),
            IntegrationError::TooManySteps { t, t_end, steps } => write!(
                f,
                "the adaptive integrator took {steps} internal steps, the limit per call, and reached t = {t:?}, short \
                 of t = {t_end:?} (the motion needs very small steps there)"
            ),
            IntegrationError::FixedStepsExceedLimit { t, t_end, fixed_step, steps, limit } => write!(
                f,
                "from t = {t:?} to {t_end:?} RK4 with solver.fixedStep = {fixed_step:e} s needs {steps:.3e} steps, more \
                 than the limit of {limit} internal steps per call; nothing was computed"
            ),
        }
    }
}

/// Counters of the work done, for benchmarks and diagnostics.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct IntegratorStats {
    pub accepted_steps: u64,
    pub rejected_steps: u64,
    pub rhs_evaluations: u64,
    /// Steps redone to end on a non-smooth point (adaptive method).
    pub event_landings: u64,
}

/// An integrator with its memory between calls (the adaptive method's proposed next step).
/// `Copy`, so that a caller can keep the value from before a step and roll back to it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Integrator {
    pub settings: SolverSettings,
    pub dopri5: dopri5::Dopri5Memory,
    pub stats: IntegratorStats,
    /// Sides of the system's switching functions at the current time.
    pub sides: SwitchingSides,
}

impl Integrator {
    pub fn new(settings: SolverSettings) -> Self {
        Integrator {
            settings,
            dopri5: dopri5::Dopri5Memory::default(),
            stats: IntegratorStats::default(),
            sides: SwitchingSides::default(),
        }
    }

    /// Advances `y` from `t0` to exactly `t1` (> `t0`), appending the sign changes of the
    /// system's switching functions to `crossings`.
    pub fn integrate<S: OdeSystem<N>, const N: usize>(
        &mut self,
        system: &S,
        t0: f64,
        y: &mut [f64; N],
        t1: f64,
        crossings: &mut CrossingLog<N>,
    ) -> Result<(), IntegrationError<S::Fault>> {
        self.integrate_until_event(system, t0, y, t1, crossings, false).map(|_| ())
    }

    /// As [`Integrator::integrate`]; with `stop_at_restart`, returns early at the first
    /// non-smooth point (a [`SwitchingKind::Restart`] crossing: the adaptive method has landed
    /// on it, the fixed-step method stops at the end of the step that crossed it). Returns
    /// the time reached. Inlined, so that a caller compiled for wider registers (the
    /// platform's AVX2 path, `simulation::vector`) compiles the methods and its system with
    /// them.
    #[inline(always)]
    pub fn integrate_until_event<S: OdeSystem<N>, const N: usize>(
        &mut self,
        system: &S,
        t0: f64,
        y: &mut [f64; N],
        t1: f64,
        crossings: &mut CrossingLog<N>,
        stop_at_restart: bool,
    ) -> Result<f64, IntegrationError<S::Fault>> {
        if system.switching_count() > 0 && !self.sides.known {
            self.sides = switching_sides(system, t0, y);
        }
        let mut events = Events { sides: &mut self.sides, log: crossings, stop_at_restart };
        let call = MethodCall {
            settings: &self.settings,
            memory: &mut self.dopri5,
            stats: &mut self.stats,
            events: &mut events,
        };
        run(system, call, t0, y, t1)
    }
}

/// A plain ODE `y' = f(t, y)` of fixed size, from its rate: an [`OdeSystem`] without checks,
/// switching functions or faults, so that the methods serve any state array (the washout's
/// filters, a test's oscillator) without a platform around it.
#[derive(Clone, Copy, Debug)]
pub struct Ode<F>(pub F);

impl<F: Fn(f64, &[f64; N]) -> [f64; N], const N: usize> OdeSystem<N> for Ode<F> {
    type Fault = std::convert::Infallible;

    #[inline(always)]
    fn derivative(&self, t: f64, y: &[f64; N], dy: &mut [f64; N]) {
        *dy = (self.0)(t, y);
    }

    #[inline(always)]
    fn derivative_of(&self, t: f64, y: &[f64; N]) -> [f64; N] {
        (self.0)(t, y)
    }
}

/// Classical RK4 on the plain ODE `rate` from `t0` to exactly `t1`, in the fewest equal steps
/// not longer than `max_step` ([`Method::RungeKutta4`]'s rule: an interval within 1e-9 of a
/// multiple of `max_step` takes that multiple): the integrators' own method, for a state array
/// and a rate closure. Never fails: a plain ODE has no checks (the step count is bounded by
/// [`SolverSettings::max_steps_per_call`]; beyond it `y` is left as it was).
pub fn rk4_fixed_steps<F: Fn(f64, &[f64; N]) -> [f64; N], const N: usize>(
    rate: F,
    t0: f64,
    y: &mut [f64; N],
    t1: f64,
    max_step: f64,
) {
    let settings = SolverSettings { method: Method::RungeKutta4, fixed_step: max_step, ..SolverSettings::default() };
    let _ = Integrator::new(settings).integrate(&Ode(rate), t0, y, t1, &mut CrossingLog::default());
}

/// What a method works with during one call, besides the system and the interval.
pub(crate) struct MethodCall<'a, 'e, const N: usize> {
    pub settings: &'a SolverSettings,
    /// The adaptive method's memory between calls (its next step size).
    pub memory: &'a mut dopri5::Dopri5Memory,
    pub stats: &'a mut IntegratorStats,
    pub events: &'a mut Events<'e, N>,
}

/// The chosen method over one call.
#[inline(always)]
fn run<S: OdeSystem<N>, const N: usize>(
    system: &S,
    call: MethodCall<'_, '_, N>,
    t0: f64,
    y: &mut [f64; N],
    t1: f64,
) -> Result<f64, IntegrationError<S::Fault>> {
    match call.settings.method {
        Method::DormandPrince45 => dopri5::integrate(system, call, t0, y, t1),
        Method::RungeKutta4 => rk4::integrate(system, call, t0, y, t1),
    }
}

/// Keeps a method's stage in memory before the right-hand side reads it: otherwise the
/// compiler folds the stage's combination into the right-hand side's loads and rebuilds the
/// vectors it needs with shuffles, which costs more than the store (`benches/results/`).
/// Changes no number.
#[inline(always)]
pub(crate) fn in_memory<T>(stage: &mut T) {
    std::hint::black_box(stage);
}

/// The switching bookkeeping a method updates during one call.
pub(crate) struct Events<'a, const N: usize> {
    pub sides: &'a mut SwitchingSides,
    pub log: &'a mut CrossingLog<N>,
    /// End the call at the first [`SwitchingKind::Restart`] crossing.
    pub stop_at_restart: bool,
}

impl<const N: usize> Events<'_, N> {
    /// Whether the crossings logged from `first` on include a non-smooth point that ends the
    /// call.
    pub fn stops_after<S: OdeSystem<N>>(&self, system: &S, first: usize) -> bool {
        self.stop_at_restart
            && self.log.as_slice().iter().skip(first).any(|c| system.switching_kind(c.index) == SwitchingKind::Restart)
    }
}

/// Iterates over the set bits of `mask`, lowest first.
pub(crate) fn bits(mask: u32) -> impl Iterator<Item = usize> {
    // Lowest set bit first, each step clearing it: nothing to do for an empty mask (every
    // step without a crossing).
    let mut rest = mask;
    std::iter::from_fn(move || {
        (rest != 0).then(|| {
            let i = rest.trailing_zeros() as usize;
            rest &= rest - 1;
            i
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bits_lists_the_set_bits_lowest_first() {
        assert_eq!(bits(0).count(), 0);
        assert_eq!(bits(0b1011).collect::<Vec<_>>(), [0, 1, 3]);
        assert_eq!(bits(1 << 31 | 1 << 4).collect::<Vec<_>>(), [4, 31]);
        assert_eq!(bits(u32::MAX).collect::<Vec<_>>(), (0..32).collect::<Vec<_>>());
    }

    /// A ball dropped from height `H` onto a stiff linear spring floor (`y'' = -g` above the
    /// floor, `y'' = -g - k y` in it): the right-hand side has a kink at `y = 0`, and the
    /// motion is known in closed form.
    struct Ball {
        stiffness: f64,
        events: bool,
    }

    const GRAVITY: f64 = 9.81;

    impl OdeSystem<2> for Ball {
        type Fault = ();
        fn derivative(&self, _t: f64, y: &[f64; 2], dy: &mut [f64; 2]) {
            dy[0] = y[1];
            dy[1] = -GRAVITY - if y[0] < 0.0 { self.stiffness * y[0] } else { 0.0 };
        }
        fn switching_count(&self) -> usize {
            if self.events { 1 } else { 0 }
        }
        fn switching(&self, _t: f64, y: &[f64; 2], g: &mut [f64; MAX_SWITCHING]) {
            g[0] = y[0];
        }
        fn switching_kind(&self, _index: usize) -> SwitchingKind {
            SwitchingKind::Restart
        }
    }

    /// Time of the first contact and of the first lift-off.
    fn exact_bounce(height: f64, k: f64) -> (f64, f64) {
        let t_fall = (2.0 * height / GRAVITY).sqrt();
        // In contact, from t_fall: y = (g/k)(cos x - 1) - (v0/w) sin x with x = w (t - t_fall);
        // y = 0 again where tan(x/2) = -v0 w / g, i.e. x = 2 pi - 2 atan(v0 w / g).
        let w = k.sqrt();
        let v0 = GRAVITY * t_fall;
        let x = 2.0 * std::f64::consts::PI - 2.0 * (v0 * w / GRAVITY).atan();
        (t_fall, t_fall + x / w)
    }

    fn simulate(method: Method, events: bool, rel_tol: f64) -> (f64, Vec<Crossing<2>>) {
        let k = 1e4;
        let ball = Ball { stiffness: k, events };
        let mut integ = Integrator::new(SolverSettings {
            method,
            rel_tol,
            abs_tol: rel_tol * 1e-2,
            fixed_step: 1e-3,
            ..Default::default()
        });
        let mut y = [1.0, 0.0];
        let mut log = CrossingLog::default();
        let mut all = vec![];
        // 10 ms communication steps up to just after the lift-off; report the height error
        // against the closed form at the end (the ball flies freely again by then).
        let (_, t_off) = exact_bounce(1.0, k);
        let t_end = t_off + 0.1;
        let mut t = 0.0;
        while t < t_end {
            let t_next = (t + 0.01f64).min(t_end);
            log.clear();
            integ.integrate(&ball, t, &mut y, t_next, &mut log).unwrap();
            all.extend_from_slice(log.as_slice());
            t = t_next;
        }
        let v_off = (2.0 * GRAVITY * 1.0f64).sqrt(); // elastic: leaves as fast as it came
        let dt = t_end - t_off;
        let exact = v_off * dt - 0.5 * GRAVITY * dt * dt;
        ((y[0] - exact).abs(), all)
    }

    #[test]
    fn adaptive_method_lands_on_kinks_and_keeps_its_accuracy_through_them() {
        let (t_on, t_off) = exact_bounce(1.0, 1e4);
        let (err_events, crossings) = simulate(Method::DormandPrince45, true, 1e-10);
        let (err_plain, _) = simulate(Method::DormandPrince45, false, 1e-10);
        println!("bouncing ball, relTol 1e-10: height error {err_events:e} with event location, {err_plain:e} without");
        assert_eq!(crossings.len(), 2, "{crossings:?}");
        assert!((crossings[0].t - t_on).abs() < 1e-9, "{} vs {t_on}", crossings[0].t);
        assert!((crossings[1].t - t_off).abs() < 1e-9, "{} vs {t_off}", crossings[1].t);
        assert!(!crossings[0].rising && crossings[1].rising);
        assert!(err_events < 1e-8, "{err_events}");
        assert!(err_plain > 10.0 * err_events, "{err_plain} vs {err_events}");
    }

    #[test]
    fn fixed_step_method_reports_crossings_by_interpolation() {
        let (t_on, _) = exact_bounce(1.0, 1e4);
        let (err, crossings) = simulate(Method::RungeKutta4, true, 1e-8);
        println!("bouncing ball, RK4 1 ms: height error {err:e}, first contact {:e} s off", crossings[0].t - t_on);
        assert_eq!(crossings.len(), 2);
        assert!((crossings[0].t - t_on).abs() < 1e-3);
    }
}
