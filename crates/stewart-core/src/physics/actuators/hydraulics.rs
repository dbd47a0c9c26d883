//! Hydraulic servo legs (docs/model.md §10; the paper's stand is driven by hydraulic
//! cylinders): each leg is a double-acting differential cylinder fed by a critically centred
//! four-way servo valve. Per leg, with the piston's stroke position `x = l - lmin` and the
//! stroke `L_s = lmax - lmin`:
//!
//! ```text
//! A_A = pi D^2 / 4,  A_B = pi (D^2 - d^2) / 4          cap and rod side areas
//! V_A = V_A0 + A_A x,  V_B = V_B0 + A_B (L_s - x)      chamber volumes
//! u   = p_A A_A - p_B A_B                              axial force on the leg (replaces F)
//! s'' = w_v^2 (c - s) - 2 zeta_v w_v s'                spool, c = clamp(valve, -1, 1)
//! s >= 0: Q_A = K s phi(p_S - p_A),  Q_B = -K s phi(p_B - p_T)
//! s <  0: Q_A = K s phi(p_A - p_T),  Q_B = -K s phi(p_S - p_B)
//!         + null leakage C_v of both lands of each chamber, to supply and to tank
//! p_A' = beta / V_A (Q_A - A_A l' - Q_i),  p_B' = beta / V_B (Q_B + A_B l' + Q_i)
//! ```
//!
//! with `phi(dp) = dp / (dp^2 + p_cr^2)^(1/4)` (the Modelica library's `regRoot`: `K phi(dp)`
//! tends to `K sgn(dp) sqrt|dp|`), `K = Q_N / sqrt(dp_N / 2)` and `Q_i = C_i (p_A - p_B)`.
//!
//! Oil with entrained air (docs/model.md §10b): with the absolute pressure `P = p + p_atm`, the
//! air's volume fraction `alpha0` at atmospheric pressure and its polytropic exponent `n`, each
//! chamber's `beta` is
//!
//! ```text
//! theta(P) = alpha0 / (1 - alpha0) (p_atm / P)^(1/n)
//! beta_e(p) = beta (1 + theta) / (1 + theta beta / (n P))      (0 at and below zero absolute)
//! ```
//!
//! which tends to `n P` as `P -> 0`: no chamber reaches zero absolute. With `alpha0 = 0` the oil
//! has no air and the law is section 10's, to the bit ([`HydraulicLegs::air`] is `None`).
//!
//! Energy: the power drawn from the supply `P_S = p_S Q_S - p_T Q_T` splits exactly into the
//! leg's power `u l'`, the lands' and leakages' losses (each `Q dp >= 0`) and the compression
//! power `p_A V_A p_A' / beta_e(p_A) + p_B V_B p_B' / beta_e(p_B)` ([`HydraulicRate`]; with air
//! it is computed as `p_A q_A + p_B q_B`, the chambers' net inflows `q` times their pressures,
//! which it equals, and which stays finite where `beta_e` is 0).
//!
//! The law is written once over [`Number`]: one leg in `f64` or [`crate::physics::number::Dual`]
//! (values and exact derivatives), the six side by side in vector registers
//! ([`crate::physics::legs::per_leg::PerLeg`], the steps' fast path: the same bits).

mod actuator;
pub mod power_unit;
pub use actuator::{Block, HydraulicActuators, block, holding_pressures};

use crate::physics::error::ParameterError;
use crate::physics::number::Number;
use crate::physics::stand::check_finite;

