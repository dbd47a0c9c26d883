"""The hydraulic power unit (docs/model.md §10b, `hydraulic.supply = 1`) and the controller's safe
landing through the packaged FMUs: the supply line at rest against the pump's characteristic and
the accumulator's gas law computed here, the energy balance with work.pump, FMI 3 = FMI 2 bit for
bit, Model Exchange against Co-Simulation through the accumulator's switch to empty (a state
event), an FMU state that continues to the bit (the controller's landing in it), and a pump stop
at the heave programme's highest point that the accumulator and the safe landing answer: at rest
on the landing floor, no stop touched. (The line's law against an independent formulation:
tests/hydraulics.rs; its exact derivatives: test_hydraulics.py.)"""

import math

import numpy as np
import pytest
from fmpy import simulate_fmu

from stewart_fmu import CONTROLLER_FMU, PLATFORM_FMU, Platform
from stewart_fmu import hydraulics as hy
from stewart_fmu.core import LEGS, Component
from stewart_fmu.ssp import SYSTEM_POWER_UNIT_SSP
from test_fmi3 import PLATFORM3, Fmu3
from oracles.hydraulics import ATMOSPHERE
from oracles.stand import EQUILIBRIUM_FORCE, GRAVITY, MASS
from references import check_figures

pytestmark = pytest.mark.quick

POWERED = {"drive": 2, "hydraulic.supply": 1}
PERIOD = 2 * math.pi / 2.5573423705088842  # the default heave programme's


def unit_parameters():
    names = ["pump.maxFlow", "pump.setPressure", "pump.compensatorBand", "accumulator.volume",
             "accumulator.precharge", "accumulator.polytropic", "pS"]
    from fmpy import read_model_description
    start = {v.name: v.start for v in read_model_description(str(PLATFORM_FMU)).modelVariables}
    return {n: float(start[n]) for n in names}


U = unit_parameters()


def balance(c):
    return c["E"] - c["E"][0] - (c["work.pump"] - c["work.compression"] - c["work.dissipated"])


def test_at_rest_the_pump_holds_the_line_where_its_flow_meets_the_valves_draw():
    """The stand held by the controller, 3 s: the line settles in the compensator's band where
    the pump's flow Q_max (p_set + dp_c - p_S) / dp_c equals the valves' draw, the accumulator
    holds V_0 (1 - (P_0 / P_S)^(1/n_a)) of oil (both written here from §10b), and
    E - E0 = work.pump - work.compression - work.dissipated."""
    c, errors, status = hy.closed_loop(3.0, controller={"programme": 2}, platform={"hydraulic.supply": 1},
                                       record=hy.POWER_UNIT)
    assert status == "ok", status
    p, pump, draw, oil = (c[n][-1] for n in ("supply.pressure", "supply.pumpFlow", "Qsupply",
                                             "accumulator.oilVolume"))
    characteristic = U["pump.maxFlow"] * (U["pump.setPressure"] + U["pump.compensatorBand"] - p) \
        / U["pump.compensatorBand"]
    gas = U["accumulator.volume"] * (1 - (U["accumulator.precharge"] / (p + ATMOSPHERE))
                                     ** (1 / U["accumulator.polytropic"]))
    rate = np.gradient(c["supply.pressure"], c["time"])[-1]
    print(f"at rest with the power unit: line {p / 1e6:.4f} MPa ({rate:.1e} Pa/s), pump {pump * 6e4:.3f} L/min "
          f"(characteristic {characteristic * 6e4:.3f}), valves {draw * 6e4:.3f} L/min, accumulator {oil * 1e3:.4f} L "
          f"(gas law {gas * 1e3:.4f}); energy balance {np.abs(balance(c)).max():.1e} J; leg error "
          f"{errors.max() * 1e3:.4f} mm")
    assert U["pump.setPressure"] < p < U["pump.setPressure"] + U["pump.compensatorBand"]
    assert abs(pump - characteristic) < 1e-12 * U["pump.maxFlow"] and abs(oil - gas) < 1e-12 * oil
    assert abs(pump - draw) < 0.01 * draw and abs(rate) < 1e3
    assert np.abs(balance(c)).max() < 1e-7 * c["work.dissipated"][-1] and errors.max() < 1e-3


