//! The hydraulic power unit (docs/model.md §10b, `hydraulic.supply = 1`): a supply line of
//! volume `V_s` at pressure `p_S` (a state), fed by a pressure-compensated pump, backed by a
//! gas-charged accumulator, protected by a relief valve and drained by the six valves (`Q_S`):
//!
//! ```text
//! Q_pump   = speed Q_max clamp((p_set + dp_c - p_S) / dp_c, 0, 1)      speed clamped to [0, 1]
//! Q_relief = K_r max(0, p_S - p_relief)
//! V_oil    = V_0 (1 - (P_0 / P_S)^(1/n_a)) charged (P_S > P_0), else 0  (P_S = p_S + p_atm)
//! (V_s / beta_e(p_S) + dV_oil/dp_S) p_S' = Q_pump - Q_S - Q_relief
//! ```
//!
//! Energy: the pump delivers `p_S Q_pump - p_T (Q_T + Q_relief)` (`work.pump`), the relief
//! throttles `(p_S - p_T) Q_relief` (`work.dissipated`), the line's oil stores `p_S V_s p_S' /
//! beta_e(p_S)` (`work.compression`) and the accumulator's gas `E_acc` (in `E`).

use super::ATMOSPHERIC_PRESSURE;
use crate::maths;
use crate::physics::error::ParameterError;
use crate::physics::number::Real;
use crate::physics::stand::check_finite;

/// Default largest pump flow `Q_max`, m³/s: 800 L/min, the default heave programme's peak
/// draw of the six valves (720 L/min at 16 MPa, `output/hydraulic_summary.txt`) with 11 %
/// margin: the pump alone keeps up with the programme, the accumulator is for its failure.
pub const DEFAULT_PUMP_MAX_FLOW: f64 = 800.0e-3 / 60.0;
/// Default compensator setting `p_set`, Pa: SPEC's 16 MPa, the ideal supply's pressure.
pub const DEFAULT_PUMP_SET_PRESSURE: f64 = 16.0e6;
/// Default compensator band `dp_c`, Pa: 0.5 MPa, a pressure-compensated pump's regulation from
/// full flow to none (3 % of the setting); the supply holds within it while the pump keeps up.
pub const DEFAULT_PUMP_COMPENSATOR_BAND: f64 = 0.5e6;
/// Default relief cracking pressure `p_relief`, Pa: 18 MPa, 1.5 MPa above the compensator's
/// no-flow pressure, so that it opens only when the compensator fails to hold.
pub const DEFAULT_RELIEF_PRESSURE: f64 = 18.0e6;
/// Default relief gain `K_r`, m³/(s.Pa): the pump's full flow through the relief at 1 MPa over
/// its cracking pressure.
pub const DEFAULT_RELIEF_GAIN: f64 = DEFAULT_PUMP_MAX_FLOW / 1.0e6;
/// Default accumulator gas volume `V_0`, m³ (40 L): with [`DEFAULT_ACCUMULATOR_PRECHARGE`] it
/// holds 12.9 L between a safe landing's 12 MPa trigger and 6.7 MPa absolute, against the 7.0 L a
/// landing from the top of the default heave fills the rod sides with; checked by simulation over
/// a heave cycle's pump stops and a design study (docs/model.md §10b, "sizing the accumulator").
pub const DEFAULT_ACCUMULATOR_VOLUME: f64 = 40.0e-3;
/// Default precharge `P_0`, Pa absolute: 6 MPa, 90 % of the lowest pressure the landing works
/// down to (6.7 MPa absolute) as accumulator makers advise; a higher precharge gives more oil
/// above the trigger but empties the accumulator during the landing (the design study's map).
pub const DEFAULT_ACCUMULATOR_PRECHARGE: f64 = 6.0e6;
/// Default polytropic exponent `n_a` of the accumulator's gas: 1.4, adiabatic nitrogen (a
/// discharge over seconds exchanges little heat), the conservative choice for sizing.
pub const DEFAULT_ACCUMULATOR_POLYTROPIC: f64 = 1.4;
/// Default supply line volume `V_s`, m³: 5 L of pipes, hoses and manifold between the pump, the
/// accumulator and the six valves.
pub const DEFAULT_SUPPLY_VOLUME: f64 = 5.0e-3;

/// The power unit's parameters (`pump.*`, `relief.*`, `accumulator.*`, `supply.volume`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PowerUnit {
    /// `Q_max`, m³/s.
    pub max_flow: f64,
    /// `p_set`, Pa (gauge).
    pub set_pressure: f64,
    /// `dp_c`, Pa.
    pub compensator_band: f64,
    /// `p_relief`, Pa (gauge).
    pub relief_pressure: f64,
    /// `K_r`, m³/(s.Pa).
    pub relief_gain: f64,
    /// `V_0`, m³.
    pub accumulator_volume: f64,
    /// `P_0`, Pa (absolute).
    pub precharge: f64,
    /// `n_a`.
    pub accumulator_polytropic: f64,
    /// `V_s`, m³.
    pub supply_volume: f64,
}

