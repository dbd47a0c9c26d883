//! An independent reference formulation ("oracle") of the whole machine of SPEC §1, §6, §8,
//! §9, §10 and §10b: the loaded platform on six legs that are two bodies each (cylinder and
//! rod), with end stops, joint limits, cylinder friction and optional DC drives or hydraulic
//! servo legs (oil with entrained air, and a power unit).
//!
//! Formulation: Kane's equations (d'Alembert's principle in generalised speeds) with the
//! generalised speeds `nu = (v, w)`: `v` the centre-of-mass velocity (inertial components),
//! `w` the angular velocity (body components). Every leg is written as a set of "particles"
//! whose kinetic energies add up to the leg's `T` of SPEC §8: the cylinder's centre of mass
//! `c_k` (mass `m_c`), the rod's centre of mass `p_k` (mass `m_r`), the unit vector `n_k`
//! itself (a fictitious particle of mass `J_c + J_r`: the transverse rotation energy is
//! `1/2 (J_c + J_r) |n_k'|^2`) and, with drives, the leg length `l_k` (a 1-D particle of mass
//! `J_m N^2`: the rotor's `1/2 J_m omega^2`). For each particle `x(q)`, `x' = P_x nu` (partial
//! velocities `P_x`) and `x'' = P_x nu' + b_x(nu)`; Kane's equations read
//!
//!     [diag(M, M, M, J1, J2, J3) + sum_x m_x P_x^T P_x] nu' =
//!         Q - (0, w x J w) - sum_x m_x P_x^T b_x
//!
//! with the generalised active forces `Q`: gravity (`-M g ez` on the platform, `-m g ez` on
//! `c_k`, `p_k`), the leg's axial force `(u_k + f_k + stop_k) P_l^T`, the joint limits'
//! `-(k_j delta + damping) P_theta^T`. The partial velocities and the velocity-product
//! accelerations `b_x` come from second-order Taylor jets in time (value, first and second
//! time derivative) pushed through the kinematics: the platform's jets `r(t)`, `R(t)` with
//! `R' = R [w]x`, `R'' = R ([w']x + [w]x^2)`, evaluated once with `(nu, nu' = 0)` (giving
//! `b_x`) and six times with `(nu = e_j, nu' = 0)` (giving the columns of `P_x`).
//! Orientation: a unit quaternion, `q' = q (0, w) / 2`. Integration: classical RK4 at a fixed
//! substep (at most `max_step`, an exact divisor of the communication step), inputs held over
//! each communication step, with event location: a substep that would straddle a kink of the
//! right-hand side (contact onset or release of an end stop or joint limit, a switch of the
//! damping's clamp) is cut at the crossing. Work accumulators ride along as extra states.
//!
//! The joint forces (`joint_forces`) come from a separate Newton-Euler balance of each leg:
//! the rod's axial equation and the whole leg's moment about `B_k`.
//!
//! Readings of SPEC §6/§8/§9 where it leaves room:
//! - joint angles `theta = atan2(|n x n_ref|, n . n_ref)` in `[0, pi]`; reference directions
//!   from the pose `(reference_r, R_ref = Rx Ry Rz(reference_angles))`: `nB_ref` the leg
//!   direction there (inertial), `nA_ref = R_ref^T nB_ref` (body); the platform angle is
//!   between `R^T n` and `nA_ref`;
//! - joint-limit moment (magnitude, reducing `theta`): `k_j delta + clamp(c_j theta', -k_j
//!   delta, k_j delta)`, `delta = theta - thetaMax > 0`, `theta'` the angle's own rate. The
//!   base limit acts between ground and cylinder, the platform limit between platform and
//!   rod (equal and opposite), about `n x n_ref`; in Kane's equations it is the generalised
//!   force `-(moment) d theta'/d nu`;
//! - end-stop force along the leg (sign as `u`): `+(k pen + clamp(c pen', -k pen, k pen))`
//!   at the lower stop (`pen = lmin - l`), `-(...)` at the upper (`pen = l - lmax`);
//! - the universal joint at `B_k` transmits no moment (with zero axial inertia and all other
//!   moments on the leg transverse, the axial balance makes its constraint torque vanish);
//! - drives: the rotor's inertia reaction passes through the screw, so the axial force the
//!   rod receives is `u + f + stop - J_m N^2 l''`; no gyroscopic rotor terms (SPEC §9).
//!
//! Hydraulic servo legs (SPEC §10, `hydraulics`, inputs `Valves`): the chamber pressures and
//! the spools (position and rate) are states integrated with the rest by the same RK4; the
//! actuator force `u_k = p_A A_A - p_B A_B` takes the place of the input force (friction, end
//! stops, joint limits and the legs' masses act as before; `work.forces` stays 0). The
//! spools' zero crossings are located like the contacts (the flow law's kink at `s = 0`).
//! Readings of SPEC §10 where it leaves room:
//! - the valve as four metering lands P->A, A->T, P->B, B->T, each a flow from its upstream
//!   to its downstream port: for `s >= 0` (so also at `s = 0`, where both are zero)
//!   `K s phi(p_S - p_A)` through P->A and `K s phi(p_B - p_T)` through B->T, for `s < 0`
//!   `K |s| phi(p_A - p_T)` through A->T and `K |s| phi(p_S - p_B)` through P->B, the other two
//!   closed (critical centre); every land also leaks `C_v dp` with its own drop. This is
//!   SPEC's `Q_A`, `Q_B` term by term. `Q_S` is the sum of the P->A and P->B paths, `Q_T` of
//!   the A->T and B->T paths (orifice and leakage; either may be negative);
//! - the losses are `sum over the four lands of (orifice flow + leakage) * its drop` (so
//!   `K |s| phi(dp) dp + C_v dp^2 >= 0` per land; a reversed orifice flow still loses), plus
//!   `C_i (p_A - p_B)^2`; all go to `work.dissipated`;
//! - `x_k = l_k - lmin_k` with the hydraulics' own `lmin`, `lmax`; neither `x` nor the
//!   volumes are clamped (beyond the stroke, into an end stop, `V` goes on linearly);
//! - no saturation of the spool position itself (only the command is clamped): the second-
//!   order spool may overshoot 1 a little and the flows scale linearly with it;
//! - `p_S` and the commands are inputs held over each communication step; `p_S = 0` makes the
//!   supply port a second tank at 0 gauge (the formulas unchanged);
//! - `work.compression` integrates `sum (p_A V_A p_A' + p_B V_B p_B') / beta` with the
//!   current volumes; `energy` holds no hydraulic energy.
//!
//! Oil with entrained air and the power unit (SPEC §10b, `OracleHydraulics::air_fraction`,
//! `air_polytropic`, `power_unit`; input `pump_speed` of `Valves`):
//! - every chamber's `beta` (its pressure equation and its compression power) is
//!   `beta_e(p)` of its own pressure (`effective_bulk_modulus`), and so is the supply line's.
//!   With `air_fraction == 0` the code takes section 10's path: `beta_e` returns `beta`
//!   itself and the compression power keeps section 10's expression, so every result is the
//!   same to the bit (the self-check compares a digest of a whole run with one recorded from
//!   the code before §10b);
//! - near vacuum: the pressure equations stay in the plain form `p' = beta_e(p) / V (...)`.
//!   The relative rate is `|p'| / P = (beta_e / P) |Q| / V` (`Q` the chamber's net inflow
//!   less its volume rate) and `beta_e / P` is bounded: it tends to `n` at zero absolute
//!   (`beta_e -> n P`) and peaks at about `sqrt(beta / (4 c))` near `P = sqrt(c beta)` (`c =
//!   alpha0 / (1 - alpha0) p_atm`, `n = 1`): about 700 at `alpha0 = 0.005`. With the stand's
//!   `|Q| / V` of a few per second, `h |p'| / P` stays below about 0.1 at the default 10 µs
//!   substep: the pressure decays exponentially and RK4's stages cannot cross zero absolute,
//!   so no change of variables is needed. `effective_bulk_modulus` panics if a pressure at or
//!   below zero absolute ever reaches it with air, so a violation cannot pass silently;
//! - the power unit: the supply line's pressure `p_S` is a state (`OracleState::
//!   supply_pressure`), `(V_s / beta_e(p_S) + dV_oil/dp_S) p_S' = Q_pump - Q_S - Q_relief` with
//!   `Q_S` the six valves' draw (leakage included); the input `supply_pressure` is then
//!   ignored; with `power_unit = None` the state is ignored (held) and `p_S` is the input;
//! - the kinks of the supply's right-hand side are located like the contacts: the
//!   compensator's two corners (`p_S = p_set`, `p_S = p_set + dp_c`), the relief's opening
//!   (`p_S = p_relief`) and the accumulator's switch between empty and charged (`P_S = P_0`,
//!   where `dV_oil/dp_S` jumps); at `P_S = P_0` exactly the accumulator counts as empty.
//!   The accumulator's state is held over each RK4 step (a discrete state, decided at the
//!   step's start; the charged formula continues smoothly past the precharge), so that the
//!   step that ends just past the located switch does not mix the jump into its last stage;
//! - energy: `work.pump = integral (p_S Q_pump - p_T (Q_T + Q_relief))`, `Q_T` the six
//!   valves' return; the supply line's `p_S V_s p_S' / beta_e(p_S)` joins `work.compression`,
//!   the relief's `(p_S - p_T) Q_relief` joins `work.dissipated`, and `energy` adds the
//!   accumulator's gas energy `E_acc`; `work.hydraulic` stays the valves' draw;
//! - `OracleWork::supply_volume` integrates the valves' total draw `Q_S` (a diagnostic for
//!   the oil's mass balance); `OracleState::lowest_pressure` is the lowest chamber gauge
//!   pressure at the start and at the end of every substep (SPEC's `pmin`), carried along
//!   with the state.

use nalgebra::{Matrix3, Matrix6, Rotation3, UnitQuaternion, Vector3, Vector6};
use std::ops::{Add, Mul, Neg, Sub};

// ------------------------------------------------------------------------------------------
// Parameters, state, inputs
// ------------------------------------------------------------------------------------------

#[derive(Clone, Copy, Debug)]
pub struct OracleStops {
    pub lmin: [f64; 6],
    pub lmax: [f64; 6],
    /// `k_s`, N/m.
    pub stiffness: f64,
    /// `c_s`, N.s/m: the damping force is `clamp(c_s * pen', -k_s pen, k_s pen)`.
    pub damping: f64,
}

#[derive(Clone, Copy, Debug)]
pub struct OracleJoints {
    /// Reference pose of the joint angles: centre of mass and 1-2-3 angles.
    pub reference_r: [f64; 3],
    pub reference_angles: [f64; 3],
    pub base_max: f64,
    pub platform_max: f64,
    /// `k_j`, N.m/rad.
    pub stiffness: f64,
    /// `c_j`, N.m.s/rad: the damping moment is `clamp(c_j delta', -k_j delta, k_j delta)`.
    pub damping: f64,
}