/// Default bore `D`, m: an ISO 63 mm cylinder. At the 16 MPa supply it pushes 50 kN, six and a
/// half times the 7.7 kN the default heave programme's most loaded leg needs; so large because
/// the oil column's stiffness grows with the area squared: with this bore the default stand's
/// oil-column modes lie at 60-135 rad/s, above the motion's band.
pub const DEFAULT_BORE: f64 = 0.063;
/// Default rod `d`, m: the ISO 36 mm rod of a 63 mm bore (area ratio 0.67).
pub const DEFAULT_ROD: f64 = 0.036;
/// Default dead volume of the cap side, m³ (0.2 L): a valve mounted on the cylinder, its
/// ports and the cap's end volume. It sets the stiffness near the lower end of the stroke.
pub const DEFAULT_DEAD_VOLUME_A: f64 = 0.2e-3;
/// Default dead volume of the rod side, m³ (0.2 L): as the cap side's.
pub const DEFAULT_DEAD_VOLUME_B: f64 = 0.2e-3;
/// Default effective bulk modulus `beta`, Pa: mineral oil (1.4-1.8 GPa) softened by hoses,
/// seals and a little entrained air.
pub const DEFAULT_BULK_MODULUS: f64 = 1.0e9;
/// Default supply pressure `p_S` (the input `pS`'s start), Pa: 16 MPa, a common industrial
/// supply.
pub const DEFAULT_SUPPLY_PRESSURE: f64 = 16.0e6;
/// Default tank pressure `p_T`, Pa (gauge): 0.
pub const DEFAULT_TANK_PRESSURE: f64 = 0.0;
/// Default rated flow `Q_N`, m³/s: 100 L/min at the rated drop, a size 2-3 servo valve. The
/// default heave programme's fastest leg (0.64 m/s, 120 L/min into the cap side) needs a
/// spool opening of about 0.7 at the supply, which leaves the loop a margin.
pub const DEFAULT_RATED_FLOW: f64 = 100.0e-3 / 60.0;
/// Default rated pressure drop `dp_N`, Pa: 7 MPa over the valve (3.5 MPa per land), the usual
/// rating point of servo valves.
pub const DEFAULT_RATED_PRESSURE_DROP: f64 = 7.0e6;
/// Default spool natural frequency `w_v`, rad/s: 100 Hz, a servo valve's 90 degree phase
/// frequency (80-150 Hz), five times the oil columns' highest mode.
pub const DEFAULT_VALVE_OMEGA: f64 = 2.0 * std::f64::consts::PI * 100.0;
/// Default spool damping ratio `zeta_v`: 0.7, a well damped spool.
pub const DEFAULT_VALVE_DAMPING: f64 = 0.7;
/// Default regularisation pressure `p_cr` of the square-root law, Pa: 1 bar. Above a few bar
/// the flow is within 1 % of the square root; below, the law is linear with a finite slope
/// (the pole it adds, `beta K / (V sqrt(p_cr))`, docs/model.md §10 gives at mid-stroke and
/// near `lmin`).
pub const DEFAULT_PCR: f64 = 1.0e5;
/// Default null leakage `C_v` of each land, m³/(s.Pa): 0.5 L/min of supply flow at null with
/// the chambers at `p_S / 2`, the leakage of a new servo valve of this size.
pub const DEFAULT_VALVE_LEAKAGE: f64 = 5.0e-13;
/// Default internal leakage `C_i` across the piston, m³/(s.Pa): 6 mL/min per MPa, a tight
/// piston seal.
pub const DEFAULT_INTERNAL_LEAKAGE: f64 = 1.0e-13;
/// Default air volume fraction `alpha0` at atmospheric pressure: 0.5 %, undissolved air in a
/// servo oil in service (0.1-1 %), the middle of that range.
/// At the default supply it softens the oil by 0.2 %, at tank pressure fifty times.
pub const DEFAULT_AIR_FRACTION: f64 = 0.005;
/// Default polytropic exponent `n` of the entrained air: 1, isothermal (small bubbles exchange
/// heat with the oil faster than the pressure changes).
pub const DEFAULT_AIR_POLYTROPIC: f64 = 1.0;
/// Atmospheric pressure `p_atm`, Pa: zero gauge is this much above zero absolute.
pub const ATMOSPHERIC_PRESSURE: f64 = 101_325.0;
/// Chamber pressure below which oil without air (`alpha0 = 0`) would cavitate and the model
/// stops being valid, Pa (gauge): -1 bar.
pub const CAVITATION_PRESSURE: f64 = -1.0e5;

