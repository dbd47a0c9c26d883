//! The simulation state's layout (the body's 24 coordinates, the legs' two integrals, then each
//! actuator's block: `crate::physics::actuators::layout`), its rate (one assembly for every
//! actuator, which the definition and the steps' fast path run alike), and the switching
//! functions: what the integrators, the outputs and the models index the state by.

use crate::physics::actuators::hydraulics::HydraulicActuators;
use crate::physics::actuators::{Actuator, ActuatorKind, BodyRate, InState, Supply, layout, with_actuator};
use crate::physics::body::state::{BodyState, STATE_DIM, StateVector};
use crate::physics::legs::geometry::LegGeometry;
use crate::physics::number::Real;
use crate::physics::special_form::{Definition, SpecialForm};
use crate::physics::stand::LEG_COUNT;

/// Length of the simulation state: the 24 special-form coordinates, the work of the
/// actuator forces and the energy dissipated (quadratures integrated with the motion, so that
/// the energy balance holds to the integration tolerance), then each actuator's block (the
/// drives' six armature currents and the electric energy supplied; the hydraulic legs' 12
/// chamber pressures, 6 spool positions and rates, the hydraulic and compression work, the
/// power unit's supply pressure and pump work), 0
/// and constant when its actuator is not the legs'.
pub const SIMULATION_DIM: usize = layout::END;

/// The leading part of a [`SimulationState`] the integrators step when the legs' actuator's
/// block ends within it (the later blocks are then 0 and constant): up to the end of the
/// drives' block; an actuator listed after it steps the whole state. The
/// shorter arrays keep the force inputs' and the drives' steps as cheap as before the
/// hydraulics ([`PlatformSimulation::advance`](super::PlatformSimulation::advance)); within
/// them the methods step up to the active actuator's block's end only
/// (`OdeSystem::active_dimension`).
pub const MECHANICAL_DIM: usize = layout::Electric.end;
const _: () = assert!(MECHANICAL_DIM <= SIMULATION_DIM, "the leading part of the state");

/// The simulation state, `r, v, e1, e2, e3, e1', e2', e3', W_F, W_d, I_1..I_6, W_e, p_A1..6,
/// p_B1..6, s_1..6, s_1'..6', W_h, W_c, p_S, W_p`.
pub type SimulationState = [f64; SIMULATION_DIM];

/// Offsets of the quadratures in a [`SimulationState`].
pub mod quadrature {
    use crate::physics::actuators::hydraulics::block;
    use crate::physics::actuators::layout;
    /// `work.F = integral of sum_k F_k ldot_k dt`, J.
    pub const WORK_F: usize = super::STATE_DIM;
    /// `work.dissipated = integral of P_d dt`, J.
    pub const WORK_DISSIPATED: usize = super::STATE_DIM + 1;
    /// `work.electric = integral of sum_k U_k I_k dt`, J.
    pub const WORK_ELECTRIC: usize = layout::Electric.start + crate::physics::stand::LEG_COUNT;
    /// `work.hydraulic = integral of sum_k P_S,k dt`, J.
    pub const WORK_HYDRAULIC: usize = layout::Hydraulic.start + block::WORK_HYDRAULIC;
    /// `work.compression = integral of sum_k (p_A V_A p_A' + p_B V_B p_B') / beta dt`, J.
    pub const WORK_COMPRESSION: usize = layout::Hydraulic.start + block::WORK_COMPRESSION;
    /// `work.pump = integral of (p_S Q_pump - p_T (Q_T + Q_relief)) dt`, J (the power unit).
    pub const WORK_PUMP: usize = layout::Hydraulic.start + block::WORK_PUMP;
}
const _: () = assert!(quadrature::WORK_DISSIPATED + 1 == layout::START, "the actuators' blocks follow");

/// Offsets of the hydraulic legs' states in a [`SimulationState`]: `p_A`, `p_B` (Pa), the
/// spools' positions `s` and rates `s'` (1/s), six each.
pub mod hydraulic {
    use crate::physics::actuators::hydraulics::block;
    use crate::physics::actuators::layout;
    pub const PA: usize = layout::Hydraulic.start + block::PA;
    pub const PB: usize = layout::Hydraulic.start + block::PB;
    pub const SPOOL: usize = layout::Hydraulic.start + block::SPOOL;
    pub const SPOOL_RATE: usize = layout::Hydraulic.start + block::SPOOL_RATE;
    /// The power unit's supply line pressure `p_S`, Pa.
    pub const SUPPLY_PRESSURE: usize = layout::Hydraulic.start + block::SUPPLY_PRESSURE;
}

/// Offset of the drives' armature currents `I_1..I_6` (A) in a [`SimulationState`].
pub const CURRENTS: usize = layout::Electric.start;

/// The rate of the state `y` (the whole simulation state, or its leading part holding the
/// legs' actuator's block: `N`) into `dy`, through `body` (the definition or the fast path):
/// the active actuator's rate ([`Actuator::rate`]: its block and the body's), the legs'
/// integrals, and 0 for every other actuator's block. The one assembly of the whole state's
/// rate, in any number type.
#[inline(always)]
pub fn rate_in<T: Real, B: BodyRate<T>, const N: usize>(form: &SpecialForm, body: &B, y: &[T; N], dy: &mut [T; N]) {
    with_actuator!(form.actuator(), a => rate_of(a, body, y, dy));
}

