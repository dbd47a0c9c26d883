//! The predictive method's QP at one solve (docs/cueing.md writes it out):
//!
//! - **Unknowns** `du`: for each input block `b` and channel `c` a jerk added to the nominal
//!   plan's (the previous plan shifted by the solve period), the angular ones scaled by `g`.
//! - **Prediction**: the commanded motion integrated exactly over the grid; the simulator's
//!   cues (`fsim`, `omegasim`) at each grid point linearised about the nominal plan's; the
//!   perception's lags advanced exactly over each grid step with the cues taken linearly between
//!   the points; the vehicle's perception the same way from its predicted cues.
//! - **Objective** `1/2 sum w r^2` over the grid points `j = 1..N` (`dt` each): the perceived
//!   errors (simulator minus vehicle) per axis in thresholds, weighed `mpc.weight.*` times
//!   `exp(-max(0, tau_j - known)/trust)` (`known`: how far ahead a preview knows the
//!   vehicle's motion; the held inputs are a guess from now on); the head's displacement and
//!   the yaw, weighed `mpc.weight.neutral`; and over every grid step the jerks, weighed
//!   `mpc.weight.input` (angular ones times g²).
//! - **Constraints** at the blocks' ends: every leg within [`super::STROKE_SHARE`] of its stroke
//!   to the margins (the legs linearised about the nominal pose), every leg's speed
//!   (`J(nominal pose) (p', beta')`) within `mpc.legSpeed`, the roll and pitch rates within
//!   `tilt.rateLimit` plus the vehicle's own.
//!
//! Every buffer is a fixed-size array: building allocates nothing.

use nalgebra::Vector3;

use super::linearisation::{Cues, Legs};
use super::motion::{CHANNELS, CommandedMotion, jerk_response};
use super::{
    BLOCKS, CONSTRAINED, GRID_STEPS, INEQUALITIES, PredictiveParameters, PredictiveStand, QP_ROWS, QP_UNKNOWNS, SLACK,
    STROKE_SHARE, UNKNOWNS,
};
use crate::maths;
use crate::physics::cueing::perception::{CANAL, LagStep, OTOLITH, Perception, THRESHOLD_F, THRESHOLD_OMEGA};
use crate::physics::cueing::washout::VehicleMotion;
use crate::physics::stand::LEG_COUNT;

/// The cues: `fsim` (3), then `omegasim` (3).
const CUES: usize = 6;
/// The slack's linear weight: far above any multiplier the constraints take when they can
/// all hold, so that it is 0 then (an exact penalty).
pub const SLACK_PENALTY: f64 = 1e4;
/// The slack's quadratic weight.
pub const SLACK_CURVATURE: f64 = 1.0;
/// What one unit of the slack lets each kind of row give: a centimetre of a leg's length,
/// 5 cm/s of its speed, a degree per second of tilt rate, a degree of tilt.
const GIVE_LENGTH: f64 = 0.01;
const GIVE_SPEED: f64 = 0.05;
const GIVE_TILT_RATE: f64 = std::f64::consts::PI / 180.0;
const GIVE_TILT: f64 = std::f64::consts::PI / 180.0;
/// Ratio of consecutive grid steps: the first is 35 ms at the default 2 s horizon, the last
/// 0.21 s (a bump's heave is resolved ahead, the far future only sketched).
pub const GRID_GROWTH: f64 = 1.1;
/// The return to neutral weighs the head's and the yaw's rates per this time, s, squared: a
/// drift of 0.1 m/s costs as a displacement of 0.1 m.
pub const NEUTRAL_TIME: f64 = 1.0;
/// The return to neutral at the horizon's end weighs this many seconds of it: a plan that
/// ends far from neutral, or moving, costs; a sustained force is then the tilt's, as in the
/// classical washout's split.
pub const TERMINAL_WEIGHT: f64 = 10.0;
/// The triple pole, 1/s, of the nominal plan's return to neutral after a failed solve
/// ([`Problem::returning_inputs`]): back within the default 2 s horizon (the unit test below).
pub const RETURN_RATE: f64 = 3.0;
/// ... at most this over each grid step's length: the feedback's jerk held over a step
/// returns only while pole times step stays below about 0.67 (above it the held jerks
/// overshoot and grow), which longer horizons' last steps would pass.
pub const RETURN_RATE_PER_STEP: f64 = 0.5;
/// A row over the unknowns.
type Row = [f64; UNKNOWNS];

