"""A Python co-simulation master over two FMU2Slave instances, StewartController and
StewartPlatform: controller.F -> platform.F (or with electric drives, `drive = 1` in both,
controller.U -> platform.U), platform.l -> controller.l, platform.ldot -> controller.ldot, at
a fixed communication step.

Two coupling schemes:
- "gauss-seidel" (the default): at each communication point the platform's measured legs go
  to the controller, whose forces at that point go to the platform, then both step. The
  controller has direct feed-through, so the platform sees forces from its own current
  legs (the sampled-data loop a real controller implements).
- "jacobi": FMPy's SSP algorithm, replicated exactly (fmpy/ssp/simulation.py): connections
  start at 0.0; each step every component gets its inputs from the connections, steps, and
  writes its outputs; then the connections are copied. The measurement reaches the platform
  one communication step later.
"""

import numpy as np
from fmpy.fmi1 import FMICallException

from .core import CONTROLLER_FMU, LEGS, PLATFORM_FMU, Component, check_names, check_times, vector_of
from .ssp import SYSTEM_DRIVES_SSP, SYSTEM_SSP  # noqa: F401 (the systems this master runs, for its users)

SCHEMES = ("gauss-seidel", "jacobi")

L = [f"l[{k}]" for k in LEGS]
LDOT = [f"ldot[{k}]" for k in LEGS]
F = [f"F[{k}]" for k in LEGS]
U = [f"U[{k}]" for k in LEGS]
VALVE = [f"valve[{k}]" for k in LEGS]
PA = [f"pA[{k}]" for k in LEGS]
PB = [f"pB[{k}]" for k in LEGS]
#: What the controller gets from the platform and what it sends back, by `drive` (0 forces,
#: 1 electric drives, 2 hydraulic legs).
MEASURED = {0: L + LDOT, 1: L + LDOT, 2: L + LDOT + PA + PB + ["supply.pressure"]}
COMMANDS = {0: F, 1: U, 2: VALVE}
LP = [f"lp[{k}]" for k in LEGS]


def closed_loop(t_end, h, scheme="gauss-seidel", platform_reals=None, controller_reals=None, controller_integers=None,
                record=("r[3]",), force_hook=None, events=None):
    """Runs the coupled system; returns (times, recorded platform outputs, max |l - l^p| per
    step, status) with status "ok" or the FMU's message if a step failed. With `drive = 1` in
    both components' parameters the voltages U are exchanged instead of the forces F.
    `force_hook(t, F)` may change the forces (or voltages) on their way to the platform (an
    actuator failure); `events`
    receives the platform's logEvents messages. Raises ValueError, before anything runs, for
    an end time or step that is not positive and finite, an unknown scheme, or a variable name
    the FMUs do not have."""
    check_times(t_end, h, "t_end", "h")
    if scheme not in SCHEMES:
        raise ValueError(f"scheme = {scheme!r}: 'gauss-seidel' or 'jacobi'")
    drives = [int(dict(p or {}).get("drive", 0)) for p in (platform_reals, {**(controller_reals or {}),
                                                                           **(controller_integers or {})})]
    if drives[0] != drives[1]:
        raise ValueError(f"drive = {drives[0]} in platform_reals but {drives[1]} in the controller's parameters: the "
                         "controller's commands (F, U or valve) drive the platform only when both have the same drive")
    if drives[0] not in COMMANDS:
        raise ValueError(f"drive = {drives[0]}: 0 (forces), 1 (electric drives) or 2 (hydraulic legs)")
    commands, measured = COMMANDS[drives[0]], MEASURED[drives[0]]
    record = list(record)
    platform = Component(PLATFORM_FMU, "platform", platform_reals, events=events,
                         what=("platform_reals", "platform_integers"))
    try:
        check_names(record, platform.vr, platform.md.modelName, "record")
        controller = Component(CONTROLLER_FMU, "controller", controller_reals, controller_integers,
                               what=("controller_reals", "controller_integers"))
    except ValueError:
        platform.free()
        raise
    try:
        return _run(platform, controller, t_end, h, scheme, record, force_hook, commands, measured)
    finally:
        platform.free()
        controller.free()


def steps(platform, controller, n, h, scheme="gauss-seidel", commands=F, force_hook=None, measured=L + LDOT):
    """The package's one Python master loop: `n` communication steps of `h` of the platform and
    the controller (any objects with `values`, `set_values` and `slave`, as
    `stewart_fmu.core.Component`), coupled by `scheme`; yields the time after each step (`t +=
    h`, as the compiled master and FMPy's SSP master count it). `force_hook(t, commands)` may
    change the commands on their way to the platform (Gauss-Seidel). An FMU's failed step is
    raised from the loop (FMICallException) at the time of the last step yielded. `measured`: the
    platform's outputs the controller reads (the legs; with hydraulics the pressures too).
    Without a controller (None) the platform runs alone: `force_hook` changes the inputs it
    holds (`commands`), and the scheme does not matter."""
    time = 0.0
    connection_f, connection_measured = np.zeros(6), np.zeros(len(measured))
    for _ in range(n):
        if controller is None:
            if force_hook:
                # Only the inputs the hook changes are set: a set makes the outputs that follow
                # the inputs stale in the FMU's value cache.
                held = platform.values(commands)
                wanted = force_hook(time, held.copy())
                changed = [i for i in range(len(commands)) if not wanted[i] == held[i]]
                if changed:
                    platform.set_values([commands[i] for i in changed], [wanted[i] for i in changed])
            platform.slave.doStep(currentCommunicationPoint=time, communicationStepSize=h)
        elif scheme == "gauss-seidel":
            controller.set_values(measured, platform.values(measured))
            forces = controller.values(commands)
            if force_hook:
                forces = force_hook(time, forces)
            platform.set_values(commands, forces)
            platform.slave.doStep(currentCommunicationPoint=time, communicationStepSize=h)
            controller.slave.doStep(currentCommunicationPoint=time, communicationStepSize=h)
        else:
            # fmpy.ssp.simulation: platform first (the SSD's element order), then controller.
            platform.set_values(commands, connection_f)
            platform.slave.doStep(currentCommunicationPoint=time, communicationStepSize=h)
            out_measured = platform.values(measured)
            controller.set_values(measured, connection_measured)
            controller.slave.doStep(currentCommunicationPoint=time, communicationStepSize=h)
            out_f = controller.values(commands)
            connection_f, connection_measured = out_f, out_measured
        time += h
        yield time


def _checked(force_hook, commands):
    """`force_hook` with its six commands checked (ValueError naming the element)."""
    what = {id(F): "force_hook's forces", id(U): "force_hook's voltages"}.get(id(commands), "force_hook's valve commands")
    return lambda t, forces: vector_of(force_hook(t, forces), 6, what, lambda i: commands[i])


def _run(platform, controller, t_end, h, scheme, record, force_hook, commands=F, measured=L + LDOT):
    times, rows, errors, status = [], [], [], "ok"
    hook = _checked(force_hook, commands) if force_hook else None
    try:
        for time in steps(platform, controller, int(round(t_end / h)), h, scheme, commands, hook, measured):
            times.append(time)
            rows.append(platform.values(record))
            errors.append(np.max(np.abs(platform.values(L) - controller.values(LP))))
    except FMICallException as e:  # a discarded or failed step ends the run; a bug in Python is raised
        status = str(e)
    return np.array(times), np.array(rows), np.array(errors), status