impl Default for PowerUnit {
    fn default() -> Self {
        PowerUnit {
            max_flow: DEFAULT_PUMP_MAX_FLOW,
            set_pressure: DEFAULT_PUMP_SET_PRESSURE,
            compensator_band: DEFAULT_PUMP_COMPENSATOR_BAND,
            relief_pressure: DEFAULT_RELIEF_PRESSURE,
            relief_gain: DEFAULT_RELIEF_GAIN,
            accumulator_volume: DEFAULT_ACCUMULATOR_VOLUME,
            precharge: DEFAULT_ACCUMULATOR_PRECHARGE,
            accumulator_polytropic: DEFAULT_ACCUMULATOR_POLYTROPIC,
            supply_volume: DEFAULT_SUPPLY_VOLUME,
        }
    }
}

impl PowerUnit {
    /// `Q_pump`, m³/s, at the supply pressure `p` and the pump's speed `speed` (clamped to [0, 1]).
    #[inline(always)]
    pub fn pump_flow<T: Real>(&self, speed: T, p: T) -> T {
        let (zero, one) = (T::constant(0.0), T::constant(1.0));
        let delivery = ((T::constant(self.set_pressure + self.compensator_band) - p) / self.compensator_band)
            .clamp_to(zero, one);
        speed.clamp_to(zero, one) * self.max_flow * delivery
    }

    /// `Q_relief`, m³/s, at the supply pressure `p`.
    #[inline(always)]
    pub fn relief_flow<T: Real>(&self, p: T) -> T {
        let opening = p - self.relief_pressure;
        T::select(opening.greater(T::constant(0.0)), opening * self.relief_gain, T::constant(0.0))
    }

    /// The precharge as a gauge pressure, Pa: the accumulator is charged above it.
    pub fn precharge_gauge(&self) -> f64 {
        self.precharge - ATMOSPHERIC_PRESSURE
    }

    /// Whether the accumulator holds oil at the supply pressure `p` (`P_S > P_0`; empty at
    /// `P_S = P_0` exactly).
    #[inline(always)]
    pub fn charged(&self, p: f64) -> bool {
        p + ATMOSPHERIC_PRESSURE > self.precharge
    }

    /// `V_oil`, m³, at the supply pressure `p`.
    pub fn oil_volume(&self, p: f64) -> f64 {
        if !self.charged(p) {
            return 0.0;
        }
        self.accumulator_volume * (1.0 - self.gas_volume_fraction(p + ATMOSPHERIC_PRESSURE))
    }

    /// `V_g / V_0 = (P_0 / P_S)^(1/n_a)`, the gas's share of the accumulator at the absolute
    /// supply pressure `absolute` (> 0), as `exp(ln(P_0 / P_S) / n_a)`: libm's `log` and `exp`
    /// together take about 145 instructions fewer than its `pow` (benches/results/hydraulics.txt
    /// §7), and every rate evaluation with the power unit needs this once; within a few ulps of
    /// `pow` over the accumulator's range (a test below).
    #[inline(always)]
    fn gas_volume_fraction<T: Real>(&self, absolute: T) -> T {
        ((T::constant(self.precharge) / absolute).ln() * (1.0 / self.accumulator_polytropic)).exp()
    }

    /// `dV_oil/dp_S`, m³/Pa, at the supply pressure `p`: `V_0 / (n_a P_S) (P_0 / P_S)^(1/n_a)`
    /// while charged, 0 while empty (a jump at the precharge: an event).
    #[inline(always)]
    pub fn oil_volume_slope<T: Real>(&self, p: T) -> T {
        let absolute = p + ATMOSPHERIC_PRESSURE;
        let zero = T::constant(0.0);
        if !absolute.greater(T::constant(self.precharge)) {
            return zero;
        }
        self.gas_volume_fraction(absolute) * self.accumulator_volume / (absolute * self.accumulator_polytropic)
    }

    /// The accumulator's gas energy `E_acc`, J, at the supply pressure `p`: `(P_g V_g - P_0 V_0)
    /// / (n_a - 1) - p_atm (V_0 - V_g)` (`P_0 V_0 ln(V_0 / V_g) - p_atm (V_0 - V_g)` for `n_a =
    /// 1`), `V_g = V_0 - V_oil`; 0 while empty.
    pub fn gas_energy(&self, p: f64) -> f64 {
        if !self.charged(p) {
            return 0.0;
        }
        let (v0, p0, na) = (self.accumulator_volume, self.precharge, self.accumulator_polytropic);
        let vg = v0 - self.oil_volume(p);
        let gas = if na == 1.0 { p0 * v0 * maths::ln(v0 / vg) } else { ((p + ATMOSPHERIC_PRESSURE) * vg - p0 * v0) / (na - 1.0) };
        gas - ATMOSPHERIC_PRESSURE * (v0 - vg)
    }