/// The unknowns' scale: jerks of the head (m/s³) as they are, angular jerks (rad/s³) times g.
fn unknown_scale(gravity: f64, c: usize) -> f64 {
    if c < 3 { 1.0 } else { gravity }
}

/// The QP's data and the fixed facts of its grid.
#[derive(Debug)]
pub struct Problem {
    /// The grid's step lengths, s (growing geometrically: fine ahead, coarse far).
    steps: [f64; GRID_STEPS],
    /// The grid's points, s from the solve (`times[0] = 0`).
    times: [f64; GRID_STEPS + 1],
    /// The solve period, s (the nominal plan is the last one `period` later).
    period: f64,
    gravity: f64,
    /// `sensitivity[j][b]`: position, rate and acceleration of a channel at grid point `j` per
    /// unit jerk over block `b` (0 for a block that starts at or after `j`).
    sensitivity: [[[f64; 3]; BLOCKS.len()]; GRID_STEPS + 1],
    block_of: [usize; GRID_STEPS],
    /// The legs' lengths at the neutral pose, m.
    neutral_legs: [f64; LEG_COUNT],
    otolith_steps: [[LagStep; 2]; GRID_STEPS],
    canal_steps: [[LagStep; 3]; GRID_STEPS],
    /// `H`, row-major, `g`, `A`, row-major, `b` of `min du^T H du / 2 + g^T du, A du <= b`, in
    /// the scaled unknowns.
    pub hessian: [f64; QP_UNKNOWNS * QP_UNKNOWNS],
    pub gradient: [f64; QP_UNKNOWNS],
    pub constraints: [f64; QP_ROWS * QP_UNKNOWNS],
    pub bounds: [f64; QP_ROWS],
    /// The solver's answer, in the scaled unknowns (the slack last).
    pub solution: [f64; QP_UNKNOWNS],
    /// The cues' rows at the previous and the current grid point.
    cue_rows: [[Row; CUES]; 2],
    /// The simulator's lags' rows: per cue the otoliths' two or the canals' three lags.
    lag_rows: [[Row; 3]; CUES],
}

impl Problem {
    pub fn new(p: &PredictiveParameters, stand: &PredictiveStand) -> Problem {
        let (steps, times) = grid(p);
        let mut block_of = [0; GRID_STEPS];
        let mut at = 0;
        for (b, &len) in BLOCKS.iter().enumerate() {
            block_of[at..at + len].fill(b);
            at += len;
        }
        // Each block's unit jerk propagated over the grid.
        let mut sensitivity = [[[0.0; 3]; BLOCKS.len()]; GRID_STEPS + 1];
        for b in 0..BLOCKS.len() {
            let (mut x, mut v, mut a) = (0.0, 0.0, 0.0);
            for j in 0..GRID_STEPS {
                let h = steps[j];
                let jerk = if block_of[j] == b { 1.0 } else { 0.0 };
                let [p3, p2, p1] = jerk_response(h);
                (x, v, a) = (x + v * h + a * h * h / 2.0 + jerk * p3, v + a * h + jerk * p2, a + jerk * p1);
                sensitivity[j + 1][b] = [x, v, a];
            }
        }
        Problem {
            steps,
            times,
            period: p.period,
            gravity: stand.gravity,
            sensitivity,
            block_of,
            neutral_legs: Legs::at(&stand.workspace, &stand.head, &[0.0; 3], &[0.0; 3]).length,
            otolith_steps: steps.map(|h| OTOLITH.steps(h)),
            canal_steps: steps.map(|h| CANAL.steps(h)),
            hessian: [0.0; QP_UNKNOWNS * QP_UNKNOWNS],
            gradient: [0.0; QP_UNKNOWNS],
            constraints: [0.0; QP_ROWS * QP_UNKNOWNS],
            bounds: [0.0; QP_ROWS],
            solution: [0.0; QP_UNKNOWNS],
            cue_rows: [[[0.0; UNKNOWNS]; CUES]; 2],
            lag_rows: [[[0.0; UNKNOWNS]; 3]; CUES],
        }
    }