/// The hydraulic legs' parameters (`hydraulic.*`, `valve.*`), the same for all six legs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HydraulicLegs {
    /// `D`, m.
    pub bore: f64,
    /// `d`, m.
    pub rod: f64,
    /// `V_A0`, m³.
    pub dead_volume_a: f64,
    /// `V_B0`, m³.
    pub dead_volume_b: f64,
    /// `beta`, Pa.
    pub bulk_modulus: f64,
    /// `p_T`, Pa.
    pub tank_pressure: f64,
    /// `Q_N`, m³/s.
    pub rated_flow: f64,
    /// `dp_N`, Pa.
    pub rated_pressure_drop: f64,
    /// `w_v`, rad/s.
    pub valve_omega: f64,
    /// `zeta_v`.
    pub valve_damping: f64,
    /// `p_cr`, Pa.
    pub pcr: f64,
    /// `C_v`, m³/(s.Pa).
    pub valve_leakage: f64,
    /// `C_i`, m³/(s.Pa).
    pub internal_leakage: f64,
    /// `alpha0`, the air's volume fraction at atmospheric pressure (0 = oil without air).
    pub air_fraction: f64,
    /// `n`, the air's polytropic exponent.
    pub air_polytropic: f64,
}

/// The entrained air's constants of [`HydraulicLegs::effective_bulk_modulus`] (with air).
#[derive(Clone, Copy, Debug)]
pub struct EntrainedAir {
    /// `alpha0 / (1 - alpha0)`.
    ratio: f64,
    /// `1 / n`.
    inverse_polytropic: f64,
    /// `beta / n`, Pa.
    beta_over_n: f64,
    /// `a = alpha0 / (1 - alpha0) p_atm` (Pa) and `a beta / n` (Pa²): for `n = 1`, `theta =
    /// a / P` and `beta_e = beta P (P + a) / (P^2 + a beta / n)`, one division.
    air_pressure: f64,
    isothermal_constant: f64,
}

impl Default for HydraulicLegs {
    fn default() -> Self {
        HydraulicLegs {
            bore: DEFAULT_BORE,
            rod: DEFAULT_ROD,
            dead_volume_a: DEFAULT_DEAD_VOLUME_A,
            dead_volume_b: DEFAULT_DEAD_VOLUME_B,
            bulk_modulus: DEFAULT_BULK_MODULUS,
            tank_pressure: DEFAULT_TANK_PRESSURE,
            rated_flow: DEFAULT_RATED_FLOW,
            rated_pressure_drop: DEFAULT_RATED_PRESSURE_DROP,
            valve_omega: DEFAULT_VALVE_OMEGA,
            valve_damping: DEFAULT_VALVE_DAMPING,
            pcr: DEFAULT_PCR,
            valve_leakage: DEFAULT_VALVE_LEAKAGE,
            internal_leakage: DEFAULT_INTERNAL_LEAKAGE,
            air_fraction: DEFAULT_AIR_FRACTION,
            air_polytropic: DEFAULT_AIR_POLYTROPIC,
        }
    }
}

/// One leg's hydraulic state.
#[derive(Clone, Copy, Debug)]
pub struct Chambers<T> {
    /// `p_A`, `p_B`, Pa (gauge).
    pub pa: T,
    pub pb: T,
    /// `s`, normalised spool position, and `s'`, 1/s.
    pub spool: T,
    pub spool_rate: T,
}

/// Where one leg's piston is: `x = l - lmin` (m), the stroke `L_s` (m) and `l'` (m/s).
#[derive(Clone, Copy, Debug)]
pub struct Piston<T> {
    pub position: T,
    pub stroke: T,
    pub rate: T,
}

/// One leg's contribution to a right-hand side.
#[derive(Clone, Copy, Debug)]
pub struct HydraulicRate<T> {
    /// `u = p_A A_A - p_B A_B`, N.
    pub force: T,
    /// `p_A'`, `p_B'`, Pa/s.
    pub pa_rate: T,
    pub pb_rate: T,
    /// `s'` (1/s) and `s''` (1/s²).
    pub spool_rate: T,
    pub spool_acceleration: T,
    /// `Q_S`, m³/s: drawn from the supply (leakage included).
    pub supply_flow: T,
    /// `Q_T`, m³/s: returned to the tank (leakage included).
    pub tank_flow: T,
    /// `P_S = p_S Q_S - p_T Q_T`, W.
    pub supply_power: T,
    /// `p_A V_A p_A' / beta_e(p_A) + p_B V_B p_B' / beta_e(p_B)`, W.
    pub compression_power: T,
    /// The lands' throttling, the null leakage and the internal leakage, W (>= 0).
    pub dissipation: T,
}

impl HydraulicLegs {
    /// `(A_A, A_B)`, m².
    pub fn areas(&self) -> (f64, f64) {
        let quarter_pi = 0.25 * std::f64::consts::PI;
        (quarter_pi * self.bore * self.bore, quarter_pi * (self.bore * self.bore - self.rod * self.rod))
    }

