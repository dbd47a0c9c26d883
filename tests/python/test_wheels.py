"""The wheels of every platform (python/build_wheels.py; the README's `bash python/build_wheels.sh`),
built once for the session (wheels.py):

- each wheel's tag, metadata (the workspace's one version, which the crates and the FMUs carry
  too; the licence) and contents: the package's files, the compiled master built for its
  platform (its ELF machine, libraries and glibc versions; the Windows .pyd's imports: system
  DLLs and python3.dll), the FMUs with all their binaries (the aarch64 wheel's FMI 2 FMUs with
  the aarch64 binary in linux64) and the viewer page;
- the aarch64 wheel installed by the pip of an arm64 CPython (Debian 12's, under qemu-user)
  runs the README's tour (its Python blocks and its study on a local Dask cluster) and a 20-run
  study with the compiled master: every number equal to x86-64's;
- the compiled master built for Windows x64 (the `stewart-master` command: no Windows CPython
  is here to load the wheel's .pyd) runs the same study under wine on the Windows wheel's
  FMUs: its rows equal Linux's.
"""

import io
import json
import os
import re
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import wheels as W
from test_readme import check_study, check_tour, run_study, run_tour

import platforms as P
from stewart_fmu import study as st

ROOT = W.ROOT
BUILD = W.build_wheels

# A closed loop (the paper's units and heave programme) over feedback gains, dampings and
# communication steps, leg 2 failing at t = 8: 11 runs end ok, 9 with the platform's discard
# (its message quotes the leg forces to 17 digits), so the rows compare statuses, messages and
# every metric.
STUDY = """
[study]
name = "platforms"
system = "closed-loop"
units = "nondimensional"
stop_time = 10.0
step = 0.05
stable_error = 0.01

[fixed]
"controller.heave.centre[3]" = 1.3059496109441155
"controller.heave.amplitude" = 0.2
"scenario.failed_leg" = 2
"scenario.failure_time" = 8.0

[grid]
"controller.G" = [2.0, 10.0]
"controller.D" = [0.79, 1.58]
step = [0.05, 0.2, 0.29, 0.3, 0.58]
"""
# What `stewart-master study` writes of a run's row.
MASTER_ROW = ["status", "message", "discard_time", "max_leg_error", "max_pose_error", "min_kappa", "max_stop_force",
              "energy_residual", "peak_deceleration", "final_z", "landing_deceleration"]
# What a Windows DLL of the compiled master may import: Windows' own DLLs (as the FMUs' DLLs,
# docs/platforms.md) and the stable ABI's python3.dll.
WINDOWS_DLLS = {"kernel32.dll", "ntdll.dll", "msvcrt.dll", "bcryptprimitives.dll", "userenv.dll", "ws2_32.dll",
                "advapi32.dll", "api-ms-win-core-synch-l1-2-0.dll", "python3.dll"}
LINUX_LIBRARIES = {"libc.so.6", "libm.so.6", "libgcc_s.so.1", "ld-linux-x86-64.so.2", "ld-linux-aarch64.so.1"}
ELF_MACHINES = {"x86_64-linux": "Advanced Micro Devices X86-64", "aarch64-linux": "AArch64"}


def elf(path):
    """(machine, needed libraries, newest GLIBC version asked) of an ELF file."""
    header = subprocess.run(["readelf", "-h", str(path)], capture_output=True, text=True, check=True).stdout
    machine = re.search(r"Machine:\s+(.*)", header).group(1).strip()
    dynamic = subprocess.run(["readelf", "-d", "-V", str(path)], capture_output=True, text=True, check=True).stdout
    needed = set(re.findall(r"\(NEEDED\)\s+Shared library: \[([^\]]+)\]", dynamic))
    versions = [tuple(int(x) for x in v.split(".")) for v in re.findall(r"GLIBC_(\d+(?:\.\d+)+)", dynamic)]
    return machine, needed, max(versions)


def fmu_entries(data):
    with zipfile.ZipFile(io.BytesIO(data)) as z:
        return {name: z.read(name) for name in z.namelist()}


