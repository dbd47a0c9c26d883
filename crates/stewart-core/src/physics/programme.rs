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

/// How long a safe landing takes to reach its descent speed from the programme's motion, and
/// to stop at its floor, s: long enough for the heave programme's fastest motion (0.64 m/s) to
/// turn into a descent at under 3 m/s² and to stop without a jolt.
pub const LANDING_BLEND: f64 = 0.5;

/// A safe landing: from the programme point `from` at the landing's start (time 0 here), the
/// centre of mass brought into a vertical descent at `speed` over [`LANDING_BLEND`] (quintic:
/// position, velocity and acceleration continuous, the horizontal motion brought to rest), down
/// at `speed` until it stops at the height `floor` over [`LANDING_BLEND`]; the attitude held as
/// it was at the start (no rotation). What a stand does when its supply fails: land on its
/// lower stops under control while the accumulator still feeds the valves.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SafeLanding {
    pub from: PoseTrajectoryPoint,
    /// Descent speed, m/s (> 0).
    pub speed: f64,
    /// Height of the centre of mass at the end, m.
    pub floor: f64,
}

/// The quintic from `(p0, v0, a0)` to `(p1, v1, 0)` over `duration` at `t` (clamped to it):
/// position, velocity, acceleration.
fn quintic(start: (f64, f64, f64), end: (f64, f64), duration: f64, t: f64) -> (f64, f64, f64) {
    let (p0, v0, a0) = start;
    let (p1, v1) = end;
    let t = t.clamp(0.0, duration);
    let d = duration;
    // p(t) = p0 + v0 t + a0 t²/2 + c3 t³ + c4 t⁴ + c5 t⁵ with p(d) = p1, p'(d) = v1, p''(d) = 0.
    let dp = p1 - p0 - v0 * d - 0.5 * a0 * d * d;
    let dv = v1 - v0 - a0 * d;
    let da = -a0;
    let c3 = (10.0 * dp - 4.0 * dv * d + 0.5 * da * d * d) / (d * d * d);
    let c4 = (-15.0 * dp + 7.0 * dv * d - da * d * d) / (d * d * d * d);
    let c5 = (6.0 * dp - 3.0 * dv * d + 0.5 * da * d * d) / (d * d * d * d * d);
    let p = p0 + t * (v0 + t * (0.5 * a0 + t * (c3 + t * (c4 + t * c5))));
    let v = v0 + t * (a0 + t * (3.0 * c3 + t * (4.0 * c4 + t * 5.0 * c5)));
    let a = a0 + t * (6.0 * c3 + t * (12.0 * c4 + t * 20.0 * c5));
    (p, v, a)
}

impl SafeLanding {
    /// The vertical profile: `Some((z1, cruise))` when there is room to reach the descent speed
    /// and stop at the floor (the blend ends at `z1`, then `cruise` s at `speed`), `None` when the
    /// programme comes down too fast too near the floor (then one quintic brings it to rest there,
    /// over [`SafeLanding::direct_duration`]).
    fn descent(&self) -> Option<(f64, f64)> {
        let z1 = self.from.r.z + 0.5 * (self.from.v.z - self.speed) * LANDING_BLEND;
        let stopping = 0.5 * self.speed * LANDING_BLEND;
        (z1 - stopping >= self.floor).then(|| (z1, (z1 - stopping - self.floor) / self.speed))
    }

    /// The direct stop's duration: the time a uniform deceleration from the programme's
    /// descent rate takes over the room left (at least 0.2 s).
    fn direct_duration(&self) -> f64 {
        let room = self.from.r.z - self.floor;
        if room > 0.0 { (2.0 * room / self.speed.max(-self.from.v.z)).max(0.2) } else { LANDING_BLEND }
    }