    /// The nominal jerks per grid step: the last plan `period` later, step `j` taking the
    /// mean of the last plan's jerks over `[times[j], times[j + 1]] + period` (0 beyond its
    /// horizon). The mean keeps the last plan's acceleration at every grid point and its rate
    /// and position to second order; taking the jerk at one instant of the step instead moved
    /// each block's edge by the period at every solve, and a jump of 100 m/s³ between blocks
    /// then put the nominal motion a metre off the last plan's 2 s ahead, more at each solve.
    pub fn nominal_inputs(&self, plan: &[[f64; CHANNELS]; GRID_STEPS]) -> [[f64; CHANNELS]; GRID_STEPS] {
        shifted_plan(&self.times, self.period, plan)
    }

    /// The nominal jerks when there is no last plan to follow (the last solve failed and the
    /// classical washout moved the command): the command brought back to neutral by a triple
    /// pole at RETURN_RATE, the jerk held over each grid step. Zero jerks instead would carry
    /// the washout's last acceleration through the whole horizon (tens of rad/s of tilt rate
    /// 2 s ahead), and the constraints linearised about that were violated by thousands of
    /// their units: the QP's plans then followed them out.
    pub fn returning_inputs(&self, now: &CommandedMotion) -> [[f64; CHANNELS]; GRID_STEPS] {
        returning_plan(&self.steps, now)
    }

    /// The grid's points, s from the solve.
    pub fn times(&self) -> &[f64; GRID_STEPS + 1] {
        &self.times
    }

    /// How far the constraints had to give in the last solve (0: not at all; in units of the
    /// rows, each scaled to unit length).
    pub fn slack(&self) -> f64 {
        self.solution[SLACK]
    }

    /// The plan from the solution: the nominal jerks plus each block's correction.
    pub fn plan(&self, nominal: &[[f64; CHANNELS]; GRID_STEPS]) -> [[f64; CHANNELS]; GRID_STEPS] {
        std::array::from_fn(|j| {
            let b = self.block_of[j];
            std::array::from_fn(|c| nominal[j][c] + self.solution[b * CHANNELS + c] / unknown_scale(self.gravity, c))
        })
    }

    /// `H += w row^T row`, `g += w r0 row` (one residual `r0 + row du` weighed `w`).
    fn add_residual(&mut self, w: f64, r0: f64, row: &Row) {
        for i in 0..UNKNOWNS {
            if row[i] == 0.0 {
                continue;
            }
            let wi = w * row[i];
            self.gradient[i] += wi * r0;
            for k in 0..UNKNOWNS {
                self.hessian[i * QP_UNKNOWNS + k] += wi * row[k];
            }
        }
    }

    /// A residual of one unknown alone: `r0 + du_i`.
    fn add_unit_residual(&mut self, w: f64, r0: f64, i: usize) {
        self.gradient[i] += w * r0;
        self.hessian[i * QP_UNKNOWNS + i] += w;
    }

    /// The row of channel `c`'s position (`part` 0), rate (1) or acceleration (2) at grid
    /// point `j`, times `factor`, added into `row` (unscaled unknowns).
    fn add_channel(&self, row: &mut Row, j: usize, c: usize, part: usize, factor: f64) {
        if factor == 0.0 {
            return;
        }
        for b in 0..BLOCKS.len() {
            row[b * CHANNELS + c] += factor * self.sensitivity[j][b][part];
        }
    }

    /// The cues' rows at grid point `j` from their Jacobians.
    fn cue_rows_at(&self, j: usize, cues: &Cues) -> [Row; CUES] {
        let mut rows = [[0.0; UNKNOWNS]; CUES];
        for o in 0..3 {
            for c in 0..3 {
                self.add_channel(&mut rows[o], j, c, 2, cues.fsim_by_acceleration[o][c]);
                self.add_channel(&mut rows[o], j, 3 + c, 0, cues.fsim_by_angles[o][c]);
                self.add_channel(&mut rows[3 + o], j, 3 + c, 0, cues.omegasim_by_angles[o][c]);
                self.add_channel(&mut rows[3 + o], j, 3 + c, 1, cues.omegasim_by_rates[o][c]);
            }
        }
        rows
    }

