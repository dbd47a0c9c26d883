//! The hydraulic legs as the legs' actuator ([`Actuator`]): the law of [`super`] on each leg's
//! stroke, with the supply pressure (an input) and the chambers' states in the simulation state
//! ([`block`]), their rate, force, check and stability bound.

use super::power_unit::{PowerUnit, PowerUnitRate};
use super::{ATMOSPHERIC_PRESSURE, Chambers, DEFAULT_SUPPLY_PRESSURE, HydraulicLegs, Piston, magnitude};
use crate::physics::actuators::{Actuator, BodyRate, LegMotion, LegPower, PerLegLaw, Supply};
use crate::physics::body::state::{BodyState, STATE_DIM};
use crate::physics::error::{ParameterError, PhysicsFault};
use crate::physics::legs::geometry::LegGeometry;
use crate::physics::legs::per_leg::{Narrow, PerLeg, sum_over_legs};
use crate::physics::number::{Number, Real};
use crate::physics::stand::{LEG_COUNT, check_finite};

/// The hydraulic legs of a stand: the law's parameters, each leg's stroke (from the end
/// stops' `lmin`, `lmax`, whether the stops are on or not), the supply pressure and the pump's
/// speed (inputs held over each step), the chambers' pressures at the start, and the power
/// unit (docs/model.md §10b) when it feeds them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HydraulicActuators {
    pub legs: HydraulicLegs,
    /// `lmin_k`, m: where the piston's position `x_k = l_k - lmin_k` is 0.
    pub lower: [f64; LEG_COUNT],
    /// `L_s = lmax_k - lmin_k`, m.
    pub stroke: [f64; LEG_COUNT],
    /// `p_S`, Pa: the input `pS` (without the power unit; with it, the supply line's pressure
    /// at the start).
    pub supply: f64,
    /// `pump.speed`, 1 (the power unit's input).
    pub pump_speed: f64,
    /// The power unit's parameters, and whether it feeds the legs (`hydraulic.supply = 1`; else
    /// the supply pressure is the input `pS`).
    pub power_unit: PowerUnit,
    pub powered: bool,
    /// `pA0`, `pB0`, Pa.
    pub initial_pa: [f64; LEG_COUNT],
    pub initial_pb: [f64; LEG_COUNT],
}

impl Default for HydraulicActuators {
    /// The default legs on the default end stops' strokes, holding the default stand.
    fn default() -> Self {
        let stops = crate::physics::legs::end_stops::EndStops::default();
        HydraulicActuators::new(HydraulicLegs::default(), stops.lower, stops.upper)
    }
}

/// Where each quantity's six values sit in the hydraulic legs' block of the simulation state,
/// and the two integrals after them.
pub mod block {
    use crate::physics::stand::LEG_COUNT;
    pub const PA: usize = 0;
    pub const PB: usize = LEG_COUNT;
    pub const SPOOL: usize = 2 * LEG_COUNT;
    pub const SPOOL_RATE: usize = 3 * LEG_COUNT;
    /// `work.hydraulic`, `work.compression`.
    pub const WORK_HYDRAULIC: usize = 4 * LEG_COUNT;
    pub const WORK_COMPRESSION: usize = 4 * LEG_COUNT + 1;
    /// The power unit's: the supply line's pressure `p_S` and `work.pump` (last, so that without
    /// the power unit the legs' states are a leading part of the block).
    pub const SUPPLY_PRESSURE: usize = 4 * LEG_COUNT + 2;
    pub const WORK_PUMP: usize = 4 * LEG_COUNT + 3;
    /// The block's length, and that of its leading part without the power unit.
    pub const LEN: usize = 4 * LEG_COUNT + 4;
    pub const LEGS: usize = 4 * LEG_COUNT + 2;
}

/// The hydraulic legs' block of the simulation state, in the number type `T`.
pub type Block<T> = [T; block::LEN];

