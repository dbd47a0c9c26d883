"""The package outside the repository: the Linux x86-64 wheel (python/build_wheels.py, built once
for the session by wheels.py, nothing written into python/) installed into a fresh virtual
environment in a temporary folder (its dependencies from PyPI, at the versions of
tests/requirements.txt). From a working directory outside the repository, that environment
runs the README's tour (its Python blocks, and its design study with `stewart-sweep` on a
local Dask cluster of two worker processes on 127.0.0.1), with the repository's numbers bit
for bit; a simulation and a closed loop whose numbers equal the repository's (the equilibrium
holds, the legs track the programme); and `view()`, whose page, served and opened in headless
Chromium, shows the legs Python computes from its CSV. A missing FMU is an error that names both ways
to point at one (the environment variable and `--fmu`). Without its compiled master (as on a
platform where the extension cannot load) the package runs its studies with the FMPy master,
says so once, and gives the compiled master's rows; `--master compiled` is then an error that
says why."""

import hashlib
import json
import os
import subprocess
import sys
import textwrap
import zipfile

import functools
import http.server
import threading
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import wheels as W
from test_readme import check_study, check_tour, run_study, run_tour
from test_viewer import QuietHandler, browse, expected

from stewart_fmu import NEUTRAL_Z, ROOT
from stewart_fmu.cosim import closed_loop
from fmpy import simulate_fmu

STUDY = """
[study]
name = "mass"
system = "closed-loop"
units = "si"
stop_time = 2.0
step = 0.002
stable_error = 0.01

[grid]
"platform.M" = [2500.0, 3000.0, 3500.0]
"controller.G" = [1e5, 2e5]
"""

PACKAGED = W.build_wheels.PACKAGED  # the FMUs and SSP files a wheel carries


def sha(path):
    return hashlib.sha256(path.read_bytes()).hexdigest()


def clean_env(venv):
    """The fresh environment's PATH first, no variables that point into the repository."""
    env = {k: v for k, v in os.environ.items()
           if k not in ("PYTHONPATH", "VIRTUAL_ENV", "STEWART_PLATFORM_FMU", "STEWART_CONTROLLER_FMU")}
    env["PATH"] = f"{venv / 'bin'}:{env.get('PATH', '')}"
    return env


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    """(venv, work folder, wheel): the wheel built by the script and installed into a fresh
    virtual environment outside the repository."""
    before = subprocess.run(["git", "status", "--porcelain", "--ignored", "python"], cwd=ROOT, capture_output=True,
                            text=True).stdout
    wheel = W.wheels()["x86_64-linux"]
    after = subprocess.run(["git", "status", "--porcelain", "--ignored", "python"], cwd=ROOT, capture_output=True,
                           text=True).stdout
    assert after == before, f"building the wheels wrote into python/:\n{after}"
    with zipfile.ZipFile(wheel) as z:
        names = set(z.namelist())
        for name in PACKAGED:
            data = z.read(f"stewart_fmu/data/fmu/{name}")
            assert hashlib.sha256(data).hexdigest() == sha(ROOT / "target" / "fmu" / name), name
        assert "stewart_fmu/data/viewer/index.html" in names
        assert "stewart_fmu/_master.abi3.so" in names  # the compiled co-simulation master
        assert any(n.startswith("stewart_fmu/data/viewer/assets/") and n.endswith(".js") for n in names)
    print(f"wheel: {wheel.name}, {wheel.stat().st_size / 1e6:.2f} MB, {len(names)} files")

    base = tmp_path_factory.mktemp("fresh")
    assert ROOT.resolve() not in base.resolve().parents
    venv, work = base / "venv", base / "work"
    work.mkdir()
    # A venv from the interpreter this one was made from, as a user's `python3 -m venv`.
    subprocess.run([getattr(sys, "_base_executable", "python3"), "-m", "venv", str(venv)], check=True)
    # tests/requirements.txt's versions as constraints.
    constraints = W.constraints(base)
    pip = subprocess.run([str(venv / "bin" / "python"), "-m", "pip", "install", "--quiet", "--disable-pip-version-check",
                          "-c", str(constraints), str(wheel)], capture_output=True, text=True, cwd=work)
    assert pip.returncode == 0, pip.stderr[-3000:]
    return venv, work, wheel


