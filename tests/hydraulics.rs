//! The hydraulic servo legs of docs/model.md §10 against an independent formulation
//! (`common::machine_oracle`, written from the specification alone, RK4 at 10 µs), their
//! energy balance through end-stop contacts, and the fixed-step method's treatment of the
//! stiff oil columns and orifices (sub-steps within its stability bound) against a tight
//! reference: the work-precision table the docs quote.

use crate::common;
use common::dyn_law;

use common::machine_oracle::{OracleHydraulics, OracleInputs, OracleMachine, OraclePowerUnit, OracleState};
use nalgebra::Vector3;
use stewart_fmu::integration::{
    CrossingLog, Integrator, MAX_SWITCHING, Method, OdeSystem, SolverSettings, SwitchingKind,
};
use stewart_fmu::physics::actuators::hydraulics::power_unit::PowerUnit;
use stewart_fmu::physics::actuators::hydraulics::{
    ATMOSPHERIC_PRESSURE, DEFAULT_SUPPLY_PRESSURE, HydraulicActuators, HydraulicLegs,
};
use stewart_fmu::physics::actuators::{HeldForces, LegForceLaw};
use stewart_fmu::physics::body::kinematics::rotation_from_angles;
use stewart_fmu::physics::body::state::BodyState;
use stewart_fmu::physics::error::PhysicsFault;
use stewart_fmu::physics::legs::end_stops::EndStops;
use stewart_fmu::physics::stand::Stand;
use stewart_fmu::simulation::PlatformDynamics;
use stewart_fmu::simulation::SIMULATION_DIM;
use stewart_fmu::simulation::outputs::actuator_state;
use stewart_fmu::simulation::state::quadrature;
use stewart_fmu::simulation::{LegOutputs, PlatformOutputs, PlatformSimulation, Stabilisation};

const L0: f64 = 1.7550860729486566;

fn oracle_hydraulics(h: &HydraulicLegs, stops: &EndStops) -> OracleHydraulics {
    OracleHydraulics {
        bore: h.bore,
        rod: h.rod,
        dead_volume_a: h.dead_volume_a,
        dead_volume_b: h.dead_volume_b,
        bulk_modulus: h.bulk_modulus,
        tank_pressure: h.tank_pressure,
        rated_flow: h.rated_flow,
        rated_pressure_drop: h.rated_pressure_drop,
        omega: h.valve_omega,
        damping: h.valve_damping,
        pcr: h.pcr,
        valve_leakage: h.valve_leakage,
        internal_leakage: h.internal_leakage,
        lmin: stops.lower,
        lmax: stops.upper,
        air_fraction: h.air_fraction,
        air_polytropic: h.air_polytropic,
        power_unit: None,
    }
}

/// The holding pressures of the default stand at its neutral pose (massless legs).
fn holding(h: &HydraulicLegs) -> ([f64; 6], [f64; 6]) {
    let s = Stand::truck_cabin();
    let pb = 0.5 * DEFAULT_SUPPLY_PRESSURE;
    ([h.cap_pressure(0.2005 * s.mass * s.gravity, pb); 6], [pb; 6])
}

/// Section 10's oil: no entrained air (what the §10 oracle and tables are written for).
fn without_air() -> HydraulicLegs {
    HydraulicLegs { air_fraction: 0.0, ..HydraulicLegs::default() }
}

fn simulation(start: &BodyState, settings: SolverSettings, stops: bool, h: HydraulicLegs) -> PlatformSimulation {
    powered_simulation(start, settings, stops, h, None)
}

/// [`simulation`] with the power unit `unit` feeding the legs (`hydraulic.supply = 1`), if any.
fn powered_simulation(
    start: &BodyState,
    settings: SolverSettings,
    stops: bool,
    h: HydraulicLegs,
    unit: Option<PowerUnit>,
) -> PlatformSimulation {
    let (pa, pb) = holding(&h);
    let strokes = EndStops::default();
    let mut legs = HydraulicActuators::new(h, strokes.lower, strokes.upper);
    if let Some(unit) = unit {
        (legs.power_unit, legs.powered) = (unit, true);
    }
    PlatformSimulation::new(Stand::truck_cabin(), *start, settings, Stabilisation::Projection, 0.0)
        .and_then(|s| s.with_end_stops(stops.then_some(strokes)))
        .and_then(|s| s.with_hydraulics(Some(legs), pa, pb))
        .expect("valid hydraulics")
}

