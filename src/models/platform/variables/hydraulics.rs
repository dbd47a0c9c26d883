//! The hydraulic legs' parameters (docs/model.md §10 and §10b, `drive = 2`): their names, units
//! and meanings, declared in `super`'s table by value reference.

use crate::models::variables::VariableGroup as V;

pub const fn tank_pressure(vr: u32) -> V {
    V::parameter("hydraulic.tankPressure", &[], vr, Some("Pa"), "Tank (return line) pressure p_T, gauge")
}

pub const fn dead_volume_a(vr: u32) -> V {
    V::parameter(
        "hydraulic.deadVolumeA",
        &[],
        vr,
        Some("m3"),
        "Dead volume V_A0 of each cap-side chamber at lmin (ports, hoses, the cap's end): V_A = V_A0 + A_A (l - lmin)",
    )
}

pub const fn dead_volume_b(vr: u32) -> V {
    V::parameter(
        "hydraulic.deadVolumeB",
        &[],
        vr,
        Some("m3"),
        "Dead volume V_B0 of each rod-side chamber at lmax: V_B = V_B0 + A_B (lmax - l)",
    )
}

pub const fn bulk_modulus(vr: u32) -> V {
    V::parameter(
        "hydraulic.bulkModulus",
        &[],
        vr,
        Some("Pa"),
        "Effective bulk modulus beta of the oil with its hoses and seals",
    )
}

pub const fn valve_omega(vr: u32) -> V {
    V::parameter("valve.omega", &[], vr, Some("rad/s"), "Natural frequency w_v of each valve's spool (second order)")
}

pub const fn valve_damping(vr: u32) -> V {
    V::parameter("valve.damping", &[], vr, Some("1"), "Damping ratio zeta_v of each valve's spool")
}

pub const fn valve_pcr(vr: u32) -> V {
    V::parameter(
        "valve.pcr",
        &[],
        vr,
        Some("Pa"),
        "Regularisation pressure p_cr of the orifice law phi(dp) = dp / (dp^2 + p_cr^2)^(1/4): the flow is \
         linear in dp below about p_cr, the square root above",
    )
}

pub const fn valve_leakage(vr: u32) -> V {
    V::parameter(
        "valve.leakage",
        &[],
        vr,
        Some("m3/(s.Pa)"),
        "Null leakage coefficient C_v of each land: each chamber leaks C_v dp to supply and to tank",
    )
}

pub const fn internal_leakage(vr: u32) -> V {
    V::parameter(
        "hydraulic.internalLeakage",
        &[],
        vr,
        Some("m3/(s.Pa)"),
        "Internal leakage coefficient C_i across each piston: Q_i = C_i (p_A - p_B)",
    )
}

pub const fn air_fraction(vr: u32) -> V {
    V::parameter(
        "hydraulic.airFraction",
        &[],
        vr,
        Some("1"),
        "Volume fraction alpha0 of undissolved air in the oil at atmospheric pressure: each chamber's bulk \
         modulus becomes beta_e(p) = beta (1 + theta) / (1 + theta beta / (n P)), theta = alpha0 / (1 - alpha0) \
         (p_atm / P)^(1/n), P = p + 101325 Pa absolute, so no chamber reaches zero absolute; 0: oil without air \
         (section 10's law, which has no pressure floor)",
    )
}

pub const fn air_polytropic(vr: u32) -> V {
    V::parameter(
        "hydraulic.airPolytropic",
        &[],
        vr,
        Some("1"),
        "Polytropic exponent n of the entrained air (1: isothermal)",
    )
}

pub const fn pa0(vr: u32) -> V {
    V::parameter(
        "pA0",
        &[6],
        vr,
        Some("Pa"),
        "Initial cap-side pressure of leg k (default: what holds the default stand at rest in its neutral pose \
         with pB0 = pS/2)",
    )
}

pub const fn pb0(vr: u32) -> V {
    V::parameter("pB0", &[6], vr, Some("Pa"), "Initial rod-side pressure of leg k (default pS/2 at the default supply)")
}