impl HydraulicActuators {
    /// The legs' law with the strokes `[lmin, lmax]` at the default supply pressure, starting
    /// at the default stand's holding pressures.
    pub fn new(legs: HydraulicLegs, lower: [f64; LEG_COUNT], upper: [f64; LEG_COUNT]) -> Self {
        let (pa, pb) = holding_pressures();
        HydraulicActuators {
            legs,
            lower,
            stroke: std::array::from_fn(|k| upper[k] - lower[k]),
            supply: DEFAULT_SUPPLY_PRESSURE,
            pump_speed: 1.0,
            power_unit: PowerUnit::default(),
            powered: false,
            initial_pa: [pa; LEG_COUNT],
            initial_pb: [pb; LEG_COUNT],
        }
    }

    /// The chambers of leg `k` (< 6) in the legs' block `x`.
    #[inline(always)]
    pub fn chambers<T: Copy>(x: &Block<T>, k: usize) -> Chambers<T> {
        Chambers { pa: x[block::PA + k], pb: x[block::PB + k], spool: x[block::SPOOL + k], spool_rate: x[block::SPOOL_RATE + k] }
    }

    /// The legs' rates at their block `x` (legs of lengths `l`, rates `l_dot`) for the valve
    /// commands `valves` and the supply pressure `supply`, written into `dx`; returns the forces
    /// `u_k` and the sums over the legs of the supply power, the compression power, the losses,
    /// the supply flow `Q_S` and the tank flow `Q_T`. The law through `body`'s
    /// [`BodyRate::per_leg`]: leg by leg in the definition, the six side by side in the steps.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    pub fn leg_rates<T: Real, B: BodyRate<T>>(
        &self,
        body: &B,
        x: &Block<T>,
        l: &[T; LEG_COUNT],
        l_dot: &[T; LEG_COUNT],
        valves: &[T; LEG_COUNT],
        supply: T,
        dx: &mut Block<T>,
    ) -> ([T; LEG_COUNT], [T; 5]) {
        // The block holds each quantity's six values side by side: the law's inputs as they are.
        let quantity = |start: usize| -> [T; LEG_COUNT] { std::array::from_fn(|k| x[start + k]) };
        let inputs = [
            quantity(block::PA),
            quantity(block::PB),
            quantity(block::SPOOL),
            quantity(block::SPOOL_RATE),
            std::array::from_fn(|k| self.piston(k, l[k], l_dot[k]).position),
            self.stroke.map(T::constant),
            *l_dot,
            valves.map(|v| v.clamp_to(T::constant(-1.0), T::constant(1.0))),
            [supply; LEG_COUNT],
        ];
        let [pa_rate, pb_rate, spool_rate, spool_acceleration, u, powers @ ..] = body.per_leg(&LegLaw(&self.legs), &inputs);
        for (start, rates) in
            [(block::PA, pa_rate), (block::PB, pb_rate), (block::SPOOL, spool_rate), (block::SPOOL_RATE, spool_acceleration)]
        {
            dx[start..start + LEG_COUNT].copy_from_slice(&rates);
        }
        (u, powers.map(|p| sum_over_legs(&p)))
    }

    /// The chambers of the six legs side by side (SSE2 pairs on x86-64: the baseline) in the
    /// legs' block `x`, for the step's bounds.
    #[inline(always)]
    fn chambers_side_by_side(x: &Block<f64>) -> Chambers<PerLeg<Narrow>> {
        let quantity = |start: usize| PerLeg::<Narrow>::new(x[start..].first_chunk().unwrap_or(&[0.0; LEG_COUNT]));
        Chambers {
            pa: quantity(block::PA),
            pb: quantity(block::PB),
            spool: quantity(block::SPOOL),
            spool_rate: quantity(block::SPOOL_RATE),
        }
    }

    /// `Qsupply`, m³/s: the flow the six valves draw from the supply at the legs' block `x`
    /// (lengths `l`, rates `l_dot`) and the supply pressure `supply`, in any number type.
    pub fn supply_flow<T: Real>(&self, x: &Block<T>, l: &[T; LEG_COUNT], l_dot: &[T; LEG_COUNT], supply: T) -> T {
        let flows: [T; LEG_COUNT] = std::array::from_fn(|k| {
            self.legs.rate(&Self::chambers(x, k), &self.piston(k, l[k], l_dot[k]), T::zero(), supply).supply_flow
        });
        sum_over_legs(&flows)
    }

    /// The supply pressure the valves see at the legs' block `x`: the power unit's line, or
    /// the input.
    #[inline(always)]
    pub fn supply_pressure<T: Real>(&self, x: &Block<T>, input: T) -> T {
        if self.powered { x[block::SUPPLY_PRESSURE] } else { input }
    }

    /// The power unit's rates at the supply pressure `p` for the pump's speed `speed`, the
    /// valves' draw `drawn` (`Q_S`, m³/s) and return to the tank `returned` (`Q_T`, m³/s):
    /// `(V_s / beta_e(p_S) + dV_oil/dp_S) p_S' = Q_pump - Q_S - Q_relief`, written as `p_S' =
    /// beta_e q / (V_s + beta_e dV_oil/dp_S)` (finite, 0, where `beta_e` is 0), and the line's
    /// compression power as `p_S` times the net inflow into its own oil.
    #[inline(always)]
    pub fn power_unit_rate<T: Real>(&self, p: T, speed: T, drawn: T, returned: T) -> PowerUnitRate<T> {
        let unit = &self.power_unit;
        let (pump, relief) = (unit.pump_flow(speed, p), unit.relief_flow(p));
        let beta = match self.legs.air() {
            None => T::constant(self.legs.bulk_modulus),
            Some(air) => self.legs.effective_bulk_modulus(&air, p),
        };
        let slope = unit.oil_volume_slope(p);
        let net = pump - drawn - relief;
        let pressure_rate = net * beta / (beta * slope + unit.supply_volume);
        let tank = self.legs.tank_pressure;
        PowerUnitRate {
            pressure_rate,
            pump_power: p * pump - (returned + relief) * tank,
            compression_power: p * (net - slope * pressure_rate),
            dissipation: (p - tank) * relief,
        }
    }

    /// The power unit's outputs at the simulation's hydraulic block `x` and the inputs
    /// `supply`: `supply.pressure` (the input `pS` without the power unit), `supply.pumpFlow`,
    /// `supply.reliefFlow`, `accumulator.oilVolume` (0 without it).
    pub fn power_unit_outputs<T: Real>(&self, x: &Block<T>, supply: Supply<T>) -> [T; 4] {
        let p = self.supply_pressure(x, supply.pressure);
        if !self.powered {
            return [p, T::zero(), T::zero(), T::zero()];
        }
        let unit = &self.power_unit;
        // V_oil's value, and its change through its slope (exact to first order: duals).
        let at = p.value();
        let oil = T::constant(unit.oil_volume(at)) + (p - at) * unit.oil_volume_slope(at);
        [p, unit.pump_flow(supply.pump_speed, p), unit.relief_flow(p), oil]
    }

    /// The largest rate (1/s) of the supply line's pressure with the power unit at the legs'
    /// block `x` and the line's pressure `p`: the conductance seen from the line (the pump's
    /// compensator `Q_max / dp_c`, the relief `K_r`, each valve's open land from the supply `K
    /// |s| phi'` and its leakage) over its capacitance `V_s / beta_e + dV_oil/dp_S`; with air as
    /// the chambers' bound ([`HydraulicLegs::stiffness`]): the oil's stiffening with pressure,
    /// and at most half the line's absolute pressure lost in a step.
    fn supply_line_stiffness(&self, chambers: &Chambers<PerLeg<Narrow>>, p: f64) -> f64 {
        let (unit, legs) = (&self.power_unit, &self.legs);
        let speed = self.pump_speed.clamp(0.0, 1.0);
        let mut conductance = speed * unit.max_flow / unit.compensator_band + unit.relief_gain;
        let mut flow = speed * unit.max_flow + unit.relief_flow(p);
        // Each leg's share in lanes, then summed leg by leg in order (the same bits as a loop).
        let Chambers { pa, pb, spool, .. } = *chambers;
        let (zero, line) = (PerLeg::splat(0.0), PerLeg::splat(p));
        let drop = PerLeg::select(zero.greater(spool), line - pb, line - pa);
        let (slope, per_opening) = legs.land(drop);
        let opening = magnitude(spool) * legs.flow_coefficient();
        let leakage = legs.valve_leakage;
        let shares = (opening * slope + 2.0 * leakage).to_array();
        let flows = (opening * per_opening + (magnitude(line - pa) + magnitude(line - pb)) * leakage).to_array();
        for k in 0..LEG_COUNT {
            conductance += shares[k];
            flow += flows[k];
        }
        let slope = unit.oil_volume_slope(p);
        let Some(air) = legs.air() else {
            return conductance * legs.bulk_modulus / (unit.supply_volume + legs.bulk_modulus * slope);
        };
        let beta = legs.effective_bulk_modulus(&air, p);
        let mut rate = conductance * beta / (unit.supply_volume + beta * slope)
            + legs.effective_bulk_modulus_slope(&air, p).abs() * flow / unit.supply_volume;
        let absolute = p + ATMOSPHERIC_PRESSURE;
        if absolute > 0.0 {
            rate = rate.max(4.0 * beta * flow / (unit.supply_volume * absolute));
        }
        rate
    }

    /// The piston of leg `k` at length `l` and rate `l_dot`.
    #[inline(always)]
    pub fn piston<T: Number>(&self, k: usize, l: T, l_dot: T) -> Piston<T> {
        Piston { position: l - self.lower[k], stroke: T::constant(self.stroke[k]), rate: l_dot }
    }

    /// Checks the law's parameters and the strokes.
    pub fn validate(&self) -> Result<(), ParameterError> {
        self.legs.validate()?;
        check_finite("pS", self.supply)?;
        for k in 0..LEG_COUNT {
            if !(self.stroke[k] > 0.0) {
                return Err(ParameterError::new(
                    format!("lmax[{}]", k + 1),
                    format!("the hydraulic leg's stroke lmax - lmin = {:e} m must be > 0", self.stroke[k]),
                ));
            }
        }
        Ok(())
    }
}

