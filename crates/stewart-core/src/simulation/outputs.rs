//! The FMU outputs derived from a simulation state, and their directional derivatives. The
//! time derivatives of the outputs (`fmi2GetRealOutputDerivatives`) are the directional
//! derivative along the state's own rate `dy/dt`: one chain rule serves both.

use nalgebra::{Matrix3, Matrix6, Scalar, Vector3};

use super::state::{
    CURRENTS, SIMULATION_DIM, SimulationState, actuator_forces, body, hydraulic, power_unit_outputs, quadrature,
    supply_flow_of,
};
use crate::physics::actuators::{Actuator, Supply, layout, with_actuator};
use crate::physics::body::invariants::mechanical_energy;
use crate::physics::body::kinematics::angles_from_rotation;
use crate::physics::body::state::{BodyState, STATE_DIM};
use crate::physics::direct_problem::ForceMomentMatrix;
use crate::physics::legs::bodies::LegMotion;
use crate::physics::legs::geometry::LegGeometry;
use crate::physics::legs::joint_limits::angle;
use crate::physics::number::{Dual, Real, lift};
use crate::physics::special_form::SpecialForm;
use crate::physics::stand::{LEG_COUNT, Stand};

/// A field of an outputs type: its numbers through a function, the shape kept.
pub trait Numbers<T: Real> {
    type With<U: Real>;
    fn map_numbers<U: Real>(&self, f: &impl Fn(T) -> U) -> Self::With<U>;
}

impl<T: Real> Numbers<T> for T {
    type With<U: Real> = U;
    fn map_numbers<U: Real>(&self, f: &impl Fn(T) -> U) -> U {
        f(*self)
    }
}

impl<T: Real, const N: usize> Numbers<T> for [T; N] {
    type With<U: Real> = [U; N];
    fn map_numbers<U: Real>(&self, f: &impl Fn(T) -> U) -> [U; N] {
        self.map(f)
    }
}

impl<T: Real> Numbers<T> for Vector3<T> {
    type With<U: Real> = Vector3<U>;
    fn map_numbers<U: Real>(&self, f: &impl Fn(T) -> U) -> Vector3<U> {
        self.map(f)
    }
}

impl<T: Real> Numbers<T> for Matrix3<T> {
    type With<U: Real> = Matrix3<U>;
    fn map_numbers<U: Real>(&self, f: &impl Fn(T) -> U) -> Matrix3<U> {
        self.map(f)
    }
}

impl<T: Real, const N: usize> Numbers<T> for [Vector3<T>; N] {
    type With<U: Real> = [Vector3<U>; N];
    fn map_numbers<U: Real>(&self, f: &impl Fn(T) -> U) -> [Vector3<U>; N] {
        self.map(|v| v.map(f))
    }
}

