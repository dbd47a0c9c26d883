//! Which configurations the motion may pass through: legs of nonzero length, platform joints
//! on the side of the base plane where they started, a finite state. Checked on the initial
//! pose (as parameter errors) and after every internal integration step (as faults that stop
//! the step). A singular leg arrangement is not among them: with the leg forces given, the
//! motion is regular there (the simulation reports such passages instead).

use super::body::state::BodyState;
use super::direct_problem::ForceMomentMatrix;
use super::error::{ParameterError, PhysicsFault};
use super::legs::geometry::{JointArrays, LegGeometry, LegKinematics};
use super::stand::{COINCIDENCE_TOLERANCE, LEG_COUNT, Stand};

/// The limits a stand's motion must respect, fixed when the simulation starts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConfigurationGuard {
    /// Shortest admissible leg, m.
    pub min_leg_length: f64,
    /// Height of the base plane: the mean height of the base joints, m.
    pub base_plane: f64,
    /// +1 if the platform joints started above the base plane, -1 if below (a suspended
    /// platform).
    pub side: f64,
    /// The stand's characteristic length (scales the moment rows of the force/moment matrix).
    pub characteristic_length: f64,
}

impl ConfigurationGuard {
    /// Checks the initial pose and fixes the limits for the motion that starts there.
    pub fn for_initial_state(stand: &Stand, state: &BodyState) -> Result<Self, ParameterError> {
        if !state.is_finite() {
            return Err(ParameterError::new("r0", "the initial state is not finite"));
        }
        let legs = LegGeometry::new(stand, state);
        let min_leg_length = COINCIDENCE_TOLERANCE * stand.characteristic_length().max(f64::MIN_POSITIVE);
        for k in 0..LEG_COUNT {
            if legs.length[k] <= min_leg_length {
                return Err(ParameterError::new(
                    "r0",
                    format!(
                        "leg {} has zero length in the initial pose (platform joint A[{}] coincides with base joint B[{}])",
                        k + 1,
                        k + 1,
                        k + 1
                    ),
                ));
            }
        }
        let base_plane = stand.base_joints.iter().map(|b| b.z).sum::<f64>() / LEG_COUNT as f64;
        let heights: Vec<f64> = (0..LEG_COUNT).map(|k| state.r.z + legs.arm[k].z - base_plane).collect();
        let side = if heights[0] > 0.0 { 1.0 } else { -1.0 };
        if let Some(k) = heights.iter().position(|&h| h * side <= 0.0) {
            return Err(ParameterError::new(
                "r0",
                format!(
                    "in the initial pose platform joint A[{}] is on or across the base plane (height {:e} m, \
                     while A[1] is at {:e} m)",
                    k + 1,
                    heights[k],
                    heights[0]
                ),
            ));
        }
        Ok(ConfigurationGuard {
            min_leg_length,
            base_plane,
            side,
            characteristic_length: stand.characteristic_length().max(f64::MIN_POSITIVE),
        })
    }

    /// Cheap checks for every internal step: finite state, legs not collapsed, platform
    /// joints on their side of the base plane.
    #[inline(always)]
    pub fn check(&self, joints: &JointArrays, state: &BodyState) -> Result<(), PhysicsFault> {
        if !state.is_finite() {
            return Err(PhysicsFault::NonFiniteState);
        }
        self.check_legs(state, &joints.kinematics(state))
    }

    /// [`ConfigurationGuard::check`] of a finite state whose legs are computed already.
    #[inline(always)]
    pub fn check_legs(&self, state: &BodyState, legs: &LegKinematics) -> Result<(), PhysicsFault> {
        let min_squared = self.min_leg_length * self.min_leg_length;
        let mut bad = false;
        for k in 0..LEG_COUNT {
            // No early exit: the six comparisons run side by side; the fault is named below.
            bad |= !(squared_length(legs, k) > min_squared) | !(self.height(state, legs, k) * self.side > 0.0);
        }
        if bad { Err(self.fault(state, legs)) } else { Ok(()) }
    }

    /// Height of platform joint `k` above the base plane, m.
    #[inline(always)]
    fn height(&self, state: &BodyState, legs: &LegKinematics, k: usize) -> f64 {
        state.r.z + legs.arm[2][k] - self.base_plane
    }

    /// The first leg that fails [`ConfigurationGuard::check_legs`].
    #[cold]
    fn fault(&self, state: &BodyState, legs: &LegKinematics) -> PhysicsFault {
        let min_squared = self.min_leg_length * self.min_leg_length;
        for k in 0..LEG_COUNT {
            let length_squared = squared_length(legs, k);
            if !(length_squared > min_squared) {
                return PhysicsFault::LegCollapsed { leg: k + 1, length: length_squared.sqrt() };
            }
            let height = self.height(state, legs, k);
            if !(height * self.side > 0.0) {
                return PhysicsFault::JointBelowBase { leg: k + 1, height };
            }
        }
        PhysicsFault::NonFiniteState
    }

    /// The condition number of the force/moment matrix of a state (the FMU output `kappa`;
    /// infinite at a singular arrangement).
    pub fn condition_number(stand: &Stand, state: &BodyState) -> f64 {
        ForceMomentMatrix::new(stand, &LegGeometry::new(stand, state)).condition_number()
    }
}

/// `|a_k - B_k|²`, m² (no square root).
#[inline(always)]
fn squared_length(legs: &LegKinematics, k: usize) -> f64 {
    legs.leg[0][k] * legs.leg[0][k] + legs.leg[1][k] * legs.leg[1][k] + legs.leg[2][k] * legs.leg[2][k]
}
