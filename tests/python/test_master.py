"""The compiled co-simulation master (crates/stewart-master, `stewart_fmu.master`) against the
FMPy master (`stewart_fmu.study._execute`, `stewart_fmu.cosim`): the shipped stability study
(with its discards), payload, power-loss (the platform alone, its forces cut) and workspace
studies, a study with electric drives and a failed leg, and studies of hydraulic legs fed by the
power unit whose pump stops (the shipped accumulator study among them), give the same rows in
every column to the bit; the closed loop gives the same numbers with both schemes; its command line
writes what Python gets and says when an FMU ends a run; on a real Dask cluster on loopback a
worker killed mid-study loses no run and the rows equal the serial run's."""

import math
import os
import signal
import subprocess
import sys
import time
import zipfile
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from stewart_fmu import ROOT, master
from stewart_fmu import study as st
from stewart_fmu.cosim import SYSTEM_SSP, closed_loop
from stewart_fmu.sweep import load_results, run_batch
from test_sweep import cluster, comparable, rows_written, start_cluster  # noqa: F401 - cluster is a fixture

SWEEP = str(Path(sys.executable).parent / "stewart-sweep")
MASTER = str(Path(sys.executable).parent / "stewart-master")


@pytest.mark.quick
def test_the_compiled_master_is_built_and_loads():
    ok, reason = master.available()
    assert ok, reason


def same(a, b):
    return a == b or (isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b))


def compare(spec, runs):
    """Both masters' rows for `runs` in this process: (compiled, fmpy, columns that differ)."""
    fmus = st.fmus_for(spec)
    compiled = run_batch(spec, runs, fmus, "compiled")
    fmpy = run_batch(spec, runs, fmus, "fmpy")
    differ = [(r["run_id"], c, r[c], s[c]) for r, s in zip(compiled, fmpy) for c in r
              if c not in ("wall_time", "worker") and not same(r[c], s[c])]
    return compiled, fmpy, differ


# (study file, runs compared: all, or the first N to keep the FMPy side short)
STUDIES = [("stability.toml", None), ("payload.toml", 24), ("power_loss.toml", None), ("workspace.toml", 12),
           ("accumulator.toml", 1)]


@pytest.mark.parametrize("name,count", STUDIES)
def test_the_shipped_studies_give_the_same_rows_with_both_masters(name, count):
    spec = st.load(ROOT / "studies" / name)
    runs = st.runs(spec)[:count]
    compiled, fmpy, differ = compare(spec, runs)
    statuses = pd.Series([r["status"] for r in compiled]).value_counts().to_dict()
    print(f"{name}: {len(runs)} runs ({statuses}); columns that differ between the masters: {len(differ)}; "
          f"mean run {np.mean([r['wall_time'] for r in compiled]) * 1e3:.1f} ms compiled, "
          f"{np.mean([r['wall_time'] for r in fmpy]) * 1e3:.1f} ms FMPy")
    assert len(compiled) == len(fmpy) == len(runs)
    assert not differ, differ[:5]
    if name == "stability.toml":
        # A study with discards: the step limit ends runs, with the FMU's message and time.
        discards = [r for r in compiled if r["status"] == "discard"]
        assert len(discards) > 10 and all("base plane" in r["message"] for r in discards)
        assert all(r["discard_time"] > 0 for r in discards) and any(r["status"] == "ok" for r in compiled)
    if name == "power_loss.toml":
        assert all(r["status"] == "ok" and r["peak_deceleration"] > 0 for r in compiled)
    if name == "accumulator.toml":
        # 20 L precharged to 4.5 MPa: the supply falls, the controller lands the stand; the
        # balance of docs/model.md §10b (work.pump) holds to the integration's tolerance.
        r = compiled[0]
        print(f"accumulator study, first point: lowest supply {r['min_supply_pressure'] / 1e6:.3f} MPa, upward "
              f"acceleration after the stop {r['landing_deceleration']:.3f} m/s2, final z {r['final_z']:.4f} m, "
              f"energy residual {r['energy_residual']:.2e} J")
        assert r["status"] == "ok" and r["min_supply_pressure"] < 12.0e6 and r["final_z"] < 1.6
        assert r["energy_residual"] < 1e-6 and 0.0 < r["landing_deceleration"] < 10.0


DRIVES = """
[study]
name = "drives"
system = "closed-loop"
units = "si"
stop_time = 1.5
step = 0.002
stable_error = 0.01

[fixed]
"platform.drive" = 1
"controller.drive" = 1
"scenario.failure_time" = 0.5

[grid]
"scenario.failed_leg" = [1, 4]
"platform.M" = [2500.0, 3500.0]
"""


