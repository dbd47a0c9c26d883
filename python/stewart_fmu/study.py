"""Design studies: a study file (TOML) names the system, the fixed and varied parameters, the
scenario and the plots; this module expands it into runs and executes one run, returning one
row of metrics. `stewart_fmu.sweep` distributes the runs on Dask.

A run is a dict of parameter values keyed by name:

- `platform.<variable>` and `controller.<variable>`: FMU parameters by their FMI 2 names
  (`platform.M`, `controller.G`, `platform.r0[3]`);
- `platform.com_offset[i]` (m or R_b): the centre of mass moved by that much in the body frame
  (the platform joints `A` move by minus it, `r0` by plus it, so the legs start unchanged);
- `step`, `stop_time`: the communication step and the end of the run;
- `scenario.power_loss_at` (platform alone): the leg forces fall to 0 at that time;
  `scenario.failed_leg`, `scenario.failure_time` (closed loop): that leg's force falls to 0.

A run is stable when it completes, every leg stays within the study's `stable_error` of its
programme (closed loop) and, with `stop_contact_unstable = true`, no leg touches an end stop.

A run's id is a hash of its parameter values, so a study can be resumed and a run is never
executed twice. Results do not depend on where a run executes: a worker process unpacks each
FMU once and reuses its instances with `fmi2Reset`, which restores them exactly.
"""

import hashlib
import itertools
import json
import math
import os
import tempfile
import tomllib
import zipfile
from pathlib import Path

import numpy as np
from fmpy import read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave, fmi2Terminated

from . import study_schema
from .core import fmu_file, recording_callbacks, set_values, stand_parameters
from .study_schema import DEFAULT_MAX_RUNS, StudyError


METRICS = ["max_leg_error", "max_pose_error", "stable", "discard_time", "min_kappa", "max_stop_force",
           "energy_residual", "peak_deceleration", "final_z"]


def plan(path, max_runs=DEFAULT_MAX_RUNS, fmus=None):
    """The study file's Plan, checked against the schema (`stewart_fmu.study_schema`) and the
    FMUs (`fmus`: `study_schema.fmu_paths()`, the package's by default) before anything runs;
    raises StudyError naming every problem."""
    path = Path(path)
    try:
        spec = tomllib.loads(path.read_text())
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as e:
        raise StudyError(path, [f"cannot read the study file: {e}"]) from e
    return study_schema.check(spec, path, max_runs, fmus=fmus)


def load(path, max_runs=DEFAULT_MAX_RUNS):
    """The study file as a dict, checked (defaults filled in)."""
    return plan(path, max_runs).spec


def runs(spec):
    """Every run of the study, in a fixed order: the grid's product, times the random samples
    (drawn in a fixed order from the study's seed)."""
    grid = spec.get("grid", {})
    names = sorted(grid)
    grid_points = [dict(zip(names, values)) for values in itertools.product(*(grid[n] for n in names))] or [{}]
    random = dict(spec.get("random", {}))
    samples = int(random.pop("samples", 0))
    seed = int(random.pop("seed", 0))
    if samples:
        rng = np.random.default_rng(seed)
        draws = {}
        for name in sorted(random):
            (kind, (a, b)), = random[name].items()
            draws[name] = rng.uniform(a, b, samples) if kind == "uniform" else rng.normal(a, b, samples)
        sample_points = [{n: float(draws[n][i]) for n in sorted(draws)} for i in range(samples)]
    else:
        sample_points = [{}]
    fixed = spec.get("fixed", {})
    return [dict(fixed, **g, **s) for g in grid_points for s in sample_points]


def run_id(run):
    """A short, stable id of a run's parameter values."""
    text = json.dumps({k: run[k] for k in sorted(run)}, sort_keys=True, default=repr)
    return hashlib.sha1(text.encode()).hexdigest()[:16]


# ----- execution -------------------------------------------------------------------------------

class _Component:
    """One FMU2Slave kept for the life of the worker process, reset between runs."""

    def __init__(self, unzipped, md, name):
        self.md = md
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self.variables = study_schema.variables_of(md)
        self.fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzipped, modelIdentifier=md.coSimulation.modelIdentifier,
                             instanceName=name)
        # The FMU's messages are kept, not printed: a failed run's row carries its message.
        self.messages = []
        self.fmu.instantiate(callbacks=recording_callbacks(self.messages))
        self.fresh = True

    def last_problem(self):
        """The last discard or error message of the current run."""
        return next((m for status, _, m in reversed(self.messages) if status >= 2), "")

    def start(self, values):
        self.messages.clear()
        if not self.fresh:
            self.fmu.reset()
        self.fresh = False
        self.fmu.setupExperiment(startTime=0.0)
        self.fmu.enterInitializationMode()
        set_values(self.fmu, self.md, values)
        self.fmu.exitInitializationMode()

    def get(self, names):
        return np.array(self.fmu.getReal([self.vr[n] for n in names]))

    def set(self, names, values):
        self.fmu.setReal([self.vr[n] for n in names], [float(v) for v in values])