def test_fmi3_equals_fmi2_with_the_power_unit_bit_for_bit():
    """A force loop with a ripple and the pump stopped at 0.5 s, 1.5 s at 1 ms: every output of the
    FMI 3 platform with the power unit equals the FMI 2 platform's."""
    p2 = Platform(parameters=POWERED, name="fmi2-power-unit")
    p3 = Fmu3(PLATFORM3, name="fmi3-power-unit", integers=POWERED)
    names = ["r[3]", "E", "work.pump", "work.compression", "work.dissipated"] + hy.POWER_UNIT[:4]
    l0 = p2.vector("l", 6)
    hold = EQUILIBRIUM_FORCE * MASS * GRAVITY
    area_a, area_b = math.pi / 4 * 0.063 ** 2, math.pi / 4 * (0.063 ** 2 - 0.036 ** 2)
    for i in range(1500):
        legs, rates = p2.vector("l", 6), p2.vector("ldot", 6)
        pa, pb = p2.vector("pA", 6), p2.vector("pB", 6)
        valve = 1.5e-5 * (hold + 2e5 * (l0 - legs) - 2e4 * rates - (pa * area_a - pb * area_b)) \
            + 0.3 * np.sin(3 * p2.time + np.arange(6))
        speed = 1.0 if i < 500 else 0.0
        p2.slave.setReal([p2.vr[f"valve[{k}]"] for k in LEGS] + [p2.vr["pump.speed"]], list(valve) + [speed])
        p3.set("valve", valve)
        p3.set("pump.speed", speed)
        p2.step(1e-3)
        p3.step(1e-3)
        out2 = np.array(p2.get(*names))
        out3 = np.array([p3.get(n) if n != "r[3]" else p3.get("r")[2] for n in names])
        assert np.array_equal(out2, out3), f"step {i}: {out2 - out3}"
    print(f"FMI 3 = FMI 2 with the power unit over 1500 steps; supply {p2.get('supply.pressure')[0] / 1e6:.4f} MPa")
    p2.free()
    p3.free()


def test_model_exchange_through_the_accumulators_switch_matches_co_simulation():
    """A 1 L accumulator, the pump stopped from the start, the valves at 0.05: the accumulator
    empties (Model Exchange's event indicator, located by FMPy's CVODE) and the line collapses.
    Heave, line pressure and the accumulator's oil from Model Exchange (rtol 1e-10) equal
    Co-Simulation's (relTol 1e-11)."""
    start = {**POWERED, "stops": False, "pump.speed": 0.0, "accumulator.volume": 1e-3,
             **{f"valve[{k}]": 0.05 for k in LEGS}}
    outputs = ["r[3]", "supply.pressure", "accumulator.oilVolume"]
    me = simulate_fmu(str(PLATFORM_FMU), fmi_type="ModelExchange", start_values=start, stop_time=1.5,
                      output_interval=0.01, relative_tolerance=1e-10, output=outputs)
    cs = simulate_fmu(str(PLATFORM_FMU), fmi_type="CoSimulation", start_values={**start, "solver.relTol": 1e-11},
                      stop_time=1.5, output_interval=0.01, output=outputs)
    # Model Exchange's rows include its events' instants: its last row at each output time.
    at = np.searchsorted(me["time"], cs["time"] + 1e-12, side="right") - 1
    events = len(me) - len(cs)
    dz = float(np.max(np.abs(me["r[3]"][at] - cs["r[3]"])))
    dp = float(np.max(np.abs(me["supply.pressure"][at] - cs["supply.pressure"])))
    empty = cs["time"][np.argmax(cs["accumulator.oilVolume"] == 0.0)]
    print(f"power unit, Model Exchange (CVODE) against Co-Simulation: heave within {dz:.1e} m, line within {dp:.1e} Pa; "
          f"the accumulator empty at {empty:.2f} s ({events} event rows), the line at {cs['supply.pressure'][-1] / 1e6:.3f} "
          "MPa at 1.5 s")
    assert cs["accumulator.oilVolume"][-1] == 0.0 and cs["supply.pressure"][-1] < 0.5 * U["pS"]
    assert events >= 1 and dz < 1e-6 and dp < 1e-3 * U["pS"]
    check_figures("model.txt", "power unit, Model Exchange (CVODE) against Co-Simulation through a 1 L accumulator's "
                  "emptying", f"heave within {dz:.1e} m, line within {dp:.1e} Pa")


