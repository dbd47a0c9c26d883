"""The hydraulic servo legs (docs/model.md §10: each leg a differential cylinder fed by a
servo valve, valve commands in, chamber pressures out) through the packaged FMUs, SI units,
default stand and legs. Shared by the tests (tests/python/test_hydraulics.py) and the main
job's demonstration (examples/hydraulic_scenarios.py).

1. holding: the stand at rest under closed-loop control on the holding pressures;
2. the paper's heave programme in closed loop, hydraulic mode;
3. loss of control power: every valve command to 0, the legs lock and creep on the leakage;
4. pump failure: `pS` to 0 with the controller still commanding;
5. one valve stuck open under feedback;

and with the power unit (`hydraulic.supply = 1`, docs/model.md §10b): the heave programme fed
by the pump and the accumulator, and a pump stop that the accumulator and the controller's safe
landing answer.

The parameters are the FMU's (its model description's start values). What the tests and the
demonstration compare the runs with (the holding pressures, the creep rate, the valve flows) is
§10 written out independently of the FMU's code, in tests/python/oracles/hydraulics.py.
"""

import numpy as np
from fmpy import read_model_description

from .core import CONTROLLER_FMU, LEGS, PLATFORM_FMU, Component
from .cosim import COMMANDS, MEASURED, steps

PARAMETERS = ("hydraulic.bore", "hydraulic.rod", "hydraulic.deadVolumeA", "hydraulic.deadVolumeB",
              "hydraulic.bulkModulus", "hydraulic.tankPressure", "valve.ratedFlow", "valve.ratedPressureDrop",
              "valve.omega", "valve.damping", "valve.pcr", "valve.leakage", "hydraulic.internalLeakage",
              "hydraulic.airFraction", "hydraulic.airPolytropic", "pS")
PA = [f"pA[{k}]" for k in LEGS]
PB = [f"pB[{k}]" for k in LEGS]
SPOOL = [f"spool[{k}]" for k in LEGS]
L = [f"l[{k}]" for k in LEGS]
RECORD = (["r[3]", "v[3]", "der(v[3])", "angles[1]", "angles[2]", "E", "work.hydraulic", "work.compression",
           "work.dissipated", "Qsupply", "pmin"] + PA + PB + SPOOL + L + [f"ldot[{k}]" for k in LEGS]
          + [f"actuatorForce[{k}]" for k in LEGS] + [f"Fstop[{k}]" for k in LEGS])


def hydraulic_parameters(fmu=PLATFORM_FMU):
    """The FMU's default hydraulic parameters and supply (its model description's start values),
    with the strokes' ends `lmin`, `lmax` of leg 1."""
    start = {v.name: v.start for v in read_model_description(str(fmu)).modelVariables}
    return {n: float(start[n]) for n in PARAMETERS + ("lmin[1]", "lmax[1]")}


def closed_loop(t_end, h=1e-3, hook=None, record=(), controller=None, platform=None, events=None):
    """The platform and the controller in hydraulic mode (`drive = 2` in both) on the default
    heave programme (or `controller` parameters), through the package's master loop
    (Gauss-Seidel); `hook(t, platform, valves)` may change the platform's inputs before each
    step (return the valve commands it sends). Returns (columns: `time` and RECORD + `record`,
    the largest |l - l^p| after each step, status)."""
    names = list(dict.fromkeys(RECORD + list(record)))
    pl = Component(PLATFORM_FMU, "platform", {"drive": 2, **(platform or {})}, events=events)
    ctrl = Component(CONTROLLER_FMU, "controller", {"drive": 2, **(controller or {})})
    lp = [f"lp[{k}]" for k in LEGS]
    times, rows, errors, status = [0.0], [pl.values(names)], [0.0], "ok"
    commands = COMMANDS[2]

    def through(t, valves):
        return hook(t, pl, valves) if hook else valves

    try:
        for t in steps(pl, ctrl, int(round(t_end / h)), h, "gauss-seidel", commands, through, MEASURED[2]):
            times.append(t)
            rows.append(pl.values(names))
            errors.append(float(np.max(np.abs(pl.values(L) - ctrl.values(lp)))))
    except Exception as e:  # noqa: BLE001 - a discarded step ends the run, as in cosim
        status = str(e)
    finally:
        pl.free()
        ctrl.free()
    rows = np.array(rows)
    return {"time": np.array(times), **{n: rows[:, j] for j, n in enumerate(names)}}, np.array(errors), status


