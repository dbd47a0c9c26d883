//! Classical fixed-step Runge-Kutta 4. Each interval is split into the fewest equal steps not
//! longer than `SolverSettings::fixed_step`, so the cost per interval is known in advance
//! (real-time use) and the last step ends exactly on the interval's end.
//!
//! A system's [`LinearDecay`] block (a fast circuit) is integrated by exponential time
//! differencing (Krogstad's ETDRK4): its linear part exactly, the rest by the same four
//! stages. For the other components the method is the classical one, to the bit; with a decay
//! rate of zero, ETDRK4 is the classical method too.
//!
//! Switching functions are evaluated at every step's end; a sign change is placed at the
//! linearly interpolated time and state. A non-smooth point inside a step is stepped across:
//! that step's local error is of first order in the step (the method's order assumes a smooth
//! right-hand side), which the end-stop tests measure.

use super::{
    Crossing, IntegrationError, LinearDecay, MAX_SWITCHING, MethodCall, OdeSystem, SwitchingKind, bits, each, in_memory,
};

/// The coefficients of Krogstad's ETDRK4 (2005; the phi-function form of Hochbruck and
/// Ostermann) for one decay rate and step, `z = -rate h`: the propagators `e^(z/2)`, `e^z`,
/// the stages' weights and the output weights.
#[derive(Clone, Copy, Debug)]
struct Exponential {
    block: LinearDecay,
    half: f64,
    full: f64,
    /// `h/2 phi1(z/2)`: stage 2's weight of `n(y)`.
    a1: f64,
    /// `h/2 (phi1(z/2) - 2 phi2(z/2))` and `h phi2(z/2)`: stage 3's weights of `n(y)`, `n(a)`.
    b1: f64,
    b2: f64,
    /// `h (phi1 - 2 phi2)` and `2 h phi2`: stage 4's weights of `n(y)`, `n(b)`.
    c1: f64,
    c3: f64,
    /// Weights of the four stages' `n` in the output: `h (phi1 - 3 phi2 + 4 phi3)`,
    /// `h (2 phi2 - 4 phi3)` (stages 2 and 3 each), `h (4 phi3 - phi2)`.
    weights: [f64; 3],
}

/// `phi1(z) = (e^z - 1)/z`, `phi2 = (phi1 - 1)/z`, `phi3 = (phi2 - 1/2)/z` from `e^z - 1`: by
/// their Taylor series near 0, where the recurrences cancel, by the recurrences elsewhere.
fn phi123(z: f64, exp_m1: f64) -> [f64; 3] {
    if z.abs() < 0.5 {
        // Terms z^k / (k + j)!; 16 terms leave less than 0.5^16/16! of the first.
        let mut out = [0.0; 3];
        for (j, phi) in out.iter_mut().enumerate() {
            let mut term = 1.0 / [1.0, 2.0, 6.0][j];
            for k in 0..16 {
                *phi += term;
                term *= z / (k + j + 2) as f64;
            }
        }
        out
    } else {
        let phi1 = exp_m1 / z;
        let phi2 = (phi1 - 1.0) / z;
        [phi1, phi2, (phi2 - 0.5) / z]
    }
}

impl Exponential {
    // Inlined into the step of every system, in the crate that instantiates it.
    #[inline]
    fn new(block: LinearDecay, h: f64) -> Self {
        let z = -block.rate * h;
        // One exponential: e^z - 1 = (e^(z/2) - 1)(e^(z/2) + 1), without cancellation.
        let half_m1 = crate::maths::exp_m1(0.5 * z);
        let full_m1 = half_m1 * (half_m1 + 2.0);
        let [p1, p2, p3] = phi123(z, full_m1);
        let [q1, q2, _] = phi123(0.5 * z, half_m1);
        Exponential {
            block,
            half: half_m1 + 1.0,
            full: full_m1 + 1.0,
            a1: 0.5 * h * q1,
            b1: 0.5 * h * (q1 - 2.0 * q2),
            b2: h * q2,
            c1: h * (p1 - 2.0 * p2),
            c3: 2.0 * h * p2,
            weights: [h * (p1 - 3.0 * p2 + 4.0 * p3), h * (2.0 * p2 - 4.0 * p3), h * (4.0 * p3 - p2)],
        }
    }

