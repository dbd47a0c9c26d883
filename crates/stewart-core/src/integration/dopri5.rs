//! Dormand-Prince 5(4) (Hairer, Nørsett, Wanner, Solving ODEs I, II.5), with the PI step-size
//! control of Hairer's DOPRI5 code. Propagates the 5th-order solution (local extrapolation).

use super::{
    Crossing, Events, IntegrationError, IntegratorStats, MAX_SWITCHING, MethodCall, OdeSystem, SolverSettings,
    SwitchingKind, bits, each,
};

const C2: f64 = 1.0 / 5.0;
const C3: f64 = 3.0 / 10.0;
const C4: f64 = 4.0 / 5.0;
const C5: f64 = 8.0 / 9.0;
const A21: f64 = 1.0 / 5.0;
const A31: f64 = 3.0 / 40.0;
const A32: f64 = 9.0 / 40.0;
const A41: f64 = 44.0 / 45.0;
const A42: f64 = -56.0 / 15.0;
const A43: f64 = 32.0 / 9.0;
const A51: f64 = 19372.0 / 6561.0;
const A52: f64 = -25360.0 / 2187.0;
const A53: f64 = 64448.0 / 6561.0;
const A54: f64 = -212.0 / 729.0;
const A61: f64 = 9017.0 / 3168.0;
const A62: f64 = -355.0 / 33.0;
const A63: f64 = 46732.0 / 5247.0;
const A64: f64 = 49.0 / 176.0;
const A65: f64 = -5103.0 / 18656.0;
const A71: f64 = 35.0 / 384.0;
const A73: f64 = 500.0 / 1113.0;
const A74: f64 = 125.0 / 192.0;
const A75: f64 = -2187.0 / 6784.0;
const A76: f64 = 11.0 / 84.0;
// Error estimate: 5th-order weights minus the embedded 4th-order ones.
const E1: f64 = 71.0 / 57600.0;
const E3: f64 = -71.0 / 16695.0;
const E4: f64 = 71.0 / 1920.0;
const E5: f64 = -17253.0 / 339200.0;
const E6: f64 = 22.0 / 525.0;
const E7: f64 = -1.0 / 40.0;

const SAFETY: f64 = 0.9;
/// Step may shrink at most by 1/5 and grow at most by 10 per step.
const FAC_SHRINK_LIMIT: f64 = 5.0;
const FAC_GROW_LIMIT: f64 = 0.1;
const BETA: f64 = 0.04;
const EXPO1: f64 = 0.2 - BETA * 0.75;

/// What the adaptive method carries from one call to the next.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dopri5Memory {
    /// Proposed next step; 0 = not yet known (an initial step is estimated).
    pub h_next: f64,
    /// Previous accepted error ratio for the PI controller.
    pub err_old: f64,
}

impl Default for Dopri5Memory {
    fn default() -> Self {
        Dopri5Memory { h_next: 0.0, err_old: 1e-4 }
    }
}

/// Hairer's error norm `sqrt(1/n sum_i (v_i / sc_i)²)`, `sc_i = atol + rtol max(|y0_i|, |y1_i|)`,
/// averaged over the system's `n` active components ([`OdeSystem::active_dimension`]).
/// The squares are summed in four interleaved partial sums (element `i` into sum `i mod 4`,
/// then `(s0 + s1) + (s2 + s3)`): a fixed order, so the same bits whatever registers the
/// method is compiled for, and one that vectorises (a single running sum does not).
#[inline(always)]
fn scaled_rms<const N: usize>(v: &[f64; N], y0: &[f64; N], y1: &[f64; N], s: &SolverSettings, n: usize) -> f64 {
    // `max` by comparison (a NaN in `y1` gives a NaN norm, which the caller treats as a
    // failed trial); `f64::max`'s NaN rule does not vectorise.
    let square = |i: usize| {
        let (a, b) = (y0[i].abs(), y1[i].abs());
        let q = v[i] / (s.abs_tol + s.rel_tol * if a > b { a } else { b });
        q * q
    };
    let mut sums = [0.0; 4];
    for block in 0..N / 4 {
        let i = 4 * block;
        sums = [sums[0] + square(i), sums[1] + square(i + 1), sums[2] + square(i + 2), sums[3] + square(i + 3)];
    }
    for i in N / 4 * 4..N {
        sums[i % 4] += square(i);
    }
    (((sums[0] + sums[1]) + (sums[2] + sums[3])) / n as f64).sqrt()
}