_PROCESS = {}  # per worker process: components by role and FMU content hash
_FOLDERS = {}  # per worker process: where each FMU is unpacked (kept when a component is dropped)


def _component(role, fmu):
    """The worker process's instance of an FMU given as bytes or a path."""
    data = fmu if isinstance(fmu, bytes) else Path(fmu).read_bytes()
    key = (role, hashlib.sha256(data).hexdigest())
    if key not in _PROCESS:
        if key not in _FOLDERS:
            folder = tempfile.mkdtemp(prefix=f"stewart-{role}-")
            path = Path(folder) / f"{role}.fmu"
            path.write_bytes(data)
            with zipfile.ZipFile(path) as z:
                z.extractall(folder)
            _FOLDERS[key] = (folder, read_model_description(str(path)))
        folder, md = _FOLDERS[key]
        _PROCESS[key] = _Component(folder, md, role)
    return _PROCESS[key]


def _drop_components():
    """After a run failed in an unforeseen way its instances may be in any state: free them, so
    the next run on this worker starts from new ones."""
    for key in list(_PROCESS):
        _safe(_PROCESS.pop(key).fmu.freeInstance, None)


def fmus_for(spec, paths=None):
    """The FMUs a study needs, as bytes (they travel to the workers; no shared file system).
    `paths`: `study_schema.fmu_paths()`, the package's FMUs by default."""
    paths = paths or study_schema.fmu_paths()
    roles = ("platform", "controller") if spec["study"]["system"] == "closed-loop" else ("platform",)
    return {role: Path(fmu_file(paths[role], "--fmu" if role == "platform" else "--controller-fmu")).read_bytes()
            for role in roles}


LEGS = range(1, 7)
L = [f"l[{k}]" for k in LEGS]
LDOT = [f"ldot[{k}]" for k in LEGS]
F = [f"F[{k}]" for k in LEGS]
LP = [f"lp[{k}]" for k in LEGS]
FSTOP = [f"Fstop[{k}]" for k in LEGS]
ENERGY = ["E", "work.F", "work.dissipated", "kappa", "r[1]", "r[2]", "r[3]", "v[3]"]


def _parameters(spec, run, platform_md):
    """The values for each FMU from the study's units and the run (`platform_md`: the platform's
    model description, for the start values the centre-of-mass offset moves)."""
    study = spec["study"]
    platform, controller = {}, {}
    if study["units"] == "nondimensional":
        stand = stand_parameters(nondimensional=True)
        platform.update(stand)
        controller.update({k: v for k, v in stand.items() if k in ("M", "g") or k[0] in "JAB"})
    offset = [0.0, 0.0, 0.0]
    for name, value in run.items():
        role, _, variable = name.partition(".")
        if role == "platform" and variable.startswith("com_offset["):
            offset[int(variable[11]) - 1] = float(value)
        elif role == "platform":
            platform[variable] = value
        elif role == "controller":
            controller[variable] = value
    if any(offset):
        md_start = _start_values(platform_md)
        for k in LEGS:
            for i in range(3):
                name = f"A[{k},{i + 1}]"
                platform[name] = float(platform.get(name, md_start[name])) - offset[i]
        for i in range(3):
            name = f"r0[{i + 1}]"
            platform[name] = float(platform.get(name, md_start[name])) + offset[i]
    return platform, controller


def _start_values(md):
    """The Real start values of a model description (the worker's own copy of the FMU's: on a
    remote worker the client's files are not there)."""
    return {v.name: float(v.start) for v in md.modelVariables if v.start is not None and v.type == "Real"}


def failed_metrics(message):
    """The row of a run that could not run: status "error", its message, no metrics."""
    row = {m: math.nan for m in METRICS}
    row.update(status="error", message=message, stable=False)
    return row