/// The oracle's power unit of the same parameters.
fn oracle_power_unit(u: &PowerUnit) -> OraclePowerUnit {
    OraclePowerUnit {
        max_flow: u.max_flow,
        set_pressure: u.set_pressure,
        compensator_band: u.compensator_band,
        relief_pressure: u.relief_pressure,
        relief_gain: u.relief_gain,
        accumulator_volume: u.accumulator_volume,
        precharge: u.precharge,
        accumulator_polytropic: u.accumulator_polytropic,
        supply_volume: u.supply_volume,
    }
}

fn oracle_state(s: &BodyState, pa: [f64; 6], pb: [f64; 6]) -> OracleState {
    let rotation = s.rotation();
    OracleState {
        r: s.r.into(),
        rotation: std::array::from_fn(|a| std::array::from_fn(|b| rotation[(a, b)])),
        v: s.v.into(),
        w: s.angular_velocity_body().into(),
        currents: [0.0; 6],
        pa,
        pb,
        spool: [0.0; 6],
        spool_rate: [0.0; 6],
        supply_pressure: DEFAULT_SUPPLY_PRESSURE,
        lowest_pressure: f64::INFINITY,
    }
}

/// Valve commands from the legs at a communication point: a force loop about the holding force
/// with a leg-length feedback, and a ripple that keeps the stand moving (the controller FMU's
/// structure, written here with fixed gains).
/// What a valve law reads at a communication point: `l`, `ldot`, `pA`, `pB`.
type Measured<'a> = (&'a [f64; 6], &'a [f64; 6], &'a [f64; 6], &'a [f64; 6]);

fn valve_law(ripple: f64) -> impl Fn(f64, Measured) -> [f64; 6] {
    let h = HydraulicLegs::default();
    let (area_a, area_b) = h.areas();
    let s = Stand::truck_cabin();
    let hold = 0.2005 * s.mass * s.gravity;
    move |t, (l, ldot, pa, pb)| {
        std::array::from_fn(|k| {
            let command = hold + 2.0e5 * (L0 - l[k]) - 2.0e4 * ldot[k];
            let measured = pa[k] * area_a - pb[k] * area_b;
            1.5e-5 * (command - measured) + 0.02 * (L0 - l[k]) * 50.0 + ripple * (3.0 * t + k as f64).sin()
        })
    }
}

fn tilted_start() -> BodyState {
    BodyState::from_pose(
        Stand::truck_cabin_neutral_position() + Vector3::new(0.01, -0.02, 0.03),
        Vector3::new(0.05, 0.02, -0.1),
        &rotation_from_angles(&Vector3::new(0.02, -0.03, 0.05)),
        &Vector3::new(0.1, -0.05, 0.2),
    )
}

/// The largest differences between the FMU's state and the oracle's: legs (m) and pressures
/// (relative to the supply pressure).
fn difference(sim: &PlatformSimulation, oracle: &OracleMachine, o: &OracleState) -> (f64, f64) {
    let legs = LegOutputs::compute(&sim.form, &sim.state).l;
    let oracle_legs = oracle.leg_lengths(o);
    let [pa, pb] = sim.pressures();
    let mut leg: f64 = 0.0;
    let mut pressure: f64 = 0.0;
    for k in 0..6 {
        leg = leg.max((legs[k] - oracle_legs[k]).abs());
        pressure = pressure.max((pa[k] - o.pa[k]).abs().max((pb[k] - o.pb[k]).abs()) / DEFAULT_SUPPLY_PRESSURE);
    }
    (leg, pressure)
}

