//! A Co-Simulation step of the cueing FMU: the washout's states by RK4 in sub-steps of at most
//! `solver.maxStep`, the predictive method's solves at `start + k mpc.period` and its motion
//! under the held jerks, and the perception's lags over each sub-step (the vehicle's inputs
//! and the command's cues taken linearly between the sub-steps' ends). Nothing allocates.

use std::path::Path;

use super::parameters::{MAX_STEPS_PER_CALL, Method};
use super::{CueingModel, CueingStates, PerceptionStates, PredictiveState, check_pitch};
use crate::control::predictive_cueing::motion::{CHANNELS, CommandedMotion};
use crate::control::predictive_cueing::{GRID_STEPS, SolveOutcome, guess};
use crate::models::StepError;
use crate::physics::cueing::jet::Jet;
use crate::physics::cueing::perception::{Perception, PerceptionSteps};
use crate::physics::cueing::washout::{
    STATE_DIM, TILT_MODE_SWITCHES, TiltModes, VehicleMotion, WashoutParameters, WashoutPose, layout,
};

/// Rate, 1/s, at which the commanded motion follows the classical washout's pose through a
/// period whose solve failed (a triple pole: the hand-over is continuous in position, velocity
/// and acceleration, and takes about 0.3 s).
pub const FALLBACK_RATE: f64 = 20.0;

/// What a step leaves.
pub struct After {
    pub washout: CueingStates,
    pub tilt_modes: TiltModes,
    pub perception: PerceptionStates,
    pub predictive: PredictiveState,
}

/// The vehicle's future from a preview file: rows of `time, f[1..3], omega[1..3]` (s, m/s²,
/// rad/s), read at initialisation.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Preview {
    rows: Vec<[f64; 7]>,
}

impl Preview {
    /// The rows of `path` (empty: no preview). The columns are found by their header names.
    pub fn read(path: &str) -> Result<Preview, String> {
        if path.is_empty() {
            return Ok(Preview::default());
        }
        let text = std::fs::read_to_string(Path::new(path))
            .map_err(|e| format!("parameter preview.file: cannot read {path:?}: {e}"))?;
        Self::parse(&text).map_err(|why| format!("parameter preview.file: {path:?}: {why}"))
    }