    /// `K = Q_N / sqrt(dp_N / 2)`, m³/(s.Pa^1/2).
    pub fn flow_coefficient(&self) -> f64 {
        self.rated_flow / (0.5 * self.rated_pressure_drop).sqrt()
    }

    /// The entrained air's constants, `None` for oil without air (`alpha0 = 0`).
    #[inline(always)]
    pub fn air(&self) -> Option<EntrainedAir> {
        (self.air_fraction != 0.0).then(|| {
            let ratio = self.air_fraction / (1.0 - self.air_fraction);
            let beta_over_n = self.bulk_modulus / self.air_polytropic;
            EntrainedAir {
                ratio,
                inverse_polytropic: 1.0 / self.air_polytropic,
                beta_over_n,
                air_pressure: ratio * ATMOSPHERIC_PRESSURE,
                isothermal_constant: ratio * ATMOSPHERIC_PRESSURE * beta_over_n,
            }
        })
    }

    /// `beta_e(p)`, Pa, of oil with entrained air at the gauge pressure `p`: `beta (1 + theta) /
    /// (1 + theta beta / (n P))`, `theta = alpha0 / (1 - alpha0) (p_atm / P)^(1/n)`, `P = p +
    /// p_atm`; 0 at and below zero absolute (its limit there: `beta_e -> n P`). Computed
    /// everywhere and then selected, so that six legs side by side take the same bits.
    #[inline(always)]
    pub fn effective_bulk_modulus<T: Number>(&self, air: &EntrainedAir, p: T) -> T {
        let absolute = p + ATMOSPHERIC_PRESSURE;
        let zero = T::constant(0.0);
        let beta_e = if air.inverse_polytropic == 1.0 {
            // n = 1 (the default): theta = a / P, multiplied through by P^2.
            absolute * (absolute + air.air_pressure) * self.bulk_modulus / (absolute * absolute + air.isothermal_constant)
        } else {
            let theta = (T::constant(ATMOSPHERIC_PRESSURE) / absolute).powf(air.inverse_polytropic) * air.ratio;
            (theta + 1.0) * self.bulk_modulus / (theta * air.beta_over_n / absolute + 1.0)
        };
        T::select(absolute.greater(zero), beta_e, zero)
    }

    /// `beta_e'(p)`, the effective bulk modulus's rate of change with pressure (1), in closed
    /// form: for `n = 1` `beta (2 P c - a P^2 + a c) / (P^2 + c)^2` with `c = a beta / n`;
    /// otherwise `beta (theta' D - (1 + theta) D') / D^2` with `D = 1 + theta beta / (n P)`,
    /// `theta' = -theta / (n P)` and `D' = -theta beta / (n P^2) (1 / n + 1)`. 0 at and below
    /// zero absolute.
    #[inline(always)]
    pub fn effective_bulk_modulus_slope<T: Number>(&self, air: &EntrainedAir, p: T) -> T {
        let absolute = p + ATMOSPHERIC_PRESSURE;
        let zero = T::constant(0.0);
        let slope = if air.inverse_polytropic == 1.0 {
            let (a, c) = (air.air_pressure, air.isothermal_constant);
            let d = absolute * absolute + c;
            (absolute * 2.0 * c - absolute * a * absolute + a * c) * self.bulk_modulus / (d * d)
        } else {
            let n = air.inverse_polytropic;
            let theta = (T::constant(ATMOSPHERIC_PRESSURE) / absolute).powf(n) * air.ratio;
            let d = theta * air.beta_over_n / absolute + 1.0;
            let theta_rate = zero - theta * n / absolute;
            let d_rate = zero - theta * air.beta_over_n / (absolute * absolute) * (n + 1.0);
            (theta_rate * d - (theta + 1.0) * d_rate) * self.bulk_modulus / (d * d)
        };
        T::select(absolute.greater(zero), slope, zero)
    }

    /// `(V_A, V_B)`, m³, at the piston position `x` in a stroke `L_s`.
    #[inline(always)]
    pub fn volumes<T: Number>(&self, piston: &Piston<T>) -> (T, T) {
        let (area_a, area_b) = self.areas();
        (piston.position * area_a + self.dead_volume_a, (piston.stroke - piston.position) * area_b + self.dead_volume_b)
    }