def test_a_drives_study_with_a_failed_leg_gives_the_same_rows_with_both_masters(tmp_path):
    """The voltages' coupling (StewartSystemDrives.ssp) with a leg's voltage cut at 0.5 s."""
    path = tmp_path / "drives.toml"
    path.write_text(DRIVES)
    spec = st.load(path)
    runs = st.runs(spec)
    compiled, _, differ = compare(spec, runs)
    print(f"drives study: {len(runs)} runs, statuses {[r['status'] for r in compiled]}, max leg errors "
          f"{[round(r['max_leg_error'], 6) for r in compiled]} m; columns that differ: {len(differ)}")
    assert not differ, differ[:5]
    assert all(r["status"] == "ok" for r in compiled)
    # The failed leg is felt: it no longer follows its programme.
    assert all(r["max_leg_error"] > 1e-3 for r in compiled)
    # The balance with the drives' electric work (docs/model.md §9): 1.2e-6 J measured.
    assert all(r["energy_residual"] < 1e-4 for r in compiled), [r["energy_residual"] for r in compiled]


POWER_UNIT = """
[study]
name = "pump_stop"
system = "closed-loop"
units = "si"
stop_time = 1.5
step = 0.001

[fixed]
"platform.drive" = 2
"controller.drive" = 2
"controller.landing.pressure" = 12.0e6
"scenario.pump_stop_at" = 0.3

[grid]
"platform.hydraulic.supply" = [0, 1]
"platform.accumulator.volume" = [2.0e-3, 40.0e-3]
"""


def test_a_pump_stop_study_gives_the_same_rows_with_both_masters(tmp_path):
    """Hydraulic legs (StewartSystemHydraulic.ssp's valve commands, the pressures and the supply
    pressure measured) on the power unit, its pump stopped at 0.3 s (`pump.speed` set by the
    master, an input no connection drives): the same rows to the bit, the balance of
    docs/model.md §10b in `energy_residual`, a small accumulator's supply lower than a large
    one's; with the ideal supply the pump stop is refused by name."""
    path = tmp_path / "pump_stop.toml"
    path.write_text(POWER_UNIT)
    spec = st.load(path)
    runs = st.runs(spec)
    compiled, _, differ = compare(spec, runs)
    rows = {(r["run_id"]): r for r in compiled}
    by = {(int(run["platform.hydraulic.supply"]), run["platform.accumulator.volume"]): rows[st.run_id(run)]
          for run in runs}
    for key, r in sorted(by.items()):
        print(f"supply {key[0]}, accumulator {key[1] * 1e3:.0f} L: {r['status']} {r['message'][:60]!r} lowest supply "
              f"{r['min_supply_pressure'] / 1e6:.3f} MPa, upward acceleration after the stop "
              f"{r['landing_deceleration']:.3f} m/s2, energy residual {r['energy_residual']:.2e} J")
    assert not differ, differ[:5]
    for volume in (2.0e-3, 40.0e-3):
        assert by[(0, volume)]["status"] == "error" and "hydraulic.supply = 1" in by[(0, volume)]["message"]
        assert by[(1, volume)]["status"] == "ok"
    # The 2 L accumulator empties and the supply collapses (a stiff passage for the default
    # adaptive method at its tolerance); the 40 L one keeps the supply up.
    assert by[(1, 2.0e-3)]["energy_residual"] < 1e-2 and by[(1, 40.0e-3)]["energy_residual"] < 1e-6
    assert by[(1, 2.0e-3)]["min_supply_pressure"] < by[(1, 40.0e-3)]["min_supply_pressure"] - 1e6
    # The ideal supply (work.hydraulic in the balance) with a valve's command cut at 0.3 s.
    path.write_text(POWER_UNIT.replace('"scenario.pump_stop_at" = 0.3', '"scenario.failed_leg" = 2\n'
                                       '"scenario.failure_time" = 0.3').split("[grid]")[0])
    spec = st.load(path)
    compiled, _, differ = compare(spec, st.runs(spec))
    r = compiled[0]
    print(f"ideal supply, valve 2 cut at 0.3 s: {r['status']}, largest leg error {r['max_leg_error'] * 1e3:.2f} mm, "
          f"supply {r['min_supply_pressure'] / 1e6:.1f} MPa, energy residual {r['energy_residual']:.2e} J; "
          f"columns that differ: {len(differ)}")
    assert not differ, differ[:5]
    assert r["status"] == "ok" and r["energy_residual"] < 1e-6 and r["max_leg_error"] > 1e-3
    assert r["min_supply_pressure"] == 16.0e6 and r["landing_deceleration"] >= 0.0


