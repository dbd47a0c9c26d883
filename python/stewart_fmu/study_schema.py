"""The study file's schema, checked before anything runs (docs/studies.md describes it for users).

`check(spec, path)` refuses a study with every problem it finds, each naming the key at fault
and saying what to change: unknown sections and keys (with the nearest known name), types,
ranges, units of time, variable names against the FMUs' own model descriptions, the plots'
parameters and files, the number of steps a run takes and the number of runs. It returns the
`Plan` (`stewart-sweep --check` prints it). The count of runs is computed without expanding
them, so a 10^7-run grid is refused at once instead of filling the memory.

`check_run(spec, run, variables)` applies the same value checks to one run where it executes,
so a run that reaches a worker without `check` (the API) is an error row, never a crash.
"""

import math
from dataclasses import dataclass, field
from pathlib import Path, PurePosixPath

from .core import nearest
from .study_params import (SYSTEMS, UNITS, Param, StudyError, check_value, describe, fmu_paths, fmu_variables,
                           number, quoted)

# Each run is a Python loop of about 50 us a communication step (two FMUs); 10^7 steps is
# about 10 min of one worker: beyond that a run is almost surely a unit mistake (ms for s).
MAX_STEPS_PER_RUN = 10_000_000

# The default of `stewart-sweep --max-runs`, sized for a 2-core, 24 GiB machine: the shipped
# studies run at 5 .. 40 runs/s there (their summaries; docs/studies.md), so 10^5 runs take 1 .. 6 hours, and
# their run list (about 0.4 kB a run: 380 MB measured for 10^6) and rows stay far below the
# memory. 10^7 runs would take weeks (the red-team run's 10^7 grid took 5.6 GB before a run).
DEFAULT_MAX_RUNS = 100_000

SECTIONS = ("study", "fixed", "grid", "random", "plot")
STUDY_KEYS = {
    "name": "the study's name (default: the file's name)",
    "description": "free text",
    "system": "'platform' (the platform alone, open-loop forces), 'closed-loop' (platform + controller) or "
              "'cueing' (the motion cueing FMU alone on a vehicle's manoeuvre)",
    "manoeuvre": "system = 'cueing': the vehicle's motion, a manoeuvre of stewart_fmu.vehicle (accelerate, brake, "
                 "lane_change, curve, bumps, slalom, emergency_stop, lane_change_05g, pothole) or a CSV file of its columns "
                 "(time, f[1..3], omega[1..3]; relative to the study file)",
    "units": "'si' or 'nondimensional' (the paper's units: R_b, M, sqrt(R_b/g))",
    "stop_time": "the end of each run (s, or time units)",
    "step": "the communication step (s, or time units)",
    "stable_error": "largest leg tracking error of a stable run (m, or R_b)",
    "stop_contact_unstable": "true: a run that touches an end stop is not stable",
}
REQUIRED_STUDY_KEYS = ("stop_time", "step")
# Metrics a plot can show (`stable` is a yes/no, shown by the map's blanks instead).
PLOT_VALUES = ("max_leg_error", "max_pose_error", "discard_time", "min_kappa", "max_stop_force", "energy_residual",
               "peak_deceleration", "final_z", "min_supply_pressure", "landing_deceleration", "wall_time", "cue_error",
               "max_usage", "least_scale", "max_tilt", "perceived_error", "correlation", "false_cues", "fallbacks")
PLOT_KEYS = {
    "map": ("kind", "value", "x", "y", "facet", "log", "file", "title", "unstable_blank"),
    "scatter": ("kind", "value", "x", "file", "title"),
    "histogram": ("kind", "value", "bins", "file", "title"),
}
PLOT_FORMATS = (".png", ".pdf", ".svg")
RESERVED_FILES = ("results.parquet", "summary.txt", "study.toml")