    /// The rates, the force, the flows and the powers of one leg (or six side by side) at its
    /// state `chambers`, piston `piston`, saturated valve command `command` (in [-1, 1]) and
    /// supply pressure `supply`: the law.
    #[inline(always)]
    pub fn rate<T: Number>(
        &self,
        chambers: &Chambers<T>,
        piston: &Piston<T>,
        command: T,
        supply: T,
    ) -> HydraulicRate<T> {
        let (area_a, area_b) = self.areas();
        let k = self.flow_coefficient();
        let tank = self.tank_pressure;
        let pcr2 = self.pcr * self.pcr;
        let Chambers { pa, pb, spool, spool_rate } = *chambers;
        // phi(dp) = dp / (dp^2 + p_cr^2)^(1/4): a function, not a closure, so that it inlines
        // into the AVX2 path.
        #[inline(always)]
        fn phi<T: Number>(dp: T, pcr2: f64) -> T {
            dp / (dp * dp + pcr2).sqrt().sqrt()
        }
        let zero = T::constant(0.0);
        let opening = spool * k;
        // The four lands' flows (each >= 0 in the direction written), by the spool's side.
        let extend = spool.greater(zero);
        let retract = zero.greater(spool);
        let supply_a = T::select(extend, opening * phi(supply - pa, pcr2), zero);
        let b_tank = T::select(extend, opening * phi(pb - tank, pcr2), zero);
        let closing = zero - opening;
        let a_tank = T::select(retract, closing * phi(pa - tank, pcr2), zero);
        let supply_b = T::select(retract, closing * phi(supply - pb, pcr2), zero);
        // The null leakage, each chamber to supply and to tank.
        let (drop_sa, drop_at, drop_sb, drop_bt) = (supply - pa, pa - tank, supply - pb, pb - tank);
        let (leak_sa, leak_at) = (drop_sa * self.valve_leakage, drop_at * self.valve_leakage);
        let (leak_sb, leak_bt) = (drop_sb * self.valve_leakage, drop_bt * self.valve_leakage);
        let internal = (pa - pb) * self.internal_leakage;
        let flow_a = (supply_a - a_tank) + (leak_sa - leak_at);
        let flow_b = (supply_b - b_tank) + (leak_sb - leak_bt);
        let (volume_a, volume_b) = self.volumes(piston);
        // The chambers' net inflows q_A, q_B and their rates beta_e q / V.
        let inflow_a = flow_a - piston.rate * area_a - internal;
        let inflow_b = flow_b + piston.rate * area_b + internal;
        let (pa_rate, pb_rate, compression_power) = match self.air() {
            // Oil without air: section 10's expressions, in their order (the same bits).
            None => {
                let beta = self.bulk_modulus;
                let pa_rate = inflow_a * beta / volume_a;
                let pb_rate = inflow_b * beta / volume_b;
                (pa_rate, pb_rate, (pa * volume_a * pa_rate + pb * volume_b * pb_rate) / beta)
            }
            Some(air) => (
                inflow_a * self.effective_bulk_modulus(&air, pa) / volume_a,
                inflow_b * self.effective_bulk_modulus(&air, pb) / volume_b,
                pa * inflow_a + pb * inflow_b,
            ),
        };
        let supply_flow = (supply_a + supply_b) + (leak_sa + leak_sb);
        let tank_flow = (a_tank + b_tank) + (leak_at + leak_bt);
        let w = self.valve_omega;
        HydraulicRate {
            force: pa * area_a - pb * area_b,
            pa_rate,
            pb_rate,
            spool_rate,
            spool_acceleration: (command - spool) * (w * w) - spool_rate * (2.0 * self.valve_damping * w),
            supply_flow,
            supply_power: supply * supply_flow - tank_flow * tank,
            tank_flow,
            compression_power,
            dissipation: ((supply_a * drop_sa + a_tank * drop_at) + (supply_b * drop_sb + b_tank * drop_bt))
                + ((leak_sa * drop_sa + leak_at * drop_at) + (leak_sb * drop_sb + leak_bt * drop_bt))
                + internal * (pa - pb),
        }
    }

