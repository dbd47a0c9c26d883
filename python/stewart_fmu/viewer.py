"""The 3-D viewer (`viewer/`, three.js) for any platform result: `view(result, stand)` writes
the built page, the result as CSV and the stand as JSON into a folder, and returns the address
to open once the folder is served (`python -m http.server`).

A result is what `fmpy.simulate_fmu` returns (a structured array) or a dict of columns; it needs
`time` and `r[1..3]` and either `R[a,b]` or `angles[1..3]`; `F[k]`, `Fstop[k]`, `l[k]` and
the joint angles `thetaB[k]`, `thetaA[k]` colour the legs and joints and feed the plots when
present (`VIEW_OUTPUTS` lists them all for `simulate_fmu(..., output=VIEW_OUTPUTS)`); with
hydraulic legs the pressures `pA[k]`, `pB[k]` colour the cylinders by the load pressure and,
with `spool[k]`, feed two more plots, and `supply.pressure` with `accumulator.oilVolume` a third
(the power unit's, docs/model.md §10b; `HYDRAULIC_VIEW_OUTPUTS`).
"""

import json
import shutil
import subprocess
import sys
from pathlib import Path
from urllib.parse import quote

import numpy as np
from fmpy import read_model_description

from .core import DATA, IN_REPOSITORY, LEGS, PLATFORM_FMU, ROOT, fmu_file

VIEWER = ROOT / "viewer"  # the viewer's sources, in the repository
VIEW_OUTPUTS = ([f"r[{i}]" for i in (1, 2, 3)] + [f"R[{a},{b}]" for a in (1, 2, 3) for b in (1, 2, 3)]
                + [f"angles[{i}]" for i in (1, 2, 3)] + [f"l[{k}]" for k in LEGS] + [f"F[{k}]" for k in LEGS]
                + [f"Fstop[{k}]" for k in LEGS] + [f"thetaB[{k}]" for k in LEGS] + [f"thetaA[{k}]" for k in LEGS])
# With hydraulic legs (drive = 2): the chamber pressures colour the cylinders by the load
# pressure and feed a plot, as the spools do theirs; the supply pressure and the accumulator's
# oil (the power unit, hydraulic.supply = 1) feed a third.
HYDRAULIC_VIEW_OUTPUTS = ([f"{n}[{k}]" for n in ("pA", "pB", "spool") for k in LEGS]
                          + ["supply.pressure", "accumulator.oilVolume"])
# The scalar parameters the viewer draws with: the legs' bodies (docs/model.md §8) and the
# joint limits (a joint beyond its limit is drawn red).
STAND_SCALARS = ("leg.cylinderMass", "leg.rodMass", "leg.cylinderCoM", "leg.rodCoM", "joints.baseMaxAngle",
                 "joints.platformMaxAngle", "hydraulic.bore", "hydraulic.rod")


def built_viewer():
    """The built page: installed from a wheel, the copy it carries (stewart_fmu/data/viewer/);
    in the repository, viewer/dist/, built with npm from the committed lock file if missing."""
    if not IN_REPOSITORY:
        packaged = DATA / "viewer"
        if (packaged / "index.html").is_file():
            return packaged
        raise RuntimeError(f"the viewer page is not in this installation of stewart_fmu ({packaged} is missing): "
                           "install a wheel `bash python/build_wheels.sh` builds, which carries it")
    dist = VIEWER / "dist"
    if not (dist / "index.html").exists():
        npm = shutil.which("npm")
        if npm is None:
            raise RuntimeError("viewer/dist is missing and npm is not installed: install Node.js and npm, then run "
                               "`npm ci && npm run build` in viewer/")
        print("stewart_fmu.viewer: building the viewer page in viewer/ (npm ci and vite; about a minute)",
              file=sys.stderr, flush=True)
        for command in ([npm, "ci", "--no-audit", "--no-fund"], [npm, "run", "build"]):
            run = subprocess.run(command, cwd=VIEWER, capture_output=True, text=True)
            if run.returncode != 0:
                raise RuntimeError(f"`{' '.join(command[1:])}` in {VIEWER} failed:\n{run.stderr[-2000:]}")
    return dist


