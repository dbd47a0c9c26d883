//! Programme motions with exact first and second derivatives, for the direct problem.
//!
//! Each degree of freedom follows a sinusoid with the paper's soft start (section 6):
//!
//! ```text
//! q(t) = q0 + a sin(Omega t + phi) (1 - exp(-t/T))²
//! ```
//!
//! The factor `(1 - exp(-t/T))²` makes velocity vanish at `t = 0` and, for `phi = 0`, the
//! acceleration too, so the programme forces start without a jump. (With a phase the initial
//! acceleration is `2 a sin(phi) / T²`.) Before `t = 0` a soft-started programme rests at
//! `q0`: the factor is 0 there (its formula would grow like `exp(-t/T)` and overflow for a run
//! that starts long before 0). The paper's heave law (5.1) is
//! `z(t) = z0 + 0.2 sin t (1 - exp(-t/2))²` in non-dimensional units.

use nalgebra::Vector3;

use super::body::kinematics::{PoseTrajectoryPoint, sin_cos};
use crate::maths;

/// `q(t) = offset + amplitude sin(frequency t + phase) (1 - exp(-t/time_constant))²`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SoftStartSinusoid {
    /// `q0`, in the unit of the coordinate (m or rad).
    pub offset: f64,
    /// `a`, same unit.
    pub amplitude: f64,
    /// `Omega`, rad/s.
    pub frequency: f64,
    /// `phi`, rad.
    pub phase: f64,
    /// `T`, s; 0 switches the soft start off (the factor is 1).
    pub time_constant: f64,
}

impl SoftStartSinusoid {
    pub fn constant(offset: f64) -> Self {
        SoftStartSinusoid { offset, amplitude: 0.0, frequency: 0.0, phase: 0.0, time_constant: 0.0 }
    }

    /// Value, first and second derivative at time `t`.
    pub fn evaluate(&self, t: f64) -> (f64, f64, f64) {
        let (g, g1, g2) = if self.time_constant > 0.0 && t < 0.0 {
            (0.0, 0.0, 0.0)
        } else if self.time_constant > 0.0 {
            let tc = self.time_constant;
            let e = maths::exp(-t / tc);
            ((1.0 - e) * (1.0 - e), 2.0 * (e - e * e) / tc, 2.0 * (2.0 * e * e - e) / (tc * tc))
        } else {
            (1.0, 0.0, 0.0)
        };
        let w = self.frequency;
        let (s, c) = sin_cos(w * t + self.phase);
        let a = self.amplitude;
        (self.offset + a * s * g, a * (w * c * g + s * g1), a * (-w * w * s * g + 2.0 * w * c * g1 + s * g2))
    }
}

/// A six-degree-of-freedom programme: centre of mass `x, y, z` (m) and 1-2-3 angles
/// `roll, pitch, yaw` (rad), each a [`SoftStartSinusoid`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PoseProgramme {
    pub dof: [SoftStartSinusoid; 6],
}

impl PoseProgramme {
    /// A pure heave `z(t) = z0 + a sin(Omega t)(1 - exp(-t/T))²` above `(x0, y0)`, no rotation.
    pub fn heave(centre: Vector3<f64>, amplitude: f64, frequency: f64, time_constant: f64) -> Self {
        let mut dof = [SoftStartSinusoid::constant(0.0); 6];
        dof[0] = SoftStartSinusoid::constant(centre.x);
        dof[1] = SoftStartSinusoid::constant(centre.y);
        dof[2] = SoftStartSinusoid { offset: centre.z, amplitude, frequency, phase: 0.0, time_constant };
        PoseProgramme { dof }
    }

    /// The pose with its derivatives at time `t`.
    pub fn point(&self, t: f64) -> PoseTrajectoryPoint {
        let mut q = [0.0; 6];
        let mut d = [0.0; 6];
        let mut dd = [0.0; 6];
        for i in 0..6 {
            (q[i], d[i], dd[i]) = self.dof[i].evaluate(t);
        }
        PoseTrajectoryPoint::from_angles(
            Vector3::new(q[0], q[1], q[2]),
            Vector3::new(d[0], d[1], d[2]),
            Vector3::new(dd[0], dd[1], dd[2]),
            &Vector3::new(q[3], q[4], q[5]),
            &Vector3::new(d[3], d[4], d[5]),
            &Vector3::new(dd[3], dd[4], dd[5]),
        )
    }
}

