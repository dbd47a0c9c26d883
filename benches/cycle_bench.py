"""The whole co-simulation cycle, measured fairly: a plain C host (benches/c/cycle_host.c) sets
the six leg forces (leg feedback around the neutral legs), steps 1 ms and reads the twelve leg
lengths and rates, through the packaged FMI 2 and FMI 3 platform FMUs. Prints one table:

- instructions per cycle and its split (set, step, get: the host's functions, and the
  exported call inside each alone, per call), from callgrind over 5000 cycles (repeatable;
  wall times on this shared machine vary up to 2x between runs), in four
  motions: hovering on the leg feedback (no stop touched), resting in contact with all six
  lower stops (zero forces), hovering with the end stops switched off, and (FMI 2) hovering
  with `logEvents` delivered to a logger that drops it, so that passages through singular
  arrangements are tracked (skipped when nobody can be told);
- wall-clock latency over 10^6 cycles (mean, p50, p99, p99.9, max), one run;
- throughput with 1 and 2 threads, each with its own instance;
- instantiate + initialise + free;
- MuJoCo 4's RK4 `mj_step` on the same stand (examples/compare_performance.py's model), in its
  own C loop (`mj_step(model, data, nstep=N)`) and per call from Python, and its instructions
  per step (callgrind, inclusive `mj_step` over 200 steps), if `mujoco` is installed (`pip
  install mujoco`); the wall-clock ratios to ours use the C-loop figure.

    .venv/bin/python benches/cycle_bench.py [output-folder]   # after cargo run --release --bin build-fmu
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
OUT = Path(sys.argv[1] if len(sys.argv) > 1 else ROOT / "benches" / "results")
FMUS = {"fmi2": ROOT / "target" / "fmu" / "StewartPlatform.fmu",
        "fmi3": ROOT / "target" / "fmu" / "fmi3" / "StewartPlatform.fmu"}
COUNT_CYCLES = 5000
LATENCY_CYCLES = 1_000_000


def unpack(version, folder):
    with zipfile.ZipFile(FMUS[version]) as z:
        z.extractall(folder / version)
    md = (folder / version / "modelDescription.xml").read_text()
    token = re.search(r'(?:guid|instantiationToken)="([^"]+)"', md).group(1)
    binary = next((folder / version / "binaries").rglob("StewartPlatform.so"))
    return str(binary), token


def instructions(host, version, binary, token, method, folder, scenario="hover"):
    """Inclusive instruction counts of the host's cycle functions, per cycle."""
    out = folder / f"cg.{version}.{method}.{scenario}"
    subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", host, version, binary, token,
                    method, "count", str(COUNT_CYCLES)], check=True, capture_output=True,
                   env=dict(os.environ, CYCLE_SCENARIO=scenario))
    report = subprocess.run(["callgrind_annotate", "--inclusive=yes", str(out)], check=True, capture_output=True,
                            text=True).stdout
    counts = {}
    for name in ("run_cycles", "set_forces", "do_step", "get_outputs"):
        m = re.search(r"^\s*([\d,]+) \([^)]*\)\s+\S*cycle_host\.c:" + name + r" \[", report, re.M)
        counts[name] = int(m.group(1).replace(",", "")) / COUNT_CYCLES
    # The FMU's own share of each host function: the exported function it calls, per call
    # (without the host's force law, call and status check).
    tree = subprocess.run(["callgrind_annotate", "--tree=calling", "--inclusive=yes", str(out)], check=True,
                          capture_output=True, text=True).stdout
    for name in ("set_forces", "do_step", "get_outputs"):
        m = re.search(r"\*\s+\S*cycle_host\.c:" + name + r" \[.*\n\s*([\d,]+) \([^)]*\)\s+>\s+\S*:(fmi\w+) "
                      r"\(([\d,]+)x\)", tree)
        counts["fmu_" + name] = int(m.group(1).replace(",", "")) / int(m.group(3).replace(",", ""))
    return counts


def run(host, *args):
    return subprocess.run([host, *map(str, args)], check=True, capture_output=True, text=True).stdout


def mujoco_step_us():
    try:
        import mujoco
    except ImportError:
        return None
    import importlib.util
    spec = importlib.util.spec_from_file_location("compare_performance", ROOT / "examples" / "compare_performance.py")
    comparison = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(comparison)
    mjcf = comparison.mjcf
    model = mujoco.MjModel.from_xml_string(mjcf("RK4", 1e-3))
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    n = 5000
    start = time.perf_counter()
    mujoco.mj_step(model, data, nstep=n)
    c_loop = (time.perf_counter() - start) / n * 1e6
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    start = time.perf_counter()
    for _ in range(n):
        mujoco.mj_step(model, data)
    per_call = (time.perf_counter() - start) / n * 1e6
    return c_loop, per_call


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


