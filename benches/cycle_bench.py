"""The whole co-simulation cycle, measured fairly: a plain C host (benches/c/cycle_host.c) sets
the six leg forces (leg feedback around the neutral legs), steps 1 ms and reads the twelve leg
lengths and rates, through the packaged FMI 2 and FMI 3 platform FMUs. Prints one table:

- instructions per cycle and its split (set, step, get: the host's functions, and the
  exported call inside each alone, per call), from callgrind over 5000 cycles (repeatable;
  wall times on this shared machine vary up to 2x between runs), in four
  motions: hovering on the leg feedback (no stop touched), resting in contact with all six
  lower stops (zero forces), hovering with the end stops switched off, hovering while the host
  reads the pose (r, R, angles) besides the legs, and (FMI 2) hovering
  with `logEvents` delivered to a logger that drops it, so that passages through singular
  arrangements are tracked (skipped when nobody can be told);
- wall-clock time per cycle with the clock outside the loop (as MuJoCo's own C loop is timed):
  21 runs of 50,000 cycles after 0.3 s of warm-up, minimum and median, FMI 2 and FMI 3. This
  shared machine moves between levels of speed (other tenants of the host; MuJoCo moves with
  us, the slowest level about 1.5x the quietest), each held for seconds, so one run can sit
  wholly in one: the minimum is the machine at its quietest in the run, the median what the
  run met;
- wall-clock latency over 10^6 cycles (mean, p50, p99, p99.9, max; each sample includes one
  clock read, printed), one run;
- throughput with 1 and 2 threads, each with its own instance;
- instantiate + initialise + free;
- MuJoCo 4's RK4 `mj_step` on the same stand (examples/compare_performance.py's model), in its
  own C loop (`mj_step(model, data, nstep=N)`: 21 runs of 250 steps after 0.3 s of warm-up,
  minimum and median, like ours) and per call from Python, and its instructions per step
  (callgrind, inclusive `mj_step` over 200 steps), if `mujoco` is installed (`pip install
  mujoco`); the wall-clock ratios to ours compare the C loops, minimum with minimum and median
  with median.

    .venv/bin/python benches/cycle_bench.py [output-folder]   # after cargo run --release --bin build-fmu
    .venv/bin/python benches/cycle_bench.py --counts FMU_DIR [FMU_DIR ...]
        # only the instruction table, for each folder of FMUs (target/fmu's layout: two builds
        # compared in one run; printed, nothing written)
"""

import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
OUT = Path(sys.argv[1] if len(sys.argv) > 1 and sys.argv[1] != "--counts" else ROOT / "benches" / "results")
FMU_DIR = ROOT / "target" / "fmu"


def fmu_files(fmu_dir):
    return {"fmi2": fmu_dir / "StewartPlatform.fmu", "fmi3": fmu_dir / "fmi3" / "StewartPlatform.fmu"}


FMUS = fmu_files(FMU_DIR)
COUNT_CYCLES = 5000
LATENCY_CYCLES = 1_000_000
LOOP_CYCLES, LOOP_RUNS = 50_000, 21
MUJOCO_STEPS, MUJOCO_RUNS, WARM_UP_SECONDS = 250, 21, 0.3


def unpack(version, folder, fmus=FMUS):
    with zipfile.ZipFile(fmus[version]) as z:
        z.extractall(folder / version)
    md = (folder / version / "modelDescription.xml").read_text()
    token = re.search(r'(?:guid|instantiationToken)="([^"]+)"', md).group(1)
    # This machine's binary (the FMUs carry other platforms' too).
    binary = folder / version / "binaries" / ("linux64" if version == "fmi2" else "x86_64-linux") / "StewartPlatform.so"
    return str(binary), token