    /// Builds `H`, `g`, `A`, `b` for a solve from the commanded motion `now` with the nominal
    /// jerks `nominal` (see the module's documentation).
    #[allow(clippy::too_many_arguments)]
    pub fn build(
        &mut self,
        p: &PredictiveParameters,
        stand: &PredictiveStand,
        now: &CommandedMotion,
        nominal: &[[f64; CHANNELS]; GRID_STEPS],
        vehicle: &[VehicleMotion; GRID_STEPS + 1],
        known: f64,
        perceived_vehicle: &Perception,
        perceived_simulator: &Perception,
    ) {
        self.hessian.fill(0.0);
        self.gradient.fill(0.0);
        let g = stand.gravity;
        let error_weight: [f64; CUES] = std::array::from_fn(|o| {
            if o < 3 {
                p.weight_f[o] / (THRESHOLD_F[o] * THRESHOLD_F[o])
            } else {
                p.weight_omega[o - 3] / (THRESHOLD_OMEGA[o - 3] * THRESHOLD_OMEGA[o - 3])
            }
        });
        let cues_of = |m: &CommandedMotion| {
            let (_, _, acceleration) = m.head();
            let (angles, rates, _) = m.attitude();
            Cues::at(g, &acceleration, &angles, &rates)
        };
        let mut motion = *now;
        let mut cues = cues_of(&motion);
        self.cue_rows[0] = [[0.0; UNKNOWNS]; CUES];
        self.lag_rows = [[[0.0; UNKNOWNS]; 3]; CUES];
        let (mut vehicle_lags, mut simulator_lags) = (*perceived_vehicle, *perceived_simulator);
        let mut constrained = 0;
        for j in 1..=GRID_STEPS {
            let dt = self.steps[j - 1];
            // The nominal motion, its cues and their rows at grid point j.
            motion.advance(&nominal[j - 1], dt);
            let before = cues;
            cues = cues_of(&motion);
            self.cue_rows[1] = self.cue_rows_at(j, &cues);
            let (v0, v1) = (&vehicle[j - 1], &vehicle[j]);
            let lag_steps = perception_steps(self.otolith_steps[j - 1], self.canal_steps[j - 1]);
            vehicle_lags.advance(&lag_steps, &v0.f, &v0.omega, &v1.f, &v1.omega);
            simulator_lags.advance(&lag_steps, &before.fsim, &before.omegasim, &cues.fsim, &cues.omegasim);
            self.advance_lag_rows(j - 1);
            // The perceived errors.
            let (felt_vehicle_f, felt_vehicle_w) = vehicle_lags.perceived();
            let (felt_sim_f, felt_sim_w) = simulator_lags.perceived();
            // A guess of the vehicle's future weighs less the further ahead it guesses; what a
            // preview knows is no guess.
            let trust = maths::exp(-(self.times[j] - known).max(0.0) / p.trust);
            for o in 0..CUES {
                let error =
                    if o < 3 { felt_sim_f[o] - felt_vehicle_f[o] } else { felt_sim_w[o - 3] - felt_vehicle_w[o - 3] };
                let row = self.perceived_row(o);
                self.add_residual(dt * trust * error_weight[o], error, &row);
            }
            // Back to neutral: the head's displacement and the yaw, and their rates (per
            // NEUTRAL_TIME² s²), over the horizon and, TERMINAL_WEIGHT times more, at its end.
            for c in [0, 1, 2, 5] {
                let (mut at, mut moving) = ([0.0; UNKNOWNS], [0.0; UNKNOWNS]);
                self.add_channel(&mut at, j, c, 0, 1.0);
                self.add_channel(&mut moving, j, c, 1, NEUTRAL_TIME);
                let mut w = dt * p.weight_neutral;
                if j == GRID_STEPS {
                    w += TERMINAL_WEIGHT * p.weight_neutral;
                }
                self.add_residual(w, motion.position[c], &at);
                self.add_residual(w, NEUTRAL_TIME * motion.rate[c], &moving);
            }
            if CONSTRAINED.contains(&j) {
                self.constrain(constrained, p, stand, &motion, &cues, &vehicle[j]);
                constrained += 1;
            }
            self.cue_rows[0] = self.cue_rows[1];
        }
        // The slack: at least 0, weighed SLACK_PENALTY linearly (and a little quadratically,
        // for a definite Hessian).
        self.hessian[SLACK * QP_UNKNOWNS + SLACK] = SLACK_CURVATURE;
        self.gradient[SLACK] = SLACK_PENALTY;
        self.constraints[INEQUALITIES * QP_UNKNOWNS..].fill(0.0);
        self.constraints[INEQUALITIES * QP_UNKNOWNS + SLACK] = -1.0;
        self.bounds[INEQUALITIES] = 0.0;
        // Smooth inputs: every grid step's jerks.
        for j in 0..GRID_STEPS {
            let b = self.block_of[j];
            for c in 0..CHANNELS {
                let s = unknown_scale(g, c);
                self.add_unit_residual(self.steps[j] * p.weight_input * s * s, nominal[j][c], b * CHANNELS + c);
            }
        }
        self.scale_unknowns();
    }