    /// The landing's point `t` after its start.
    pub fn point(&self, t: f64) -> PoseTrajectoryPoint {
        let (from, blend) = (&self.from, LANDING_BLEND);
        let t = t.max(0.0);
        // Horizontally: to rest, covering what the motion carries over the blend.
        let horizontal = |i: usize| {
            let (p, v, a) = (from.r[i], from.v[i], from.a[i]);
            quintic((p, v, a), (p + 0.5 * v * blend, 0.0), blend, t)
        };
        let (x, y) = (horizontal(0), horizontal(1));
        // Vertically: into the descent, down at `speed`, then to rest at the floor.
        let start = (from.r.z, from.v.z, from.a.z);
        let z = match self.descent() {
            None => quintic(start, (self.floor, 0.0), self.direct_duration(), t),
            Some((z1, _)) if t < blend => quintic(start, (z1, -self.speed), blend, t),
            Some((z1, cruise)) if t < blend + cruise => (z1 - self.speed * (t - blend), -self.speed, 0.0),
            Some((z1, cruise)) => {
                let z2 = z1 - self.speed * cruise;
                quintic((z2, -self.speed, 0.0), (self.floor, 0.0), blend, t - blend - cruise)
            }
        };
        PoseTrajectoryPoint {
            r: Vector3::new(x.0, y.0, z.0),
            v: Vector3::new(x.1, y.1, z.1),
            a: Vector3::new(x.2, y.2, z.2),
            rotation: from.rotation,
            w: Vector3::zeros(),
            w_dot: Vector3::zeros(),
        }
    }

    /// When the landing ends (at rest on its floor), s after its start.
    pub fn duration(&self) -> f64 {
        match self.descent() {
            Some((_, cruise)) => 2.0 * LANDING_BLEND + cruise,
            None => self.direct_duration().max(LANDING_BLEND),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The landing starts where the programme was (position, velocity, acceleration), descends
    /// at its speed, ends at rest on its floor; its derivatives are the finite differences'.
    /// Started anywhere in a heave cycle (down to its lowest point, 8 cm above the floor, coming
    /// down at up to 0.77 m/s) it never goes below its floor.
    #[test]
    fn a_safe_landing_is_smooth_and_ends_at_rest_on_its_floor() {
        let heave = PoseProgramme::heave(Vector3::new(0.0, 0.0, 1.96), 0.3, 2.0, 1.0);
        for i in 0..500 {
            let t0 = 2.0 + i as f64 * 0.005;
            let from = heave.point(t0);
            let landing = SafeLanding { from, speed: 0.1, floor: 1.58 };
            let lowest = (0..=1000)
                .map(|j| landing.point(j as f64 * landing.duration() / 1000.0).r.z)
                .fold(f64::INFINITY, f64::min);
            assert!(lowest >= 1.58 - 1e-12, "t0 {t0}: down to {lowest}");
            let p0 = landing.point(0.0);
            assert!((p0.r - from.r).norm() < 1e-15 && (p0.v - from.v).norm() < 1e-15 && (p0.a - from.a).norm() < 1e-12);
            if landing.descent().is_some_and(|(_, cruise)| cruise > 0.6) {
                let mid = landing.point(LANDING_BLEND + 0.5);
                assert_eq!((mid.v.x, mid.v.y, mid.v.z), (0.0, 0.0, -0.1));
            }
            let end = landing.point(landing.duration());
            assert!((end.r.z - 1.58).abs() < 1e-12 && end.v.norm() < 1e-12 && end.a.norm() < 1e-9, "{end:?}");
            assert_eq!(landing.point(landing.duration() + 10.0).r, end.r);
            let h = 1e-6;
            let mut t = 0.05;
            while t < landing.duration() {
                let (a, b, c) = (landing.point(t - h), landing.point(t), landing.point(t + h));
                assert!(((c.r - a.r) / (2.0 * h) - b.v).norm() < 1e-6, "t0 {t0}, t {t}");
                assert!(((c.v - a.v) / (2.0 * h) - b.a).norm() < 1e-5, "t0 {t0}, t {t}");
                t += 0.171;
            }
        }
    }

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