#[derive(Clone, Copy, Debug, Default)]
pub struct OracleFriction {
    pub coulomb: f64,
    pub static_: f64,
    pub stribeck_velocity: f64,
    pub smoothing: f64,
    pub viscous: f64,
}

#[derive(Clone, Copy, Debug)]
pub struct OracleDrives {
    pub resistance: f64,
    pub inductance: f64,
    pub ke: f64,
    pub kt: f64,
    pub rotor_inertia: f64,
    pub damping: f64,
    pub gear_ratio: f64,
    pub screw_lead: f64,
}

impl OracleDrives {
    /// `N = 2 pi i / p`, rad/m.
    pub fn n(&self) -> f64 {
        2.0 * std::f64::consts::PI * self.gear_ratio / self.screw_lead
    }
}

/// SPEC §10: hydraulic servo legs (all six legs share the scalars). The stroke position is
/// `x_k = l_k - lmin_k`, the stroke `L_s = lmax_k - lmin_k` (from these `lmin`, `lmax`,
/// whether or not end stops are on).
#[derive(Clone, Copy, Debug)]
pub struct OracleHydraulics {
    /// `D`, m.
    pub bore: f64,
    /// `d`, m.
    pub rod: f64,
    /// `V_A0`, `V_B0`, m3.
    pub dead_volume_a: f64,
    pub dead_volume_b: f64,
    /// `beta`, Pa.
    pub bulk_modulus: f64,
    /// `p_T`, Pa (gauge).
    pub tank_pressure: f64,
    /// `Q_N`, m3/s.
    pub rated_flow: f64,
    /// `dp_N`, Pa (over the valve, half of it per land).
    pub rated_pressure_drop: f64,
    /// `w_v`, rad/s.
    pub omega: f64,
    /// `zeta_v`.
    pub damping: f64,
    /// `p_cr`, Pa.
    pub pcr: f64,
    /// `C_v`, m3/(s.Pa): null leakage of each land.
    pub valve_leakage: f64,
    /// `C_i`, m3/(s.Pa): leakage across the piston.
    pub internal_leakage: f64,
    pub lmin: [f64; 6],
    pub lmax: [f64; 6],
    /// SPEC §10b `alpha0`: the air's volume fraction at atmospheric pressure. 0 (air-free
    /// oil) is section 10 to the bit.
    pub air_fraction: f64,
    /// SPEC §10b `n`: the air's polytropic exponent (not used when `air_fraction` is 0).
    pub air_polytropic: f64,
    /// SPEC §10b power unit (`hydraulic.supply = 1`); `None` (`hydraulic.supply = 0`): the
    /// supply pressure is the input.
    pub power_unit: Option<OraclePowerUnit>,
}

/// SPEC §10b: the atmospheric pressure `p_atm`, Pa.
pub const ATMOSPHERIC_PRESSURE: f64 = 101325.0;
/// SPEC §10: the start value of the input `pS` (and so of the power unit's `p_S`), Pa.
pub const RATED_SUPPLY_PRESSURE: f64 = 16e6;

/// SPEC §10b: the power unit, a supply line fed by a pressure-compensated pump, backed by a
/// gas-charged accumulator and protected by a relief valve. Pressures gauge unless said.
#[derive(Clone, Copy, Debug)]
pub struct OraclePowerUnit {
    /// `Q_max`, m3/s.
    pub max_flow: f64,
    /// `p_set`, Pa: full flow up to here.
    pub set_pressure: f64,
    /// `dp_c`, Pa: no flow from `p_set + dp_c` on.
    pub compensator_band: f64,
    /// `p_relief`, Pa.
    pub relief_pressure: f64,
    /// `K_r`, m3/(s.Pa).
    pub relief_gain: f64,
    /// `V_0`, m3: the accumulator's gas volume when empty.
    pub accumulator_volume: f64,
    /// `P_0`, Pa absolute.
    pub precharge: f64,
    /// `n_a`.
    pub accumulator_polytropic: f64,
    /// `V_s`, m3.
    pub supply_volume: f64,
}

impl OraclePowerUnit {
    /// `Q_pump = speed Q_max clamp((p_set + dp_c - p_S) / dp_c, 0, 1)`, speed clamped to [0, 1].
    pub fn pump_flow(&self, speed: f64, ps: f64) -> f64 {
        let delivery = clamp((self.set_pressure + self.compensator_band - ps) / self.compensator_band, 0.0, 1.0);
        clamp(speed, 0.0, 1.0) * self.max_flow * delivery
    }
    /// `Q_relief = K_r max(0, p_S - p_relief)`.
    pub fn relief_flow(&self, ps: f64) -> f64 {
        self.relief_gain * (ps - self.relief_pressure).max(0.0)
    }
    /// The accumulator charged (gas compressed) at this supply pressure: `P_S > P_0`.
    pub fn charged(&self, ps: f64) -> bool {
        ps + ATMOSPHERIC_PRESSURE > self.precharge
    }
    /// `V_oil = V_0 (1 - (P_0 / P_S)^(1/n_a))` when charged, else 0.
    pub fn oil_volume(&self, ps: f64) -> f64 {
        if self.charged(ps) {
            let pabs = ps + ATMOSPHERIC_PRESSURE;
            self.accumulator_volume * (1.0 - (self.precharge / pabs).powf(1.0 / self.accumulator_polytropic))
        } else {
            0.0
        }
    }
    /// `dV_oil/dp_S = V_0 / (n_a P_S) (P_0 / P_S)^(1/n_a)` when `charged`, else 0. The
    /// charged formula continues smoothly below the precharge, so that an RK4 step that holds
    /// the accumulator's state (see `rk4`) integrates a smooth right-hand side up to the event.
    pub fn oil_volume_slope(&self, ps: f64, charged: bool) -> f64 {
        if charged {
            let (pabs, na) = (ps + ATMOSPHERIC_PRESSURE, self.accumulator_polytropic);
            self.accumulator_volume / (na * pabs) * (self.precharge / pabs).powf(1.0 / na)
        } else {
            0.0
        }
    }
    /// The gas energy `E_acc = (P_g V_g - P_0 V_0) / (n_a - 1) - p_atm (V_0 - V_g)` (for
    /// `n_a = 1`: `P_0 V_0 ln(V_0 / V_g) - p_atm (V_0 - V_g)`), `V_g = V_0 - V_oil`,
    /// `P_g = max(P_S, P_0)`; zero while empty.
    pub fn gas_energy(&self, ps: f64) -> f64 {
        if !self.charged(ps) {
            return 0.0;
        }
        let (v0, p0, na) = (self.accumulator_volume, self.precharge, self.accumulator_polytropic);
        let vg = v0 - self.oil_volume(ps);
        let pg = ps + ATMOSPHERIC_PRESSURE;
        let gas = if na == 1.0 { p0 * v0 * (v0 / vg).ln() } else { (pg * vg - p0 * v0) / (na - 1.0) };
        gas - ATMOSPHERIC_PRESSURE * (v0 - vg)
    }
}

impl OracleHydraulics {
    /// Cap side area `A_A = pi D^2 / 4`.
    pub fn area_a(&self) -> f64 {
        std::f64::consts::PI * self.bore * self.bore / 4.0
    }
    /// Rod side (annulus) area `A_B = pi (D^2 - d^2) / 4`.
    pub fn area_b(&self) -> f64 {
        std::f64::consts::PI * (self.bore * self.bore - self.rod * self.rod) / 4.0
    }
    /// Flow gain `K = Q_N / sqrt(dp_N / 2)`.
    pub fn gain(&self) -> f64 {
        self.rated_flow / (0.5 * self.rated_pressure_drop).sqrt()
    }
    /// SPEC §10b `beta_e(p) = beta (1 + theta) / (1 + theta beta / (n P))`, `theta =
    /// alpha0 / (1 - alpha0) (p_atm / P)^(1/n)`, `P = p + p_atm`; exactly `beta` without air
    /// (`alpha0 = 0`, where the formula is undefined at and below zero absolute).
    pub fn effective_bulk_modulus(&self, p: f64) -> f64 {
        if self.air_fraction == 0.0 {
            return self.bulk_modulus;
        }
        let pabs = p + ATMOSPHERIC_PRESSURE;
        assert!(pabs > 0.0, "oil with air at {pabs} Pa absolute: the substep is too long for the decay towards vacuum");
        let (a, n, beta) = (self.air_fraction, self.air_polytropic, self.bulk_modulus);
        let theta = a / (1.0 - a) * (ATMOSPHERIC_PRESSURE / pabs).powf(1.0 / n);
        beta * (1.0 + theta) / (1.0 + theta * beta / (n * pabs))
    }
    /// The regularised square root `phi(dp) = dp / (dp^2 + p_cr^2)^(1/4)`.
    pub fn phi(&self, dp: f64) -> f64 {
        dp / (dp * dp + self.pcr * self.pcr).sqrt().sqrt()
    }
    /// Chamber volumes of leg k at length `l`: `V_A = V_A0 + A_A x`, `V_B = V_B0 + A_B (L_s - x)`.
    pub fn volumes(&self, k: usize, l: f64) -> (f64, f64) {
        let x = l - self.lmin[k];
        let stroke = self.lmax[k] - self.lmin[k];
        (self.dead_volume_a + self.area_a() * x, self.dead_volume_b + self.area_b() * (stroke - x))
    }

    /// One servo valve: the land flows of SPEC §10 at spool position `s`, chamber pressures
    /// `pa`, `pb` and supply pressure `ps`.
    pub fn valve(&self, s: f64, pa: f64, pb: f64, ps: f64) -> OracleValve {
        let (pt, k, cv) = (self.tank_pressure, self.gain(), self.valve_leakage);
        // The four metering lands, each as a flow from its upstream port to its downstream
        // port (the regularised law may reverse it): P->A, A->T, P->B, B->T. A critically
        // centred spool opens P->A and B->T for s >= 0, P->B and A->T for s < 0.
        let (pa_flow, at_flow, pb_flow, bt_flow) = if s >= 0.0 {
            (k * s * self.phi(ps - pa), 0.0, 0.0, k * s * self.phi(pb - pt))
        } else {
            (0.0, k * (-s) * self.phi(pa - pt), k * (-s) * self.phi(ps - pb), 0.0)
        };
        // Null leakage of every land (the same four paths).
        let (pa_leak, at_leak, pb_leak, bt_leak) = (cv * (ps - pa), cv * (pa - pt), cv * (ps - pb), cv * (pb - pt));
        let q_pa = pa_flow + pa_leak;
        let q_at = at_flow + at_leak;
        let q_pb = pb_flow + pb_leak;
        let q_bt = bt_flow + bt_leak;
        OracleValve {
            q_a: q_pa - q_at,
            q_b: q_pb - q_bt,
            q_supply: q_pa + q_pb,
            q_tank: q_at + q_bt,
            throttling: pa_flow * (ps - pa) + at_flow * (pa - pt) + pb_flow * (ps - pb) + bt_flow * (pb - pt),
            leakage: pa_leak * (ps - pa) + at_leak * (pa - pt) + pb_leak * (ps - pb) + bt_leak * (pb - pt),
        }
    }
}

