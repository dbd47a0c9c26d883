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
  `scenario.failed_leg`, `scenario.failure_time` (closed loop): that leg's force falls to 0;
  `scenario.pump_stop_at` (hydraulic legs fed by the power unit, `platform.drive = 2`,
  `platform.hydraulic.supply = 1`): the platform's `pump.speed` falls to 0.

A run is stable when it completes, every leg stays within the study's `stable_error` of its
programme (closed loop) and, with `stop_contact_unstable = true`, no leg touches an end stop.

A run's id is a hash of its parameter values, so a study can be resumed and a run is never
executed twice. Results do not depend on where a run executes: a worker process unpacks each
FMU once and reuses its instances with `fmi2Reset`, which restores them exactly.

Two masters run a study's points, with the same rows to the bit: the compiled one
(`stewart_fmu.master`, Rust; the default: the loop in compiled code at the FMUs' own speed,
many runs per call) and the FMPy one (`_execute` below, the reference: `--master fmpy`). In a
closed-loop study the coupling is `StewartSystem.ssp`'s (with `drive = 1` in both FMUs,
`StewartSystemDrives.ssp`'s voltages; with `drive = 2`, `StewartSystemHydraulic.ssp`'s valve
commands, the pressures measured), Gauss-Seidel.
"""

import hashlib
import io
import itertools
import json
import math
import os
import time
import tempfile
import tomllib
import zipfile
from pathlib import Path

import numpy as np
from fmpy import read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import fmi2Terminated

from . import cosim, study_params, study_schema
from .cosim import COMMANDS, F, L, LP, MEASURED
from .core import LEGS, Component, fmu_file, stand_parameters
from .ssp import couplings
from .study_schema import DEFAULT_MAX_RUNS, StudyError


MASTERS = ("compiled", "fmpy")
METRICS = ["max_leg_error", "max_pose_error", "stable", "discard_time", "min_kappa", "max_stop_force",
           "energy_residual", "peak_deceleration", "final_z", "min_supply_pressure", "landing_deceleration", "cue_error", "max_usage", "least_scale", "max_tilt",
           "perceived_error", "correlation", "false_cues", "fallbacks"]


def plan(path, max_runs=DEFAULT_MAX_RUNS, fmus=None):
    """The study file's Plan, checked against the schema (`stewart_fmu.study_schema`) and the
    FMUs (`fmus`: `study_params.fmu_paths()`, the package's by default) before anything runs;
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

_PROCESS = {}  # per worker process: components by role and FMU content hash
_FILES = {}  # per worker process: where each FMU is written (kept when a component is dropped)


def _component(role, fmu):
    """The worker process's instance of an FMU given as bytes or a path: instantiated once,
    started again for each run (`Component.start`), its messages kept for the run's row."""
    data = fmu if isinstance(fmu, bytes) else Path(fmu).read_bytes()
    key = (role, hashlib.sha256(data).hexdigest())
    if key not in _PROCESS:
        if key not in _FILES:
            path = Path(tempfile.mkdtemp(prefix=f"stewart-{role}-")) / f"{role}.fmu"
            path.write_bytes(data)
            _FILES[key] = path
        component = Component(_FILES[key], role, messages=[], start=False)
        component.variables = study_params.variables_of(component.md)
        _PROCESS[key] = component
    return _PROCESS[key]


def _drop_components():
    """After a run failed in an unforeseen way its instances may be in any state: free them, so
    the next run on this worker starts from new ones."""
    for key in list(_PROCESS):
        _safe(_PROCESS.pop(key).slave.freeInstance, None)


def fmus_for(spec, paths=None):
    """The FMUs a study needs, as bytes (they travel to the workers; no shared file system).
    `paths`: `study_params.fmu_paths()`, the package's FMUs by default."""
    paths = paths or study_params.fmu_paths()
    roles = study_params.ROLES[spec["study"]["system"]]
    options = {"platform": "--fmu", "controller": "--controller-fmu", "cueing": "--cueing-fmu"}
    fmus = {role: Path(fmu_file(paths[role], options[role])).read_bytes() for role in roles}
    if spec["study"]["system"] == "cueing":
        # The vehicle's motion travels with the FMUs (a worker may not see the study's files).
        fmus["manoeuvre"] = study_schema.manoeuvre_columns(spec["study"])
    if "controller" in fmus:
        try:
            fmus["couplings"] = couplings()  # the compiled master's: they travel with the FMUs
        except FileNotFoundError:
            pass  # no SSP files here: the FMPy master runs the study (sweep.choose_master says so)
    return fmus


FSTOP = [f"Fstop[{k}]" for k in LEGS]
# What the FMPy master reads from the platform after each step, in one call: the energy, its
# works and kappa, the position and the heave rate; the hydraulic supply's work (`work.pump`
# with the power unit, else `work.hydraulic`), the oil's compression, the supply's pressure
# (docs/model.md §10, §10b; all 0 for forces and drives but the pressure, pS), the drives'
# electric work (§9); then the end stops' forces and the legs' lengths. (The compiled master
# reads the same values in one call too, in its own order: PLATFORM_WATCHED in
# crates/stewart-master/src/study.rs.)
WATCHED = ["E", "work.F", "work.dissipated", "kappa", "r[1]", "r[2]", "r[3]", "v[3]", "work.hydraulic", "work.pump",
           "work.compression", "supply.pressure", "work.electric", *FSTOP, *L]
_SCALARS = len(WATCHED) - len(FSTOP) - len(L)  # where the end stops' forces begin
# The controller's, in the closed loop (one call; the compiled master's CONTROLLER_WATCHED).
CONTROLLER_WATCHED = [*LP, "rp[1]", "rp[2]", "rp[3]"]


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


def execute(spec, run, fmus, master="fmpy"):
    """Runs one point of the study with `master` ("compiled" or "fmpy"); returns its row
    (parameters are added by the caller): status "ok", "discard" or "error", the message, and
    the metrics. Never raises: a run that fails for any reason (a value the FMU refuses, a bad
    value that reached here without the study's check, a bug) is an error row with its
    message."""
    if master == "compiled":
        return execute_many(spec, [run], fmus)[0][0]
    row = {m: math.nan for m in METRICS}
    row.update(status="ok", message="")
    try:
        if spec["study"]["system"] == "cueing":
            _execute_cueing(spec, run, fmus, row)
        else:
            _execute(spec, run, fmus, row)
    except Exception as e:  # noqa: BLE001 - a failed run is data, never the study's crash
        _drop_components()
        row.update(status="error", message=f"{type(e).__name__}: {e}", stable=False)
    return row


def _drive(run):
    """The platform's `drive` (0 forces, 1 electric drives, 2 hydraulic servo legs)."""
    return int(run.get("platform.drive", 0))


def _commands(run, closed):
    """The platform's command inputs (F; U with electric drives; valve with hydraulic legs) and,
    if the run's values do not fit together, why it cannot run."""
    drives = [int(run.get(f"{role}.drive", 0)) for role in ("platform", "controller")]
    if closed and drives[0] != drives[1]:
        return F, (f"platform.drive = {drives[0]} but controller.drive = {drives[1]}: the controller's commands "
                   f"(F, U or valve) drive the platform only when both have the same drive")
    if drives[0] not in COMMANDS:
        return F, f"platform.drive = {drives[0]}: 0 (forces), 1 (electric drives) or 2 (hydraulic servo legs)"
    if run.get("scenario.pump_stop_at") is not None and (
            drives[0] != 2 or int(run.get("platform.hydraulic.supply", 0)) != 1):
        return F, ("scenario.pump_stop_at stops the power unit's pump: it needs platform.drive = 2 and "
                   "platform.hydraulic.supply = 1 in the study")
    return COMMANDS[drives[0]], None


def _scenario(run, closed, commands):
    """The run's scenario as platform inputs held at a value from a time on: (input, value,
    time)."""
    held = []
    if closed and run.get("scenario.failed_leg") is not None:
        leg = int(run["scenario.failed_leg"])
        held.append((commands[leg - 1], 0.0, float(run.get("scenario.failure_time", 0.0))))
    if not closed and run.get("scenario.power_loss_at") is not None:
        held += [(c, 0.0, float(run["scenario.power_loss_at"])) for c in commands]
    if run.get("scenario.pump_stop_at") is not None:
        held.append(("pump.speed", 0.0, float(run["scenario.pump_stop_at"])))
    return held


def _event(held):
    """The scenario's event, s: its earliest held input's time (infinite without one)."""
    return min((at for _, _, at in held), default=math.inf)


def _finish(study, row, closed, run):
    """The row's `stable` from its status and metrics (both masters); the supply's pressure is
    the hydraulic legs' alone."""
    if _drive(run) != 2:
        row["min_supply_pressure"] = math.nan
    threshold = float(study.get("stable_error", math.inf))
    touched = bool(study.get("stop_contact_unstable", False)) and row["max_stop_force"] > 0.0
    row["stable"] = bool(row["status"] == "ok" and (not closed or row["max_leg_error"] < threshold) and not touched)


# ----- the compiled master ----------------------------------------------------------------------

_COMPILED = {}  # per worker process: the compiled master's systems by study system and FMU hashes
_DESCRIPTIONS = {}  # per worker process: each FMU's model description and variables, by content hash


def _description(data):
    """(model description, variables) of an FMU given as bytes, read once per process."""
    key = hashlib.sha256(data).hexdigest()
    if key not in _DESCRIPTIONS:
        with zipfile.ZipFile(io.BytesIO(data)) as z:
            xml = z.read("modelDescription.xml")
        folder = tempfile.mkdtemp(prefix="stewart-md-")
        path = Path(folder) / "modelDescription.xml"
        path.write_bytes(xml)
        md = read_model_description(str(path))
        path.unlink()
        os.rmdir(folder)
        _DESCRIPTIONS[key] = (md, study_params.variables_of(md))
    return _DESCRIPTIONS[key]


def _compiled_system(fmus, closed, drive):
    from . import master  # here, not at the top: it loads the compiled master's library, which a study with
    # the FMPy master (and each of its workers) never needs
    platform, controller = fmus["platform"], fmus.get("controller")
    key = (closed, drive, hashlib.sha256(platform).hexdigest(), hashlib.sha256(controller or b"").hexdigest())
    if key not in _COMPILED:
        if closed:
            ssd = fmus.get("couplings", {}).get(drive) or couplings()[drive]
            _COMPILED[key] = master.System({"platform": platform, "controller": controller}, ssd)
        else:
            _COMPILED[key] = master.System({"platform": platform})
    return _COMPILED[key]


def _drop_compiled():
    for key in list(_COMPILED):
        _safe(_COMPILED.pop(key).close, None)


def compiled_point(spec, run, platform_md, variables):
    """A run as the compiled master's study point: (drive, (steps, step, values, overrides))
    with values and overrides by qualified name (`stewart_fmu._master.System.study`'s, and one
    line of `stewart-master study`), or (None, why it cannot run)."""
    study = spec["study"]
    closed = study["system"] == "closed-loop"
    problems = study_schema.check_run(spec, run, variables)
    commands, mismatch = _commands(run, closed)
    if problems or mismatch:
        return None, "; ".join(problems or [mismatch])
    h = float(run.get("step", study["step"]))
    n = int(round(float(run.get("stop_time", study["stop_time"])) / h))
    platform_values, controller_values = _parameters(spec, run, platform_md)
    values = ([(f"platform.{k}", v) for k, v in platform_values.items()]
              + [(f"controller.{k}", v) for k, v in controller_values.items()])
    overrides = [(f"platform.{name}", value, at) for name, value, at in _scenario(run, closed, commands)]
    return _drive(run), (n, h, values, overrides)


def execute_many(spec, runs, fmus):
    """Runs study points with the compiled master, in this process, in one call per coupling;
    returns [(row, seconds)] in the order of `runs`. Never raises: as `execute`."""
    study = spec["study"]
    closed = study["system"] == "closed-loop"
    out = [None] * len(runs)
    points = {}  # drive -> [(index, point)]
    prepared = [0.0] * len(runs)  # each run's share of the Python around the loop, s
    try:
        platform_md, platform_variables = _description(fmus["platform"])
        variables = {"platform": platform_variables,
                     "controller": _description(fmus["controller"])[1] if closed else {}}
    except Exception as e:  # noqa: BLE001 - an FMU that cannot be read: every run is an error row
        return [(failed_metrics(f"{type(e).__name__}: {e}"), 0.0) for _ in runs]
    for i, run in enumerate(runs):
        started = time.perf_counter()
        row = {m: math.nan for m in METRICS}
        row.update(status="ok", message="")
        try:
            drive, point = compiled_point(spec, run, platform_md, variables)
            if drive is None:
                row.update(status="error", message=point, stable=False)
                out[i] = (row, time.perf_counter() - started)
                continue
            points.setdefault(drive, []).append((i, point))
            out[i] = row
            prepared[i] = time.perf_counter() - started
        except Exception as e:  # noqa: BLE001 - a failed run is data
            out[i] = (failed_metrics(f"{type(e).__name__}: {e}"), time.perf_counter() - started)
    for drive, batch in points.items():
        try:
            results = _compiled_system(fmus, closed, drive).study(closed, [p for _, p in batch])
        except Exception as e:  # noqa: BLE001 - the system cannot be made or run: its runs are error rows
            _drop_compiled()
            results = [{"status": "error", "message": f"{type(e).__name__}: {e}", "seconds": 0.0} for _ in batch]
        for (i, _), result in zip(batch, results):
            row = out[i]
            seconds = result.pop("seconds")
            row.update(result)
            if row["status"] == "error" and row["message"].startswith("panic in the compiled master"):
                _drop_compiled()
            _finish(study, row, closed, runs[i])
            out[i] = (row, seconds + prepared[i])
    return out


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
    commands, mismatch = _commands(run, closed)
    if mismatch:
        row.update(status="error", message=mismatch, stable=False)
        return
    h = float(run.get("step", study["step"]))
    stop = float(run.get("stop_time", study["stop_time"]))
    if not _start(spec, run, platform, controller, row):
        return
    # The scenario: inputs held from a time on (a failed leg, a power loss, a pump stop).
    scenario = _scenario(run, closed, commands)
    n = int(round(stop / h))
    t = start = 0.0
    e0, line0 = platform.values(["E", "supply.linePressure"])
    powered = line0 != 0.0  # the power unit: its line's pressure is a state, 0 without it
    event = _event(scenario)
    leg_error = pose_error = stop_force = residual = deceleration = 0.0
    kappa_min = supply_min = math.inf
    landing = -math.inf
    v_prev = None
    values = None
    try:
        for t in _steps(platform, controller if closed else None, n, h, commands, scenario, _drive(run)):
            values = platform.values(WATCHED)
            (energy, work, dissipated, kappa, x, y, z, vz, hydraulic, pump, compression, supply,
             electric) = values[:_SCALARS]
            stops, legs = values[_SCALARS:_SCALARS + len(FSTOP)], values[_SCALARS + len(FSTOP):]
            # As the compiled master sums it (crates/stewart-master/src/study.rs).
            work = work + ((electric + (pump if powered else hydraulic)) - compression)
            residual = max(residual, abs(energy - e0 - (work - dissipated)))
            kappa_min = min(kappa_min, kappa)
            supply_min = min(supply_min, supply)
            stop_force = max(stop_force, float(np.max(np.abs(stops))))
            if v_prev is not None:
                deceleration = max(deceleration, (vz - v_prev) / h)
                if start >= event:
                    landing = max(landing, (vz - v_prev) / h)
            start = t
            v_prev = vz
            if closed:
                c = controller.values(CONTROLLER_WATCHED)
                lp, rp = c[:len(LP)], c[len(LP):]
                leg_error = max(leg_error, float(np.max(np.abs(legs - lp))))
                # |r - r^p| written out, so that both masters sum the squares in one order.
                dx, dy, dz = (float(r - rp[i]) for i, r in enumerate((x, y, z)))
                pose_error = max(pose_error, math.sqrt(dx * dx + dy * dy + dz * dz))
    except FMICallException as e:
        terminated = _safe(lambda: platform.slave.getBooleanStatus(fmi2Terminated), True)
        problem = platform.last_problem() or (controller.last_problem() if controller else "") or str(e)
        row.update(status="discard" if e.status == 2 else "error", discard_time=t,
                   message=problem + ("" if terminated else " (recoverable with shorter steps)"))
    row.update(max_stop_force=stop_force, energy_residual=residual, min_kappa=kappa_min if kappa_min < math.inf else math.nan,
               peak_deceleration=deceleration, final_z=float(z) if values is not None else math.nan,
               min_supply_pressure=supply_min if supply_min < math.inf else math.nan,
               landing_deceleration=landing if landing > -math.inf else math.nan)
    if closed:
        row.update(max_leg_error=leg_error, max_pose_error=pose_error)
    _finish(study, row, closed, run)


def _start(spec, run, platform, controller, row):
    """Starts the run's components with its parameters; False (the row an error) if one
    refuses them."""
    try:
        platform_values, controller_values = _parameters(spec, run, platform.md)
        platform.start(platform_values, what=("values", "values"))
        if controller is not None:
            controller.start(controller_values, what=("values", "values"))
    except FMICallException as e:
        problems = [c.last_problem() for c in (platform, controller) if c is not None and c.last_problem()]
        row.update(status="error", message=problems[-1] if problems else str(e), stable=False)
        return False
    return True


def _execute_cueing(spec, run, fmus, row):
    """One run of a cueing study: the cueing FMU alone on the study's manoeuvre (interpolated to
    the communication points, held over each step). Metrics: `cue_error`, the root mean square
    of |f - fsim| (m/s2: the cue the driver misses); `max_usage`, the washout's largest
    workspace usage (1: a leg at its margin); `least_scale`, the limiter's least share of the
    washout's command; `max_tilt`, the largest |roll| or |pitch| commanded (rad); SPEC 12's
    perception measures (`stewart_fmu.cueing.measures`): `perceived_error` (rms of the
    horizontal perceived specific-force error, m/s2), `correlation`, `false_cues`; and
    `fallbacks`, the predictive method's failed solves."""
    from . import cueing, vehicle
    study = spec["study"]
    cue = _component("cueing", fmus["cueing"])
    problems = study_schema.check_run(spec, run, {"cueing": cue.variables})
    if problems:
        row.update(status="error", message="; ".join(problems), stable=False)
        return
    h = float(run.get("step", study["step"]))
    stop = float(run.get("stop_time", study["stop_time"]))
    manoeuvre = fmus["manoeuvre"]
    try:
        cue.start({k.partition(".")[2]: v for k, v in run.items() if k.startswith("cueing.")}, what=("values", "values"))
    except FMICallException as e:
        row.update(status="error", message=cue.last_problem() or str(e), stable=False)
        return
    inputs = cueing.F + cueing.OMEGA
    outputs = cueing.FSIM + ["workspace.usage", "workspace.scale", "pose.angles[1]", "pose.angles[2]"]
    perceived = cueing.PERCEIVED + cueing.PERCEIVED_SIM
    felt = []
    squares, count, usage, scale, tilt, t = 0.0, 0, 0.0, 1.0, 0.0, 0.0
    try:
        for i in range(int(round(stop / h)) + 1):
            f, w = vehicle.at(manoeuvre, t)
            cue.set_values(inputs, np.concatenate([f, w]))
            o = cue.values(outputs)
            squares += float(np.sum((o[:3] - f) ** 2))
            count += 1
            usage, scale = max(usage, float(o[3])), min(scale, float(o[4]))
            tilt = max(tilt, abs(float(o[5])), abs(float(o[6])))
            felt.append(cue.values(perceived))
            if i < round(stop / h):
                cue.slave.doStep(currentCommunicationPoint=t, communicationStepSize=h)
                t += h
    except FMICallException as e:
        row.update(status="discard" if e.status == 2 else "error", discard_time=t, message=cue.last_problem() or str(e))
    row.update(cue_error=math.sqrt(squares / max(count, 1)), max_usage=usage, least_scale=scale, max_tilt=tilt)
    if felt:
        felt = np.array(felt)
        m = cueing.measures({n: felt[:, j] for j, n in enumerate(perceived)})
        row.update(perceived_error=m["perceived_error"], correlation=m["correlation"], false_cues=m["false_cues"])
    row["fallbacks"] = int(cue.slave.getInteger([cue.vr["mpc.fallbacks"]])[0])
    row["stable"] = row["status"] == "ok"


def _steps(platform, controller, n, h, commands, held, drive):
    """A run's communication steps through the package's one master loop
    (`stewart_fmu.cosim.steps`: Gauss-Seidel, or the platform alone without a controller),
    yielding the time after each; `held`: the platform's inputs (name, value, from time) held
    from a time on, a command on its way to the platform, another input (no connection drives
    it: `pump.speed`) set before each step from then on, as the compiled master sets them."""
    on_the_way = [(commands.index(name), value, at) for name, value, at in held if name in commands]
    free = [(name, value, at) for name, value, at in held if name not in commands]

    def hold(t, forces):
        for k, value, at in on_the_way:
            if t >= at:
                forces[k] = value
        for name, value, at in free:
            if t >= at:
                platform.set_values([name], [value])
        return forces
    yield from cosim.steps(platform, controller, n, h, "gauss-seidel", commands, hold if held else None,
                           MEASURED[drive])


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
