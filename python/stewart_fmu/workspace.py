"""The workspace scenarios (end stops, singular arrangements) through the packaged FMUs, in SI
units on the default stand. Shared by the tests (tests/python/test_workspace.py) and the main
job's demonstration (examples/workspace_scenarios.py).

1. power loss: equilibrium forces, then all six drop to zero; the platform falls onto its
   lower stops and comes to rest;
2. elastic stops (no contact damping): the platform bounces on its stops;
3. start-up: from rest on the lower stops the controller lifts the platform to its neutral
   pose (programme 4), then runs the heave programme;
4. actuator failure: under feedback, leg 1's force drops to zero; the platform tilts onto
   its stops;
5. tumble: no end stops, open-loop forces; the platform tumbles through singular leg
   arrangements;
6. power loss through Model Exchange (FMPy's CVODE, contacts located by the event indicators).
"""

import math
import re
import shutil

import numpy as np
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi2 import FMU2Model

from .cosim import closed_loop
from .core import (LEGS, PLATFORM_FMU, check_names, default_stand, equilibrium_force_si, fmu_file, open_loop,
                   recording_callbacks)


def start_values(names, fmu=PLATFORM_FMU):
    """Start values of the FMU's own model description (the defaults the FMU runs with)."""
    md = read_model_description(fmu_file(fmu))
    values = {v.name: v.start for v in md.modelVariables}
    check_names(names, values, md.modelName, "start_values")
    return {n: float(values[n]) for n in names}


def stop_defaults():
    s = start_values(["lmin[1]", "lmax[1]", "stops.stiffness", "stops.damping"])
    return s["lmin[1]"], s["lmax[1]"], s["stops.stiffness"], s["stops.damping"]


def static_rest_height(stiffness, lmin):
    """The default platform at rest on its six lower stops, solved independently of the FMU's
    code from the default stand's geometry (the FMU's joints, `default_stand`): pure heave by
    the stand's symmetry, `6 k_s (lmin - l) (H/l) = M g` with `l = sqrt(d² + H²)`, `d` the
    legs' horizontal projection and `H` the platform joints' height. Returns (centre-of-mass
    height, leg length)."""
    stand = default_stand()
    (bx, by, _), (ax, ay, az) = stand["B"][0], stand["A"][0]
    d = math.hypot(ax - bx, ay - by)
    weight = stand["M"] * stand["g"]

    def excess(h):
        l = math.hypot(d, h)
        return 6.0 * stiffness * (lmin - l) * h / l - weight

    lo, hi = 0.5, math.sqrt(lmin * lmin - d * d)
    assert excess(lo) > 0 > excess(hi)
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if excess(mid) > 0 else (lo, mid)
    h = 0.5 * (lo + hi)
    return h - az, math.hypot(d, h)


def contact_events(messages):
    """(time, leg, 'reached'/'left', 'lower'/'upper') from the FMU's logEvents messages."""
    out = []
    for _, _, text in messages:
        m = re.match(r"t = ([-+0-9.eE]+): leg (\d) (reached|left) its (lower|upper) end stop", text)
        if m:
            out.append((float(m.group(1)), int(m.group(2)), m.group(3), m.group(4)))
    return out


def singular_passages(messages):
    return [float(m.group(1)) for _, _, text in messages
            if (m := re.match(r"t = ([-+0-9.eE]+): the legs passed through a singular arrangement", text))]


# The joints' angles from their reference directions (docs/model.md §8: their limits'
# margins in the defaults table come from these runs).
JOINT_ANGLES = [f"thetaB[{k}]" for k in LEGS] + [f"thetaA[{k}]" for k in LEGS]
RECORD = (["r[1]", "r[2]", "r[3]", "v[3]", "der(v[3])", "angles[1]", "angles[2]", "E", "work.F", "work.dissipated",
           "kappa"] + [f"l[{k}]" for k in LEGS] + [f"Fstop[{k}]" for k in LEGS] + JOINT_ANGLES)


def largest_joint_angles(data, during=slice(None)):
    """(the largest base joint angle, the largest platform joint angle) of a run's records, in
    degrees, over the rows `during` selects."""
    return tuple(float(np.degrees(max(np.max(data[f"theta{side}[{k}]"][during]) for k in LEGS))) for side in "BA")


def _platform_run(force_of_t, t_end, h, parameters=None, record=RECORD, events=None):
    """Open loop, forces held over each step (`stewart_fmu.core.open_loop`); returns a dict of
    arrays. RuntimeError if a step is discarded: every scenario here runs to its end."""
    data, status = open_loop(force_of_t, t_end, h, parameters, record, events)
    if status != "ok":
        raise RuntimeError(f"the open-loop run ended at t = {data['time'][-1]}: {status}")
    return data


def power_loss(t_cut=0.5, t_end=5.0, h=1e-3, parameters=None):
    """Scenario 1. Returns the recorded outputs and the contact events."""
    events = []
    force = equilibrium_force_si()
    data = _platform_run(lambda t: [force if t < t_cut - 1e-12 else 0.0] * 6, t_end, h,
                         parameters=parameters, events=events)
    data["events"] = contact_events(events)
    return data


