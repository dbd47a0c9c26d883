"""What the cueing FMU costs where cueing runs: a simulator's real-time computer at 1 kHz.
A plain C host (benches/c/cueing_host.c) drives the packaged StewartCueing.fmu (FMI 2, this
machine's binary) through the main job's eight manoeuvres, 1 ms communication steps, each
cycle setting f and omega, stepping and reading the 18 values of the pose command. Prints one
table and writes it to benches/results/cueing_realtime.txt:

- wall time per cycle, both methods, over every drive (8 x 20,000 cycles: more than 10^5): the
  mean, the largest, the largest of the cycles with a solve (every 10th, the predictive
  method's default period) and of those without; CLOCK_MONOTONIC around each cycle, one run on
  this shared machine (other tenants move it by up to 2x: the instruction counts are the
  stable measure);
- instructions (callgrind) of the cycles with the most solver iterations of each drive (the
  worst solves), and the mean per cycle over one drive (the slalom), both methods;
- allocations and system calls in 10^4 cycles after the first 2,000 (an LD_PRELOAD counter of
  the C library's allocating functions, benches/c/cueing_alloc.c; strace between two marker
  calls of the host).

    .venv/bin/python benches/cueing_bench.py     # after cargo run --release --bin build-fmu
"""

import os
import re
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "python"))
from stewart_fmu import vehicle  # noqa: E402

FMU = ROOT / "target" / "fmu" / "StewartCueing.fmu"
OUT = ROOT / "benches" / "results" / "cueing_realtime.txt"
DRIVES = {**vehicle.MANOEUVRES, "emergency_stop": vehicle.HARSH["emergency_stop"], "pothole": vehicle.HARSH["pothole"]}
QUIET_STEPS, QUIET_WARM = 10_000, 2_000


def build(tmp):
    """The host and the allocation counter, compiled here."""
    host, shim = tmp / "cueing_host", tmp / "cueing_alloc.so"
    subprocess.run(["gcc", "-O2", "-o", host, ROOT / "benches" / "c" / "cueing_host.c", "-ldl"], check=True)
    subprocess.run(["gcc", "-O2", "-shared", "-fPIC", "-o", shim, ROOT / "benches" / "c" / "cueing_alloc.c"],
                   check=True)
    return host, shim


def unpack(tmp):
    """The FMU's binary, GUID and resources address."""
    folder = tmp / "fmu"
    with zipfile.ZipFile(FMU) as z:
        z.extractall(folder)
    guid = re.search(r'guid="([^"]+)"', (folder / "modelDescription.xml").read_text()).group(1)
    return folder / "binaries" / "linux64" / "StewartCueing.so", guid, (folder / "resources").as_uri()


def drives(tmp, only=None):
    """Each manoeuvre's f and omega at every millisecond, as the host reads them."""
    paths = {}
    for name, make in DRIVES.items():
        if only and name not in only:
            continue
        m = make()
        t = np.arange(int(round(m["time"][-1] / 1e-3)) + 1) * 1e-3
        columns = [np.interp(t, m["time"], m[c]) for c in vehicle.COLUMNS[1:]]
        path = tmp / f"{name}.bin"
        np.column_stack(columns).astype("<f8").tofile(path)
        paths[name] = path
    return paths


def run(host, binary, guid, resources, method, mode, paths, prefix=(), env=None):
    command = [*prefix, str(host), str(binary), guid, resources, str(method), mode, *map(str, paths)]
    return subprocess.run(command, capture_output=True, text=True, check=True, env=env)


def timing(host, unpacked, paths):
    """Per method and drive: mean and largest cycles (us) and the steps of the most
    iterations."""
    rows = {}
    for method in (0, 1):
        out = run(host, *unpacked, method, "time", paths.values()).stdout
        for name, line in zip(paths, out.splitlines()):
            values = dict(re.findall(r"(\w+) ([\d.]+)", line))
            worst = [tuple(map(int, w.split(":"))) for w in line.split("most_iterations")[1].split()]
            rows[(method, name)] = {k: float(v) for k, v in values.items()} | {"worst": worst}
    return rows


def callgrind_counts(host, unpacked, paths, targets, tmp):
    """Instructions of each listed cycle (`targets`: (drive index, step)), one callgrind run."""
    out = tmp / "callgrind.%p"
    mode = "count:" + ",".join(f"{d}:{s}" for d, s in targets)
    run(host, *unpacked, 1, mode, paths.values(),
        prefix=("valgrind", "--tool=callgrind", "--collect-atstart=no", f"--callgrind-out-file={out}"))
    counts = []
    for f in sorted(tmp.glob("callgrind.*")):
        m = re.search(r"^(?:summary|totals): (\d+)", f.read_text(errors="replace"), re.M)
        if m and int(m.group(1)) > 0:
            counts.append(int(m.group(1)))
        f.unlink()
    return counts