def run_python(venv, work, code, env=None):
    run = subprocess.run([str(venv / "bin" / "python"), "-c", textwrap.dedent(code)], cwd=work, capture_output=True,
                         text=True, env=env or clean_env(venv), timeout=600)
    assert run.returncode == 0, run.stderr[-3000:]
    return json.loads(run.stdout.strip().splitlines()[-1])


def test_the_installed_package_uses_its_own_fmus_and_matches_the_repository(installed):
    venv, work, _ = installed
    got = run_python(venv, work, """
        import json
        import numpy as np
        from fmpy import simulate_fmu
        import stewart_fmu
        from stewart_fmu import CONTROLLER_FMU, PLATFORM_FMU
        from stewart_fmu.cosim import SYSTEM_SSP, closed_loop
        result = simulate_fmu(PLATFORM_FMU, output=["r[3]", "E"])
        t, rows, errors, status = closed_loop(2.0, 1e-3, record=("r[3]",))
        print(json.dumps({"package": stewart_fmu.__file__, "platform": str(PLATFORM_FMU), "controller": str(CONTROLLER_FMU),
                          "ssp": str(SYSTEM_SSP), "z": result["r[3]"].tolist(), "status": status,
                          "errors": errors.tolist(), "loop_z": rows[:, 0].tolist()}))
    """)
    site = str(venv / "lib")
    for key in ("package", "platform", "controller", "ssp"):
        assert got[key].startswith(site), (key, got[key])
    assert got["platform"].endswith("stewart_fmu/data/fmu/StewartPlatform.fmu")
    here = simulate_fmu(str(ROOT / "target" / "fmu" / "StewartPlatform.fmu"), output=["r[3]", "E"])
    t, rows, errors, status = closed_loop(2.0, 1e-3, record=("r[3]",))
    z = np.array(got["z"])
    print(f"installed package: equilibrium z = {z[-1]!r} m over 3 s (max |z - z0| {np.max(np.abs(z - NEUTRAL_Z)):.1e}); "
          f"closed loop 2 s: largest leg error {max(got['errors']) * 1e3:.4f} mm; same as the repository's to the bit: "
          f"{np.array_equal(z, here['r[3]']) and got['errors'] == errors.tolist()}")
    assert np.max(np.abs(z - NEUTRAL_Z)) < 1e-12
    assert np.array_equal(z, here["r[3]"])
    assert got["status"] == status == "ok"
    assert got["errors"] == errors.tolist() and got["loop_z"] == rows[:, 0].tolist()
    assert max(got["errors"]) < 2e-5  # the legs track the heave programme to 0.02 mm


def test_the_installed_package_has_the_compiled_master_with_the_repositorys_numbers(installed):
    """The wheel's extension module runs the closed loop outside the repository, to the bit as
    the repository's compiled master and FMPy master do; its `stewart-master` command runs."""
    venv, work, _ = installed
    got = run_python(venv, work, """
        import json
        from stewart_fmu import master
        t, rows, errors, status = master.closed_loop(2.0, 1e-3, record=("r[3]",))
        print(json.dumps({"module": master._master.__file__, "available": master.available()[0], "status": status,
                          "errors": errors.tolist(), "z": rows[:, 0].tolist()}))
    """)
    t, rows, errors, status = closed_loop(2.0, 1e-3, record=("r[3]",))
    print(f"installed compiled master: {got['module']}; closed loop 2 s: status {got['status']}, same as FMPy's "
          f"master in the repository to the bit: {got['errors'] == errors.tolist() and got['z'] == rows[:, 0].tolist()}")
    assert got["available"] and got["module"].startswith(str(venv / "lib"))
    assert got["status"] == status == "ok"
    assert got["errors"] == errors.tolist() and got["z"] == rows[:, 0].tolist()
    command = subprocess.run([str(venv / "bin" / "stewart-master"), "describe", "missing.ssp"], capture_output=True,
                             text=True, cwd=work, env=clean_env(venv))
    assert command.returncode == 2  # no such SSP file: a message, not a crash
    assert "stewart-master:" in command.stderr and "Traceback" not in command.stderr


