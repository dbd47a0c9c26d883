"""Leaks and memory errors: a C host (tests/c/leak_host.c) runs 1000 instantiate/step/free
cycles with the error, discard and FMU-state paths and unloads and reloads the library every
100 cycles, under valgrind's memcheck, against the binary from the packaged FMU, first in one
thread, then in four threads at once; the library must leave the process at the end. Stale
instance handles, an instance freed from the host's logger callback during a call and FMU
states freed through the wrong instance are refused without reading freed memory. And
FMPy loads, instantiates, frees and unloads the FMU hundreds of times in one process."""

import re
import shutil
import subprocess
import zipfile

import pytest
from fmpy import read_model_description

from stewart_fmu import PLATFORM_FMU, ROOT, Platform


# (threads, cycles): the host's cycles repeat every 70 (each tenth a path: an error and reset, a
# discard, a corrupted state, a state freed through another instance, an instance freed from the
# logger; every seventh with logging) and load the library again every 100; one thread covers
# every combination four times and reloads twice in 300 cycles; four threads need 1000 to
# reload each.
@pytest.mark.parametrize("threads, cycles", [(1, 300), (4, 1000)])
def test_valgrind_reports_no_leaks_and_no_invalid_accesses(tmp_path, threads, cycles):
    valgrind, gcc = shutil.which("valgrind"), shutil.which("gcc")
    if not valgrind or not gcc:
        pytest.fail("valgrind and gcc are needed (tests/run_all.sh installs valgrind with apt-get)")
    with zipfile.ZipFile(PLATFORM_FMU) as z:
        z.extract("binaries/linux64/StewartPlatform.so", tmp_path)
    library = tmp_path / "binaries" / "linux64" / "StewartPlatform.so"
    host = tmp_path / "leak_host"
    subprocess.run([gcc, "-O1", "-g", "-Wall", "-Wextra", "-Werror", "-o", str(host), str(ROOT / "tests" / "c" / "leak_host.c"),
                    "-ldl", "-lpthread"], check=True)
    guid = read_model_description(str(PLATFORM_FMU)).guid
    run = subprocess.run([valgrind, "--leak-check=full", "--error-exitcode=99", str(host), str(library), guid, str(cycles),
                          str(threads)], capture_output=True, text=True)
    report = run.stderr
    summary = [line.split("== ", 1)[-1] for line in report.splitlines()
               if re.search(r"(definitely|indirectly|possibly) lost:|ERROR SUMMARY|in use at exit|All heap", line)]
    print(run.stdout.strip())
    print("\n".join(summary))
    assert run.returncode == 0, report[-3000:]
    assert f"cycles {cycles} in {threads} threads:" in run.stdout and f"discarded {cycles // 10}" in run.stdout
    assert "library unloaded at the end: yes" in run.stdout
    # Stale handles after a free, an instance freed from the host's logger during a call, and
    # a state freed through another instance: each refused, and (below) no invalid read.
    assert (f"stale handles refused {cycles * 9 // 10}, freed from the logger during a call {cycles // 10}, states "
            f"freed by another instance refused {cycles // 10}") in run.stdout
    # Unloaded, the library leaves nothing behind: every heap block is freed.
    assert re.search(r"All heap blocks were freed -- no leaks are possible", report), report[-3000:]
    assert re.search(r"ERROR SUMMARY: 0 errors", report), report[-3000:]


def test_fmpy_load_instantiate_free_unload_cycles():
    """FMPy's freeInstance() also dlcloses the library: every cycle unloads and reloads it."""
    for i in range(300):
        pl = Platform(name=f"cycle{i}")
        pl.step(0.01)
        assert abs(pl.get("r[3]")[0] - 1.9589244164161732) < 1e-12
        pl.free()


@pytest.mark.parametrize("method", ["rk4", "dopri5"])
def test_valgrind_runs_the_electric_drives(tmp_path, method):
    """The electric drives' steps (their own lanes code, the exponential RK4) under memcheck:
    300 cycles of the cycle bench's host (benches/c/cycle_host.c, CYCLE_SCENARIO=drives) with
    no memory error, and no instruction valgrind cannot decode (LLVM can emit AVX forms that
    valgrind 3.19 lacks; this is where they would show)."""
    valgrind, gcc = shutil.which("valgrind"), shutil.which("gcc")
    if not valgrind or not gcc:
        pytest.fail("valgrind and gcc are needed (tests/run_all.sh installs valgrind with apt-get)")
    with zipfile.ZipFile(PLATFORM_FMU) as z:
        z.extract("binaries/linux64/StewartPlatform.so", tmp_path)
    library = tmp_path / "binaries" / "linux64" / "StewartPlatform.so"
    host = tmp_path / "cycle_host"
    subprocess.run([gcc, "-O1", "-g", "-o", str(host), str(ROOT / "benches" / "c" / "cycle_host.c"), "-ldl", "-lpthread"],
                   check=True)
    guid = read_model_description(str(PLATFORM_FMU)).guid
    run = subprocess.run([valgrind, "--error-exitcode=99", str(host), "fmi2", str(library), guid, method, "count", "300"],
                         capture_output=True, text=True, env={"CYCLE_SCENARIO": "drives", "PATH": "/usr/bin:/bin"})
    print(run.stdout.strip(), [line for line in run.stderr.splitlines() if "ERROR SUMMARY" in line])
    assert run.returncode == 0, run.stderr[-3000:]
    assert "unhandled instruction" not in run.stderr and "ERROR SUMMARY: 0 errors" in run.stderr
    # The held voltages keep the default stand near its neutral legs (1.755 m).
    leg = float(re.search(r"final leg 1: ([\d.]+) m", run.stdout).group(1))
    assert abs(leg - 1.7550860729486566) < 1e-3
