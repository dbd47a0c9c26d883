//! An independent formulation of the same rigid body, for checking the special form:
//! the centre-of-mass theorem plus Euler's equations in body axes, orientation as a unit
//! quaternion, integrated with its own classical RK4 at a small fixed step. It shares no
//! code with the crate's physics core except the stand's parameters.

use nalgebra::{Matrix3, Quaternion, UnitQuaternion, Vector3};
use stewart_fmu::physics::stand::Stand;

/// Leg forces as a function of time, leg lengths and leg length rates.
pub type LegLaw<'a> = dyn Fn(f64, &[f64; 6], &[f64; 6]) -> [f64; 6] + 'a;

#[derive(Clone, Copy, Debug)]
pub struct NeState {
    pub r: Vector3<f64>,
    pub v: Vector3<f64>,
    /// Orientation body -> inertial, components (w, x, y, z).
    pub q: Quaternion<f64>,
    /// Angular velocity, body components.
    pub w: Vector3<f64>,
}

impl NeState {
    pub fn rotation(&self) -> Matrix3<f64> {
        UnitQuaternion::from_quaternion(self.q).to_rotation_matrix().into_inner()
    }

    fn add(&self, d: &NeState, h: f64) -> NeState {
        NeState { r: self.r + d.r * h, v: self.v + d.v * h, q: self.q + d.q * h, w: self.w + d.w * h }
    }
}

pub struct NewtonEuler<'a> {
    pub stand: Stand,
    pub law: &'a LegLaw<'a>,
}

impl NewtonEuler<'_> {
    /// Leg lengths and rates computed from this formulation's own kinematics.
    #[allow(clippy::type_complexity)]
    pub fn legs(&self, s: &NeState) -> ([f64; 6], [f64; 6], [Vector3<f64>; 6], [Vector3<f64>; 6]) {
        let rot = s.rotation();
        let omega = rot * s.w;
        let (mut l, mut ld, mut n, mut arm) = ([0.0; 6], [0.0; 6], [Vector3::zeros(); 6], [Vector3::zeros(); 6]);
        for k in 0..6 {
            arm[k] = rot * self.stand.platform_joints[k];
            let d = s.r + arm[k] - self.stand.base_joints[k];
            l[k] = d.norm();
            n[k] = d / l[k];
            ld[k] = n[k].dot(&(s.v + omega.cross(&arm[k])));
        }
        (l, ld, n, arm)
    }

    fn derivative(&self, t: f64, s: &NeState) -> NeState {
        let (l, ld, n, arm) = self.legs(s);
        let u = (self.law)(t, &l, &ld);
        let mut force = Vector3::new(0.0, 0.0, -self.stand.mass * self.stand.gravity);
        let mut moment = Vector3::zeros();
        for k in 0..6 {
            force += n[k] * u[k];
            moment += arm[k].cross(&(n[k] * u[k]));
        }
        let rot = s.rotation();
        let moment_body = rot.transpose() * moment;
        let j = Vector3::from(self.stand.inertia);
        // Euler's equations: J w' + w x (J w) = L (body axes).
        let w_dot = (moment_body - s.w.cross(&j.component_mul(&s.w))).component_div(&j);
        // Quaternion kinematics with body angular velocity: q' = q (0, w) / 2.
        let q_dot = s.q * Quaternion::new(0.0, s.w.x, s.w.y, s.w.z) * 0.5;
        NeState { r: s.v, v: force / self.stand.mass, q: q_dot, w: w_dot }
    }

    /// Classical RK4 from t0 to t1 in `steps` equal steps, renormalising the quaternion.
    pub fn integrate(&self, s: &mut NeState, t0: f64, t1: f64, steps: usize) {
        let h = (t1 - t0) / steps as f64;
        for i in 0..steps {
            let t = t0 + i as f64 * h;
            let k1 = self.derivative(t, s);
            let k2 = self.derivative(t + h / 2.0, &s.add(&k1, h / 2.0));
            let k3 = self.derivative(t + h / 2.0, &s.add(&k2, h / 2.0));
            let k4 = self.derivative(t + h, &s.add(&k3, h));
            *s = NeState {
                r: s.r + (k1.r + (k2.r + k3.r) * 2.0 + k4.r) * (h / 6.0),
                v: s.v + (k1.v + (k2.v + k3.v) * 2.0 + k4.v) * (h / 6.0),
                q: s.q + (k1.q + (k2.q + k3.q) * 2.0 + k4.q) * (h / 6.0),
                w: s.w + (k1.w + (k2.w + k3.w) * 2.0 + k4.w) * (h / 6.0),
            };
            s.q = s.q.normalize();
        }
    }
}