/// One servo valve's flows (m3/s) and losses (W).
#[derive(Clone, Copy, Debug, Default)]
pub struct OracleValve {
    /// Net flows into chamber A and chamber B (`Q_A`, `Q_B` of SPEC §10, leakage included).
    pub q_a: f64,
    pub q_b: f64,
    /// Flow out of the supply line `Q_S` and into the tank line `Q_T` (leakage included).
    pub q_supply: f64,
    pub q_tank: f64,
    /// Throttling loss of the metering lands, `sum Q dp` (>= 0).
    pub throttling: f64,
    /// Null leakage loss of the lands, `sum C_v dp^2` (>= 0).
    pub leakage: f64,
}

/// Per-leg hydraulic powers (W) at an instant.
#[derive(Clone, Copy, Debug, Default)]
pub struct OracleHydraulicPowers {
    /// `P_S = p_S Q_S - p_T Q_T`.
    pub supply: [f64; 6],
    /// `u_k ldot_k`.
    pub leg: [f64; 6],
    /// Valve throttling and leakage plus internal leakage `C_i (p_A - p_B)^2`.
    pub losses: [f64; 6],
    /// `p_A V_A p_A' / beta + p_B V_B p_B' / beta`.
    pub compression: [f64; 6],
}

#[derive(Clone, Debug)]
pub struct OracleMachine {
    pub mass: f64,
    pub inertia: [f64; 3],
    pub gravity: f64,
    pub base_joints: [[f64; 3]; 6],
    pub platform_joints: [[f64; 3]; 6],
    pub cylinder_mass: f64,
    pub rod_mass: f64,
    pub cylinder_com: f64,
    pub rod_com: f64,
    pub cylinder_inertia: f64,
    pub rod_inertia: f64,
    pub stops: Option<OracleStops>,
    pub joints: Option<OracleJoints>,
    pub friction: OracleFriction,
    pub drives: Option<OracleDrives>,
    /// SPEC §10 hydraulic servo legs (inputs `Valves`); exclusive with `drives`.
    pub hydraulics: Option<OracleHydraulics>,
    /// Largest RK4 substep (s); each communication step is cut into equal substeps.
    pub max_step: f64,
}

#[derive(Clone, Copy, Debug)]
pub struct OracleState {
    pub r: [f64; 3],
    /// `R[a][b]`, body -> inertial, column b = e_b.
    pub rotation: [[f64; 3]; 3],
    pub v: [f64; 3],
    /// Angular velocity, body components.
    pub w: [f64; 3],
    pub currents: [f64; 6],
    /// Chamber gauge pressures (Pa), hydraulics only.
    pub pa: [f64; 6],
    pub pb: [f64; 6],
    /// Spool positions (normalised) and their rates (1/s), hydraulics only.
    pub spool: [f64; 6],
    pub spool_rate: [f64; 6],
    /// The supply line's pressure `p_S` (Pa, gauge), a state with the power unit only (SPEC
    /// §10b; with the accumulator charged to it).
    pub supply_pressure: f64,
    /// The lowest chamber gauge pressure seen since the start (Pa), SPEC's `pmin`: updated
    /// from the start and at the end of every substep (hydraulics only).
    pub lowest_pressure: f64,
}

impl OracleState {
    pub fn at_rest(r: [f64; 3], rotation: [[f64; 3]; 3]) -> Self {
        OracleState {
            r,
            rotation,
            v: [0.0; 3],
            w: [0.0; 3],
            currents: [0.0; 6],
            pa: [0.0; 6],
            pb: [0.0; 6],
            spool: [0.0; 6],
            spool_rate: [0.0; 6],
            supply_pressure: RATED_SUPPLY_PRESSURE,
            lowest_pressure: f64::INFINITY,
        }
    }
}

/// The states besides the platform's: currents, chamber pressures, spools, supply line.
#[derive(Clone, Copy, Debug, Default)]
struct Internal {
    currents: [f64; 6],
    pa: [f64; 6],
    pb: [f64; 6],
    spool: [f64; 6],
    spool_rate: [f64; 6],
    supply_pressure: f64,
    /// The accumulator's state held over an RK4 step (`None`: from `supply_pressure`).
    charged: Option<bool>,
}

impl Internal {
    fn of(s: &OracleState) -> Internal {
        Internal {
            currents: s.currents,
            pa: s.pa,
            pb: s.pb,
            spool: s.spool,
            spool_rate: s.spool_rate,
            supply_pressure: s.supply_pressure,
            charged: None,
        }
    }
}

#[derive(Clone, Copy, Debug)]
pub enum OracleInputs {
    /// Leg forces `u_k` (N), no drives.
    Forces([f64; 6]),
    /// Armature voltages `U_k` (V), drives required.
    Voltages([f64; 6]),
    /// Linear springs `u_k = -stiffness (l_k - rest_k)` evaluated inside the right-hand side
    /// (a conservative leg law for the energy checks), no drives.
    Springs { stiffness: f64, rest: [f64; 6] },
    /// Servo valve commands (saturated to [-1, 1] inside), the supply pressure `p_S` (Pa; used
    /// without the power unit) and `pump.speed` (clamped to [0, 1] inside; used with the
    /// power unit), hydraulics required.
    Valves { valve: [f64; 6], supply_pressure: f64, pump_speed: f64 },
}

/// Work accumulated since the start of a run (J).
#[derive(Clone, Copy, Debug, Default)]
pub struct OracleWork {
    /// Work of the leg forces `u_k` (inputs `Forces` or `Springs`), `integral sum u_k ldot_k`.
    pub forces: f64,
    /// Electric energy supplied, `integral sum U_k I_k`.
    pub electric: f64,
    /// Dissipated: friction, end-stop and joint-limit damping, `R I^2`, `D omega^2` and the
    /// conversion mismatch `(k_e - k_t) omega I`, the valves' throttling and leakage losses
    /// and the internal leakage loss.
    pub dissipated: f64,
    /// Hydraulic energy drawn from the supply, `integral sum_k (p_S Q_S - p_T Q_T)`.
    pub hydraulic: f64,
    /// The oil's compression energy, `integral sum_k (p_A V_A p_A' + p_B V_B p_B') / beta`
    /// (`beta_e` of each pressure with air; plus the supply line's with the power unit).
    pub compression: f64,
    /// SPEC §10b `work.pump`, `integral (p_S Q_pump - p_T (Q_T + Q_relief))` (power unit only).
    pub pump: f64,
    /// The oil volume the six valves drew from the supply line, `integral Q_S` (m3; hydraulics).
    pub supply_volume: f64,
}

/// The power unit's outputs at an instant (SPEC §10b); with the power unit off the supply
/// pressure is the input and the rest is 0.
#[derive(Clone, Copy, Debug, Default)]
pub struct OraclePowerUnitOutputs {
    /// `supply.pressure`, Pa gauge.
    pub supply_pressure: f64,
    /// `supply.pumpFlow`, `supply.reliefFlow`, m3/s.
    pub pump_flow: f64,
    pub relief_flow: f64,
    /// `accumulator.oilVolume`, m3.
    pub oil_volume: f64,
    /// `E_acc`, J (part of `energy`).
    pub gas_energy: f64,
}

/// The axial forces and joint-limit moments of one evaluation (diagnostics).
#[derive(Clone, Copy, Debug, Default)]
pub struct OracleLegForces {
    /// `u_k` (from the input, the spring law, the drive or the chamber pressures).
    pub actuator: [f64; 6],
    pub friction: [f64; 6],
    /// End-stop force along the leg (sign as `u_k`): elastic and damping parts.
    pub stop_elastic: [f64; 6],
    pub stop_damping: [f64; 6],
    /// Joint-limit moments (magnitudes, acting to reduce the angle): elastic `k_j delta`
    /// and damping `clamp(c_j delta', ...)`, base and platform joints.
    pub base_elastic: [f64; 6],
    pub base_damping: [f64; 6],
    pub platform_elastic: [f64; 6],
    pub platform_damping: [f64; 6],
}

// ------------------------------------------------------------------------------------------
// Second-order Taylor jets in time
// ------------------------------------------------------------------------------------------

/// `x(t0)`, `x'(t0)`, `x''(t0)`.
#[derive(Clone, Copy, Debug, Default)]
struct Jet {
    v: f64,
    d: f64,
    dd: f64,
}

impl Jet {
    fn cst(v: f64) -> Jet {
        Jet { v, d: 0.0, dd: 0.0 }
    }
    fn scale(self, a: f64) -> Jet {
        Jet { v: self.v * a, d: self.d * a, dd: self.dd * a }
    }
    /// `f(x(t))` from `f(x)`, `f'(x)`, `f''(x)`.
    fn chain(self, f0: f64, f1: f64, f2: f64) -> Jet {
        Jet { v: f0, d: f1 * self.d, dd: f2 * self.d * self.d + f1 * self.dd }
    }
    fn sqrt(self) -> Jet {
        let s = self.v.sqrt();
        self.chain(s, 0.5 / s, -0.25 / (s * s * s))
    }
    fn recip(self) -> Jet {
        let r = 1.0 / self.v;
        self.chain(r, -r * r, 2.0 * r * r * r)
    }
}

impl Add for Jet {
    type Output = Jet;
    fn add(self, o: Jet) -> Jet {
        Jet { v: self.v + o.v, d: self.d + o.d, dd: self.dd + o.dd }
    }
}
impl Sub for Jet {
    type Output = Jet;
    fn sub(self, o: Jet) -> Jet {
        Jet { v: self.v - o.v, d: self.d - o.d, dd: self.dd - o.dd }
    }
}
impl Neg for Jet {
    type Output = Jet;
    fn neg(self) -> Jet {
        Jet { v: -self.v, d: -self.d, dd: -self.dd }
    }
}
impl Mul for Jet {
    type Output = Jet;
    fn mul(self, o: Jet) -> Jet {
        Jet { v: self.v * o.v, d: self.d * o.v + self.v * o.d, dd: self.dd * o.v + 2.0 * self.d * o.d + self.v * o.dd }
    }
}

type JV = [Jet; 3];