    fn range<const N: usize>(&self) -> std::ops::Range<usize> {
        self.block.start.min(N)..(self.block.start + self.block.len).min(N)
    }
}

#[inline(always)]
pub(super) fn integrate<S: OdeSystem<N>, const N: usize>(
    system: &S,
    call: MethodCall<'_, '_, N>,
    t0: f64,
    y: &mut [f64; N],
    t1: f64,
) -> Result<f64, IntegrationError<S::Fault>> {
    // RK4 keeps nothing between calls.
    let MethodCall { settings: s, stats, events, .. } = call;
    let switching = system.switching_count().min(MAX_SWITCHING);
    let mut g_start = [0.0; MAX_SWITCHING];
    let mut g_end = [0.0; MAX_SWITCHING];
    let mut y_start = [0.0; N];
    let span = t1 - t0;
    // The 1e-9 slack keeps an interval that is a multiple of the step (up to round-off) at
    // that multiple.
    let steps = if s.fixed_step > 0.0 { ((span / s.fixed_step) * (1.0 - 1e-9)).ceil().max(1.0) } else { 1.0 };
    if steps > s.max_steps_per_call as f64 {
        return Err(IntegrationError::FixedStepsExceedLimit {
            t: t0,
            t_end: t1,
            fixed_step: s.fixed_step,
            steps,
            limit: s.max_steps_per_call,
        });
    }
    let n = steps as u64;
    let h = span / steps;
    let exponential = system.linear_decay().map(|block| Exponential::new(block, h));
    for i in 0..n {
        let t = t0 + i as f64 * h;
        let t_end = if i + 1 == n { t1 } else { t0 + (i + 1) as f64 * h };
        let t_mid = t + 0.5 * h;
        if switching > 0 {
            y_start = *y;
        }
        let stable = system.stable_step(t, y);
        match &exponential {
            None if h > stable => {
                std::hint::cold_path();
                stats.rhs_evaluations += 4 * sub_steps(system, t, t_end, h, stable, y) - 4;
            }
            None => classical_step(system, t, t_mid, t_end, h, y),
            Some(e) => exponential_step(system, e, t, t_mid, t_end, h, y),
        }
        stats.rhs_evaluations += 4;
        stats.accepted_steps += 1;
        system.after_step(y);
        system
            .check_and_switching(t_end, y, (switching > 0).then_some(&mut g_end))
            .map_err(|fault| IntegrationError::Fault { t: t_end, fault })?;
        let logged_before = events.log.as_slice().len();
        if switching > 0 {
            let changed = events.sides.changed(&g_end, switching);
            if changed != 0 {
                // Only now the start values are needed (rare: no cost in the hot path).
                system.switching(t, &y_start, &mut g_start);
            }
            for i in bits(changed) {
                let (g0, g1) = (g_start.get(i).copied().unwrap_or(0.0), g_end.get(i).copied().unwrap_or(0.0));
                // Linear interpolation between the step's ends.
                let theta = if (g0 > 0.0) != (g1 > 0.0) && g0 != g1 { (g0 / (g0 - g1)).clamp(0.0, 1.0) } else { 0.0 };
                let mut yc = [0.0; N];
                for j in 0..N {
                    yc[j] = y_start[j] + theta * (y[j] - y_start[j]);
                }
                let tc = t + theta * h;
                if system.switching_kind(i) == SwitchingKind::Stop
                    && let Some(fault) = system.switching_fault(i, tc, &yc)
                {
                    return Err(IntegrationError::Fault { t: tc, fault });
                }
                events.log.push(Crossing { index: i, t: tc, rising: g1 > 0.0, y: yc });
            }
            events.sides.bits ^= changed;
            if events.stops_after(system, logged_before) {
                return Ok(t_end);
            }
        }
    }
    Ok(t1)
}