/// Hairer's initial step estimate. Inlined, so that a caller compiled for wider registers
/// has its own copy.
#[inline(always)]
fn initial_step<S: OdeSystem<N>, const N: usize>(
    system: &S,
    s: &SolverSettings,
    stats: &mut IntegratorStats,
    t0: f64,
    y0: &[f64; N],
    f0: &[f64; N],
    h_max: f64,
) -> f64 {
    let n = system.active_dimension();
    let d0 = scaled_rms(y0, y0, y0, s, n);
    let d1 = scaled_rms(f0, y0, y0, s, n);
    let mut h0 = if d0 < 1e-10 || d1 < 1e-10 { 1e-6 } else { 0.01 * d0 / d1 };
    h0 = h0.min(h_max);
    let mut y1 = [0.0; N];
    for i in 0..N {
        y1[i] = y0[i] + h0 * f0[i];
    }
    let mut f1 = [0.0; N];
    system.derivative(t0 + h0, &y1, &mut f1);
    stats.rhs_evaluations += 1;
    let mut df = [0.0; N];
    for i in 0..N {
        df[i] = f1[i] - f0[i];
    }
    let d2 = scaled_rms(&df, y0, y0, s, n) / h0;
    let dm = d1.max(d2);
    let h1 = if dm <= 1e-15 { (h0 * 1e-3).max(1e-6) } else { crate::maths::pow(0.01 / dm, 0.2) };
    (100.0 * h0).min(h1).min(h_max)
}

/// Coefficients of the continuous extension (Hairer's `dense output` of DOPRI5, order 4).
const D1: f64 = -12715105075.0 / 11282082432.0;
const D3: f64 = 87487479700.0 / 32700410799.0;
const D4: f64 = -10690763975.0 / 1880347072.0;
const D5: f64 = 701980252875.0 / 199316789632.0;
const D6: f64 = -1453857185.0 / 822651844.0;
const D7: f64 = 69997945.0 / 29380423.0;

/// The step's interpolant `y(t + theta h)`, theta in [0, 1]: built only when a switching
/// function changed sign in the step.
struct DenseOutput<const N: usize> {
    r: [[f64; N]; 5],
}

impl<const N: usize> DenseOutput<N> {
    fn new(y0: &[f64; N], y1: &[f64; N], k: [&[f64; N]; 7], h: f64) -> Self {
        let mut r = [[0.0; N]; 5];
        for i in 0..N {
            let ydiff = y1[i] - y0[i];
            let bspl = h * k[0][i] - ydiff;
            r[0][i] = y0[i];
            r[1][i] = ydiff;
            r[2][i] = bspl;
            r[3][i] = ydiff - h * k[6][i] - bspl;
            r[4][i] = h * (D1 * k[0][i] + D3 * k[2][i] + D4 * k[3][i] + D5 * k[4][i] + D6 * k[5][i] + D7 * k[6][i]);
        }
        DenseOutput { r }
    }

    fn at(&self, theta: f64) -> [f64; N] {
        let theta1 = 1.0 - theta;
        let mut y = [0.0; N];
        for i in 0..N {
            y[i] = self.r[0][i]
                + theta * (self.r[1][i] + theta1 * (self.r[2][i] + theta * (self.r[3][i] + theta1 * self.r[4][i])));
        }
        y
    }
}

/// The root of switching function `index` on the step's interpolant, by the Illinois
/// variant of regula falsi: returns the theta in (0, 1] at the end of the final bracket that
/// is on the function's new side.
fn locate<S: OdeSystem<N>, const N: usize>(
    system: &S,
    dense: &DenseOutput<N>,
    t: f64,
    h: f64,
    index: usize,
    g_start: f64,
    g_end: f64,
) -> f64 {
    let (mut a, mut b, mut fa, mut fb) = (0.0, 1.0, g_start, g_end);
    let new_side = g_end > 0.0;
    // Time resolution: far below any integration error, above the clock's round-off.
    let tolerance = (1e-12 + 4.0 * f64::EPSILON * t.abs() / h).min(1e-3);
    let mut g = [0.0; MAX_SWITCHING];
    let mut last_moved = 0i8;
    for _ in 0..100 {
        if b - a <= tolerance {
            break;
        }
        let mut c = if fb != fa { (a * fb - b * fa) / (fb - fa) } else { 0.5 * (a + b) };
        if !(c > a && c < b) {
            c = 0.5 * (a + b);
        }
        system.switching(t + c * h, &dense.at(c), &mut g);
        let fc = g.get(index).copied().unwrap_or(0.0);
        if (fc > 0.0) == new_side {
            b = c;
            fb = fc;
            if last_moved == -1 {
                fa *= 0.5;
            }
            last_moved = -1;
        } else {
            a = c;
            fa = fc;
            if last_moved == 1 {
                fb *= 0.5;
            }
            last_moved = 1;
        }
    }
    b
}

