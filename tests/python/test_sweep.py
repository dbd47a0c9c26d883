"""Design studies on a real Dask cluster on loopback (a `dask scheduler` and two `dask worker`
processes started here, no mocks): a 40-run study through `stewart-sweep --scheduler` with one
worker killed mid-study gives every row once, equal to the serial run's rows; an interrupted
study resumes without running anything twice; the shipped stability study reproduces the
communication-step limit of docs/control.md. The serial runs use the default (compiled) master,
the interrupted and the killed-worker runs the FMPy master: their rows are equal."""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd
import pytest

from stewart_fmu import ROOT
from stewart_fmu.sweep import load_results

SWEEP = str(Path(sys.executable).parent / "stewart-sweep")
DASK = str(Path(sys.executable).parent / "dask")

STUDY = """
[study]
name = "forty"
system = "closed-loop"
units = "nondimensional"
stop_time = 20.0
step = 0.01
stable_error = 0.01

[fixed]
"controller.heave.centre[3]" = 1.3059496109441155
"controller.heave.amplitude" = 0.2

[grid]
"controller.G" = [2.0, 5.0, 10.0, 20.0]

[random]
samples = 10
seed = 7
"controller.D" = { uniform = [0.0, 2.0] }
"platform.M" = { normal = [1.0, 0.05] }
"""


def comparable(frame):
    """The rows without where and how long they ran, in run-id order."""
    return frame.drop(columns=["wall_time", "worker"]).sort_values("run_id").reset_index(drop=True)


def rows_written(out):
    return len(load_results(out))


@pytest.fixture
def study_file(tmp_path):
    path = tmp_path / "forty.toml"
    path.write_text(STUDY)
    return path