def check_run(spec, run, variables):
    """Messages for the values of one run (empty if it can run)."""
    study = spec.get("study", {})
    system, units = study.get("system", "closed-loop"), study.get("units", "si")
    problems = []
    for key in ("step", "stop_time"):
        if key not in run:
            problem = check_value(describe(key, system, units, variables), study.get(key), f"study.{key}")
            problems += [problem] if problem else []
    for name, value in run.items():
        param = describe(name, system, units, variables)
        if isinstance(param, str):
            problems.append(param)
        elif (problem := check_value(param, value, name)) is not None:
            problems.append(problem)
    if not problems:
        steps, h, stop = _steps(run.get("step", study.get("step")), run.get("stop_time", study.get("stop_time")))
        if steps is not None and not 1 <= steps <= MAX_STEPS_PER_RUN:
            problems.append(_steps_problem(steps, h, stop, units))
    return problems


def _steps(h, stop):
    if all(isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x) and x > 0 for x in (h, stop)):
        return int(round(stop / h)), h, stop
    return None, h, stop


def _steps_problem(steps, h, stop, units):
    unit = "s" if units == "si" else "time units"
    if steps < 1:
        return (f"step {number(h)} {unit} with stop_time {number(stop)} {unit} gives no step: "
                f"the step must be shorter than the stop time")
    return (f"stop_time {number(stop)} {unit} at a step of {number(h)} {unit} is {number(float(steps))} steps a run, "
            f"more than {number(float(MAX_STEPS_PER_RUN))} (about 10 min of a worker): check the units of time "
            f"({unit}) or split the study")


# ----- the whole file ---------------------------------------------------------------------------

@dataclass
class Plan:
    """What a valid study will run."""
    spec: dict
    path: str
    runs: int
    grid: dict = field(default_factory=dict)  # name -> values
    samples: int = 0
    max_runs: int = DEFAULT_MAX_RUNS
    steps: tuple = (0, 0)  # fewest and most steps of a run

    def text(self):
        study = self.spec["study"]
        unit = "s" if study["units"] == "si" else "time units"
        lines = [f"study {study['name']} ({study['system']}, {study['units']} units) from {self.path}"]
        if study.get("description"):
            lines.append(f"  {study['description']}")
        lines.append(f"  time: stop_time {number(study['stop_time'])} {unit}, step {number(study['step'])} {unit} "
                     f"(varied runs: {self.steps[0]} .. {self.steps[1]} steps a run)")
        for name, value in sorted(self.spec.get("fixed", {}).items()):
            lines.append(f"  fixed  {name} = {number(value)}")
        for name, values in sorted(self.grid.items()):
            shown = ", ".join(number(v) for v in values[:8]) + (", ..." if len(values) > 8 else "")
            lines.append(f"  grid   {name}: {len(values)} values ({shown})")
        random = self.spec.get("random", {})
        for name, dist in sorted((n, d) for n, d in random.items() if n not in ("samples", "seed")):
            (kind, (a, b)), = dist.items()
            lines.append(f"  random {name}: {kind} [{number(a)}, {number(b)}]")
        if self.samples:
            lines.append(f"  random: {self.samples} samples, seed {random.get('seed', 0)}")
        factors = [f"{len(v)} {n}" for n, v in sorted(self.grid.items())] + (
            [f"{self.samples} samples"] if self.samples else [])
        lines.append(f"  runs: {' x '.join(factors) + ' = ' if len(factors) > 1 else ''}{self.runs} "
                     f"(--max-runs {self.max_runs})")
        for i, p in enumerate(self.spec.get("plot", [])):
            kind = p.get("kind", "histogram")
            over = {"map": f" over {p.get('x')} x {p.get('y')}" + (f", a panel per {p['facet']}" if p.get("facet")
                                                                      else ""),
                    "scatter": f" against {p.get('x')}", "histogram": ""}[kind]
            lines.append(f"  plot {i + 1}: {kind} of {p.get('value', 'max_leg_error')}{over} -> "
                         f"{p.get('file', f'plot{i + 1}.png')}")
        return "\n".join(lines)


