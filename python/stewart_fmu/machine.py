"""The machine (docs/model.md §8: legs as bodies, joint limits, cylinder friction) through the
packaged FMUs, SI units, default stand. Shared by the tests (tests/python/test_machine.py)
and the main job's demonstration (examples/machine_scenarios.py).

1. heavy legs: the default closed loop drives the heave programme with 40 kg cylinders and
   15 kg rods in both FMUs, against the same programme with the paper's massless legs;
2. ripple: open-loop forces 5900.715 (1 + 0.05 sin(2t + k)) N on leg k tip the platform
   over; the joint limits stop the tilt and it rests on them (without them, the platform
   joints pass through the base plane and the step is discarded);
3. friction: a small heave (5 mm) in the closed loop with cylinder friction, against the same
   without friction.
"""

import math
import re

import numpy as np

from .core import LEGS, equilibrium_force_si, open_loop
from .cosim import closed_loop

# An electric actuator of a 3-tonne simulator: 40 kg cylinder, 15 kg rod; transverse inertias
# of a 1 m barrel (m L^2 / 12 = 3.3 kg m2; 2.5 with the mass towards the joint) and a rod.
HEAVY = {"leg.cylinderMass": 40.0, "leg.rodMass": 15.0, "leg.cylinderInertia": 2.5, "leg.rodInertia": 0.6}
# A hydraulic cylinder's seals: 300 N Coulomb, 450 N breakaway (docs/model.md §8's law).
FRICTION = {"friction.coulomb": 300.0, "friction.static": 450.0, "friction.viscous": 2000.0}
JOINT_ANGLES = [f"thetaB[{k}]" for k in LEGS] + [f"thetaA[{k}]" for k in LEGS]
JOINT_FORCES = [f"jointForce[{k},{i}]" for k in LEGS for i in (1, 2, 3)]
_JOINT_EVENT = re.compile(r"t = ([-+0-9.eE]+): the (base|platform) joint of leg (\d) (reached|left)")


def ripple(t):
    """The tipping forces: 5900.715 (1 + 0.05 sin(2t + k)) N on leg k."""
    force = equilibrium_force_si()
    return [force * (1.0 + 0.05 * math.sin(2.0 * t + k)) for k in LEGS]


def joint_events(messages):
    """(t, 'base' or 'platform', leg, 'reached' or 'left') of each joint-limit message of the
    FMU's logEvents."""
    return [(float(m.group(1)), m.group(2), int(m.group(3)), m.group(4)) for _, _, text in messages
            if (m := _JOINT_EVENT.match(text))]


def tilt(columns):
    """The body axis e3's angle from the vertical, rad: acos(R[3,3])."""
    return np.arccos(np.clip(np.asarray(columns["R[3,3]"]), -1.0, 1.0))


def ripple_run(t_end=10.0, h=0.01, joints=True, parameters=None, record=()):
    """The open-loop ripple through FMPy: returns a dict of columns (`time` and `record`
    plus r, R, angles, the joint angles, Fstop and the energy terms), `events` (the joint-limit
    messages, `joint_events`) and `status` ("ok" or the FMU's message of a discarded step)."""
    names = list(dict.fromkeys(["r[1]", "r[2]", "r[3]"] + [f"R[{a},{b}]" for a in (1, 2, 3) for b in (1, 2, 3)]
                                + ["angles[1]", "angles[2]", "angles[3]"] + [f"l[{k}]" for k in LEGS]
                                + [f"F[{k}]" for k in LEGS] + [f"Fstop[{k}]" for k in LEGS] + JOINT_ANGLES
                                + ["E", "work.F", "work.dissipated"] + list(record)))
    messages = []
    columns, status = open_loop(ripple, t_end, h, {"joints": joints, **(parameters or {})}, names, messages,
                                name="ripple")
    return columns, joint_events(messages), status


def heave_with_legs(legs=None, t_end=10.0, h=1e-3, friction=None, controller_reals=None, record=()):
    """The default closed loop on the heave programme with the given `leg.*` parameters in
    both FMUs and `friction.*` in the platform: returns (columns, largest leg error per step,
    status); columns hold `time`, r[3], the forces F, the joint forces and angles."""
    legs, friction = dict(legs or {}), dict(friction or {})
    names = list(dict.fromkeys(["r[3]"] + [f"F[{k}]" for k in LEGS] + [f"l[{k}]" for k in LEGS] + JOINT_FORCES
                                + JOINT_ANGLES + ["E", "work.F", "work.dissipated"] + list(record)))
    t, rows, errors, status = closed_loop(t_end, h, platform_reals={**legs, **friction},
                                          controller_reals={**legs, **(controller_reals or {})}, record=names)
    columns = {"time": t, **{n: rows[:, j] for j, n in enumerate(names)}}
    return columns, errors, status