/// The default stand's holding pressures `(p_A, p_B)`, Pa: the rod side at half the default
/// supply, the cap side pushing the paper's equilibrium force `0.2005 M g` with it (the legs are
/// massless by default). The start values of `pA0`, `pB0`.
pub fn holding_pressures() -> (f64, f64) {
    let stand = crate::physics::stand::Stand::truck_cabin();
    let force = crate::physics::stand::PAPER_EQUILIBRIUM_LEG_FORCE * stand.mass * stand.gravity;
    let pb = 0.5 * DEFAULT_SUPPLY_PRESSURE;
    (HydraulicLegs::default().cap_pressure(force, pb), pb)
}

/// The fraction of RK4's real stability interval (2.785) a hydraulic step may use: the fast
/// rates grow within a step as a land's drop shrinks.
const STABLE_STEP_FACTOR: f64 = 2.0;

/// The legs' states: the pressures `p_A`, `p_B`, the spools' positions and rates (six each),
/// then `work.hydraulic`, `work.compression` ([`block`]).
/// The hydraulic law of one leg ([`HydraulicLegs::rate`]) as a [`PerLegLaw`]: from `p_A`, `p_B`,
/// `s`, `s'`, the piston's position, stroke and rate, the saturated valve command and the supply
/// pressure to `p_A'`, `p_B'`, `s'`, `s''`, `u`, and the supply power, compression power,
/// losses, `Q_S` and `Q_T`.
struct LegLaw<'a>(&'a HydraulicLegs);