def execute(spec, run, fmus):
    """Runs one point of the study; returns its row (parameters are added by the caller):
    status "ok", "discard" or "error", the message, and the metrics. Never raises: a run that
    fails for any reason (a value the FMU refuses, a bad value that reached here without the
    study's check, a bug) is an error row with its message."""
    row = {m: math.nan for m in METRICS}
    row.update(status="ok", message="")
    try:
        _execute(spec, run, fmus, row)
    except Exception as e:  # noqa: BLE001 - a failed run is data, never the study's crash
        _drop_components()
        row.update(status="error", message=f"{type(e).__name__}: {e}", stable=False)
    return row


def _execute(spec, run, fmus, row):
    study = spec["study"]
    closed = study["system"] == "closed-loop"
    platform = _component("platform", fmus["platform"])
    controller = _component("controller", fmus["controller"]) if closed else None
    # The schema's value checks again, here where the run executes: the FMUs' variables are
    # the workers' own, and a run given through the API has not been checked.
    problems = study_schema.check_run(spec, run, {"platform": platform.variables,
                                                  "controller": controller.variables if closed else {}})
    if problems:
        row.update(status="error", message="; ".join(problems), stable=False)
        return
    h = float(run.get("step", study["step"]))
    stop = float(run.get("stop_time", study["stop_time"]))
    try:
        platform_values, controller_values = _parameters(spec, run, platform.md)
        platform.start(platform_values)
        if closed:
            controller.start(controller_values)
    except FMICallException as e:
        problems = [c.last_problem() for c in (platform, controller) if c is not None and c.last_problem()]
        row.update(status="error", message=problems[-1] if problems else str(e), stable=False)
        return
    power_loss = run.get("scenario.power_loss_at")
    failed_leg = run.get("scenario.failed_leg")
    failure_time = float(run.get("scenario.failure_time", 0.0))
    n = int(round(stop / h))
    t = 0.0
    e0 = platform.get(["E"])[0]
    leg_error = pose_error = stop_force = residual = deceleration = 0.0
    kappa_min = math.inf
    v_prev = None
    values = None
    try:
        for i in range(n):
            if closed:
                legs = platform.get(L + LDOT)
                controller.set(L + LDOT, legs)
                forces = controller.get(F)
                if failed_leg is not None and t >= failure_time:
                    forces[int(failed_leg) - 1] = 0.0
                platform.set(F, forces)
            elif power_loss is not None and t >= float(power_loss):
                platform.set(F, np.zeros(6))
            platform.fmu.doStep(currentCommunicationPoint=t, communicationStepSize=h)
            if closed:
                controller.fmu.doStep(currentCommunicationPoint=t, communicationStepSize=h)
            t = (i + 1) * h
            values = platform.get(ENERGY)
            energy, work, dissipated, kappa, z, vz = values[0], values[1], values[2], values[3], values[6], values[7]
            residual = max(residual, abs(energy - e0 - (work - dissipated)))
            kappa_min = min(kappa_min, kappa)
            stop_force = max(stop_force, float(np.max(np.abs(platform.get(FSTOP)))))
            if v_prev is not None:
                deceleration = max(deceleration, (vz - v_prev) / h)
            v_prev = vz
            if closed:
                leg_error = max(leg_error, float(np.max(np.abs(platform.get(L) - controller.get(LP)))))
                rp = controller.get(["rp[1]", "rp[2]", "rp[3]"])
                pose_error = max(pose_error, float(np.linalg.norm(values[4:7] - rp)))
    except FMICallException as e:
        terminated = _safe(lambda: platform.fmu.getBooleanStatus(fmi2Terminated), True)
        problem = platform.last_problem() or (controller.last_problem() if controller else "") or str(e)
        row.update(status="discard" if e.status == 2 else "error", discard_time=t,
                   message=problem + ("" if terminated else " (recoverable with shorter steps)"))
    row.update(max_stop_force=stop_force, energy_residual=residual, min_kappa=kappa_min if kappa_min < math.inf else math.nan,
               peak_deceleration=deceleration, final_z=float(values[6]) if values is not None else math.nan)
    if closed:
        row.update(max_leg_error=leg_error, max_pose_error=pose_error)
    threshold = float(study.get("stable_error", math.inf))
    touched = bool(study.get("stop_contact_unstable", False)) and stop_force > 0.0
    row["stable"] = bool(row["status"] == "ok" and (not closed or leg_error < threshold) and not touched)


def _safe(f, default):
    try:
        return f()
    except Exception:  # noqa: BLE001 - only for a diagnostic after a failed step
        return default


def worker_name():
    """Where a run executed: the Dask worker's address, or this process."""
    try:
        from distributed import get_worker
        return get_worker().address
    except (ImportError, ValueError):
        return f"pid {os.getpid()}"