/// Hydraulic legs on a moving stand: valve commands from a force loop held over 1 ms steps,
/// a ripple of 0.3 of full opening, 3 s, with section 10's oil (no air). The FMU's legs and
/// pressures agree with the oracle's (targets: 1e-8 m, 1e-3 of the supply).
#[test]
fn hydraulics_agree_with_the_independent_formulation() {
    agree_with_the_oracle(without_air(), None);
}

/// The same with the default oil (entrained air, §10b).
#[test]
fn with_air_hydraulics_agree_with_the_independent_formulation() {
    agree_with_the_oracle(HydraulicLegs::default(), None);
}

/// With air and a pump failure at 2 s (`pS` to 0, the force loop still commanding): the
/// emptying chambers approach zero absolute, where the oil is soft; the FMU's legs and
/// pressures agree with the oracle's there too, and neither goes below zero absolute.
#[test]
fn with_air_a_pump_failure_agrees_with_the_independent_formulation() {
    agree_with_the_oracle(HydraulicLegs::default(), Some(2.0));
}

fn agree_with_the_oracle(h: HydraulicLegs, pump_fails_at: Option<f64>) {
    let stops = EndStops::default();
    let oracle = OracleMachine {
        hydraulics: Some(oracle_hydraulics(&h, &stops)),
        max_step: 1e-5,
        ..OracleMachine::default_stand()
    };
    let law = valve_law(0.3);
    let start = tilted_start();
    let (pa0, pb0) = holding(&h);
    let settings = SolverSettings { method: Method::DormandPrince45, ..SolverSettings::tight() };
    let mut sim = simulation(&start, settings, false, h);
    let mut reference = oracle_state(&start, pa0, pb0);
    let (step, steps) = (1e-3, 3000);
    let (mut legs, mut pressures, mut moved, mut opening): (f64, f64, f64, f64) = (0.0, 0.0, 0.0, 0.0);
    let mut lowest = f64::INFINITY;
    for i in 0..steps {
        let t = i as f64 * step;
        let supply = if pump_fails_at.is_some_and(|at| t >= at) { 0.0 } else { DEFAULT_SUPPLY_PRESSURE };
        sim.form.set_supply_pressure(supply);
        let o = LegOutputs::compute(&sim.form, &sim.state);
        let [pa, pb] = sim.pressures();
        sim.advance(dyn_law(&HeldForces::constant(law(t, (&o.l, &o.ldot, &pa, &pb)))), t + step).expect("steps");
        let (l, ldot) = (oracle.leg_lengths(&reference), oracle.leg_rates(&reference));
        let valve = law(t, (&l, &ldot, &reference.pa, &reference.pb));
        let inputs = OracleInputs::Valves { valve, supply_pressure: supply, pump_speed: 1.0 };
        reference = oracle.simulate(&reference, step, 1, &|_| inputs)[1];
        let (l, p) = difference(&sim, &oracle, &reference);
        (legs, pressures) = (legs.max(l), pressures.max(p));
        moved = moved.max((sim.body_state().r - start.r).norm());
        opening = sim.spools().iter().fold(opening, |m, s| m.max(s.abs()));
        let [pa, pb] = sim.pressures();
        lowest = pa.iter().chain(&pb).fold(lowest, |m, &p| m.min(p));
    }
    let _figures = common::figures::print_figures(&format!(
        "hydraulics (air fraction {}, pump failing at {pump_fails_at:?} s), 3 s at 1 ms: largest difference from the \
         oracle {legs:.2e} m in the legs, {pressures:.2e} of the supply in the pressures; moved up to {moved:.3} m, \
         spools open up to {opening:.3}; lowest pressure {:.4e} Pa absolute (the oracle's {:.4e})",
        h.air_fraction,
        lowest + ATMOSPHERIC_PRESSURE,
        reference.lowest_pressure + ATMOSPHERIC_PRESSURE
    ));
    assert!(legs < 1e-8, "legs: {legs:e} m");
    assert!(pressures < 1e-3, "pressures: {pressures:e}");
    assert!(moved > 0.01 && opening > 0.1, "the stand moved ({moved} m) and the valves opened ({opening})");
    if pump_fails_at.is_some() {
        assert!(lowest + ATMOSPHERIC_PRESSURE < 1e4, "the chambers came near vacuum ({lowest:e} Pa gauge)");
        assert!(lowest > -ATMOSPHERIC_PRESSURE && reference.lowest_pressure > -ATMOSPHERIC_PRESSURE);
    }
}