def check_fmus(platform, z, names):
    """The wheel's FMUs against target/fmu: the same files, but in the aarch64 wheel the FMI 2
    FMUs' (and the SSP files' copies') linux64 binary is the FMI 3 FMU's aarch64 one."""
    fmu_dir = ROOT / "target" / "fmu"
    aarch64 = BUILD.linux_binaries("aarch64-linux")
    for name in BUILD.PACKAGED:
        inside, here = z.read(f"stewart_fmu/data/fmu/{name}"), (fmu_dir / name).read_bytes()
        if platform != "aarch64-linux" or name.startswith("fmi3/"):
            assert inside == here, name
            continue
        pairs = [(inside, here)] if name.endswith(".fmu") else [
            (fmu_entries(inside)[n], b) for n, b in fmu_entries(here).items() if n.endswith(".fmu")]
        for packed, original in pairs:
            got, want = fmu_entries(packed), fmu_entries(original)
            assert sorted(got) == sorted(want), name
            for entry, body in want.items():
                binary = re.fullmatch(r"binaries/linux64/(\w+)\.so", entry)
                assert got[entry] == (aarch64[binary.group(1)] if binary else body), (name, entry)
                if binary:
                    assert got[entry][:4] == b"\x7fELF" and got[entry][18:20] == (183).to_bytes(2, "little")


def test_each_wheel_carries_its_platforms_master_the_fmus_and_the_licence(tmp_path):
    built = W.wheels()
    version = BUILD.version()
    crates = json.loads(subprocess.run(["cargo", "metadata", "--no-deps", "--format-version", "1"], cwd=ROOT,
                                       capture_output=True, text=True, check=True).stdout)["packages"]
    assert {c["name"]: c["version"] for c in crates} == {c["name"]: version for c in crates}
    for fmu in ["StewartPlatform.fmu", "fmi3/StewartController.fmu", "StewartCueing.fmu"]:
        description = fmu_entries((ROOT / "target" / "fmu" / fmu).read_bytes())["modelDescription.xml"].decode()
        assert f'version="{version}" generationTool="stewart_fmu {version} (build-fmu)"' in description, fmu
    sources = {f"stewart_fmu/{p.name}": p.read_bytes() for p in (ROOT / "python" / "stewart_fmu").glob("*.py")}
    viewer = {f"stewart_fmu/data/viewer/{p.relative_to(BUILD.VIEWER).as_posix()}": p.read_bytes()
              for p in BUILD.VIEWER.rglob("*") if p.is_file()}
    for platform, wheel in built.items():
        tag = BUILD.PLATFORMS[platform][2]
        assert wheel.name == f"stewart_fmu-{version}-cp311-abi3-{tag}.whl"
        with zipfile.ZipFile(wheel) as z:
            names = set(z.namelist())
            info = f"stewart_fmu-{version}.dist-info"
            assert f"Tag: cp311-abi3-{tag}\n" in z.read(f"{info}/WHEEL").decode()
            metadata = z.read(f"{info}/METADATA").decode()
            for line in ("Name: stewart-fmu", f"Version: {version}", "Requires-Python: >=3.11",
                         "License-Expression: MIT", "License-File: LICENSE"):
                assert f"\n{line}\n" in metadata, line
            assert z.read(f"{info}/licenses/LICENSE") == (ROOT / "LICENSE").read_bytes()
            scripts = z.read(f"{info}/entry_points.txt").decode()
            assert "stewart-sweep=stewart_fmu.sweep:main" in scripts
            assert "stewart-master=stewart_fmu.master:main" in scripts
            for name, body in {**sources, **viewer}.items():
                assert z.read(name) == body, name
            check_fmus(platform, z, names)
            extension = "stewart_fmu/_master.pyd" if platform == "x86_64-windows" else "stewart_fmu/_master.abi3.so"
            (tmp_path / platform).mkdir()
            library = tmp_path / platform / Path(extension).name
            library.write_bytes(z.read(extension))
        expected = set(sources) | set(viewer) | {f"stewart_fmu/data/fmu/{n}" for n in BUILD.PACKAGED} | {extension}
        extra = {n for n in names if not n.startswith(info)} - expected
        assert not extra, extra
        if platform == "x86_64-windows":
            dump = subprocess.run(["x86_64-w64-mingw32-objdump", "-p", str(library)], capture_output=True, text=True,
                                  check=True).stdout
            assert "file format pei-x86-64" in dump
            dlls = {d.lower() for d in re.findall(r"DLL Name: (\S+)", dump)}
            assert "python3.dll" in dlls and dlls <= WINDOWS_DLLS, dlls - WINDOWS_DLLS
            needs = f"imports {', '.join(sorted(dlls))}"
        else:
            machine, needed, glibc = elf(library)
            assert machine == ELF_MACHINES[platform]
            assert needed <= LINUX_LIBRARIES and glibc <= (2, 34), (needed, glibc)
            needs = f"{machine}, needs {', '.join(sorted(needed))} (GLIBC_{'.'.join(map(str, glibc))} at most)"
        print(f"{wheel.name}: {wheel.stat().st_size / 1e6:.1f} MB, {len(names)} files: {len(sources)} Python files, "
              f"{Path(extension).name} ({library.stat().st_size / 1e6:.1f} MB; {needs}), {len(BUILD.PACKAGED)} FMUs and "
              f"SSP files ({sum(z.getinfo(f'stewart_fmu/data/fmu/{n}').file_size for n in BUILD.PACKAGED) / 1e6:.1f} MB"
              f"{'; FMI 2 linux64: the aarch64 binary' if platform == 'aarch64-linux' else ''}), the viewer page "
              f"({len(viewer)} files), the licence, version {version}")


