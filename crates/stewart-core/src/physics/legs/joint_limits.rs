//! Joint limits (docs/model.md §8): the angle of each base joint and each platform joint is
//! limited by a unilateral virtual potential (source document 002, as the end stops of
//! [`super::end_stops`]).
//!
//! The base joint angle `thetaB_k` is the angle between the leg direction `n_k` and its
//! direction `n0_k` at the reference pose; the platform joint angle `thetaA_k` the angle
//! between `n_k` and `w_k = R m0_k`, the reference direction fixed in the body
//! (`m0_k = R0^T n0_k`). Beyond its maximum a joint adds `V = 1/2 k_j delta^2`
//! (`delta = theta - thetaMax`) and a damping moment in contact only, limited as the end
//! stops' damping is (the law of the Modelica Standard Library's `ElastoGap`): the moment
//!
//! ```text
//! m = k_j delta + clamp(c_j theta', -k_j delta, k_j delta)
//! ```
//!
//! starts from zero at the onset and never pulls back into the limit. It turns the leg towards
//! its reference direction: on the leg it is the generalised force `m t` on `n` (`t` the unit
//! vector from `n` towards the reference, across the leg), which the leg passes to the
//! platform as the force `m t / l` at `A_k`; a platform joint's moment acts on the platform
//! too, `m (w x n) / sin(theta)`. The damping takes the power `(m - k_j delta) theta' >= 0`.

use nalgebra::Vector3;

use crate::maths;
use crate::physics::error::ParameterError;
use crate::physics::number::Real;
use crate::physics::stand::LEG_COUNT;

/// Default largest base joint angle from the reference pose, rad (25 degrees). The default
/// stand's shipped motions stay clear: the heave programme reaches 6.3 degrees, the start-up
/// from the parked pose 8.5, a power loss onto the stops 9.1, the actuator failure 16.2.
pub const DEFAULT_BASE_MAX_ANGLE: f64 = 25.0 * std::f64::consts::PI / 180.0;
/// Default largest platform joint angle from the reference pose, rad (35 degrees): the
/// actuator failure's tilt onto the stops reaches 26.3; open-loop forces that tip the platform
/// over (a 5 % ripple per leg) leave it resting on these limits, pitched about 28 degrees.
pub const DEFAULT_PLATFORM_MAX_ANGLE: f64 = 35.0 * std::f64::consts::PI / 180.0;
/// Default joint-limit stiffness `k_j`, N m/rad: the default platform tipped onto its limits
/// by its weight (about 3e4 N m about a tipping axis, shared by two or three joints) rests
/// about a degree into them.
pub const DEFAULT_STIFFNESS: f64 = 1.0e6;
/// Default joint-limit damping `c_j`, N m s/rad: about a third of the critical damping of the
/// platform tipping on two or three joint limits (its moment of inertia about a tipping axis
/// near a joint, about 1.2e4 kg m², against 2-3 k_j), so that it settles within a few swings.
pub const DEFAULT_DAMPING: f64 = 5.0e4;

/// The joint limits of the six legs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointLimits {
    /// `thetaMax` of the base joints, rad.
    pub base_max: f64,
    /// `thetaMax` of the platform joints, rad.
    pub platform_max: f64,
    /// `k_j`, N m/rad.
    pub stiffness: f64,
    /// `c_j`, N m s/rad.
    pub damping: f64,
    /// `n0_k`: the leg directions at the reference pose, inertial frame.
    pub base_reference: [Vector3<f64>; LEG_COUNT],
    /// `m0_k = R0^T n0_k`: the same directions in the body frame.
    pub platform_reference: [Vector3<f64>; LEG_COUNT],
    /// The reference pose's body axes `e0_a` (the columns of `R0`), inertial frame.
    pub reference_axes: [Vector3<f64>; 3],
    /// `cos` of the two maxima: a joint is beyond its limit where the cosine of its angle is
    /// below (the angle itself is computed only then).
    cos_base_max: f64,
    cos_platform_max: f64,
}

/// A joint's moment about its limit: the generalised force on the leg direction, the moment
/// on the platform and the damping's power.
#[derive(Clone, Copy, Debug)]
pub struct JointContact<T: nalgebra::Scalar> {
    /// The generalised force `m t` on the leg's direction `n`, N m.
    pub on_leg: Vector3<T>,
    /// The moment on the platform (platform joints), N m.
    pub on_platform: Vector3<T>,
    /// `(m - k_j delta) theta' >= 0`, W.
    pub dissipation: T,
}

/// The angle between two unit vectors from their cosine, clamped against round-off.
#[inline]
pub fn angle<T: Real>(cosine: T) -> T {
    cosine.clamp_to(T::constant(-1.0), T::one()).acos()
}

impl JointLimits {
    /// Limits at the reference directions `n0` (inertial) of a reference pose with rotation
    /// `rotation0`.
    pub fn new(
        base_max: f64,
        platform_max: f64,
        stiffness: f64,
        damping: f64,
        n0: [Vector3<f64>; LEG_COUNT],
        rotation0: &nalgebra::Matrix3<f64>,
    ) -> Self {
        JointLimits {
            base_max,
            platform_max,
            stiffness,
            damping,
            base_reference: n0,
            platform_reference: n0.map(|n| rotation0.transpose() * n),
            reference_axes: [
                rotation0.column(0).into_owned(),
                rotation0.column(1).into_owned(),
                rotation0.column(2).into_owned(),
            ],
            cos_base_max: maths::cos(base_max),
            cos_platform_max: maths::cos(platform_max),
        }
    }

