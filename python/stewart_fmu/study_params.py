"""A study's run parameters: the FMUs' variables (read from their model descriptions) and what
each run parameter accepts, its name checked against the study's system and its values against
the variable's type and range (`describe`, `check_value`). The study file's schema
(`stewart_fmu.study_schema`) and the runs where they execute (`stewart_fmu.study`) check with
these; the messages name the key at fault and say what to write.
"""

import math
from dataclasses import dataclass
from pathlib import Path

from .core import CONTROLLER_FMU, CUEING_FMU, PLATFORM_FMU, fmu_file, nearest

SYSTEMS = ("platform", "closed-loop", "cueing")
#: The FMUs of each system, by role.
ROLES = {"platform": ("platform",), "closed-loop": ("platform", "controller"), "cueing": ("cueing",)}
MODELS = {"platform": "StewartPlatform", "controller": "StewartController", "cueing": "StewartCueing"}
UNITS = ("si", "nondimensional")


class StudyError(ValueError):
    """A study file that cannot be run: `problems` lists every reason, each naming its key."""

    def __init__(self, path, problems):
        self.path, self.problems = str(path), list(problems)
        head = f"{self.path}: " if self.path else ""
        if len(self.problems) == 1:
            super().__init__(head + self.problems[0])
        else:
            super().__init__(f"{head}{len(self.problems)} problems:\n" + "\n".join(f"  - {p}" for p in self.problems))


def number(x):
    """A number as the messages print it: scientific notation when large or small."""
    if isinstance(x, bool) or not isinstance(x, (int, float)):
        text = repr(x)
        return text if len(text) <= 60 else text[:57] + "..."
    if isinstance(x, float) and not math.isfinite(x):
        return str(x)
    if x != 0 and (abs(x) >= 1e5 or abs(x) < 1e-4):
        return f"{x:.3e}"
    return repr(x)


def quoted(name):
    """A key as it is written in TOML."""
    return name if name.replace("_", "").isalnum() else f'"{name}"'


# ----- the FMUs' variables -----------------------------------------------------------------------

@dataclass(frozen=True)
class Variable:
    type: str  # Real, Integer, Boolean (Enumeration as Integer)
    causality: str
    min: float = None
    max: float = None
    unit: str = None
    description: str = ""


def variables_of(md):
    """The variables of one model description by name."""
    table = {}
    for v in md.modelVariables:
        kind = "Integer" if v.type == "Enumeration" else v.type
        lo = float(v.min) if v.min not in (None, "") else None
        hi = float(v.max) if v.max not in (None, "") else None
        table[v.name] = Variable(kind, v.causality, lo, hi, v.unit if v.unit else None, v.description or "")
    return table


_FMU_VARIABLES = {}


def fmu_paths(platform=None, controller=None, cueing=None):
    """{'platform': path, 'controller': path, 'cueing': path}: the given FMUs, or the package's
    defaults (`stewart_fmu.core`: the repository's build, the wheel's copies, or the
    environment's STEWART_PLATFORM_FMU, STEWART_CONTROLLER_FMU and STEWART_CUEING_FMU). A
    platform given without the others takes the StewartController.fmu and StewartCueing.fmu
    beside it."""
    platform = Path(platform) if platform else PLATFORM_FMU
    beside = platform != PLATFORM_FMU
    controller = Path(controller) if controller else (
        platform.parent / "StewartController.fmu" if beside else CONTROLLER_FMU)
    cueing = Path(cueing) if cueing else (platform.parent / "StewartCueing.fmu" if beside else CUEING_FMU)
    return {"platform": platform, "controller": controller, "cueing": cueing}


def fmu_variables(paths=None):
    """{'platform': ..., 'controller': ...} from the FMUs' model descriptions (`fmu_paths()`
    by default; cached while the files are unchanged)."""
    from fmpy import read_model_description
    tables = {}
    for role, path in (paths or fmu_paths()).items():
        try:
            key = (str(path), path.stat().st_mtime_ns)
        except OSError:
            if role == "cueing":
                continue  # only a cueing study needs it (its check says so)
            option = "--fmu" if role == "platform" else "--controller-fmu"
            try:
                fmu_file(path, option)
            except FileNotFoundError as e:
                raise StudyError("", [str(e)]) from None
            raise
        if key not in _FMU_VARIABLES:
            _FMU_VARIABLES[key] = variables_of(read_model_description(str(path)))
        tables[role] = _FMU_VARIABLES[key]
    return tables


# ----- run parameters --------------------------------------------------------------------------

@dataclass
class Param:
    """What a run parameter accepts: kind 'real', 'int', 'bool' or 'time' (a real >= `lo`)."""
    kind: str
    lo: float = None
    hi: float = None
    lo_open: bool = False  # lo itself refused (a step of 0)
    unit: str = None
    what: str = ""