    /// The rows of a CSV text with the header `time, f[1], f[2], f[3], omega[1], omega[2],
    /// omega[3]` (any order, other columns ignored).
    pub fn parse(text: &str) -> Result<Preview, String> {
        const NAMES: [&str; 7] = ["time", "f[1]", "f[2]", "f[3]", "omega[1]", "omega[2]", "omega[3]"];
        let mut lines = text.lines().filter(|l| !l.trim().is_empty());
        let header: Vec<&str> = lines.next().ok_or("the file is empty")?.split(',').map(str::trim).collect();
        let mut columns = [0usize; 7];
        for (c, name) in NAMES.iter().enumerate() {
            columns[c] = header
                .iter()
                .position(|h| h == name)
                .ok_or_else(|| format!("no column {name:?} (the header must name {})", NAMES.join(", ")))?;
        }
        let mut rows = Vec::new();
        for (n, line) in lines.enumerate() {
            let cells: Vec<&str> = line.split(',').map(str::trim).collect();
            let mut row = [0.0; 7];
            for (c, &at) in columns.iter().enumerate() {
                let cell = cells.get(at).ok_or_else(|| format!("row {}: too few cells", n + 2))?;
                row[c] = cell.parse::<f64>().ok().filter(|x| x.is_finite()).ok_or_else(|| {
                    format!("row {}: {:?} in column {} is not a finite number", n + 2, cell, NAMES[c])
                })?;
            }
            if let Some(last) = rows.last().map(|r: &[f64; 7]| r[0])
                && !(row[0] > last)
            {
                return Err(format!("row {}: the times must increase ({} after {last})", n + 2, row[0]));
            }
            rows.push(row);
        }
        if rows.len() < 2 {
            return Err("at least two rows are needed".into());
        }
        Ok(Preview { rows })
    }

    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }

    /// How far ahead of `t` the rows know the vehicle's motion, s: to the last row from `t` on
    /// or after the first (0 without rows, or before the first: `at` holds that row, a guess).
    pub fn known_after(&self, t: f64) -> f64 {
        match (self.rows.first(), self.rows.last()) {
            (Some(first), Some(last)) if t >= first[0] => (last[0] - t).max(0.0),
            _ => 0.0,
        }
    }

    /// The rows into an FMU state.
    pub fn save(&self, w: &mut crate::models::snapshot::ByteWriter) {
        w.u64(self.rows.len() as u64);
        for row in &self.rows {
            w.f64s(row);
        }
    }

    /// The rows from an FMU state.
    pub fn restore(
        r: &mut crate::models::snapshot::ByteReader,
    ) -> Result<Preview, crate::models::snapshot::SnapshotError> {
        let n = r.u64()?;
        if n > (r.remaining() / 56) as u64 {
            return Err(crate::models::snapshot::SnapshotError("the preview's rows: more than the state holds".into()));
        }
        let mut rows = Vec::with_capacity(n as usize);
        for _ in 0..n {
            rows.push(r.finite_array::<7>("the preview's rows")?);
        }
        Ok(Preview { rows })
    }

    pub fn len(&self) -> usize {
        self.rows.len()
    }

    /// The vehicle's motion at `t`, linear between rows, held beyond the ends.
    pub fn at(&self, t: f64) -> VehicleMotion {
        let rows = &self.rows;
        let after = rows.partition_point(|r| r[0] <= t);
        let row = if after == 0 {
            rows[0]
        } else if after == rows.len() {
            rows[rows.len() - 1]
        } else {
            let (a, b) = (&rows[after - 1], &rows[after]);
            let s = (t - a[0]) / (b[0] - a[0]);
            std::array::from_fn(|c| a[c] + s * (b[c] - a[c]))
        };
        VehicleMotion { f: [row[1], row[2], row[3]], omega: [row[4], row[5], row[6]] }
    }
}

/// The predictive method's pose: the commanded motion as jets.
pub fn predictive_pose(motion: &CommandedMotion) -> WashoutPose {
    let (p, v, a) = motion.head();
    let (b, bd, bdd) = motion.attitude();
    WashoutPose {
        head: std::array::from_fn(|i| Jet::new(p[i], v[i], a[i])),
        angles: std::array::from_fn(|i| Jet::new(b[i], bd[i], bdd[i])),
    }
}

/// The jerks that bring the commanded motion onto the classical washout's pose `pose`
/// (position, velocity and acceleration error through a triple pole at [`FALLBACK_RATE`]).
fn fallback_jerk(motion: &CommandedMotion, pose: &WashoutPose) -> [f64; CHANNELS] {
    let l = FALLBACK_RATE;
    std::array::from_fn(|c| {
        let target = if c < 3 { pose.head[c] } else { pose.angles[c - 3] };
        l * l * l * (target.v - motion.position[c])
            + 3.0 * l * l * (target.d1 - motion.rate[c])
            + 3.0 * l * (target.d2 - motion.acceleration[c])
    })
}

/// The washout's states after `dt` by one RK4 step, the inputs following `at` from `tau`,
/// the tilt's modes held.
pub(super) fn washout_rk4(
    w: &WashoutParameters,
    x: &[f64; STATE_DIM],
    modes: &TiltModes,
    tau: f64,
    dt: f64,
    at: &impl Fn(f64) -> VehicleMotion,
) -> [f64; STATE_DIM] {
    let shifted = |x: &[f64; STATE_DIM], k: &[f64; STATE_DIM], c: f64| std::array::from_fn(|i| x[i] + c * k[i]);
    let (start, middle, end) = (at(tau), at(tau + 0.5 * dt), at(tau + dt));
    let k1 = w.rate(x, &start, modes);
    let k2 = w.rate(&shifted(x, &k1, 0.5 * dt), &middle, modes);
    let k3 = w.rate(&shifted(x, &k2, 0.5 * dt), &middle, modes);
    let k4 = w.rate(&shifted(x, &k3, dt), &end, modes);
    std::array::from_fn(|i| x[i] + dt / 6.0 * (k1[i] + 2.0 * (k2[i] + k3[i]) + k4[i]))
}