/// How many inputs [`LegLaw`] takes per leg.
const LAW_INPUTS: usize = 9;

impl PerLegLaw<LAW_INPUTS, 10> for LegLaw<'_> {
    #[inline(always)]
    fn at<N: Number>(&self, inputs: [N; LAW_INPUTS]) -> [N; 10] {
        let [pa, pb, spool, spool_rate, position, stroke, rate, command, supply] = inputs;
        let r = self.0.rate(&Chambers { pa, pb, spool, spool_rate }, &Piston { position, stroke, rate }, command, supply);
        [
            r.pa_rate,
            r.pb_rate,
            r.spool_rate,
            r.spool_acceleration,
            r.force,
            r.supply_power,
            r.compression_power,
            r.dissipation,
            r.supply_flow,
            r.tank_flow,
        ]
    }
}

impl Actuator for HydraulicActuators {
    const NAME: &'static str = "hydraulic servo legs";
    const STATES: usize = block::LEN;
    const CHECKS: bool = true;
    const BOUNDED: bool = true;
    const INPUTS: &'static str = "valve commands";
    const INPUT_UNIT: &'static str = "1";

    /// The hydraulic law leg by leg at the legs' lengths and rates, then the body under the
    /// legs' forces (given forces to the body); the lands' and leakages' losses join the
    /// dissipation, the supply's power and the compression power their integrals (`work.F`
    /// stays 0).
    #[inline(always)]
    fn rate<T: Real, B: BodyRate<T>>(&self, body: &B, x: &[T], dy: &mut [T; STATE_DIM], dx: &mut [T]) -> LegPower<T> {
        let (Ok(x), Ok(dx)) = (<&Block<T>>::try_from(x), <&mut Block<T>>::try_from(dx)) else {
            return LegPower { actuator: T::zero(), dissipation: T::zero() };
        };
        let valves = body.inputs();
        let (l, l_dot) = body.legs();
        let inputs = body.supply();
        let supply = self.supply_pressure(x, inputs.pressure);
        let (u, [supplied, compression, losses, drawn, returned]) =
            self.leg_rates(body, x, &l, &l_dot, &valves, supply, dx);
        let power = body.under_forces(&u, dy);
        dx[block::WORK_HYDRAULIC] = supplied;
        if !self.powered {
            dx[block::WORK_COMPRESSION] = compression;
            dx[block::SUPPLY_PRESSURE] = T::zero();
            dx[block::WORK_PUMP] = T::zero();
            return LegPower { actuator: T::zero(), dissipation: power.dissipation + losses };
        }
        let unit = self.power_unit_rate(supply, inputs.pump_speed, drawn, returned);
        dx[block::WORK_COMPRESSION] = compression + unit.compression_power;
        dx[block::SUPPLY_PRESSURE] = unit.pressure_rate;
        dx[block::WORK_PUMP] = unit.pump_power;
        LegPower { actuator: T::zero(), dissipation: power.dissipation + (losses + unit.dissipation) }
    }