    /// The largest rate (1/s) of the leg's fast linear modes at a state: each chamber's own
    /// `beta / V (K |s| phi'(dp) + 2 C_v + C_i)` (the orifice pole, up to `beta K / (V
    /// sqrt(p_cr))` for an open land with little drop; `beta >= beta_e` below 1 GPa absolute),
    /// with air plus `|beta_e'(p) q| / V` (the oil's stiffening with pressure, large where it
    /// turns soft: a chamber emptying towards vacuum) and at least `4 beta_e |q| / (V P)` (so
    /// that a step loses at most half of a chamber's absolute pressure `P`), and the spool's
    /// `|lambda| <= w_v max(1, 2 zeta_v)`. An explicit method of stability interval `r` is stable for steps up to
    /// about `r / rate`. One leg, or six side by side (the steps' bound).
    #[inline(always)]
    pub fn stiffness<T: Number>(&self, chambers: &Chambers<T>, piston: &Piston<T>, supply: T) -> T {
        let k = self.flow_coefficient();
        let zero = T::constant(0.0);
        let Chambers { pa, pb, spool, .. } = *chambers;
        let tank = self.tank_pressure;
        // The open lands: supply to A and B to tank for s >= 0, A to tank and supply to B for s < 0.
        let retract = zero.greater(spool);
        let s = T::select(retract, zero - spool, spool);
        let (a_in, flow_a) = self.land(T::select(retract, pa - tank, supply - pa));
        let (b_in, flow_b) = self.land(T::select(retract, supply - pb, pb - tank));
        let leak = 2.0 * self.valve_leakage + self.internal_leakage;
        let (va, vb) = self.volumes(piston);
        let beta = T::constant(self.bulk_modulus);
        let mut chamber_a = beta / va * (s * k * a_in + leak);
        let mut chamber_b = beta / vb * (s * k * b_in + leak);
        if let Some(air) = self.air() {
            // |q| bounded by its terms: the open land, both lands' leakage, the piston, the
            // internal leakage.
            let (area_a, area_b) = self.areas();
            let internal = magnitude(pa - pb) * self.internal_leakage;
            let piston_rate = magnitude(piston.rate);
            let q_a = s * k * flow_a
                + (magnitude(supply - pa) + magnitude(pa - tank)) * self.valve_leakage
                + piston_rate * area_a
                + internal;
            let q_b = s * k * flow_b
                + (magnitude(supply - pb) + magnitude(pb - tank)) * self.valve_leakage
                + piston_rate * area_b
                + internal;
            chamber_a = chamber_a + magnitude(self.effective_bulk_modulus_slope(&air, pa)) * q_a / va;
            chamber_b = chamber_b + magnitude(self.effective_bulk_modulus_slope(&air, pb)) * q_b / vb;
            // No chamber may lose more than half its absolute pressure in a step (2 / rate):
            // from high pressure an emptying chamber falls almost linearly, and one step past
            // zero absolute would leave it there (beta_e = 0).
            let (absolute_a, absolute_b) = (pa + ATMOSPHERIC_PRESSURE, pb + ATMOSPHERIC_PRESSURE);
            let emptying_a = self.effective_bulk_modulus(&air, pa) * 4.0 * q_a / (va * absolute_a);
            let emptying_b = self.effective_bulk_modulus(&air, pb) * 4.0 * q_b / (vb * absolute_b);
            chamber_a = larger(chamber_a, T::select(absolute_a.greater(zero), emptying_a, zero));
            chamber_b = larger(chamber_b, T::select(absolute_b.greater(zero), emptying_b, zero));
        }
        larger(larger(chamber_a, chamber_b), T::constant(self.valve_omega * (2.0 * self.valve_damping).max(1.0)))
    }

    /// An open land's `(phi'(dp), |phi(dp)|)` at the drop `dp`: its flow's slope and its flow
    /// per `K |s|`. `phi'(dp) = (dp^2 / 2 + p_cr^2) / (dp^2 + p_cr^2)^(5/4)`.
    #[inline(always)]
    pub fn land<T: Number>(&self, dp: T) -> (T, T) {
        let pcr2 = self.pcr * self.pcr;
        let q = dp * dp + pcr2;
        let root = q.sqrt().sqrt();
        ((dp * 0.5 * dp + pcr2) / (q * root), magnitude(dp) / root)
    }