def test_co_simulation_lands_on_the_accumulators_switch():
    """The same accumulator emptying through FMI 3 Co-Simulation (the adaptive method, event mode
    and early return, 10 ms steps): the step that meets the switch returns early at it, where
    the line's pressure equals the precharge (P_0 - p_atm gauge), and says so in its event
    message; the line goes on to collapse as in Model Exchange."""
    events = []

    def intermediate_update(_env, time, _set_requested, _get_allowed, _finished, can_return_early,
                            early_return_requested, early_return_time):
        early_return_requested[0] = True
        early_return_time[0] = time

    p3 = Fmu3(PLATFORM3, name="accumulator-switch", eventModeUsed=True, earlyReturnAllowed=True,
              intermediateUpdate=intermediate_update, events=events,
              integers=POWERED, booleans={"stops": False},
              reals={"pump.speed": 0.0, "accumulator.volume": 1e-3, "solver.relTol": 1e-10, "valve": [0.05] * 6})
    h, t_end = 1e-2, 1.0
    precharge = U["accumulator.precharge"] - ATMOSPHERE
    lines = []  # the line's pressure at each early return
    early, _ = p3.steps_with_events(h, t_end, at_early_return=lambda p: lines.append(p.get("supply.pressure")))
    at_switch = lines[0] if lines else None
    line = p3.get("supply.pressure")
    p3.free()
    said = [m for _, category, m in events if "accumulator emptied" in m]
    print(f"FMI 3 Co-Simulation returned early at {[round(t, 9) for t in early]} s; the line there "
          f"{at_switch:.6f} Pa gauge against the precharge {precharge:.6f} Pa ({at_switch - precharge:+.2e} Pa), "
          f"{line / 1e6:.3f} MPa at {t_end} s; logged: {said[:1]}")
    # The first early return is at the switch, where the first message puts it. (The landing
    # step ends a hair short of the root, and the next step finds it again: one or two more
    # early returns follow within microseconds, as at contacts.)
    assert early and early[0] < t_end and said and said[0].startswith(f"t = {early[0]!r}:")
    assert abs(at_switch - precharge) < 1.0 and line < 0.5 * precharge


def test_a_pump_stop_at_the_top_of_the_heave_lands_the_stand_at_rest_on_its_floor():
    """The pump stops at the heave programme's highest point (2.25 periods in); the accumulator
    feeds the valves, the controller lands when the supply falls below 12 MPa: at rest on
    landing.floor within 2 mm, no end stop touched, the supply above the accumulator's precharge,
    E - E0 = work.pump - work.compression - work.dissipated within 1e-7 of the dissipation."""
    t_stop = round(2.25 * PERIOD, 3)
    c, errors, status = hy.pump_stop_landing(t_stop, t_stop + 8.0, 12e6)
    assert status == "ok", status
    ctrl = Component(CONTROLLER_FMU, "landing-floor", {})
    floor = ctrl.values(["landing.floor"])[0]
    ctrl.free()
    after = c["time"] >= t_stop
    stops = max(np.abs(c[f"Fstop[{k}]"]).max() for k in LEGS)
    print(f"pump stop at {t_stop} s (z = {np.interp(t_stop, c['time'], c['r[3]']):.3f} m): lowest supply "
          f"{c['supply.pressure'][after].min() / 1e6:.2f} MPa, least oil {c['accumulator.oilVolume'].min() * 1e3:.2f} L, "
          f"at rest at z = {c['r[3]'][-1]:.4f} m (floor {floor:.4f} m), |v| {abs(c['v[3]'][-1]):.1e} m/s, stop force "
          f"{stops:.0f} N; energy balance {np.abs(balance(c)).max():.1e} J")
    assert abs(c["r[3]"][-1] - floor) < 2e-3 and abs(c["v[3]"][-1]) < 1e-3 and stops == 0.0
    assert c["supply.pressure"][after].min() > U["accumulator.precharge"] - ATMOSPHERE
    assert np.abs(balance(c)).max() < 1e-7 * c["work.dissipated"][-1]