    /// The contact law for a joint at angle `theta` (rate `theta_rate`) with limit `max`;
    /// `None` inside the limit (only round-off gets here then).
    #[inline]
    fn moment<T: Real>(&self, theta: T, theta_rate: T, max: f64) -> Option<(T, T)> {
        let delta = theta - max;
        if !(delta > T::zero()) {
            return None;
        }
        let spring = delta * self.stiffness;
        let damper = (theta_rate * self.damping).clamp_to(-spring, spring);
        Some((spring + damper, damper * theta_rate))
    }

    /// The base joint of leg `k` with direction `n` (rate `n_dot`), if beyond its limit.
    pub fn base<T: Real>(&self, k: usize, n: &Vector3<T>, n_dot: &Vector3<T>) -> Option<JointContact<T>> {
        let reference = self.base_reference[k].map(T::constant);
        let cosine = n.dot(&reference);
        if !(cosine < T::constant(self.cos_base_max)) {
            return None;
        }
        let theta = angle(cosine);
        // The unit vector from n towards the reference, across the leg: (n0 - n cos) / sin.
        let sine = theta.sin();
        let towards = (reference - n * cosine) / sine;
        let theta_rate = -n_dot.dot(&towards);
        let (m, dissipation) = self.moment(theta, theta_rate, self.base_max)?;
        Some(JointContact { on_leg: towards * m, on_platform: Vector3::zeros(), dissipation })
    }

    /// The platform joint of leg `k` with direction `n` (rate `n_dot`), the reference
    /// direction `w = R m0_k` (its rate from `w_dot`, asked for only in contact), if beyond its
    /// limit.
    pub fn platform<T: Real>(
        &self,
        n: &Vector3<T>,
        n_dot: &Vector3<T>,
        w: &Vector3<T>,
        w_dot: impl FnOnce() -> Vector3<T>,
    ) -> Option<JointContact<T>> {
        let cosine = n.dot(w);
        if !(cosine < T::constant(self.cos_platform_max)) {
            return None;
        }
        let w_dot = &w_dot();
        let theta = angle(cosine);
        let sine = theta.sin();
        let towards = (w - n * cosine) / sine;
        let theta_rate = -(n_dot.dot(w) + n.dot(w_dot)) / sine;
        let (m, dissipation) = self.moment(theta, theta_rate, self.platform_max)?;
        Some(JointContact { on_leg: towards * m, on_platform: w.cross(n) * (m / sine), dissipation })
    }

    /// The joint-limit potential of an angle, J.
    pub fn potential<T: Real>(&self, theta: T, max: f64) -> T {
        let delta = theta - max;
        if delta > T::zero() { delta * delta * (0.5 * self.stiffness) } else { T::zero() }
    }

    /// Checks the parameters (FMI names in the errors).
    pub fn validate(&self) -> Result<(), ParameterError> {
        for (name, value) in [("joints.baseMaxAngle", self.base_max), ("joints.platformMaxAngle", self.platform_max)] {
            crate::physics::stand::check_finite(name, value)?;
            if !(value > 0.0 && value < std::f64::consts::PI) {
                return Err(ParameterError::new(name, format!("must be in (0, pi) rad, got {value:e} rad")));
            }
        }
        crate::physics::stand::check_finite("joints.stiffness", self.stiffness)?;
        if !(self.stiffness > 0.0) {
            return Err(ParameterError::new(
                "joints.stiffness",
                format!("the joint-limit stiffness must be positive, got {:e} N.m/rad", self.stiffness),
            ));
        }
        crate::physics::stand::check_finite("joints.damping", self.damping)?;
        if self.damping < 0.0 {
            return Err(ParameterError::new(
                "joints.damping",
                format!("the joint-limit damping must be >= 0 N.m.s/rad, got {:e}", self.damping),
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::number::{Dual, Number};

    fn limits() -> JointLimits {
        let n0 = [Vector3::new(0.3, 0.1, 1.0).normalize(); LEG_COUNT];
        JointLimits::new(0.2, 0.3, 1e6, 1e4, n0, &nalgebra::Matrix3::identity())
    }

    /// The generalised force on the leg is minus the gradient of the potential along the
    /// sphere: the potential's derivative along any tangent direction, by duals.
    #[test]
    fn the_moment_is_the_potentials_gradient_and_turns_the_leg_back() {
        let j = JointLimits { damping: 0.0, ..limits() };
        let n0 = j.base_reference[0];
        let tilted = Vector3::new(0.9, -0.2, 0.8).normalize();
        let n = (n0 * 0.2 + tilted * 0.8).normalize();
        let theta = n.dot(&n0).acos();
        assert!(theta > j.base_max, "{theta}");
        let c = j.base(0, &n, &Vector3::zeros()).expect("beyond the limit");
        for d in [Vector3::new(1.0, 0.0, 0.0), Vector3::new(0.0, 1.0, 0.0), Vector3::new(0.2, -0.5, 0.7)] {
            let tangent = d - n * n.dot(&d);
            let moved = |s: Dual| {
                let m = Vector3::new(Dual::constant(n.x), Dual::constant(n.y), Dual::constant(n.z))
                    + tangent.map(Dual::constant) * s;
                let m = m / m.dot(&m).sqrt();
                let r = n0.map(Dual::constant);
                j.potential(angle(m.dot(&r)), j.base_max)
            };
            let dv = moved(Dual::new(0.0, 1.0)).eps;
            assert!(
                (c.on_leg.dot(&tangent) + dv).abs() < 1e-6 * (1.0 + dv.abs()),
                "{} vs {dv}",
                c.on_leg.dot(&tangent)
            );
        }
        // It turns the leg back towards its reference.
        assert!(c.on_leg.dot(&(n0 - n)) > 0.0);
        assert!(j.base(0, &n0, &Vector3::zeros()).is_none());
    }
}