/// A step of `h` from `t` cut into the fewest equal classical steps not longer than `stable`,
/// each followed by [`OdeSystem::after_step`] but the last (the caller's); returns how many.
/// Inlined like the rest of the integrator: a function of its own would be compiled without
/// the caller's target features (`simulation/vector.rs`' AVX2), and each of the right-hand
/// side's register operations in it would be a call (benches/results/hydraulics.txt §8).
#[inline(always)]
fn sub_steps<S: OdeSystem<N>, const N: usize>(
    system: &S,
    t: f64,
    t_end: f64,
    h: f64,
    stable: f64,
    y: &mut [f64; N],
) -> u64 {
    // Bounded: a NaN or zero bound takes the step whole (the check then refuses its end).
    let parts = if stable > 0.0 { (h / stable).ceil().min(MAX_SUB_STEPS) } else { 1.0 };
    let n = parts as u64;
    let sub = h / parts;
    for i in 0..n {
        let start = t + i as f64 * sub;
        let end = if i + 1 == n { t_end } else { t + (i + 1) as f64 * sub };
        classical_step(system, start, start + 0.5 * sub, end, sub, y);
        if i + 1 < n {
            system.after_step(y);
        }
    }
    n.max(1)
}

/// The most sub-steps one step is cut into (a state whose rate would need more is past the
/// model's validity; the steps then go unstable and the check stops them).
const MAX_SUB_STEPS: f64 = 1000.0;

/// One classical RK4 step.
#[inline(always)]
fn classical_step<S: OdeSystem<N>, const N: usize>(
    system: &S,
    t: f64,
    t_mid: f64,
    t_end: f64,
    h: f64,
    y: &mut [f64; N],
) {
    // Stages by value (`derivative_of`, `each`): plain loops, which stay inlined in the
    // caller's registers whatever `N` (`from_fn` did not for every length).
    let k1 = system.derivative_of(t, y);
    let mut stage: [f64; N] = each(|j| y[j] + 0.5 * h * k1[j]);
    in_memory(&mut stage);
    let k2 = system.derivative_of(t_mid, &stage);
    let mut stage: [f64; N] = each(|j| y[j] + 0.5 * h * k2[j]);
    in_memory(&mut stage);
    let k3 = system.derivative_of(t_mid, &stage);
    let mut stage: [f64; N] = each(|j| y[j] + h * k3[j]);
    in_memory(&mut stage);
    let k4 = system.derivative_of(t_end, &stage);
    for j in 0..N {
        y[j] += h / 6.0 * (k1[j] + 2.0 * (k2[j] + k3[j]) + k4[j]);
    }
}

/// One ETDRK4 step: the classical stages, with the decaying block's components replaced by
/// Krogstad's (`a = e^(z/2) y + a1 n(y)`, `b = e^(z/2) y + b1 n(y) + b2 n(a)`, `c = e^z y + c1
/// n(y) + c3 n(b)`, output `e^z y + weights . n`), which with `z = 0` are the classical ones.
#[inline(always)]
fn exponential_step<S: OdeSystem<N>, const N: usize>(
    system: &S,
    e: &Exponential,
    t: f64,
    t_mid: f64,
    t_end: f64,
    h: f64,
    y: &mut [f64; N],
) {
    let r = e.range::<N>();
    let rate = e.block.rate;
    // A stage's non-stiff rates `n = f + rate y` over the block (slices: no index checks).
    let nonstiff = |k: &[f64; N], at: &[f64; N], out: &mut [f64; N]| {
        for ((n, &k), &at) in out[r.clone()].iter_mut().zip(&k[r.clone()]).zip(&at[r.clone()]) {
            *n = k + rate * at;
        }
    };
    let (mut n1, mut n2, mut n3, mut n4) = ([0.0; N], [0.0; N], [0.0; N], [0.0; N]);
    let k1 = system.derivative_of(t, y);
    nonstiff(&k1, y, &mut n1);
    let mut a: [f64; N] = std::array::from_fn(|j| y[j] + 0.5 * h * k1[j]);
    for ((a, &y), &n1) in a[r.clone()].iter_mut().zip(&y[r.clone()]).zip(&n1[r.clone()]) {
        *a = e.half * y + e.a1 * n1;
    }
    let k2 = system.derivative_of(t_mid, &a);
    nonstiff(&k2, &a, &mut n2);
    let mut b: [f64; N] = std::array::from_fn(|j| y[j] + 0.5 * h * k2[j]);
    for (((b, &y), &n1), &n2) in b[r.clone()].iter_mut().zip(&y[r.clone()]).zip(&n1[r.clone()]).zip(&n2[r.clone()]) {
        *b = e.half * y + e.b1 * n1 + e.b2 * n2;
    }
    let k3 = system.derivative_of(t_mid, &b);
    nonstiff(&k3, &b, &mut n3);
    let mut c: [f64; N] = std::array::from_fn(|j| y[j] + h * k3[j]);
    for (((c, &y), &n1), &n3) in c[r.clone()].iter_mut().zip(&y[r.clone()]).zip(&n1[r.clone()]).zip(&n3[r.clone()]) {
        *c = e.full * y + e.c1 * n1 + e.c3 * n3;
    }
    let k4 = system.derivative_of(t_end, &c);
    nonstiff(&k4, &c, &mut n4);
    let [w1, w23, w4] = e.weights;
    // The block's output from the old `y` first (into `n1`, whose block it last reads), over
    // the block alone; then the classical one elsewhere.
    for ((((n1, &y0), &n2), &n3), &n4) in
        n1[r.clone()].iter_mut().zip(&y[r.clone()]).zip(&n2[r.clone()]).zip(&n3[r.clone()]).zip(&n4[r.clone()])
    {
        *n1 = e.full * y0 + w1 * *n1 + w23 * (n2 + n3) + w4 * n4;
    }
    for j in 0..N {
        y[j] += h / 6.0 * (k1[j] + 2.0 * (k2[j] + k3[j]) + k4[j]);
    }
    y[r.clone()].copy_from_slice(&n1[r]);
}