    /// The perceived simulator cue `o`'s row: the lags' rows weighed as the filter's output.
    fn perceived_row(&self, o: usize) -> Row {
        let mut row = [0.0; UNKNOWNS];
        if o < 3 {
            for (l, &c) in OTOLITH.weights.iter().enumerate() {
                for i in 0..UNKNOWNS {
                    row[i] += c * self.lag_rows[o][l][i];
                }
            }
        } else {
            for (l, &c) in CANAL.weights.iter().enumerate() {
                for i in 0..UNKNOWNS {
                    row[i] += c * self.lag_rows[o][l][i];
                }
            }
        }
        row
    }

    /// The simulator's lags' rows over grid step `k` (the cues' rows linear between points).
    fn advance_lag_rows(&mut self, k: usize) {
        for o in 0..CUES {
            let steps: &[LagStep] = if o < 3 { &self.otolith_steps[k] } else { &self.canal_steps[k] };
            for (l, step) in steps.iter().enumerate() {
                for i in 0..UNKNOWNS {
                    self.lag_rows[o][l][i] =
                        step.apply(self.lag_rows[o][l][i], self.cue_rows[0][o][i], self.cue_rows[1][o][i]);
                }
            }
        }
    }

    /// The inequalities of constrained point number `n` (grid point `j`), each row scaled to
    /// unit length.
    fn constrain(
        &mut self,
        n: usize,
        p: &PredictiveParameters,
        stand: &PredictiveStand,
        motion: &CommandedMotion,
        cues: &Cues,
        vehicle: &VehicleMotion,
    ) {
        let j = CONSTRAINED[n];
        let ws = &stand.workspace;
        let (position, rate, _) = motion.head();
        let (angles, angle_rates, _) = motion.attitude();
        let legs = Legs::at(ws, &stand.head, &position, &angles);
        let neutral = self.neutral_legs;
        let mut at = n * super::ROWS_PER_POINT;
        for k in 0..LEG_COUNT {
            let (mut length_row, mut speed_row) = ([0.0; UNKNOWNS], [0.0; UNKNOWNS]);
            let mut speed = 0.0;
            for c in 0..CHANNELS {
                let jc = legs.jacobian[k][c];
                self.add_channel(&mut length_row, j, c, 0, jc);
                self.add_channel(&mut speed_row, j, c, 1, jc);
                speed += jc * if c < 3 { rate[c] } else { angle_rates[c - 3] };
            }
            let upper = neutral[k] + STROKE_SHARE * (ws.upper[k] - neutral[k]);
            let lower = neutral[k] + STROKE_SHARE * (ws.lower[k] - neutral[k]);
            self.set_row(at, &length_row, 1.0, upper - legs.length[k], GIVE_LENGTH);
            self.set_row(at + 1, &length_row, -1.0, legs.length[k] - lower, GIVE_LENGTH);
            self.set_row(at + 2, &speed_row, 1.0, p.leg_speed - speed, GIVE_SPEED);
            self.set_row(at + 3, &speed_row, -1.0, p.leg_speed + speed, GIVE_SPEED);
            at += 4;
        }
        for i in 0..2 {
            let limit = p.tilt_rate_limit + vehicle.omega[i].abs();
            let row = self.cue_rows[1][3 + i];
            self.set_row(at, &row, 1.0, limit - cues.omegasim[i], GIVE_TILT_RATE);
            self.set_row(at + 1, &row, -1.0, limit + cues.omegasim[i], GIVE_TILT_RATE);
            let mut angle = [0.0; UNKNOWNS];
            self.add_channel(&mut angle, j, 3 + i, 0, 1.0);
            self.set_row(at + 2, &angle, 1.0, p.tilt_max - angles[i], GIVE_TILT);
            self.set_row(at + 3, &angle, -1.0, p.tilt_max + angles[i], GIVE_TILT);
            at += 4;
        }
    }

