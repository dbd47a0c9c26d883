"""Fuzzed hydraulic legs on a Dask cluster on loopback (docs/model.md §10b): random valve
commands (beyond saturation too), pump stops and restarts, random air fractions and polytropic
exponents, both integrators; half the runs with the power unit (`hydraulic.supply = 1`, §10b:
`pump.speed` stopping and restarting, beyond [0, 1] too, random accumulator volumes and
precharges, down to ones that empty). No run gives a NaN, no chamber and no supply line of oil
with air goes to or below zero absolute, and every step the FMU refuses comes with a message
that names why."""

import sys

import cloudpickle
import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

from stewart_fmu import Platform
from stewart_fmu.core import LEGS
from oracles.hydraulics import ATMOSPHERE
from test_sweep import start_cluster

SUPPLY = 16e6  # Pa, the default supply
RUNS, DURATION, STEP = 120, 2.0, 1e-3

# The Dask workers cannot import this module: its functions travel by value.
cloudpickle.register_pickle_by_value(sys.modules[__name__])


def fuzzed_run(seed):
    """One seeded run: the oil, the integrator, a piecewise-constant valve command per leg in
    [-1.5, 1.5] (held 20-400 ms), the pump stopping once and perhaps starting again. Returns what
    the test checks: the lowest chamber pressure over the steps and `pmin`, whether any output
    was NaN, and the status (`ok` or the message of the refused step)."""
    rng = np.random.default_rng(seed)
    air = float(rng.uniform(0.001, 0.02))
    parameters = {"hydraulic.airFraction": air, "hydraulic.airPolytropic": float(rng.choice([1.0, 1.2, 1.4]))}
    integers = {"drive": 2, "solver.method": int(rng.choice([1, 2])), "hydraulic.supply": seed % 2}
    if seed % 2:
        parameters.update({"accumulator.volume": float(rng.uniform(1e-3, 60e-3)),
                           "accumulator.precharge": float(rng.uniform(2e6, 15e6))})
    steps = int(round(DURATION / STEP))
    valves = np.zeros((steps, 6))
    for k in range(6):
        i = 0
        while i < steps:
            n = int(rng.integers(20, 400))
            valves[i:i + n, k] = rng.uniform(-1.5, 1.5)
            i += n
    stop = float(rng.uniform(0.1, 1.8))
    restart = float(rng.uniform(stop, 2.5))
    events = []
    pl = Platform(parameters=parameters, integers=integers, events=events, name=f"fuzz{seed}")
    names = ([f"l[{k}]" for k in LEGS] + [f"pA[{k}]" for k in LEGS] + [f"pB[{k}]" for k in LEGS]
             + ["supply.pressure"])
    running = float(rng.uniform(0.5, 1.5))
    valve_vrs = [pl.vr[f"valve[{k}]"] for k in LEGS]
    lowest, lowest_supply, nan, status = np.inf, np.inf, False, "ok"
    try:
        for i in range(steps):
            t = i * STEP
            pl.slave.setReal(valve_vrs, [float(v) for v in valves[i]])
            on = t < stop or t >= restart
            if seed % 2:
                pl.slave.setReal([pl.vr["pump.speed"]], [running if on else float(rng.uniform(-0.5, 0.0))])
            else:
                pl.slave.setReal([pl.vr["pS"]], [SUPPLY if on else 0.0])
            pl.step(STEP)
            values = np.array(pl.get(*names))
            nan |= bool(np.any(~np.isfinite(values)))
            lowest = min(lowest, float(np.min(values[6:18])))
            lowest_supply = min(lowest_supply, float(values[18]))
        pmin = pl.get("pmin")[0]
    except FMICallException:
        status = pl.last_problem() or ""
        pmin = np.nan
    finally:
        pl.free()
    return {"seed": seed, "air": air, "lowest": lowest, "pmin": pmin, "nan": nan, "status": status,
            "method": integers["solver.method"], "power_unit": bool(seed % 2),
            "lowest_supply": lowest_supply}


@pytest.fixture(scope="module")
def fuzzed(tmp_path_factory):
    from distributed import Client
    cluster = start_cluster(tmp_path_factory.mktemp("dask"))
    address, _ = next(cluster)
    try:
        with Client(address, timeout=60) as client:
            # A lambda: Dask pickles a module-level function by name, which the workers cannot import.
            results = client.gather(client.map(lambda seed: fuzzed_run(seed), range(RUNS), pure=False))
    finally:
        next(cluster, None)
    refused = [r for r in results if r["status"] != "ok"]
    closest = min(results, key=lambda r: r["lowest"])
    line = min((r for r in results if r["power_unit"]), key=lambda r: r["lowest_supply"])
    print(f"{RUNS} fuzzed hydraulic runs on Dask ({DURATION} s at {STEP * 1e3:.0f} ms, valve commands in [-1.5, 1.5], "
          f"pump stops, air 0.1-2 %): {len(refused)} refused steps; lowest chamber pressure "
          f"{closest['lowest']:.4e} Pa gauge = {closest['lowest'] + ATMOSPHERE:.4e} Pa absolute (seed {closest['seed']}, "
          f"air {closest['air']:.4f}, power unit {closest['power_unit']}); refusals: "
          f"{sorted(set(r['status'][:100] for r in refused))[:5]}; lowest supply line (power unit) "
          f"{line['lowest_supply'] + ATMOSPHERE:.4e} Pa absolute (seed {line['seed']})")
    return results


def test_no_fuzzed_run_gives_a_nan_or_a_pressure_at_or_below_zero_absolute(fuzzed):
    for r in fuzzed:
        assert not r["nan"], r
        assert r["lowest"] > -ATMOSPHERE, r
        assert r["lowest_supply"] > -ATMOSPHERE, r
        if r["status"] == "ok":
            assert -ATMOSPHERE < r["pmin"] <= r["lowest"], r


def test_every_refused_step_is_named(fuzzed):
    """A refused step (if any) carries the FMU's message of why; most runs go through."""
    for r in fuzzed:
        if r["status"] != "ok":
            assert len(r["status"]) > 20 and ("t = " in r["status"] or "leg" in r["status"]), r
    assert sum(r["status"] == "ok" for r in fuzzed) >= 0.9 * len(fuzzed)
