"""Study throughput of the two masters: runs per second of the shipped stability study's
closed-loop runs (non-dimensional heave programme, G x D, 2000 communication steps of 0.01
each), with the compiled master (`stewart_fmu.master`, the default) and the FMPy master
(`--master fmpy`), in this process without Dask and on a local Dask cluster of 1 and 2 worker
processes (one thread each) after each worker has loaded the FMUs, handed out as `stewart-sweep`
hands them (the compiled master's runs in batches, `sweep.batches`). Then the compiled master's
cost per communication step: wall time, and instructions (callgrind, the difference between 1
and 3 runs, so that loading and Python's start-up drop out) split into the two FMUs (inside
their exported fmi2* functions), the master's loop (`System::run` without the FMUs) and the
Python around each run (the study's checks and the row); and a worker's memory over repeated
rounds. Prints one table and writes it to benches/results/sweep.txt. With --profile, only
where the instructions of a step go (the platform's step, kappa, the controller's direct
problem, the FMI calls, the master, Python), into benches/results/step_profile.txt.

    .venv/bin/python benches/sweep_bench.py             # after cargo run --release --bin build-fmu
                                                        # and pip install -e python (the compiled master)
    .venv/bin/python benches/sweep_bench.py --profile
"""

import os
import platform
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from stewart_fmu import ROOT
from stewart_fmu import study as st
from stewart_fmu.sweep import batches, run_batch

SPEC = {
    "study": {"name": "bench", "system": "closed-loop", "units": "nondimensional", "stop_time": 20.0, "step": 0.01,
              "stable_error": 0.01},
    "fixed": {"controller.heave.centre[3]": 1.3059496109441155, "controller.heave.amplitude": 0.2,
              "controller.heave.frequency": 1.0, "controller.heave.timeConstant": 2.0},
    "grid": {"controller.G": [2.0, 5.0, 10.0, 20.0, 50.0, 100.0], "controller.D": [0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 3.5,
                                                                                     4.0, 4.5, 5.0]},
}
STEPS = 2000
# Runs per measurement: the compiled master repeats the 60-run grid, so that each measurement
# lasts seconds.
ROUNDS = {"compiled": 20, "fmpy": 1}
OUT = ROOT / "benches" / "results" / "sweep.txt"


def _rss_mb():
    with open("/proc/self/status") as f:
        return next(int(line.split()[1]) for line in f if line.startswith("VmRSS:")) / 1024


def in_process(master, runs, fmus):
    run_batch(SPEC, runs[:2], fmus, master)  # load the FMUs in this process
    start = time.perf_counter()
    for batch in batches(SPEC, runs, master, 1):
        rows = run_batch(SPEC, batch, fmus, master)
        assert all(r["status"] == "ok" for r in rows), rows[0]
    return len(runs) / (time.perf_counter() - start)


def on_dask(master, runs, fmus, workers):
    from distributed import Client, LocalCluster
    with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
            Client(cluster) as client:
        shared = client.scatter(fmus, broadcast=True)
        client.gather([client.submit(run_batch, SPEC, runs[:2], shared, master, pure=False) for _ in range(2 * workers)])
        start = time.perf_counter()
        futures = [client.submit(run_batch, SPEC, b, shared, master, pure=False)
                   for b in batches(SPEC, runs, master, workers)]
        client.gather(futures)
        rate = len(runs) / (time.perf_counter() - start)
        rss = []
        for _ in range(3):
            client.gather([client.submit(run_batch, SPEC, b, shared, master, pure=False)
                           for b in batches(SPEC, runs, master, workers)])
            rss.append(max(client.run(_rss_mb).values()))
    return rate, rss


CALLGRIND_SCRIPT = """
import sys
sys.path.insert(0, {bench!r})
from sweep_bench import SPEC
from stewart_fmu import study as st
from stewart_fmu.sweep import run_batch
runs = st.runs(SPEC)
fmus = st.fmus_for(SPEC)
run_batch(SPEC, runs[:1], fmus, "compiled")
run_batch(SPEC, runs[1:1 + int(sys.argv[1])], fmus, "compiled")
"""


