"""The compiled co-simulation master (Rust: crates/stewart-master) from Python.

It loads FMI 2 Co-Simulation FMUs through their C API, connects them as an SSP system
describes and steps them at a fixed communication step with the Gauss-Seidel or Jacobi scheme
of `stewart_fmu.cosim`, in one process and with the loop in compiled code; only what is asked
for leaves the loop (a study's metrics, outputs at an interval). `stewart-sweep` runs studies
with it by default; `stewart-master` is its command line.

The extension module `stewart_fmu._master` comes with the wheels (maturin builds it from
crates/stewart-master-py: `bash python/build_wheels.sh`); in the repository, `pip install -e
python` (both set-up commands run it) builds it beside the package's files. Where it is missing
or cannot load, `available()` says why, and `stewart-sweep` runs its studies with the FMPy
master instead (the same rows, slower).

    from stewart_fmu.master import System, closed_loop
    system = System.from_ssp(SYSTEM_SSP)
    out = system.run(10_000, 1e-3, record=["platform.r[3]"], every=10)
"""

import sys

import numpy as np

from .core import CONTROLLER_FMU, IN_REPOSITORY, LEGS, PLATFORM_FMU, check_names, check_times, fmu_file
from .ssp import SYSTEMS, system_description


def _load():
    """The extension module, or the reason it is not available."""
    try:
        from . import _master  # the wheel's, or the one `pip install -e python` builds in the repository
        return _master, None
    except ImportError as e:
        error = e
    if IN_REPOSITORY:
        return None, (f"the compiled master is not built here ({error}): `pip install -e python` builds it (both "
                      "set-up commands run it)")
    return None, f"this installation of stewart_fmu has no compiled master that loads here ({error})"


_master, UNAVAILABLE = _load()


def available():
    """(True, None) if the compiled master can run here, else (False, the reason)."""
    return _master is not None, UNAVAILABLE


def _module():
    if _master is None:
        raise RuntimeError(UNAVAILABLE)
    return _master


def System(fmus, ssd=None):
    """A system of FMUs: `fmus` maps component names to FMU paths or FMU bytes; `ssd` is the
    text of an SSP system description naming those components (without it they run
    unconnected). See `System.from_ssp` for an SSP file."""
    return _module().System([(name, str(f) if not isinstance(f, bytes) else f) for name, f in fmus.items()], ssd)


def from_ssp(path):
    """The system an SSP file describes, with the FMUs it carries."""
    return _module().System.from_ssp(str(path))


def run(system, stop_time, step, scheme="gauss-seidel", values=None, record=(), interval=None, overrides=(),
        inputs=None):
    """Runs `system` from 0 to `stop_time` at the communication step `step` (Gauss-Seidel or
    Jacobi; the communication points are summed, t += h, as stewart_fmu.cosim and FMPy's SSP
    master count them). `values`: {"component.variable": value} set in initialisation mode;
    `record`: "component.variable" names recorded every `interval` (a multiple of `step`;
    default every step); `overrides`: (name, value, from_time) inputs held at a value (a
    failed actuator); `inputs`: {component: {"time": times, variable: values, ...}} inputs no
    connection drives, interpolated linearly to each communication point (numpy.interp's bits)
    and held after the last time (a vehicle's motion). Returns (times, rows, status, message):
    `rows` one row of the recorded
    values per recorded point, status "ok" or the failed call as FMPy words it."""
    check_times(stop_time, step, "stop_time", "step")
    every = 1
    if interval is not None:
        every = int(round(interval / step))
        if every < 1 or abs(every * step - interval) > 1e-9 * interval:
            raise ValueError(f"interval = {interval}: a whole multiple of step = {step} is expected")
    tables = [(component, [float(x) for x in columns["time"]],
               [(name, [float(x) for x in column]) for name, column in columns.items() if name != "time"])
              for component, columns in (inputs or {}).items()]
    out = system.run(int(round(stop_time / step)), float(step), scheme=scheme, values=list((values or {}).items()),
                     overrides=[(n, float(v), float(t)) for n, v, t in overrides], record=list(record), every=every,
                     inputs=tables)
    times = np.frombuffer(out["times"], dtype="<f8")
    rows = np.frombuffer(out["values"], dtype="<f8").reshape(len(times), len(record))
    status = "ok" if out["status"] == "ok" else out["call"]
    return times, rows, status, out["message"]


def closed_loop(t_end, h, scheme="gauss-seidel", platform_reals=None, controller_reals=None, controller_integers=None,
                record=("r[3]",)):
    """`stewart_fmu.cosim.closed_loop` with the compiled master: the same arguments (without
    `force_hook` and `events`), the same numbers to the bit, the same (times, recorded platform
    outputs, max |l - l^p| per step, status). With `drive = 1` in both components the system
    is StewartSystemDrives.ssp's (voltages U), with `drive = 2` StewartSystemHydraulic.ssp's (valve
    commands), otherwise StewartSystem.ssp's (forces F)."""
    check_times(t_end, h, "t_end", "h")
    controller_values = {**(controller_reals or {}), **(controller_integers or {})}
    drives = [int(dict(p or {}).get("drive", 0)) for p in (platform_reals, controller_values)]
    if drives[0] != drives[1]:
        raise ValueError(f"drive = {drives[0]} in platform_reals but {drives[1]} in the controller's parameters: the "
                         "controller's commands (F, U or valve) drive the platform only when both have the same drive")
    if drives[0] not in SYSTEMS:
        raise ValueError(f"drive = {drives[0]}: 0 (forces), 1 (electric drives) or 2 (hydraulic legs)")
    system = System({"platform": fmu_file(PLATFORM_FMU), "controller": fmu_file(CONTROLLER_FMU)},
                    system_description(SYSTEMS[drives[0]], bindings=False))
    try:
        names = {v[0] for v in system.variables("platform")}
        check_names(record, names, "StewartPlatform", "record")
        values = {f"platform.{k}": v for k, v in (platform_reals or {}).items()}
        values.update({f"controller.{k}": v for k, v in controller_values.items()})
        legs = [f"platform.l[{k}]" for k in LEGS] + [f"controller.lp[{k}]" for k in LEGS]
        times, rows, status, _ = run(system, t_end, h, scheme, values, [f"platform.{r}" for r in record] + legs)
    finally:
        system.close()
    k = len(record)
    errors = np.max(np.abs(rows[:, k:k + 6] - rows[:, k + 6:]), axis=1) if len(rows) else np.zeros(0)
    return times, rows[:, :k], errors, status


def main(argv=None):
    """`stewart-master`: the compiled master's command line (`stewart-master --help`)."""
    if _master is None:
        print(f"stewart-master: {UNAVAILABLE}", file=sys.stderr)
        return 2
    return _master.cli(list(sys.argv[1:] if argv is None else argv))


if __name__ == "__main__":
    sys.exit(main())
