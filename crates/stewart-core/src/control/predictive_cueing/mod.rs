//! Predictive motion cueing (SPEC §12, docs/cueing.md "Predictive cueing"): every
//! `mpc.period` an optimal control problem over `mpc.horizon` chooses the commanded head
//! motion and attitude (triple integrators driven by their jerks, [`motion`]) so that what the
//! driver would perceive of the simulator's motion (the vestibular model of
//! [`crate::physics::cueing::perception`]) follows what they would perceive of the vehicle's,
//! with every leg kept inside its margins and the tilt and leg speeds limited.
//!
//! The problem is condensed onto the jerks (one per channel and input block, [`BLOCKS`]),
//! linearised about the previous plan (its cues and legs, [`linearisation`]) and built in
//! [`problem`]; a dense interior-point method ([`crate::optimisation::dense`]) solves it. Pure: the FMU
//! (`stewart_fmu::models::cueing`) holds the state, reads the preview file, and hands a
//! failed solve to the classical washout.

pub mod linearisation;
pub mod motion;
pub mod problem;

use nalgebra::Vector3;

use crate::optimisation::dense::{DenseQp, QpOutcome, QpSettings};
use crate::physics::cueing::limiter::Workspace;
use crate::physics::cueing::perception::Perception;
use crate::physics::cueing::washout::VehicleMotion;
use motion::{CHANNELS, CommandedMotion};
use problem::Problem;

/// Grid steps over the horizon: the cues are predicted and weighed at their ends.
pub const GRID_STEPS: usize = 20;
/// The input blocks, in grid steps: over each the jerks are one unknown per channel (the
/// first block short, the later ones long: decisions far ahead are re-made before they act).
pub const BLOCKS: [usize; 4] = [1, 2, 4, 13];
/// The grid points (steps from now) at which the constraints hold: the blocks' ends.
pub const CONSTRAINED: [usize; 4] = [1, 3, 7, 20];
/// Unknowns of the QP: a jerk per channel and block.
pub const UNKNOWNS: usize = CHANNELS * BLOCKS.len();
/// Inequalities per constrained point: each leg's length and speed (upper and lower), the
/// roll and pitch rates and angles (upper and lower).
pub const ROWS_PER_POINT: usize = 2 * 6 + 2 * 6 + 2 * 2 + 2 * 2;
/// Inequalities of the constrained points.
pub const INEQUALITIES: usize = ROWS_PER_POINT * CONSTRAINED.len();
/// The QP's unknowns: the jerks and one slack by which every inequality may give.
pub const QP_UNKNOWNS: usize = UNKNOWNS + 1;
/// The slack's place among them.
pub const SLACK: usize = UNKNOWNS;
/// The QP's inequalities: the points' and the slack's own (`slack >= 0`).
pub const QP_ROWS: usize = INEQUALITIES + 1;
/// Share of each leg's stroke (from its neutral length to `lmin + margin` or `lmax - margin`)
/// the plans may use at the constrained points: the rest absorbs the motion between them and
/// the linearisation's error, before the workspace limiter's net (`Workspace::net`) would
/// have to act.
pub const STROKE_SHARE: f64 = 0.9;