#[inline(always)]
pub(super) fn integrate<S: OdeSystem<N>, const N: usize>(
    system: &S,
    call: MethodCall<'_, '_, N>,
    t0: f64,
    y: &mut [f64; N],
    t1: f64,
) -> Result<f64, IntegrationError<S::Fault>> {
    let MethodCall { settings: s, memory, stats, events, .. } = call;
    let span = t1 - t0;
    let h_max = if s.max_step > 0.0 { s.max_step.min(span) } else { span };
    let fsal = !system.modifies_state_after_step();
    let switching = system.switching_count().min(MAX_SWITCHING);
    let active = system.active_dimension();

    let mut k1 = [0.0; N];
    system.derivative(t0, y, &mut k1);
    stats.rhs_evaluations += 1;
    let mut h =
        if memory.h_next > 0.0 { memory.h_next.min(h_max) } else { initial_step(system, s, stats, t0, y, &k1, h_max) };

    let mut g = [0.0; MAX_SWITCHING];
    let mut t = t0;
    let mut rejected_last = false;
    let mut steps: u64 = 0;
    // A step redone to end on a non-smooth point: the function it lands on, and the step
    // size the controller had before.
    let mut landing: Option<(usize, f64)> = None;

    loop {
        if steps >= s.max_steps_per_call {
            return Err(IntegrationError::TooManySteps { t, t_end: t1, steps });
        }
        // Land exactly on t1: stretch or shorten the last step (Hairer's 1.01 rule); a
        // landing step ends where it was told to.
        let h_unclamped = h;
        let last = landing.is_none() && t + 1.01 * h >= t1;
        if last {
            h = t1 - t;
        }
        if h <= 16.0 * f64::EPSILON * t.abs().max(span) {
            return Err(IntegrationError::StepSizeUnderflow { t, h });
        }

        // Stages by value (`derivative_of`, `from_fn`): written once, never zeroed first.
        let stage: [f64; N] = each(|i| y[i] + h * A21 * k1[i]);
        let k2 = system.derivative_of(t + C2 * h, &stage);
        let stage: [f64; N] = each(|i| y[i] + h * (A31 * k1[i] + A32 * k2[i]));
        let k3 = system.derivative_of(t + C3 * h, &stage);
        let stage: [f64; N] = each(|i| y[i] + h * (A41 * k1[i] + A42 * k2[i] + A43 * k3[i]));
        let k4 = system.derivative_of(t + C4 * h, &stage);
        let stage: [f64; N] = each(|i| y[i] + h * (A51 * k1[i] + A52 * k2[i] + A53 * k3[i] + A54 * k4[i]));
        let k5 = system.derivative_of(t + C5 * h, &stage);
        let stage: [f64; N] =
            each(|i| y[i] + h * (A61 * k1[i] + A62 * k2[i] + A63 * k3[i] + A64 * k4[i] + A65 * k5[i]));
        let t_new = if last { t1 } else { t + h };
        let k6 = system.derivative_of(t_new, &stage);
        let y_new: [f64; N] =
            each(|i| y[i] + h * (A71 * k1[i] + A73 * k3[i] + A74 * k4[i] + A75 * k5[i] + A76 * k6[i]));
        let k7 = system.derivative_of(t_new, &y_new);
        stats.rhs_evaluations += 6;
        let err_vec: [f64; N] =
            each(|i| h * (E1 * k1[i] + E3 * k3[i] + E4 * k4[i] + E5 * k5[i] + E6 * k6[i] + E7 * k7[i]));
        let mut err = scaled_rms(&err_vec, y, &y_new, s, active);
        if !err.is_finite() {
            err = 1e10; // a non-finite trial (e.g. a stage through a singularity): shrink hard
        }
        steps += 1;

        let fac11 = crate::maths::pow(err, EXPO1);
        if err <= 1.0 {
            let logged_before = events.log.as_slice().len();
            if switching > 0 {
                system.switching(t_new, &y_new, &mut g);
                let target = landing.map(|(i, _)| i);
                let changed = events.sides.changed(&g, switching);
                if changed != 0 {
                    let dense = DenseOutput::new(y, &y_new, [&k1, &k2, &k3, &k4, &k5, &k6, &k7], h);
                    match locate_crossings(system, s, &dense, events, t, h, span, &g, changed, target) {
                        Located::Stop { t: ts, fault } => return Err(IntegrationError::Fault { t: ts, fault }),
                        Located::Land { index, theta } => {
                            // Redo the step to end on the non-smooth point; the controller's
                            // memory is untouched.
                            let resume = landing.map_or(h, |(_, r)| r);
                            landing = Some((index, resume));
                            h *= theta;
                            stats.event_landings += 1;
                            continue;
                        }
                        Located::Recorded => {}
                    }
                }
                if let Some(i) = target
                    && changed >> i & 1 == 0
                {
                    // The landing step ended a hair before the root: the crossing is here.
                    events.sides.bits ^= 1 << i;
                    events.log.push(Crossing { index: i, t: t_new, rising: events.sides.bits >> i & 1 == 1, y: y_new });
                }
            }
            // Accept.
            let fac =
                (fac11 / crate::maths::pow(memory.err_old, BETA) / SAFETY).clamp(FAC_GROW_LIMIT, FAC_SHRINK_LIMIT);
            let mut h_new = h / fac;
            if rejected_last {
                h_new = h_new.min(h);
            }
            if let Some((_, resume)) = landing.take() {
                // After a non-smooth point go on no faster than before it.
                h_new = h_new.min(resume);
            }
            memory.err_old = err.max(1e-4);
            stats.accepted_steps += 1;
            *y = y_new;
            system.after_step(y);
            system.check(t_new, y).map_err(|fault| IntegrationError::Fault { t: t_new, fault })?;
            t = t_new;
            if last {
                // Keep the step the controller wanted before the landing clamp, so that a
                // short final piece does not throttle the next call.
                memory.h_next = if rejected_last { h_new } else { h_new.max(h_unclamped) };
                return Ok(t);
            }
            if events.stops_after(system, logged_before) {
                memory.h_next = h_new;
                return Ok(t);
            }
            h = h_new.min(h_max);
            rejected_last = false;
            if fsal {
                k1 = k7;
            } else {
                system.derivative(t, y, &mut k1);
                stats.rhs_evaluations += 1;
            }
        } else {
            stats.rejected_steps += 1;
            h /= (fac11 / SAFETY).min(FAC_SHRINK_LIMIT);
            rejected_last = true;
            // A shortened landing step no longer reaches its point: it will be found again.
            landing = None;
        }
    }
}