def check(spec, path="", max_runs=DEFAULT_MAX_RUNS, variables=None, fmus=None):
    """The Plan of a study file's dict (defaults filled in); raises StudyError with every problem.
    `variables`: the FMUs' variable tables (`fmu_variables`), or read from `fmus` (`fmu_paths`)."""
    problems = _check_sections(spec, path)
    plots = spec.get("plot", [])
    study = spec.setdefault("study", {})
    study.setdefault("name", PurePosixPath(str(path)).stem or "study")
    study.setdefault("system", "closed-loop")
    study.setdefault("units", "si")
    system, units = study["system"], study["units"]
    problems += _check_study(study)
    if system == "cueing":
        problems += _check_cueing(study, path)
    if variables is None:
        variables = fmu_variables(fmus)
    if system == "cueing" and "cueing" not in variables:
        problems.append(f"system = 'cueing' needs StewartCueing.fmu: {(fmus or fmu_paths())['cueing']} is missing "
                        f"(build the FMUs with `cargo run --release --bin build-fmu`, or set STEWART_CUEING_FMU)")

    fixed, grid, random = spec.get("fixed", {}), spec.get("grid", {}), dict(spec.get("random", {}))
    samples, seed = random.pop("samples", None), random.pop("seed", 0)
    seen = _check_tables(fixed, grid, random, system, units, variables, problems)
    samples = _check_sampling(random, samples, seed, problems)
    if "scenario.failure_time" in seen and "scenario.failed_leg" not in seen:
        problems.append("scenario.failure_time is set but scenario.failed_leg is not: name the leg that fails")
    if "scenario.pump_stop_at" in seen:
        # Where the study fixes them (else each run says so in its row).
        drive, supply = fixed.get("platform.drive", 0), fixed.get("platform.hydraulic.supply", 0)
        varied = {n for n in ("platform.drive", "platform.hydraulic.supply") if n in grid or n in random}
        if not varied and (drive != 2 or supply != 1):
            problems.append("scenario.pump_stop_at stops the power unit's pump: it needs platform.drive = 2 and "
                            "platform.hydraulic.supply = 1 in [fixed]")

    steps = _check_steps(study, fixed, grid, random, units, problems)
    count = math.prod(len(v) for v in grid.values() if isinstance(v, list)) * (samples or 1)
    if count > max_runs:
        factors = " x ".join([f"{len(v)} {n}" for n, v in sorted(grid.items()) if isinstance(v, list)]
                             + ([f"{samples} samples"] if samples else []))
        problems.append(f"the study has {number(count)} runs ({factors}), more than --max-runs {number(max_runs)}: "
                        f"make the grid coarser or take fewer samples, or raise --max-runs for a bigger cluster")
    problems += _check_plots(plots, grid, random)
    if problems:
        raise StudyError(path, problems)
    return Plan(spec, str(path), count, {n: list(v) for n, v in grid.items()}, samples or 0, max_runs, steps)


def _check_sections(spec, path):
    """The problems of the file's sections; raises StudyError where their contents cannot be
    read (a section that is not a table, plots that are not an array of tables)."""
    problems, structure = [], []
    if not isinstance(spec, dict):
        raise StudyError(path, ["the study file must be a TOML table"])
    for key, value in spec.items():
        if key not in SECTIONS:
            if key in STUDY_KEYS:
                problems.append(f"{key!r} is a key of the [study] section: move it below [study]")
            else:
                problems.append(f"unknown section [{key}] (known: {', '.join(SECTIONS)}){nearest(key, SECTIONS)}")
    for key in ("study", "fixed", "grid", "random"):
        if not isinstance(spec.get(key, {}), dict):
            structure.append(f"[{key}] must be a table (a [{key}] header with key = value lines)")
    plots = spec.get("plot", [])
    if isinstance(plots, dict):
        structure.append("plots are an array of tables: write [[plot]], not [plot]")
    elif not isinstance(plots, list) or not all(isinstance(p, dict) for p in plots):
        structure.append("plots are an array of tables: write each as a [[plot]] section")
    if structure:
        raise StudyError(path, problems + structure)
    return problems