/// The power unit (§10b) feeding the legs, with the default oil: at rest (the force loop
/// holding the stand, no ripple), and with the stand moving (ripple 0.3) and the pump stopped at
/// 1 s, once with the default accumulator and once with one of 3 L that empties within the run
/// (its switch to empty, where `dV_oil/dp_S` jumps, and the supply's collapse after it). The
/// FMU's legs, chamber and supply pressures agree with the oracle's over 3 s at 1 ms (targets:
/// 1e-8 m, 1e-3 of the supply).
#[test]
fn the_power_unit_agrees_with_the_independent_formulation() {
    let small = PowerUnit { accumulator_volume: 3e-3, ..PowerUnit::default() };
    for (unit, ripple, pump_stops_at) in
        [(PowerUnit::default(), 0.0, None), (PowerUnit::default(), 0.3, Some(1.0)), (small, 0.3, Some(1.0))]
    {
        power_unit_agrees(unit, ripple, pump_stops_at);
    }
}

fn power_unit_agrees(unit: PowerUnit, ripple: f64, pump_stops_at: Option<f64>) {
    let stops = EndStops::default();
    let h = HydraulicLegs::default();
    let oracle = OracleMachine {
        hydraulics: Some(OracleHydraulics {
            power_unit: Some(oracle_power_unit(&unit)),
            ..oracle_hydraulics(&h, &stops)
        }),
        max_step: 1e-5,
        ..OracleMachine::default_stand()
    };
    let law = valve_law(ripple);
    let start = tilted_start();
    let (pa0, pb0) = holding(&h);
    let settings = SolverSettings { method: Method::DormandPrince45, ..SolverSettings::tight() };
    let mut sim = powered_simulation(&start, settings, false, h, Some(unit));
    let mut reference = oracle_state(&start, pa0, pb0);
    let (step, steps) = (1e-3, 3000);
    let (mut legs, mut pressures, mut supply, mut energy): (f64, f64, f64, f64) = (0.0, 0.0, 0.0, 0.0);
    let (mut lowest_supply, mut emptied) = (f64::INFINITY, false);
    let e0 = PlatformOutputs::compute(&sim.form, &sim.state, None).energy;
    for i in 0..steps {
        let t = i as f64 * step;
        let speed = if pump_stops_at.is_some_and(|at| t >= at) { 0.0 } else { 1.0 };
        sim.form.set_pump_speed(speed);
        let o = LegOutputs::compute(&sim.form, &sim.state);
        let [pa, pb] = sim.pressures();
        sim.advance(dyn_law(&HeldForces::constant(law(t, (&o.l, &o.ldot, &pa, &pb)))), t + step).expect("steps");
        let (l, ldot) = (oracle.leg_lengths(&reference), oracle.leg_rates(&reference));
        let valve = law(t, (&l, &ldot, &reference.pa, &reference.pb));
        // The input pS is ignored with the power unit: a value that would show if it were not.
        let inputs = OracleInputs::Valves { valve, supply_pressure: 1.0e6, pump_speed: speed };
        reference = oracle.simulate(&reference, step, 1, &|_| inputs)[1];
        let (l, p) = difference(&sim, &oracle, &reference);
        (legs, pressures) = (legs.max(l), pressures.max(p));
        let out = PlatformOutputs::compute(&sim.form, &sim.state, None);
        let [line, ..] = out.power_unit;
        supply = supply.max((line - reference.supply_pressure).abs() / DEFAULT_SUPPLY_PRESSURE);
        lowest_supply = lowest_supply.min(line);
        emptied |= out.power_unit[3] == 0.0;
        let balance = out.energy
            - e0
            - (out.actuator_states[actuator_state(quadrature::WORK_PUMP)]
                - out.compression_work
                - out.dissipated_energy);
        energy = energy.max(balance.abs());
    }
    let out = PlatformOutputs::compute(&sim.form, &sim.state, None);
    let _figures = common::figures::print_figures(&format!(
        "power unit (accumulator {:.0} L, ripple {ripple}, pump stopping at {pump_stops_at:?} s), 3 s at 1 ms: largest \
         difference from the oracle {legs:.2e} m in the legs, {pressures:.2e} of the supply in the chambers, {supply:.2e} \
         in the supply line; supply {:.4} MPa at the end (lowest {:.4} MPa), accumulator oil {:.3} L; energy balance \
         within {energy:.2e} J of {:.0} J dissipated",
        unit.accumulator_volume * 1e3,
        out.power_unit[0] / 1e6,
        lowest_supply / 1e6,
        out.power_unit[3] * 1e3,
        out.dissipated_energy
    ));
    assert!(legs < 1e-8, "legs: {legs:e} m");
    assert!(pressures < 1e-3 && supply < 1e-3, "pressures: {pressures:e}, supply {supply:e}");
    assert!(energy < 1e-7 * out.dissipated_energy.max(1.0), "energy balance {energy:e} J");
    if unit.accumulator_volume < 5e-3 {
        assert!(emptied && lowest_supply < 1e6, "the small accumulator emptied and the supply fell");
    }
}