/// Most switches of the tilt's limiter within one sub-step (two angles, each switching twice
/// at most in any motion the filters can make in a millisecond; more is a chattering target,
/// then stepped across).
const MAX_SWITCHES_PER_SUB_STEP: usize = 8;

/// The washout over a piece of a sub-step with the ideal tilt limiter.
pub(super) struct Advance {
    /// The states and modes where the piece ended.
    pub x: [f64; STATE_DIM],
    pub modes: TiltModes,
    /// Where it ended: the piece's end, or the first switch of a tilt's mode before it.
    pub reached: f64,
    /// At a switch (a mode's or a target's clip): the states and modes just before it (the
    /// cues jump there).
    pub before: Option<([f64; STATE_DIM], TiltModes)>,
}

/// The washout from `tau` towards `until` with the ideal tilt limiter: RK4 to the end;
/// where a tilt's switching function changed sign, the switch located (to round-off, along
/// the RK4 step from `tau`: a one-step method's solution is defined for every step length)
/// and the step taken only to it, the mode switched there (`locate` false: stepped across,
/// the modes held). Following angles are set to their targets where the piece ends.
pub(super) fn advance_washout(
    w: &WashoutParameters,
    x: &[f64; STATE_DIM],
    modes: &TiltModes,
    tau: f64,
    until: f64,
    at: &impl Fn(f64) -> VehicleMotion,
    locate: bool,
) -> Advance {
    let dt = until - tau;
    let end = washout_rk4(w, x, modes, tau, dt, at);
    let g0 = w.tilt_switching(x, &at(tau), modes);
    let g1 = w.tilt_switching(&end, &at(until), modes);
    // A mode's function crosses below zero; a clip's either way.
    let crossed = |i: usize, g: f64, start: f64| {
        if i < TILT_MODE_SWITCHES { g < 0.0 } else { (g < 0.0) != (start < 0.0) }
    };
    if !locate || !(0..4).any(|i| crossed(i, g1[i], g0[i])) {
        let mut end = end;
        w.follow_targets(&mut end, &at(until), modes);
        return Advance { x: end, modes: *modes, reached: until, before: None };
    }
    // The earliest crossing: regula falsi (Illinois) on s in (0, dt] for each crossed
    // function, the state at s being the RK4 step of length s; `a` the last length on the
    // start's side, `b` the first beyond.
    let mut first: Option<(f64, f64, usize)> = None;
    for i in (0..4).filter(|&i| crossed(i, g1[i], g0[i])) {
        let g = |s: f64| w.tilt_switching(&washout_rk4(w, x, modes, tau, s, at), &at(tau + s), modes)[i];
        let side = |v: f64| crossed(i, v, g0[i]);
        let (mut a, mut ga, mut b, mut gb) = (0.0, g0[i], dt, g1[i]);
        let mut last = 0;
        for _ in 0..100 {
            if b - a <= 1e-13 * dt {
                break;
            }
            let s = if ga != gb { (a * gb - b * ga) / (gb - ga) } else { 0.5 * (a + b) };
            let s = if s > a && s < b { s } else { 0.5 * (a + b) };
            let gs = g(s);
            if side(gs) {
                (b, gb) = (s, gs);
                if last == -1 {
                    ga *= 0.5;
                }
                last = -1;
            } else {
                (a, ga) = (s, gs);
                if last == 1 {
                    gb *= 0.5;
                }
                last = 1;
            }
        }
        if first.is_none_or(|(_, s, _)| b < s) {
            first = Some((a, b, i));
        }
    }
    let Some((a, b, i)) = first else {
        return Advance { x: end, modes: *modes, reached: until, before: None };
    };
    let mut before = washout_rk4(w, x, modes, tau, a, at);
    w.follow_targets(&mut before, &at(tau + a), modes);
    let mut after = washout_rk4(w, x, modes, tau, b, at);
    let mut switched = *modes;
    let now = at(tau + b);
    if i < TILT_MODE_SWITCHES {
        w.switch_tilt(&mut after, &now, &mut switched, i);
    }
    w.follow_targets(&mut after, &now, &switched);
    Advance { x: after, modes: switched, reached: tau + b, before: Some((before, *modes)) }
}