def _check_tables(fixed, grid, random, system, units, variables, problems):
    """Each parameter of [fixed], [grid] and [random] (its name, value, values or distribution)
    into `problems`; returns the section each name is set in."""
    seen = {}
    for section, table in (("fixed", fixed), ("grid", grid), ("random", random)):
        for name, value in table.items():
            where = f"{section}.{quoted(name)}"
            if name in seen:
                problems.append(f"{name} is set in both [{seen[name]}] and [{section}]: keep one")
                continue
            seen[name] = section
            if name in ("platform", "controller", "scenario") and isinstance(value, dict):
                inner = next(iter(value), "name")
                problems.append(f"{where}: quote dotted names, \"{name}.{inner}\" = ... (without the quotes TOML "
                                f"reads a nested table)")
                continue
            param = describe(name, system, units, variables)
            if isinstance(param, str):
                problems.append(f"[{section}] {param}")
                continue
            if section == "fixed":
                problems += filter(None, [check_value(param, value, where)])
            elif section == "grid":
                problems += _check_grid(param, value, where)
            else:
                problems += _check_distribution(name, param, value, where)
    return seen


def _check_sampling(random, samples, seed, problems):
    """[random]'s samples and seed into `problems`; returns the samples (None if not valid)."""
    if random and samples is None:
        problems.append("[random] has distributions but no samples: add samples = N (N >= 1)")
    if samples is not None:
        if isinstance(samples, bool) or not isinstance(samples, int) or samples < 1:
            problems.append(f"random.samples = {number(samples)}: a whole number of at least 1 is expected")
            samples = None
        elif not random:
            problems.append(f"random.samples = {samples} but [random] has no distributions: every sample would be "
                            f"the same run; add one or remove samples")
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        problems.append(f"random.seed = {number(seed)}: a whole number >= 0 is expected")
    return samples


def _check_study(study):
    problems = []
    for key, value in study.items():
        if key not in STUDY_KEYS:
            problems.append(f"study.{key}: unknown key{nearest(key, STUDY_KEYS)} (known: {', '.join(STUDY_KEYS)})")
        elif key in ("name", "description") and not isinstance(value, str):
            problems.append(f"study.{key} = {number(value)}: text in quotes is expected")
        elif key == "system" and value not in SYSTEMS:
            problems.append(f"study.system = {number(value)}: 'platform', 'closed-loop' or 'cueing'"
                            f"{nearest(value, SYSTEMS)}")
        elif key == "manoeuvre" and study.get("system") != "cueing":
            problems.append("study.manoeuvre applies to system = 'cueing' studies")
        elif key == "units" and value not in UNITS:
            problems.append(f"study.units = {number(value)}: 'si' or 'nondimensional'{nearest(value, UNITS)}")
        elif key == "stop_contact_unstable" and not isinstance(value, bool):
            problems.append(f"study.stop_contact_unstable = {number(value)}: write true or false")
        elif key == "stable_error":
            problems += filter(None, [check_value(Param("real", 0.0, lo_open=True, what="stable error"), value,
                                                  "study.stable_error")])
    unit = "s" if study.get("units") == "si" else "time units"
    for key in REQUIRED_STUDY_KEYS:
        if key not in study:
            problems.append(f"study.{key} is missing: {STUDY_KEYS[key]}")
        else:
            what = "communication step" if key == "step" else "end of the run"
            problems += filter(None, [check_value(Param("time", 0.0, lo_open=True, unit=unit, what=what), study[key],
                                                  f"study.{key}")])
    return problems


def manoeuvre_columns(study, path=""):
    """The columns of a cueing study's manoeuvre (a name of `stewart_fmu.vehicle` or a CSV file,
    relative to the study file), or ValueError saying why not."""
    from . import vehicle
    name = study.get("manoeuvre")
    known = {**vehicle.MANOEUVRES, **vehicle.HARSH}
    if not isinstance(name, str):
        raise ValueError(f"study.manoeuvre is missing: {STUDY_KEYS['manoeuvre']}")
    if name in known:
        return known[name]()
    file = Path(path).parent / name if path else Path(name)
    if file.suffix.lower() != ".csv":
        raise ValueError(f"study.manoeuvre = {name!r}: one of {', '.join(known)}{nearest(name, known)}, or a .csv file")
    if not file.is_file():
        raise ValueError(f"study.manoeuvre = {name!r}: no such file {file}")
    return vehicle.read_csv(file)