def test_the_readme_tour_runs_from_the_installed_package_as_in_the_repository(installed, tmp_path):
    """The tour's Python blocks and its study (stewart-sweep on a local Dask cluster of two
    workers) in the fresh environment, from a folder outside the repository: what they show
    (test_readme.check_tour, check_study), and the same numbers as the repository's run."""
    venv, work, _ = installed
    kept = run_tour(venv / "bin" / "python", work, clean_env(venv))
    check_tour(kept)
    rows, out = run_study(venv / "bin", work, clean_env(venv))
    by_mass = check_study(rows, out)
    here_env = {k: v for k, v in os.environ.items() if not k.startswith("STEWART_")}
    here = run_tour(sys.executable, tmp_path, here_env)
    repo_rows, _ = run_study(Path(sys.executable).parent, tmp_path, here_env)

    def comparable(frame):
        return frame.drop(columns=["wall_time", "worker"]).sort_values("run_id").reset_index(drop=True)

    print(f"installed package, the README's tour outside the repository: equilibrium z = "
          f"{kept[0]['result']['r[3]'][-1]!r} m; closed loop {max(kept[1]['errors']) * 1e3:.4f} mm; motion cueing pitch "
          f"{kept[2]['pitch']:.6f} rad; study on 2 local Dask workers: largest leg error by mass (kg -> mm) "
          f"{ {m: round(e * 1e3, 3) for m, e in by_mass.items()} }; equal to the repository's run: "
          f"{kept == here}")
    assert kept == here, "the installed package computes the repository's numbers"
    pd.testing.assert_frame_equal(comparable(rows), comparable(repo_rows))


def test_view_writes_the_packaged_page_and_the_browser_shows_the_result(installed):
    venv, work, _ = installed
    got = run_python(venv, work, """
        import json
        from fmpy import simulate_fmu
        from stewart_fmu import PLATFORM_FMU
        from stewart_fmu.viewer import VIEW_OUTPUTS, stand, view
        start = {"angles0[1]": 0.02}
        result = simulate_fmu(PLATFORM_FMU, stop_time=1.0, start_values=start, output=VIEW_OUTPUTS)
        print(json.dumps({"address": view(result, stand(start), "my_viewer", "tilted")}))
    """)
    folder = work / "my_viewer"
    assert (folder / "index.html").read_bytes() == (ROOT / "viewer" / "dist" / "index.html").read_bytes()
    assert json.loads((folder / "data" / "index.json").read_text())[0]["data"] == "data/tilted.csv"
    handler = functools.partial(QuietHandler, directory=str(folder))
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    try:
        report = browse(f"http://127.0.0.1:{server.server_address[1]}/{got['address']}", work / "shot.png", [0.5, 1.0])
    finally:
        server.shutdown()
    worst = 0.0
    for sample in report["samples"]:
        _, ends, r, _ = expected(folder, sample["t"], "tilted")
        worst = max(worst, np.max(np.abs(np.array(sample["ends"]) - np.array(ends))))
    print(f"installed view(): {report['rows']} rows shown, leg end points within {worst:.1e} m of Python")
    assert report["rows"] > 10 and worst < 1e-9


