//! The hydraulic power unit's variables (docs/model.md §10b, `hydraulic.supply = 1`): their
//! names, units and meanings, declared in `super`'s table by value reference.

use crate::models::variables::Dependency;
use crate::models::variables::VariableGroup as V;

pub const fn supply_mode(vr: u32) -> V {
    V::parameter(
        "hydraulic.supply", &[], vr, None,
        "Hydraulic supply (drive = 2): 0 = the supply pressure is the input pS (an ideal source); 1 = the power \
         unit: a supply line whose pressure is a state, fed by a pressure-compensated pump, backed by a gas \
         accumulator, protected by a relief valve",
    )
    .integer(0, 1)
}

pub const fn pump_speed(vr: u32) -> V {
    V::input(
        "pump.speed", &[], vr, Some("1"),
        "Pump running (1) to stopped (0), clamped to [0, 1]: scales the pump's flow (hydraulic.supply = 1). Drop it \
         to 0 to model a pump or mains failure: the accumulator then feeds the valves",
    )
}

pub const fn max_flow(vr: u32) -> V {
    V::parameter("pump.maxFlow", &[], vr, Some("m3/s"), "Largest pump flow Q_max (full flow up to pump.setPressure)")
}

pub const fn set_pressure(vr: u32) -> V {
    V::parameter(
        "pump.setPressure", &[], vr, Some("Pa"),
        "Compensator setting p_set, gauge: full flow up to it, none from p_set + pump.compensatorBand",
    )
}

pub const fn compensator_band(vr: u32) -> V {
    V::parameter("pump.compensatorBand", &[], vr, Some("Pa"), "Compensator band dp_c from full flow to none")
}

pub const fn relief_pressure(vr: u32) -> V {
    V::parameter("relief.pressure", &[], vr, Some("Pa"), "Relief valve cracking pressure p_relief, gauge")
}

pub const fn relief_gain(vr: u32) -> V {
    V::parameter(
        "relief.gain", &[], vr, Some("m3/(s.Pa)"),
        "Relief valve gain K_r: Q_relief = K_r max(0, p_S - p_relief)",
    )
}

pub const fn accumulator_volume(vr: u32) -> V {
    V::parameter("accumulator.volume", &[], vr, Some("m3"), "Accumulator gas volume V_0 when empty of oil")
}

pub const fn precharge(vr: u32) -> V {
    V::parameter(
        "accumulator.precharge", &[], vr, Some("Pa"),
        "Accumulator gas precharge P_0, absolute: oil enters above it",
    )
}

pub const fn accumulator_polytropic(vr: u32) -> V {
    V::parameter("accumulator.polytropic", &[], vr, Some("1"), "Polytropic exponent n_a of the accumulator's gas")
}

pub const fn supply_volume(vr: u32) -> V {
    V::parameter(
        "supply.volume", &[], vr, Some("m3"),
        "Oil volume V_s of the supply line (pipes, hoses, manifold) between the pump, the accumulator and the valves",
    )
}

pub const fn supply_pressure(vr: u32, dependencies: &'static [Dependency]) -> V {
    V::output(
        "supply.pressure", &[], vr, Some("Pa"),
        "Supply pressure p_S the valves see, gauge: the input pS (hydraulic.supply = 0) or the power unit's supply \
         line (supply.linePressure)",
        dependencies,
    )
}

pub const fn pump_flow(vr: u32, dependencies: &'static [Dependency]) -> V {
    V::output("supply.pumpFlow", &[], vr, Some("m3/s"), "Pump flow Q_pump (0 unless hydraulic.supply = 1)", dependencies)
}

pub const fn relief_flow(vr: u32, dependencies: &'static [Dependency]) -> V {
    V::output(
        "supply.reliefFlow", &[], vr, Some("m3/s"), "Relief valve flow Q_relief (0 unless hydraulic.supply = 1)",
        dependencies,
    )
}

pub const fn oil_volume(vr: u32, dependencies: &'static [Dependency]) -> V {
    V::output(
        "accumulator.oilVolume", &[], vr, Some("m3"),
        "Oil in the accumulator V_oil = V_0 (1 - (P_0 / P_S)^(1/n_a)) above the precharge, 0 below (0 unless \
         hydraulic.supply = 1)",
        dependencies,
    )
}

pub const fn pump_work(vr: u32) -> V {
    V::output(
        "work.pump", &[], vr, Some("J"),
        "Energy the pump delivered since the start, the integral of p_S Q_pump - p_T (Q_T + Q_relief) (Model \
         Exchange state; with hydraulic.supply = 1, E(t) - E(0) = work.F + work.electric + work.pump - \
         work.compression - work.dissipated, E with the accumulator's gas energy)",
        &[],
    )
}

pub const fn line_pressure(vr: u32, dependencies: &'static [Dependency]) -> V {
    V::local(
        "supply.linePressure", &[], vr, Some("Pa"),
        "The power unit's supply line pressure p_S, gauge (Model Exchange state; starts at pS's start value with the \
         accumulator charged to it; 0 and constant unless hydraulic.supply = 1)",
        dependencies,
    )
}

pub const fn line_pressure_rate(vr: u32, parameters: &'static [Dependency], knowns: &'static [Dependency]) -> V {
    V::local(
        "der(supply.linePressure)", &[], vr, Some("Pa/s"),
        "(Q_pump - Q_S - Q_relief) / (V_s / beta_e(p_S) + dV_oil/dp_S) (Model Exchange derivative of \
         supply.linePressure)",
        parameters,
    )
    .derivative("supply.linePressure", "supply.linePressure", 1, knowns)
}

pub const fn pump_power(vr: u32, parameters: &'static [Dependency], knowns: &'static [Dependency]) -> V {
    V::local(
        "der(work.pump)", &[], vr, Some("W"),
        "Power the pump delivers (Model Exchange derivative of work.pump)",
        parameters,
    )
    .derivative("work.pump", "work.pump", 1, knowns)
}