/// An outputs type in the number type `T` (default `f64`), each field declared once, and its
/// `map`: every number through a function (a dual's derivative part, say).
macro_rules! with_map {
    ($(#[$meta:meta])* pub struct $name:ident<T> { $($(#[$field_meta:meta])* pub $field:ident: $ty:ty,)* }) => {
        $(#[$meta])*
        pub struct $name<T: Scalar = f64> {
            $($(#[$field_meta])* pub $field: $ty,)*
        }

        impl<T: Real> $name<T> {
            /// Every value through `f` (a dual's derivative part, say).
            pub fn map<U: Real>(&self, f: impl Fn(T) -> U) -> $name<U> {
                $name { $($field: Numbers::map_numbers(&self.$field, &f),)* }
            }
        }
    };
}

with_map! {
/// Everything the platform FMU reports about a state (except `kappa`, which costs an
/// eigenvalue problem and is a cache block of its own, computed when read:
/// [`condition_number`]), in the
/// number type `T`: `f64` for the values, [`Dual`] for their directional derivatives.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlatformOutputs<T> {
    /// Centre of mass, m.
    pub r: Vector3<T>,
    /// Centre-of-mass velocity, m/s.
    pub v: Vector3<T>,
    /// Rotation body -> inertial (column b = e_b).
    pub rotation: Matrix3<T>,
    /// Roll, pitch, yaw (1-2-3), rad.
    pub angles: Vector3<T>,
    /// Angular velocity, body components, rad/s.
    pub w: Vector3<T>,
    /// Leg lengths, m.
    pub l: [T; LEG_COUNT],
    /// Leg length rates, m/s.
    pub ldot: [T; LEG_COUNT],
    /// The platform's and the legs' kinetic and gravitational potential energy, the stops'
    /// and joint limits' potentials and the drives' magnetic energy, J.
    pub energy: T,
    /// max over a, b of |e_a . e_b - delta_ab|.
    pub constraint_error: T,
    /// End-stop force along each leg, N (sign as the leg forces; 0 inside the stroke).
    pub stop_force: [T; LEG_COUNT],
    /// Work of the actuator forces since the start, J.
    pub work_of_forces: T,
    /// Energy taken by the stops' and joint limits' damping and by friction since the start, J.
    pub dissipated_energy: T,
    /// Base joint angles from the reference pose, rad (0 without joint limits' reference).
    pub theta_b: [T; LEG_COUNT],
    /// Platform joint angles from the reference pose, rad.
    pub theta_a: [T; LEG_COUNT],
    /// The force of each leg on the platform at `A_k`, inertial frame, N (not numbers where
    /// the inputs were not given: see [`PlatformOutputs::compute`]).
    pub joint_force: [Vector3<T>; LEG_COUNT],
    /// The actuators' axial forces on the legs, N: the leg forces `F`, or the drives' forces of
    /// their currents (not numbers where the inputs were not given).
    pub actuator_force: [T; LEG_COUNT],
    /// The drives' armature currents, A (0 without drives).
    pub current: [T; LEG_COUNT],
    /// Electric energy supplied to the drives since the start, J.
    pub electric_work: T,
    /// `pA`, `pB`, Pa; `spool`.
    pub pa: [T; LEG_COUNT],
    pub pb: [T; LEG_COUNT],
    pub spool: [T; LEG_COUNT],
    /// `Qsupply`, m³/s.
    pub supply_flow: T,
    /// `work.hydraulic`, `work.compression`, J.
    pub hydraulic_work: T,
    pub compression_work: T,
    /// `supply.pressure` (Pa), `supply.pumpFlow`, `supply.reliefFlow` (m³/s),
    /// `accumulator.oilVolume` (m³): the power unit's (the pressure is the input `pS` without it).
    pub power_unit: [T; 4],
    /// The actuators' part of the state (every actuator's block, [`actuator_state`]): an
    /// actuator's states and integrals are outputs read off it.
    pub actuator_states: [T; ACTUATOR_STATES],
}
}

/// How many states the actuators' blocks hold together.
pub const ACTUATOR_STATES: usize = layout::END - layout::START;

/// Where the simulation state's component `at` (an actuator's) sits in
/// [`PlatformOutputs::actuator_states`].
pub const fn actuator_state(at: usize) -> usize {
    at - layout::START
}

/// The actuators' states read off the simulation state (the field of [`PlatformOutputs`] of the
/// same name).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ActuatorStateOutputs<T: Scalar = f64> {
    pub actuator_states: [T; ACTUATOR_STATES],
}

impl<T: Real> ActuatorStateOutputs<T> {
    pub fn of(y: &[T; SIMULATION_DIM]) -> Self {
        ActuatorStateOutputs { actuator_states: std::array::from_fn(|i| y[layout::START + i]) }
    }
}

/// The body's pose and rates: the outputs `r`, `v`, `R`, `angles`, `w` (the fields of
/// [`PlatformOutputs`] of the same names), a group a host reads without the legs' other values.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PoseOutputs<T: Scalar = f64> {
    pub r: Vector3<T>,
    pub v: Vector3<T>,
    pub rotation: Matrix3<T>,
    pub angles: Vector3<T>,
    pub w: Vector3<T>,
}

impl<T: Real> PoseOutputs<T> {
    pub fn of(state: &BodyState<T>) -> Self {
        let rotation = state.rotation();
        PoseOutputs {
            r: state.r,
            v: state.v,
            rotation,
            angles: angles_from_rotation(&rotation),
            w: state.angular_velocity_body(),
        }
    }
}

/// What the legs' geometry gives beyond their lengths and rates: the energy (the legs', the
/// stops' and the joint limits' potentials are in it), the end stops' forces and the joint
/// angles (the fields of [`PlatformOutputs`] of the same names).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LegLoadOutputs<T: Scalar = f64> {
    pub energy: T,
    pub stop_force: [T; LEG_COUNT],
    pub theta_b: [T; LEG_COUNT],
    pub theta_a: [T; LEG_COUNT],
}

