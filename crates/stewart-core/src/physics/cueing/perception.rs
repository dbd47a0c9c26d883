//! What a driver perceives (SPEC §12; docs/cueing.md): the vestibular organs as linear filters
//! per cabin axis, applied alike to the vehicle's motion and to the simulator's.
//!
//! ```text
//! otoliths (specific force):   OTO(s) = (tau_oa s + 1) / ((tau_oL s + 1)(tau_oS s + 1))
//! canals (angular velocity):   SCC(s) = tau_1 tau_a s^2 / ((tau_1 s + 1)(tau_2 s + 1)(tau_a s + 1))
//! ```
//!
//! Both have real, distinct poles, so each is a sum of first-order lags of its input with unit
//! gain at rest, `sum_i c_i / (tau_i s + 1)` (partial fractions, [`VestibularFilter::weights`]):
//! its states are the input lagged by each time constant (the cue's own unit), its output
//! `sum_i c_i x_i`. At rest every lag equals the input, so the otoliths start at `g ez` and
//! the canals at zero. A lag advances exactly over a step on which its input is linear
//! ([`VestibularFilter::advance`]): the vehicle's inputs are (held, or following their
//! first derivatives), and the predictive method's horizon takes the simulator's cues so.

use crate::maths;

/// `tau_oa`, s: the otoliths' lead.
pub const OTOLITH_LEAD: f64 = 10.0;
/// `tau_oL`, s: the otoliths' long lag.
pub const OTOLITH_LONG: f64 = 5.0;
/// `tau_oS`, s: the otoliths' short lag.
pub const OTOLITH_SHORT: f64 = 0.016;
/// `tau_1`, s: the canals' long time constant.
pub const CANAL_LONG: f64 = 5.73;
/// `tau_2`, s: the canals' short time constant.
pub const CANAL_SHORT: f64 = 0.005;
/// `tau_a`, s: the canals' adaptation.
pub const CANAL_ADAPTATION: f64 = 80.0;
/// Thresholds of perception (Reid and Nahon 1985): specific force per cabin axis, m/s².
pub const THRESHOLD_F: [f64; 3] = [0.17, 0.17, 0.28];
/// Thresholds of perception: angular velocity per cabin axis (roll, pitch, yaw), rad/s
/// (3.0, 3.6, 2.6 deg/s).
pub const THRESHOLD_OMEGA: [f64; 3] =
    [3.0 * std::f64::consts::PI / 180.0, 3.6 * std::f64::consts::PI / 180.0, 2.6 * std::f64::consts::PI / 180.0];

/// A vestibular filter as `K` first-order lags with unit gain at rest (see the module).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VestibularFilter<const K: usize> {
    /// The lags' time constants, s.
    pub tau: [f64; K],
    /// Their weights `c_i` in the output.
    pub weights: [f64; K],
}

/// The otoliths' filter: lags of `tau_oL` and `tau_oS`, weights from `OTO`'s partial
/// fractions: `c_L = (tau_oL - tau_oa)/(tau_oL - tau_oS)`, `c_S = (tau_oa - tau_oS)/(tau_oL -
/// tau_oS)` (they sum to 1, the gain at rest).
pub const OTOLITH: VestibularFilter<2> = VestibularFilter {
    tau: [OTOLITH_LONG, OTOLITH_SHORT],
    weights: [
        (OTOLITH_LONG - OTOLITH_LEAD) / (OTOLITH_LONG - OTOLITH_SHORT),
        (OTOLITH_LEAD - OTOLITH_SHORT) / (OTOLITH_LONG - OTOLITH_SHORT),
    ],
};

/// `SCC`'s residue at the pole `-1/tau_i` (the other two time constants `tau_j`, `tau_k`):
/// `c_i = tau_1 tau_a s^2 / ((tau_j s + 1)(tau_k s + 1))` at `s = -1/tau_i`.
const fn canal_weight(tau_i: f64, tau_j: f64, tau_k: f64) -> f64 {
    let s = -1.0 / tau_i;
    CANAL_LONG * CANAL_ADAPTATION * s * s / ((tau_j * s + 1.0) * (tau_k * s + 1.0))
}

/// The canals' filter: lags of `tau_1`, `tau_2`, `tau_a` (weights summing to 0: no gain at
/// rest).
pub const CANAL: VestibularFilter<3> = VestibularFilter {
    tau: [CANAL_LONG, CANAL_SHORT, CANAL_ADAPTATION],
    weights: [
        canal_weight(CANAL_LONG, CANAL_SHORT, CANAL_ADAPTATION),
        canal_weight(CANAL_SHORT, CANAL_LONG, CANAL_ADAPTATION),
        canal_weight(CANAL_ADAPTATION, CANAL_LONG, CANAL_SHORT),
    ],
};