@pytest.fixture(scope="module")
def x86_study(tmp_path_factory):
    """The 20-run study with the compiled master on Linux x86-64 (the repository's
    environment, serial): (study file, rows)."""
    folder = tmp_path_factory.mktemp("x86")
    (folder / "platforms.toml").write_text(STUDY)
    run = subprocess.run([str(Path(sys.executable).parent / "stewart-sweep"), "platforms.toml", "--out", "out",
                          "--serial", "--master", "compiled"], cwd=folder, capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-3000:]
    assert "with the compiled master" in run.stdout
    return folder / "platforms.toml", W.rows(folder / "out")


def test_the_aarch64_wheel_runs_the_tour_and_a_study_under_qemu_with_the_numbers_of_x86_64(tmp_path, x86_study):
    bin_dir = W.arm64_install(W.wheels()["aarch64-linux"])
    env = W.arm64_env()
    work = tmp_path / "arm64"
    work.mkdir()
    python = bin_dir / "python"
    probe = subprocess.run([str(python), "-c", "import json, platform, stewart_fmu.master as m, stewart_fmu as s; "
                            "print(json.dumps([platform.machine(), m.available()[0], m._master.__file__, "
                            "str(s.PLATFORM_FMU), platform.python_version()]))"], cwd=work, env=env,
                           capture_output=True, text=True, timeout=600)
    assert probe.returncode == 0, probe.stderr[-3000:]
    machine, available, extension, fmu, python_version = json.loads(probe.stdout.splitlines()[-1])
    assert machine == "aarch64" and available and extension.endswith("_master.abi3.so")
    assert extension.startswith(str(W.ARM64_VENV)) and fmu.startswith(str(W.ARM64_VENV))
    # The README's tour: its Python blocks (FMPy: the platform, the closed loop, motion cueing,
    # the viewer page) and its study (stewart-sweep, two Dask workers on 127.0.0.1, the
    # compiled master), on aarch64 and here.
    arm_tour = run_tour(python, work, env)
    check_tour(arm_tour)
    arm_tour_rows, out = run_study(bin_dir, work, env)
    check_study(arm_tour_rows, out)
    here_env = {k: v for k, v in os.environ.items() if not k.startswith("STEWART_")}
    x86_tour = run_tour(sys.executable, tmp_path, here_env)
    x86_tour_rows, _ = run_study(Path(sys.executable).parent, tmp_path, here_env)
    tour_values = [(a, b) for a, b in zip(flatten(arm_tour), flatten(x86_tour))]
    tour_largest = max(abs(a - b) for a, b in tour_values if isinstance(a, float))
    tour_cells, tour_rows_largest = W.differences(W.rows(out), W.rows(tmp_path / "mass"))
    # The 20-run study with the compiled master.
    study, x86_rows = x86_study
    (work / "platforms.toml").write_text(study.read_text())
    run = subprocess.run([str(bin_dir / "stewart-sweep"), "platforms.toml", "--out", "platforms", "--serial",
                          "--master", "compiled"], cwd=work, env=env, capture_output=True, text=True, timeout=1800)
    assert run.returncode == 0, run.stderr[-3000:]
    assert "with the compiled master" in run.stdout
    arm_rows = W.rows(work / "platforms")
    cells, largest = W.differences(arm_rows, x86_rows)
    print(f"aarch64 wheel (qemu-user, arm64 CPython {python_version}): the README's tour: "
          f"{len(tour_values)} values, the largest difference to x86-64 {tour_largest}; its study: "
          f"{len(arm_tour_rows)} rows, {tour_cells} cells differ (largest difference {tour_rows_largest}); "
          f"20-run study with the compiled master: statuses {arm_rows['status'].value_counts().to_dict()}, "
          f"{arm_rows.size} cells, {cells} differ from x86-64's, the largest difference {largest}")
    assert len(tour_values) == len(flatten(x86_tour)) and arm_tour == x86_tour
    assert tour_cells == 0 and tour_rows_largest == 0.0
    assert len(arm_rows) == 20 and set(arm_rows["status"]) == {"ok", "discard"}
    assert cells == 0 and largest == 0.0