def mean_instructions(host, unpacked, path, method, tmp):
    out = tmp / "all.out"
    run(host, *unpacked, method, "all", [path],
        prefix=("valgrind", "--tool=callgrind", "--collect-atstart=no", f"--callgrind-out-file={out}"))
    total = int(re.search(r"^(?:summary|totals): (\d+)", out.read_text(), re.M).group(1))
    out.unlink()
    cycles = os.path.getsize(path) // 48 - 1
    return total / cycles


def quiet(host, shim, unpacked, path, method, tmp):
    """Allocations and system calls in QUIET_STEPS cycles after QUIET_WARM."""
    mode = f"quiet:{QUIET_WARM}:{QUIET_STEPS}"
    env = {**os.environ, "LD_PRELOAD": str(shim)}
    allocated = int(re.search(r"allocations (\d+)", run(host, *unpacked, method, mode, [path], env=env).stderr).group(1))
    trace = tmp / "strace.txt"
    run(host, *unpacked, method, mode, [path], prefix=("strace", "-f", "-o", str(trace)))
    lines = trace.read_text().splitlines()
    marks = [i for i, line in enumerate(lines) if "getppid(" in line]
    between = lines[marks[0] + 1: marks[1]] if len(marks) >= 2 else None
    return allocated, (len(between) if between is not None else -1), QUIET_STEPS


def main():
    with tempfile.TemporaryDirectory() as t:
        tmp = Path(t)
        host, shim = build(tmp)
        unpacked = unpack(tmp)
        paths = drives(tmp)
        print(f"timing {len(paths)} drives x 2 methods ...", flush=True)
        rows = timing(host, unpacked, paths)
        lines = ["Cueing FMU on a real-time host: a C host, FMI 2, 1 ms cycles (set f, omega; doStep; get the pose",
                 "command), the main job's manoeuvres; benches/cueing_bench.py. Times: CLOCK_MONOTONIC per cycle,",
                 "one run on a shared 2-core machine; instructions: callgrind.", ""]
        lines.append(f"{'drive':16s} {'method':11s} {'cycles':>7s} {'mean us':>8s} {'max us':>8s} "
                     f"{'max solve us':>12s} {'max other us':>12s} {'most iterations':>15s}")
        total_cycles = {0: 0, 1: 0}
        for (method, name), r in rows.items():
            total_cycles[method] += int(r["steps"])
            lines.append(f"{name:16s} {['classical', 'predictive'][method]:11s} {int(r['steps']):7d} "
                         f"{r['mean_ns'] / 1e3:8.1f} {r['max_ns'] / 1e3:8.1f} {r['max_solve_ns'] / 1e3:12.1f} "
                         f"{r['max_plain_ns'] / 1e3:12.1f} {max(w[1] for w in r['worst']):15d}")
        for method in (0, 1):
            sel = [r for (m, _), r in rows.items() if m == method]
            mean = sum(r["mean_ns"] * r["steps"] for r in sel) / sum(r["steps"] for r in sel)
            lines.append(f"{'all drives':16s} {['classical', 'predictive'][method]:11s} {total_cycles[method]:7d} "
                         f"{mean / 1e3:8.1f} {max(r['max_ns'] for r in sel) / 1e3:8.1f} "
                         f"{max(r['max_solve_ns'] for r in sel) / 1e3:12.1f} "
                         f"{max(r['max_plain_ns'] for r in sel) / 1e3:12.1f}")
        print(f"callgrind: the worst solves ...", flush=True)
        targets = [(d, s) for d, name in enumerate(paths) for s, _ in rows[(1, name)]["worst"] if s >= 0]
        counts = callgrind_counts(host, unpacked, paths, targets, tmp)
        slalom = paths["slalom"]
        means = {m: mean_instructions(host, unpacked, slalom, m, tmp) for m in (0, 1)}
        lines += ["", f"instructions of the cycles with the most solver iterations ({len(counts)} cycles, 3 per drive): "
                      f"largest {max(counts):,}, smallest {min(counts):,}",
                  f"instructions per cycle, mean over the slalom (20,000 cycles): classical {means[0]:,.0f}, "
                  f"predictive {means[1]:,.0f}"]
        print("allocations and system calls ...", flush=True)
        for method in (0, 1):
            allocated, calls, cycles = quiet(host, shim, unpacked, slalom, method, tmp)
            lines.append(f"{['classical', 'predictive'][method]}: {allocated} allocations and {calls} system calls in "
                         f"{cycles} cycles after {QUIET_WARM} (the slalom)")
        text = "\n".join(lines) + "\n"
        print(text)
        OUT.write_text(text)


if __name__ == "__main__":
    main()