def resting(t_end=3.0):
    """Scenario 1: the programme holds the neutral pose (programme 2 with zero amplitudes)."""
    return closed_loop(t_end, controller={"programme": 2})


def heave(t_end=10.0):
    """Scenario 2: the default heave programme."""
    return closed_loop(t_end)


def control_power_loss(t_loss=1.0, t_end=6.0):
    """Scenario 3: at rest under control, then every valve command 0 (the spools centre)."""
    def lose(t, _platform, valves):
        return np.zeros(6) if t >= t_loss - 1e-12 else valves
    return closed_loop(t_end, hook=lose, controller={"programme": 2})


def pump_failure(t_fail=1.0, t_end=4.0, events=None, platform=None):
    """Scenario 4: the heave programme; the supply pressure to 0 at `t_fail`, the controller
    still commanding (`platform`: parameters of the platform, e.g. `hydraulic.airFraction`)."""
    def fail(t, platform, valves):
        if t >= t_fail - 1e-12:
            platform.set_values(["pS"], [0.0])
        return valves
    return closed_loop(t_end, hook=fail, events=events, platform=platform,
                       record=[f"jointForce[{k},{c}]" for k in LEGS for c in (1, 2, 3)])


POWER_UNIT = ["supply.pressure", "supply.pumpFlow", "supply.reliefFlow", "accumulator.oilVolume", "work.pump"]


def power_unit_heave(t_end=10.0, platform=None):
    """The heave programme with the power unit feeding the valves (`hydraulic.supply = 1`)."""
    return closed_loop(t_end, platform={"hydraulic.supply": 1, **(platform or {})}, record=POWER_UNIT)


def pump_stop_landing(t_stop, t_end, landing_pressure, platform=None, controller=None):
    """The heave programme with the power unit; the pump stops at `t_stop` (`pump.speed` 0),
    the accumulator feeds the valves, and the controller starts its safe landing when the
    measured supply pressure falls below `landing_pressure` (`landing.pressure`)."""
    def stop(t, platform, valves):
        if abs(t - t_stop) < 1e-9:
            platform.set_values(["pump.speed"], [0.0])
        return valves
    return closed_loop(t_end, hook=stop, platform={"hydraulic.supply": 1, **(platform or {})},
                       controller={"landing.pressure": landing_pressure, **(controller or {})},
                       record=POWER_UNIT)


def stuck_valve(t_stick=1.0, t_end=6.0, leg=1, opening=0.2, platform=None):
    """Scenario 5: leg `leg`'s valve sticks at `opening` from `t_stick` under feedback (the
    controller does not know; `platform`: parameters of the platform)."""
    def stick(t, _platform, valves):
        if t >= t_stick - 1e-12:
            valves = np.array(valves, dtype=float)
            valves[leg - 1] = opening
        return valves
    return closed_loop(t_end, hook=stick, controller={"programme": 2}, platform=platform,
                       record=[f"jointForce[{k},{c}]" for k in LEGS for c in (1, 2, 3)]
                       + [f"thetaB[{k}]" for k in LEGS] + [f"thetaA[{k}]" for k in LEGS])


def cycle_figures(c, period, p):
    """Over the last whole `period` of a run: peak supply flow (m³/s), peak and mean hydraulic
    power (W, from work.hydraulic), the range of the chamber pressures (Pa) and the largest
    spool opening."""
    t = c["time"]
    last = t >= t[-1] - period
    power = np.gradient(c["work.hydraulic"], t)
    pressures = np.concatenate([c[n][last] for n in PA + PB])
    return {
        "peak_flow": float(np.max(c["Qsupply"][last])),
        "peak_power": float(np.max(power[last])),
        "mean_power": float((c["work.hydraulic"][last][-1] - c["work.hydraulic"][last][0]) / (t[last][-1] - t[last][0])),
        "pressure_range": (float(pressures.min()), float(pressures.max())),
        "largest_opening": float(np.max(np.abs(np.concatenate([c[n][last] for n in SPOOL])))),
    }


__all__ = ["hydraulic_parameters", "closed_loop", "resting", "heave", "control_power_loss", "pump_failure",
           "stuck_valve", "cycle_figures"]
