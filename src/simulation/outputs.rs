//! The FMU outputs derived from a state (SPEC §3), and their first time derivatives for
//! `fmi2GetRealOutputDerivatives`.

use nalgebra::{Matrix3, Vector3};

use crate::physics::body_state::{BodyState, StateVector, layout};
use crate::physics::invariants::mechanical_energy;
use crate::physics::kinematics::{angle_rates, angles_from_rotation};
use crate::physics::legs::LegGeometry;
use crate::physics::stand::{LEG_COUNT, Stand};

/// Everything the platform FMU reports about a state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlatformOutputs {
    /// Centre of mass, m.
    pub r: Vector3<f64>,
    /// Centre-of-mass velocity, m/s.
    pub v: Vector3<f64>,
    /// Rotation body -> inertial (column b = e_b).
    pub rotation: Matrix3<f64>,
    /// Roll, pitch, yaw (1-2-3), rad.
    pub angles: Vector3<f64>,
    /// Angular velocity, body components, rad/s.
    pub w: Vector3<f64>,
    /// Leg lengths, m.
    pub l: [f64; LEG_COUNT],
    /// Leg length rates, m/s.
    pub ldot: [f64; LEG_COUNT],
    /// Kinetic plus gravitational potential energy, J.
    pub energy: f64,
    /// max over a, b of |e_a . e_b - delta_ab|.
    pub constraint_error: f64,
}

impl PlatformOutputs {
    pub fn compute(stand: &Stand, state: &BodyState) -> Self {
        let legs = LegGeometry::new(stand, state);
        let rotation = state.rotation();
        PlatformOutputs {
            r: state.r,
            v: state.v,
            rotation,
            angles: angles_from_rotation(&rotation),
            w: state.angular_velocity_body(),
            l: legs.length,
            ldot: legs.length_rates(stand, state),
            energy: mechanical_energy(stand, state),
            constraint_error: state.constraint_residual(),
        }
    }

    /// First time derivatives of the outputs, given the state derivative `dy` (which carries
    /// the accelerations for the current leg forces). `constraint_error` has none (it is a
    /// maximum of absolute values); its entry is 0.
    pub fn time_derivatives(stand: &Stand, state: &BodyState, dy: &StateVector) -> Self {
        let at = |i: usize| Vector3::new(dy[i], dy[i + 1], dy[i + 2]);
        let acc = at(layout::V);
        let e_dd = [at(layout::E_DOT), at(layout::E_DOT + 3), at(layout::E_DOT + 6)];
        let out = Self::compute(stand, state);
        let [e1, e2, e3] = &state.e;
        // d/dt of w1 = (e2'.e3 - e3'.e2)/2 is (e2''.e3 - e3''.e2)/2: the e'.e' terms cancel.
        let w_dot = Vector3::new(
            0.5 * (e_dd[1].dot(e3) - e_dd[2].dot(e2)),
            0.5 * (e_dd[2].dot(e1) - e_dd[0].dot(e3)),
            0.5 * (e_dd[0].dot(e2) - e_dd[1].dot(e1)),
        );
        let legs = LegGeometry::new(stand, state);
        let mut l_ddot = [0.0; LEG_COUNT];
        for k in 0..LEG_COUNT {
            let p = &stand.platform_joints[k];
            let s = state.v + state.body_vector_rate(p);
            let s_dot = acc + e_dd[0] * p.x + e_dd[1] * p.y + e_dd[2] * p.z;
            let l = legs.length[k];
            l_ddot[k] = if l > 0.0 {
                (s.norm_squared() - out.ldot[k] * out.ldot[k]) / l + legs.direction[k].dot(&s_dot)
            } else {
                0.0
            };
        }
        let j = Vector3::from(stand.inertia);
        let energy_rate = stand.mass * state.v.dot(&acc)
            + out.w.dot(&j.component_mul(&w_dot))
            + stand.mass * stand.gravity * state.v.z;
        PlatformOutputs {
            r: state.v,
            v: acc,
            rotation: state.rotation_rate(),
            angles: angle_rates(&out.angles, &out.w),
            w: w_dot,
            l: out.ldot,
            ldot: l_ddot,
            energy: energy_rate,
            constraint_error: 0.0,
        }
    }
}

