"""The hydraulic servo legs (docs/model.md §10: each leg a differential cylinder fed by a
servo valve, valve commands in, chamber pressures out) through the packaged FMUs, SI units,
default stand and legs. Shared by the tests (tests/python/test_hydraulics.py) and the main
job's demonstration (examples/hydraulic_scenarios.py).

1. holding: the stand at rest under closed-loop control on the holding pressures;
2. the paper's heave programme in closed loop, hydraulic mode;
3. loss of control power: every valve command to 0, the legs lock and creep on the leakage;
4. pump failure: `pS` to 0 with the controller still commanding;
5. one valve stuck open under feedback.

The holding pressures, the creep rate and the valve flows are computed here from the FMU's
parameter values and §10's equations, independently of the FMU's code.
"""

import math

import numpy as np
from fmpy import read_model_description

from .core import CONTROLLER_FMU, EQUILIBRIUM_FORCE, GRAVITY, H_C, LEGS, MASS, PLATFORM_FMU, Component
from .core import neutral_leg_geometry
from .cosim import COMMANDS, MEASURED, steps

PARAMETERS = ("hydraulic.bore", "hydraulic.rod", "hydraulic.deadVolumeA", "hydraulic.deadVolumeB",
              "hydraulic.bulkModulus", "hydraulic.tankPressure", "valve.ratedFlow", "valve.ratedPressureDrop",
              "valve.omega", "valve.damping", "valve.pcr", "valve.leakage", "hydraulic.internalLeakage", "pS")
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


def areas(p):
    """`(A_A, A_B)`, m²."""
    d, rod = p["hydraulic.bore"], p["hydraulic.rod"]
    return math.pi * d * d / 4.0, math.pi * (d * d - rod * rod) / 4.0


def flow_coefficient(p):
    """`K = Q_N / sqrt(dp_N / 2)`."""
    return p["valve.ratedFlow"] / math.sqrt(p["valve.ratedPressureDrop"] / 2.0)


def volumes(l, p):
    """`(V_A, V_B)`, m³, of a leg of length `l`."""
    area_a, area_b = areas(p)
    x = l - p["lmin[1]"]
    return p["hydraulic.deadVolumeA"] + area_a * x, p["hydraulic.deadVolumeB"] + area_b * (p["lmax[1]"] - p["lmin[1]"] - x)


def holding_pressures(p):
    """The default stand's holding pressures at its neutral pose: `p_B = p_S / 2`, and the cap
    side pushing `0.2005 M g` (docs/model.md §3) with it."""
    area_a, area_b = areas(p)
    pb = p["pS"] / 2.0
    return (EQUILIBRIUM_FORCE * MASS * GRAVITY + pb * area_b) / area_a, pb


def leakage_flows(pa, pb, p, supply=None):
    """The leakage into each chamber at a centred spool (§10: each land's null leakage to
    supply and to tank, the piston's internal leakage): `(Q_A, Q_B)`, m³/s."""
    ps = p["pS"] if supply is None else supply
    pt, cv, ci = p["hydraulic.tankPressure"], p["valve.leakage"], p["hydraulic.internalLeakage"]
    internal = ci * (pa - pb)
    return cv * (ps - pa) - cv * (pa - pt) - internal, cv * (ps - pb) - cv * (pb - pt) + internal


def quasi_static_creep(pa, pb, l, p, supply=None):
    """The leg rate (m/s) at which a locked leg (spool centred) creeps on its leakage while it
    keeps carrying its load: the force `p_A A_A - p_B A_B` constant, so `A_A p_A' = A_B p_B'`
    with `p_A' = beta/V_A (Q_A - A_A v)`, `p_B' = beta/V_B (Q_B + A_B v)`:
    `v = (A_A Q_A / V_A - A_B Q_B / V_B) / (A_A^2 / V_A + A_B^2 / V_B)`."""
    area_a, area_b = areas(p)
    va, vb = volumes(l, p)
    qa, qb = leakage_flows(pa, pb, p, supply)
    return (area_a * qa / va - area_b * qb / vb) / (area_a * area_a / va + area_b * area_b / vb)


def heave_rate_of_leg_rate(l):
    """`z'` per unit leg rate in pure heave at leg length `l`: the legs' vertical direction
    cosine is `n_z = H / l`, `l' = n_z z'`."""
    d, _ = neutral_leg_geometry(nondimensional=False)
    height = math.sqrt(max(l * l - d * d, 0.0))
    return l / height


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


def pump_failure(t_fail=1.0, t_end=4.0, events=None):
    """Scenario 4: the heave programme; the supply pressure to 0 at `t_fail`, the controller
    still commanding."""
    def fail(t, platform, valves):
        if t >= t_fail - 1e-12:
            platform.set_values(["pS"], [0.0])
        return valves
    return closed_loop(t_end, hook=fail, events=events,
                       record=[f"jointForce[{k},{c}]" for k in LEGS for c in (1, 2, 3)])


def stuck_valve(t_stick=1.0, t_end=6.0, leg=1, opening=0.2):
    """Scenario 5: leg `leg`'s valve sticks at `opening` from `t_stick` under feedback (the
    controller does not know)."""
    def stick(t, _platform, valves):
        if t >= t_stick - 1e-12:
            valves = np.array(valves, dtype=float)
            valves[leg - 1] = opening
        return valves
    return closed_loop(t_end, hook=stick, controller={"programme": 2},
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


__all__ = ["hydraulic_parameters", "areas", "flow_coefficient", "volumes", "holding_pressures", "leakage_flows",
           "quasi_static_creep", "heave_rate_of_leg_rate", "closed_loop", "resting", "heave", "control_power_loss",
           "pump_failure", "stuck_valve", "cycle_figures", "H_C"]