#[cfg(test)]
mod tests {
    use crate::integration::{Integrator, Method, OdeSystem, SolverSettings};

    /// A plain ODE from its rate (`Ode`, `rk4_fixed_steps`) steps as the classical RK4 written
    /// out by hand (as the washout FMU's steps were), to the bit, for an interval that is a
    /// whole number of steps.
    #[test]
    fn a_rate_closure_steps_as_the_classical_method_by_hand() {
        let rate = |t: f64, y: &[f64; 3]| [y[1], -4.0 * y[0] + 0.3 * t.sin(), -0.5 * y[2] + y[0] * y[1]];
        let (h, n) = (1e-2, 4);
        let mut by_hand = [0.2, -0.1, 1.0];
        let dt = h / n as f64;
        let shifted = |x: &[f64; 3], k: &[f64; 3], c: f64| std::array::from_fn(|i| x[i] + c * k[i]);
        for step in 0..n {
            let tau = step as f64 * dt;
            let k1 = rate(tau, &by_hand);
            let k2 = rate(tau + 0.5 * dt, &shifted(&by_hand, &k1, 0.5 * dt));
            let k3 = rate(tau + 0.5 * dt, &shifted(&by_hand, &k2, 0.5 * dt));
            let k4 = rate(if step + 1 == n { h } else { (step + 1) as f64 * dt }, &shifted(&by_hand, &k3, dt));
            for i in 0..3 {
                by_hand[i] += dt / 6.0 * (k1[i] + 2.0 * (k2[i] + k3[i]) + k4[i]);
            }
        }
        let mut y = [0.2, -0.1, 1.0];
        crate::integration::rk4_fixed_steps(rate, 0.0, &mut y, h, dt);
        assert_eq!(y.map(f64::to_bits), by_hand.map(f64::to_bits));
    }

    /// y' = -y, y(0) = 1: a known answer for both methods.
    struct Decay;
    impl OdeSystem<1> for Decay {
        type Fault = ();
        fn derivative(&self, _t: f64, y: &[f64; 1], dy: &mut [f64; 1]) {
            dy[0] = -y[0];
        }
    }

    /// Harmonic oscillator x'' = -x over two periods.
    struct Oscillator;
    impl OdeSystem<2> for Oscillator {
        type Fault = ();
        fn derivative(&self, _t: f64, y: &[f64; 2], dy: &mut [f64; 2]) {
            dy[0] = y[1];
            dy[1] = -y[0];
        }
    }