/// A rest-to-rest transfer of the centre of mass from `from` to `to` in `duration`, along the
/// quintic smooth step `s(tau) = 10 tau³ - 15 tau⁴ + 6 tau⁵` (velocity and acceleration zero
/// at both ends, so the programme forces start and end without a jump), no rotation; then
/// `then` with its time counted from the end of the transfer. The start-up of a platform
/// parked on its lower stops: lift it to the working pose, then run the programme.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StartUp {
    /// Centre of mass at `t = 0` (the parked pose), m.
    pub from: Vector3<f64>,
    /// Centre of mass at `t = duration`, m (where `then` starts).
    pub to: Vector3<f64>,
    /// s; > 0.
    pub duration: f64,
    pub then: PoseProgramme,
}

impl StartUp {
    pub fn point(&self, t: f64) -> PoseTrajectoryPoint {
        if t >= self.duration || !(self.duration > 0.0) {
            return self.then.point(t - self.duration);
        }
        let tau = (t / self.duration).max(0.0);
        let s = tau * tau * tau * (10.0 + tau * (-15.0 + 6.0 * tau));
        let ds = 30.0 * tau * tau * (1.0 - tau) * (1.0 - tau) / self.duration;
        let dds = 60.0 * tau * (1.0 - tau) * (1.0 - 2.0 * tau) / (self.duration * self.duration);
        let d = self.to - self.from;
        let zero = Vector3::zeros();
        PoseTrajectoryPoint::from_angles(self.from + d * s, d * ds, d * dds, &zero, &zero, &zero)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn start_up_is_smooth_and_hands_over_to_the_programme() {
        let then = PoseProgramme::heave(Vector3::new(0.0, 0.0, 1.96), 0.3, 2.0, 1.0);
        let up = StartUp { from: Vector3::new(0.0, 0.0, 1.57), to: Vector3::new(0.0, 0.0, 1.96), duration: 3.0, then };
        let p0 = up.point(0.0);
        assert_eq!((p0.r.z, p0.v.z, p0.a.z), (1.57, 0.0, 0.0));
        // Continuous value, rate and acceleration at the hand-over.
        let (before, after) = (up.point(3.0 - 1e-9), up.point(3.0 + 1e-9));
        assert!((before.r - after.r).norm() < 1e-8 && (before.v - after.v).norm() < 1e-7);
        assert!((before.a - after.a).norm() < 1e-6, "{:?} {:?}", before.a, after.a);
        for t in [0.3, 1.5, 2.7] {
            let h = 1e-5;
            let fd1 = (up.point(t + h).r.z - up.point(t - h).r.z) / (2.0 * h);
            let fd2 = (up.point(t + h).v.z - up.point(t - h).v.z) / (2.0 * h);
            assert!((up.point(t).v.z - fd1).abs() < 1e-8 && (up.point(t).a.z - fd2).abs() < 1e-7);
        }
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let s = SoftStartSinusoid { offset: 0.3, amplitude: 0.2, frequency: 1.3, phase: 0.4, time_constant: 2.0 };
        let h = 1e-5;
        for t in [0.5, 3.0, 10.0] {
            let (_, d, dd) = s.evaluate(t);
            let fd1 = (s.evaluate(t + h).0 - s.evaluate(t - h).0) / (2.0 * h);
            let fd2 = (s.evaluate(t + h).1 - s.evaluate(t - h).1) / (2.0 * h);
            assert!((d - fd1).abs() < 1e-9, "t={t}: {d} vs {fd1}");
            assert!((dd - fd2).abs() < 1e-9, "t={t}: {dd} vs {fd2}");
        }
        // At t = 0 from the right (the programme rests before 0): second-order one-sided.
        let one_sided = |f: &dyn Fn(f64) -> f64| (-3.0 * f(0.0) + 4.0 * f(h) - f(2.0 * h)) / (2.0 * h);
        let (_, d, dd) = s.evaluate(0.0);
        assert!((d - one_sided(&|t| s.evaluate(t).0)).abs() < 1e-9);
        assert!((dd - one_sided(&|t| s.evaluate(t).1)).abs() < 1e-8);
        // Before 0 it rests at the offset, however early the run starts.
        assert_eq!(s.evaluate(-1e9), (0.3, 0.0, 0.0));
        // Soft start: at rest at t = 0 (acceleration too when the phase is 0, as in the paper).
        let s = SoftStartSinusoid { phase: 0.0, ..s };
        let (q, d, dd) = s.evaluate(0.0);
        assert_eq!((q, d, dd), (0.3, 0.0, 0.0));
    }
}
