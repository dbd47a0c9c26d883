//! The simulation state's layout (the body's 24 coordinates, then the quadratures, the drives'
//! currents, the hydraulic states), its rate for every actuator, and the switching functions:
//! what the integrators, the outputs and the models index the state by.

use crate::physics::actuators::drives::DriveRate;
use crate::physics::actuators::hydraulics::{Chambers, HydraulicActuators};
use crate::physics::body::state::{BodyState, STATE_DIM, StateVector};
use crate::physics::number::Real;

use crate::physics::legs::geometry::LegGeometry;
use crate::physics::special_form::{SpecialForm, sum_over_legs};
use crate::physics::stand::LEG_COUNT;

/// Length of the simulation state: the 24 special-form coordinates, the work of the
/// actuator forces and the energy dissipated (quadratures integrated with the motion, so that
/// the energy balance holds to the integration tolerance), the drives' six armature currents
/// and the electric energy supplied, then the hydraulic legs' 12 chamber pressures, 6 spool
/// positions and rates and the hydraulic and compression work (each 0 and constant when its
/// actuator is off).
pub const SIMULATION_DIM: usize = STATE_DIM + 35;

/// The length of the state without drives or hydraulics: the trailing components stay 0, and
/// the methods step as they would without them ([`OdeSystem::active_dimension`]).
pub(super) const WITHOUT_DRIVES: usize = STATE_DIM + 2;
/// The length of the state with drives (the hydraulic components stay 0), and the length the
/// integrators step without hydraulic legs ([`MECHANICAL_DIM`]).
pub(super) const WITH_DRIVES: usize = STATE_DIM + 9;

/// The leading part of a [`SimulationState`] the integrators step when the hydraulic legs are
/// off (their components are then 0 and constant): the shorter arrays keep the force inputs'
/// and the drives' steps as cheap as before the hydraulics
/// ([`PlatformSimulation::advance`](super::PlatformSimulation::advance)).
pub const MECHANICAL_DIM: usize = WITH_DRIVES;
const _: () = assert!(MECHANICAL_DIM <= SIMULATION_DIM, "the leading part of the state");

/// The simulation state, `r, v, e1, e2, e3, e1', e2', e3', W_F, W_d, I_1..I_6, W_e, p_A1..6,
/// p_B1..6, s_1..6, s_1'..6', W_h, W_c`.
pub type SimulationState = [f64; SIMULATION_DIM];

/// Offsets of the quadratures in a [`SimulationState`].
pub mod quadrature {
    /// `work.F = integral of sum_k F_k ldot_k dt`, J.
    pub const WORK_F: usize = super::STATE_DIM;
    /// `work.dissipated = integral of P_d dt`, J.
    pub const WORK_DISSIPATED: usize = super::STATE_DIM + 1;
    /// `work.electric = integral of sum_k U_k I_k dt`, J.
    pub const WORK_ELECTRIC: usize = super::STATE_DIM + 8;
    /// `work.hydraulic = integral of sum_k P_S,k dt`, J.
    pub const WORK_HYDRAULIC: usize = super::STATE_DIM + 33;
    /// `work.compression = integral of sum_k (p_A V_A p_A' + p_B V_B p_B') / beta dt`, J.
    pub const WORK_COMPRESSION: usize = super::STATE_DIM + 34;
}

/// Offsets of the hydraulic legs' states in a [`SimulationState`]: `p_A`, `p_B` (Pa), the
/// spools' positions `s` and rates `s'` (1/s), six each.
pub mod hydraulic {
    pub const PA: usize = super::STATE_DIM + 9;
    pub const PB: usize = PA + 6;
    pub const SPOOL: usize = PB + 6;
    pub const SPOOL_RATE: usize = SPOOL + 6;
}

/// Offset of the drives' armature currents `I_1..I_6` (A) in a [`SimulationState`].
pub const CURRENTS: usize = STATE_DIM + 2;

/// The drives' forces and rates at the simulation state `y` and voltages `inputs` (`None`
/// without drives).
fn drive_rates<T: Real>(
    form: &SpecialForm,
    y: &[T; SIMULATION_DIM],
    inputs: &[T; LEG_COUNT],
) -> Option<[DriveRate<T>; LEG_COUNT]> {
    form.drives()?;
    let zero = [T::zero(); STATE_DIM];
    let currents: [T; LEG_COUNT] = std::array::from_fn(|k| y[CURRENTS + k]);
    form.drive_rates(&BodyState::from_vector(y.first_chunk::<STATE_DIM>().unwrap_or(&zero)), &currents, inputs)
}

