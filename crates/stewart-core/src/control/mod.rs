//! Programme motion control of the paper's section 7: leg forces from the direct problem
//! plus feedback on the leg lengths,
//!
//! ```text
//! F_k = F_k^p(t) + G (l_k^p(t) - l_k) + D (ldot_k^p(t) - ldot_k)  (+ a disturbance)
//! ```
//!
//! with programme forces `F^p` and programme leg lengths `l^p` from the direct problem and
//! inverse kinematics ([`crate::physics::direct_problem`]), measured lengths `l` and rates
//! `ldot`. Pure functions; the controller FMU (`stewart_fmu::models::controller`) wraps them.

pub mod predictive_cueing;

use crate::maths;
use crate::physics::direct_problem::DirectProblemSolution;
use crate::physics::stand::LEG_COUNT;

/// Gains of the leg-length feedback.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LegFeedback {
    /// `G`, N/m: force per metre of leg-length error.
    pub gain: f64,
    /// `D`, N s/m: force per m/s of leg-rate error.
    pub damping: f64,
    /// Whether the programme forces `F^p` are fed forward (the paper also tries `F^p = 0`).
    pub feedforward: bool,
}

impl LegFeedback {
    /// Leg forces for the programme at one instant and the measured legs. A measured length
    /// that is not positive and finite is no measurement (a co-simulation master may still
    /// have zeros on its connections before the first exchange): that leg gets its
    /// programme force only.
    pub fn leg_forces(
        &self,
        programme: &DirectProblemSolution,
        l: &[f64; LEG_COUNT],
        ldot: &[f64; LEG_COUNT],
    ) -> [f64; LEG_COUNT] {
        let mut f = [0.0; LEG_COUNT];
        for k in 0..LEG_COUNT {
            let feedforward = if self.feedforward { programme.forces[k] } else { 0.0 };
            let measured = l[k].is_finite() && l[k] > 0.0 && ldot[k].is_finite();
            f[k] = if measured {
                feedforward + self.gain * (programme.lengths[k] - l[k]) + self.damping * (programme.rates[k] - ldot[k])
            } else {
                feedforward
            };
        }
        f
    }
}

/// The paper's force perturbation, `amplitude sin(frequency t) (1 - exp(-t / time_constant))`
/// (section 6: `0.0001 sin 2t (1 - exp(-t/2))` in non-dimensional units).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Disturbance {
    /// N
    pub amplitude: f64,
    /// rad/s
    pub frequency: f64,
    /// s; 0 = no soft start
    pub time_constant: f64,
}

impl Disturbance {
    #[inline]
    pub fn at(&self, t: f64) -> f64 {
        if self.amplitude == 0.0 {
            return 0.0;
        }
        // Soft-started at t = 0; nothing before (the formula would overflow for t far below 0).
        let soft = if self.time_constant > 0.0 { (1.0 - maths::exp(-t / self.time_constant)).max(0.0) } else { 1.0 };
        self.amplitude * maths::sin(self.frequency * t) * soft
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn feedback_law_and_missing_measurements() {
        let p = DirectProblemSolution { forces: [1.0; 6], lengths: [2.0; 6], rates: [0.5; 6] };
        let fb = LegFeedback { gain: 10.0, damping: 2.0, feedforward: true };
        let l = [1.9, 2.0, 2.1, 0.0, f64::NAN, 2.0];
        let ld = [0.5, 0.0, 0.5, 0.5, 0.5, 0.5];
        let f = fb.leg_forces(&p, &l, &ld);
        assert!((f[0] - 2.0).abs() < 1e-12); // 1 + 10 * 0.1
        assert!((f[1] - 2.0).abs() < 1e-12); // 1 + 2 * 0.5
        assert!((f[2] - 0.0).abs() < 1e-12);
        assert_eq!(f[3], 1.0); // no measurement yet
        assert_eq!(f[4], 1.0);
        let no_ff = LegFeedback { feedforward: false, ..fb }.leg_forces(&p, &l, &ld);
        assert!((no_ff[0] - 1.0).abs() < 1e-12);
    }
}
