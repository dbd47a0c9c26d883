//! The hydraulic legs as the legs' actuator ([`Actuator`]): the law of [`super`] on each leg's
//! stroke, with the supply pressure (an input) and the chambers' states in the simulation state
//! ([`block`]), their rate, force, check and stability bound.

use super::{ATMOSPHERIC_PRESSURE, Chambers, DEFAULT_SUPPLY_PRESSURE, HydraulicLegs, Piston};
use crate::physics::actuators::{Actuator, BodyRate, LegMotion, LegPower};
use crate::physics::body::state::{BodyState, STATE_DIM};
use crate::physics::error::{ParameterError, PhysicsFault};
use crate::physics::legs::geometry::LegGeometry;
use crate::physics::legs::per_leg::sum_over_legs;
use crate::physics::number::{Number, Real};
use crate::physics::stand::{LEG_COUNT, check_finite};

/// The hydraulic legs of a stand: the law's parameters, each leg's stroke (from the end
/// stops' `lmin`, `lmax`, whether the stops are on or not), the supply pressure (an input held
/// over each step) and the chambers' pressures at the start.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HydraulicActuators {
    pub legs: HydraulicLegs,
    /// `lmin_k`, m: where the piston's position `x_k = l_k - lmin_k` is 0.
    pub lower: [f64; LEG_COUNT],
    /// `L_s = lmax_k - lmin_k`, m.
    pub stroke: [f64; LEG_COUNT],
    /// `p_S`, Pa.
    pub supply: f64,
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
    /// The block's length.
    pub const LEN: usize = 4 * LEG_COUNT + 2;
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
    /// `u_k` and the sums over the legs of the supply power, the compression power and the
    /// losses. Leg by leg, in any number type.
    #[inline(always)]
    pub fn leg_rates<T: Real>(
        &self,
        x: &Block<T>,
        l: &[T; LEG_COUNT],
        l_dot: &[T; LEG_COUNT],
        valves: &[T; LEG_COUNT],
        supply: T,
        dx: &mut Block<T>,
    ) -> ([T; LEG_COUNT], [T; 3]) {
        let mut u = [T::zero(); LEG_COUNT];
        let mut powers = [[T::zero(); LEG_COUNT]; 3];
        for k in 0..LEG_COUNT {
            let command = valves[k].clamp_to(T::constant(-1.0), T::constant(1.0));
            let r = self.legs.rate(&Self::chambers(x, k), &self.piston(k, l[k], l_dot[k]), command, supply);
            dx[block::PA + k] = r.pa_rate;
            dx[block::PB + k] = r.pb_rate;
            dx[block::SPOOL + k] = r.spool_rate;
            dx[block::SPOOL_RATE + k] = r.spool_acceleration;
            u[k] = r.force;
            powers[0][k] = r.supply_power;
            powers[1][k] = r.compression_power;
            powers[2][k] = r.dissipation;
        }
        (u, powers.map(|p| sum_over_legs(&p)))
    }

    /// `Qsupply`, m³/s: the flow the six valves draw from the supply at the legs' block `x`
    /// (lengths `l`, rates `l_dot`) and the supply pressure `supply`, in any number type.
    pub fn supply_flow<T: Real>(&self, x: &Block<T>, l: &[T; LEG_COUNT], l_dot: &[T; LEG_COUNT], supply: T) -> T {
        let flows: [T; LEG_COUNT] = std::array::from_fn(|k| {
            self.legs.rate(&Self::chambers(x, k), &self.piston(k, l[k], l_dot[k]), T::zero(), supply).supply_flow
        });
        sum_over_legs(&flows)
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
impl Actuator for HydraulicActuators {
    const NAME: &'static str = "hydraulic servo legs";
    const STATES: usize = 4 * LEG_COUNT + 2;
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
        let (u, [supplied, compression, losses]) = self.leg_rates(x, &l, &l_dot, &valves, body.supply(), dx);
        let power = body.under_forces(&u, dy);
        dx[block::WORK_HYDRAULIC] = supplied;
        dx[block::WORK_COMPRESSION] = compression;
        LegPower { actuator: T::zero(), dissipation: power.dissipation + losses }
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
        let mut fastest = 0.0_f64;
        for k in 0..LEG_COUNT {
            fastest =
                fastest.max(self.legs.stiffness(&Self::chambers(x, k), &self.piston(k, l[k], l_dot[k]), self.supply));
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

    fn validate(&self) -> Result<(), ParameterError> {
        HydraulicActuators::validate(self)?;
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

    /// The chambers at `pA0`, `pB0`; the spools centred and at rest.
    fn initial_state(&self, x: &mut [f64]) {
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