def flatten(value):
    """The numbers and strings of a JSON value, in order."""
    if isinstance(value, dict):
        return [x for k in sorted(value) for x in [k, *flatten(value[k])]]
    if isinstance(value, list):
        return [x for v in value for x in flatten(v)]
    return [float(value) if isinstance(value, (int, float)) and not isinstance(value, bool) else value]


def runs_file(spec, folder):
    """The study's runs as `stewart-master study` lines (study.compiled_point: the points the
    Python extension runs), and the points."""
    fmus = st.fmus_for(spec)
    platform_md, platform_variables = st._description(fmus["platform"])
    variables = {"platform": platform_variables, "controller": st._description(fmus["controller"])[1]}
    points, lines = [], []
    for run in st.runs(spec):
        drive, point = st.compiled_point(spec, run, platform_md, variables)
        assert drive == 0, point
        steps, step, values, overrides = point
        text = lambda v: ("true" if v else "false") if isinstance(v, bool) else repr(v)  # noqa: E731
        lines.append(" ".join([str(steps), repr(step), *(f"{n}={text(v)}" for n, v in values),
                               *(f"{n}={v!r}@{t!r}" for n, v, t in overrides)]))
        points.append((st.run_id(run), point))
    path = folder / "runs.txt"
    path.write_text("\n".join(lines) + "\n")
    return path, points


def test_the_windows_master_runs_the_study_under_wine_with_the_rows_of_linux(tmp_path, x86_study):
    """`stewart-master study` built for Windows x64 (wine 8) on the Windows wheel's
    StewartSystem.ssp (FMI 2, its win64 DLLs) against the Linux extension on the same file and
    points, and against stewart-sweep's rows on Linux."""
    with zipfile.ZipFile(W.wheels()["x86_64-windows"]) as z:
        ssp = tmp_path / "StewartSystem.ssp"
        ssp.write_bytes(z.read("stewart_fmu/data/fmu/StewartSystem.ssp"))
    study, x86_rows = x86_study
    spec = st.load(study)
    runs, points = runs_file(spec, tmp_path)
    exe = W.windows_master()
    P.build_hosts()  # the bcryptprimitives.dll stand-in wine 8 lacks (docs/platforms.md)
    P.ensure_wine_prefix()
    folder = tmp_path / "windows"
    folder.mkdir()
    (folder / exe.name).write_bytes(exe.read_bytes())
    (folder / "bcryptprimitives.dll").write_bytes((P.BUILD / "x86_64-windows" / "bcryptprimitives.dll").read_bytes())
    out = tmp_path / "windows_rows.csv"
    run = subprocess.run([P.WINE, P.windows_path(folder / exe.name), "study", P.windows_path(ssp), "--runs",
                          P.windows_path(runs), "--out", P.windows_path(out)], env=P.wine_environment(),
                         capture_output=True, text=True, timeout=900)
    assert run.returncode == 0, (run.stdout + run.stderr)[-3000:]
    windows = pd.read_csv(out, keep_default_na=False, na_values=["NaN"])
    windows.index = [i for i, _ in points]
    from stewart_fmu import _master
    system = _master.System.from_ssp(str(ssp))
    linux = pd.DataFrame(system.study(True, [p for _, p in points]), index=[i for i, _ in points])
    system.close()
    columns = MASTER_ROW
    extension_cells, extension_largest = W.differences(windows[columns], linux[columns])
    sweep = x86_rows.loc[windows.index, columns]
    sweep_cells, sweep_largest = W.differences(windows[columns], sweep)
    print(f"Windows stewart-master (wine): {len(windows)} runs, statuses {windows['status'].value_counts().to_dict()}; "
          f"against the Linux extension on the same SSP: {extension_cells} of {windows[columns].size} cells differ "
          f"(largest difference {extension_largest}); against stewart-sweep's rows on Linux: {sweep_cells} differ "
          f"(largest {sweep_largest})")
    assert len(windows) == 20 and set(windows["status"]) == {"ok", "discard"}
    assert extension_cells == 0 and extension_largest == 0.0
    assert sweep_cells == 0 and sweep_largest == 0.0