def _check_cueing(study, path):
    problems = []
    if study.get("units") != "si":
        problems.append("a system = 'cueing' study runs in SI units: remove study.units or write 'si'")
    try:
        manoeuvre_columns(study, path)
    except ValueError as e:
        problems.append(str(e))
        return problems
    name = study["manoeuvre"]
    if name.lower().endswith(".csv") and path:
        # Where the workers' runs read it from, whatever their directory.
        study["manoeuvre"] = str((Path(path).parent / name).resolve())
    return problems


def _check_grid(param, values, where):
    if not isinstance(values, list) or not values:
        return [f"{where} = {number(values)}: a non-empty list of values is expected, [a, b, ...]"]
    problems = [p for i, v in enumerate(values) if (p := check_value(param, v, f"{where}[{i}]")) is not None]
    if not problems:
        repeated = sorted({number(v) for i, v in enumerate(values) if v in values[:i]})
        if repeated:
            problems.append(f"{where} lists {', '.join(repeated)} more than once: each run would be the same")
    return problems


def _check_distribution(name, param, dist, where):
    if not (isinstance(dist, dict) and len(dist) == 1 and next(iter(dist)) in ("uniform", "normal")):
        return [f"{where} = {number(dist)}: write {{ uniform = [low, high] }} or {{ normal = [mean, sd] }}"
                + (nearest(next(iter(dist)), ("uniform", "normal")) if isinstance(dist, dict) and len(dist) == 1
                   else "")]
    (kind, pair), = dist.items()
    where = f"{where}.{kind}"
    if param.kind != "real" and param.kind != "time":
        return [f"{where}: {name} takes {'true/false' if param.kind == 'bool' else 'integers'}: "
                f"vary it in [grid] instead"]
    if (not isinstance(pair, list) or len(pair) != 2
            or not all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in pair)):
        return [f"{where} = {number(pair)}: two numbers are expected, "
                + ("[low, high]" if kind == "uniform" else "[mean, sd]")]
    a, b = pair
    if not (math.isfinite(a) and math.isfinite(b)):
        return [f"{where} = [{number(a)}, {number(b)}]: finite numbers are expected"]
    if kind == "uniform":
        if a > b:
            return [f"{where} = [{number(a)}, {number(b)}]: low is above high"]
        return [p for p, x in ((check_value(param, a, f"{where} low"), a), (check_value(param, b, f"{where} high"), b))
                if p is not None]
    if b < 0:
        return [f"{where} = [{number(a)}, {number(b)}]: the standard deviation must be >= 0"]
    if param.lo is not None or param.hi is not None:
        return [f"{where}: a normal draw can leave the range of {name}: use uniform = [low, high]"]
    return []


def _time_values(key, study, fixed, grid, random):
    """The values (or uniform bounds) a time key takes over the study."""
    if key in grid and isinstance(grid[key], list):
        return grid[key]
    if key in random and isinstance(random[key], dict) and "uniform" in random[key]:
        return random[key]["uniform"]
    return [fixed.get(key, study.get(key))]


def _check_steps(study, fixed, grid, random, units, problems):
    hs = _time_values("step", study, fixed, grid, random)
    stops = _time_values("stop_time", study, fixed, grid, random)
    valid = [x for x in hs + stops if isinstance(x, (int, float)) and not isinstance(x, bool)
             and math.isfinite(x) and x > 0]
    if len(valid) != len(hs) + len(stops):
        return (0, 0)  # a bad value, already reported
    fewest, h_max, stop_min = _steps(max(hs), min(stops))
    most, h_min, stop_max = _steps(min(hs), max(stops))
    if fewest < 1:
        problems.append(_steps_problem(fewest, h_max, stop_min, units))
    if most > MAX_STEPS_PER_RUN:
        problems.append(_steps_problem(most, h_min, stop_max, units))
    return (fewest, most)