/// How a lag of time constant `tau` advances over a step `h` on which its input goes linearly
/// from `y0` to `y1`: `x1 = decay x0 + from_start y0 + from_end y1` (exact).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LagStep {
    pub decay: f64,
    pub from_start: f64,
    pub from_end: f64,
}

impl LagStep {
    /// The step of `h >= 0`: with `e = exp(-h/tau)`, `from_end = 1 - tau (1 - e)/h` and
    /// `from_start = 1 - e - from_end` (none at all for `h = 0`).
    pub fn new(tau: f64, h: f64) -> LagStep {
        if h == 0.0 {
            return LagStep { decay: 1.0, from_start: 0.0, from_end: 0.0 };
        }
        let e = maths::exp(-h / tau);
        // 1 - e, accurate when h << tau.
        let one_minus_e = -maths::exp_m1(-h / tau);
        let from_end = 1.0 - tau * one_minus_e / h;
        LagStep { decay: e, from_start: one_minus_e - from_end, from_end }
    }

    #[inline]
    pub fn apply(&self, x: f64, y0: f64, y1: f64) -> f64 {
        self.decay * x + self.from_start * y0 + self.from_end * y1
    }
}

impl<const K: usize> VestibularFilter<K> {
    /// The perceived cue of the lag states `x`.
    #[inline]
    pub fn output(&self, x: &[f64; K]) -> f64 {
        let mut out = 0.0;
        for i in 0..K {
            out += self.weights[i] * x[i];
        }
        out
    }

    /// The lags' rates for the input `y`.
    #[inline]
    pub fn rate(&self, x: &[f64; K], y: f64) -> [f64; K] {
        std::array::from_fn(|i| (y - x[i]) / self.tau[i])
    }

    /// The lags' steps of length `h`.
    pub fn steps(&self, h: f64) -> [LagStep; K] {
        self.tau.map(|tau| LagStep::new(tau, h))
    }

    /// Advances the lags over a step on which the input goes linearly from `y0` to `y1`
    /// (`steps` of that length).
    #[inline]
    pub fn advance(steps: &[LagStep; K], x: &mut [f64; K], y0: f64, y1: f64) {
        for i in 0..K {
            x[i] = steps[i].apply(x[i], y0, y1);
        }
    }

    /// The filter's transfer function at `s = j omega`, as (real, imaginary), from its lags.
    pub fn response(&self, omega: f64) -> (f64, f64) {
        let (mut re, mut im) = (0.0, 0.0);
        for i in 0..K {
            // c / (1 + j w tau) = c (1 - j w tau) / (1 + (w tau)^2)
            let wt = omega * self.tau[i];
            let d = 1.0 + wt * wt;
            re += self.weights[i] / d;
            im -= self.weights[i] * wt / d;
        }
        (re, im)
    }
}

/// The perception of one motion: per cabin axis the otoliths' two lags of the specific force
/// and the canals' three lags of the angular velocity.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Perception {
    pub otolith: [[f64; 2]; 3],
    pub canal: [[f64; 3]; 3],
}

/// The steps of every lag for one step length.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PerceptionSteps {
    pub otolith: [LagStep; 2],
    pub canal: [LagStep; 3],
}

impl PerceptionSteps {
    pub fn new(h: f64) -> Self {
        PerceptionSteps { otolith: OTOLITH.steps(h), canal: CANAL.steps(h) }
    }
}

impl Perception {
    /// At rest under the specific force `f` (the otoliths' lags at `f`, the canals' at 0).
    pub fn at_rest(f: [f64; 3]) -> Self {
        Perception { otolith: f.map(|fi| [fi; 2]), canal: [[0.0; 3]; 3] }
    }

    /// The perceived specific force and angular velocity.
    pub fn perceived(&self) -> ([f64; 3], [f64; 3]) {
        (self.otolith.map(|x| OTOLITH.output(&x)), self.canal.map(|x| CANAL.output(&x)))
    }

    /// The lags' rates for the cues `f`, `omega`.
    pub fn rate(&self, f: &[f64; 3], omega: &[f64; 3]) -> Perception {
        Perception {
            otolith: std::array::from_fn(|i| OTOLITH.rate(&self.otolith[i], f[i])),
            canal: std::array::from_fn(|i| CANAL.rate(&self.canal[i], omega[i])),
        }
    }