    /// `u_k = p_A A_A - p_B A_B`.
    fn axial_forces<T: Real>(
        &self,
        _state: &BodyState<T>,
        _legs: &LegGeometry<T>,
        _platform_joints: &[nalgebra::Vector3<f64>; LEG_COUNT],
        x: &[T],
        _u: &[T; LEG_COUNT],
    ) -> [T; LEG_COUNT] {
        let (area_a, area_b) = self.legs.areas();
        let Ok(x) = <&Block<T>>::try_from(x) else { return [T::zero(); LEG_COUNT] };
        std::array::from_fn(|k| x[block::PA + k] * area_a - x[block::PB + k] * area_b)
    }

    /// The legs' fast modes ([`HydraulicLegs::stiffness`]) against RK4's stability interval
    /// (2.78 on the negative real axis), with a margin for the rate's growth within the step.
    fn stable_step(&self, x: &[f64], legs: impl FnOnce(bool) -> LegMotion) -> f64 {
        let Ok(x) = <&Block<f64>>::try_from(x) else { return f64::INFINITY };
        // The rates bound the chambers' flows, which matter with air alone.
        let LegMotion { lengths: l, rates: l_dot } = legs(self.legs.air().is_some());
        let supply = self.supply_pressure(x, self.supply);
        // The six legs side by side (the same bits as leg by leg).
        let chambers = Self::chambers_side_by_side(x);
        let piston = Piston {
            position: PerLeg::new(&l) - PerLeg::new(&self.lower),
            stroke: PerLeg::new(&self.stroke),
            rate: PerLeg::new(&l_dot),
        };
        let rates = self.legs.stiffness(&chambers, &piston, PerLeg::splat(supply)).to_array();
        let mut fastest = 0.0_f64;
        for rate in rates {
            fastest = fastest.max(rate);
        }
        if self.powered {
            fastest = fastest.max(self.supply_line_stiffness(&chambers, supply));
        }
        STABLE_STEP_FACTOR / fastest
    }

    /// Each chamber's volume must stay positive (a leg far beyond its stroke, through its
    /// stop); the lowest pressure is recorded.
    fn check(&self, x: &[f64], l: &[f64; LEG_COUNT], lowest: &mut f64) -> Result<(), PhysicsFault> {
        for k in 0..LEG_COUNT {
            let (va, vb) = self.legs.volumes(&self.piston(k, l[k], 0.0));
            if !(va > 0.0 && vb > 0.0) {
                return Err(PhysicsFault::ChamberEmptied { leg: k + 1, length: l[k] });
            }
            let pressure = |i: usize| x.get(i + k).copied().unwrap_or(f64::NAN);
            *lowest = lowest.min(pressure(block::PA)).min(pressure(block::PB));
        }
        Ok(())
    }

