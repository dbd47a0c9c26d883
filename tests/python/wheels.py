"""The wheels for the tests (test_wheels.py, test_wheel.py): built once per test session by
python/build_wheels.py (the README's command, after its set-up), and the places that run them
here: an arm64 CPython under qemu-user for the aarch64 wheel, wine for the compiled master built
for Windows.

The arm64 CPython is Debian 12's own (its packages unpacked, not installed, as for
test_platforms.py: platforms.arm64_python) with a virtual environment of its own in
target/arm64-python/venv: the environment's `bin/python` is a two-line script that runs the
arm64 interpreter under qemu-user with itself as argv[0], so that everything that starts Python
again from sys.executable (pip's scripts, Dask's worker processes) runs under qemu too, with no
binfmt_misc registration on the machine. The dependencies' aarch64 wheels come from PyPI
(tests/requirements.txt's versions, through this machine's pip, made once); the arm64 pip in
that environment installs the aarch64 wheel itself, so its tags are checked by an aarch64 pip.
"""

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import platforms as P

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "python"))
import build_wheels  # noqa: E402  python/build_wheels.py: the platforms, the wheels' names, the cross builds

from stewart_fmu import study as st  # noqa: E402
from stewart_fmu.sweep_results import load_results  # noqa: E402

WHEELS = build_wheels.WHEELS
_BUILT = {}


def wheels():
    """{platform: wheel} for the three platforms, built once per test run."""
    if not _BUILT:
        with P.made_once("wheels"):
            _build_wheels()
    return dict(_BUILT)


def _build_wheels():
    """python/build_wheels.py, under the lock, once per test run: the other test worker
    (pytest-xdist, the same PYTEST_XDIST_TESTRUNUID) may have built them and be reading them."""
    run_id = os.environ.get("PYTEST_XDIST_TESTRUNUID", f"pid {os.getpid()}")
    stamp = WHEELS / "built-for-test-run"
    version = build_wheels.version()
    paths = {p: WHEELS / build_wheels.wheel_name(p, version) for p in build_wheels.PLATFORMS}
    if not (stamp.exists() and stamp.read_text() == run_id and all(w.exists() for w in paths.values())):
        run = subprocess.run([sys.executable, str(ROOT / "python" / "build_wheels.py")], cwd=ROOT, capture_output=True,
                             text=True)
        assert run.returncode == 0, (run.stdout + run.stderr)[-4000:]
        print("\n".join(line for line in run.stdout.splitlines() if line.startswith("build_wheels:")))
        stamp.write_text(run_id)
    _BUILT.update(paths)


def constraints(folder):
    """tests/requirements.txt as a pip constraints file (constraints take no extras)."""
    path = folder / "constraints.txt"
    path.write_text(re.sub(r"\[[^\]]*\]", "", (ROOT / "tests" / "requirements.txt").read_text()))
    return path


def differences(a, b):
    """(cells that differ, the largest difference of two numbers) between two row tables of the
    same runs: every column exactly, NaN equal to NaN."""
    assert list(a.index) == list(b.index) and list(a.columns) == list(b.columns)
    cells, largest = 0, 0.0
    for column in a.columns:
        x, y = a[column].to_numpy(), b[column].to_numpy()
        if x.dtype.kind == "f" or y.dtype.kind == "f":
            x, y = x.astype(float), y.astype(float)
            same = (x == y) | (np.isnan(x) & np.isnan(y))
            finite = ~same & np.isfinite(x) & np.isfinite(y)
            largest = max(largest, float(np.max(np.abs(x - y)[finite], initial=0.0)))
            largest = max(largest, np.inf if np.any(~same & ~finite) else 0.0)
        else:
            same = x == y
        cells += int(np.sum(~same))
    return cells, largest


def rows(out):
    """A study's rows (stewart-sweep's --out folder) by run id, the columns every master gives
    (not wall_time, worker)."""
    frame = load_results(out).set_index("run_id").sort_index()
    return frame[["status", "message", *st.METRICS] + [c for c in frame.columns if c.startswith("param:")]]


# ----- the arm64 CPython under qemu-user ---------------------------------------------------------

ARM64_VENV = P.ARM64_PYTHON / "venv"
# The package's dependencies (pyproject.toml) and pip, at tests/requirements.txt's versions.
ARM64_REQUIREMENTS = ["fmpy", "numpy", "scipy", "matplotlib", "dask[distributed]", "pandas", "pyarrow"]
ARM64_PIP = "pip==24.3.1"


def arm64_venv():
    """The arm64 environment's `bin` folder (made once: Debian's arm64 CPython, pip, and the
    package's dependencies from PyPI's aarch64 wheels, about 200 MB)."""
    with P.made_once("arm64-venv"):
        return _arm64_venv()


