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
