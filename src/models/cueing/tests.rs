//! The cueing model's unit tests.

use super::*;
use crate::physics::stand::LEG_COUNT;

/// The default washout after 1.5 s of braking in a left curve, or (`limited`) one that
/// leaves the workspace on a sustained braking in a left curve (full scale,
/// a slow return), so that the limiter acts.
fn moving_model(limited: bool) -> CueingModel {
    let mut m = CueingModel::default();
    if limited {
        let w = &mut m.parameters.washout;
        w.scale_f = [1.0; 3];
        w.scale_omega = [1.0; 3];
        w.hp_f_break = [0.1; 3];
        w.hp_f_omega = [1.0, 1.0, 2.0];
    }
    m.vehicle = if limited {
        VehicleMotion { f: [-4.0, 3.0, 11.0], omega: [0.05, -0.04, 0.3] }
    } else {
        VehicleMotion { f: [-1.5, 1.0, 10.3], omega: [0.05, -0.04, 0.3] }
    };
    m.parameters.validate().unwrap();
    for _ in 0..150 {
        m.state = CueingStates::from_vector(&m.integrate(0.01));
    }
    m
}

impl CueingModel {
    /// The washout's states `h` (either sign) ahead, the inputs held.
    fn integrate(&self, h: f64) -> [f64; STATE_DIM] {
        let mut x = self.state.to_vector();
        let n = (h.abs() / 1e-3).ceil().max(1.0);
        for i in 0..n as usize {
            let tau = i as f64 * h / n;
            x = stepping::washout_rk4(&self.parameters.washout, &x, &self.tilt_modes, tau, h / n, &|_| {
                self.vehicle
            });
        }
        x
    }

    fn outputs_at(&self, x: &[f64; STATE_DIM]) -> CueingOutputs {
        let c = self.command(x, &self.vehicle, &self.tilt_modes, &self.predictive_state.motion);
        CueingOutputs::of(&c, &self.perception.vehicle(), &self.perception.simulator())
    }
}

/// The pose command's velocity and acceleration (through the washout's jets and the
/// limiter's Newton steps on jets) against central differences of the command along the
/// motion, the inputs held: the limiter acting, and not.
#[test]
fn the_command_carries_its_exact_derivatives() {
    for limited in [true, false] {
        let m = moving_model(limited);
        let now = m.outputs_at(&m.state.to_vector());
        assert_eq!(now.limited, limited, "usage {}", now.usage);
        let d = 1e-4;
        let at = |h: f64| m.outputs_at(&m.integrate(h));
        let (ahead, behind) = (at(d), at(-d));
        for i in 0..3 {
            let v = (ahead.r[i] - behind.r[i]) / (2.0 * d);
            let a = (ahead.r[i] - 2.0 * now.r[i] + behind.r[i]) / (d * d);
            let rate = (ahead.angles[i] - behind.angles[i]) / (2.0 * d);
            let accel = (ahead.angles[i] - 2.0 * now.angles[i] + behind.angles[i]) / (d * d);
            assert!((now.v[i] - v).abs() < 1e-7, "limited {limited}: v[{i}] {} against {v}", now.v[i]);
            assert!((now.a[i] - a).abs() < 1e-3, "limited {limited}: a[{i}] {} against {a}", now.a[i]);
            assert!(
                (now.angle_rates[i] - rate).abs() < 1e-8,
                "angleRates[{i}] {} against {rate}",
                now.angle_rates[i]
            );
            assert!(
                (now.angle_accelerations[i] - accel).abs() < 1e-4,
                "angleAccelerations[{i}] {} against {accel}",
                now.angle_accelerations[i]
            );
        }
    }
}

/// Every leg of the limited command stays inside `[lmin + margin, lmax - margin]` while
/// the washout's own pose would leave it.
#[test]
fn the_limited_command_keeps_the_legs_inside_their_margins() {
    let m = moving_model(true);
    let o = m.outputs_at(&m.state.to_vector());
    assert!(o.usage > 1.0, "the washout's own pose leaves the workspace (usage {})", o.usage);
    let ws = m.parameters.workspace();
    let dr = [0, 1, 2].map(|i| o.r[i] - m.parameters.neutral[i]);
    for k in 0..LEG_COUNT {
        let l = ws.leg_length(k, &dr, &o.angles);
        assert!(
            l > ws.lower[k] && l < ws.upper[k],
            "leg {}: {l} outside [{}, {}]",
            k + 1,
            ws.lower[k],
            ws.upper[k]
        );
    }
}

/// The variables' descriptions quote facts the code holds elsewhere: the guess's clip, the
/// thresholds of perception, the solver's tolerances, the grid and its blocks. The text must
/// follow the constants (a description is a `&'static str`, so it cannot be formatted from
/// them).
#[test]
fn the_descriptions_quote_the_constants_they_describe() {
    use crate::control::predictive_cueing::{
        BLOCKS, GRID_STEPS, GUESS_LIMIT_F, GUESS_LIMIT_OMEGA, QP_ACCEPTABLE_TOLERANCE, QP_TOLERANCE,
    };
    use crate::physics::cueing::perception::{THRESHOLD_F, THRESHOLD_OMEGA};
    use variables::{GROUPS, group};
    let quotes = |id: usize, fact: String| {
        let text = GROUPS[id].description;
        assert!(text.contains(&fact), "{}'s description does not say {fact:?}: {text}", GROUPS[id].name);
    };
    quotes(group::MPC_TREND, format!("within {GUESS_LIMIT_F} m/s2 and {GUESS_LIMIT_OMEGA} rad/s"));
    let [f1, f2, f3] = THRESHOLD_F;
    quotes(group::MPC_WEIGHT_F, format!("({f1}, {f2}, {f3} m/s2)"));
    let [w1, w2, w3] = THRESHOLD_OMEGA.map(f64::to_degrees);
    quotes(group::MPC_WEIGHT_OMEGA, format!("({w1:.1}, {w2:.1}, {w3:.1} deg/s)"));
    quotes(group::MPC_MAX_ITERATIONS, format!("within {QP_ACCEPTABLE_TOLERANCE:e}"));
    quotes(group::MPC_ACCEPTABLE, format!("acceptable level ({QP_ACCEPTABLE_TOLERANCE:e}"));
    quotes(group::MPC_ACCEPTABLE, format!("tolerance ({QP_TOLERANCE:e})"));
    let [b1, b2, b3, b4] = BLOCKS;
    let grid = format!("({GRID_STEPS} grid steps; the jerks in 4 blocks of {b1}, {b2}, {b3} and {b4} steps)");
    quotes(group::MPC_HORIZON, grid);
}
