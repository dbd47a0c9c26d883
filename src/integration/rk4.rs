//! Classical fixed-step Runge-Kutta 4. Each interval is split into the fewest equal steps not
//! longer than `SolverSettings::fixed_step`, so the cost per interval is known in advance
//! (real-time use) and the last step ends exactly on the interval's end.
//!
//! Switching functions are evaluated at every step's end; a sign change is placed at the
//! linearly interpolated time and state. A non-smooth point inside a step is stepped across:
//! that step's local error is of first order in the step (the method's order assumes a smooth
//! right-hand side), which the end-stop tests measure.

use super::{Crossing, IntegrationError, MAX_SWITCHING, MethodCall, OdeSystem, SwitchingKind, bits, in_memory};

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
    for i in 0..n {
        let t = t0 + i as f64 * h;
        let t_end = if i + 1 == n { t1 } else { t0 + (i + 1) as f64 * h };
        let t_mid = t + 0.5 * h;
        if switching > 0 {
            y_start = *y;
        }
        // Stages by value (`derivative_of`, `from_fn`): written once, never zeroed first.
        let k1 = system.derivative_of(t, y);
        let mut stage: [f64; N] = std::array::from_fn(|j| y[j] + 0.5 * h * k1[j]);
        in_memory(&mut stage);
        let k2 = system.derivative_of(t_mid, &stage);
        let mut stage: [f64; N] = std::array::from_fn(|j| y[j] + 0.5 * h * k2[j]);
        in_memory(&mut stage);
        let k3 = system.derivative_of(t_mid, &stage);
        let mut stage: [f64; N] = std::array::from_fn(|j| y[j] + h * k3[j]);
        in_memory(&mut stage);
        let k4 = system.derivative_of(t_end, &stage);
        for j in 0..N {
            y[j] += h / 6.0 * (k1[j] + 2.0 * (k2[j] + k3[j]) + k4[j]);
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

#[cfg(test)]
mod tests {
    use crate::integration::{Integrator, Method, OdeSystem, SolverSettings};

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