fn rolled_back(t: f64, h: f64, why: String, retry_shorter: bool) -> StepError {
    StepError { message: format!("step from t = {t:?} to {:?} rolled back: {why}", t + h), retry_shorter }
}

/// One communication step from `t` to `t + h` (see the module); the model is not changed, the
/// states after the step are returned (or why there are none).
pub fn step(m: &mut CueingModel, t: f64, h: f64) -> Result<After, StepError> {
    let p = &m.parameters;
    let predictive = p.method == Method::Predictive;
    let period = p.predictive.period;
    // The work is bounded: a step that would take more internal steps than the limit is
    // refused before anything is computed.
    let finest = if predictive { p.max_step.min(period) } else { p.max_step };
    let steps = h / finest;
    if !(steps <= MAX_STEPS_PER_CALL) {
        return Err(rolled_back(
            t,
            h,
            format!(
                "a communication step of {h:e} s takes {steps:.3e} internal steps of at most {finest:e} s \
                 (solver.maxStep{}), more than the limit of {MAX_STEPS_PER_CALL:e} per call; use shorter \
                 communication steps",
                if predictive { ", mpc.period" } else { "" }
            ),
            true,
        ));
    }
    let (vehicle, rates) = (m.vehicle, m.input_rates);
    let at = |tau: f64| VehicleMotion {
        f: std::array::from_fn(|i| vehicle.f[i] + rates[i] * (tau - t)),
        omega: std::array::from_fn(|i| vehicle.omega[i] + rates[3 + i] * (tau - t)),
    };
    let mut x = m.state.to_vector();
    let mut modes = m.tilt_modes;
    let (mut felt_vehicle, mut felt_simulator) = (m.perception.vehicle(), m.perception.simulator());
    let mut predictive_state = m.predictive_state;
    let mut cue = m.command(&x, &vehicle, &modes, &predictive_state.motion);
    // Equal sub-steps of at most solver.maxStep (a step that exceeds a multiple of it by
    // round-off, as a host's sums of steps do, takes no extra one); the predictive method's
    // also cut at its solves.
    let sub_steps = (h / p.max_step * (1.0 - 1e-12)).abs().ceil().max(1.0) as u64;
    let sub_step = h / sub_steps as f64;
    let end = t + h;
    let (mut tau, mut i) = (t, 0u64);
    let mut steps = PerceptionSteps::new(sub_step);
    let mut steps_length = sub_step;
    let mut switches = 0;
    while i < sub_steps {
        let sub_end = if i + 1 == sub_steps { end } else { t + (i + 1) as f64 * sub_step };
        let mut next = sub_end;
        if predictive {
            let due = m.start_time + predictive_state.solves as f64 * period;
            // A solve due now (to a nanosecond of the period, against the host's sums of steps).
            if tau >= due - 1e-9 * period {
                solve(m, tau, &x, &modes, &felt_vehicle, &felt_simulator, &mut predictive_state, &at);
            }
            // The next solve cuts this step, unless it falls at the step's end (to a nanosecond):
            // then it is the next step's first, with the inputs set for it.
            let due = m.start_time + predictive_state.solves as f64 * period;
            if due < sub_end - 1e-9 * period {
                next = next.min(due);
            }
        }
        if next > tau {
            let p = &m.parameters;
            let piece = advance_washout(&p.washout, &x, &modes, tau, next, &at, switches < MAX_SWITCHES_PER_SUB_STEP);
            let dt = piece.reached - tau;
            predictive_state.motion.advance(&predictive_state.jerk, dt);
            let (from, to) = (at(tau), at(piece.reached));
            // The cues at the piece's end, before a switch there (they jump at it).
            let (left_x, left_modes) = piece.before.unwrap_or((piece.x, piece.modes));
            let left = m.command(&left_x, &to, &left_modes, &predictive_state.motion);
            if dt != steps_length {
                steps = PerceptionSteps::new(dt);
                steps_length = dt;
            }
            felt_vehicle.advance(&steps, &from.f, &from.omega, &to.f, &to.omega);
            felt_simulator.advance(&steps, &cue.fsim, &cue.omegasim, &left.fsim, &left.omegasim);
            cue = match piece.before {
                Some(_) => {
                    switches += 1;
                    m.command(&piece.x, &to, &piece.modes, &predictive_state.motion)
                }
                None => left,
            };
            (x, modes, tau) = (piece.x, piece.modes, piece.reached);
        }
        if tau >= sub_end {
            tau = sub_end;
            i += 1;
            switches = 0;
        }
    }
    check(t, h, &x, &predictive_state, m.parameters.method)?;
    let mut perception = m.perception;
    perception.set(&felt_vehicle, &felt_simulator);
    Ok(After { washout: CueingStates::from_vector(&x), tilt_modes: modes, perception, predictive: predictive_state })
}