    /// The cap-side pressure `p_A` (Pa) at which the leg pushes with `force` (N) for the rod-side
    /// pressure `p_B`.
    pub fn cap_pressure(&self, force: f64, pb: f64) -> f64 {
        let (area_a, area_b) = self.areas();
        (force + pb * area_b) / area_a
    }

    /// Checks the parameters (FMI names in the errors).
    pub fn validate(&self) -> Result<(), ParameterError> {
        for (name, value, positive) in [
            ("hydraulic.bore", self.bore, true),
            ("hydraulic.rod", self.rod, false),
            ("hydraulic.deadVolumeA", self.dead_volume_a, true),
            ("hydraulic.deadVolumeB", self.dead_volume_b, true),
            ("hydraulic.bulkModulus", self.bulk_modulus, true),
            ("hydraulic.tankPressure", self.tank_pressure, false),
            ("valve.ratedFlow", self.rated_flow, true),
            ("valve.ratedPressureDrop", self.rated_pressure_drop, true),
            ("valve.omega", self.valve_omega, true),
            ("valve.damping", self.valve_damping, true),
            ("valve.pcr", self.pcr, true),
            ("valve.leakage", self.valve_leakage, false),
            ("hydraulic.internalLeakage", self.internal_leakage, false),
            ("hydraulic.airFraction", self.air_fraction, false),
            ("hydraulic.airPolytropic", self.air_polytropic, true),
        ] {
            check_finite(name, value)?;
            if positive && !(value > 0.0) {
                return Err(ParameterError::new(name, format!("must be > 0, got {value:e}")));
            }
            if !positive && value < 0.0 && name != "hydraulic.tankPressure" {
                return Err(ParameterError::new(name, format!("must be >= 0, got {value:e}")));
            }
        }
        if !(self.air_fraction < 1.0) {
            return Err(ParameterError::new(
                "hydraulic.airFraction",
                format!("the air's volume fraction at atmospheric pressure must be in [0, 1), got {:e}", self.air_fraction),
            ));
        }
        if !(self.rod < self.bore) {
            return Err(ParameterError::new(
                "hydraulic.rod",
                format!("must be smaller than hydraulic.bore = {:e} m, got {:e} m", self.bore, self.rod),
            ));
        }
        if !(self.flow_coefficient().is_finite()) {
            return Err(ParameterError::new(
                "valve.ratedFlow",
                format!(
                    "the flow coefficient valve.ratedFlow / sqrt(valve.ratedPressureDrop / 2) = {:e} is not finite",
                    self.flow_coefficient()
                ),
            ));
        }
        Ok(())
    }
}

/// The valve command `c = clamp(valve, -1, 1)` (NaN stays NaN, and is refused at the input).
pub fn saturated(valve: f64) -> f64 {
    valve.clamp(-1.0, 1.0)
}

/// `|x|` in any number type (`-x` where `x < 0`).
#[inline(always)]
fn magnitude<T: Number>(x: T) -> T {
    let zero = T::constant(0.0);
    T::select(zero.greater(x), zero - x, x)
}