fn jv_const(x: &Vector3<f64>) -> JV {
    [Jet::cst(x.x), Jet::cst(x.y), Jet::cst(x.z)]
}
fn jv_add(a: &JV, b: &JV) -> JV {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
fn jv_sub(a: &JV, b: &JV) -> JV {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn jv_mul(a: &JV, s: Jet) -> JV {
    [a[0] * s, a[1] * s, a[2] * s]
}
fn jv_scale(a: &JV, s: f64) -> JV {
    [a[0].scale(s), a[1].scale(s), a[2].scale(s)]
}
fn jv_dot(a: &JV, b: &JV) -> Jet {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn jv_val(a: &JV) -> Vector3<f64> {
    Vector3::new(a[0].v, a[1].v, a[2].v)
}
fn jv_d(a: &JV) -> Vector3<f64> {
    Vector3::new(a[0].d, a[1].d, a[2].d)
}
fn jv_dd(a: &JV) -> Vector3<f64> {
    Vector3::new(a[0].dd, a[1].dd, a[2].dd)
}

/// The platform's pose as jets: `r(t)` and `R(t)`.
struct PlatformJet {
    r: JV,
    rot: [[Jet; 3]; 3],
}

fn skew(w: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -w.z, w.y, w.z, 0.0, -w.x, -w.y, w.x, 0.0)
}

fn platform_jet(
    r: &Vector3<f64>,
    rot: &Matrix3<f64>,
    v: &Vector3<f64>,
    w: &Vector3<f64>,
    vd: &Vector3<f64>,
    wd: &Vector3<f64>,
) -> PlatformJet {
    let ww = skew(w);
    let rd = rot * ww;
    let rdd = rot * (skew(wd) + ww * ww);
    let mut m = [[Jet::default(); 3]; 3];
    for a in 0..3 {
        for b in 0..3 {
            m[a][b] = Jet { v: rot[(a, b)], d: rd[(a, b)], dd: rdd[(a, b)] };
        }
    }
    PlatformJet {
        r: [Jet { v: r.x, d: v.x, dd: vd.x }, Jet { v: r.y, d: v.y, dd: vd.y }, Jet { v: r.z, d: v.z, dd: vd.z }],
        rot: m,
    }
}

/// `R x` for a constant body vector `x`.
fn rot_const(rot: &[[Jet; 3]; 3], x: &Vector3<f64>) -> JV {
    let mut out = [Jet::default(); 3];
    for a in 0..3 {
        out[a] = rot[a][0].scale(x.x) + rot[a][1].scale(x.y) + rot[a][2].scale(x.z);
    }
    out
}

/// `R^T x`.
fn rot_t(rot: &[[Jet; 3]; 3], x: &JV) -> JV {
    let mut out = [Jet::default(); 3];
    for b in 0..3 {
        out[b] = rot[0][b] * x[0] + rot[1][b] * x[1] + rot[2][b] * x[2];
    }
    out
}

/// One leg's kinematic quantities as jets.
#[derive(Clone, Copy, Default)]
struct LegJet {
    l: Jet,
    n: JV,
    c: JV,
    p: JV,
    /// `cos thetaB = n . nB_ref`, `cos thetaA = (R^T n) . nA_ref`.
    cos_b: Jet,
    cos_a: Jet,
}

/// The joint angles' reference directions: inertial (base joints) and body (platform joints).
#[derive(Clone, Copy)]
struct Refs {
    base: [Vector3<f64>; 6],
    platform: [Vector3<f64>; 6],
}

// ------------------------------------------------------------------------------------------
// Helpers
// ------------------------------------------------------------------------------------------

/// `R = Rx(roll) Ry(pitch) Rz(yaw)`, counter-clockwise positive.
pub fn rotation_from_angles(angles: [f64; 3]) -> [[f64; 3]; 3] {
    let (s1, c1) = angles[0].sin_cos();
    let (s2, c2) = angles[1].sin_cos();
    let (s3, c3) = angles[2].sin_cos();
    let rx = Matrix3::new(1.0, 0.0, 0.0, 0.0, c1, -s1, 0.0, s1, c1);
    let ry = Matrix3::new(c2, 0.0, s2, 0.0, 1.0, 0.0, -s2, 0.0, c2);
    let rz = Matrix3::new(c3, -s3, 0.0, s3, c3, 0.0, 0.0, 0.0, 1.0);
    to_arr(&(rx * ry * rz))
}

pub fn identity_rotation() -> [[f64; 3]; 3] {
    [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
}

/// SPEC §2: the neutral centre of mass of the default stand.
pub const NEUTRAL_R: [f64; 3] = [0.0, 0.0, 1.9589244164161732];
/// SPEC §2: the paper's equilibrium leg force, in units of `M g`.
pub const EQUILIBRIUM_LEG_FORCE: f64 = 0.2005;

fn to_mat(m: &[[f64; 3]; 3]) -> Matrix3<f64> {
    Matrix3::new(m[0][0], m[0][1], m[0][2], m[1][0], m[1][1], m[1][2], m[2][0], m[2][1], m[2][2])
}
fn to_arr(m: &Matrix3<f64>) -> [[f64; 3]; 3] {
    let mut a = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            a[i][j] = m[(i, j)];
        }
    }
    a
}
fn v3(a: [f64; 3]) -> Vector3<f64> {
    Vector3::new(a[0], a[1], a[2])
}
fn angle_between(a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    a.cross(b).norm().atan2(a.dot(b))
}
fn clamp(x: f64, lo: f64, hi: f64) -> f64 {
    x.max(lo).min(hi)
}

/// Quaternion (w, x, y, z), normalised inside, to the rotation matrix body -> inertial.
fn quat_to_mat(q: &[f64]) -> Matrix3<f64> {
    let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
    let (w, x, y, z) = (q[0] / n, q[1] / n, q[2] / n, q[3] / n);
    Matrix3::new(
        1.0 - 2.0 * (y * y + z * z),
        2.0 * (x * y - w * z),
        2.0 * (x * z + w * y),
        2.0 * (x * y + w * z),
        1.0 - 2.0 * (x * x + z * z),
        2.0 * (y * z - w * x),
        2.0 * (x * z - w * y),
        2.0 * (y * z + w * x),
        1.0 - 2.0 * (x * x + y * y),
    )
}

/// Layout of the integrated vector.
const NX: usize = 52;
const IR: usize = 0; // r: 3
const IQ: usize = 3; // quaternion: 4
const IV: usize = 7; // v: 3
const IW: usize = 10; // w: 3
const II: usize = 13; // currents: 6
const IPA: usize = 19; // p_A: 6
const IPB: usize = 25; // p_B: 6
const IS: usize = 31; // spool: 6
const ISD: usize = 37; // spool rate: 6
const IWF: usize = 43; // work of the forces
const IWE: usize = 44; // electric work
const IWD: usize = 45; // dissipated
const IWH: usize = 46; // hydraulic work
const IWC: usize = 47; // compression work
const IPS: usize = 48; // supply line pressure p_S (power unit)
const IWP: usize = 49; // pump work
const IVS: usize = 50; // volume drawn by the valves
const IPMIN: usize = 51; // lowest chamber pressure (not integrated: set after every substep)
/// Number of switching functions: 10 per leg (stops, joint limits), one per spool, then the
/// power unit's four (compensator corners, relief, accumulator).
const NSW: usize = 70;

type Unpacked = (Vector3<f64>, Matrix3<f64>, Vector3<f64>, Vector3<f64>, Internal);

/// Everything one evaluation of the dynamics gives.
struct Dynamics {
    nu_dot: Vector6<f64>,
    current_dot: [f64; 6],
    pa_dot: [f64; 6],
    pb_dot: [f64; 6],
    spool_acc: [f64; 6],
    forces: OracleLegForces,
    hydraulic: OracleHydraulicPowers,
    power_forces: f64,
    power_electric: f64,
    power_dissipated: f64,
    power_hydraulic: f64,
    power_compression: f64,
    /// Power unit: `p_S'`, `p_S Q_pump - p_T (Q_T + Q_relief)`.
    supply_dot: f64,
    power_pump: f64,
    /// The six valves' draw from the supply line, `Q_S` (m3/s).
    supply_draw: f64,
    power_unit: OraclePowerUnitOutputs,
}

// ------------------------------------------------------------------------------------------
// The machine
// ------------------------------------------------------------------------------------------

impl OracleMachine {
    /// SPEC §2 truck-cabin stand; legs massless, no stops, joints, friction or drives.
    pub fn default_stand() -> Self {
        let (rb, rp, hc) = (1.5, 1.0, 0.5);
        let base_deg = [-10.0f64, 10.0, 110.0, 130.0, 230.0, 250.0];
        let plat_deg = [-50.0f64, 50.0, 70.0, 170.0, 190.0, 290.0];
        let mut base_joints = [[0.0; 3]; 6];
        let mut platform_joints = [[0.0; 3]; 6];
        for k in 0..6 {
            let (pb, pp) = (base_deg[k].to_radians(), plat_deg[k].to_radians());
            base_joints[k] = [rb * pb.cos(), rb * pb.sin(), 0.0];
            platform_joints[k] = [rp * pp.cos(), rp * pp.sin(), -hc];
        }
        OracleMachine {
            mass: 3000.0,
            inertia: [1500.0, 1500.0, 2200.0],
            gravity: 9.81,
            base_joints,
            platform_joints,
            cylinder_mass: 0.0,
            rod_mass: 0.0,
            cylinder_com: 0.0,
            rod_com: 0.0,
            cylinder_inertia: 0.0,
            rod_inertia: 0.0,
            stops: None,
            joints: None,
            friction: OracleFriction::default(),
            drives: None,
            hydraulics: None,
            max_step: 1e-5,
        }
    }

    fn b(&self, k: usize) -> Vector3<f64> {
        v3(self.base_joints[k])
    }
    fn a(&self, k: usize) -> Vector3<f64> {
        v3(self.platform_joints[k])
    }

    fn refs(&self) -> Option<Refs> {
        let j = self.joints.as_ref()?;
        Some(self.refs_at(j.reference_r, j.reference_angles))
    }

    fn refs_at(&self, reference_r: [f64; 3], reference_angles: [f64; 3]) -> Refs {
        let rot = to_mat(&rotation_from_angles(reference_angles));
        let r = v3(reference_r);
        let mut refs = Refs { base: [Vector3::zeros(); 6], platform: [Vector3::zeros(); 6] };
        for k in 0..6 {
            let n = (r + rot * self.a(k) - self.b(k)).normalize();
            refs.base[k] = n;
            refs.platform[k] = rot.transpose() * n;
        }
        refs
    }

    fn leg_jet(&self, k: usize, pj: &PlatformJet, refs: &Option<Refs>) -> LegJet {
        let a = jv_add(&pj.r, &rot_const(&pj.rot, &self.a(k)));
        let d = jv_sub(&a, &jv_const(&self.b(k)));
        let l = jv_dot(&d, &d).sqrt();
        let n = jv_mul(&d, l.recip());
        let c = jv_add(&jv_const(&self.b(k)), &jv_scale(&n, self.cylinder_com));
        let p = jv_sub(&a, &jv_scale(&n, self.rod_com));
        let (cos_b, cos_a) = match refs {
            Some(refs) => {
                let m = rot_t(&pj.rot, &n);
                (jv_dot(&n, &jv_const(&refs.base[k])), jv_dot(&m, &jv_const(&refs.platform[k])))
            }
            None => (Jet::cst(1.0), Jet::cst(1.0)),
        };
        LegJet { l, n, c, p, cos_b, cos_a }
    }

    fn legs(&self, pj: &PlatformJet, refs: &Option<Refs>) -> [LegJet; 6] {
        let mut out = [LegJet::default(); 6];
        for k in 0..6 {
            out[k] = self.leg_jet(k, pj, refs);
        }
        out
    }

    /// The legs' jets for `nu = e_j`, `nu' = 0`, j = 0..6: their first derivatives are the
    /// partial velocities.
    fn unit_legs(&self, r: &Vector3<f64>, rot: &Matrix3<f64>, refs: &Option<Refs>) -> [[LegJet; 6]; 6] {
        let z = Vector3::zeros();
        let mut out = [[LegJet::default(); 6]; 6];
        for j in 0..6 {
            let mut nu = [0.0; 6];
            nu[j] = 1.0;
            let pj =
                platform_jet(r, rot, &Vector3::new(nu[0], nu[1], nu[2]), &Vector3::new(nu[3], nu[4], nu[5]), &z, &z);
            out[j] = self.legs(&pj, refs);
        }
        out
    }

    fn rotor_mass(&self) -> f64 {
        self.drives.map_or(0.0, |d| d.rotor_inertia * d.n() * d.n())
    }

    /// A joint-limit angle's rate and partial rates (`d theta' / d nu_j`) from the cosine's
    /// jets, when beyond the limit: `theta = acos(cos)`, `theta' = -cos' / sin theta`.
    fn limit(cos0: &Jet, cos_unit: [f64; 6], sin: f64) -> (f64, [f64; 6]) {
        let rate = -cos0.d / sin;
        let mut partial = [0.0; 6];
        for j in 0..6 {
            partial[j] = -cos_unit[j] / sin;
        }
        (rate, partial)
    }

    /// Kane's equations: the accelerations, the currents' rates and the powers.
    fn dynamics(
        &self,
        r: &Vector3<f64>,
        rot: &Matrix3<f64>,
        v: &Vector3<f64>,
        w: &Vector3<f64>,
        ex: &Internal,
        inputs: &OracleInputs,
    ) -> Dynamics {
        let currents = &ex.currents;
        let refs = self.refs();
        let z = Vector3::zeros();
        let legs0 = self.legs(&platform_jet(r, rot, v, w, &z, &z), &refs);
        let unit = self.unit_legs(r, rot, &refs);
        let g = self.gravity;
        let jt = self.cylinder_inertia + self.rod_inertia;
        let jm = self.rotor_mass();
        let jb = v3(self.inertia);

        let mut mm = Matrix6::zeros();
        for i in 0..3 {
            mm[(i, i)] = self.mass;
            mm[(3 + i, 3 + i)] = jb[i];
        }
        let mut rhs = Vector6::zeros();
        rhs[2] = -self.mass * g;
        let gyro = w.cross(&jb.component_mul(w));
        for i in 0..3 {
            rhs[3 + i] = -gyro[i];
        }

        let mut f = OracleLegForces::default();
        let (mut p_forces, mut p_electric, mut p_diss) = (0.0, 0.0, 0.0);
        let mut current_dot = [0.0; 6];
        let (mut pa_dot, mut pb_dot, mut spool_acc) = ([0.0; 6], [0.0; 6], [0.0; 6]);
        let mut hyd = OracleHydraulicPowers::default();
        let (mut p_hydraulic, mut p_compression) = (0.0, 0.0);
        let (mut supply_dot, mut p_pump, mut supply_draw) = (0.0, 0.0, 0.0);
        let mut power_unit = OraclePowerUnitOutputs::default();
        let ld: [f64; 6] = std::array::from_fn(|k| legs0[k].l.d);
        let l: [f64; 6] = std::array::from_fn(|k| legs0[k].l.v);

        // Actuator forces.
        match (inputs, &self.drives, &self.hydraulics) {
            (OracleInputs::Forces(u), None, None) => {
                f.actuator = *u;
                p_forces = (0..6).map(|k| u[k] * ld[k]).sum();
            }
            (OracleInputs::Springs { stiffness, rest }, None, None) => {
                for k in 0..6 {
                    f.actuator[k] = -stiffness * (l[k] - rest[k]);
                    p_forces += f.actuator[k] * ld[k];
                }
            }
            (OracleInputs::Valves { valve, supply_pressure, pump_speed }, None, Some(h)) => {
                let (aa, ab, beta) = (h.area_a(), h.area_b(), h.bulk_modulus);
                // SPEC §10b: with the power unit p_S is the supply line's state.
                let ps = if h.power_unit.is_some() { ex.supply_pressure } else { *supply_pressure };
                let pt = h.tank_pressure;
                let mut q_tank = 0.0;
                for k in 0..6 {
                    let (pa, pb, sp) = (ex.pa[k], ex.pb[k], ex.spool[k]);
                    let c = clamp(valve[k], -1.0, 1.0);
                    spool_acc[k] = h.omega * h.omega * (c - sp) - 2.0 * h.damping * h.omega * ex.spool_rate[k];
                    let q = h.valve(sp, pa, pb, ps);
                    let (va, vb) = h.volumes(k, l[k]);
                    let qi = h.internal_leakage * (pa - pb);
                    let (beta_a, beta_b) = (h.effective_bulk_modulus(pa), h.effective_bulk_modulus(pb));
                    pa_dot[k] = beta_a / va * (q.q_a - aa * ld[k] - qi);
                    pb_dot[k] = beta_b / vb * (q.q_b + ab * ld[k] + qi);
                    f.actuator[k] = pa * aa - pb * ab;
                    hyd.supply[k] = ps * q.q_supply - pt * q.q_tank;
                    hyd.leg[k] = f.actuator[k] * ld[k];
                    hyd.losses[k] = q.throttling + q.leakage + qi * (pa - pb);
                    hyd.compression[k] = if h.air_fraction == 0.0 {
                        // Section 10's expression, so that air-free oil gives its results to the bit.
                        (pa * va * pa_dot[k] + pb * vb * pb_dot[k]) / beta
                    } else {
                        pa * va * pa_dot[k] / beta_a + pb * vb * pb_dot[k] / beta_b
                    };
                    p_hydraulic += hyd.supply[k];
                    p_compression += hyd.compression[k];
                    p_diss += hyd.losses[k];
                    supply_draw += q.q_supply;
                    q_tank += q.q_tank;
                }
                power_unit.supply_pressure = ps;
                if let Some(pu) = &h.power_unit {
                    // (V_s / beta_e(p_S) + dV_oil/dp_S) p_S' = Q_pump - Q_S - Q_relief.
                    let q_pump = pu.pump_flow(*pump_speed, ps);
                    let q_relief = pu.relief_flow(ps);
                    let beta_s = h.effective_bulk_modulus(ps);
                    let charged = ex.charged.unwrap_or_else(|| pu.charged(ps));
                    let capacitance = pu.supply_volume / beta_s + pu.oil_volume_slope(ps, charged);
                    supply_dot = (q_pump - supply_draw - q_relief) / capacitance;
                    p_pump = ps * q_pump - pt * (q_tank + q_relief);
                    p_compression += ps * pu.supply_volume * supply_dot / beta_s;
                    p_diss += (ps - pt) * q_relief;
                    power_unit.pump_flow = q_pump;
                    power_unit.relief_flow = q_relief;
                    power_unit.oil_volume = pu.oil_volume(ps);
                    power_unit.gas_energy = pu.gas_energy(ps);
                }
            }
            (OracleInputs::Voltages(u), Some(d), None) => {
                let nn = d.n();
                for k in 0..6 {
                    let om = nn * ld[k];
                    let i = currents[k];
                    f.actuator[k] = nn * (d.kt * i - d.damping * om);
                    current_dot[k] = (u[k] - d.resistance * i - d.ke * om) / d.inductance;
                    p_electric += u[k] * i;
                    p_diss += d.resistance * i * i + d.damping * om * om + (d.ke - d.kt) * om * i;
                }
            }
            (inp, d, h) => panic!(
                "inputs {inp:?} do not fit the drives {d:?} and hydraulics {h:?}: forces and springs without \
                 either, voltages with drives, valves with hydraulics"
            ),
        }

        // Friction.
        let fr = &self.friction;
        for k in 0..6 {
            let x = ld[k];
            let mut fk = -fr.viscous * x;
            if fr.coulomb != 0.0 || fr.static_ != 0.0 {
                fk -= (fr.coulomb + (fr.static_ - fr.coulomb) * (-(x / fr.stribeck_velocity).powi(2)).exp())
                    * (x / fr.smoothing).tanh();
            }
            f.friction[k] = fk;
            p_diss -= fk * x;
        }

        // End stops.
        if let Some(s) = &self.stops {
            for k in 0..6 {
                let (pen, pen_rate, sign) = if l[k] < s.lmin[k] {
                    (s.lmin[k] - l[k], -ld[k], 1.0)
                } else if l[k] > s.lmax[k] {
                    (l[k] - s.lmax[k], ld[k], -1.0)
                } else {
                    continue;
                };
                let el = s.stiffness * pen;
                let dmp = clamp(s.damping * pen_rate, -el, el);
                f.stop_elastic[k] = sign * el;
                f.stop_damping[k] = sign * dmp;
                p_diss += dmp * pen_rate;
            }
        }

        for k in 0..6 {
            let lg = &legs0[k];
            let pc = Matrix3x6::from_fn(|i, j| unit[j][k].c[i].d);
            let pp = Matrix3x6::from_fn(|i, j| unit[j][k].p[i].d);
            let pn = Matrix3x6::from_fn(|i, j| unit[j][k].n[i].d);
            let pl = Vector6::from_fn(|j, _| unit[j][k].l.d);
            // Generalised inertia.
            mm += pc.transpose() * pc * self.cylinder_mass
                + pp.transpose() * pp * self.rod_mass
                + pn.transpose() * pn * jt
                + pl * pl.transpose() * jm;
            // Velocity-product accelerations.
            rhs -= pc.transpose() * jv_dd(&lg.c) * self.cylinder_mass
                + pp.transpose() * jv_dd(&lg.p) * self.rod_mass
                + pn.transpose() * jv_dd(&lg.n) * jt
                + pl * (lg.l.dd * jm);
            // Gravity on the leg bodies.
            rhs += pc.transpose() * Vector3::new(0.0, 0.0, -self.cylinder_mass * g)
                + pp.transpose() * Vector3::new(0.0, 0.0, -self.rod_mass * g);
            // Axial force between cylinder and rod.
            let axial = f.actuator[k] + f.friction[k] + f.stop_elastic[k] + f.stop_damping[k];
            rhs += pl * axial;
        }

        // Joint limits.
        if let (Some(j), Some(refs)) = (&self.joints, &refs) {
            for k in 0..6 {
                let lg = &legs0[k];
                let n = jv_val(&lg.n);
                let rot_n = rot.transpose() * n;
                for (base, theta, sin) in [
                    (true, angle_between(&n, &refs.base[k]), n.cross(&refs.base[k]).norm()),
                    (false, angle_between(&rot_n, &refs.platform[k]), rot_n.cross(&refs.platform[k]).norm()),
                ] {
                    let max = if base { j.base_max } else { j.platform_max };
                    if theta <= max {
                        continue;
                    }
                    let delta = theta - max;
                    let cos0 = if base { lg.cos_b } else { lg.cos_a };
                    let cos_unit =
                        std::array::from_fn(|jj| if base { unit[jj][k].cos_b.d } else { unit[jj][k].cos_a.d });
                    let (rate, partial) = Self::limit(&cos0, cos_unit, sin);
                    let el = j.stiffness * delta;
                    let dmp = clamp(j.damping * rate, -el, el);
                    if base {
                        f.base_elastic[k] = el;
                        f.base_damping[k] = dmp;
                    } else {
                        f.platform_elastic[k] = el;
                        f.platform_damping[k] = dmp;
                    }
                    p_diss += dmp * rate;
                    for jj in 0..6 {
                        rhs[jj] -= (el + dmp) * partial[jj];
                    }
                }
            }
        }

        let nu_dot = mm.cholesky().expect("generalised mass matrix positive definite").solve(&rhs);
        Dynamics {
            nu_dot,
            current_dot,
            pa_dot,
            pb_dot,
            spool_acc,
            forces: f,
            hydraulic: hyd,
            power_forces: p_forces,
            power_electric: p_electric,
            power_dissipated: p_diss,
            power_hydraulic: p_hydraulic,
            power_compression: p_compression,
            supply_dot,
            power_pump: p_pump,
            supply_draw,
            power_unit,
        }
    }

    /// `(r, R, v, w, currents and hydraulic states)`.
    fn unpack(x: &[f64; NX]) -> Unpacked {
        (
            Vector3::new(x[IR], x[IR + 1], x[IR + 2]),
            quat_to_mat(&x[IQ..IQ + 4]),
            Vector3::new(x[IV], x[IV + 1], x[IV + 2]),
            Vector3::new(x[IW], x[IW + 1], x[IW + 2]),
            Internal {
                currents: std::array::from_fn(|k| x[II + k]),
                pa: std::array::from_fn(|k| x[IPA + k]),
                pb: std::array::from_fn(|k| x[IPB + k]),
                spool: std::array::from_fn(|k| x[IS + k]),
                spool_rate: std::array::from_fn(|k| x[ISD + k]),
                supply_pressure: x[IPS],
                charged: None,
            },
        )
    }

    fn pack(s: &OracleState) -> [f64; NX] {
        let mut x = [0.0; NX];
        let q = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(to_mat(&s.rotation)));
        let q = q.quaternion();
        x[IR..IR + 3].copy_from_slice(&s.r);
        x[IQ..IQ + 4].copy_from_slice(&[q.w, q.i, q.j, q.k]);
        x[IV..IV + 3].copy_from_slice(&s.v);
        x[IW..IW + 3].copy_from_slice(&s.w);
        x[II..II + 6].copy_from_slice(&s.currents);
        x[IPA..IPA + 6].copy_from_slice(&s.pa);
        x[IPB..IPB + 6].copy_from_slice(&s.pb);
        x[IS..IS + 6].copy_from_slice(&s.spool);
        x[ISD..ISD + 6].copy_from_slice(&s.spool_rate);
        x[IPS] = s.supply_pressure;
        x[IPMIN] = s.lowest_pressure;
        x
    }

    fn state_of(x: &[f64; NX]) -> OracleState {
        let (r, rot, v, w, ex) = Self::unpack(x);
        OracleState {
            r: r.into(),
            rotation: to_arr(&rot),
            v: v.into(),
            w: w.into(),
            currents: ex.currents,
            pa: ex.pa,
            pb: ex.pb,
            spool: ex.spool,
            spool_rate: ex.spool_rate,
            supply_pressure: ex.supply_pressure,
            lowest_pressure: x[IPMIN],
        }
    }

    /// `charged`: the accumulator's state to hold (`None`: from the state's `p_S`).
    fn derivative(&self, x: &[f64; NX], inputs: &OracleInputs, charged: Option<bool>) -> [f64; NX] {
        let (r, rot, v, w, mut ex) = Self::unpack(x);
        ex.charged = charged;
        let dy = self.dynamics(&r, &rot, &v, &w, &ex, inputs);
        let mut dx = [0.0; NX];
        dx[IR..IR + 3].copy_from_slice(v.as_slice());
        // q' = q (0, w) / 2.
        let (q0, qv) = (x[IQ], Vector3::new(x[IQ + 1], x[IQ + 2], x[IQ + 3]));
        let qvd = (w * q0 + qv.cross(&w)) * 0.5;
        dx[IQ] = -0.5 * qv.dot(&w);
        dx[IQ + 1..IQ + 4].copy_from_slice(qvd.as_slice());
        for i in 0..3 {
            dx[IV + i] = dy.nu_dot[i];
            dx[IW + i] = dy.nu_dot[3 + i];
        }
        dx[II..II + 6].copy_from_slice(&dy.current_dot);
        dx[IPA..IPA + 6].copy_from_slice(&dy.pa_dot);
        dx[IPB..IPB + 6].copy_from_slice(&dy.pb_dot);
        dx[IS..IS + 6].copy_from_slice(&ex.spool_rate);
        dx[ISD..ISD + 6].copy_from_slice(&dy.spool_acc);
        dx[IWF] = dy.power_forces;
        dx[IWE] = dy.power_electric;
        dx[IWD] = dy.power_dissipated;
        dx[IWH] = dy.power_hydraulic;
        dx[IWC] = dy.power_compression;
        dx[IPS] = dy.supply_dot;
        dx[IWP] = dy.power_pump;
        dx[IVS] = dy.supply_draw;
        dx
    }

    /// One RK4 step. The accumulator's state (charged or empty) is held over the step as a
    /// discrete state: at its switch `p_S'` jumps (not a mere kink), and a stage evaluated just
    /// past the located crossing would otherwise mix the two sides (an O(h) error).
    fn rk4(&self, x: &mut [f64; NX], h: f64, inputs: &OracleInputs) {
        let stage = |x: &[f64; NX], k: &[f64; NX], a: f64| -> [f64; NX] { std::array::from_fn(|i| x[i] + a * k[i]) };
        let charged = self.hydraulics.and_then(|hy| hy.power_unit).map(|pu| pu.charged(x[IPS]));
        let k1 = self.derivative(x, inputs, charged);
        let k2 = self.derivative(&stage(x, &k1, h / 2.0), inputs, charged);
        let k3 = self.derivative(&stage(x, &k2, h / 2.0), inputs, charged);
        let k4 = self.derivative(&stage(x, &k3, h), inputs, charged);
        for i in 0..NX {
            x[i] += h / 6.0 * (k1[i] + 2.0 * (k2[i] + k3[i]) + k4[i]);
        }
        let n = (x[IQ..IQ + 4].iter().map(|q| q * q).sum::<f64>()).sqrt();
        for q in &mut x[IQ..IQ + 4] {
            *q /= n;
        }
    }

    /// The switching functions of the non-smooth terms (positive where a term is on): per leg
    /// the lower and upper end-stop contact, the saturation of the stop damping's clamp at
    /// its upper and lower bound, and the same three for the base and the platform joint
    /// limit; then, with hydraulics, the spool positions (the flow law's kink at `s = 0`) and,
    /// with the power unit, `p_S` against the compensator's corners, the relief's opening and
    /// the accumulator's precharge (where `dV_oil/dp_S` jumps).
    /// The right-hand side is smooth (and the forces continuous) between sign changes.
    fn switches(&self, x: &[f64; NX]) -> [f64; NSW] {
        let (r, rot, v, w, ex) = Self::unpack(x);
        let mut out = [-1.0; NSW];
        if let Some(h) = &self.hydraulics {
            out[60..66].copy_from_slice(&ex.spool);
            if let Some(pu) = &h.power_unit {
                let ps = ex.supply_pressure;
                out[66] = ps - pu.set_pressure;
                out[67] = ps - (pu.set_pressure + pu.compensator_band);
                out[68] = ps - pu.relief_pressure;
                out[69] = ps + ATMOSPHERIC_PRESSURE - pu.precharge;
            }
        }
        // The clamp's switches: `c pen' - k pen` and `-c pen' - k pen` while in contact.
        let clamp_switches = |pen: f64, rate: f64, k: f64, c: f64| -> (f64, f64) {
            if pen > 0.0 && c != 0.0 { (c * rate - k * pen, -c * rate - k * pen) } else { (-1.0, -1.0) }
        };
        let refs = self.refs();
        for k in 0..6 {
            let o = &mut out[10 * k..10 * k + 10];
            let (_, _, l, n, ld, nd) = self.plain_leg(k, &r, &rot, &v, &w);
            if let Some(s) = &self.stops {
                o[0] = s.lmin[k] - l;
                o[1] = l - s.lmax[k];
                let (pen, rate) = if o[0] > o[1] { (o[0], -ld) } else { (o[1], ld) };
                (o[2], o[3]) = clamp_switches(pen, rate, s.stiffness, s.damping);
            }
            if let (Some(j), Some(refs)) = (&self.joints, &refs) {
                // thetaB' = -(n'.ref)/sin, thetaA' = -(m'.ref)/sin with m = R^T n,
                // m' = R^T n' - w x m.
                let m = rot.transpose() * n;
                let md = rot.transpose() * nd - w.cross(&m);
                for (i, (dir, dird, reference, max)) in
                    [(n, nd, refs.base[k], j.base_max), (m, md, refs.platform[k], j.platform_max)]
                        .into_iter()
                        .enumerate()
                {
                    let theta = angle_between(&dir, &reference);
                    let rate = -dird.dot(&reference) / dir.cross(&reference).norm();
                    let delta = theta - max;
                    o[4 + 3 * i] = delta;
                    (o[5 + 3 * i], o[6 + 3 * i]) = clamp_switches(delta, rate, j.stiffness, j.damping);
                }
            }
        }
        out
    }

    /// One substep of `h` with event location: where a switching function changes sign
    /// within the step, the step is cut at the (earliest) crossing, found by the Illinois
    /// variant of regula falsi on the RK4 step length, so that no RK4 step straddles a kink of
    /// the right-hand side (which would cost an O(h^2) local error).
    fn advance(&self, x: &mut [f64; NX], h: f64, inputs: &OracleInputs) {
        let mut rem = h;
        let mut guard = 0;
        while rem > 0.0 {
            let g0 = self.switches(x);
            let mut x1 = *x;
            self.rk4(&mut x1, rem, inputs);
            let g1 = self.switches(&x1);
            let changed: Vec<usize> = (0..NSW).filter(|&i| (g0[i] > 0.0) != (g1[i] > 0.0)).collect();
            guard += 1;
            if changed.is_empty() || guard > 50 {
                *x = x1;
                return;
            }
            let mut best: Option<(f64, [f64; NX])> = None;
            for &i in &changed {
                let (b, xb) = self.locate(x, rem, i, g0[i], g1[i], &x1, inputs);
                if best.as_ref().is_none_or(|(bb, _)| b < *bb) {
                    best = Some((b, xb));
                }
            }
            let (b, xb) = best.unwrap();
            *x = xb;
            if b >= rem {
                return;
            }
            rem -= b;
        }
    }

    /// The step length `b` in `(0, h]` just past the sign change of switching function `i`,
    /// bracketed to `1e-12 h`, and the state there.
    #[allow(clippy::too_many_arguments)]
    fn locate(
        &self,
        x: &[f64; NX],
        h: f64,
        i: usize,
        g0: f64,
        g1: f64,
        x1: &[f64; NX],
        inputs: &OracleInputs,
    ) -> (f64, [f64; NX]) {
        let old = g0 > 0.0;
        let (mut a, mut fa) = (0.0, g0);
        let (mut b, mut fb, mut xb) = (h, g1, *x1);
        let mut last_side = 0;
        for _ in 0..200 {
            if b - a <= 1e-12 * h {
                break;
            }
            let mut c = b - fb * (b - a) / (fb - fa);
            if !(c > a && c < b) {
                c = 0.5 * (a + b);
            }
            let mut xc = *x;
            self.rk4(&mut xc, c, inputs);
            let fc = self.switches(&xc)[i];
            if (fc > 0.0) == old {
                (a, fa) = (c, fc);
                if last_side == -1 {
                    fb *= 0.5;
                }
                last_side = -1;
            } else {
                (b, fb, xb) = (c, fc, xc);
                if last_side == 1 {
                    fa *= 0.5;
                }
                last_side = 1;
            }
        }
        (b, xb)
    }

    /// Integrates from `start` (t = 0) over `steps` communication steps of `h`; `inputs(t)`
    /// is called at each communication point and held over the step; returns the state at
    /// every communication point (start included).
    pub fn simulate(
        &self,
        start: &OracleState,
        h: f64,
        steps: usize,
        inputs: &dyn Fn(f64) -> OracleInputs,
    ) -> Vec<OracleState> {
        self.simulate_with_work(start, h, steps, inputs).into_iter().map(|(s, _)| s).collect()
    }

    /// As `simulate`, with the work accumulated since the start at every communication point.
    pub fn simulate_with_work(
        &self,
        start: &OracleState,
        h: f64,
        steps: usize,
        inputs: &dyn Fn(f64) -> OracleInputs,
    ) -> Vec<(OracleState, OracleWork)> {
        let mut x = Self::pack(start);
        let work = |x: &[f64; NX]| OracleWork {
            forces: x[IWF],
            electric: x[IWE],
            dissipated: x[IWD],
            hydraulic: x[IWH],
            compression: x[IWC],
            pump: x[IWP],
            supply_volume: x[IVS],
        };
        // The start as given (not through the quaternion), so that out[0] == start.
        let mut out = vec![(*start, work(&x))];
        let sub = ((h / self.max_step) * (1.0 - 1e-12)).ceil().max(1.0) as usize;
        let hs = h / sub as f64;
        let lowest = |x: &mut [f64; NX]| {
            if self.hydraulics.is_some() {
                x[IPMIN] = x[IPA..IPB + 6].iter().fold(x[IPMIN], |m, &p| m.min(p));
            }
        };
        lowest(&mut x);
        for i in 0..steps {
            let u = inputs(i as f64 * h);
            for _ in 0..sub {
                self.advance(&mut x, hs, &u);
                lowest(&mut x);
            }
            out.push((Self::state_of(&x), work(&x)));
        }
        out
    }

    /// The accelerations `(v', w')` (inertial, body) at a state under the inputs.
    pub fn accelerations(&self, s: &OracleState, inputs: &OracleInputs) -> ([f64; 3], [f64; 3]) {
        let dy = self.dynamics(&v3(s.r), &to_mat(&s.rotation), &v3(s.v), &v3(s.w), &Internal::of(s), inputs);
        ([dy.nu_dot[0], dy.nu_dot[1], dy.nu_dot[2]], [dy.nu_dot[3], dy.nu_dot[4], dy.nu_dot[5]])
    }

    /// The currents' rates `I'` (zero without drives).
    pub fn current_rates(&self, s: &OracleState, inputs: &OracleInputs) -> [f64; 6] {
        self.dynamics(&v3(s.r), &to_mat(&s.rotation), &v3(s.v), &v3(s.w), &Internal::of(s), inputs).current_dot
    }

    /// The axial forces and joint-limit moments at a state under the inputs.
    pub fn leg_forces(&self, s: &OracleState, inputs: &OracleInputs) -> OracleLegForces {
        self.dynamics(&v3(s.r), &to_mat(&s.rotation), &v3(s.v), &v3(s.w), &Internal::of(s), inputs).forces
    }

    // --- hydraulics (SPEC §10) -------------------------------------------------------------

    fn hydraulics(&self) -> &OracleHydraulics {
        self.hydraulics.as_ref().expect("hydraulic servo legs required")
    }

    /// Chamber volumes `(V_A, V_B)` of the six legs at the state's leg lengths.
    pub fn chamber_volumes(&self, s: &OracleState) -> ([f64; 6], [f64; 6]) {
        let h = self.hydraulics();
        let l = self.leg_lengths(s);
        let mut va = [0.0; 6];
        let mut vb = [0.0; 6];
        for k in 0..6 {
            (va[k], vb[k]) = h.volumes(k, l[k]);
        }
        (va, vb)
    }

    /// Total flow drawn from the supply (m3/s), all six valves, leakage included (`Qsupply`),
    /// at the input `pS` or, with the power unit, at the state's `p_S`.
    pub fn supply_flow(&self, s: &OracleState, inputs: &OracleInputs) -> f64 {
        let h = self.hydraulics();
        let OracleInputs::Valves { supply_pressure, .. } = inputs else { panic!("valve inputs required") };
        let ps = if h.power_unit.is_some() { s.supply_pressure } else { *supply_pressure };
        (0..6).map(|k| h.valve(s.spool[k], s.pa[k], s.pb[k], ps).q_supply).sum()
    }

    /// SPEC §10b's outputs of the power unit at a state under the inputs: `supply.pressure`,
    /// `supply.pumpFlow`, `supply.reliefFlow`, `accumulator.oilVolume` and `E_acc`.
    pub fn power_unit_outputs(&self, s: &OracleState, inputs: &OracleInputs) -> OraclePowerUnitOutputs {
        self.dynamics(&v3(s.r), &to_mat(&s.rotation), &v3(s.v), &v3(s.w), &Internal::of(s), inputs).power_unit
    }

    /// The supply line's pressure rate `p_S'` (Pa/s; 0 without the power unit).
    pub fn supply_pressure_rate(&self, s: &OracleState, inputs: &OracleInputs) -> f64 {
        self.dynamics(&v3(s.r), &to_mat(&s.rotation), &v3(s.v), &v3(s.w), &Internal::of(s), inputs).supply_dot
    }

    /// The chamber pressures' rates `(p_A', p_B')` (Pa/s).
    pub fn hydraulic_rates(&self, s: &OracleState, inputs: &OracleInputs) -> ([f64; 6], [f64; 6]) {
        let dy = self.dynamics(&v3(s.r), &to_mat(&s.rotation), &v3(s.v), &v3(s.w), &Internal::of(s), inputs);
        (dy.pa_dot, dy.pb_dot)
    }

    /// The spools' accelerations `s''` (1/s^2).
    pub fn spool_accelerations(&self, s: &OracleState, inputs: &OracleInputs) -> [f64; 6] {
        self.dynamics(&v3(s.r), &to_mat(&s.rotation), &v3(s.v), &v3(s.w), &Internal::of(s), inputs).spool_acc
    }

    /// The per-leg powers that the work accumulators integrate (supply, losses, compression)
    /// and the leg's power `u_k ldot_k`.
    pub fn hydraulic_powers(&self, s: &OracleState, inputs: &OracleInputs) -> OracleHydraulicPowers {
        self.dynamics(&v3(s.r), &to_mat(&s.rotation), &v3(s.v), &v3(s.w), &Internal::of(s), inputs).hydraulic
    }

    /// The chamber pressures `(p_A, p_B)` that hold the stand (legs' masses included) at rest
    /// in the pose with `p_B = p_S / 2`: `p_A = (u_k + p_B A_B) / A_A`, `u_k` from
    /// `static_leg_forces`.
    pub fn holding_pressures(
        &self,
        r: [f64; 3],
        rotation: [[f64; 3]; 3],
        supply_pressure: f64,
    ) -> ([f64; 6], [f64; 6]) {
        let h = self.hydraulics();
        let u = self.static_leg_forces(r, rotation);
        let pb = [0.5 * supply_pressure; 6];
        let pa = std::array::from_fn(|k| (u[k] + pb[k] * h.area_b()) / h.area_a());
        (pa, pb)
    }

    // --- plain (jet-free) kinematics and energies ---------------------------------------

    /// Leg k: `a_k`, `a_k'`, `l_k`, `n_k`, `l_k'`, `n_k'` by direct formulas.
    #[allow(clippy::type_complexity)]
    fn plain_leg(
        &self,
        k: usize,
        r: &Vector3<f64>,
        rot: &Matrix3<f64>,
        v: &Vector3<f64>,
        w: &Vector3<f64>,
    ) -> (Vector3<f64>, Vector3<f64>, f64, Vector3<f64>, f64, Vector3<f64>) {
        let arm = rot * self.a(k);
        let a = r + arm;
        let ad = v + rot * w.cross(&self.a(k));
        let d = a - self.b(k);
        let l = d.norm();
        let n = d / l;
        let ld = n.dot(&ad);
        let nd = (ad - n * ld) / l;
        (a, ad, l, n, ld, nd)
    }

    pub fn leg_lengths(&self, s: &OracleState) -> [f64; 6] {
        let (r, rot) = (v3(s.r), to_mat(&s.rotation));
        std::array::from_fn(|k| (r + rot * self.a(k) - self.b(k)).norm())
    }

    pub fn leg_rates(&self, s: &OracleState) -> [f64; 6] {
        let (r, rot, v, w) = (v3(s.r), to_mat(&s.rotation), v3(s.v), v3(s.w));
        std::array::from_fn(|k| self.plain_leg(k, &r, &rot, &v, &w).4)
    }

    /// `(thetaB, thetaA)`, each `atan2(|n x n_ref|, n . n_ref)` in `[0, pi]`, from the joint
    /// limits' reference pose, or without joint limits from SPEC §8's default reference (the
    /// neutral pose `NEUTRAL_R`, no rotation).
    pub fn joint_angles(&self, s: &OracleState) -> ([f64; 6], [f64; 6]) {
        let refs = self.refs().unwrap_or_else(|| self.refs_at(NEUTRAL_R, [0.0; 3]));
        let (r, rot) = (v3(s.r), to_mat(&s.rotation));
        let mut tb = [0.0; 6];
        let mut ta = [0.0; 6];
        for k in 0..6 {
            let n = (r + rot * self.a(k) - self.b(k)).normalize();
            tb[k] = angle_between(&n, &refs.base[k]);
            ta[k] = angle_between(&(rot.transpose() * n), &refs.platform[k]);
        }
        (tb, ta)
    }

    /// Kinetic energy of platform, leg bodies and rotors.
    pub fn kinetic_energy(&self, r: [f64; 3], rotation: [[f64; 3]; 3], v: [f64; 3], w: [f64; 3]) -> f64 {
        let (r, rot, v, w) = (v3(r), to_mat(&rotation), v3(v), v3(w));
        let jb = v3(self.inertia);
        let mut t = 0.5 * self.mass * v.norm_squared() + 0.5 * w.dot(&jb.component_mul(&w));
        let jm = self.rotor_mass();
        for k in 0..6 {
            let (_, ad, _, _, ld, nd) = self.plain_leg(k, &r, &rot, &v, &w);
            let cd = nd * self.cylinder_com;
            let pd = ad - nd * self.rod_com;
            t += 0.5 * self.cylinder_mass * cd.norm_squared()
                + 0.5 * self.rod_mass * pd.norm_squared()
                + 0.5 * (self.cylinder_inertia + self.rod_inertia) * nd.norm_squared()
                + 0.5 * jm * ld * ld;
        }
        t
    }

    /// Potential energy: gravity (platform and leg bodies), end stops and joint limits.
    pub fn potential_energy(&self, r: [f64; 3], rotation: [[f64; 3]; 3]) -> f64 {
        let (rv, rot) = (v3(r), to_mat(&rotation));
        let g = self.gravity;
        let mut e = self.mass * g * rv.z;
        for k in 0..6 {
            let (a, _, l, n, _, _) = self.plain_leg(k, &rv, &rot, &Vector3::zeros(), &Vector3::zeros());
            let c = self.b(k) + n * self.cylinder_com;
            let p = a - n * self.rod_com;
            e += g * (self.cylinder_mass * c.z + self.rod_mass * p.z);
            if let Some(s) = &self.stops {
                let pen = (s.lmin[k] - l).max(l - s.lmax[k]).max(0.0);
                e += 0.5 * s.stiffness * pen * pen;
            }
        }
        if let Some(j) = &self.joints {
            let (tb, ta) = self.joint_angles(&OracleState::at_rest(r, rotation));
            for k in 0..6 {
                let (db, da) = ((tb[k] - j.base_max).max(0.0), (ta[k] - j.platform_max).max(0.0));
                e += 0.5 * j.stiffness * (db * db + da * da);
            }
        }
        e
    }

    /// Total energy: kinetic (platform, legs, rotors) + gravity + stops + joint limits +
    /// magnetic `1/2 L I^2` + the accumulator's gas energy `E_acc` (power unit, SPEC §10b).
    /// No other hydraulic stored energy (SPEC §10: the oil's is `work.compression`).
    pub fn energy(&self, s: &OracleState) -> f64 {
        let magnetic = self.drives.map_or(0.0, |d| 0.5 * d.inductance * s.currents.iter().map(|i| i * i).sum::<f64>());
        let e = self.kinetic_energy(s.r, s.rotation, s.v, s.w) + self.potential_energy(s.r, s.rotation) + magnetic;
        match self.hydraulics.and_then(|h| h.power_unit) {
            Some(pu) => e + pu.gas_energy(s.supply_pressure),
            None => e,
        }
    }

    // --- joint forces and statics --------------------------------------------------------

    /// The force of leg k on the platform at `A_k` (inertial frame), from the Newton-Euler
    /// balance of each leg with the accelerations of `accelerations`: the rod's axial
    /// equation gives `G.n = F - J_m N^2 l'' - m_r (p''.n + g n_z)` (`F` the axial force
    /// between cylinder and rod, less the rotor's inertia with drives), the whole leg's moment balance about
    /// `B_k` gives `l n x G = gravity moments + joint-limit moments - dH_B/dt`,
    /// `H_B = m_c (c - B) x c' + m_r (p - B) x p' + (J_c + J_r) n x n'`.
    pub fn joint_forces(&self, s: &OracleState, inputs: &OracleInputs) -> [[f64; 3]; 6] {
        let (r, rot, v, w) = (v3(s.r), to_mat(&s.rotation), v3(s.v), v3(s.w));
        let dy = self.dynamics(&r, &rot, &v, &w, &Internal::of(s), inputs);
        let vd = Vector3::new(dy.nu_dot[0], dy.nu_dot[1], dy.nu_dot[2]);
        let wd = Vector3::new(dy.nu_dot[3], dy.nu_dot[4], dy.nu_dot[5]);
        let refs = self.refs();
        let legs = self.legs(&platform_jet(&r, &rot, &v, &w, &vd, &wd), &refs);
        let moments = self.joint_limit_moments_from(&rot, &legs, &dy.forces, &refs);
        let g = self.gravity;
        let ez = Vector3::z();
        let jt = self.cylinder_inertia + self.rod_inertia;
        let jm = self.rotor_mass();
        let f = &dy.forces;
        std::array::from_fn(|k| {
            let lg = &legs[k];
            let (n, c, p) = (jv_val(&lg.n), jv_val(&lg.c), jv_val(&lg.p));
            let b = self.b(k);
            // The screw delivers the axial force less the rotor's inertial force `J_m N^2 l''`.
            let axial = f.actuator[k] + f.friction[k] + f.stop_elastic[k] + f.stop_damping[k] - jm * lg.l.dd;
            let g_n = axial - self.rod_mass * (jv_dd(&lg.p).dot(&n) + g * n.z);
            let dh = (c - b).cross(&jv_dd(&lg.c)) * self.cylinder_mass
                + (p - b).cross(&jv_dd(&lg.p)) * self.rod_mass
                + n.cross(&jv_dd(&lg.n)) * jt;
            let grav = (c - b).cross(&(-ez * (self.cylinder_mass * g))) + (p - b).cross(&(-ez * (self.rod_mass * g)));
            let (m_base, m_rod) = moments[k];
            let n_x_g = (grav + m_base + m_rod - dh) / lg.l.v;
            let gk = n * g_n + n_x_g.cross(&n);
            gk.into()
        })
    }

    /// Joint-limit moments (inertial) of leg k: on the cylinder from the base-joint limit, on
    /// the rod from the platform-joint limit (the platform receives its opposite).
    fn joint_limit_moments_from(
        &self,
        rot: &Matrix3<f64>,
        legs: &[LegJet; 6],
        f: &OracleLegForces,
        refs: &Option<Refs>,
    ) -> [(Vector3<f64>, Vector3<f64>); 6] {
        let mut out = [(Vector3::zeros(), Vector3::zeros()); 6];
        let Some(refs) = refs else { return out };
        for k in 0..6 {
            let n = jv_val(&legs[k].n);
            let mb = f.base_elastic[k] + f.base_damping[k];
            if mb != 0.0 {
                let axis = n.cross(&refs.base[k]);
                out[k].0 = axis * (mb / axis.norm());
            }
            let ma = f.platform_elastic[k] + f.platform_damping[k];
            if ma != 0.0 {
                let axis = n.cross(&(rot * refs.platform[k]));
                out[k].1 = axis * (ma / axis.norm());
            }
        }
        out
    }

    /// The moment (inertial) of each platform-joint limit on the platform.
    pub fn platform_joint_moments(&self, s: &OracleState, inputs: &OracleInputs) -> [[f64; 3]; 6] {
        let (r, rot, v, w) = (v3(s.r), to_mat(&s.rotation), v3(s.v), v3(s.w));
        let dy = self.dynamics(&r, &rot, &v, &w, &Internal::of(s), inputs);
        let refs = self.refs();
        let z = Vector3::zeros();
        let legs = self.legs(&platform_jet(&r, &rot, &v, &w, &z, &z), &refs);
        let m = self.joint_limit_moments_from(&rot, &legs, &dy.forces, &refs);
        std::array::from_fn(|k| (-m[k].1).into())
    }

    /// Leg forces `u_k` that hold the platform at rest in the pose (legs with mass, gravity,
    /// elastic end-stop and joint-limit forces where in contact): the virtual-work balance
    /// `P_l^T u = -Q(q)` with the partial velocities `P_l` of the leg lengths.
    pub fn static_leg_forces(&self, r: [f64; 3], rotation: [[f64; 3]; 3]) -> [f64; 6] {
        let (rv, rot) = (v3(r), to_mat(&rotation));
        let refs = self.refs();
        let unit = self.unit_legs(&rv, &rot, &refs);
        let g = self.gravity;
        let mut q = Vector6::zeros();
        q[2] = -self.mass * g;
        let mut jl_t = Matrix6::zeros();
        let l = self.leg_lengths(&OracleState::at_rest(r, rotation));
        for k in 0..6 {
            let pc = Matrix3x6::from_fn(|i, j| unit[j][k].c[i].d);
            let pp = Matrix3x6::from_fn(|i, j| unit[j][k].p[i].d);
            let pl = Vector6::from_fn(|j, _| unit[j][k].l.d);
            jl_t.set_column(k, &pl);
            q += pc.transpose() * Vector3::new(0.0, 0.0, -self.cylinder_mass * g)
                + pp.transpose() * Vector3::new(0.0, 0.0, -self.rod_mass * g);
            if let Some(s) = &self.stops {
                let stop = if l[k] < s.lmin[k] {
                    s.stiffness * (s.lmin[k] - l[k])
                } else if l[k] > s.lmax[k] {
                    -s.stiffness * (l[k] - s.lmax[k])
                } else {
                    0.0
                };
                q += pl * stop;
            }
        }
        if let (Some(j), Some(refs)) = (&self.joints, &refs) {
            let (tb, ta) = self.joint_angles(&OracleState::at_rest(r, rotation));
            let rest = self.legs(
                &platform_jet(&rv, &rot, &Vector3::zeros(), &Vector3::zeros(), &Vector3::zeros(), &Vector3::zeros()),
                &Some(*refs),
            );
            for k in 0..6 {
                let n = jv_val(&rest[k].n);
                let rot_n = rot.transpose() * n;
                for (base, theta, max, sin) in [
                    (true, tb[k], j.base_max, n.cross(&refs.base[k]).norm()),
                    (false, ta[k], j.platform_max, rot_n.cross(&refs.platform[k]).norm()),
                ] {
                    if theta > max {
                        for jj in 0..6 {
                            let dcos = if base { unit[jj][k].cos_b.d } else { unit[jj][k].cos_a.d };
                            q[jj] -= j.stiffness * (theta - max) * (-dcos / sin);
                        }
                    }
                }
            }
        }
        let u = jl_t.lu().solve(&(-q)).expect("non-singular leg arrangement");
        std::array::from_fn(|k| u[k])
    }
}

type Matrix3x6 = nalgebra::Matrix3x6<f64>;