/// The predictive method's parameters (SI units; defaults and reasons: docs/cueing.md).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PredictiveParameters {
    /// `mpc.period`, s: time between solves.
    pub period: f64,
    /// `mpc.horizon`, s.
    pub horizon: f64,
    /// `mpc.trust`, s: the perceived errors at `tau` ahead weigh `exp(-tau/trust)` where the
    /// vehicle's motion is guessed ([`guess`]); where a preview knows it they weigh 1.
    pub trust: f64,
    /// `mpc.trend`, s: the guess of the vehicle's future goes on with the inputs' rate of change
    /// over the last solve period for about this long ([`guess`]); 0 holds the inputs.
    pub trend: f64,
    /// `mpc.weight.f[i]`: per squared threshold of perceived specific-force error.
    pub weight_f: [f64; 3],
    /// `mpc.weight.omega[i]`: per squared threshold of perceived angular-velocity error.
    pub weight_omega: [f64; 3],
    /// `mpc.weight.neutral`: per m² of the head's displacement and per rad² of yaw.
    pub weight_neutral: f64,
    /// `mpc.weight.input`: per (m/s³)² of head jerk (angular jerks count times g²).
    pub weight_input: f64,
    /// `mpc.legSpeed`, m/s.
    pub leg_speed: f64,
    /// `tilt.rateLimit`, rad/s: the simulator's roll and pitch rates may exceed the vehicle's
    /// by this much at most.
    pub tilt_rate_limit: f64,
    /// `tilt.max`, rad: the largest roll and pitch.
    pub tilt_max: f64,
    /// `mpc.maxIterations`: a solve that does not converge within it takes its last iterate
    /// within [`QP_ACCEPTABLE_TOLERANCE`], or (none) fails.
    pub max_iterations: u32,
}

/// The default truck cabin's tuning (docs/cueing.md).
pub const DEFAULT_PREDICTIVE: PredictiveParameters = PredictiveParameters {
    period: 0.01,
    horizon: 2.0,
    trust: 0.6,
    trend: 1.0,
    weight_f: [1.0, 1.0, 4.0],
    weight_omega: [1.0, 1.0, 1.0],
    weight_neutral: 10.0,
    weight_input: 1e-3,
    leg_speed: 0.5,
    tilt_rate_limit: 3.0 * std::f64::consts::PI / 180.0,
    tilt_max: 10.0 * std::f64::consts::PI / 180.0,
    max_iterations: 30,
};

const GRID_GROWTH_TEXT: &str = "a factor 1.1";

/// The QP solver's relative tolerance (residuals and complementarity).
pub const QP_TOLERANCE: f64 = 1e-8;
/// The tolerance a solve that ends without reaching [`QP_TOLERANCE`] (out of iterations, or
/// broken down) is still used at, relative as that one is: a plan re-made a period later
/// (docs/cueing.md, "A failed solve").
pub const QP_ACCEPTABLE_TOLERANCE: f64 = 1e-6;

impl PredictiveParameters {
    /// Why the parameters cannot be used, naming the parameter.
    pub fn validate(&self) -> Result<(), String> {
        let positive = |name: &str, x: f64| {
            if x > 0.0 && x.is_finite() { Ok(()) } else { Err(format!("parameter {name}: must be > 0, got {x:?}")) }
        };
        positive("mpc.period", self.period)?;
        positive("mpc.horizon", self.horizon)?;
        positive("mpc.trust", self.trust)?;
        if !(self.trend >= 0.0 && self.trend.is_finite()) {
            return Err(format!("parameter mpc.trend: must be >= 0 (0 holds the inputs), got {:?}", self.trend));
        }
        positive("mpc.weight.input", self.weight_input)?;
        positive("mpc.legSpeed", self.leg_speed)?;
        positive("tilt.rateLimit", self.tilt_rate_limit)?;
        let first = self.first_grid_step();
        if !(self.period <= first * (1.0 + 1e-12)) {
            return Err(format!(
                "parameter mpc.period: {:?} s is longer than the plans' first step ({first:.4e} s, the horizon \
                 mpc.horizon = {:?} s over 20 steps growing by {GRID_GROWTH_TEXT}): the first block's jerks would be \
                 held past the step they were planned for; shorten the period or lengthen the horizon",
                self.period, self.horizon
            ));
        }
        for (name, w) in [("mpc.weight.f", &self.weight_f), ("mpc.weight.omega", &self.weight_omega)] {
            for (i, &x) in w.iter().enumerate() {
                if !(x >= 0.0 && x.is_finite()) {
                    return Err(format!("parameter {name}[{}]: must be >= 0, got {x:?}", i + 1));
                }
            }
        }
        if !(self.weight_neutral >= 0.0 && self.weight_neutral.is_finite()) {
            return Err(format!("parameter mpc.weight.neutral: must be >= 0, got {:?}", self.weight_neutral));
        }
        if self.max_iterations == 0 {
            return Err("parameter mpc.maxIterations: must be at least 1".into());
        }
        Ok(())
    }