    /// Checks the parameters (FMI names in the errors).
    pub fn validate(&self) -> Result<(), ParameterError> {
        for (name, value, positive) in [
            ("pump.maxFlow", self.max_flow, false),
            ("pump.setPressure", self.set_pressure, false),
            ("pump.compensatorBand", self.compensator_band, true),
            ("relief.pressure", self.relief_pressure, false),
            ("relief.gain", self.relief_gain, false),
            ("accumulator.volume", self.accumulator_volume, false),
            ("accumulator.precharge", self.precharge, true),
            ("accumulator.polytropic", self.accumulator_polytropic, true),
            ("supply.volume", self.supply_volume, true),
        ] {
            check_finite(name, value)?;
            if positive && !(value > 0.0) {
                return Err(ParameterError::new(name, format!("must be > 0, got {value:e}")));
            }
            if !positive && value < 0.0 {
                return Err(ParameterError::new(name, format!("must be >= 0, got {value:e}")));
            }
        }
        Ok(())
    }
}

/// What the power unit adds to a right-hand side.
#[derive(Clone, Copy, Debug)]
pub struct PowerUnitRate<T> {
    /// `p_S'`, Pa/s.
    pub pressure_rate: T,
    /// `p_S Q_pump - p_T (Q_T + Q_relief)`, W.
    pub pump_power: T,
    /// The supply line's compression power `p_S V_s p_S' / beta_e(p_S)`, W.
    pub compression_power: T,
    /// The relief's throttling `(p_S - p_T) Q_relief`, W (>= 0).
    pub dissipation: T,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::number::Dual;

    /// The accumulator's gas energy changes by the work the oil does on it, `p_S dV_oil`
    /// (gauge: the atmosphere's share is in `E_acc`), and its slope is `V_oil`'s derivative.
    #[test]
    fn the_gas_energy_is_the_oil_work_and_the_slope_the_derivative() {
        for na in [1.0, 1.4] {
            let u = PowerUnit { accumulator_polytropic: na, ..PowerUnit::default() };
            for p in [9.5e6, 12e6, 16.3e6] {
                let d = 1e3;
                let slope = (u.oil_volume(p + d) - u.oil_volume(p - d)) / (2.0 * d);
                assert!((u.oil_volume_slope(p) - slope).abs() < 1e-7 * slope, "n_a {na}, p {p:e}");
                let dual = u.oil_volume_slope(Dual::new(p, 1.0)).re;
                assert_eq!(dual, u.oil_volume_slope(p));
                let de = (u.gas_energy(p + d) - u.gas_energy(p - d)) / (2.0 * d);
                assert!((de - p * slope).abs() < 1e-7 * de, "n_a {na}, p {p:e}: {de:e} {:e}", p * slope);
            }
            assert_eq!(u.oil_volume(u.precharge_gauge()), 0.0);
            assert_eq!(u.gas_energy(u.precharge_gauge() - 1.0), 0.0);
        }
    }

    /// The gas's share `(P_0 / P_S)^(1/n_a)` through `log` and `exp` against libm's `pow`: a few
    /// ulps apart from the precharge to far above the relief, and the dual's slope exact.
    #[test]
    fn the_gas_share_is_the_power_law() {
        for na in [1.0, 1.2, 1.4, 1.67] {
            let u = PowerUnit { accumulator_polytropic: na, ..PowerUnit::default() };
            let mut worst = 0_u64;
            for i in 0..=10_000 {
                let absolute = u.precharge * (1.0 + 9.0 * f64::from(i) / 10_000.0);
                let by_pow = maths::pow(u.precharge / absolute, 1.0 / na);
                let ours = u.gas_volume_fraction(absolute);
                worst = worst.max((ours.to_bits() as i64 - by_pow.to_bits() as i64).unsigned_abs());
                let slope = u.gas_volume_fraction(Dual::new(absolute, 1.0)).eps;
                let expected = -by_pow / (na * absolute);
                assert!((slope - expected).abs() <= 1e-14 * expected.abs(), "n_a {na}, P_S {absolute:e}");
            }
            assert!(worst <= 4, "n_a {na}: {worst} ulps from pow");
        }
    }

    /// Full flow up to `p_set`, none from `p_set + dp_c`, linear between; the relief above its
    /// cracking pressure only.
    #[test]
    fn the_pump_and_the_relief_follow_their_characteristics() {
        let u = PowerUnit::default();
        assert_eq!(u.pump_flow(1.0, 10e6), u.max_flow);
        assert_eq!(u.pump_flow(1.0, 16.5e6), 0.0);
        assert!((u.pump_flow(1.0, 16.25e6) / u.max_flow - 0.5).abs() < 1e-12);
        assert_eq!(u.pump_flow(2.0, 10e6), u.max_flow);
        assert_eq!(u.pump_flow(-1.0, 10e6), 0.0);
        assert_eq!(u.relief_flow(17e6), 0.0);
        assert!((u.relief_flow(19e6) - u.max_flow).abs() < 1e-15);
    }
}