def describe(name, system, units, variables):
    """The Param of a run parameter name, or a message saying why the name is not one."""
    time_unit = "s" if units == "si" else "time units"
    if name in ("step", "stop_time"):
        return Param("time", 0.0, lo_open=True, unit=time_unit, what="communication step" if name == "step" else
                     "end of the run")
    if name in ("scenario.power_loss_at", "scenario.failed_leg", "scenario.failure_time"):
        needs = "platform" if name == "scenario.power_loss_at" else "closed-loop"
        if system in SYSTEMS and system != needs:
            return f"{name} applies to system = '{needs}' studies, and this one is '{system}'"
        if name == "scenario.failed_leg":
            return Param("int", 1, 6, what="leg number")
        return Param("time", 0.0, unit=time_unit, what="time of the failure")
    if name == "scenario.pump_stop_at":
        if system == "cueing":
            return f"{name} applies to system = 'platform' or 'closed-loop' studies, and this one is 'cueing'"
        return Param("time", 0.0, unit=time_unit, what="time the pump stops")
    role, dot, variable = name.partition(".")
    if not dot:
        known = [f"{r}.{name}" for r in ("platform", "controller") if name in variables.get(r, {})]
        hint = f"; did you mean {known[0]!r}?" if known else nearest(name, _candidates(system, variables))
        return (f"{name!r} is not a run parameter: name FMU variables as platform.<name> or controller.<name>, "
                f"or use step, stop_time, scenario.*{hint}")
    if role == "platform" and variable.startswith("com_offset"):
        if variable in ("com_offset[1]", "com_offset[2]", "com_offset[3]"):
            return Param("real", unit="m" if units == "si" else "R_b", what="centre-of-mass offset")
        return f"{name}: the centre-of-mass offset has 3 components, platform.com_offset[1] .. [3]"
    if role == "controller" and system == "platform":
        return f"{name}: a system = 'platform' study has no controller (use system = 'closed-loop')"
    if role not in MODELS:
        return f"{name!r} is not a run parameter{nearest(name, _candidates(system, variables))}"
    if isinstance(system, str) and system in ROLES and role not in ROLES[system]:
        return (f"{name}: a system = '{system}' study runs {', '.join(ROLES[system])} only"
                f"{nearest(name, _candidates(system, variables))}")
    table = variables.get(role, {})
    v = table.get(variable)
    if v is None:
        return f"{name}: {MODELS[role]} has no variable {variable!r}{nearest(name, _candidates(system, variables))}"
    if role == "cueing" and v.causality == "input":
        return f"{name} is an input that the study's manoeuvre drives: it cannot be set"
    if v.causality not in ("parameter", "input"):
        return f"{name} is {'an' if v.causality[0] in 'aeiou' else 'a'} {v.causality}, not a parameter or input"
    if system == "closed-loop" and v.causality == "input":
        # The commands (F, U or valve, by `drive`) and what the controller measures.
        driven = ("F", "U", "valve") if role == "platform" else ("l", "ldot", "pA", "pB", "supply.pressure")
        if variable.split("[")[0] in driven:
            return (f"{name} is an input the coupling drives in a closed-loop study (the platform's commands F, U or "
                    f"valve by its drive, the controller's measurements l, ldot, pA, pB, supply.pressure): it cannot "
                    f"be set")
    unit = v.unit if units == "si" else None
    if v.type == "Real":
        return Param("real", v.min, v.max, unit=unit, what=v.causality)
    if v.type == "Integer":
        return Param("int", v.min, v.max, unit=unit, what=v.causality)
    if v.type == "Boolean":
        return Param("bool", what=v.causality)
    return f"{name} is a {v.type} variable, which a study cannot set"


def _candidates(system, variables):
    names = ["step", "stop_time"]
    if system != "cueing":
        names += ["platform.com_offset[1]", "platform.com_offset[2]", "platform.com_offset[3]"]
        names += ["scenario.power_loss_at"] if system == "platform" else ["scenario.failed_leg", "scenario.failure_time"]
        names += ["scenario.pump_stop_at"]
    for role in ROLES.get(system, ("platform", "controller")) if isinstance(system, str) else ("platform", "controller"):
        names += [f"{role}.{n}" for n, v in variables.get(role, {}).items() if v.causality in ("parameter", "input")]
    return names


def check_value(param, value, where):
    """A message if `value` does not fit `param`, naming `where` and saying what to write."""
    if param.kind == "bool":
        return None if isinstance(value, bool) else f"{where} = {number(value)}: write true or false"
    if param.kind == "int":
        if isinstance(value, bool) or not isinstance(value, int):
            if isinstance(value, float) and math.isfinite(value) and value.is_integer():
                return f"{where} = {number(value)}: an integer is expected, write {int(value)}"
            return f"{where} = {number(value)}: an integer is expected"
    elif isinstance(value, bool) or not isinstance(value, (int, float)):
        if param.kind == "time" and isinstance(value, str):
            return (f"{where} = {value!r}: write a number of {param.unit} "
                    f"(the study's units; a time with a unit in a string is not read)")
        return f"{where} = {number(value)}: a number is expected{' (unit: ' + param.unit + ')' if param.unit else ''}"
    elif not math.isfinite(value):
        return f"{where} = {value}: a finite number is expected"
    unit = f" {param.unit}" if param.unit else ""
    if param.lo is not None and (value < param.lo or (param.lo_open and value == param.lo)):
        bound = f"greater than {number(param.lo)}" if param.lo_open else f"at least {number(param.lo)}"
        return f"{where} = {number(value)}{unit}: the {param.what} must be {bound}{unit}"
    if param.hi is not None and value > param.hi:
        return f"{where} = {number(value)}{unit}: the {param.what} must be at most {number(param.hi)}{unit}"
    return None