    /// Inequality `r`: `sign row du <= bound + give slack`, scaled to a unit row in the jerks
    /// (unscaled unknowns here; [`Problem::scale_unknowns`] scales them with the rest). `give`
    /// is how much of the row's own quantity one unit of the slack lets it give (a
    /// centimetre of a leg, a degree of tilt, ...): the problem stays solvable where the
    /// first points' bounds conflict, and the slack's penalty keeps it 0 where they do not.
    fn set_row(&mut self, r: usize, row: &Row, sign: f64, bound: f64, give: f64) {
        let norm = row.iter().map(|x| x * x).sum::<f64>().sqrt();
        let scale = if norm > 0.0 { 1.0 / norm } else { 1.0 };
        for i in 0..UNKNOWNS {
            self.constraints[r * QP_UNKNOWNS + i] = sign * scale * row[i];
        }
        self.constraints[r * QP_UNKNOWNS + SLACK] = -give * scale;
        self.bounds[r] = bound * scale;
    }

    /// From jerks to the scaled unknowns `x = D du` (`D`: 1 for the head, g for the angles).
    fn scale_unknowns(&mut self) {
        let d: [f64; QP_UNKNOWNS] =
            std::array::from_fn(|i| if i == SLACK { 1.0 } else { unknown_scale(self.gravity, i % CHANNELS) });
        for i in 0..QP_UNKNOWNS {
            self.gradient[i] /= d[i];
            for k in 0..QP_UNKNOWNS {
                self.hessian[i * QP_UNKNOWNS + k] /= d[i] * d[k];
            }
        }
        for r in 0..QP_ROWS {
            for i in 0..QP_UNKNOWNS {
                self.constraints[r * QP_UNKNOWNS + i] /= d[i];
            }
        }
    }
}

/// The grid's step lengths and points, s: `h_j = h_0 GRID_GROWTH^j` from `tau_0 = 0`.
fn grid(p: &PredictiveParameters) -> ([f64; GRID_STEPS], [f64; GRID_STEPS + 1]) {
    let first = p.first_grid_step();
    let steps: [f64; GRID_STEPS] = std::array::from_fn(|j| first * maths::pow(GRID_GROWTH, j as f64));
    let mut times = [0.0; GRID_STEPS + 1];
    for j in 0..GRID_STEPS {
        times[j + 1] = times[j] + steps[j];
    }
    (steps, times)
}

/// [`Problem::nominal_inputs`] on the grid `times`.
fn shifted_plan(
    times: &[f64; GRID_STEPS + 1],
    period: f64,
    plan: &[[f64; CHANNELS]; GRID_STEPS],
) -> [[f64; CHANNELS]; GRID_STEPS] {
    std::array::from_fn(|j| {
        let (from, to) = (times[j] + period, times[j + 1] + period);
        let mut sum = [0.0; CHANNELS];
        for k in 0..GRID_STEPS {
            let overlap = to.min(times[k + 1]) - from.max(times[k]);
            if overlap > 0.0 {
                for c in 0..CHANNELS {
                    sum[c] += overlap * plan[k][c];
                }
            }
        }
        std::array::from_fn(|c| sum[c] / (times[j + 1] - times[j]))
    })
}

/// [`Problem::returning_inputs`] over the grid's `steps`.
fn returning_plan(steps: &[f64; GRID_STEPS], now: &CommandedMotion) -> [[f64; CHANNELS]; GRID_STEPS] {
    let mut motion = *now;
    let mut nominal = [[0.0; CHANNELS]; GRID_STEPS];
    for (j, jerk) in nominal.iter_mut().enumerate() {
        let l = RETURN_RATE.min(RETURN_RATE_PER_STEP / steps[j]);
        *jerk = std::array::from_fn(|c| {
            -(l * l * l * motion.position[c] + 3.0 * l * l * motion.rate[c] + 3.0 * l * motion.acceleration[c])
        });
        motion.advance(jerk, steps[j]);
    }
    nominal
}

fn perception_steps(otolith: [LagStep; 2], canal: [LagStep; 3]) -> crate::physics::cueing::perception::PerceptionSteps {
    crate::physics::cueing::perception::PerceptionSteps { otolith, canal }
}

/// The head point as a vector (for callers building a [`PredictiveStand`]).
pub fn head_vector(head: &[f64; 3]) -> Vector3<f64> {
    Vector3::new(head[0], head[1], head[2])
}

#[cfg(test)]
mod tests {
    use super::super::DEFAULT_PREDICTIVE;
    use super::*;

