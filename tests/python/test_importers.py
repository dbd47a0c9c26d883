"""The packaged FMU in two FMI importers besides FMPy: libcosim (Open Simulation Platform,
through libcosimpy from PyPI; FMI Library parser, calls from worker threads, set/get
iterations in Initialization Mode) and fmi-sim (rust-fmi, from crates.io). Each run is
compared with the same run driven from FMPy's FMU2Slave."""

import csv
import math
import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from stewart_fmu import PLATFORM_FMU, ROOT, Platform

FORCE = 5900.715
OUTPUTS = ["r[1]", "r[2]", "r[3]", "angles[1]", "angles[2]", "angles[3]", "l[1]", "l[4]", "E"]


def relative_difference(a, b):
    return float(np.max(np.abs(a - b) / np.maximum(1.0, np.abs(b))))


def fmpy_run(steps, h, forces_at=None, reals=None, integers=None):
    """Reference: the same run from FMPy, outputs after each step."""
    pl = Platform(parameters=reals, integers=integers)
    rows = []
    for i in range(steps):
        if forces_at is not None:
            pl.set_forces(forces_at(pl.time))
        pl.step(h)
        rows.append(pl.get(*OUTPUTS))
    pl.free()
    return np.array(rows)


def test_libcosim_runs_the_fmu_like_fmpy():
    from libcosimpy.CosimEnums import CosimVariableType
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave

    from fmpy import read_model_description
    vr = {v.name: v.valueReference for v in read_model_description(str(PLATFORM_FMU)).modelVariables}
    step_ns = 10_000_000  # 10 ms
    execution = CosimExecution.from_step_size(step_size=step_ns)
    slave = CosimLocalSlave(fmu_path=str(PLATFORM_FMU), instance_name="platform")
    index = execution.add_local_slave(local_slave=slave)
    # A tilted start, a stronger first leg and the fixed-step integrator, set as libcosim
    # initial values (applied in Initialization Mode).
    assert execution.real_initial_value(slave_index=index, variable_reference=vr["F[1]"], value=6000.0)
    assert execution.real_initial_value(slave_index=index, variable_reference=vr["angles0[1]"], value=0.01)
    assert execution.integer_initial_value(slave_index=index, variable_reference=vr["solver.method"], value=2)
    observer = CosimObserver.create_time_series()
    execution.add_observer(observer=observer)
    for name in OUTPUTS:
        observer.start_time_series(index, value_reference=vr[name], variable_type=CosimVariableType.REAL)
    assert execution.simulate_until(target_time=100 * step_ns)
    series = {}
    for name in OUTPUTS:
        steps, times, values = observer.time_series_real_samples(index, value_reference=vr[name], from_step=1,
                                                                  sample_count=100)
        series[name] = np.array(values)
    got = np.column_stack([series[n] for n in OUTPUTS])
    want = fmpy_run(100, 0.01, reals={"F[1]": 6000.0, "angles0[1]": 0.01}, integers={"solver.method": 2})
    difference = relative_difference(got, want)
    print(f"libcosim vs FMPy, 100 steps of 10 ms: max relative difference {difference:.1e}")
    assert got.shape == want.shape
    assert np.ptp(want[:, 2]) > 1e-4  # the platform moves
    # The same arithmetic, whoever calls it; libcosim's communication points (integer
    # nanoseconds) differ from FMPy's accumulated ones by a few ulps.
    assert difference < 1e-12


def fmi_sim_binary():
    path = os.environ.get("FMI_SIM") or shutil.which("fmi-sim") or str(ROOT / "target" / "tools" / "bin" / "fmi-sim")
    if not Path(path).exists():
        pytest.fail("fmi-sim is not installed: tests/run_all.sh installs it with "
                    "`cargo install fmi-sim --root target/tools`")
    return path


def test_fmi_sim_runs_the_fmu_like_fmpy(tmp_path):
    """fmi-sim (rust-fmi) with start values and leg forces from a CSV input file."""
    h, steps = 0.01, 100

    def forces_at(t):
        return [FORCE + 100.0 * math.sin(3.0 * t + k) for k in range(6)]

    inputs = tmp_path / "forces.csv"
    with open(inputs, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["time"] + [f"F[{k}]" for k in range(1, 7)])
        for i in range(steps + 1):
            w.writerow([repr(i * h)] + [repr(x) for x in forces_at(i * h)])
    out = tmp_path / "out.csv"
    cmd = [fmi_sim_binary(), "--model", str(PLATFORM_FMU), "-i", str(inputs), "-o", str(out), "co-simulation",
           "--step", str(h), "-f", "1.0", "--init-values", "angles0[2]=0.005"]
    run = subprocess.run(cmd, capture_output=True, text=True)
    assert run.returncode == 0, run.stderr[-2000:]
    with open(out) as f:
        rows = list(csv.DictReader(f))
    got = np.array([[float(r[n]) for n in OUTPUTS] for r in rows[1:]])
    want = fmpy_run(steps, h, forces_at=forces_at, reals={"angles0[2]": 0.005})
    difference = relative_difference(got, want)
    print(f"fmi-sim vs FMPy, 100 steps of 10 ms with CSV forces: max relative difference {difference:.1e}")
    assert got.shape == want.shape
    assert np.ptp(want[:, 2]) > 1e-4
    assert difference < 1e-12