    /// The grid's first step, s: `h_0` of `h_j = h_0 GRID_GROWTH^j` summing to the horizon.
    pub fn first_grid_step(&self) -> f64 {
        let g = problem::GRID_GROWTH;
        self.horizon * (g - 1.0) / (crate::maths::pow(g, GRID_STEPS as f64) - 1.0)
    }
}

/// The largest change of the horizontal specific force (m/s²) and of the angular velocity
/// (rad/s) a [`guess`] extrapolates: the bounds of the drives the method is tested on, so that
/// a noisy input's difference quotient cannot make the guess leave them.
pub const GUESS_LIMIT_F: f64 = 8.0;
pub const GUESS_LIMIT_OMEGA: f64 = 0.5;

/// The vehicle's motion `tau` ahead guessed from its motion `now` and its inputs' rate of
/// change `rate` (`d f / dt`, m/s³, then `d omega / dt`, rad/s², cabin axes): the horizontal
/// specific force and the angular velocity go on at that rate, fading over `trend` s, `rate
/// trend (1 - exp(-tau / trend))` (within [`GUESS_LIMIT_F`], [`GUESS_LIMIT_OMEGA`]); the vertical
/// specific force is held. `trend = 0` holds the inputs. A ramp (a braking's onset and end,
/// a lane change's swing) is seen coming for the second or so its rate lasts; a held guess
/// sees only the level reached.
pub fn guess(now: &VehicleMotion, rate: &[f64; 6], trend: f64, tau: f64) -> VehicleMotion {
    if !(trend > 0.0) {
        return *now;
    }
    let reach = trend * (1.0 - crate::maths::exp(-tau / trend));
    let change = |i: usize, limit: f64| (rate[i] * reach).clamp(-limit, limit);
    VehicleMotion {
        f: [now.f[0] + change(0, GUESS_LIMIT_F), now.f[1] + change(1, GUESS_LIMIT_F), now.f[2]],
        omega: std::array::from_fn(|i| now.omega[i] + change(3 + i, GUESS_LIMIT_OMEGA)),
    }
}

/// The stand as the predictive method sees it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PredictiveStand {
    /// The legs, their margins (`lmin + margin`, `lmax - margin`) and the neutral pose.
    pub workspace: Workspace,
    /// The head point, body frame from the centre of mass, m.
    pub head: Vector3<f64>,
    /// `g`, m/s².
    pub gravity: f64,
}

/// What a solve found.
#[derive(Clone, Copy, Debug, PartialEq)]
// Returned by value once per solve: boxing the plan would allocate in the step.
#[allow(clippy::large_enum_variant)]
pub enum SolveOutcome {
    /// The new plan: jerks per grid step (its first are the next period's); `acceptable`
    /// where the solve kept an iterate within [`QP_ACCEPTABLE_TOLERANCE`] only (out of
    /// iterations, or broken down), not one within [`QP_TOLERANCE`].
    Planned { iterations: u32, plan: [[f64; CHANNELS]; GRID_STEPS], acceptable: bool },
    /// No plan: the period goes to the classical washout.
    Failed { iterations: u32, why: &'static str },
}

/// The predictive method: the QP and its buffers (no state of the motion: the caller holds
/// the commanded motion and the plan). Allocates when made, never after.
#[derive(Debug)]
pub struct PredictiveCueing {
    pub parameters: PredictiveParameters,
    pub stand: PredictiveStand,
    qp: DenseQp,
    problem: Box<Problem>,
}

impl PredictiveCueing {
    pub fn new(parameters: PredictiveParameters, stand: PredictiveStand) -> Result<Self, String> {
        parameters.validate()?;
        let qp = DenseQp::new(
            QP_UNKNOWNS,
            QP_ROWS,
            QpSettings {
                max_iterations: parameters.max_iterations,
                tolerance: QP_TOLERANCE,
                acceptable_tolerance: QP_ACCEPTABLE_TOLERANCE,
            },
        )?;
        let problem = Box::new(Problem::new(&parameters, &stand));
        Ok(PredictiveCueing { parameters, stand, qp, problem })
    }

