"""The basics the tests, the examples and users share: where the packaged FMUs are, the
default stand (docs/model.md §3) in SI or the paper's non-dimensional units, read from the
platform FMU's model description, and a thin driver around FMPy's FMU2Slave."""

import difflib
import functools
import math
import os
from pathlib import Path

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave, fmi2CallbackFunctions, fmi2CallbackLoggerTYPE

# Where the FMUs are. Used from its repository (python/stewart_fmu/, an editable install) the
# package takes them from the repository's build, target/fmu/; installed from a wheel it takes
# the copies the wheel carries (stewart_fmu/data/fmu/, python/build_wheels.py). The environment
# variables STEWART_PLATFORM_FMU and STEWART_CONTROLLER_FMU (and stewart-sweep's --fmu,
# --controller-fmu) point elsewhere.
PACKAGE = Path(__file__).resolve().parent
ROOT = PACKAGE.parents[1]  # the repository's root (meaningful only when the package is used from it)
IN_REPOSITORY = (ROOT / "Cargo.toml").is_file() and (ROOT / "python" / "stewart_fmu").is_dir()
DATA = PACKAGE / "data"  # in a wheel: fmu/ (as target/fmu/) and viewer/ (the built viewer page)
FMU_DIR = ROOT / "target" / "fmu" if IN_REPOSITORY else DATA / "fmu"
PLATFORM_FMU = Path(os.environ.get("STEWART_PLATFORM_FMU") or FMU_DIR / "StewartPlatform.fmu")
CONTROLLER_FMU = Path(os.environ.get("STEWART_CONTROLLER_FMU") or PLATFORM_FMU.parent / "StewartController.fmu")
CUEING_FMU = Path(os.environ.get("STEWART_CUEING_FMU") or PLATFORM_FMU.parent / "StewartCueing.fmu")


def fmu_file(path, option="--fmu"):
    """`path` as a string if the FMU is there; otherwise FileNotFoundError saying how to get
    it or point at it (`option`: stewart-sweep's option for this FMU)."""
    path = Path(path)
    if path.is_file():
        return str(path)
    if IN_REPOSITORY:
        where = "build the FMUs with `cargo run --release --bin build-fmu` (both set-up commands do), or point at them"
    elif path.parent == DATA / "fmu":
        where = ("this installation of stewart_fmu carries no FMUs (install a wheel `bash python/build_wheels.sh` "
                 "builds, which does), or point at them")
    else:
        where = "point at the FMUs"
    for variable in ("STEWART_PLATFORM_FMU", "STEWART_CONTROLLER_FMU", "STEWART_CUEING_FMU"):
        if os.environ.get(variable) and Path(os.environ[variable]) == path:
            where = f"the environment variable {variable} names it; correct it or " + where
    raise FileNotFoundError(f"{path.name} not found at {path}: {where}: set the environment variables "
                            f"STEWART_PLATFORM_FMU=/path/to/StewartPlatform.fmu (and STEWART_CONTROLLER_FMU; by "
                            f"default StewartController.fmu beside it), or give stewart-sweep {option} PATH")

# The legs' numbers in the FMUs' variable names (`l[1]` .. `l[6]`).
LEGS = range(1, 7)

# The paper's equilibrium leg force of the default stand's neutral pose, in units of M g (its
# section 5; the stand's neutral height is chosen so that each leg carries exactly this).
EQUILIBRIUM_FORCE = 0.2005
# The default stand's values the package names (PEP 562: read from the FMU on first use).
_STAND_CONSTANTS = {"MASS": lambda s: s["M"], "INERTIA": lambda s: s["J"], "GRAVITY": lambda s: s["g"],
                    "NEUTRAL_Z": lambda s: s["r0"][2]}


@functools.cache
def _stand_of(fmu):
    md = read_model_description(fmu_file(fmu))
    start = {v.name: float(v.start) for v in md.modelVariables if v.type == "Real" and v.start is not None}
    vector = lambda name, n: tuple(start[f"{name}[{i}]"] for i in range(1, n + 1))  # noqa: E731
    matrix = lambda name: tuple(tuple(start[f"{name}[{k},{i}]"] for i in (1, 2, 3)) for k in LEGS)  # noqa: E731
    return {"M": start["M"], "J": vector("J", 3), "g": start["g"], "r0": vector("r0", 3), "B": matrix("B"),
            "A": matrix("A")}


def default_stand(fmu=PLATFORM_FMU):
    """The default stand (docs/model.md §3), SI, as the platform FMU defines it: its model
    description's start values of `M`, `J`, `g`, the neutral pose `r0` and the joints `B`, `A`
    (rows by leg), as a dict of those names. The module's `MASS`, `INERTIA`, `GRAVITY` and
    `NEUTRAL_Z` are its values."""
    return _stand_of(str(fmu))


