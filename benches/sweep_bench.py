"""Study throughput: runs per second of a 60-run closed-loop study (non-dimensional heave
programme, 2000 communication steps per run), in this process without Dask and on a local
Dask cluster with 1 and 2 worker processes (one thread each), after each worker has loaded the
FMUs once. Prints a table with the parallel efficiency and the scheduler's cost per run.

    .venv/bin/python benches/sweep_bench.py
"""

import os
import time

from stewart_fmu import study as st
from stewart_fmu.sweep import run_and_time

SPEC = {
    "study": {"name": "bench", "system": "closed-loop", "units": "nondimensional", "stop_time": 20.0, "step": 0.01,
              "stable_error": 0.01},
    "fixed": {"controller.heave.centre[3]": 1.3059496109441155, "controller.heave.amplitude": 0.2},
    "grid": {"controller.G": [2.0, 5.0, 10.0, 20.0, 50.0, 100.0], "controller.D": [0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 3.5,
                                                                                     4.0, 4.5, 5.0]},
}


def _rss_mb():
    with open("/proc/self/status") as f:
        return next(int(line.split()[1]) for line in f if line.startswith("VmRSS:")) / 1024


def main():
    runs = st.runs(SPEC)
    fmus = st.fmus_for(SPEC)
    run_and_time(SPEC, runs[0], fmus)  # load the FMUs in this process
    start = time.perf_counter()
    rows = [run_and_time(SPEC, r, fmus) for r in runs]
    serial = len(runs) / (time.perf_counter() - start)
    per_run = sum(r["wall_time"] for r in rows) / len(rows)
    lines = [f"study throughput, {len(runs)} runs of {SPEC['study']['stop_time'] / SPEC['study']['step']:.0f} steps, "
             f"{os.cpu_count()} cores", f"{'where':28} {'runs/s':>8} {'efficiency':>10}",
             f"{'this process, no Dask':28} {serial:8.2f} {'':>10}"]
    from distributed import Client, LocalCluster
    rates = {}
    for workers in (1, 2):
        with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
                Client(cluster) as client:
            shared = client.scatter(fmus, broadcast=True)
            warm = [client.submit(run_and_time, SPEC, runs[i], shared, pure=False) for i in range(workers * 2)]
            client.gather(warm)
            start = time.perf_counter()
            futures = [client.submit(run_and_time, SPEC, r, shared, pure=False) for r in runs]
            client.gather(futures)
            rates[workers] = len(runs) / (time.perf_counter() - start)
        lines.append(f"{f'Dask, {workers} local worker(s)':28} {rates[workers]:8.2f} "
                     f"{rates[workers] / (workers * serial):10.0%}")
    # A worker's memory over a longer study: 5 rounds of the 60 runs on one worker.
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
            Client(cluster) as client:
        shared = client.scatter(fmus, broadcast=True)
        rss = []
        for _ in range(5):
            client.gather([client.submit(run_and_time, SPEC, r, shared, pure=False) for r in runs])
            rss.append(next(iter(client.run(_rss_mb).values())))
    lines.append(f"worker RSS after each 60 runs (MB): {', '.join(f'{x:.1f}' for x in rss)}")
    overhead = 1.0 / rates[1] - 1.0 / serial
    lines.append(f"mean run {per_run * 1e3:.1f} ms in-process; Dask's cost per run with one worker "
                 f"{overhead * 1e3:.1f} ms; N workers give about N x {1 / (per_run + max(overhead, 0)):.1f} runs/s "
                 f"while the scheduler keeps up (a few thousand tasks/s)")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
