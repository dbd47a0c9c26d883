//! The paper's actuators (`drive = 0`): the leg forces `F` are the inputs, held over each
//! communication step (`super::HeldForces`), and act on the legs as they are. No states; their
//! power is the work of given forces (`work.F`).

use super::{Actuator, BodyRate, LegPower};
use crate::physics::body::state::{BodyState, STATE_DIM};
use crate::physics::error::ParameterError;
use crate::physics::legs::geometry::LegGeometry;
use crate::physics::number::Real;
use crate::physics::stand::LEG_COUNT;

/// Ideal force actuators: the inputs are the axial forces.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ForceInputs;

impl Actuator for ForceInputs {
    const NAME: &'static str = "forces";
    const STATES: usize = 0;
    const HOT: bool = true;
    const INPUTS: &'static str = "leg forces";
    const INPUT_UNIT: &'static str = "N";

    #[inline(always)]
    fn rate<T: Real, B: BodyRate<T>>(&self, body: &B, _x: &[T], dy: &mut [T; STATE_DIM], _dx: &mut [T]) -> LegPower<T> {
        body.under_inputs(dy)
    }

    fn axial_forces<T: Real>(
        &self,
        _state: &BodyState<T>,
        _legs: &LegGeometry<T>,
        _platform_joints: &[nalgebra::Vector3<f64>; LEG_COUNT],
        _x: &[T],
        u: &[T; LEG_COUNT],
    ) -> [T; LEG_COUNT] {
        *u
    }

    fn validate(&self) -> Result<(), ParameterError> {
        Ok(())
    }
}