def stand(parameters=None, fmu=PLATFORM_FMU):
    """The stand of a run for the viewer: the FMU's start values of `B`, `A`, `lmin`, `lmax`,
    the legs' bodies and the joint limits, overridden by `parameters` (FMI names, as given to
    `simulate_fmu`'s `start_values`)."""
    variables = read_model_description(fmu_file(fmu)).modelVariables
    start = {v.name: float(v.start) for v in variables if v.start is not None and v.type == "Real"}
    joints = {v.name: v.start == "true" for v in variables if v.type == "Boolean"}.get("joints", False)
    for k, v in (parameters or {}).items():
        if k == "joints":
            joints = bool(v)
        elif isinstance(v, (int, float)):
            start[k] = float(v)
    scalars = {name.split(".")[-1]: start[name] for name in STAND_SCALARS if name in start}
    return {
        "B": [[start[f"B[{k},{i}]"] for i in (1, 2, 3)] for k in LEGS],
        "A": [[start[f"A[{k},{i}]"] for i in (1, 2, 3)] for k in LEGS],
        "lmin": [start[f"lmin[{k}]"] for k in LEGS],
        "lmax": [start[f"lmax[{k}]"] for k in LEGS],
        "joints": joints,
        **scalars,
        "source": f"{Path(fmu).name} start values" + (" with the run's parameters" if parameters else ""),
    }


def _columns(result):
    if isinstance(result, np.ndarray) and result.dtype.names:
        return {n: np.asarray(result[n], dtype=float) for n in result.dtype.names}
    return {k: np.asarray(v, dtype=float) for k, v in result.items()}


def write_csv(path, result):
    """The result as a CSV the viewer reads (FMPy's layout: quoted names, full precision)."""
    columns = _columns(result)
    names = ["time"] + [n for n in columns if n != "time"]
    missing = [n for n in ("time", "r[1]", "r[2]", "r[3]") if n not in columns]
    if missing:
        raise ValueError(f"not a platform result: missing columns {', '.join(missing)}")
    rows = np.column_stack([columns[n] for n in names])
    with open(path, "w") as f:
        f.write(",".join(f'"{n}"' for n in names) + "\n")
        for row in rows:
            f.write(",".join(repr(float(x)) for x in row) + "\n")


def view(result, stand_values=None, out="output/viewer", name="result", title=None):
    """Writes the viewer page with `result` into `out` (data in `out/data/NAME.csv` and
    `NAME.stand.json`, listed in `out/data/index.json` beside earlier ones); returns the page's
    address relative to `out`, its query encoded. `name` is a file name: no folders."""
    if not isinstance(name, str) or not name or name in (".", "..") or "/" in name or "\\" in name or "\0" in name:
        raise ValueError(f"name = {name!r}: a file name for the result is expected (no '/', not empty)")
    out = Path(out)
    dist = built_viewer()
    out.mkdir(parents=True, exist_ok=True)
    shutil.copytree(dist, out, dirs_exist_ok=True)
    data = out / "data"
    data.mkdir(exist_ok=True)
    write_csv(data / f"{name}.csv", result)
    (data / f"{name}.stand.json").write_text(json.dumps(stand_values or stand(), indent=1))
    index_path = data / "index.json"
    index = json.loads(index_path.read_text()) if index_path.exists() else []
    entry = {"title": title or name, "data": f"data/{name}.csv", "stand": f"data/{name}.stand.json"}
    index = [d for d in index if d["data"] != entry["data"]] + [entry]
    index_path.write_text(json.dumps(index, indent=1))
    return f"index.html?data={quote(entry['data'])}&stand={quote(entry['stand'])}"
