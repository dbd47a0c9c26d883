//! The FMU outputs derived from a simulation state, and their directional derivatives. The
//! time derivatives of the outputs (`fmi2GetRealOutputDerivatives`) are the directional
//! derivative along the state's own rate `dy/dt`: one chain rule serves both.

use nalgebra::{Matrix3, Matrix6, Vector3};

use super::platform::{SimulationState, body, quadrature};
use crate::physics::body_state::BodyState;
use crate::physics::direct_problem::ForceMomentMatrix;
use crate::physics::invariants::mechanical_energy;
use crate::physics::kinematics::angles_from_rotation;
use crate::physics::legs::LegGeometry;
use crate::physics::special_form::SpecialForm;
use crate::physics::stand::{LEG_COUNT, Stand};

/// Everything the platform FMU reports about a state (except `kappa`, which costs a
/// singular value decomposition and is computed on request: [`condition_number`]).
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
    /// Kinetic plus gravitational potential energy plus the stops' potential energy, J.
    pub energy: f64,
    /// max over a, b of |e_a . e_b - delta_ab|.
    pub constraint_error: f64,
    /// End-stop force along each leg, N (sign as the leg forces; 0 inside the stroke).
    pub stop_force: [f64; LEG_COUNT],
    /// Work of the actuator forces since the start, J.
    pub work_of_forces: f64,
    /// Energy taken by the stops' damping since the start, J.
    pub dissipated_energy: f64,
}

/// Leg lengths and rates alone (a subset of [`PlatformOutputs`], the same numbers).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LegOutputs {
    pub l: [f64; LEG_COUNT],
    pub ldot: [f64; LEG_COUNT],
}

impl LegOutputs {
    pub fn compute(form: &SpecialForm, y: &SimulationState) -> Self {
        let state = BodyState::from_vector(body(y));
        let legs = LegGeometry::new(&form.stand, &state);
        LegOutputs { ldot: legs.length_rates(&form.stand, &state), l: legs.length }
    }
}

impl PlatformOutputs {
    pub fn compute(form: &SpecialForm, y: &SimulationState) -> Self {
        let stand = &form.stand;
        let state = BodyState::from_vector(body(y));
        let legs = LegGeometry::new(stand, &state);
        let rotation = state.rotation();
        let ldot = legs.length_rates(stand, &state);
        let mut stop_force = [0.0; LEG_COUNT];
        let mut stop_energy = 0.0;
        if let Some(stops) = form.stops() {
            for k in 0..LEG_COUNT {
                stop_force[k] = stops.contact(k, legs.length[k], ldot[k]).force;
            }
            stop_energy = stops.potential_energy(&legs.length);
        }
        PlatformOutputs {
            r: state.r,
            v: state.v,
            rotation,
            angles: angles_from_rotation(&rotation),
            w: state.angular_velocity_body(),
            l: legs.length,
            ldot,
            energy: mechanical_energy(stand, &state) + stop_energy,
            constraint_error: state.constraint_residual(),
            stop_force,
            work_of_forces: y[quadrature::WORK_F],
            dissipated_energy: y[quadrature::WORK_DISSIPATED],
        }
    }

    /// Directional derivative of the outputs: their change for a change `dy` of the state
    /// (exact chain rule; for `fmi2GetDirectionalDerivative` and linearisation). With `dy`
    /// the state's rate `dy/dt` it gives the outputs' time derivatives. The entry for
    /// `constraint_error` is the change of the largest residual `|e_a.e_b - delta_ab|`.
    pub fn tangent(form: &SpecialForm, y: &SimulationState, dy: &SimulationState) -> Self {
        let stand = &form.stand;
        let s = BodyState::from_vector(body(y));
        let ds = BodyState::from_vector(body(dy));
        let out = Self::compute(form, y);
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
        let mut dstop = [0.0; LEG_COUNT];
        let mut dstop_energy = 0.0;
        if let Some(stops) = form.stops() {
            for k in 0..LEG_COUNT {
                dstop[k] = stops.contact_tangent(k, out.l[k], out.ldot[k], dl[k], dldot[k]).force;
            }
            dstop_energy = stops.potential_energy_tangent(&out.l, &dl);
        }
        let j = Vector3::from(stand.inertia);
        let denergy = stand.mass * s.v.dot(&ds.v)
            + out.w.dot(&j.component_mul(&dw))
            + stand.mass * stand.gravity * ds.r.z
            + dstop_energy;
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
            stop_force: dstop,
            work_of_forces: dy[quadrature::WORK_F],
            dissipated_energy: dy[quadrature::WORK_DISSIPATED],
        }
    }
}

/// `kappa`: the 2-norm condition number of the legs' force/moment matrix (moment rows
/// divided by the stand's characteristic length), infinite at a singular arrangement.
pub fn condition_number(stand: &Stand, y: &SimulationState) -> f64 {
    let state = BodyState::from_vector(body(y));
    ForceMomentMatrix::new(stand, &LegGeometry::new(stand, &state)).condition_number()
}

/// Change of `kappa` for a change `dy` of the state: `kappa = s_max / s_min` with
/// `ds_i = u_i^T dM v_i` for the singular triplets. 0 where `kappa` is infinite.
pub fn condition_number_tangent(stand: &Stand, y: &SimulationState, dy: &SimulationState) -> f64 {
    let s = BodyState::from_vector(body(y));
    let ds = BodyState::from_vector(body(dy));
    let legs = LegGeometry::new(stand, &s);
    let m = ForceMomentMatrix::new(stand, &legs);
    let ell = m.moment_scale;
    let mut dm = Matrix6::zeros();
    for k in 0..LEG_COUNT {
        let l = legs.length[k];
        if l <= 0.0 {
            continue;
        }
        let n = legs.direction[k];
        let darm = ds.body_vector(&stand.platform_joints[k]);
        let dq = ds.r + darm;
        let dn = (dq - n * n.dot(&dq)) / l;
        let dmoment = (darm.cross(&n) + legs.arm[k].cross(&dn)) / ell;
        dm.fixed_view_mut::<3, 1>(0, k).copy_from(&dn);
        dm.fixed_view_mut::<3, 1>(3, k).copy_from(&dmoment);
    }
    let svd = m.matrix.svd(true, true);
    let (Some(u), Some(v_t)) = (svd.u, svd.v_t) else { return 0.0 };
    let (imax, imin) = (svd.singular_values.imax(), svd.singular_values.imin());
    let (smax, smin) = (svd.singular_values[imax], svd.singular_values[imin]);
    if !(smin > 0.0) {
        return 0.0;
    }
    let dsigma = |i: usize| (u.column(i).transpose() * dm * v_t.row(i).transpose())[0];
    (dsigma(imax) * smin - smax * dsigma(imin)) / (smin * smin)
}