@pytest.fixture(scope="module")
def serial_rows(tmp_path_factory):
    folder = tmp_path_factory.mktemp("serial")
    path = folder / "forty.toml"
    path.write_text(STUDY)
    run = subprocess.run([SWEEP, str(path), "--out", str(folder / "out"), "--serial"], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr[-2000:]
    rows = load_results(folder / "out")
    assert len(rows) == 40 and rows["run_id"].is_unique
    return comparable(rows)


@pytest.fixture
def cluster(tmp_path):
    """A scheduler and two single-threaded worker processes on 127.0.0.1."""
    yield from start_cluster(tmp_path)


def start_cluster(tmp_path, worker_log=None, **config):
    """A scheduler and two single-threaded worker processes (each under its nanny, which
    restarts it when it dies) on 127.0.0.1; `config`: Dask settings as environment variables
    (DASK_...); `worker_log`: a file for the workers' standard error."""
    scheduler_file = tmp_path / "scheduler.json"
    env = dict(os.environ, DASK_DISTRIBUTED__WORKER__DAEMON="False", **config)
    scheduler = subprocess.Popen([DASK, "scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                                  "--scheduler-file", str(scheduler_file)], stdout=subprocess.DEVNULL,
                                 stderr=subprocess.DEVNULL, env=env)
    for _ in range(300):
        if scheduler_file.exists() and scheduler_file.stat().st_size > 0:
            break
        time.sleep(0.1)
    import json
    address = json.loads(scheduler_file.read_text())["address"]
    log = open(worker_log, "a") if worker_log else subprocess.DEVNULL
    workers = [subprocess.Popen([DASK, "worker", address, "--nworkers", "1", "--nthreads", "1", "--no-dashboard",
                                 "--host", "127.0.0.1", "--name", f"w{i}"], stdout=subprocess.DEVNULL, stderr=log,
                                env=env, start_new_session=True) for i in range(2)]
    try:
        from distributed import Client
        with Client(address, timeout=60) as client:
            client.wait_for_workers(2, timeout=60)
        yield address, workers
    finally:
        for p in workers + [scheduler]:
            if p.poll() is None:
                os.killpg(p.pid, signal.SIGKILL) if p in workers else p.kill()
            p.wait()
        if worker_log:
            log.close()


def test_a_killed_worker_loses_nothing_and_rows_equal_the_serial_run(study_file, tmp_path, cluster, serial_rows):
    address, workers = cluster
    out = tmp_path / "cluster"
    # The FMPy master, one run a task (the compiled master's batches: test_master.py); the
    # serial rows are the compiled master's, so the rows of the two masters are compared too.
    sweep = subprocess.Popen([SWEEP, str(study_file), "--out", str(out), "--scheduler", address, "--master", "fmpy"],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    while rows_written(out) < 6 and sweep.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)
    written_at_kill = rows_written(out)
    os.killpg(workers[0].pid, signal.SIGKILL)  # the worker process and its nanny
    stdout, stderr = sweep.communicate(timeout=300)
    assert sweep.returncode == 0, stderr[-3000:]
    rows = load_results(out)
    print(f"40-run study on 2 workers, one killed after {written_at_kill} rows were written: {len(rows)} rows, "
          f"run ids unique {rows['run_id'].is_unique}, workers seen {sorted(rows['worker'].unique())}")
    assert written_at_kill < 40, "the kill came after the study had finished: make the runs longer"
    assert len(rows) == 40 and rows["run_id"].is_unique
    pd.testing.assert_frame_equal(comparable(rows), serial_rows)


def test_an_interrupted_study_resumes_without_running_anything_twice(study_file, tmp_path, serial_rows):
    out = tmp_path / "resume"
    # Interrupted under the FMPy master, resumed under the compiled one: one results file.
    first = subprocess.Popen([SWEEP, str(study_file), "--out", str(out), "--serial", "--master", "fmpy"],
                             stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    while rows_written(out) < 5 and first.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)
    first.kill()
    first.wait()
    done = rows_written(out)
    second = subprocess.run([SWEEP, str(study_file), "--out", str(out), "--workers", "2"], capture_output=True,
                            text=True)
    assert second.returncode == 0, second.stderr[-3000:]
    print(f"interrupted after {done} rows; the second call: {second.stdout.splitlines()[0]}")
    assert 0 < done < 40
    assert f"{done} done already, running {40 - done}" in second.stdout
    rows = load_results(out)
    assert len(rows) == 40 and rows["run_id"].is_unique
    pd.testing.assert_frame_equal(comparable(rows), serial_rows)


def test_the_stability_study_reproduces_the_communication_step_limit(tmp_path):
    """studies/stability.toml, G = 10 and D = 1.58 only: stable at a step of 0.29, not at 0.30."""
    out = tmp_path / "stability"
    run = subprocess.run([SWEEP, str(ROOT / "studies" / "stability.toml"), "--out", str(out), "--workers", "2"],
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr[-3000:]
    rows = load_results(out)
    pick = rows[(rows["param:controller.G"] == 10.0) & (rows["param:controller.D"] == 1.58)].set_index("param:step")
    print(f"stability study: {len(rows)} runs, {int(rows['stable'].sum())} stable; G = 10, D = 1.58: "
          f"stable at steps {sorted(pick.index[pick['stable']])}")
    assert len(rows) == 132
    assert pick.loc[0.29, "stable"] and not pick.loc[0.30, "stable"]
    assert pick.loc[0.30, "status"] == "discard" and "base plane" in pick.loc[0.30, "message"]
    assert (out / "stability_map.png").stat().st_size > 10_000


# ----- issue 28: failed runs, the lock, --out and --scheduler problems -----------------------------

FAILING = """
[study]
name = "failing"
system = "closed-loop"
units = "nondimensional"
stop_time = 0.05
step = 0.01

[grid]
"platform.M" = [-1.0, -2.0]
"""


def test_a_study_whose_every_run_fails_exits_non_zero_with_the_first_error_and_resumes(tmp_path):
    """Every run refused by the FMU: rows with the message, exit 1 with the first error; the
    same command again runs nothing, says the same and does not crash."""
    path = tmp_path / "failing.toml"
    path.write_text(FAILING)
    out = tmp_path / "out"
    for attempt in range(2):
        run = subprocess.run([SWEEP, str(path), "--out", str(out), "--serial"], capture_output=True, text=True,
                             timeout=120)
        print(f"call {attempt + 1}: exit {run.returncode}; {run.stdout.splitlines()[0]}; {run.stderr.strip()[-300:]}")
        assert run.returncode == 1, run.stdout + run.stderr
        assert "Traceback" not in run.stderr
        assert "every run failed (2 of 2); the first error: " in run.stderr
        assert "parameter M: mass must be positive, got -1" in run.stderr and "platform.M = -1.0" in run.stderr
        assert f"2 runs, {2 * attempt} done already, running {2 - 2 * attempt}" in run.stdout
    rows = load_results(out)
    assert len(rows) == 2 and rows["run_id"].is_unique and set(rows["status"]) == {"error"}
    assert rows["message"].str.contains("mass must be positive").all()


def test_a_study_with_some_failed_runs_exits_zero_and_names_the_first_error(tmp_path):
    path = tmp_path / "mixed.toml"
    path.write_text(FAILING.replace("[-1.0, -2.0]", "[1.0, -2.0]"))
    run = subprocess.run([SWEEP, str(path), "--out", str(tmp_path / "out"), "--serial"], capture_output=True,
                         text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    assert "first error: fmi2ExitInitializationMode: parameter M: mass must be positive, got -2" in run.stdout


def test_two_sweeps_on_one_out_run_one_at_a_time(study_file, tmp_path):
    """The second sweep on the same --out is refused while the first runs, naming it; the
    first writes every row once."""
    out = tmp_path / "shared"
    # Interrupted under the FMPy master, resumed under the compiled one: one results file.
    first = subprocess.Popen([SWEEP, str(study_file), "--out", str(out), "--serial", "--master", "fmpy"],
                             stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    while rows_written(out) < 1 and first.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)
    second = subprocess.run([SWEEP, str(study_file), "--out", str(out), "--workers", "2"], capture_output=True,
                            text=True, timeout=300)
    still_running = first.poll() is None
    first.communicate(timeout=300)
    print(f"second sweep while the first ran: exit {second.returncode}: {second.stderr.strip()}")
    assert still_running, "the first sweep ended before the second started: make the study longer"
    assert first.returncode == 0
    assert second.returncode == 2 and "Traceback" not in second.stderr
    assert f"is in use by another stewart-sweep (pid {first.pid} on " in second.stderr
    rows = load_results(out)
    assert len(rows) == 40 and rows["run_id"].is_unique
    assert not (out / ".stewart-sweep.lock").exists()


def test_the_lock_of_a_killed_sweep_does_not_block_the_next(study_file, tmp_path):
    out = tmp_path / "killed"
    # The FMPy master: slow enough to be killed mid-study.
    first = subprocess.Popen([SWEEP, str(study_file), "--out", str(out), "--serial", "--master", "fmpy"],
                             stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 120
    while rows_written(out) < 3 and first.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)
    first.kill()
    first.wait()
    lock = out / ".stewart-sweep.lock"
    assert f'"pid": {first.pid}' in lock.read_text()
    second = subprocess.run([SWEEP, str(study_file), "--out", str(out), "--serial"], capture_output=True, text=True,
                            timeout=300)
    assert second.returncode == 0, second.stderr
    assert f"the lock of a sweep that ended without releasing it (pid {first.pid}" in second.stderr
    rows = load_results(out)
    assert len(rows) == 40 and rows["run_id"].is_unique


def test_out_that_is_a_file_or_read_only_gets_a_message(study_file, tmp_path):
    afile = tmp_path / "afile"
    afile.write_text("not a folder")
    run = subprocess.run([SWEEP, str(study_file), "--out", str(afile), "--serial"], capture_output=True, text=True,
                         timeout=60)
    assert run.returncode == 2 and "Traceback" not in run.stderr
    assert f"--out {afile} is a file, not a folder" in run.stderr
    readonly = tmp_path / "readonly"
    readonly.mkdir()
    # root writes through permission bits: make the folder immutable instead
    made = subprocess.run(["chattr", "+i", str(readonly)], capture_output=True) if os.geteuid() == 0 else None
    if made is None:
        readonly.chmod(0o555)
    elif made.returncode != 0:
        pytest.skip(f"cannot make a read-only folder here: {made.stderr.decode().strip()}")
    try:
        for out in (readonly, readonly / "sub"):
            run = subprocess.run([SWEEP, str(study_file), "--out", str(out), "--serial"], capture_output=True,
                                 text=True, timeout=60)
            print(f"--out {out}: exit {run.returncode}: {run.stderr.strip()}")
            assert run.returncode == 2 and "Traceback" not in run.stderr
            assert f"{out} (" in run.stderr and "give a folder you can write to" in run.stderr
    finally:
        if made is not None:
            subprocess.run(["chattr", "-i", str(readonly)])
        readonly.chmod(0o755)


def test_an_unreachable_scheduler_is_reported_within_the_connection_timeout(study_file, tmp_path):
    import socket
    with socket.socket() as s:  # a port nothing listens on
        s.bind(("127.0.0.1", 0))
        address = f"tcp://127.0.0.1:{s.getsockname()[1]}"
    started = time.monotonic()
    run = subprocess.run([SWEEP, str(study_file), "--out", str(tmp_path / "out"), "--scheduler", address],
                         capture_output=True, text=True, timeout=120)
    took = time.monotonic() - started
    print(f"unreachable scheduler: exit {run.returncode} after {took:.1f} s: {run.stderr.strip()}")
    assert run.returncode == 2 and "Traceback" not in run.stderr
    assert f"no Dask scheduler answered at {address} within 5 s" in run.stderr
    assert took < 20