def main():
    if not shutil.which("valgrind") or not shutil.which("gcc"):
        sys.exit("cycle_bench: valgrind and gcc are needed")
    OUT.mkdir(parents=True, exist_ok=True)
    folder = Path(tempfile.mkdtemp(prefix="cycle_bench_"))
    host = str(folder / "cycle_host")
    subprocess.run(["gcc", "-O2", "-g", "-Wall", "-Wextra", "-Werror", "-o", host,
                    str(ROOT / "benches" / "c" / "cycle_host.c"), "-ldl", "-lpthread"], check=True)
    lines = [f"cycle_bench: {time.strftime('%Y-%m-%d %H:%M')}, {os.cpu_count()} cores, "
             f"{open('/proc/cpuinfo').read().split('model name')[1].split(':')[1].splitlines()[0].strip()}", ""]
    lines.append("Instructions per cycle (callgrind, 5000 cycles): set 6 forces + fmi2DoStep/fmi3DoStep 1 ms + get 12 values")
    lines.append("(hover: leg feedback, no stop touched; contact: resting on all six lower stops; nostops: hover with "
                 "stops = false; logevents: hover with logEvents delivered, singular passages tracked)")
    lines.append("(set, step, get: the host's functions, each around one call; in the FMU: that exported call alone, "
                 "per call)")
    lines.append(f"{'FMU':6} {'method':7} {'motion':9} {'cycle':>8} {'set':>7} {'step':>8} {'get':>7}   "
                 f"{'in the FMU: set':>15} {'step':>8} {'get':>7}")
    cycles = {}
    for version in ("fmi2", "fmi3"):
        binary, token = unpack(version, folder)
        for method in ("rk4", "dopri5"):
            scenarios = ("hover", "contact", "nostops", "logevents") if version == "fmi2" else ("hover", "contact")
            for scenario in scenarios:
                c = instructions(host, version, binary, token, method, folder, scenario)
                cycles[(version, method, scenario)] = c
                lines.append(f"{version:6} {method:7} {scenario:9} {c['run_cycles']:8.0f} {c['set_forces']:7.0f} "
                             f"{c['do_step']:8.0f} {c['get_outputs']:7.0f}   {c['fmu_set_forces']:15.0f} "
                             f"{c['fmu_do_step']:8.0f} {c['fmu_get_outputs']:7.0f}")
    lines.append("")
    binary, token = unpack("fmi2", folder)
    latency = {}
    for method in ("rk4", "dopri5"):
        text = run(host, "fmi2", binary, token, method, "latency", LATENCY_CYCLES)
        latency[method] = text.splitlines()[0]
        lines.append(f"FMI 2 {method}: {latency[method]}")
    for threads in (1, 2):
        lines.append(f"FMI 2 rk4, {run(host, 'fmi2', binary, token, 'rk4', 'threads', 200_000, threads).strip()}")
    lines.append(f"FMI 2: {run(host, 'fmi2', binary, token, 'rk4', 'instantiate', 2000).strip()}")
    binary3, token3 = unpack("fmi3", folder)
    lines.append(f"FMI 3: {run(host, 'fmi3', binary3, token3, 'rk4', 'instantiate', 2000).strip()}")
    lines.append("")
    mj = mujoco_step_us()
    if mj is None:
        lines.append("MuJoCo: not installed (pip install mujoco), no comparison")
    else:
        c_loop, per_call = mj
        ours = {m: float(re.search(r"mean ([\d.]+)", latency[m]).group(1)) for m in latency}
        lines.append(f"MuJoCo RK4 mj_step, same stand, 1 ms: {c_loop:.1f} us per step in its C loop (nstep), "
                     f"{per_call:.1f} us per call from Python")
        lines.append(f"ratio MuJoCo C loop / our full cycle: RK4 {c_loop / ours['rk4']:.0f}x, "
                     f"adaptive default {c_loop / ours['dopri5']:.0f}x (wall clock, this run)")
        mj_instructions = mujoco_instructions(folder)
        ours_rk4 = cycles[("fmi2", "rk4", "hover")]["run_cycles"]
        ours_adaptive = cycles[("fmi2", "dopri5", "hover")]["run_cycles"]
        lines.append(f"MuJoCo RK4 mj_step: {mj_instructions:,.0f} instructions per step (callgrind, 200 steps); ratio to "
                     f"our full FMI 2 cycle: RK4 {mj_instructions / ours_rk4:.0f}x, adaptive default "
                     f"{mj_instructions / ours_adaptive:.0f}x")
    text = "\n".join(lines)
    print(text)
    (OUT / "cycle.txt").write_text(text + "\n")
    shutil.rmtree(folder, ignore_errors=True)


if __name__ == "__main__":
    main()