@pytest.mark.quick
@pytest.mark.parametrize("scheme", ["gauss-seidel", "jacobi"])
def test_the_closed_loop_is_the_fmpy_masters_to_the_bit(scheme):
    record = ("r[3]", "E", "F[1]")
    t1, rows1, errors1, status1 = master.closed_loop(3.0, 1e-3, scheme, record=record)
    t2, rows2, errors2, status2 = closed_loop(3.0, 1e-3, scheme, record=record)
    print(f"closed loop, 3 s at 1 ms, {scheme}: {len(t1)} points, largest leg error {errors1.max() * 1e3:.4f} mm, "
          f"same numbers as stewart_fmu.cosim: {np.array_equal(rows1, rows2) and np.array_equal(errors1, errors2)}")
    assert status1 == status2 == "ok"
    assert np.array_equal(t1, t2) and np.array_equal(rows1, rows2) and np.array_equal(errors1, errors2)


@pytest.mark.quick
def test_the_command_line_writes_what_python_gets_and_reports_a_discard(tmp_path):
    out = tmp_path / "heave.csv"
    run = subprocess.run([MASTER, "run", str(SYSTEM_SSP), "--stop-time", "2", "--step", "0.001", "--record",
                          "platform.r[3]", "--record", "controller.F[1]", "--interval", "0.01", "--out", str(out)],
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    table = pd.read_csv(out)
    system = master.from_ssp(SYSTEM_SSP)
    times, rows, status, _ = master.run(system, 2.0, 0.001, record=["platform.r[3]", "controller.F[1]"],
                                        interval=0.01)
    print(f"stewart-master run: {run.stderr.strip()}; {len(table)} rows, equal to Python's: "
          f"{np.array_equal(table.to_numpy()[:, 1:], rows)}")
    assert status == "ok" and len(table) == 200
    assert np.array_equal(table["time"].to_numpy(), times) and np.array_equal(table.to_numpy()[:, 1:], rows)
    # A point of the stability study that the platform discards (a step beyond the loop's
    # limit): the command ends it with exit status 1 and the FMU's message, as the study's row
    # (not the same bits: the command applies the SSP's bindings first and sums the time).
    spec = st.load(ROOT / "studies" / "stability.toml")
    fmus = st.fmus_for(spec)
    point = next(r for r in st.runs(spec) if float(r["step"]) >= 0.3)
    row = run_batch(spec, [point], fmus, "fmpy")[0]
    platform_md, _ = st._description(fmus["platform"])
    platform, controller = st._parameters(spec, point, platform_md)
    sets = [a for role, values in (("platform", platform), ("controller", controller)) for k, v in values.items()
            for a in ("--set", f"{role}.{k}={v!r}")]
    bad = subprocess.run([MASTER, "run", str(SYSTEM_SSP), "--stop-time", str(spec["study"]["stop_time"]), "--step",
                          str(point["step"]), *sets], capture_output=True, text=True)
    print(f"stability point {point}: FMPy master's row {row['status']} at t = {row['discard_time']}: "
          f"{row['message']}; stewart-master: exit {bad.returncode}: {bad.stderr.strip()}")
    assert row["status"] == "discard"
    assert bad.returncode == 1 and "fmi2DoStep failed with status 2 (discard)" in bad.stderr
    assert "passed through the base plane" in row["message"] and "passed through the base plane" in bad.stderr
    wrong = subprocess.run([MASTER, "run", str(SYSTEM_SSP), "--stop-time", "1", "--step", "0.001", "--set",
                            "platform.nonsense=1"], capture_output=True, text=True)
    assert wrong.returncode == 2 and "nonsense" in wrong.stderr


def test_a_bad_value_is_the_runs_error_row_not_the_batchs(tmp_path):
    """One point the FMU refuses (a negative mass) among good ones: its row says why, the others run."""
    spec = st.load(ROOT / "studies" / "power_loss.toml")
    runs = st.runs(spec)[:3]
    runs[1] = {**runs[1], "platform.M": -1.0}
    compiled, fmpy, differ = compare(spec, runs)
    print(f"a negative mass: {compiled[1]['status']}: {compiled[1]['message']}")
    assert [r["status"] for r in compiled] == ["ok", "error", "ok"]
    assert compiled[1]["message"] and not differ


STUDY = """
[study]
name = "long"
system = "closed-loop"
units = "nondimensional"
stop_time = 300.0
step = 0.01
stable_error = 0.01

[fixed]
"controller.heave.centre[3]" = 1.3059496109441155
"controller.heave.amplitude" = 0.2

[grid]
"controller.G" = [5.0, 10.0, 20.0, 50.0]

[random]
samples = 10
seed = 11
"controller.D" = { uniform = [1.0, 3.0] }
"""


def test_a_killed_worker_loses_no_run_of_the_compiled_master(tmp_path, cluster):  # noqa: F811
    """stewart-sweep (the compiled master, runs in batches) on two workers, one killed mid-study:
    every run once, the rows equal the serial run's."""
    study = tmp_path / "long.toml"
    study.write_text(STUDY)
    serial = subprocess.run([SWEEP, str(study), "--out", str(tmp_path / "serial"), "--serial"], capture_output=True,
                            text=True)
    assert serial.returncode == 0, serial.stderr[-3000:]
    assert "with the compiled master" in serial.stdout
    address, workers = cluster
    out = tmp_path / "cluster"
    sweep = subprocess.Popen([SWEEP, str(study), "--out", str(out), "--scheduler", address],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    while rows_written(out) < 4 and sweep.poll() is None and time.monotonic() < deadline:
        time.sleep(0.02)
    written_at_kill = rows_written(out)
    os.killpg(workers[0].pid, signal.SIGKILL)
    stdout, stderr = sweep.communicate(timeout=300)
    assert sweep.returncode == 0, stderr[-3000:]
    rows = load_results(out)
    print(f"{len(rows)}-run study (30,000 steps a run) on 2 workers, one killed after {written_at_kill} rows: "
          f"{len(rows)} rows, run ids unique {rows['run_id'].is_unique}; {stdout.splitlines()[-0]}")
    assert written_at_kill < 40, "the kill came after the study had finished: make the runs longer"
    assert len(rows) == 40 and rows["run_id"].is_unique
    assert (rows["status"] == "ok").all()
    pd.testing.assert_frame_equal(comparable(rows), comparable(load_results(tmp_path / "serial")))


# A platform FMU whose binary crashes: a shim library in front of the real one (which it loads
# as a dependency) that writes through a null pointer in fmi2DoStep, 50 steps into a run whose
# platform mass was set to TRIGGER; every other call is the real FMU's.
CRASHING_SHIM = r"""
#define _GNU_SOURCE
#include <dlfcn.h>
#include <stddef.h>
typedef int status_t;
static int armed;
static long steps;
status_t fmi2SetReal(void *c, const unsigned int vr[], size_t n, const double value[]) {
    static status_t (*real)(void *, const unsigned int *, size_t, const double *);
    if (!real) real = (status_t (*)(void *, const unsigned int *, size_t, const double *))dlsym(RTLD_NEXT, "fmi2SetReal");
    for (size_t i = 0; i < n; i++)
        if (vr[i] == MASS_VR) { armed = value[i] == TRIGGER; steps = 0; }
    return real(c, vr, n, value);
}
status_t fmi2DoStep(void *c, double t, double h, int no_prior) {
    static status_t (*real)(void *, double, double, int);
    if (!real) real = (status_t (*)(void *, double, double, int))dlsym(RTLD_NEXT, "fmi2DoStep");
    if (armed && ++steps > 50) {
        volatile int *volatile nowhere = NULL;
        *nowhere = 1;
    }
    return real(c, t, h, no_prior);
}
"""
TRIGGER = 1.25
# 18 runs on 2 workers: batches of 3 (sweep.batches), so that the crashing run takes two others
# down with it.
MASSES = [round(1.0 + 0.01 * i, 2) for i in range(8)] + [TRIGGER] + [round(1.08 + 0.01 * i, 2) for i in range(9)]


def crashing_platform_fmu(folder):
    """StewartPlatform.fmu with the crashing shim as its binary (the real one beside it)."""
    from fmpy import read_model_description
    from stewart_fmu.core import PLATFORM_FMU
    mass_vr = next(v.valueReference for v in read_model_description(str(PLATFORM_FMU)).modelVariables if v.name == "M")
    unpacked = folder / "unpacked"
    with zipfile.ZipFile(PLATFORM_FMU) as z:
        z.extractall(unpacked)
    binaries = unpacked / "binaries" / "linux64"
    (binaries / "StewartPlatform.so").rename(binaries / "StewartPlatformInside.so")
    (folder / "shim.c").write_text(CRASHING_SHIM)
    subprocess.run(["gcc", "-shared", "-fPIC", "-O1", f"-DMASS_VR={mass_vr}u", f"-DTRIGGER={TRIGGER!r}",
                    "-o", str(binaries / "StewartPlatform.so"), str(folder / "shim.c"), f"-L{binaries}", "-Wl,--no-as-needed",
                    "-l:StewartPlatformInside.so", "-Wl,-rpath,$ORIGIN", "-ldl"], check=True)
    fmu = folder / "crash" / "StewartPlatform.fmu"
    fmu.parent.mkdir()
    with zipfile.ZipFile(fmu, "w", zipfile.ZIP_DEFLATED) as z:
        for path in sorted(unpacked.rglob("*")):
            if path.is_file():
                z.write(path, path.relative_to(unpacked).as_posix())
    return fmu


CRASH_STUDY = """
[study]
name = "crash"
system = "closed-loop"
units = "nondimensional"
stop_time = 3.0
step = 0.01
stable_error = 0.01

[fixed]
"controller.heave.centre[3]" = 1.3059496109441155
"controller.heave.amplitude" = 0.2
"controller.heave.frequency" = 1.0
"controller.heave.timeConstant" = 2.0
"controller.G" = 10.0
"controller.D" = 1.58

[grid]
"platform.M" = [MASSES]
""".replace("MASSES", ", ".join(map(repr, MASSES)))


def test_an_fmu_that_crashes_its_worker_is_that_runs_error_row(tmp_path):
    """A segmentation fault inside the platform FMU's fmi2DoStep (a shim binary in front of the
    real one) in one run of a compiled-master study on a Dask cluster on loopback: the worker
    process dies (its nanny starts a new one), Dask gives the task to the other worker once
    (allowed-failures 1), which dies too; Dask blames every task the dying workers held, so
    stewart-sweep runs each blamed run again at the end, alone on the cluster: the crashing run
    ends as its own error row saying that the worker died, every other run is a row equal to the
    serial run's, and the workers' log has Python's fault report. 18 runs: batches of three, so
    that the crashing run takes two innocent ones down with it."""
    fmu = crashing_platform_fmu(tmp_path)
    from stewart_fmu.core import CONTROLLER_FMU
    study = tmp_path / "crash.toml"
    study.write_text(CRASH_STUDY)
    # The serial reference without the crashing run (in this process it would end the process).
    serial_study = tmp_path / "serial.toml"
    serial_study.write_text(CRASH_STUDY.replace(f", {TRIGGER!r}", ""))
    assert str(TRIGGER) not in serial_study.read_text()
    serial = subprocess.run([SWEEP, str(serial_study), "--out", str(tmp_path / "serial"), "--serial", "--fmu", str(fmu),
                             "--controller-fmu", str(CONTROLLER_FMU)], capture_output=True, text=True)
    assert serial.returncode == 0, serial.stderr[-3000:]
    log = tmp_path / "workers.log"
    cluster = start_cluster(tmp_path, worker_log=log, DASK_DISTRIBUTED__SCHEDULER__ALLOWED_FAILURES="1")
    address, _ = next(cluster)
    try:
        started = time.monotonic()
        sweep = subprocess.run([SWEEP, str(study), "--out", str(tmp_path / "cluster"), "--scheduler", address,
                                "--fmu", str(fmu), "--controller-fmu", str(CONTROLLER_FMU)], capture_output=True,
                               text=True, timeout=600)
        seconds = time.monotonic() - started
    finally:
        next(cluster, None)
    assert sweep.returncode == 0, sweep.stderr[-3000:]
    rows = load_results(tmp_path / "cluster")
    crashed = rows[rows["param:platform.M"] == TRIGGER]
    print(f"a run that crashes its worker ({seconds:.0f} s for the study): {len(rows)} rows, statuses "
          f"{rows['status'].value_counts().to_dict()}; its row: {list(crashed['message'])!r}")
    assert len(rows) == len(MASSES) and rows["run_id"].is_unique
    assert list(crashed["status"]) == ["error"]
    assert "worker process died" in crashed["message"].iloc[0]
    others = rows[rows["param:platform.M"] != TRIGGER]
    assert (others["status"] == "ok").all()
    pd.testing.assert_frame_equal(comparable(others), comparable(load_results(tmp_path / "serial")))
    report = log.read_text()
    assert "Fatal Python error: Segmentation fault" in report, report[-3000:]