/// The larger of `a` and `b` by value (`a` if equal) in any number type.
#[inline(always)]
fn larger<T: Number>(a: T, b: T) -> T {
    T::select(b.greater(a), b, a)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::number::Dual;

    fn leg() -> (Chambers<f64>, Piston<f64>) {
        (
            Chambers { pa: 7.3e6, pb: 8.1e6, spool: 0.3, spool_rate: -2.0 },
            Piston { position: 0.3, stroke: 0.7, rate: 0.4 },
        )
    }

    /// `P_S = u l' + losses + compression power` to round-off, for either spool side, written
    /// from the flows independently of the law's bookkeeping.
    #[test]
    fn the_power_balance_closes() {
        let h = HydraulicLegs::default();
        for spool in [0.3, -0.4, 0.0] {
            let (mut c, p) = leg();
            c.spool = spool;
            let r = h.rate(&c, &p, 0.5, 16e6);
            let residual = r.supply_power - (r.force * p.rate + r.dissipation + r.compression_power);
            assert!(residual.abs() < 1e-9 * r.supply_power.abs().max(1.0), "spool {spool}: {residual:e} W");
            assert!(r.dissipation >= 0.0);
        }
    }

    /// With air the compression power `p q` is `p V p' / beta_e(p)` of each chamber, and the
    /// balance closes as without air; at and below zero absolute a chamber's pressure stands.
    #[test]
    fn with_air_the_power_balance_closes_and_vacuum_is_a_floor() {
        let h = HydraulicLegs::default();
        let air = h.air().expect("the default oil carries air");
        let (c, p) = leg();
        for (pa, pb) in [(7.3e6, 8.1e6), (2e4, -9e4), (-1.0e5, 3e5)] {
            let chambers = Chambers { pa, pb, ..c };
            let r = h.rate(&chambers, &p, 0.5, 16e6);
            let (va, vb) = h.volumes(&p);
            let written = pa * va * r.pa_rate / h.effective_bulk_modulus(&air, pa)
                + pb * vb * r.pb_rate / h.effective_bulk_modulus(&air, pb);
            assert!((r.compression_power - written).abs() < 1e-12 * written.abs().max(1.0), "{pa:e} {pb:e}");
            let residual = r.supply_power - (r.force * p.rate + r.dissipation + r.compression_power);
            assert!(residual.abs() < 1e-9 * r.supply_power.abs().max(1.0), "{residual:e} W");
        }
        let below = Chambers { pa: -ATMOSPHERIC_PRESSURE, pb: -2.0e5, ..c };
        let r = h.rate(&below, &p, 0.5, 16e6);
        assert_eq!((r.pa_rate, r.pb_rate), (0.0, 0.0));
    }

    /// `beta_e`: `beta` without air, the liquid's `beta` (to 1 %) at the supply, `n P` near
    /// zero absolute (for n = 1 and n = 1.4), and its derivative the central difference's.
    #[test]
    fn the_effective_bulk_modulus_has_its_limits_and_derivative() {
        for n in [1.0, 1.4] {
            let h = HydraulicLegs { air_polytropic: n, ..HydraulicLegs::default() };
            let air = h.air().unwrap();
            let at = |p: f64| h.effective_bulk_modulus(&air, p);
            assert!((at(16e6) / h.bulk_modulus - 1.0).abs() < 1e-2, "{}", at(16e6));
            let absolute = 1e-3;
            assert!((at(absolute - ATMOSPHERIC_PRESSURE) / (n * absolute) - 1.0).abs() < 1e-3);
            for p in [-9.0e4, 0.0, 5e5, 7e6] {
                let d = 1e-3 * (p + ATMOSPHERIC_PRESSURE);
                let central = (at(p + d) - at(p - d)) / (2.0 * d);
                let exact = h.effective_bulk_modulus(&air, Dual::new(p, 1.0)).eps;
                assert!((exact - central).abs() < 1e-5 * central.abs(), "n {n}, p {p:e}: {exact:e} {central:e}");
                let closed = h.effective_bulk_modulus_slope(&air, p);
                assert!((closed - central).abs() < 1e-5 * central.abs(), "n {n}, p {p:e}: {closed:e} {central:e}");
                assert!((closed - exact).abs() < 1e-12 * exact.abs(), "n {n}, p {p:e}: {closed:e} {exact:e}");
            }
        }
        let without = HydraulicLegs { air_fraction: 0.0, ..HydraulicLegs::default() };
        assert!(without.air().is_none());
    }

    /// At a large drop the regularised law is the square root: `Q = K s sqrt(dp)`, and the
    /// rated flow passes at the rated drop over both lands.
    #[test]
    fn the_rated_flow_passes_at_the_rated_drop() {
        let h = HydraulicLegs { valve_leakage: 0.0, internal_leakage: 0.0, ..HydraulicLegs::default() };
        // Both lands see dp_N / 2: supply 7 MPa, p_A = 3.5 MPa, p_B = 3.5 MPa, tank 0, blocked piston.
        let c = Chambers { pa: 3.5e6, pb: 3.5e6, spool: 1.0, spool_rate: 0.0 };
        let p = Piston { position: 0.35, stroke: 0.7, rate: 0.0 };
        let r = h.rate(&c, &p, 1.0, 7.0e6);
        // The regularisation's deficit at dp = 3.5 MPa: (1 + (p_cr/dp)^2)^(-1/4) = 1 - 2.0e-4.
        let deficit = (1.0 + (h.pcr / 3.5e6_f64).powi(2)).powf(-0.25);
        assert!((r.supply_flow / (h.rated_flow * deficit) - 1.0).abs() < 1e-14, "{}", r.supply_flow / h.rated_flow);
    }
}