    /// Advances over a step on which the cues go linearly from `(f0, w0)` to `(f1, w1)`.
    pub fn advance(&mut self, steps: &PerceptionSteps, f0: &[f64; 3], w0: &[f64; 3], f1: &[f64; 3], w1: &[f64; 3]) {
        for i in 0..3 {
            VestibularFilter::advance(&steps.otolith, &mut self.otolith[i], f0[i], f1[i]);
            VestibularFilter::advance(&steps.canal, &mut self.canal[i], w0[i], w1[i]);
        }
    }

    /// The 15 lags in the FMU's order: the otoliths' (axis by axis, long then short lag),
    /// then the canals' (axis by axis: `tau_1`, `tau_2`, `tau_a`).
    pub fn to_array(&self) -> [f64; 15] {
        let mut x = [0.0; 15];
        for i in 0..3 {
            x[2 * i..2 * i + 2].copy_from_slice(&self.otolith[i]);
            x[6 + 3 * i..6 + 3 * i + 3].copy_from_slice(&self.canal[i]);
        }
        x
    }

    pub fn from_array(x: &[f64; 15]) -> Self {
        Perception {
            otolith: std::array::from_fn(|i| [x[2 * i], x[2 * i + 1]]),
            canal: std::array::from_fn(|i| [x[6 + 3 * i], x[7 + 3 * i], x[8 + 3 * i]]),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `OTO` and `SCC` at `s = j omega`, written as SPEC §12 writes them (complex arithmetic
    /// on (re, im) pairs).
    fn spec_response(otolith: bool, omega: f64) -> (f64, f64) {
        let mul = |a: (f64, f64), b: (f64, f64)| (a.0 * b.0 - a.1 * b.1, a.0 * b.1 + a.1 * b.0);
        let div = |a: (f64, f64), b: (f64, f64)| {
            let d = b.0 * b.0 + b.1 * b.1;
            ((a.0 * b.0 + a.1 * b.1) / d, (a.1 * b.0 - a.0 * b.1) / d)
        };
        let lag = |tau: f64| (1.0, omega * tau);
        if otolith {
            div((1.0, omega * OTOLITH_LEAD), mul(lag(OTOLITH_LONG), lag(OTOLITH_SHORT)))
        } else {
            let s2 = (-omega * omega * CANAL_LONG * CANAL_ADAPTATION, 0.0);
            div(s2, mul(mul(lag(CANAL_LONG), lag(CANAL_SHORT)), lag(CANAL_ADAPTATION)))
        }
    }

    /// The lags' sum is the transfer function at the OMCT's twelve frequencies and beyond.
    #[test]
    fn the_lags_are_the_transfer_functions() {
        for k in -10..=20 {
            let omega = 10f64.powf(f64::from(k) / 5.0 - 1.0);
            for otolith in [true, false] {
                let (re, im) = if otolith { OTOLITH.response(omega) } else { CANAL.response(omega) };
                let (sre, sim) = spec_response(otolith, omega);
                let scale = (sre * sre + sim * sim).sqrt().max(1e-3);
                assert!(
                    ((re - sre).abs() + (im - sim).abs()) / scale < 1e-12,
                    "{omega}: {re} {im} against {sre} {sim}"
                );
            }
        }
        assert!((OTOLITH.weights[0] + OTOLITH.weights[1] - 1.0).abs() < 1e-15);
        assert!(CANAL.weights.iter().sum::<f64>().abs() < 1e-12);
    }

    /// A lag's step is exact for a linear input: against the closed form of
    /// `x' = (a + b t - x)/tau`, `x(t) = a + b (t - tau) + (x0 - a + b tau) exp(-t/tau)`.
    #[test]
    fn a_lag_step_is_exact_for_a_linear_input() {
        for (tau, h) in [(5.0f64, 1e-3f64), (0.005, 1e-3), (0.016, 0.05), (80.0, 0.1)] {
            let (x0, a, b) = (0.3, 1.2, -4.0);
            let exact = a + b * (h - tau) + (x0 - a + b * tau) * (-h / tau).exp();
            let stepped = LagStep::new(tau, h).apply(x0, a, a + b * h);
            assert!((stepped - exact).abs() < 1e-13, "tau {tau}, h {h}: {stepped} against {exact}");
        }
    }
}