/// The predictive method's solve at `tau`, or the classical washout's pose followed through a
/// period whose solve failed.
#[allow(clippy::too_many_arguments)]
fn solve(
    m: &mut CueingModel,
    tau: f64,
    x: &[f64; STATE_DIM],
    modes: &TiltModes,
    felt_vehicle: &Perception,
    felt_simulator: &Perception,
    state: &mut PredictiveState,
    at: &impl Fn(f64) -> VehicleMotion,
) {
    let Some(solver) = m.predictive.as_deref_mut() else { return };
    let now = at(tau);
    let times = *solver.grid_times();
    // Without a preview the future is a guess: the inputs going on at their rate over the
    // last period (`mpc.trend`; none at the first solve).
    let (period, trend) = (solver.parameters.period, solver.parameters.trend);
    let rate: [f64; 6] = match state.last_vehicle.replace(now) {
        Some(last) => std::array::from_fn(|i| {
            if i < 3 { (now.f[i] - last.f[i]) / period } else { (now.omega[i - 3] - last.omega[i - 3]) / period }
        }),
        None => [0.0; 6],
    };
    let future: [VehicleMotion; GRID_STEPS + 1] = std::array::from_fn(|j| {
        if j == 0 {
            now
        } else if m.preview.is_empty() {
            guess(&now, &rate, trend, times[j])
        } else {
            m.preview.at(tau + times[j])
        }
    });
    let last_plan = if state.falling_back { None } else { Some(&state.plan) };
    let known = m.preview.known_after(tau);
    let outcome = solver.solve(&state.motion, last_plan, &future, known, felt_vehicle, felt_simulator);
    state.solves += 1;
    match outcome {
        SolveOutcome::Planned { iterations, plan, acceptable } => {
            state.plan = plan;
            state.acceptable = state.acceptable.saturating_add(i32::from(acceptable));
            state.jerk = plan[0];
            state.iterations = iterations as i32;
            state.falling_back = false;
        }
        SolveOutcome::Failed { iterations, .. } => {
            state.plan = [[0.0; CHANNELS]; GRID_STEPS];
            state.iterations = iterations as i32;
            state.fallbacks = state.fallbacks.saturating_add(1);
            state.falling_back = true;
            state.jerk = fallback_jerk(&state.motion, &m.parameters.washout.pose(x, &now, modes));
        }
    }
}

/// Whether the states after a step can be continued from.
fn check(t: f64, h: f64, x: &[f64; STATE_DIM], p: &PredictiveState, method: Method) -> Result<(), StepError> {
    let pitch = match method {
        Method::Classical => x[layout::ROTATION_ANGLES + 1] + x[layout::TILT_ANGLES + 1],
        Method::Predictive => p.motion.position[4],
    };
    check_pitch(pitch).map_err(|why| rolled_back(t, h, why, false))?;
    if let Some(i) = x.iter().position(|v| !v.is_finite()) {
        return Err(rolled_back(
            t,
            h,
            format!("state {} of the washout is not finite (check the filters' parameters and the inputs)", i + 1),
            false,
        ));
    }
    if !p.motion.is_finite() {
        return Err(rolled_back(t, h, "the predictive method's command is not finite".into(), false));
    }
    Ok(())
}