/// [`rate_in`] for actuator `A`: its block's place known when compiled.
#[inline(always)]
fn rate_of<A: Actuator + InState, T: Real, B: BodyRate<T>, const N: usize>(
    a: &A,
    body: &B,
    y: &[T; N],
    dy: &mut [T; N],
) {
    if !A::HOT {
        std::hint::cold_path();
    }
    let Some((head, rest)) = dy.split_first_chunk_mut::<STATE_DIM>() else { return };
    let (integrals, blocks) = rest.split_at_mut(rest.len().min(layout::START - STATE_DIM));
    let (before, after) = blocks.split_at_mut(blocks.len().min(A::BLOCK.start - layout::START));
    let (x_rate, after) = after.split_at_mut(after.len().min(A::BLOCK.len()));
    let x = y.get(A::BLOCK).unwrap_or(&[]);
    let power = Actuator::rate(a, body, x, head, x_rate);
    if let [work, dissipated] = integrals {
        (*work, *dissipated) = (power.actuator, power.dissipation);
    }
    // The other actuators' states stay as they are (0). (Two fills of lengths known when
    // compiled; one loop over both took 50 instructions a right-hand side.)
    before.fill(T::zero());
    after.fill(T::zero());
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
    state_rate_supplied(form, y, inputs, form.supply())
}

/// [`state_rate`] with the hydraulic supply's inputs `supply` (`pS`, Pa, and `pump.speed`) in
/// the number type (for derivatives with respect to them); without hydraulics they are not used.
pub fn state_rate_supplied<T: Real>(
    form: &SpecialForm,
    y: &[T; SIMULATION_DIM],
    inputs: &[T; LEG_COUNT],
    supply: Supply<T>,
) -> [T; SIMULATION_DIM] {
    let zero = [T::zero(); STATE_DIM];
    let body = y.first_chunk::<STATE_DIM>().unwrap_or(&zero);
    let mut dy = [T::zero(); SIMULATION_DIM];
    rate_in(form, &Definition { form, body, inputs, supply }, y, &mut dy);
    dy
}

/// The axial forces the actuators exert at the simulation state `y` for the inputs: the
/// inputs themselves (leg forces `F`), with drives the forces of their currents, with
/// hydraulic legs those of their chamber pressures ([`Actuator::axial_forces`]).
pub fn actuator_forces<T: Real>(
    form: &SpecialForm,
    y: &[T; SIMULATION_DIM],
    inputs: &[T; LEG_COUNT],
) -> [T; LEG_COUNT] {
    if form.actuator().kind() == ActuatorKind::Forces {
        return *inputs;
    }
    let zero = [T::zero(); STATE_DIM];
    let state = BodyState::from_vector(y.first_chunk::<STATE_DIM>().unwrap_or(&zero));
    let legs = LegGeometry::new(&form.stand, &state);
    let x = y.get(form.actuator().kind().block()).unwrap_or(&[]);
    with_actuator!(form.actuator(), a => a.axial_forces(&state, &legs, &form.stand.platform_joints, x, inputs))
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

/// The power unit's outputs `[supply.pressure, supply.pumpFlow, supply.reliefFlow,
/// accumulator.oilVolume]` at the simulation state `y` for the supply's inputs `supply`
/// ([`HydraulicActuators::power_unit_outputs`]; 0 without hydraulic legs).
pub fn power_unit_outputs<T: Real>(form: &SpecialForm, y: &[T; SIMULATION_DIM], supply: Supply<T>) -> [T; 4] {
    match (form.hydraulics(), y.get(layout::Hydraulic).and_then(|x| x.try_into().ok())) {
        (Some(h), Some(x)) => h.power_unit_outputs(x, supply),
        _ => [T::zero(); 4],
    }
}

/// `Qsupply` of the hydraulic legs `h` at the simulation state `y` (legs of lengths `l`, rates
/// `l_dot`) and the input `pS` `supply` (with the power unit its line's pressure instead), in
/// any number type ([`HydraulicActuators::supply_flow`]).
pub fn supply_flow_of<T: Real>(
    h: &HydraulicActuators,
    y: &[T; SIMULATION_DIM],
    l: &[T; LEG_COUNT],
    l_dot: &[T; LEG_COUNT],
    supply: T,
) -> T {
    match y.get(layout::Hydraulic).and_then(|x| x.try_into().ok()) {
        Some(x) => h.supply_flow(x, l, l_dot, h.supply_pressure(x, supply)),
        None => T::zero(),
    }
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
    /// After the others: `p_S - (P_0 - p_atm)`, the power unit's supply pressure over the
    /// accumulator's precharge (a sign change is the accumulator emptying or charging again,
    /// where `dV_oil/dp_S` jumps); 1 without the power unit. A switching function of the
    /// steps only with the power unit (the adaptive method lands on it and restarts there, as
    /// at a contact; RK4 steps across it).
    pub const ACCUMULATOR: usize = COUNT;
    /// How many event indicators Model Exchange has.
    pub const EVENT_INDICATORS: usize = COUNT + 1;
}

/// The accumulator's event indicator ([`switching::ACCUMULATOR`]) at the simulation state `y`
/// (or its leading part: 1 where it ends before the supply line).
#[inline(always)]
pub fn accumulator_switching<const N: usize>(form: &SpecialForm, y: &[f64; N]) -> f64 {
    match (form.hydraulics(), y.get(hydraulic::SUPPLY_PRESSURE)) {
        (Some(h), Some(p)) if h.powered => p - h.power_unit.precharge_gauge(),
        _ => 1.0,
    }
}

/// The special-form body coordinates of a simulation state.
#[inline(always)]
pub fn body<const N: usize>(y: &[f64; N]) -> &StateVector {
    y.first_chunk::<STATE_DIM>().unwrap_or(&[0.0; STATE_DIM])
}