/// `E(t) - E(0) = work.hydraulic - work.compression - work.dissipated` through end-stop
/// contacts: three valves open to extension, three to retraction, then the pump fails; with
/// the default oil (entrained air, §10b: the emptying chambers approach zero absolute) and
/// without air.
#[test]
fn the_hydraulic_energy_balance_holds() {
    for h in [HydraulicLegs::default(), without_air()] {
        energy_balance(h);
    }
}

fn energy_balance(h: HydraulicLegs) {
    let settings = SolverSettings { rel_tol: 1e-11, abs_tol: 1e-13, ..SolverSettings::default() };
    let mut sim = simulation(&tilted_start(), settings, true, h);
    let e0 = PlatformOutputs::compute(&sim.form, &sim.state, None).energy;
    let (mut worst, mut contacts, mut supplied, mut dissipated) = (0.0f64, 0, 0.0, 0.0);
    for i in 0..300 {
        let t = i as f64 * 0.01;
        if t >= 2.0 {
            sim.form.set_supply_pressure(0.0);
        }
        let valve: [f64; 6] = std::array::from_fn(|k| if k % 2 == 0 { 0.5 } else { -0.4 });
        sim.advance(dyn_law(&HeldForces::constant(valve)), t + 0.01).expect("the motion goes on");
        contacts += sim.crossings.as_slice().len();
        let o = PlatformOutputs::compute(&sim.form, &sim.state, None);
        let balance = o.energy - e0 - (o.hydraulic_work - o.compression_work - o.dissipated_energy);
        worst = worst.max(balance.abs());
        assert_eq!(o.work_of_forces, 0.0);
        (supplied, dissipated) = (o.hydraulic_work, o.dissipated_energy);
    }
    let _figures = common::figures::print_figures(&format!(
        "hydraulics (air fraction {}): largest |E - E0 - (work.hydraulic - work.compression - work.dissipated)| = \
         {worst:.2e} J over 3 s ({contacts} contacts located; {supplied:.0} J supplied, {dissipated:.0} J dissipated; \
         lowest pressure {:.3e} Pa gauge)",
        h.air_fraction, sim.lowest_pressure
    ));
    assert!(contacts >= 2, "contacts with the stops ({contacts})");
    assert!(worst < 1e-7 * dissipated, "{worst:e} J");
    if h.air().is_some() {
        assert!(sim.lowest_pressure > -ATMOSPHERIC_PRESSURE, "below zero absolute: {:e} Pa", sim.lowest_pressure);
    }
}

