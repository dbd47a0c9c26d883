//! Which configurations the motion may pass through: legs of nonzero length, platform joints
//! on the side of the base plane where they started, a finite state, a non-singular leg
//! arrangement. Checked on the initial pose (as parameter errors) and after every internal
//! integration step (as faults that stop the step).

use super::body_state::BodyState;
use super::direct_problem::{ForceMomentMatrix, SINGULAR_CONDITION_NUMBER, force_moment_determinant};
use super::error::{ParameterError, PhysicsFault};
use super::legs::LegGeometry;
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
    /// Determinant of the force/moment matrix in the initial pose (signed). A sign change
    /// means the motion passed through a singular configuration; a small `|det| / |det0|`
    /// triggers the condition-number check.
    pub reference_determinant: f64,
    /// The stand's characteristic length (scales the moment rows of the force/moment matrix).
    pub characteristic_length: f64,
    /// Whether [`ConfigurationGuard::check_singularity`] is applied. Always on in the FMU;
    /// tests of a free body far from its (unloaded) legs switch it off.
    pub detect_singularities: bool,
}

/// Ratio `|det M| / |det M0|` below which the condition number is computed.
const DETERMINANT_ALARM: f64 = 1e-3;

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
        let matrix = ForceMomentMatrix::new(stand, &legs);
        let condition_number = matrix.condition_number();
        if !(condition_number < SINGULAR_CONDITION_NUMBER) {
            return Err(ParameterError::new(
                "r0",
                format!(
                    "the initial pose is a singular leg configuration: the 6x6 force/moment matrix has condition \
                     number {condition_number:e} (limit {SINGULAR_CONDITION_NUMBER:e}); the legs cannot hold the platform"
                ),
            ));
        }
        Ok(ConfigurationGuard {
            min_leg_length,
            base_plane,
            side,
            reference_determinant: matrix.determinant(),
            characteristic_length: matrix.moment_scale,
            detect_singularities: true,
        })
    }

    /// Cheap checks for every internal step: finite state, legs not collapsed, platform
    /// joints on their side of the base plane. Squared lengths, no square roots on the way.
    #[inline]
    pub fn check(&self, stand: &Stand, state: &BodyState) -> Result<(), PhysicsFault> {
        if !state.is_finite() {
            return Err(PhysicsFault::NonFiniteState);
        }
        let min_squared = self.min_leg_length * self.min_leg_length;
        for k in 0..LEG_COUNT {
            let arm = state.body_vector(&stand.platform_joints[k]);
            let length_squared = (state.r + arm - stand.base_joints[k]).norm_squared();
            if !(length_squared > min_squared) {
                return Err(PhysicsFault::LegCollapsed { leg: k + 1, length: length_squared.sqrt() });
            }
            let height = state.r.z + arm.z - self.base_plane;
            if !(height * self.side > 0.0) {
                return Err(PhysicsFault::JointBelowBase { leg: k + 1, height });
            }
        }
        Ok(())
    }

    /// Both checks, for a state reached outside the integrator (Model Exchange).
    pub fn check_all(&self, stand: &Stand, state: &BodyState) -> Result<(), PhysicsFault> {
        self.check(stand, state).and_then(|()| self.check_singularity(stand, state))
    }

    /// Singularity check (once per communication step, a 6x6 determinant): a sign change of
    /// the determinant since the initial pose means the legs passed through a singular
    /// configuration during the step; a shrunken determinant triggers the condition number.
    pub fn check_singularity(&self, stand: &Stand, state: &BodyState) -> Result<(), PhysicsFault> {
        if !self.detect_singularities {
            return Ok(());
        }
        let legs = &LegGeometry::new(stand, state);
        let det = force_moment_determinant(legs, self.characteristic_length);
        if det * self.reference_determinant <= 0.0 {
            return Err(PhysicsFault::PassedSingularConfiguration);
        }
        if det.abs() >= DETERMINANT_ALARM * self.reference_determinant.abs() {
            return Ok(());
        }
        let condition_number = ForceMomentMatrix::new(stand, legs).condition_number();
        if condition_number < SINGULAR_CONDITION_NUMBER {
            Ok(())
        } else {
            Err(PhysicsFault::SingularConfiguration { condition_number })
        }
    }
}