def instructions(host, version, binary, token, method, folder, scenario="hover"):
    """Inclusive instruction counts of the host's cycle functions, per cycle."""
    out = folder / f"cg.{version}.{method}.{scenario}"
    subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", host, version, binary, token,
                    method, "count", str(COUNT_CYCLES)], check=True, capture_output=True,
                   env=dict(os.environ, CYCLE_SCENARIO=scenario))
    report = subprocess.run(["callgrind_annotate", "--inclusive=yes", "--threshold=100", str(out)], check=True,
                            capture_output=True, text=True).stdout
    counts = {}
    for name in ("run_cycles", "set_forces", "do_step", "get_outputs"):
        m = re.search(r"^\s*([\d,]+) \([^)]*\)\s+\S*cycle_host\.c:" + name + r" \[", report, re.M)
        counts[name] = int(m.group(1).replace(",", "")) / COUNT_CYCLES
    # The FMU's own share of each host function: the exported function it calls, per call
    # (without the host's force law, call and status check).
    tree = subprocess.run(["callgrind_annotate", "--tree=calling", "--inclusive=yes", "--threshold=100", str(out)], check=True,
                          capture_output=True, text=True).stdout
    for name in ("set_forces", "do_step", "get_outputs"):
        m = re.search(r"\*\s+\S*cycle_host\.c:" + name + r" \[.*\n\s*([\d,]+) \([^)]*\)\s+>\s+\S*:(fmi\w+) "
                      r"\(([\d,]+)x\)", tree)
        counts["fmu_" + name] = int(m.group(1).replace(",", "")) / int(m.group(3).replace(",", ""))
    return counts


def run(host, *args):
    return subprocess.run([host, *map(str, args)], check=True, capture_output=True, text=True).stdout


def mujoco_step_us():
    """MuJoCo's RK4 step in microseconds: (minimum, median) over runs of its C loop, and the
    median per call from Python; None without `mujoco`."""
    try:
        import mujoco
    except ImportError:
        return None
    import importlib.util
    import statistics
    spec = importlib.util.spec_from_file_location("compare_performance", ROOT / "examples" / "compare_performance.py")
    comparison = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(comparison)
    mjcf = comparison.mjcf
    model = mujoco.MjModel.from_xml_string(mjcf("RK4", 1e-3))
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    start = time.perf_counter()
    while time.perf_counter() - start < WARM_UP_SECONDS:
        mujoco.mj_step(model, data, nstep=MUJOCO_STEPS)
    c_loop = []
    for _ in range(MUJOCO_RUNS):
        start = time.perf_counter()
        mujoco.mj_step(model, data, nstep=MUJOCO_STEPS)
        c_loop.append((time.perf_counter() - start) / MUJOCO_STEPS * 1e6)
    per_call = []
    for _ in range(5):
        start = time.perf_counter()
        for _ in range(MUJOCO_STEPS):
            mujoco.mj_step(model, data)
        per_call.append((time.perf_counter() - start) / MUJOCO_STEPS * 1e6)
    return min(c_loop), statistics.median(c_loop), statistics.median(per_call)


MUJOCO_COUNT = """
import importlib.util, sys
import mujoco
spec = importlib.util.spec_from_file_location("cp", sys.argv[1])
cp = importlib.util.module_from_spec(spec)
spec.loader.exec_module(cp)
model = mujoco.MjModel.from_xml_string(cp.mjcf("RK4", 1e-3))
data = mujoco.MjData(model)
mujoco.mj_forward(model, data)
mujoco.mj_step(model, data, nstep=int(sys.argv[2]))
"""


def mujoco_instructions(folder, steps=200):
    """Instructions per RK4 `mj_step`: callgrind's inclusive count of `mj_step` over `steps`."""
    script, out = folder / "mj_count.py", folder / "cg.mujoco"
    script.write_text(MUJOCO_COUNT)
    subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", sys.executable, str(script),
                    str(ROOT / "examples" / "compare_performance.py"), str(steps)], check=True, capture_output=True)
    report = subprocess.run(["callgrind_annotate", "--inclusive=yes", str(out)], check=True, capture_output=True,
                            text=True).stdout
    m = re.search(r"^\s*([\d,]+) \([^)]*\)\s+\S*:mj_step \[", report, re.M)
    return int(m.group(1).replace(",", "")) / steps