    fn active_states(&self) -> usize {
        if self.powered { block::LEN } else { block::LEGS }
    }

    /// The accumulator's gas energy `E_acc` (with the power unit): its value, and its change
    /// through `dE_acc/dp_S = p_S dV_oil/dp_S` (exact to first order: duals).
    fn stored_energy<T: Real>(&self, x: &[T]) -> Option<T> {
        if !self.powered {
            return None;
        }
        let p = *x.get(block::SUPPLY_PRESSURE)?;
        let at = p.value();
        let unit = &self.power_unit;
        Some(T::constant(unit.gas_energy(at)) + (p - at) * (at * unit.oil_volume_slope(at)))
    }

    fn validate(&self) -> Result<(), ParameterError> {
        HydraulicActuators::validate(self)?;
        if self.powered {
            self.power_unit.validate()?;
            if self.legs.air().is_some() && !(self.supply > -ATMOSPHERIC_PRESSURE) {
                return Err(ParameterError::new(
                    "pS",
                    format!(
                        "the power unit's supply line starts at pS = {:e} Pa gauge, at or below zero absolute, where \
                         oil with air (hydraulic.airFraction > 0) cannot be",
                        self.supply
                    ),
                ));
            }
        }
        for k in 0..LEG_COUNT {
            for (name, p) in [("pA0", self.initial_pa[k]), ("pB0", self.initial_pb[k])] {
                let name = format!("{name}[{}]", k + 1);
                check_finite(&name, p)?;
                // Oil with air cannot be at or below zero absolute (its bulk modulus is 0 there).
                if self.legs.air().is_some() && !(p > -ATMOSPHERIC_PRESSURE) {
                    return Err(ParameterError::new(
                        name,
                        format!(
                            "{p:e} Pa gauge is at or below zero absolute (-{ATMOSPHERIC_PRESSURE} Pa gauge), where oil \
                             with air (hydraulic.airFraction > 0) cannot be"
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// The chambers at `pA0`, `pB0`; the spools centred and at rest; with the power unit the
    /// supply line at the input `pS`'s value (the accumulator charged to it), else 0 (a state
    /// the integrators leave as it is, and whose value would move the adaptive method's first
    /// step through its norm).
    fn initial_state(&self, x: &mut [f64]) {
        if let Some(slot) = x.get_mut(block::SUPPLY_PRESSURE) {
            *slot = if self.powered { self.supply } else { 0.0 };
        }
        for k in 0..LEG_COUNT {
            for (i, p) in [(block::PA, self.initial_pa[k]), (block::PB, self.initial_pb[k])] {
                if let Some(slot) = x.get_mut(i + k) {
                    *slot = p;
                }
            }
        }
    }

    /// Every piston within its stroke's dead volumes at the start.
    fn check_start(&self, _x: &[f64], l: &[f64; LEG_COUNT]) -> Result<(), ParameterError> {
        for k in 0..LEG_COUNT {
            let (va, vb) = self.legs.volumes(&self.piston(k, l[k], 0.0));
            if !(va > 0.0 && vb > 0.0) {
                return Err(ParameterError::new(
                    format!("lmin[{}]", k + 1),
                    format!(
                        "leg {} starts at {:e} m, where a hydraulic chamber has no volume (V_A = {va:e} m3, V_B = \
                         {vb:e} m3): the initial pose must put every piston within its stroke's dead volumes",
                        k + 1,
                        l[k]
                    ),
                ));
            }
        }
        Ok(())
    }

    fn on_strokes(self, lower: &[f64; LEG_COUNT], upper: &[f64; LEG_COUNT]) -> Self {
        HydraulicActuators { lower: *lower, stroke: std::array::from_fn(|k| upper[k] - lower[k]), ..self }
    }

    fn take_inputs(&mut self, from: &Self) {
        self.supply = from.supply;
        self.pump_speed = from.pump_speed;
    }

    fn describe(&self) -> String {
        let (area_a, area_b) = self.legs.areas();
        format!(
            ", hydraulic servo legs (valve inputs; A_A = {area_a:.4e} m2, A_B = {area_b:.4e} m2, K = {:.4e} \
             m3/(s.Pa^0.5), beta = {:e} Pa, initial pA {:?} Pa, pB {:?} Pa)",
            self.legs.flow_coefficient(),
            self.legs.bulk_modulus,
            self.initial_pa,
            self.initial_pb
        )
    }
}


#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::legs::per_leg::Lanes;

    /// Six legs in states from vacuum to above the supply, both spool sides, with and without
    /// air, for n = 1 and n = 1.4: each input per leg, in `inputs[i][k]`.
    fn states() -> Vec<(HydraulicLegs, [[f64; LEG_COUNT]; LAW_INPUTS])> {
        let mut cases = Vec::new();
        for (air_fraction, air_polytropic) in [(0.0, 1.0), (0.005, 1.0), (0.005, 1.4)] {
            let legs = HydraulicLegs { air_fraction, air_polytropic, ..HydraulicLegs::default() };
            for seed in 0..20_u32 {
                // A fixed spread of values per leg (no random source in the crate's tests).
                let w = |i: usize, k: usize| ((seed as f64 + 1.0) * (i as f64 + 2.3) * (k as f64 + 0.7)).sin();
                let inputs = std::array::from_fn(|i| {
                    std::array::from_fn(|k| match i {
                        0 | 1 => 9e6 + 1.1e7 * w(i, k),  // p_A, p_B: -2e6 .. 2e7 Pa gauge
                        2 => w(i, k),                    // spool
                        3 => 50.0 * w(i, k),             // spool rate
                        4 => 0.2 + 0.19 * w(i, k),       // position
                        5 => 0.4,                        // stroke
                        6 => 0.5 * w(i, k),              // piston rate
                        7 => w(i, k),                    // command
                        _ => 16e6 + 1e6 * w(i, 0),       // supply
                    })
                });
                cases.push((legs, inputs));
            }
        }
        cases
    }

    /// The legs' law and the stiffness bound side by side in registers give each leg's bits.
    fn law_in_lanes_is_leg_by_leg<V: Lanes>() {
        for (legs, inputs) in states() {
            let lanes = LegLaw(&legs).at(inputs.map(|x| PerLeg::<V>::new(&x))).map(PerLeg::to_array);
            let chambers = |k: usize| Chambers { pa: inputs[0][k], pb: inputs[1][k], spool: inputs[2][k], spool_rate: inputs[3][k] };
            let piston = |k: usize| Piston { position: inputs[4][k], stroke: inputs[5][k], rate: inputs[6][k] };
            let stiffness = legs
                .stiffness(
                    &Chambers { pa: PerLeg::<V>::new(&inputs[0]), pb: PerLeg::new(&inputs[1]), spool: PerLeg::new(&inputs[2]), spool_rate: PerLeg::new(&inputs[3]) },
                    &Piston { position: PerLeg::new(&inputs[4]), stroke: PerLeg::new(&inputs[5]), rate: PerLeg::new(&inputs[6]) },
                    PerLeg::new(&inputs[8]),
                )
                .to_array();
            for k in 0..LEG_COUNT {
                let one = LegLaw(&legs).at(inputs.map(|x| x[k]));
                for (o, value) in one.iter().enumerate() {
                    assert_eq!(value.to_bits(), lanes[o][k].to_bits(), "output {o} of leg {k}: {value:e} {:e}", lanes[o][k]);
                }
                let alone = legs.stiffness(&chambers(k), &piston(k), inputs[8][k]);
                assert_eq!(alone.to_bits(), stiffness[k].to_bits(), "stiffness of leg {k}: {alone:e} {:e}", stiffness[k]);
                assert!(alone > 0.0);
            }
        }
    }

    #[test]
    fn the_law_and_its_bound_in_lanes_are_leg_by_leg() {
        law_in_lanes_is_leg_by_leg::<Narrow>();
        if crate::simd::wide_testable() {
            law_in_lanes_is_leg_by_leg::<crate::simd::Wide>();
        }
    }
}