    /// The motion of `plan` (jerks per step of the grid `times`) from `start`, `t` later.
    fn motion_at(
        start: &CommandedMotion,
        times: &[f64; GRID_STEPS + 1],
        plan: &[[f64; CHANNELS]; GRID_STEPS],
        t: f64,
    ) -> CommandedMotion {
        let mut m = *start;
        for k in 0..GRID_STEPS {
            if t <= times[k] {
                break;
            }
            m.advance(&plan[k], t.min(times[k + 1]) - times[k]);
        }
        if t > times[GRID_STEPS] {
            m.advance(&[0.0; CHANNELS], t - times[GRID_STEPS]);
        }
        m
    }

    /// The nominal plan a period later follows the last plan: the same acceleration at every
    /// grid point (to round-off), the position within 5 cm over the 2 s horizon with jumps
    /// of 200 m/s³ at every step (3.4 cm measured); the rule it replaced (each step the jerk
    /// at one instant) put it 2 m off.
    #[test]
    fn the_shifted_plan_follows_the_last_plan() {
        let (_, times) = grid(&DEFAULT_PREDICTIVE);
        let period = DEFAULT_PREDICTIVE.period;
        let plan: [[f64; CHANNELS]; GRID_STEPS] =
            std::array::from_fn(|k| std::array::from_fn(|c| if (k + c) % 2 == 0 { 100.0 } else { -100.0 }));
        let start =
            CommandedMotion { position: [0.1; CHANNELS], rate: [-0.2; CHANNELS], acceleration: [0.5; CHANNELS] };
        let later = motion_at(&start, &times, &plan, period);
        let nominal = shifted_plan(&times, period, &plan);
        let (mut worst_a, mut worst_p) = (0.0f64, 0.0f64);
        let mut m = later;
        for j in 0..GRID_STEPS {
            m.advance(&nominal[j], times[j + 1] - times[j]);
            let want = motion_at(&start, &times, &plan, times[j + 1] + period);
            for c in 0..CHANNELS {
                worst_a = worst_a.max((m.acceleration[c] - want.acceleration[c]).abs());
                worst_p = worst_p.max((m.position[c] - want.position[c]).abs());
            }
        }
        // The point rule, for contrast.
        let point: [[f64; CHANNELS]; GRID_STEPS] = std::array::from_fn(|j| {
            let t = times[j] + period;
            plan[times[1..].partition_point(|&end| end <= t)]
        });
        let mut m = later;
        let mut point_p = 0.0f64;
        for j in 0..GRID_STEPS {
            m.advance(&point[j], times[j + 1] - times[j]);
            let want = motion_at(&start, &times, &plan, times[j + 1] + period);
            point_p = point_p.max((m.position[0] - want.position[0]).abs());
        }
        println!(
            "2 s ahead: the mean rule {worst_p:.2e} m off the last plan (acceleration {worst_a:.1e}), the point rule {point_p:.2e} m"
        );
        assert!(worst_a < 1e-10, "acceleration off by {worst_a:e}");
        assert!(worst_p < 0.05, "position off by {worst_p:e} m");
        assert!(point_p > 20.0 * worst_p);
    }

    /// After a failed solve the nominal plan brings the command back to neutral: from a
    /// washout's motion (0.1, 0.5 /s, 5 /s² in every channel) the largest excursion over the
    /// horizon is under 5 % of the zero jerks' (which hold the acceleration: 11.1 at 2 s) and
    /// the horizon ends within a fifth of it.
    #[test]
    fn the_returning_plan_comes_back_to_neutral() {
        let (steps, times) = grid(&DEFAULT_PREDICTIVE);
        let start = CommandedMotion { position: [0.1; CHANNELS], rate: [0.5; CHANNELS], acceleration: [5.0; CHANNELS] };
        let nominal = returning_plan(&steps, &start);
        let mut m = start;
        let mut largest = 0.0f64;
        for j in 0..GRID_STEPS {
            m.advance(&nominal[j], steps[j]);
            largest = largest.max(m.position[0].abs());
        }
        let held = motion_at(&start, &times, &[[0.0; CHANNELS]; GRID_STEPS], times[GRID_STEPS]);
        println!(
            "largest excursion {largest:.3} (zero jerks: {:.2}), at the horizon's end {:.3}",
            held.position[0], m.position[0]
        );
        assert!(largest < 0.05 * held.position[0] && m.position[0].abs() < 0.2 * largest);
    }
}