def instruction_table(host, fmus, folder):
    """The callgrind table: its lines and the counts by (version, method, motion)."""
    lines = ["Instructions per cycle (callgrind, 5000 cycles): set 6 forces + fmi2DoStep/fmi3DoStep 1 ms + get 12 values",
             "(hover: leg feedback, no stop touched; contact: resting on all six lower stops; nostops: hover with "
             "stops = false; nojoints: hover with joints = false; heavylegs: hover with 40 kg cylinders and 15 kg "
             "rods; drives: hover with the default electric drives, voltages in; hydraulics: hover with the default hydraulic "
             "legs, valve commands in, 12 pressures out besides the legs; powerunit: hydraulics fed by the power unit "
             "(hydraulic.supply = 1); pumpfailure: hydraulic legs, every valve open and pS = 0 from the start (RK4's "
             "sub-steps); pose: hover reading the pose (r, R, angles: 15 "
             "values) besides the legs; logevents: hover with logEvents delivered, singular passages tracked)",
             "(set, step, get: the host's functions, each around one call; in the FMU: that exported call alone, "
             "per call)",
             f"{'FMU':6} {'method':7} {'motion':9} {'cycle':>8} {'set':>7} {'step':>8} {'get':>7}   "
             f"{'in the FMU: set':>15} {'step':>8} {'get':>7}"]
    cycles = {}
    for version, (binary, token) in fmus.items():
        for method in ("rk4", "dopri5"):
            scenarios = (("hover", "contact", "nostops", "nojoints", "heavylegs", "drives", "hydraulics", "powerunit",
                          "pumpfailure", "pose", "logevents") if version == "fmi2"
                         else ("hover", "contact", "drives", "hydraulics", "powerunit", "pose"))
            for scenario in scenarios:
                c = instructions(host, version, binary, token, method, folder, scenario)
                cycles[(version, method, scenario)] = c
                lines.append(f"{version:6} {method:7} {scenario:9} {c['run_cycles']:8.0f} {c['set_forces']:7.0f} "
                             f"{c['do_step']:8.0f} {c['get_outputs']:7.0f}   {c['fmu_set_forces']:15.0f} "
                             f"{c['fmu_do_step']:8.0f} {c['fmu_get_outputs']:7.0f}")
    return lines, cycles


def loop_time(host, fmus, version, method):
    """One `loop` run of the C host: its line and (min, median) in us per cycle."""
    binary, token = fmus[version]
    text = run(host, version, binary, token, method, "loop", LOOP_CYCLES, LOOP_RUNS).splitlines()[0]
    m = re.search(r"min ([\d.]+) median ([\d.]+)", text)
    return f"FMI {version[-1]} {method}: {text}", (float(m.group(1)), float(m.group(2)))


def build_host(folder):
    host = str(folder / "cycle_host")
    subprocess.run(["gcc", "-O2", "-g", "-Wall", "-Wextra", "-Werror", "-o", host,
                    str(ROOT / "benches" / "c" / "cycle_host.c"), "-ldl", "-lpthread"], check=True)
    return host


def counts_only(fmu_dirs):
    """The instruction table of each folder of FMUs, one after the other in one run."""
    folder = Path(tempfile.mkdtemp(prefix="cycle_bench_"))
    host = build_host(folder)
    for n, fmu_dir in enumerate(fmu_dirs):
        unpacked = folder / f"build{n}"
        fmus = {version: unpack(version, unpacked, fmu_files(Path(fmu_dir))) for version in FMUS}
        table, _ = instruction_table(host, fmus, unpacked)
        print(f"{fmu_dir}:")
        print("\n".join(table[3:]))
        print()
    shutil.rmtree(folder, ignore_errors=True)