def elastic_bounces(t_end, rel_tol, h=1e-2):
    """Scenario 2: elastic stops, zero forces from the neutral pose, tolerance `rel_tol`."""
    events = []
    data = _platform_run(lambda t: [0.0] * 6, t_end, h, events=events,
                         parameters={"stops.damping": 0.0, "solver.relTol": rel_tol, "solver.absTol": rel_tol * 1e-2},
                         record=["r[3]", "E", "angles[1]", "angles[2]"])
    data["events"] = contact_events(events)
    return data


def start_up(t_end=12.0, h=1e-3, duration=3.0):
    """Scenario 3: platform parked at rest on its lower stops; the controller's start-up
    programme lifts it to the neutral pose in `duration`, then the heave programme runs."""
    lmin, _, stiffness, _ = stop_defaults()
    z_rest, _ = static_rest_height(stiffness, lmin)
    events = []
    record = ["r[3]", "angles[1]", "angles[2]"] + [f"l[{k}]" for k in LEGS] + [f"Fstop[{k}]" for k in LEGS] \
        + JOINT_ANGLES
    t, rows, errors, status = closed_loop(
        t_end, h, platform_reals={"r0[3]": z_rest}, controller_integers={"programme": 4},
        controller_reals={"startup.position[3]": z_rest, "startup.duration": duration}, record=record, events=events)
    data = {name: rows[:, j] for j, name in enumerate(record)}
    data.update(time=t, error=errors, status=status, events=contact_events(events), z_rest=z_rest)
    return data


def actuator_failure(t_fail=1.0, t_end=5.0, h=1e-3, leg=1):
    """Scenario 4: the closed loop on the default heave programme; leg `leg`'s force drops to
    zero at `t_fail` (the controller does not know)."""
    events = []
    record = ["r[3]", "angles[1]", "angles[2]", "der(v[3])"] + [f"l[{k}]" for k in LEGS] \
        + [f"Fstop[{k}]" for k in LEGS] + JOINT_ANGLES

    def fail(time, forces):
        if time >= t_fail - 1e-12:
            forces = forces.copy()
            forces[leg - 1] = 0.0
        return forces

    t, rows, errors, status = closed_loop(t_end, h, record=record, force_hook=fail, events=events)
    data = {name: rows[:, j] for j, name in enumerate(record)}
    data.update(time=t, error=errors, status=status, events=contact_events(events))
    return data


def tumble_forces(t):
    """Open-loop forces under which the platform without end stops tumbles through singular
    leg arrangements while rising (5 % more than its weight on average)."""
    force = equilibrium_force_si()
    return [force * (1.05 + 0.5 * math.sin(2.0 * t + 1.1 * k)) for k in range(6)]


def tumble(t_end=3.0, h=1e-2, rel_tol=1e-12):
    """Scenario 5: no end stops, open-loop forces held over each step."""
    events = []
    record = ["r[1]", "r[2]", "r[3]", "kappa"] + [f"R[{a},{b}]" for a in range(1, 4) for b in range(1, 4)]
    data = _platform_run(tumble_forces, t_end, h, events=events, record=record,
                         parameters={"stops": False, "joints": False, "solver.relTol": rel_tol, "solver.absTol": rel_tol * 1e-2})
    data["singular"] = singular_passages(events)
    return data


def power_loss_model_exchange(t_cut=0.5, t_end=5.0):
    """Scenario 6: scenario 1 through FMPy's Model Exchange with CVODE; the force drop is an
    input event (two rows at t_cut), the contacts are located by the event indicators."""
    force = equilibrium_force_si()
    inputs = np.array([(0.0,) + (force,) * 6, (t_cut,) + (force,) * 6,
                       (t_cut,) + (0.0,) * 6, (t_end,) + (0.0,) * 6],
                      dtype=[("time", float)] + [(f"F[{k}]", float) for k in LEGS])
    # The instance is made here with the package's recording callbacks, not through
    # simulate_fmu's `logger`: FMPy keeps that one in a process-wide logging proxy, which then
    # points at a freed callback for every FMU the process runs later (a crash).
    messages = []
    md = read_model_description(str(PLATFORM_FMU))
    unzipped = extract(str(PLATFORM_FMU))
    fmu = FMU2Model(guid=md.guid, unzipDirectory=unzipped, modelIdentifier=md.modelExchange.modelIdentifier,
                    instanceName="power_loss")
    fmu.instantiate(callbacks=recording_callbacks(messages), loggingOn=True)
    try:
        result = simulate_fmu(unzipped, model_description=md, fmu_instance=fmu, solver="CVode",
                              relative_tolerance=1e-8, input=inputs, stop_time=t_end, output_interval=1e-3,
                              output=["r[1]", "r[2]", "r[3]", "v[3]", "E", "work.F", "work.dissipated"]
                              + [f"Fstop[{k}]" for k in LEGS])
    finally:
        fmu.freeInstance()
        shutil.rmtree(unzipped, ignore_errors=True)
    return result, contact_events(messages)