/// The axial forces the actuators exert at the simulation state `y` for the inputs: the
/// inputs themselves (leg forces `F`), with drives the forces of their currents, with
/// hydraulic legs those of their chamber pressures.
pub fn actuator_forces<T: Real>(
    form: &SpecialForm,
    y: &[T; SIMULATION_DIM],
    inputs: &[T; LEG_COUNT],
) -> [T; LEG_COUNT] {
    if let Some(h) = form.hydraulics() {
        let (area_a, area_b) = h.legs.areas();
        return std::array::from_fn(|k| y[hydraulic::PA + k] * area_a - y[hydraulic::PB + k] * area_b);
    }
    drive_rates(form, y, inputs).map_or(*inputs, |d| d.map(|k| k.force))
}

/// `Qsupply`, m³/s: the flow the six valves draw from the supply at the simulation state `y`
/// (0 without hydraulic legs).
pub fn supply_flow(form: &SpecialForm, y: &SimulationState) -> f64 {
    let Some(h) = form.hydraulics() else { return 0.0 };
    let state = BodyState::from_vector(body(y));
    let legs = LegGeometry::new(&form.stand, &state);
    let l_dot = legs.length_rates(&form.stand, &state);
    supply_flow_of(h, y, &legs.length, &l_dot, h.supply)
}

/// `Qsupply` of the hydraulic legs `h` at the simulation state `y` (legs of lengths `l`, rates
/// `l_dot`) and the supply pressure `supply`, in any number type: the valves' law
/// ([`crate::physics::actuators::hydraulics::HydraulicLegs::rate`]'s supply flow) summed over
/// the legs.
pub fn supply_flow_of<T: Real>(
    h: &HydraulicActuators,
    y: &[T; SIMULATION_DIM],
    l: &[T; LEG_COUNT],
    l_dot: &[T; LEG_COUNT],
    supply: T,
) -> T {
    let flows: [T; LEG_COUNT] = std::array::from_fn(|k| {
        h.legs.rate(&chambers(y, k), &h.piston(k, l[k], l_dot[k]), T::zero(), supply).supply_flow
    });
    sum_over_legs(&flows)
}

/// The chambers of hydraulic leg `k` in a simulation state.
#[inline(always)]
pub(crate) fn chambers<T: Copy>(y: &[T; SIMULATION_DIM], k: usize) -> Chambers<T> {
    Chambers {
        pa: y[hydraulic::PA + k],
        pb: y[hydraulic::PB + k],
        spool: y[hydraulic::SPOOL + k],
        spool_rate: y[hydraulic::SPOOL_RATE + k],
    }
}

/// The hydraulic legs' rates at the simulation state `y` (legs of lengths `l`, rates `l_dot`)
/// for the valve commands `valves` and the supply pressure `supply`, written into `dy`; returns
/// the forces `u_k` and the sums of the supply power, the compression power and the losses.
#[inline(always)]
pub(super) fn hydraulic_rates<T: Real>(
    h: &HydraulicActuators,
    y: &[T; SIMULATION_DIM],
    l: &[T; LEG_COUNT],
    l_dot: &[T; LEG_COUNT],
    valves: &[T; LEG_COUNT],
    supply: T,
    dy: &mut [T; SIMULATION_DIM],
) -> ([T; LEG_COUNT], [T; 3]) {
    let mut u = [T::zero(); LEG_COUNT];
    let mut powers = [[T::zero(); LEG_COUNT]; 3];
    for k in 0..LEG_COUNT {
        let command = valves[k].clamp_to(T::constant(-1.0), T::constant(1.0));
        let r = h.legs.rate(&chambers(y, k), &h.piston(k, l[k], l_dot[k]), command, supply);
        dy[hydraulic::PA + k] = r.pa_rate;
        dy[hydraulic::PB + k] = r.pb_rate;
        dy[hydraulic::SPOOL + k] = r.spool_rate;
        dy[hydraulic::SPOOL_RATE + k] = r.spool_acceleration;
        u[k] = r.force;
        powers[0][k] = r.supply_power;
        powers[1][k] = r.compression_power;
        powers[2][k] = r.dissipation;
    }
    (u, powers.map(|p| sum_over_legs(&p)))
}