def main():
    if not shutil.which("valgrind") or not shutil.which("gcc"):
        sys.exit("cycle_bench: valgrind and gcc are needed")
    if sys.argv[1:2] == ["--counts"]:
        return counts_only(sys.argv[2:] or [FMU_DIR])
    OUT.mkdir(parents=True, exist_ok=True)
    folder = Path(tempfile.mkdtemp(prefix="cycle_bench_"))
    host = build_host(folder)
    header = [f"cycle_bench: {time.strftime('%Y-%m-%d %H:%M')}, {os.cpu_count()} cores, "
              f"{open('/proc/cpuinfo').read().split('model name')[1].split(':')[1].splitlines()[0].strip()}", ""]
    fmus = {version: unpack(version, folder) for version in FMUS}
    # Wall clock first, ours and MuJoCo's C loops next to each other in time; callgrind last.
    wall, loops = [], {}
    for method in ("rk4", "dopri5"):
        line, loops[("fmi2", method)] = loop_time(host, fmus, "fmi2", method)
        wall.append(line)
    mj = mujoco_step_us()
    for method in ("rk4", "dopri5"):
        line, loops[("fmi3", method)] = loop_time(host, fmus, "fmi3", method)
        wall.append(line)
    binary, token = fmus["fmi2"]
    for method in ("rk4", "dopri5"):
        text = run(host, "fmi2", binary, token, method, "latency", LATENCY_CYCLES)
        wall.append(f"FMI 2 {method}: {text.splitlines()[0]}")
    for threads in (1, 2):
        wall.append(f"FMI 2 rk4, {run(host, 'fmi2', binary, token, 'rk4', 'threads', 200_000, threads).strip()}")
    wall.append(f"FMI 2: {run(host, 'fmi2', binary, token, 'rk4', 'instantiate', 2000).strip()}")
    binary3, token3 = fmus["fmi3"]
    wall.append(f"FMI 3: {run(host, 'fmi3', binary3, token3, 'rk4', 'instantiate', 2000).strip()}")
    table, cycles = instruction_table(host, fmus, folder)
    mujoco = []
    if mj is None:
        mujoco.append("MuJoCo: not installed (pip install mujoco), no comparison")
    else:
        c_min, c_median, per_call = mj
        mujoco.append(f"MuJoCo RK4 mj_step, same stand, 1 ms, in its C loop (nstep={MUJOCO_STEPS}, {MUJOCO_RUNS} runs, "
                      f"timed between our FMI 2 and FMI 3 loops): min {c_min:.1f} median {c_median:.1f} us per step; "
                      f"{per_call:.1f} us per call from Python")
        rk4, adaptive = loops[("fmi2", "rk4")], loops[("fmi2", "dopri5")]
        mujoco.append(f"ratio MuJoCo C loop / our full FMI 2 cycle in its C loop (wall clock, this run): "
                      f"RK4 {c_min / rk4[0]:.0f}x (min) {c_median / rk4[1]:.0f}x (median), "
                      f"adaptive default {c_min / adaptive[0]:.0f}x (min) {c_median / adaptive[1]:.0f}x (median)")
        mj_instructions = mujoco_instructions(folder)
        ours_rk4 = cycles[("fmi2", "rk4", "hover")]["run_cycles"]
        ours_adaptive = cycles[("fmi2", "dopri5", "hover")]["run_cycles"]
        mujoco.append(f"MuJoCo RK4 mj_step: {mj_instructions:,.0f} instructions per step (callgrind, 200 steps); "
                      f"ratio to our full FMI 2 cycle: RK4 {mj_instructions / ours_rk4:.0f}x, adaptive default "
                      f"{mj_instructions / ours_adaptive:.0f}x")
    text = "\n".join(header + table + [""] + wall + [""] + mujoco)
    print(text)
    (OUT / "cycle.txt").write_text(text + "\n")
    shutil.rmtree(folder, ignore_errors=True)


if __name__ == "__main__":
    main()
