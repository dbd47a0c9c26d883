//! Leg geometry of a state: attachment arms, lengths, unit directions and length rates.
//! Computed once per right-hand-side evaluation and shared by the force law and the
//! special-form accelerations (no recomputation of the geometry).

use nalgebra::Vector3;

use super::body_state::BodyState;
use super::stand::{LEG_COUNT, Stand};

/// Geometry of the six legs for one state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LegGeometry {
    /// Arms `R A_k` from the centre of mass to platform joint k, inertial components, m.
    pub arm: [Vector3<f64>; LEG_COUNT],
    /// Leg lengths `l_k`, m.
    pub length: [f64; LEG_COUNT],
    /// Unit leg directions `n_k = (a_k - B_k) / l_k` (zero for a collapsed leg, never NaN).
    pub direction: [Vector3<f64>; LEG_COUNT],
}

impl LegGeometry {
    #[inline(always)]
    pub fn new(stand: &Stand, state: &BodyState) -> Self {
        let mut arm = [Vector3::zeros(); LEG_COUNT];
        let mut length = [0.0; LEG_COUNT];
        let mut direction = [Vector3::zeros(); LEG_COUNT];
        for k in 0..LEG_COUNT {
            arm[k] = state.body_vector(&stand.platform_joints[k]);
            let leg = state.r + arm[k] - stand.base_joints[k];
            length[k] = leg.norm();
            // One division, three multiplications.
            direction[k] = if length[k] > 0.0 { leg * (1.0 / length[k]) } else { Vector3::zeros() };
        }
        LegGeometry { arm, length, direction }
    }

    /// Leg length rates `dl_k/dt = n_k . (v + d(R A_k)/dt)`, m/s.
    #[inline(always)]
    pub fn length_rates(&self, stand: &Stand, state: &BodyState) -> [f64; LEG_COUNT] {
        let mut rates = [0.0; LEG_COUNT];
        for k in 0..LEG_COUNT {
            rates[k] = self.direction[k].dot(&(state.v + state.body_vector_rate(&stand.platform_joints[k])));
        }
        rates
    }

    /// Resultant force `sum_k u_k n_k` and moment about the centre of mass
    /// `L = sum_k (R A_k) x (u_k n_k)` of the leg forces `u`.
    #[inline(always)]
    pub fn resultant(&self, u: &[f64; LEG_COUNT]) -> (Vector3<f64>, Vector3<f64>) {
        let mut force = Vector3::zeros();
        let mut moment = Vector3::zeros();
        for k in 0..LEG_COUNT {
            let f = self.direction[k] * u[k];
            force += f;
            moment += self.arm[k].cross(&f);
        }
        (force, moment)
    }
}