/// The stiff regime: the pump fails (`pS` to 0) with the valves open, the rod sides empty
/// through the valves and the stand falls onto its stops, where an open land with little drop
/// makes the pressures' own rates reach `beta K / (V sqrt(p_cr))`, ~1e4 /s. RK4 at the default
/// 1 ms step cuts its steps within its stability bound and stays stable; the table gives its
/// error against a tight adaptive reference, and the adaptive method's at its default
/// tolerance, with their costs (right-hand-side evaluations).
#[test]
fn the_fixed_step_method_stays_stable_in_the_stiff_regime() {
    let (whole, errors) = work_precision(without_air());
    // The whole steps ring in the open lands' linear range; the sub-steps do not.
    assert!(whole > 10.0 * errors[0].2, "whole steps {whole:e} Pa against sub-steps {:e} Pa", errors[0].2);
    for (name, leg, pressure) in errors {
        assert!(leg < 1e-4 && pressure < 1e5, "{name}: {leg:e} m, {pressure:e} Pa");
    }
}

/// The same with the default oil (entrained air, §10b): the emptying chambers approach zero
/// absolute, where the oil is soft and stiffens steeply with pressure (`beta_e'(p) q / V` in
/// the step-cutting bound); every method stays within the same bounds and above zero absolute.
#[test]
fn with_air_the_methods_stay_accurate_through_near_vacuum_chambers() {
    let (_, errors) = work_precision(HydraulicLegs::default());
    for (name, leg, pressure) in errors {
        assert!(leg < 1e-4 && pressure < 1e5, "{name}: {leg:e} m, {pressure:e} Pa");
    }
}