impl PlatformOutputs {
    /// Directional derivative of the outputs: their change for a change `ds` of the state
    /// (exact chain rule; for `fmi2GetDirectionalDerivative` and linearisation). The entry for
    /// `constraint_error` is the change of the largest residual `|e_a.e_b - delta_ab|`.
    pub fn tangent(stand: &Stand, s: &BodyState, ds: &BodyState) -> Self {
        let out = Self::compute(stand, s);
        let rot = s.rotation();
        let drot = Matrix3::from_columns(&ds.e);
        // angles: pitch = asin(R02), roll = atan2(-R12, R22), yaw = atan2(-R01, R00).
        let datan2 = |y: f64, x: f64, dy: f64, dx: f64| {
            let d = x * x + y * y;
            if d > 0.0 { (x * dy - y * dx) / d } else { 0.0 }
        };
        let r02 = rot[(0, 2)];
        let dpitch = if r02.abs() < 1.0 { drot[(0, 2)] / (1.0 - r02 * r02).sqrt() } else { 0.0 };
        let droll = datan2(-rot[(1, 2)], rot[(2, 2)], -drot[(1, 2)], drot[(2, 2)]);
        let dyaw = datan2(-rot[(0, 1)], rot[(0, 0)], -drot[(0, 1)], drot[(0, 0)]);
        let [e1, e2, e3] = &s.e;
        let [d1, d2, d3] = &s.e_dot;
        let [de1, de2, de3] = &ds.e;
        let [dd1, dd2, dd3] = &ds.e_dot;
        let dw = Vector3::new(
            0.5 * (dd2.dot(e3) + d2.dot(de3) - dd3.dot(e2) - d3.dot(de2)),
            0.5 * (dd3.dot(e1) + d3.dot(de1) - dd1.dot(e3) - d1.dot(de3)),
            0.5 * (dd1.dot(e2) + d1.dot(de2) - dd2.dot(e1) - d2.dot(de1)),
        );
        let mut dl = [0.0; LEG_COUNT];
        let mut dldot = [0.0; LEG_COUNT];
        for k in 0..LEG_COUNT {
            let p = &stand.platform_joints[k];
            let q = s.r + s.body_vector(p) - stand.base_joints[k];
            let dq = ds.r + ds.body_vector(p);
            let l = q.norm();
            if l <= 0.0 {
                continue;
            }
            let n = q / l;
            let dn = (dq - n * n.dot(&dq)) / l;
            let sv = s.v + s.body_vector_rate(p);
            let dsv = ds.v + ds.body_vector_rate(p);
            dl[k] = n.dot(&dq);
            dldot[k] = dn.dot(&sv) + n.dot(&dsv);
        }
        let j = Vector3::from(stand.inertia);
        let denergy =
            stand.mass * s.v.dot(&ds.v) + out.w.dot(&j.component_mul(&dw)) + stand.mass * stand.gravity * ds.r.z;
        // The largest residual and its change.
        let (mut worst, mut dworst) = (-1.0, 0.0);
        for a in 0..3 {
            for b in a..3 {
                let c = s.e[a].dot(&s.e[b]) - if a == b { 1.0 } else { 0.0 };
                if c.abs() > worst {
                    worst = c.abs();
                    let dc = ds.e[a].dot(&s.e[b]) + s.e[a].dot(&ds.e[b]);
                    dworst = if c < 0.0 { -dc } else { dc };
                }
            }
        }
        PlatformOutputs {
            r: ds.r,
            v: ds.v,
            rotation: drot,
            angles: Vector3::new(droll, dpitch, dyaw),
            w: dw,
            l: dl,
            ldot: dldot,
            energy: denergy,
            constraint_error: dworst,
        }
    }
}
