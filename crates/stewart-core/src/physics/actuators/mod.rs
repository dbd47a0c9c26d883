//! What drives the legs: leg force laws `u_k(t, state)` (the inputs `F`, springs, feedback
//! closures) and the electric drives of [`drives`] (voltages in, the force from the motor's
//! current).
//!
//! `u_k > 0` pushes the platform away from the base (extension), N.

pub mod drives;
pub mod hydraulics;

use crate::physics::body::state::BodyState;
use crate::physics::legs::geometry::LegGeometry;
use crate::physics::stand::LEG_COUNT;

/// Axial leg forces as a function of time and state.
pub trait LegForceLaw {
    fn leg_forces(&self, t: f64, state: &BodyState, legs: &LegGeometry) -> [f64; LEG_COUNT];

    /// Whether the forces depend on the state. If not, the right-hand side skips building
    /// the [`LegGeometry`] (the fast path of every co-simulation step, whose forces are
    /// inputs) and calls [`LegForceLaw::leg_forces_at`].
    fn depends_on_state(&self) -> bool {
        true
    }

    /// The forces of a law that does not depend on the state.
    fn leg_forces_at(&self, _t: f64) -> [f64; LEG_COUNT] {
        [0.0; LEG_COUNT]
    }
}

/// Forces held over a communication step as a first-order polynomial in time:
/// `u_k(t) = value_k + slope_k (t - t0)`. With zero slopes this is the zero-order hold a
/// co-simulation master implies; with slopes from `fmi2SetRealInputDerivatives` it is the
/// first-order input interpolation of FMI.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeldForces {
    pub value: [f64; LEG_COUNT],
    pub slope: [f64; LEG_COUNT],
    pub t0: f64,
}

impl HeldForces {
    pub fn constant(value: [f64; LEG_COUNT]) -> Self {
        HeldForces { value, slope: [0.0; LEG_COUNT], t0: 0.0 }
    }
}

impl LegForceLaw for HeldForces {
    #[inline(always)]
    fn leg_forces(&self, t: f64, _state: &BodyState, _legs: &LegGeometry) -> [f64; LEG_COUNT] {
        self.leg_forces_at(t)
    }

    fn depends_on_state(&self) -> bool {
        false
    }

    #[inline(always)]
    fn leg_forces_at(&self, t: f64) -> [f64; LEG_COUNT] {
        let dt = t - self.t0;
        let mut u = self.value;
        for k in 0..LEG_COUNT {
            u[k] += self.slope[k] * dt;
        }
        u
    }
}

/// Legs replaced by linear springs: `u_k = -c (l_k - L_k0)`. A conservative system (the
/// textbook's energy check, docs/model.md §7): potential `c/2 sum_k (l_k - L_k0)²`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpringLegs {
    /// Spring stiffness `c`, N/m.
    pub stiffness: f64,
    /// Unstretched lengths `L_k0`, m.
    pub rest_length: [f64; LEG_COUNT],
}

impl SpringLegs {
    /// Potential energy stored in the springs, J.
    pub fn potential_energy(&self, legs: &LegGeometry) -> f64 {
        (0..LEG_COUNT).map(|k| 0.5 * self.stiffness * (legs.length[k] - self.rest_length[k]).powi(2)).sum()
    }
}

impl LegForceLaw for SpringLegs {
    fn leg_forces(&self, _t: f64, _state: &BodyState, legs: &LegGeometry) -> [f64; LEG_COUNT] {
        let mut u = [0.0; LEG_COUNT];
        for k in 0..LEG_COUNT {
            u[k] = -self.stiffness * (legs.length[k] - self.rest_length[k]);
        }
        u
    }
}

/// Any closure `|t, state, legs| -> [u_k]` is a force law (tests, feedback experiments).
impl<F> LegForceLaw for F
where
    F: Fn(f64, &BodyState, &LegGeometry) -> [f64; LEG_COUNT],
{
    fn leg_forces(&self, t: f64, state: &BodyState, legs: &LegGeometry) -> [f64; LEG_COUNT] {
        self(t, state, legs)
    }
}