def callgrind(n, folder):
    """{function (with object): inclusive instructions} and the total, for a process that
    runs 1 + n study runs with the compiled master."""
    script = Path(folder) / "runs.py"
    script.write_text(CALLGRIND_SCRIPT.format(bench=str(Path(__file__).parent)))
    out = Path(folder) / f"callgrind.{n}"
    # A fixed hash seed: otherwise Python's own start-up and imports differ by millions of
    # instructions between the two processes, more than the runs' difference. No bytecode
    # written: the first process after a change of the package would compile its modules and
    # the second not. One BLAS thread: NumPy's OpenBLAS threads spin while they wait, for as
    # many instructions as the wall time allows (either made the Python share negative).
    env = dict(os.environ, PYTHONHASHSEED="0", PYTHONDONTWRITEBYTECODE="1", OPENBLAS_NUM_THREADS="1",
               OMP_NUM_THREADS="1")
    subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", sys.executable, str(script), str(n)],
                   check=True, capture_output=True, env=env)
    report = subprocess.run(["callgrind_annotate", "--inclusive=yes", "--threshold=100", str(out)], check=True,
                            capture_output=True, text=True).stdout
    counts = {}
    for line in report.splitlines():
        m = re.match(r"\s*([\d,]+) \([^)]*\)\s+(\S.*)$", line)
        if m:
            counts[m.group(2)] = counts.get(m.group(2), 0) + int(m.group(1).replace(",", ""))
    total = next(v for k, v in counts.items() if k.startswith("PROGRAM TOTALS"))
    return counts, total


def instructions_per_step():
    """Instructions per closed-loop step: total, in the FMUs, in the master's loop, in the
    Python around the runs (callgrind: 3 runs minus 1 run, over 2 x 2000 steps)."""
    with tempfile.TemporaryDirectory() as folder:
        (one, total_one), (three, total_three) = callgrind(1, folder), callgrind(3, folder)
    steps = 2 * STEPS

    def summed(counts, pattern):
        return sum(v for k, v in counts.items() if re.search(pattern, k))

    fmu = r"\?\?\?:fmi2(DoStep|GetReal|SetReal|SetInteger|SetBoolean|Reset|SetupExperiment|EnterInitializationMode|" \
          r"ExitInitializationMode) \["
    loop = r"stewart_master::system::System::run \["
    per = {
        "total": (total_three - total_one) / steps,
        "fmus": (summed(three, fmu) - summed(one, fmu)) / steps,
        "loop": (summed(three, loop) - summed(one, loop)) / steps,
    }
    per["master"] = per["loop"] - per["fmus"]
    per["python"] = per["total"] - per["loop"]
    # Where the FMUs' share goes: inclusive counts of functions that do not call each other
    # (the controller's step calls its direct problem, which calls its programme point).
    part = {name: (summed(three, pattern) - summed(one, pattern)) / steps for name, pattern in PARTS.items()}
    per["parts"] = {
        "platform_step": part["platform_step"],
        "kappa": part["kappa"],
        "platform_outputs": part["platform_outputs"],
        "direct_problem": part["direct_problem"] - part["programme_point"],
        "programme_point": part["programme_point"],
        "controller_rest": part["controller_step"] - part["direct_problem"],
    }
    per["parts"]["fmi"] = per["fmus"] - sum(per["parts"].values())
    return per


# The functions counted (callgrind_annotate's "file:function [object]", whatever crate holds
# them): name -> pattern.
PARTS = {
    "platform_step": r"PlatformModel as [\w:]*FmuModel>::do_step \[",
    "kappa": r"::simulation::outputs::condition_number \[",
    "platform_outputs": r"::simulation::(outputs|dynamics)::(PlatformOutputs<T>|LegOutputs)::compute \[",
    "controller_step": r"ControllerModel as [\w:]*FmuModel>::do_step \[",
    "direct_problem": r"ControllerModel::direct_problem \[",
    "programme_point": r"ControllerModel::programme_point \[",
}
PROFILE_OUT = ROOT / "benches" / "results" / "step_profile.txt"
# The table's rows: the disjoint parts instructions_per_step gives, and what each is.
PART_NAMES = {
    "platform_step": "the platform's step (its integration: special form, error norm, projection, checks)",
    "kappa": "kappa, the condition number the study reads every step (eigenvalue problem)",
    "platform_outputs": "the platform's other outputs the study reads (energy, stops, legs)",
    "direct_problem": "the controller's direct problem at the programme point (6x6 LU, its norm)",
    "programme_point": "the controller's programme point (one sin, one exp)",
    "controller_rest": "the controller's step otherwise (the feedback)",
    "fmi": "the FMI calls: entry checks, gets, sets, the value cache",
}


