"""The basics the tests, the examples and users share: where the packaged FMUs are, the
default stand (docs/model.md §3) in SI or the paper's non-dimensional units, computed here
independently of the Rust code, the paper's heave programme and its direct problem, and a thin
driver around FMPy's FMU2Slave."""

import math
import os
from pathlib import Path

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave, fmi2CallbackFunctions, fmi2CallbackLoggerTYPE

# The repository this package lives in (python/stewart_fmu/): the FMUs are built into its
# target/fmu/; STEWART_PLATFORM_FMU points elsewhere.
ROOT = Path(__file__).resolve().parents[2]
PLATFORM_FMU = Path(os.environ.get("STEWART_PLATFORM_FMU", ROOT / "target" / "fmu" / "StewartPlatform.fmu"))
CONTROLLER_FMU = PLATFORM_FMU.parent / "StewartController.fmu"

# docs/model.md §3: the truck-cabin stand.
R_B, R_P, H_C = 1.5, 1.0, 0.5
BASE_AZIMUTHS = [-10, 10, 110, 130, 230, 250]
PLATFORM_AZIMUTHS = [-50, 50, 70, 170, 190, 290]
MASS, INERTIA, GRAVITY = 3000.0, (1500.0, 1500.0, 2200.0), 9.81
NEUTRAL_Z = 1.9589244164161732
EQUILIBRIUM_FORCE = 0.2005  # units of M g


def stand_parameters(nondimensional=True):
    """FMI parameter values of the default stand, in the paper's units (R_b, M, M g,
    sqrt(R_b/g)) or in SI. The paper's experiments use its idealised legs: in
    non-dimensional units the end stops and the joint limits are off (`stops`, `joints`
    false)."""
    length = R_B if nondimensional else 1.0
    mass = MASS if nondimensional else 1.0
    p = {
        "M": MASS / mass,
        "g": 1.0 if nondimensional else GRAVITY,
        "r0[1]": 0.0,
        "r0[2]": 0.0,
        "r0[3]": NEUTRAL_Z / length,
    }
    for a, j in enumerate(INERTIA):
        p[f"J[{a + 1}]"] = j / (mass * length * length)
    for k in range(6):
        pb, pp = math.radians(BASE_AZIMUTHS[k]), math.radians(PLATFORM_AZIMUTHS[k])
        for i, x in enumerate((R_B * math.cos(pb), R_B * math.sin(pb), 0.0)):
            p[f"B[{k + 1},{i + 1}]"] = x / length
        for i, x in enumerate((R_P * math.cos(pp), R_P * math.sin(pp), -H_C)):
            p[f"A[{k + 1},{i + 1}]"] = x / length
    if nondimensional:
        p["stops"] = False
        p["joints"] = False
    return p


def set_values(slave, md, values):
    """Sets parameters or inputs by name through the setter of each variable's type (Real,
    Integer or Boolean); names the model does not have are skipped."""
    types = {v.name: (v.valueReference, v.type) for v in md.modelVariables}
    groups = {"Real": [], "Integer": [], "Boolean": []}
    for name, value in values.items():
        if name in types:
            vr, kind = types[name]
            groups["Integer" if kind == "Enumeration" else kind].append((vr, value))
    if groups["Real"]:
        slave.setReal([vr for vr, _ in groups["Real"]], [float(x) for _, x in groups["Real"]])
    if groups["Integer"]:
        slave.setInteger([vr for vr, _ in groups["Integer"]], [int(x) for _, x in groups["Integer"]])
    if groups["Boolean"]:
        slave.setBoolean([vr for vr, _ in groups["Boolean"]], [bool(x) for _, x in groups["Boolean"]])


def neutral_leg_geometry(nondimensional=True):
    """Horizontal leg projection d and platform joint plane height H0 of the neutral pose."""
    length = R_B if nondimensional else 1.0
    pb, pp = math.radians(BASE_AZIMUTHS[0]), math.radians(PLATFORM_AZIMUTHS[0])
    dx = R_P * math.cos(pp) - R_B * math.cos(pb)
    dy = R_P * math.sin(pp) - R_B * math.sin(pb)
    return math.hypot(dx, dy) / length, (NEUTRAL_Z - H_C) / length