impl<T: Real> LegLoadOutputs<T> {
    /// At the simulation state `y` with body state `state`, legs `legs` and leg rates `ldot`.
    pub fn of(
        form: &SpecialForm,
        y: &[T; SIMULATION_DIM],
        state: &BodyState<T>,
        legs: &LegGeometry<T>,
        ldot: &[T; LEG_COUNT],
    ) -> Self {
        let stand = &form.stand;
        let mut stop_force = [T::zero(); LEG_COUNT];
        let mut energy = mechanical_energy(stand, state);
        if let Some(stops) = form.stops() {
            for k in 0..LEG_COUNT {
                stop_force[k] = stops.contact(k, legs.length[k], ldot[k]).force;
            }
            energy += stops.potential_energy(&legs.length);
        }
        let x = y.get(form.actuator().kind().block()).unwrap_or(&[]);
        if let Some(stored) = with_actuator!(form.actuator(), a => a.stored_energy(x)) {
            energy += stored;
        }
        let (mut theta_b, mut theta_a) = ([T::zero(); LEG_COUNT], [T::zero(); LEG_COUNT]);
        let has_mass = form.legs().has_mass();
        for k in 0..LEG_COUNT {
            if !(legs.length[k] > T::zero()) || (form.joint_limits().is_none() && !has_mass) {
                continue;
            }
            let motion = LegMotion::at(state, &stand.platform_joints[k], &legs.leg[k], legs.length[k]);
            if has_mass {
                energy += form.legs().energy(&motion, stand.base_joints[k].z, stand.gravity);
            }
            if let Some(limits) = form.joint_limits() {
                theta_b[k] = angle(motion.n.dot(&lift(&limits.base_reference[k])));
                theta_a[k] = angle(motion.n.dot(&state.body_vector(&limits.platform_reference[k])));
                energy +=
                    limits.potential(theta_b[k], limits.base_max) + limits.potential(theta_a[k], limits.platform_max);
            }
        }
        LegLoadOutputs { energy, stop_force, theta_b, theta_a }
    }

    /// At the simulation state `y`.
    pub fn at(form: &SpecialForm, y: &[T; SIMULATION_DIM]) -> Self {
        let state = BodyState::from_vector(&body_of(y));
        let legs = LegGeometry::new(&form.stand, &state);
        Self::of(form, y, &state, &legs, &legs.length_rates(&form.stand, &state))
    }
}

/// What is read off the body's state and the legs' integrals: the constraint residual,
/// `work.F` and `work.dissipated` (the fields of [`PlatformOutputs`] of the same names).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StateOutputs<T: Scalar = f64> {
    pub constraint_error: T,
    pub work_of_forces: T,
    pub dissipated_energy: T,
}

impl<T: Real> StateOutputs<T> {
    pub fn of(y: &[T; SIMULATION_DIM]) -> Self {
        StateOutputs {
            constraint_error: BodyState::from_vector(&body_of(y)).constraint_residual(),
            work_of_forces: y[quadrature::WORK_F],
            dissipated_energy: y[quadrature::WORK_DISSIPATED],
        }
    }
}

/// The body coordinates of a simulation state in any number type.
#[inline(always)]
fn body_of<T: Real>(y: &[T; SIMULATION_DIM]) -> [T; STATE_DIM] {
    y.first_chunk::<STATE_DIM>().copied().unwrap_or([T::zero(); STATE_DIM])
}

impl<T: Real> PlatformOutputs<T> {
    /// The outputs of the simulation state `y`; with the inputs `u` (leg forces, or with
    /// drives voltages), the actuators' and the joints' forces too (they depend on them), else
    /// those are not numbers.
    pub fn compute(form: &SpecialForm, y: &[T; SIMULATION_DIM], u: Option<&[T; LEG_COUNT]>) -> Self {
        Self::compute_supplied(form, y, u, form.supply())
    }