def _check_plots(plots, grid, random):
    problems, files = [], {}
    for i, p in enumerate(plots):
        where = f"plot {i + 1}"
        kind = p.get("kind", "histogram")
        if not isinstance(kind, str) or kind not in PLOT_KEYS:
            problems.append(f"{where}: kind = {number(kind)}: 'map', 'scatter' or 'histogram'{nearest(kind, PLOT_KEYS)}")
            continue
        where = f"plot {i + 1} ({kind})"
        allowed = PLOT_KEYS[kind]
        for key in p:
            if key not in allowed:
                other = [k for k, keys in PLOT_KEYS.items() if key in keys]
                problems.append(f"{where}: {key!r} is not a key of a {kind} plot"
                                + (f" (it is of {' and '.join(other)} plots)" if other else nearest(key, allowed)))
        value = p.get("value", "max_leg_error")
        if not isinstance(value, str) or value not in PLOT_VALUES:
            problems.append(f"{where}: value = {number(value)} is not a metric{nearest(value, PLOT_VALUES)} "
                            f"(metrics: {', '.join(PLOT_VALUES)})")
        problems += _check_plot_axes(p, where, kind, grid, random)
        if kind == "map" and p.get("x") is not None and p.get("x") in (p.get("y"), p.get("facet")):
            problems.append(f"{where}: x, y and facet must name different parameters")
        for key in ("log", "unstable_blank"):
            if key in p and not isinstance(p[key], bool):
                problems.append(f"{where}: {key} = {number(p[key])}: write true or false")
        if "title" in p and not isinstance(p["title"], str):
            problems.append(f"{where}: title = {number(p['title'])}: text in quotes is expected")
        if "bins" in p and (isinstance(p["bins"], bool) or not isinstance(p["bins"], int)
                            or not 1 <= p["bins"] <= 10_000):
            problems.append(f"{where}: bins = {number(p['bins'])}: a whole number from 1 to 10000 is expected")
        file = p.get("file", f"plot{i + 1}.png")
        problem = plot_file_problem(file)
        if problem:
            problems.append(f"{where}: {problem}")
        elif file in files:
            problems.append(f"{where}: file {file!r} is also plot {files[file] + 1}'s: give each plot its own file")
        else:
            files[file] = i
    return problems


def _check_plot_axes(p, where, kind, grid, random):
    """A plot's x, y and facet: each names a parameter that its kind can show."""
    problems, varied = [], set(grid) | set(random)
    for axis in ("x", "y", "facet"):
        if axis not in PLOT_KEYS[kind]:
            continue
        name = p.get(axis)
        if name is not None and not isinstance(name, str):
            problems.append(f"{where}: {axis} = {number(name)}: the name of a varied parameter in quotes is expected")
            continue
        if name is None:
            if axis != "facet":
                problems.append(f"{where}: {axis} is missing: name a varied parameter "
                                f"({', '.join(sorted(varied)) or 'none varies'})")
            continue
        if kind == "map" and name not in grid:
            if name in random:
                problems.append(f"{where}: {axis} = {name!r} is drawn at random, and a map needs [grid] values: "
                                f"use a scatter plot")
            else:
                problems.append(f"{where}: {axis} = {number(name)} is not varied in [grid]"
                                f"{nearest(name, grid)} (grid: {', '.join(sorted(grid)) or 'empty'})")
        elif name not in varied:
            problems.append(f"{where}: {axis} = {number(name)} is not a varied parameter{nearest(name, varied)} "
                            f"(varied: {', '.join(sorted(varied)) or 'none'})")
    return problems


def plot_file_problem(file):
    """Why a plot's file is not a file inside --out, or None."""
    if not isinstance(file, str) or not file.strip():
        return f"file = {number(file)}: a file name in quotes is expected, e.g. \"map.png\""
    parts = PurePosixPath(file.replace("\\", "/")).parts
    if file.startswith(("/", "\\", "~")) or (len(file) > 1 and file[1] == ":") or ".." in parts or "\0" in file:
        return f"file = {file!r}: plots are written inside --out only: give a name relative to it, without '..'"
    if PurePosixPath(file).suffix.lower() not in PLOT_FORMATS:
        return f"file = {file!r}: the name must end in {', '.join(PLOT_FORMATS)}"
    if parts[0] in RESERVED_FILES:
        return f"file = {file!r}: {parts[0]} is the study's own output: choose another name"
    return None
