//! Cylinder friction (docs/model.md §8): an axial force between cylinder and rod, acting along
//! the leg like the actuator force, Stribeck's law regularised so that it never sticks:
//!
//! ```text
//! f = -[F_c + (F_s - F_c) exp(-(ldot / v_s)^2)] tanh(ldot / v_t) - sigma ldot
//! ```
//!
//! It always opposes the leg's rate: its power `f ldot <= 0` goes into `work.dissipated`.
//! Near `ldot = 0` it is a viscous damper of rate `F_s / v_t` (the tanh's slope): a small
//! `v_t` approximates sticking more closely and makes the equations stiffer (an explicit
//! integrator's step must stay below about `m v_t / F_s` for a leg carrying mass `m`).

use crate::physics::error::ParameterError;
use crate::physics::number::Real;

/// Default Stribeck velocity `v_s`, m/s: where the static friction has decayed to the Coulomb
/// level, typical of hydraulic and ball-screw actuators (10-50 mm/s).
pub const DEFAULT_STRIBECK_VELOCITY: f64 = 0.02;
/// Default smoothing velocity `v_t`, m/s: the tanh's width, 2 mm/s.
pub const DEFAULT_SMOOTHING: f64 = 0.002;

/// The friction parameters (`friction.*`), the same for all six legs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Friction {
    /// `F_c`, N.
    pub coulomb: f64,
    /// `F_s`, N.
    pub static_: f64,
    /// `v_s`, m/s.
    pub stribeck_velocity: f64,
    /// `v_t`, m/s.
    pub smoothing: f64,
    /// `sigma`, N s/m.
    pub viscous: f64,
}

impl Default for Friction {
    /// No friction (the paper's legs).
    fn default() -> Self {
        Friction {
            coulomb: 0.0,
            static_: 0.0,
            stribeck_velocity: DEFAULT_STRIBECK_VELOCITY,
            smoothing: DEFAULT_SMOOTHING,
            viscous: 0.0,
        }
    }
}

impl Friction {
    /// Whether there is any friction.
    pub fn is_zero(&self) -> bool {
        self.coulomb == 0.0 && self.static_ == 0.0 && self.viscous == 0.0
    }

    /// The friction force on a leg of rate `ldot`, N (sign as the actuator force).
    #[inline]
    pub fn force<T: Real>(&self, ldot: T) -> T {
        let x = ldot / self.stribeck_velocity;
        let level = (-(x * x)).exp() * (self.static_ - self.coulomb) + self.coulomb;
        -(level * (ldot / self.smoothing).tanh()) - ldot * self.viscous
    }

    /// Checks the parameters (FMI names in the errors).
    pub fn validate(&self) -> Result<(), ParameterError> {
        for (name, value) in
            [("friction.coulomb", self.coulomb), ("friction.static", self.static_), ("friction.viscous", self.viscous)]
        {
            crate::physics::stand::check_finite(name, value)?;
            if value < 0.0 {
                return Err(ParameterError::new(name, format!("must be >= 0, got {value:e}")));
            }
        }
        for (name, value) in
            [("friction.stribeckVelocity", self.stribeck_velocity), ("friction.smoothing", self.smoothing)]
        {
            crate::physics::stand::check_finite(name, value)?;
            if !(value > 0.0) {
                return Err(ParameterError::new(name, format!("must be > 0 m/s, got {value:e} m/s")));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn friction_opposes_the_motion_and_decays_from_static_to_coulomb() {
        let f = Friction { coulomb: 300.0, static_: 500.0, viscous: 1000.0, ..Friction::default() };
        for v in [-1.0, -0.05, -1e-3, 1e-4, 0.01, 0.5] {
            assert!(f.force(v) * v < 0.0, "{v}: {}", f.force(v));
        }
        assert_eq!(f.force(0.0), 0.0);
        // Just past the smoothing, near the static level; far past the Stribeck velocity, the
        // Coulomb level plus the viscous part.
        assert!((f.force(0.01).abs() - 500.0).abs() < 40.0, "{}", f.force(0.01));
        assert!((f.force(0.5) + 300.0 + 500.0).abs() < 1e-6, "{}", f.force(0.5));
    }
}