def heave_programme(t, z0, a=0.2, omega=1.0, tc=2.0):
    """The paper's heave law (5.1) z = z0 + a sin(omega t)(1 - exp(-t/tc))^2 with its first
    and second derivatives (written out independently of the Rust code)."""
    e = math.exp(-t / tc)
    g, g1, g2 = (1 - e) ** 2, 2 * (e - e * e) / tc, 2 * (2 * e * e - e) / tc**2
    s, c = math.sin(omega * t), math.cos(omega * t)
    return (z0 + a * s * g, a * (omega * c * g + s * g1), a * (-omega * omega * s * g + 2 * omega * c * g1 + s * g2))


def heave_forces(t, z0=NEUTRAL_Z / R_B):
    """Direct problem for the pure heave of the symmetric default stand (non-dimensional):
    the six leg forces are equal, u = (z'' + g) / (6 n_z), n_z = H / l. Returns (u, du/dt, l, ldot)."""
    d, _ = neutral_leg_geometry()
    joint_offset = H_C / R_B

    def at(tt):
        z, zd, zdd = heave_programme(tt, z0)
        h = z - joint_offset
        l = math.hypot(d, h)
        return (zdd + 1.0) / (6.0 * h / l), l, h * zd / l

    u, l, ldot = at(t)
    eps = 1e-6
    du = (at(t + eps)[0] - at(t - eps)[0]) / (2 * eps)
    return u, du, l, ldot


def recording_callbacks(messages):
    """FMI 2 callbacks whose logger appends (status, category, message) to `messages`. The
    FMU passes each message pre-formatted with `%` doubled (see src/fmi2/logger.rs)."""
    def log(_env, _name, status, category, message):
        messages.append((status, (category or b"").decode(), (message or b"").decode().replace("%%", "%")))

    callbacks = fmi2CallbackFunctions()
    callbacks.logger = fmi2CallbackLoggerTYPE(log)
    callbacks._keep = log  # the ctypes callback must outlive the instance
    return callbacks


class Platform:
    """One FMU2Slave instance of StewartPlatform with name-based access."""

    _extracted = {}

    def __init__(self, fmu=PLATFORM_FMU, parameters=None, integers=None, start_time=0.0, stop_time=None,
                 tolerance=None, name="platform", logger=None, events=None):
        """`events`: a list that receives the FMU's logEvents messages (contacts, singular
        arrangements passed) as (status, category, message)."""
        fmu = str(fmu)
        self.md = read_model_description(fmu)
        if fmu not in Platform._extracted:
            Platform._extracted[fmu] = extract(fmu)
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.slave = FMU2Slave(guid=self.md.guid, unzipDirectory=Platform._extracted[fmu],
                               modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName=name)
        if events is not None:
            logger = recording_callbacks(events)
        self.slave.instantiate(loggingOn=False, callbacks=logger)
        if events is not None:
            self.slave.setDebugLogging(True, ["logEvents"])
        self.slave.setupExperiment(tolerance=tolerance, startTime=start_time, stopTime=stop_time)
        self.slave.enterInitializationMode()
        if parameters:
            self.set(parameters)
        if integers:
            names = list(integers)
            self.slave.setInteger([self.vr[n] for n in names], [int(integers[n]) for n in names])
        self.slave.exitInitializationMode()
        self.time = start_time

    def set(self, values):
        unknown = [n for n in values if n not in self.vr]
        assert not unknown, f"the platform has no variables {unknown}"
        set_values(self.slave, self.md, values)

    def set_forces(self, forces, rates=None):
        self.slave.setReal([self.vr[f"F[{k + 1}]"] for k in range(6)], [float(f) for f in forces])
        if rates is not None:
            self.slave.setRealInputDerivatives([self.vr[f"F[{k + 1}]"] for k in range(6)], [1] * 6,
                                               [float(r) for r in rates])

    def get(self, *names):
        return self.slave.getReal([self.vr[n] for n in names])

    def vector(self, base, n):
        return np.array(self.get(*[f"{base}[{i + 1}]" for i in range(n)]))

    def step(self, h):
        self.slave.doStep(currentCommunicationPoint=self.time, communicationStepSize=h)
        self.time += h

    def free(self):
        self.slave.terminate()
        self.slave.freeInstance()


def bisect_boundary(holds_at, lo, hi, tolerance):
    """The boundary between `lo`, where `holds_at` is true, and `hi`, where it is false,
    to within `tolerance`; returns (lo, hi) bracketing it. Checks both ends first."""
    assert holds_at(lo) and not holds_at(hi), f"no change of {holds_at.__name__} between {lo} and {hi}"
    while hi - lo > tolerance:
        mid = 0.5 * (lo + hi)
        if holds_at(mid):
            lo = mid
        else:
            hi = mid
    return lo, hi