    /// The grid's points, s after a solve: where the vehicle's motion is wanted.
    pub fn grid_times(&self) -> &[f64; GRID_STEPS + 1] {
        self.problem.times()
    }

    /// Plans from the commanded motion `now` and the last plan (what this solve linearises
    /// about, shifted by the period; `None` after a failed solve: a return to neutral from
    /// `now`, [`Problem::returning_inputs`]), with the vehicle's motion at the grid's points
    /// (`vehicle[j]` at `j` grid steps ahead, `vehicle[0]` now), how far ahead that motion is
    /// known (`known`, s: 0 for the inputs held, a preview's end less now) and the lags of both
    /// perceptions now.
    #[allow(clippy::too_many_arguments)]
    pub fn solve(
        &mut self,
        now: &CommandedMotion,
        plan: Option<&[[f64; CHANNELS]; GRID_STEPS]>,
        vehicle: &[VehicleMotion; GRID_STEPS + 1],
        known: f64,
        perceived_vehicle: &Perception,
        perceived_simulator: &Perception,
    ) -> SolveOutcome {
        let nominal = match plan {
            Some(plan) => self.problem.nominal_inputs(plan),
            None => self.problem.returning_inputs(now),
        };
        self.problem.build(
            &self.parameters,
            &self.stand,
            now,
            &nominal,
            vehicle,
            known,
            perceived_vehicle,
            perceived_simulator,
        );
        let p = &mut *self.problem;
        let outcome = self.qp.solve(&p.hessian, &p.gradient, &p.constraints, &p.bounds, &mut p.solution);
        match outcome {
            QpOutcome::Solved { iterations } | QpOutcome::Acceptable { iterations } => SolveOutcome::Planned {
                iterations,
                plan: p.plan(&nominal),
                acceptable: matches!(outcome, QpOutcome::Acceptable { .. }),
            },
            QpOutcome::Failed { iterations, why } => SolveOutcome::Failed { iterations, why },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The guess against its closed form: a held level with `trend = 0`, the rate's fading
    /// extrapolation otherwise (to `rate trend` far ahead), the limits, the vertical held.
    #[test]
    fn the_guess_goes_on_with_the_rate_and_fades() {
        let now = VehicleMotion { f: [-1.0, 0.5, 9.81], omega: [0.0, 0.1, -0.2] };
        let rate = [-2.0, 3.0, 50.0, 0.1, -0.2, 40.0];
        assert_eq!(guess(&now, &rate, 0.0, 1.5), now);
        for tau in [0.0, 0.1, 1.0, 2.0] {
            let g = guess(&now, &rate, 1.0, tau);
            let reach = 1.0 - f64::exp(-tau);
            assert!((g.f[0] - (-1.0 - 2.0 * reach)).abs() < 1e-15);
            assert!((g.f[1] - (0.5 + 3.0 * reach)).abs() < 1e-15);
            assert_eq!(g.f[2], 9.81);
            assert!((g.omega[0] - 0.1 * reach).abs() < 1e-15);
            assert!((g.omega[1] - (0.1 - 0.2 * reach)).abs() < 1e-15);
            assert!((g.omega[2] - (-0.2 + (40.0 * reach).min(GUESS_LIMIT_OMEGA))).abs() < 1e-15);
        }
        let far = guess(&now, &[100.0, 0.0, 0.0, 0.0, 0.0, 0.0], 1.0, 2.0);
        assert_eq!(far.f[0], -1.0 + GUESS_LIMIT_F);
    }
}