def __getattr__(name):
    if name in _STAND_CONSTANTS:
        return _STAND_CONSTANTS[name](default_stand())
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def equilibrium_force_si(fmu=PLATFORM_FMU):
    """The paper's equilibrium leg force of the default stand in newtons, `EQUILIBRIUM_FORCE M g`."""
    stand = default_stand(fmu)
    return EQUILIBRIUM_FORCE * stand["M"] * stand["g"]


def base_radius(stand):
    """The paper's unit of length R_b: the largest horizontal distance of a base joint from the
    `z` axis, each correctly rounded (`math.hypot`: the default stand's 1.5 m exactly)."""
    return max(math.hypot(b[0], b[1]) for b in stand["B"])


def stand_parameters(nondimensional=True, fmu=PLATFORM_FMU):
    """FMI parameter values of the default stand (`default_stand`), in the paper's units (R_b,
    M, M g, sqrt(R_b/g)) or in SI. The paper's experiments use its idealised legs: in
    non-dimensional units the end stops and the joint limits are off (`stops`, `joints`
    false)."""
    stand = default_stand(fmu)
    length = base_radius(stand) if nondimensional else 1.0
    mass = stand["M"] if nondimensional else 1.0
    p = {"M": stand["M"] / mass, "g": 1.0 if nondimensional else stand["g"]}
    for i, x in enumerate(stand["r0"]):
        p[f"r0[{i + 1}]"] = x / length
    for a, j in enumerate(stand["J"]):
        p[f"J[{a + 1}]"] = j / (mass * length * length)
    for k in range(6):
        for i in range(3):
            p[f"B[{k + 1},{i + 1}]"] = stand["B"][k][i] / length
        for i in range(3):
            p[f"A[{k + 1},{i + 1}]"] = stand["A"][k][i] / length
    if nondimensional:
        p["stops"] = False
        p["joints"] = False
    return p


def nearest(name, candidates):
    """'; did you mean X?' for the closest of `candidates` to a mistyped name, or ''."""
    match = difflib.get_close_matches(str(name), list(candidates), n=1, cutoff=0.6)
    return f"; did you mean {match[0]!r}?" if match else ""


def check_names(names, known, owner, what):
    """ValueError if `owner` (a model) has no variable of one of `names`; `what` names the
    argument they came in."""
    for name in names:
        if name not in known:
            raise ValueError(f"{what}: {owner} has no variable {name!r}{nearest(name, known)}")


def check_times(t_end, h, t_end_name="t_end", h_name="h"):
    """ValueError unless the end time and the communication step are positive and finite and
    the step fits in the end time (no run of zero steps that would look like a valid result)."""
    for name, value in ((t_end_name, t_end), (h_name, h)):
        if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
            raise ValueError(f"{name} = {value!r}: a number of seconds (or time units) is expected")
        if not (math.isfinite(value) and value > 0):
            raise ValueError(f"{name} = {value}: must be a positive, finite number of seconds (or time units)")
    if round(t_end / h) < 1:
        raise ValueError(f"{h_name} = {h} is longer than {t_end_name} = {t_end}: no step would run")


def set_values(slave, md, values, what="values"):
    """Sets parameters or inputs by name through the setter of each variable's type (Real,
    Integer, Boolean or String). A name the model does not have, or a value of the wrong kind, raises
    ValueError naming it (`what`: the argument the values came in)."""
    types = {v.name: (v.valueReference, v.type) for v in md.modelVariables}
    check_names(values, types, md.modelName, what)
    groups = {"Real": [], "Integer": [], "Boolean": [], "String": []}
    for name, value in values.items():
        vr, kind = types[name]
        kind = "Integer" if kind == "Enumeration" else kind
        if kind not in groups:
            raise ValueError(f"{what}: {name} is a {kind} variable, which cannot be set here")
        try:
            if kind == "String":
                if not isinstance(value, str):
                    raise ValueError
            elif isinstance(value, (str, bytes)):
                raise ValueError
            elif kind == "Real":
                value = float(value)
            elif kind == "Integer":
                if isinstance(value, (bool, np.bool_)) or float(value) != int(value):
                    raise ValueError
                value = int(value)
            elif isinstance(value, (bool, np.bool_)) or value in (0, 1):
                value = bool(value)
            else:
                raise ValueError
        except (TypeError, ValueError, OverflowError):
            expected = {"Real": "a number", "Integer": "an integer", "Boolean": "true or false", "String": "a text"}[kind]
            raise ValueError(f"{what}: {name} = {value!r}: {expected} is expected") from None
        groups[kind].append((vr, value))
    if groups["Real"]:
        slave.setReal([vr for vr, _ in groups["Real"]], [x for _, x in groups["Real"]])
    if groups["Integer"]:
        slave.setInteger([vr for vr, _ in groups["Integer"]], [x for _, x in groups["Integer"]])
    if groups["Boolean"]:
        slave.setBoolean([vr for vr, _ in groups["Boolean"]], [x for _, x in groups["Boolean"]])
    if groups["String"]:
        slave.setString([vr for vr, _ in groups["String"]], [x for _, x in groups["String"]])


