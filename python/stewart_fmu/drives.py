"""The electric drives (docs/model.md §9: each leg a DC motor turning a ball screw, voltages
in) through the packaged FMUs, SI units, default stand and drives. Shared by the tests
(tests/python/test_drives.py) and the main job's demonstration (examples/drive_scenarios.py).

1. holding: the neutral pose on constant holding voltages;
2. power loss with dynamic braking: the voltages drop to 0 (windings shorted) and the
   platform descends at the speed the back EMF allows, onto its lower stops; the same power
   loss with ideal force actuators (forces to 0) for comparison;
3. the heave programme in the closed loop with the controller in voltage mode;
4. actuator failure: one drive's voltage to 0 (shorted) under feedback.

The drive's static model and the quasi-static descent are computed here from the FMU's
parameter values and the default stand's geometry (docs/model.md §3), independently of the
FMU's code.
"""

import math

from fmpy import read_model_description

from .core import GRAVITY, H_C, LEGS, MASS, PLATFORM_FMU, neutral_leg_geometry
from .core import open_loop as core_open_loop
from .cosim import closed_loop

DRIVE_PARAMETERS = ("motor.R", "motor.L", "motor.ke", "motor.kt", "motor.J", "motor.D", "gear.ratio", "screw.lead")
CURRENTS = [f"I[{k}]" for k in LEGS]


def drive_parameters(fmu=PLATFORM_FMU):
    """The FMU's default drive parameters (its model description's start values)."""
    start = {v.name: v.start for v in read_model_description(str(fmu)).modelVariables}
    return {n: float(start[n]) for n in DRIVE_PARAMETERS}


def transmission(p):
    """N = 2 pi i / p, rad/m."""
    return 2.0 * math.pi * p["gear.ratio"] / p["screw.lead"]


def static_drive(force, l_dot, p):
    """The drive's static model (docs/model.md §9): current I = u / (N k_t) and voltage
    U = R I + k_e N l' for the axial force u at the leg rate l'."""
    n = transmission(p)
    current = force / (n * p["motor.kt"])
    return current, current * p["motor.R"] + p["motor.ke"] * n * l_dot


def holding(p):
    """The holding current and voltage of the default stand at its neutral pose: each leg
    carries 0.2005 M g (docs/model.md §3)."""
    return static_drive(0.2005 * MASS * GRAVITY, 0.0, p)


def braking_damping(p):
    """With the windings shorted (U = 0) and the current settled, a leg moving at l' feels the
    force -c l', c = N^2 (k_t k_e / R + D), N.s/m."""
    n = transmission(p)
    return n * n * (p["motor.kt"] * p["motor.ke"] / p["motor.R"] + p["motor.D"])


def quasi_static_descent_rate(z, p):
    """The heave rate z' (m/s, negative) at which the default stand, in pure heave at centre-of-
    mass height z, sinks with its six drives braking: each leg's braking force c l' balances the
    leg force u = M g / (6 n_z) that holds the weight (n_z = H / l the leg's vertical direction
    cosine, H = z - h_c the joint plane's height, l = sqrt(d^2 + H^2)); with l' = n_z z',
    z' = -M g / (6 c n_z^2)."""
    d, _ = neutral_leg_geometry(nondimensional=False)
    height = z - H_C
    n_z = height / math.hypot(d, height)
    return -MASS * GRAVITY / (6.0 * braking_damping(p) * n_z * n_z)


def drive_start(p=None):
    """Platform parameters for a run with drives that starts holding: drive = 1 and I0 at the
    holding current."""
    p = p or drive_parameters()
    i_hold, _ = holding(p)
    return {"drive": 1, **{f"I0[{k}]": i_hold for k in LEGS}}


RECORD = (["r[3]", "v[3]", "der(v[3])", "angles[1]", "angles[2]", "E", "work.F", "work.electric", "work.dissipated"]
          + CURRENTS + [f"Fstop[{k}]" for k in LEGS] + [f"l[{k}]" for k in LEGS] + [f"ldot[{k}]" for k in LEGS])


def open_loop(voltage_of_t, t_end, h=0.01, parameters=None, record=(), drive=True):
    """The platform with drives (or with `drive=False` the same parameters with forces as
    inputs) under `voltage_of_t(t)` -> six voltages (or forces), through FMPy; returns (columns,
    logEvents messages, status)."""
    messages = []
    start = {**(drive_start() if drive else {}), **(parameters or {})}
    columns, status = core_open_loop(voltage_of_t, t_end, h, start, list(dict.fromkeys(RECORD + list(record))),
                                     messages, "U" if drive else "F", "drives")
    return columns, messages, status


def holding_run(t_end=3.0):
    p = drive_parameters()
    _, u_hold = holding(p)
    return open_loop(lambda t: [u_hold] * 6, t_end)


def power_loss(t_loss=0.5, t_end=16.0, h=0.01):
    """Dynamic braking: holding voltages until `t_loss`, then 0."""
    p = drive_parameters()
    _, u_hold = holding(p)
    return open_loop(lambda t: [u_hold if t < t_loss else 0.0] * 6, t_end, h)


def power_loss_forces(t_loss=0.5, t_end=2.0, h=0.01):
    """The same power loss with ideal force actuators: the equilibrium forces until `t_loss`,
    then 0 (the platform falls onto its stops)."""
    force = 0.2005 * MASS * GRAVITY
    return open_loop(lambda t: [force if t < t_loss else 0.0] * 6, t_end, h, drive=False)


def heave_closed_loop(t_end=10.0, h=1e-3, record=(), force_hook=None):
    """The default controller in voltage mode on the heave programme: returns (columns, largest
    leg error per step, status); columns hold time, r[3], the currents and the legs' rates."""
    names = list(dict.fromkeys(["r[3]", "E", "work.electric", "work.dissipated", "angles[1]", "angles[2]"] + CURRENTS
                               + [f"ldot[{k}]" for k in LEGS] + list(record)))
    t, rows, errors, status = closed_loop(t_end, h, platform_reals=drive_start(), controller_integers={"drive": 1},
                                          record=names, force_hook=force_hook)
    return {"time": t, **{n: rows[:, j] for j, n in enumerate(names)}}, errors, status


def failure(t_fail=1.0, t_end=6.0, h=1e-3, leg=1):
    """Leg `leg`'s drive loses its voltage at `t_fail` (U = 0: shorted) while the controller in
    voltage mode drives the heave programme (it does not know)."""

    def fail(time, voltages):
        if time >= t_fail - 1e-12:
            voltages = voltages.copy()
            voltages[leg - 1] = 0.0
        return voltages

    record = [f"l[{k}]" for k in LEGS] + [f"Fstop[{k}]" for k in LEGS] + [f"U[{k}]" for k in LEGS]
    return heave_closed_loop(t_end, h, record=record, force_hook=fail)