    /// [`PlatformOutputs::compute`] with the hydraulic supply's inputs in the number type (for
    /// derivatives with respect to `pS` and `pump.speed`): every group of outputs, the legs
    /// computed once.
    pub fn compute_supplied(
        form: &SpecialForm,
        y: &[T; SIMULATION_DIM],
        u: Option<&[T; LEG_COUNT]>,
        supply: Supply<T>,
    ) -> Self {
        let stand = &form.stand;
        let body = body_of(y);
        let state = BodyState::from_vector(&body);
        let legs = LegGeometry::new(stand, &state);
        let ldot = legs.length_rates(stand, &state);
        let PoseOutputs { r, v, rotation, angles, w } = PoseOutputs::of(&state);
        let LegLoadOutputs { energy, stop_force, theta_b, theta_a } = LegLoadOutputs::of(form, y, &state, &legs, &ldot);
        let StateOutputs { constraint_error, work_of_forces, dissipated_energy } = StateOutputs::of(y);
        let (actuator_force, joint_force) = match u {
            Some(u) => {
                let actuator = actuator_forces(form, y, u);
                (actuator, form.joint_forces(&body, &actuator))
            }
            None => ([T::constant(f64::NAN); LEG_COUNT], [Vector3::from_element(T::constant(f64::NAN)); LEG_COUNT]),
        };
        let supply_flow =
            form.hydraulics().map_or(T::zero(), |h| supply_flow_of(h, y, &legs.length, &ldot, supply.pressure));
        PlatformOutputs {
            r,
            v,
            rotation,
            angles,
            w,
            l: legs.length,
            ldot,
            energy,
            constraint_error,
            stop_force,
            work_of_forces,
            dissipated_energy,
            theta_b,
            theta_a,
            joint_force,
            actuator_force,
            current: std::array::from_fn(|k| y[CURRENTS + k]),
            electric_work: y[quadrature::WORK_ELECTRIC],
            pa: std::array::from_fn(|k| y[hydraulic::PA + k]),
            pb: std::array::from_fn(|k| y[hydraulic::PB + k]),
            spool: std::array::from_fn(|k| y[hydraulic::SPOOL + k]),
            supply_flow,
            hydraulic_work: y[quadrature::WORK_HYDRAULIC],
            compression_work: y[quadrature::WORK_COMPRESSION],
            power_unit: power_unit_outputs(form, y, supply),
            actuator_states: ActuatorStateOutputs::of(y).actuator_states,
        }
    }
}

impl PlatformOutputs {
    /// Directional derivative of the outputs: their change for a change `dy` of the state
    /// (exact: [`PlatformOutputs::compute`] on duals; for `fmi2GetDirectionalDerivative` and
    /// linearisation). With `dy` the state's rate `dy/dt` it gives the outputs' time
    /// derivatives. The entry for `constraint_error` is the change of the largest residual
    /// `|e_a.e_b - delta_ab|`.
    pub fn tangent(form: &SpecialForm, y: &SimulationState, dy: &SimulationState) -> Self {
        PlatformOutputs::<Dual>::compute(form, &Dual::seeded(y, dy), None).map(|d| d.eps)
    }
}

/// `kappa`: the 2-norm condition number of the legs' force/moment matrix (moment rows
/// divided by the stand's characteristic length), at most
/// [`crate::physics::direct_problem::CONDITION_NUMBER_BOUND`] (its value at a singular arrangement).
pub fn condition_number(stand: &Stand, y: &SimulationState) -> f64 {
    let state = BodyState::from_vector(body(y));
    ForceMomentMatrix::new(stand, &LegGeometry::new(stand, &state)).condition_number()
}

/// Change of `kappa` for a change `dy` of the state: `kappa = s_max / s_min` with
/// `ds_i = u_i^T dM v_i` for the singular triplets. 0 where `kappa` is at its bound (a singular
/// arrangement).
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
    let Some(svd) = m.svd(true, true) else { return 0.0 };
    let (Some(u), Some(v_t)) = (svd.u, svd.v_t) else { return 0.0 };
    let (imax, imin) = (svd.singular_values.imax(), svd.singular_values.imin());
    let (smax, smin) = (svd.singular_values[imax], svd.singular_values[imin]);
    if !(smin > 0.0) || smax / smin >= crate::physics::direct_problem::CONDITION_NUMBER_BOUND {
        return 0.0;
    }
    let dsigma = |i: usize| (u.column(i).transpose() * dm * v_t.row(i).transpose())[0];
    (dsigma(imax) * smin - smax * dsigma(imin)) / (smin * smin)
}