/// What the sign changes found at the end of an accepted step call for.
enum Located<F> {
    /// A [`SwitchingKind::Stop`] function crossed first: stop with this fault at `t`.
    Stop { t: f64, fault: F },
    /// A non-smooth point lies inside the step at `theta`: redo the step to end there.
    Land { index: usize, theta: f64 },
    /// Every crossing was recorded and the sides updated: accept the step.
    Recorded,
}

/// Locates the crossings `changed` of an accepted step from `t` of size `h` on its
/// interpolant and decides what to do. `target` is the function a landing step was aimed at
/// (its crossing at the step's end is expected, not a reason to land again).
#[allow(clippy::too_many_arguments)]
fn locate_crossings<S: OdeSystem<N>, const N: usize>(
    system: &S,
    settings: &SolverSettings,
    dense: &DenseOutput<N>,
    events: &mut Events<'_, N>,
    t: f64,
    h: f64,
    span: f64,
    g_end: &[f64; MAX_SWITCHING],
    changed: u32,
    target: Option<usize>,
) -> Located<S::Fault> {
    let mut g_start = [0.0; MAX_SWITCHING];
    system.switching(t, &dense.at(0.0), &mut g_start);
    // Shorter landing steps than this are not worth it (and would underflow): a crossing
    // this close to the step's start is taken as at the start.
    let min_landing = (1e-9 * h).max(1e3 * f64::EPSILON * t.abs().max(span));
    let mut theta = [1.0; MAX_SWITCHING];
    let mut land: Option<(f64, usize)> = None;
    let mut stop: Option<(f64, usize)> = None;
    for i in bits(changed) {
        let (Some(&g0), Some(&g1)) = (g_start.get(i), g_end.get(i)) else { continue };
        // Same sign at both ends: the side was stale (the crossing happened at the start).
        let th = if (g0 > 0.0) == (g1 > 0.0) { 0.0 } else { locate(system, dense, t, h, i, g0, g1) };
        if let Some(slot) = theta.get_mut(i) {
            *slot = th;
        }
        let first = |best: Option<(f64, usize)>| if best.is_none_or(|(b, _)| th < b) { Some((th, i)) } else { best };
        match system.switching_kind(i) {
            SwitchingKind::Restart
                if settings.locate_events && th * h > min_landing && th < 1.0 && target != Some(i) =>
            {
                land = first(land)
            }
            SwitchingKind::Stop => stop = first(stop),
            _ => {}
        }
    }
    if let Some((th, i)) = stop
        && land.is_none_or(|(tl, _)| th <= tl)
    {
        let ts = t + th * h;
        if let Some(fault) = system.switching_fault(i, ts, &dense.at(th)) {
            return Located::Stop { t: ts, fault };
        }
    }
    if let Some((th, index)) = land {
        return Located::Land { index, theta: th };
    }
    // Record in time order.
    let mut pending = changed;
    while pending != 0 {
        let Some(i) = bits(pending).min_by(|&a, &b| theta[a].total_cmp(&theta[b])) else { break };
        pending &= !(1 << i);
        let th = theta.get(i).copied().unwrap_or(1.0);
        events.log.push(Crossing {
            index: i,
            t: t + th * h,
            rising: g_end.get(i).is_some_and(|&x| x > 0.0),
            y: dense.at(th),
        });
    }
    events.sides.bits ^= changed;
    Located::Recorded
}