    /// A fast circuit driven by a slow oscillator: `x'' = -x + c i`, `i' = -rate i + (u(t) - x')`
    /// with `rate = 1e4`; the reference is the adaptive method at a tight tolerance.
    struct Circuit {
        rate: f64,
        exponential: bool,
    }
    impl OdeSystem<3> for Circuit {
        type Fault = ();
        fn derivative(&self, t: f64, y: &[f64; 3], dy: &mut [f64; 3]) {
            dy[0] = y[1];
            dy[1] = -y[0] + 50.0 * y[2];
            dy[2] = -self.rate * y[2] + (t.sin() - y[1]) * 100.0;
        }
        fn linear_decay(&self) -> Option<crate::integration::LinearDecay> {
            self.exponential.then_some(crate::integration::LinearDecay { start: 2, len: 1, rate: self.rate })
        }
    }

    fn circuit(method: Method, step: f64, exponential: bool) -> [f64; 3] {
        let settings =
            SolverSettings { method, fixed_step: step, rel_tol: 1e-12, abs_tol: 1e-14, ..Default::default() };
        let mut integ = Integrator::new(settings);
        let mut y = [0.1, 0.0, 0.0];
        for i in 0..100 {
            let (t0, t1) = (i as f64 * 0.02, (i + 1) as f64 * 0.02);
            integ.integrate(&Circuit { rate: 1e4, exponential }, t0, &mut y, t1, &mut Default::default()).unwrap();
        }
        y
    }

    /// The fixed-step method integrates a fast linear decay exponentially: stable and accurate
    /// at steps 10 to 40 times the decay's time constant, where the classical method diverges,
    /// and convergent (at this stiffness Krogstad's method shows its stiff order, about 2;
    /// Cox and Matthews' variant is 1000 times less accurate here).
    #[test]
    fn rk4_integrates_a_fast_decay_exponentially() {
        let reference = circuit(Method::DormandPrince45, 0.0, false);
        let errors: Vec<f64> = [4e-3, 2e-3, 1e-3]
            .iter()
            .map(|&h| {
                let y = circuit(Method::RungeKutta4, h, true);
                (0..3).map(|j| (y[j] - reference[j]).abs()).fold(0.0, f64::max)
            })
            .collect();
        let classical = circuit(Method::RungeKutta4, 1e-3, false);
        println!(
            "stiff circuit (rate 1e4 1/s), ETDRK4 errors at 4, 2, 1 ms: {errors:?}; classical RK4 at 1 ms: {classical:?}"
        );
        assert!(!classical.iter().all(|x| x.is_finite() && x.abs() < 1e3), "the classical method should diverge");
        assert!(errors[2] < 1e-7, "{errors:?}");
        assert!(errors[0] / errors[1] > 3.5 && errors[1] / errors[2] > 3.5, "order: {errors:?}");
    }

    #[test]
    fn rk4_is_fourth_order_and_lands_on_the_end_time() {
        let mut errors = vec![];
        for step in [0.1, 0.05] {
            let mut integ =
                Integrator::new(SolverSettings { method: Method::RungeKutta4, fixed_step: step, ..Default::default() });
            let mut y = [1.0];
            integ.integrate(&Decay, 0.0, &mut y, 1.0, &mut Default::default()).unwrap();
            errors.push((y[0] - (-1.0f64).exp()).abs());
        }
        let order = (errors[0] / errors[1]).log2();
        assert!((order - 4.0).abs() < 0.1, "observed order {order}");
    }

    #[test]
    fn dopri5_meets_tolerance_with_variable_intervals() {
        let settings = SolverSettings { rel_tol: 1e-10, abs_tol: 1e-12, ..Default::default() };
        let mut integ = Integrator::new(settings);
        let mut y = [1.0, 0.0];
        let mut t: f64 = 0.0;
        // Irregular communication intervals, including tiny ones, ending exactly on 4 pi.
        let end = 4.0 * std::f64::consts::PI;
        for h in [0.3, 1e-7, 1.7, 0.013, 2.0].iter().cycle() {
            let t_next: f64 = (t + h).min(end);
            integ.integrate(&Oscillator, t, &mut y, t_next, &mut Default::default()).unwrap();
            t = t_next;
            if t == end {
                break;
            }
        }
        let exact = [t.cos(), -t.sin()];
        let err = ((y[0] - exact[0]).powi(2) + (y[1] - exact[1]).powi(2)).sqrt();
        assert!(err < 1e-8, "error {err} at t = {t}");
    }
}
