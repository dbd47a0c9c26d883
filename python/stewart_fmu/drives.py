"""The electric drives (docs/model.md §9: each leg a DC motor turning a ball screw, voltages
in) through the packaged FMUs, SI units, default stand and drives. Shared by the tests
(tests/python/test_drives.py) and the main job's demonstration (examples/drive_scenarios.py).

1. holding: the neutral pose on constant holding voltages;
2. power loss with dynamic braking: the voltages drop to 0 (windings shorted) and the
   platform descends at the speed the back EMF allows, onto its lower stops; the same power
   loss with ideal force actuators (forces to 0) for comparison;
3. the heave programme in the closed loop with the controller in voltage mode;
4. actuator failure: one drive's voltage to 0 (shorted) under feedback.

The drive's parameters are the FMU's (its model description's start values). The holding
current and voltage are the caller's: the tests and the demonstration compute them with the
drive's static model written out independently of the FMU's code (tests/python/oracles/drives.py).
"""

from fmpy import read_model_description

from .core import LEGS, PLATFORM_FMU, equilibrium_force_si
from .core import open_loop as core_open_loop
from .cosim import closed_loop

DRIVE_PARAMETERS = ("motor.R", "motor.L", "motor.ke", "motor.kt", "motor.J", "motor.D", "gear.ratio", "screw.lead")
CURRENTS = [f"I[{k}]" for k in LEGS]


def drive_parameters(fmu=PLATFORM_FMU):
    """The FMU's default drive parameters (its model description's start values)."""
    start = {v.name: v.start for v in read_model_description(str(fmu)).modelVariables}
    return {n: float(start[n]) for n in DRIVE_PARAMETERS}


def drive_start(current):
    """Platform parameters for a run with drives that starts holding: drive = 1 and I0 at the
    holding current `current` (A)."""
    return {"drive": 1, **{f"I0[{k}]": current for k in LEGS}}


RECORD = (["r[3]", "v[3]", "der(v[3])", "angles[1]", "angles[2]", "E", "work.F", "work.electric", "work.dissipated"]
          + CURRENTS + [f"Fstop[{k}]" for k in LEGS] + [f"l[{k}]" for k in LEGS] + [f"ldot[{k}]" for k in LEGS])


def open_loop(voltage_of_t, t_end, h=0.01, parameters=None, record=(), drive=True):
    """The platform with drives (drive = 1 and `parameters`, which give the initial currents
    `I0`: `drive_start`; or with `drive=False` the same parameters with forces as inputs) under
    `voltage_of_t(t)` -> six voltages (or forces), through FMPy; returns (columns, logEvents
    messages, status)."""
    messages = []
    start = {**({"drive": 1} if drive else {}), **(parameters or {})}
    columns, status = core_open_loop(voltage_of_t, t_end, h, start, list(dict.fromkeys(RECORD + list(record))),
                                     messages, "U" if drive else "F", "drives")
    return columns, messages, status


def holding_run(holding, t_end=3.0):
    """Scenario 1: `holding` = (current, voltage) of the static model, from the start."""
    i_hold, u_hold = holding
    return open_loop(lambda t: [u_hold] * 6, t_end, parameters=drive_start(i_hold))


def power_loss(holding, t_loss=0.5, t_end=16.0, h=0.01):
    """Dynamic braking: holding voltages (`holding` = (current, voltage)) until `t_loss`, then 0."""
    i_hold, u_hold = holding
    return open_loop(lambda t: [u_hold if t < t_loss else 0.0] * 6, t_end, h, parameters=drive_start(i_hold))


def power_loss_forces(t_loss=0.5, t_end=2.0, h=0.01):
    """The same power loss with ideal force actuators: the equilibrium forces until `t_loss`,
    then 0 (the platform falls onto its stops)."""
    force = equilibrium_force_si()
    return open_loop(lambda t: [force if t < t_loss else 0.0] * 6, t_end, h, drive=False)


def heave_closed_loop(current, t_end=10.0, h=1e-3, record=(), force_hook=None):
    """The default controller in voltage mode on the heave programme, the drives starting at the
    holding current `current`: returns (columns, largest leg error per step, status); columns
    hold time, r[3], the currents and the legs' rates."""
    names = list(dict.fromkeys(["r[3]", "E", "work.electric", "work.dissipated", "angles[1]", "angles[2]"] + CURRENTS
                               + [f"ldot[{k}]" for k in LEGS] + list(record)))
    t, rows, errors, status = closed_loop(t_end, h, platform_reals=drive_start(current), controller_integers={"drive": 1},
                                          record=names, force_hook=force_hook)
    return {"time": t, **{n: rows[:, j] for j, n in enumerate(names)}}, errors, status


def failure(current, t_fail=1.0, t_end=6.0, h=1e-3, leg=1):
    """Leg `leg`'s drive loses its voltage at `t_fail` (U = 0: shorted) while the controller in
    voltage mode drives the heave programme (it does not know); the drives start at the holding
    current `current`."""

    def fail(time, voltages):
        if time >= t_fail - 1e-12:
            voltages = voltages.copy()
            voltages[leg - 1] = 0.0
        return voltages

    record = [f"l[{k}]" for k in LEGS] + [f"Fstop[{k}]" for k in LEGS] + [f"U[{k}]" for k in LEGS]
    return heave_closed_loop(current, t_end, h, record=record, force_hook=fail)