def test_a_missing_fmu_names_both_ways_to_point_at_one(installed):
    venv, work, _ = installed
    (work / "small.toml").write_text(STUDY)
    env = dict(clean_env(venv), STEWART_PLATFORM_FMU=str(work / "nowhere" / "StewartPlatform.fmu"))
    run = subprocess.run([str(venv / "bin" / "stewart-sweep"), "small.toml", "--out", "missing"], cwd=work,
                         capture_output=True, text=True, env=env, timeout=300)
    print(run.stderr.strip())
    assert run.returncode == 2
    assert "StewartPlatform.fmu not found at" in run.stderr
    assert "STEWART_PLATFORM_FMU" in run.stderr and "--fmu" in run.stderr
    simulation = subprocess.run([str(venv / "bin" / "python"), "-c", "from stewart_fmu import Platform; Platform()"],
                                cwd=work, capture_output=True, text=True, env=env, timeout=300)
    assert simulation.returncode == 1 and "FileNotFoundError" in simulation.stderr
    assert "STEWART_PLATFORM_FMU" in simulation.stderr and "--fmu" in simulation.stderr
    # --fmu points the study at an FMU elsewhere (here the repository's build).
    check = subprocess.run([str(venv / "bin" / "stewart-sweep"), "small.toml", "--check", "--fmu",
                            str(ROOT / "target" / "fmu" / "StewartPlatform.fmu")], cwd=work, capture_output=True,
                           text=True, env=env, timeout=300)
    assert check.returncode == 0, check.stderr


def test_without_the_compiled_master_studies_run_with_fmpys_master_and_the_same_rows(installed):
    """The installed extension moved aside, as on a platform where it cannot load: stewart-sweep
    says once why and that the FMPy master runs the study (on two Dask workers), and its rows
    are the compiled master's; `--master compiled` is then an error that says why, and
    `stewart-master` too. Runs last: the extension is put back at its end."""
    venv, work, _ = installed
    (work / "fallback.toml").write_text(STUDY)
    sweep = str(venv / "bin" / "stewart-sweep")

    def run(*args):
        return subprocess.run([sweep, "fallback.toml", *args], cwd=work, capture_output=True, text=True,
                              env=clean_env(venv), timeout=600)

    compiled = run("--out", "compiled", "--serial")
    assert compiled.returncode == 0, compiled.stderr[-3000:]
    assert "running 6 with the compiled master" in compiled.stdout
    extension, = (venv / "lib").glob("python3*/site-packages/stewart_fmu/_master.abi3.so")
    hidden = extension.with_name("moved-aside")
    extension.rename(hidden)
    try:
        fallback = run("--out", "fallback", "--workers", "2")
        asked = run("--out", "asked", "--master", "compiled")
        command = subprocess.run([str(venv / "bin" / "stewart-master"), "describe", "any.ssp"], cwd=work,
                                 capture_output=True, text=True, env=clean_env(venv))
    finally:
        hidden.rename(extension)
    assert fallback.returncode == 0, fallback.stderr[-3000:]
    notes = [line for line in fallback.stderr.splitlines() if "compiled master" in line]
    cells, largest = W.differences(W.rows(work / "fallback"), W.rows(work / "compiled"))
    print(f"without the extension: {notes[0]!r}; {fallback.stdout.splitlines()[0]!r}; rows against the compiled "
          f"master's: {cells} cells differ, the largest difference {largest}; --master compiled: exit "
          f"{asked.returncode}: {asked.stderr.strip()!r}")
    assert len(notes) == 1 and "has no compiled master that loads here" in notes[0]
    assert notes[0].endswith("running with the FMPy master (--master fmpy; slower, the same rows)")
    assert "running 6 with the fmpy master" in fallback.stdout
    assert cells == 0 and largest == 0.0 and len(W.rows(work / "fallback")) == 6
    assert asked.returncode == 2 and "Traceback" not in asked.stderr
    assert asked.stderr.startswith("stewart-sweep: --master compiled: this installation of stewart_fmu has no compiled")
    assert command.returncode == 2 and "stewart-master: this installation of stewart_fmu has no compiled" in command.stderr