def test_fmu_states_with_the_power_unit_and_the_landing_continue_bit_for_bit():
    """The closed loop on the heave programme with the power unit, the pump stopped from the start,
    the landing started by the falling supply: both FMUs' states serialized mid-landing and
    restored into fresh instances go on to the bit, as the uninterrupted run."""
    from stewart_fmu.cosim import COMMANDS, MEASURED

    h = 1e-3

    def pair(name):
        pl = Component(PLATFORM_FMU, f"{name}-platform", {"drive": 2, "hydraulic.supply": 1, "pump.speed": 0.0})
        ctrl = Component(CONTROLLER_FMU, f"{name}-controller", {"drive": 2, "landing.pressure": 15.9e6})
        return pl, ctrl

    def run(pl, ctrl, first, n):
        out = []
        for i in range(first, first + n):
            t = i * h
            ctrl.set_values(MEASURED[2], pl.values(MEASURED[2]))
            pl.set_values(COMMANDS[2], ctrl.values(COMMANDS[2]))
            pl.slave.doStep(currentCommunicationPoint=t, communicationStepSize=h)
            ctrl.slave.doStep(currentCommunicationPoint=t, communicationStepSize=h)
            out.append(list(pl.values(["r[3]", "supply.pressure", "accumulator.oilVolume", "work.pump"]))
                       + list(ctrl.values(["rp[3]", "valve[1]"])))
        return np.array(out)

    pl, ctrl = pair("a")
    run(pl, ctrl, 0, 1500)
    saved = [c.slave.serializeFMUstate(c.slave.getFMUstate()) for c in (pl, ctrl)]
    reference = run(pl, ctrl, 1500, 500)
    pl.free()
    ctrl.free()
    pl, ctrl = pair("b")
    for c, state in zip((pl, ctrl), saved):
        c.slave.setFMUstate(c.slave.deSerializeFMUstate(state))
    restored = run(pl, ctrl, 1500, 500)
    pl.free()
    ctrl.free()
    descent = reference[0, 4] - reference[-1, 4]
    print(f"FMU states mid-landing ({len(saved[0])} + {len(saved[1])} bytes): the programme descends {descent:.3f} m "
          f"over the next 0.5 s; identical: {np.array_equal(reference, restored)}")
    assert descent > 0.03, "the landing is under way"
    assert np.array_equal(reference, restored)


def test_the_power_unit_ssp_in_the_compiled_master_lands_as_the_python_master_does():
    """StewartSystemPowerUnit.ssp (its bindings: hydraulic.supply = 1, landing.pressure = 12 MPa)
    in the compiled master, the pump stopped at the heave's highest point by an override of
    pump.speed: the same heave and supply pressure as the package's Python master to the bit,
    and the stand at rest on landing.floor."""
    from stewart_fmu import master
    t_stop = round(2.25 * PERIOD, 3)
    t_end = t_stop + 8.0
    system = master.from_ssp(SYSTEM_POWER_UNIT_SSP)
    times, rows, status, message = master.run(system, t_end, 1e-3, record=["platform.r[3]", "platform.supply.pressure"],
                                              overrides=[("platform.pump.speed", 0.0, t_stop)])
    system.close()
    assert status == "ok", message
    c, _, py_status = hy.pump_stop_landing(t_stop, t_end, 12e6)
    assert py_status == "ok"
    n = min(len(times), len(c["time"]) - 1)
    same = np.array_equal(rows[-n:, 0], c["r[3]"][-n:]) and np.array_equal(rows[-n:, 1], c["supply.pressure"][-n:])
    print(f"StewartSystemPowerUnit.ssp, compiled master, pump stop at {t_stop} s: at rest at z = {rows[-1, 0]:.4f} m, "
          f"supply {rows[-1, 1] / 1e6:.3f} MPa; the Python master's bits over {n} steps: {same}")
    assert same
    assert abs(rows[-1, 0] - c["r[3]"][-1]) == 0.0 and abs(rows[-1, 0] - 1.5768) < 2e-3