def profile():
    """Where a closed-loop step of the compiled master goes (callgrind, 3 runs minus 1): the
    table docs/studies.md quotes, written to benches/results/step_profile.txt."""
    per = instructions_per_step()
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True,
                            text=True).stdout.strip()
    lines = [f"instructions per closed-loop step of the stability study's runs, compiled master (callgrind, 3 runs "
             f"minus 1 run, 2 x {STEPS} steps), FMUs of target/fmu at {commit}, {time.strftime('%Y-%m-%d')}",
             "    .venv/bin/python benches/sweep_bench.py --profile",
             f"{'part':84} {'instructions':>12}"]
    for key, name in PART_NAMES.items():
        lines.append(f"{name:84} {per['parts'][key]:12,.0f}")
    lines.append(f"{'the two FMUs in all':84} {per['fmus']:12,.0f}")
    lines.append(f"{'the master loop without the FMUs':84} {per['master']:12,.0f}")
    lines.append(f"{'Python around the runs':84} {per['python']:12,.0f}")
    lines.append(f"{'the step in all':84} {per['total']:12,.0f}")
    text = "\n".join(lines)
    print(text)
    PROFILE_OUT.write_text(text + "\n")


def main():
    grid = st.runs(SPEC)
    fmus = st.fmus_for(SPEC)
    lines = [f"study throughput: the stability study's closed-loop runs ({len(grid)}-run G x D grid, "
             f"{STEPS} steps of 0.01 each, non-dimensional heave), {os.cpu_count()} cores "
             f"({platform.processor() or platform.machine()}), {time.strftime('%Y-%m-%d')}",
             f"{'master':9} {'where':24} {'runs':>6} {'runs/s':>9} {'us/step':>8} {'vs 1 worker':>11}"]
    rates = {}
    for master in ("compiled", "fmpy"):
        runs = grid * ROUNDS[master]
        serial = in_process(master, runs, fmus)
        lines.append(f"{master:9} {'this process, no Dask':24} {len(runs):6} {serial:9.1f} {1e6 / (serial * STEPS):8.2f}")
        rates[master] = {"serial": serial}
        for workers in (1, 2):
            rate, rss = on_dask(master, runs, fmus, workers)
            rates[master][workers] = (rate, rss)
            scale = f"{rate / rates[master][1][0]:10.2f}x" if workers > 1 else ""
            lines.append(f"{master:9} {f'Dask, {workers} local worker(s)':24} {len(runs):6} {rate:9.1f} "
                         f"{1e6 / (rate * STEPS):8.2f} {scale:>11}")
    speedup = rates["compiled"][2][0] / rates["fmpy"][2][0]
    lines.append(f"compiled / fmpy on 2 workers: {speedup:.1f}x; worker RSS after three more rounds (MB), compiled: "
                 f"{', '.join(f'{x:.0f}' for x in rates['compiled'][2][1])}; fmpy: "
                 f"{', '.join(f'{x:.0f}' for x in rates['fmpy'][2][1])}")
    per = instructions_per_step()
    lines.append(f"compiled master, instructions per closed-loop step (callgrind, 3 runs minus 1): {per['total']:,.0f} "
                 f"in all: the two FMUs {per['fmus']:,.0f} ({per['fmus'] / per['total']:.1%}), the master's loop "
                 f"{per['master']:,.0f} ({per['master'] / per['total']:.1%}), Python around the runs "
                 f"{per['python']:,.0f} ({per['python'] / per['total']:.1%})")
    text = "\n".join(lines)
    print(text)
    OUT.write_text(text + "\n")


if __name__ == "__main__":
    profile() if sys.argv[1:] == ["--profile"] else main()