def _arm64_venv():
    P.arm64_python(sys.executable)  # Debian's arm64 packages unpacked into target/arm64-python/root
    root = P.ARM64_PYTHON / "root"
    stamp = ARM64_VENV / "ready"
    wanted = " ".join([ARM64_PIP, *ARM64_REQUIREMENTS, (ROOT / "tests" / "requirements.txt").read_text()])
    if stamp.exists() and stamp.read_text() == wanted:
        return ARM64_VENV / "bin"
    shutil.rmtree(ARM64_VENV, ignore_errors=True)
    site = ARM64_VENV / "lib" / "python3.11" / "site-packages"
    site.mkdir(parents=True)
    (ARM64_VENV / "bin").mkdir()
    version = subprocess.run([*qemu(root), "-c", "import platform; print(platform.python_version())"],
                             capture_output=True, text=True, check=True).stdout.strip()
    (ARM64_VENV / "pyvenv.cfg").write_text(f"home = {root / 'usr' / 'bin'}\ninclude-system-site-packages = false\n"
                                           f"version = {version}\n")
    python = ARM64_VENV / "bin" / "python"
    # argv[0] is this script: Python finds the environment from it (pyvenv.cfg beside bin/) and
    # starts itself again through it.
    python.write_text(f'#!/bin/sh\nexec {" ".join(qemu(root)[:-1])} -0 "{python}" {root}/usr/bin/python3.11 "$@"\n')
    python.chmod(0o755)
    # The dependencies' aarch64 wheels (and pip, pure Python) through this machine's pip, which
    # picks them for the arm64 interpreter; the arm64 pip installs the package's wheel itself.
    platforms = [a for p in ("manylinux_2_36_aarch64", "manylinux_2_28_aarch64", "manylinux_2_17_aarch64",
                             "manylinux2014_aarch64") for a in ("--platform", p)]
    subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", "--disable-pip-version-check", "--target",
                    str(site), *platforms, "--python-version", version, "--implementation", "cp",
                    "--only-binary=:all:", "-c", str(constraints(P.ARM64_PYTHON)), ARM64_PIP, *ARM64_REQUIREMENTS],
                   check=True, timeout=1800)
    stamp.write_text(wanted)
    return ARM64_VENV / "bin"


def qemu(root):
    """The command that runs Debian's arm64 python3.11 under qemu-user."""
    return [P.QEMU, "-L", str(root), str(root / "usr" / "bin" / "python3.11")]


def arm64_install(wheel):
    """Installs (again) the aarch64 wheel into the arm64 environment with its own pip; returns
    the environment's `bin` folder."""
    bin_dir = arm64_venv()
    run = subprocess.run([str(bin_dir / "python"), "-m", "pip", "install", "--quiet", "--disable-pip-version-check",
                          "--no-deps", "--force-reinstall", str(wheel)], capture_output=True, text=True, timeout=900)
    assert run.returncode == 0, run.stderr[-3000:]
    return bin_dir


def arm64_env():
    """The environment for the arm64 Python's processes: no variables pointing into the
    repository; the arm64 environment's bin first on PATH."""
    env = {k: v for k, v in os.environ.items()
           if k not in ("PYTHONPATH", "VIRTUAL_ENV") and not k.startswith("STEWART_")}
    env["PATH"] = f"{ARM64_VENV / 'bin'}:{env.get('PATH', '')}"
    # Every process runs several times slower under qemu: Dask's workers get longer to answer
    # their scheduler than its default 30 s.
    env["DASK_DISTRIBUTED__COMM__TIMEOUTS__CONNECT"] = "120s"
    return env


# ----- the compiled master for Windows, under wine ---------------------------------------------

WINDOWS_TRIPLE = build_wheels.PLATFORMS["x86_64-windows"][0]


def windows_master():
    """The `stewart-master` command built for Windows x64 from the crate whose extension the
    Windows wheel carries, with the toolchain that built that extension (python/build_wheels.py's
    cross build, in target/cross/<triple>: its standard library and dependencies are already compiled)."""
    env, extra, target_dir, _ = build_wheels.cross_build(WINDOWS_TRIPLE, build_wheels.PLATFORMS["x86_64-windows"][3])
    run = subprocess.run(["cargo", "build", "--release", "-p", "stewart-master", "--bin", "stewart-master", "--target",
                          WINDOWS_TRIPLE, "--target-dir", str(target_dir), *extra], cwd=ROOT, env=env,
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr[-3000:]
    return target_dir / WINDOWS_TRIPLE / "release" / "stewart-master.exe"