def vector_of(values, n, what, names):
    """`values` as a float array of length `n`, or ValueError naming `what` and the element."""
    try:
        array = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{what}: {n} numbers ({names(0)} .. {names(n - 1)}) are expected, got {values!r}") from None
    if array.shape != (n,):
        raise ValueError(f"{what}: {n} values ({names(0)} .. {names(n - 1)}) are expected, got "
                         f"{array.size} (shape {array.shape})")
    for i, x in enumerate(array):
        if not math.isfinite(x):
            raise ValueError(f"{what}: {names(i)} = {x} is not a finite number")
    return array


def recording_callbacks(messages):
    """FMI 2 callbacks whose logger appends (status, category, message) to `messages`. The
    FMU passes each message pre-formatted with `%` doubled (see src/fmi2/logger.rs)."""
    def log(_env, _name, status, category, message):
        messages.append((status, (category or b"").decode(), (message or b"").decode().replace("%%", "%")))

    callbacks = fmi2CallbackFunctions()
    callbacks.logger = fmi2CallbackLoggerTYPE(log)
    callbacks._keep = log  # the ctypes callback must outlive the instance
    return callbacks


class NamedValues:
    """Reals of an FMU2Slave (`self.slave`) by variable name (`self.vr`), as arrays."""

    def values(self, names):
        return np.array(self.slave.getReal([self.vr[n] for n in names]))

    def set_values(self, names, values):
        self.slave.setReal([self.vr[n] for n in names], [float(v) for v in values])


class Component(NamedValues):
    """One FMU2Slave instance of a packaged FMU, initialised with its start values and ready to
    step: the one FMPy driver of the package (the closed loop's platform and controller,
    `Platform`, and a study's instances, which a worker keeps and `start`s again for each run).
    Reals by name: `get(names)` (an array), `set(names, values)`."""

    _extracted = {}

    def __init__(self, fmu, name, reals=None, integers=None, start_time=0.0, events=None, what=None, stop_time=None,
                 tolerance=None, logger=None, messages=None, start=True):
        """`reals`, `integers`: start values by name (booleans among them too); `events`: a list
        that receives the FMU's logEvents messages (contacts, singular arrangements passed) as
        (status, category, message); `messages`: a list that receives its other messages
        (warnings, discards, errors: `last_problem`) without switching logEvents on, emptied
        by each `start`; `what`: the names the arguments `reals` and `integers` came in, for
        messages; `start=False`: only instantiated, for `start`."""
        if events is not None and messages is not None:
            raise ValueError("Component: give events (logEvents on) or messages (off), not both")
        fmu = fmu_file(fmu)
        self.md = read_model_description(fmu)
        if fmu not in Component._extracted:
            Component._extracted[fmu] = extract(fmu)
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.slave = FMU2Slave(guid=self.md.guid, unzipDirectory=Component._extracted[fmu],
                               modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName=name)
        self.messages = events if events is not None else messages
        # The messages of a run: the component's own list starts empty with each run; a list of
        # events belongs to the caller, who may gather several instances' in one.
        self._messages_per_run = messages is not None
        if self.messages is not None:
            logger = recording_callbacks(self.messages)
        self.slave.instantiate(loggingOn=False, callbacks=logger)
        if events is not None:
            self.slave.setDebugLogging(True, ["logEvents"])
        self.fresh = True
        if start:
            try:
                self.start(reals, integers, start_time, stop_time, tolerance, what)
            except ValueError:
                self.slave.freeInstance()
                raise

    def start(self, reals=None, integers=None, start_time=0.0, stop_time=None, tolerance=None, what=None):
        """Initialises the instance with these start values, after a reset if it ran before."""
        if self._messages_per_run:
            self.messages.clear()  # a problem of an earlier run is not this run's
        if not self.fresh:
            self.slave.reset()
        self.fresh = False
        self.slave.setupExperiment(tolerance=tolerance, startTime=start_time, stopTime=stop_time)
        self.slave.enterInitializationMode()
        reals_name, integers_name = what or ("reals", "integers")
        set_values(self.slave, self.md, dict(reals or {}), reals_name)
        set_values(self.slave, self.md, dict(integers or {}), integers_name)
        self.slave.exitInitializationMode()
        self.time = start_time

    def last_problem(self):
        """The last discard or error message among those recorded (`messages`, `events`)."""
        return next((m for status, _, m in reversed(self.messages or []) if status >= 2), "")

    def get(self, names):
        """The Reals `names` (a list) as an array; ValueError for a name the FMU does not have."""
        check_names(names, self.vr, self.md.modelName, "get")
        return self.values(names)

    def set(self, names, values):
        """Sets the Reals `names` (a list) to `values`; ValueError for a name the FMU does not
        have."""
        check_names(names, self.vr, self.md.modelName, "set")
        self.set_values(names, values)

    def step(self, h):
        """One communication step of `h` seconds from the component's time."""
        if isinstance(h, bool) or not isinstance(h, (int, float, np.floating, np.integer)) or not (
                math.isfinite(h) and h > 0):
            raise ValueError(f"step: h = {h!r}: the communication step must be a positive, finite number of seconds")
        self.slave.doStep(currentCommunicationPoint=self.time, communicationStepSize=h)
        self.time += h

    def free(self):
        self.slave.terminate()
        self.slave.freeInstance()