/// The rate of a simulation state `y` for the inputs `inputs` (the leg forces `F`, N, with
/// drives the voltages `U`, V, with hydraulic legs the valve commands), in any number type:
/// the definition Model Exchange and the exact derivatives use, and the steps' fast paths
/// follow (bit for bit or to round-off: `crate::physics::special_form`). With drives or
/// hydraulics, `work.F` stays 0: their forces are internal, their energy comes in as
/// `work.electric` or `work.hydraulic`.
pub fn state_rate<T: Real>(
    form: &SpecialForm,
    y: &[T; SIMULATION_DIM],
    inputs: &[T; LEG_COUNT],
) -> [T; SIMULATION_DIM] {
    let supply = T::constant(form.hydraulics().map_or(0.0, |h| h.supply));
    state_rate_supplied(form, y, inputs, supply)
}

/// [`state_rate`] with the hydraulic supply pressure `supply` (Pa) in the number type (for
/// derivatives with respect to `pS`); without hydraulics it is not used.
pub fn state_rate_supplied<T: Real>(
    form: &SpecialForm,
    y: &[T; SIMULATION_DIM],
    inputs: &[T; LEG_COUNT],
    supply: T,
) -> [T; SIMULATION_DIM] {
    let zero = [T::zero(); STATE_DIM];
    let b = y.first_chunk::<STATE_DIM>().unwrap_or(&zero);
    let mut dy = [T::zero(); SIMULATION_DIM];
    if let Some(h) = form.hydraulics() {
        let state = BodyState::from_vector(b);
        let legs = LegGeometry::new(&form.stand, &state);
        let l_dot = legs.length_rates(&form.stand, &state);
        let (u, [supplied, compression, losses]) = hydraulic_rates(h, y, &legs.length, &l_dot, inputs, supply, &mut dy);
        let (rate, power) = form.rate(b, &u);
        if let Some(head) = dy.first_chunk_mut::<STATE_DIM>() {
            *head = rate;
        }
        dy[quadrature::WORK_DISSIPATED] = power.dissipation + losses;
        dy[quadrature::WORK_HYDRAULIC] = supplied;
        dy[quadrature::WORK_COMPRESSION] = compression;
        return dy;
    }
    if form.drives().is_none() {
        let (rate, power) = form.rate(b, inputs);
        if let Some(head) = dy.first_chunk_mut::<STATE_DIM>() {
            *head = rate;
        }
        dy[quadrature::WORK_F] = power.actuator;
        dy[quadrature::WORK_DISSIPATED] = power.dissipation;
        return dy;
    }
    let currents: [T; LEG_COUNT] = std::array::from_fn(|k| y[CURRENTS + k]);
    let (rate, power, drives) = form.rate_driven(b, &currents, inputs);
    if let Some(head) = dy.first_chunk_mut::<STATE_DIM>() {
        *head = rate;
    }
    dy[quadrature::WORK_DISSIPATED] = power.dissipation + sum_over_legs(&drives.map(|d| d.dissipation));
    dy[quadrature::WORK_ELECTRIC] = sum_over_legs(&drives.map(|d| d.electric_power));
    for k in 0..LEG_COUNT {
        dy[CURRENTS + k] = drives[k].current_rate;
    }
    dy
}

/// The switching functions of a platform: where the motion is not smooth or is worth
/// reporting.
pub mod switching {
    /// `l_k - lmin_k`, k = 0..5 (a sign change is a contact onset or release at a lower stop).
    pub const LOWER: usize = 0;
    /// `lmax_k - l_k`, k = 0..5.
    pub const UPPER: usize = 6;
    /// Determinant of the force/moment matrix: a sign change is a passage through a singular
    /// leg arrangement.
    pub const DETERMINANT: usize = 12;
    /// `cos thetaB_k - cos thetaMax_B`, k = 0..5 (a sign change is a base joint reaching or
    /// leaving its angle limit).
    pub const BASE_JOINT: usize = 13;
    /// `cos thetaA_k - cos thetaMax_A`, k = 0..5 (the platform joints).
    pub const PLATFORM_JOINT: usize = 19;
    pub const COUNT: usize = 25;
}

/// The special-form body coordinates of a simulation state.
#[inline(always)]
pub fn body<const N: usize>(y: &[f64; N]) -> &StateVector {
    y.first_chunk::<STATE_DIM>().unwrap_or(&[0.0; STATE_DIM])
}