def rest_height_on_stops(force, lower):
    """Pure-heave rest of the default stand with every leg pushing `force` (N) and resting on
    its lower (or upper) stops, from the default stand's geometry (docs/model.md §3) and the FMU's stop defaults:
    6 (force +- k_s delta) H / l = M g."""
    from stewart_fmu.workspace import stop_defaults
    from test_workspace import horizontal_leg_projection
    lmin, lmax, k, _ = stop_defaults()
    d = horizontal_leg_projection()
    limit = lmin if lower else lmax

    def excess(h):
        l = math.hypot(d, h)
        stop = k * (limit - l) if lower else -k * (l - limit)
        return 6.0 * (force + stop) * h / l - 3000.0 * 9.81

    h_limit = math.sqrt(limit**2 - d**2)
    lo, hi = (h_limit - 0.05, h_limit) if lower else (h_limit, h_limit + 0.05)
    assert excess(lo) > 0 > excess(hi)
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        # Above the root the stops' (or the legs') net lift falls short of the weight.
        if excess(mid) > 0:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi) + 0.5


@pytest.mark.parametrize("offset", [-0.05, 0.05])
def test_open_loop_forces_five_percent_off_equilibrium_settle_on_the_stops_in_every_host(offset, tmp_path):
    """Open-loop leg forces 5 % below (above) the equilibrium force for 10 s: the platform
    sinks (rises) onto its lower (upper) stops and rests there, in FMPy, libcosim and fmi-sim
    alike, without a discard."""
    from fmpy import simulate_fmu
    from libcosimpy.CosimEnums import CosimVariableType
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave

    force = FORCE * (1.0 + offset)
    expected = rest_height_on_stops(force, lower=offset < 0)
    forces = {f"F[{k}]": force for k in range(1, 7)}
    finals = {}
    # FMPy
    r = simulate_fmu(str(PLATFORM_FMU), start_values=forces, stop_time=10.0, output_interval=0.01,
                     output=["r[3]", "Fstop[1]"])
    assert abs(r["time"][-1] - 10.0) < 1e-9
    finals["FMPy"] = r["r[3]"][-1]
    # libcosim
    from fmpy import read_model_description
    vr = {v.name: v.valueReference for v in read_model_description(str(PLATFORM_FMU)).modelVariables}
    step_ns = 10_000_000
    execution = CosimExecution.from_step_size(step_size=step_ns)
    index = execution.add_local_slave(local_slave=CosimLocalSlave(fmu_path=str(PLATFORM_FMU), instance_name="p"))
    for name, value in forces.items():
        assert execution.real_initial_value(slave_index=index, variable_reference=vr[name], value=value)
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer=observer)
    assert execution.simulate_until(target_time=1000 * step_ns)
    finals["libcosim"] = observer.last_real_values(slave_index=index, variable_references=[vr["r[3]"]])[0]
    # fmi-sim
    inputs = tmp_path / "forces.csv"
    with open(inputs, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["time"] + list(forces))
        for t in (0.0, 10.0):
            w.writerow([repr(t)] + [repr(force)] * 6)
    out = tmp_path / "out.csv"
    run = subprocess.run([fmi_sim_binary(), "--model", str(PLATFORM_FMU), "-i", str(inputs), "-o", str(out),
                          "co-simulation", "--step", "0.01", "-f", "10.0"], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr[-2000:]
    with open(out) as f:
        rows = list(csv.DictReader(f))
    assert abs(float(rows[-1]["time"]) - 10.0) < 1e-9
    finals["fmi-sim"] = float(rows[-1]["r[3]"])
    print(f"forces {1 + offset:.2f} x equilibrium for 10 s: rest z " + ", ".join(
        f"{host} {z:.9f} m" for host, z in finals.items()) + f"; static solution on the "
          f"{'lower' if offset < 0 else 'upper'} stops {expected:.9f} m")
    for host, z in finals.items():
        assert abs(z - expected) < 1e-6, f"{host}: {z} vs {expected}"