class Platform(Component):
    """One instance of StewartPlatform, with the platform's own forms: `get("r[3]", ...)` (a
    list), `set({name: value})` (any type), `vector`, `set_forces`."""

    def __init__(self, fmu=PLATFORM_FMU, parameters=None, integers=None, start_time=0.0, stop_time=None,
                 tolerance=None, name="platform", logger=None, events=None):
        super().__init__(fmu, name, parameters, integers, start_time, events, ("parameters", "integers"), stop_time,
                         tolerance, logger)

    def get(self, *names):
        check_names(names, self.vr, self.md.modelName, "get")
        return self.slave.getReal([self.vr[n] for n in names])

    def set(self, values):
        """Sets variables by name; ValueError for a name the platform does not have."""
        set_values(self.slave, self.md, values, "set")

    def vector(self, base, n):
        return np.array(self.get(*[f"{base}[{i + 1}]" for i in range(n)]))

    def set_forces(self, forces, rates=None):
        """The six leg forces F[1] .. F[6] (and their time derivatives); ValueError unless six
        finite numbers each."""
        forces = vector_of(forces, 6, "set_forces: forces", lambda i: f"F[{i + 1}]")
        vrs = [self.vr[f"F[{k + 1}]"] for k in range(6)]
        if rates is not None:
            rates = vector_of(rates, 6, "set_forces: rates", lambda i: f"der(F[{i + 1}])")
        self.slave.setReal(vrs, [float(f) for f in forces])
        if rates is not None:
            self.slave.setRealInputDerivatives(vrs, [1] * 6, [float(r) for r in rates])


def open_loop(inputs_of_t, t_end, h, parameters=None, record=(), events=None, inputs="F", name="platform"):
    """The platform alone through FMPy: `inputs_of_t(t)` -> six values of `inputs` ("F", the
    leg forces, N; "U", the drives' voltages, V), set at each communication point and held over
    the step of `h` to `t_end`. Returns (columns: `time` and `record`, status: "ok" or the
    FMU's message of the step it discarded, where the run ends). `events`: a list that receives
    the logEvents messages (None: not delivered, nor the singular passages tracked). The
    open-loop runner of the scenarios that record outputs (workspace, machine, drives); a study's
    runs of the platform alone go through the master loop, `stewart_fmu.cosim.steps`."""
    check_times(t_end, h)
    record = list(record)
    pl = Platform(parameters=parameters, events=events, name=name)
    try:
        check_names(record, pl.vr, pl.md.modelName, "record")
        vrs = [pl.vr[f"{inputs}[{k}]"] for k in LEGS]
        times, rows, status = [pl.time], [pl.get(*record)], "ok"
        for i in range(int(round(t_end / h))):
            pl.slave.setReal(vrs, [float(x) for x in inputs_of_t(i * h)])
            pl.step(h)
            times.append(pl.time)
            rows.append(pl.get(*record))
    except FMICallException:
        status = next((text for s, _, text in reversed(events or []) if s >= 2), "the step was discarded")
    finally:
        pl.free()
    rows = np.array(rows)
    return {"time": np.array(times), **{n: rows[:, j] for j, n in enumerate(record)}}, status


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