/// The work-precision table of a pump failure with the valves fully open for the oil `h`:
/// the whole steps' pressure error, then each method's (name, leg error m, pressure error Pa).
fn work_precision(h: HydraulicLegs) -> (f64, Vec<(&'static str, f64, f64)>) {
    let start = BodyState::from_pose(
        Stand::truck_cabin_neutral_position(),
        Vector3::zeros(),
        &nalgebra::Matrix3::identity(),
        &Vector3::zeros(),
    );
    let run = |settings: SolverSettings, whole_steps: bool| {
        let mut sim = simulation(&start, settings, true, h);
        let mut trace = vec![];
        // The most right-hand-side evaluations one communication step took.
        let mut most = 0;
        for i in 0..2000 {
            let before = sim.integrator.stats.rhs_evaluations;
            let t = i as f64 * 1e-3;
            if t >= 0.5 {
                sim.form.set_supply_pressure(0.0);
            }
            let valve = HeldForces::constant([if t < 0.5 { 0.0 } else { 1.0 }; 6]);
            if whole_steps {
                let system = WholeSteps(sim.dynamics(dyn_law(&valve)));
                let mut y = sim.state;
                let reached =
                    Integrator::new(settings).integrate(&system, t, &mut y, t + 1e-3, &mut CrossingLog::default());
                if reached.is_err() || !y.iter().all(|x| x.is_finite() && x.abs() < 1e12) {
                    return (trace, 0, f64::NAN, 0);
                }
                sim.integrator.stats.rhs_evaluations += 4;
                sim.state = y;
                sim.time = t + 1e-3;
            } else {
                sim.advance(dyn_law(&valve), t + 1e-3).expect("steps");
            }
            most = most.max(sim.integrator.stats.rhs_evaluations - before);
            let legs = LegOutputs::compute(&sim.form, &sim.state).l;
            let [pa, pb] = sim.pressures();
            trace.push((legs, pa, pb));
        }
        (trace, sim.integrator.stats.rhs_evaluations, sim.lowest_pressure, most)
    };
    let (reference, _, reference_lowest, _) =
        run(SolverSettings { method: Method::DormandPrince45, ..SolverSettings::tight() }, false);

    println!(
        "pump failure at 0.5 s, valves fully open, 2 s at 1 ms communication steps (air fraction {}; the reference's \
         lowest pressure {:.4e} Pa gauge):",
        h.air_fraction, reference_lowest
    );
    println!(
        "| method | largest leg error (m) | largest pressure error (Pa) | evaluations per step | the most in one step |"
    );
    println!("|---|---|---|---|---|");
    let (mut errors, mut rows) = (vec![], vec![]);
    let rk4 = SolverSettings { method: Method::RungeKutta4, ..Default::default() };
    for (name, settings, whole_steps) in [
        ("RK4, 1 ms steps taken whole (no sub-steps)", rk4, true),
        ("RK4, solver.fixedStep 1 ms (default)", rk4, false),
        ("RK4, solver.fixedStep 0.25 ms", SolverSettings { fixed_step: 2.5e-4, ..rk4 }, false),
        ("adaptive, relTol 1e-8 (default)", SolverSettings::default(), false),
        ("adaptive, relTol 1e-6", SolverSettings { rel_tol: 1e-6, ..Default::default() }, false),
    ] {
        let (trace, evaluations, lowest, most) = run(settings, whole_steps);
        assert_eq!(trace.len(), reference.len(), "{name}: the run failed");
        let (mut leg, mut pressure): (f64, f64) = (0.0, 0.0);
        for ((l, pa, pb), (lr, par, pbr)) in trace.iter().zip(&reference) {
            for k in 0..6 {
                leg = leg.max((l[k] - lr[k]).abs());
                pressure = pressure.max((pa[k] - par[k]).abs()).max((pb[k] - pbr[k]).abs());
            }
        }
        let row = format!("| {name} | {leg:.2e} | {pressure:.2e} | {:.1} | {most} |", evaluations as f64 / 2000.0);
        println!("{row}");
        rows.push(row);
        if !whole_steps {
            assert!(lowest.is_finite());
            if h.air().is_some() {
                assert!(lowest > -ATMOSPHERIC_PRESSURE, "{name}: below zero absolute, {lowest:e} Pa");
            }
        }
        errors.push((name, leg, pressure));
    }
    common::figures::check_figures(
        "model.txt",
        &format!("pump failure at 0.5 s, valves fully open, 2 s at 1 ms (air fraction {})", h.air_fraction),
        &rows.join(" "),
    );
    let (_, _, whole) = errors.remove(0);
    let fell = reference.last().map_or(0.0, |(l, _, _)| L0 - l[0]);
    println!("the legs shortened by {fell:.3} m");
    assert!(fell > 0.1, "the stand fell ({fell} m)");
    (whole, errors)
}

/// The platform's dynamics without a stability bound: RK4 takes each step whole.
struct WholeSteps<'a>(PlatformDynamics<'a, dyn LegForceLaw + 'a>);

impl OdeSystem<SIMULATION_DIM> for WholeSteps<'_> {
    type Fault = PhysicsFault;
    fn derivative(&self, t: f64, y: &[f64; SIMULATION_DIM], dy: &mut [f64; SIMULATION_DIM]) {
        self.0.derivative(t, y, dy)
    }
    fn after_step(&self, y: &mut [f64; SIMULATION_DIM]) {
        self.0.after_step(y)
    }
    fn modifies_state_after_step(&self) -> bool {
        OdeSystem::<SIMULATION_DIM>::modifies_state_after_step(&self.0)
    }
    fn active_dimension(&self) -> usize {
        OdeSystem::<SIMULATION_DIM>::active_dimension(&self.0)
    }
    fn check(&self, t: f64, y: &[f64; SIMULATION_DIM]) -> Result<(), PhysicsFault> {
        self.0.check(t, y)
    }
    fn switching_count(&self) -> usize {
        OdeSystem::<SIMULATION_DIM>::switching_count(&self.0)
    }
    fn switching(&self, t: f64, y: &[f64; SIMULATION_DIM], g: &mut [f64; MAX_SWITCHING]) {
        self.0.switching(t, y, g)
    }
    fn switching_kind(&self, index: usize) -> SwitchingKind {
        OdeSystem::<SIMULATION_DIM>::switching_kind(&self.0, index)
    }
}
