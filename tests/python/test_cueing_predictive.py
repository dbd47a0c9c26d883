"""Predictive cueing (cueing.method = 1, SPEC §12, docs/cueing.md): what the driver perceives
on the main job's manoeuvres against the classical washout's, the legs inside their margins
on 300 fuzzed drives on a Dask cluster on loopback with the solves' success and the
command's smoothness there, the solver's counters (mpc.fallbacks, mpc.acceptable), FMI 3
against FMI 2 bit for bit, a preview file of a recorded drive, and the refusals (Model
Exchange, a bad preview file)."""

import math
import sys
from pathlib import Path

import cloudpickle
import numpy as np
import pytest
from fmpy import read_model_description

from stewart_fmu import cueing, vehicle
from stewart_fmu.core import CUEING_FMU, LEGS, Component, stand_parameters
from references import check_figures
from test_cueing import leg_lengths, start_values
from test_sweep import start_cluster

FMI3_CUEING = Path(CUEING_FMU).parent / "fmi3" / "StewartCueing.fmu"
PREDICTIVE = {"cueing.method": 1}
#: The main job's manoeuvres (examples/cueing_scenarios.py's JUDGED).
MANOEUVRES = {**vehicle.MANOEUVRES, "emergency_stop": vehicle.HARSH["emergency_stop"],
              "pothole": vehicle.HARSH["pothole"]}
#: The manoeuvres on which SPEC 12's issue asks for a perceived error lower by a quarter.
BY_A_QUARTER = ("slalom", "lane_change", "brake")


def both_methods(manoeuvre):
    """The manoeuvre through the cueing FMU alone with each method, 10 ms communication steps
    with the inputs following their chords (the FMU's internal steps stay at 1 ms)."""
    record = cueing.RECORDED + ["mpc.fallbacks"]
    return {"classical": cueing.run(manoeuvre, h=0.01, first_order=True, record=record),
            "predictive": cueing.run(manoeuvre, h=0.01, first_order=True, record=record, integers=PREDICTIVE)}


@pytest.fixture(scope="module")
def measured():
    return {name: {method: (cueing.measures(run), int(run["mpc.fallbacks"][-1]))
                   for method, run in both_methods(make()).items()} for name, make in MANOEUVRES.items()}


def test_predictive_cueing_is_perceived_closer_to_the_vehicle_than_the_washout(measured):
    """On every main-job manoeuvre the predictive method's perceived horizontal specific-force
    error (rms over x and y) is no higher than the classical washout's (bumps and pothole have
    none to speak of with either: within 0.01 m/s2 there), lower by at least a quarter on the
    slalom and the lane change, and its mean correlation over the manoeuvres is not lower; no
    solve fails. The braking falls short of a quarter: the docs say why (the measured numbers
    are printed)."""
    rows, correlation = [], {"classical": [], "predictive": []}
    for name, m in measured.items():
        c, p = m["classical"][0], m["predictive"][0]
        assert m["predictive"][1] == 0, f"{name}: {m['predictive'][1]} solves failed"
        gain = 1 - p["perceived_error"] / c["perceived_error"] if c["perceived_error"] > 0.01 else float("nan")
        rows.append(f"{name}: classical {c['perceived_error']:.3f}, predictive {p['perceived_error']:.3f} m/s2"
                    + (f" ({100 * gain:.0f} % lower)" if gain == gain else "")
                    + f"; correlation {c['correlation']:.2f} -> {p['correlation']:.2f}")
        for method in correlation:
            correlation[method].append(m[method][0]["correlation"])
        if c["perceived_error"] > 0.01:
            assert p["perceived_error"] < c["perceived_error"], rows[-1]
        else:
            assert p["perceived_error"] < c["perceived_error"] + 0.01, rows[-1]
        if name in BY_A_QUARTER and name != "brake":
            assert gain >= 0.25, rows[-1]
    mean = {k: float(np.nanmean(v)) for k, v in correlation.items()}
    print("\n".join(rows) + f"\nmean correlation: classical {mean['classical']:.2f}, predictive {mean['predictive']:.2f}")
    assert mean["predictive"] >= mean["classical"], mean


# The Dask workers cannot import this module: its functions travel by value.
cloudpickle.register_pickle_by_value(sys.modules[__name__])


def fuzzed_drive(seed, duration=8.0, f_limit=8.0, omega_limit=0.5, dt=0.01):
    """A fuzzed vehicle motion per axis: smoothed steps, a chirp (0.1 to 10 rad/s) and
    recorded-like noise (white noise low-passed at 1 to 8 rad/s), the specific force's
    deviation from rest within +-f_limit (m/s2) and the angular velocity within +-omega_limit
    (rad/s). Seeded."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(round(duration / dt)) + 1) * dt
    columns = {"time": t}
    for name, limit, rest in (("f", f_limit, (0.0, 0.0, vehicle.G)), ("omega", omega_limit, (0.0, 0.0, 0.0))):
        for k in range(3):
            x = np.zeros_like(t)
            kind = rng.integers(3)
            if kind == 0:
                for _ in range(3):
                    x += rng.uniform(-1, 1) * vehicle.smooth_step(t, rng.uniform(0, duration), rng.uniform(0.05, 1.5))
            elif kind == 1:
                w0, w1 = 10 ** rng.uniform(-1, 0), 10 ** rng.uniform(0, 1)
                phase = np.cumsum(w0 * (w1 / w0) ** (t / duration)) * dt
                x += rng.uniform(0.3, 1) * np.sin(phase) * vehicle.smooth_step(t, 0.5, 1.0)
            else:
                noise = rng.standard_normal(len(t))
                w = rng.uniform(1, 8)
                y = 0.0
                for i, n in enumerate(noise):
                    y += dt * w * (n * math.sqrt(2 / (w * dt)) - y)
                    x[i] = y
            scale = limit * rng.uniform(0.2, 1.0) / max(1e-9, float(np.max(np.abs(x))))
            columns[f"{name}[{k + 1}]"] = rest[k] + scale * x
    return columns


@pytest.fixture(scope="module")
def fuzzed(tmp_path_factory):
    """300 fuzzed drives (steps, chirps and recorded-like noise within +-8 m/s2 and +-0.5
    rad/s) through predictive cueing on a Dask cluster on loopback, measured: the closest
    approach of any leg of any commanded pose to its margin (computed here from pose.r,
    pose.angles and the stand), the largest roll or pitch of any command, the largest residual
    of the Hermite rule over a step (the command's velocity and acceleration against its
    position's change), the failed solves."""
    from distributed import Client
    stand = stand_parameters(nondimensional=False)
    p = start_values()
    lower = np.array([p[f"lmin[{k}]"] + p["margin"] for k in LEGS])
    upper = np.array([p[f"lmax[{k}]"] - p["margin"] for k in LEGS])
    record = cueing.POSE + ["workspace.scale", "mpc.fallbacks", "mpc.iterations"]
    budget = int(next(v for v in read_model_description(str(CUEING_FMU)).modelVariables
                      if v.name == "mpc.maxIterations").start)
    cluster = start_cluster(tmp_path_factory.mktemp("dask"))
    address, _ = next(cluster)
    try:
        with Client(address, timeout=60) as client:
            futures = client.map(lambda seed: cueing.run(fuzzed_drive(seed), h=0.01, record=record, first_order=True,
                                                         integers=PREDICTIVE), range(300), pure=False)
            results = client.gather(futures)
    finally:
        next(cluster, None)
    m = {"closest": np.inf, "closest_seed": None, "worst_v": 0.0, "fallbacks": 0, "solves": 0, "netted": 0,
         "drives_falling_back": 0, "at_budget": 0, "tilt": 0.0, "tilt_max": p["tilt.max"]}
    for seed, r in enumerate(results):
        pos = np.column_stack([r[f"pose.r[{k}]"] for k in (1, 2, 3)])
        ang = np.column_stack([r[f"pose.angles[{k}]"] for k in (1, 2, 3)])
        l = leg_lengths(pos, ang, stand)
        gap = min(np.min(l - lower), np.min(upper - l))
        if gap < m["closest"]:
            m["closest"], m["closest_seed"] = gap, seed
        m["netted"] += bool(np.min(r["workspace.scale"]) < 1.0)
        m["tilt"] = max(m["tilt"], float(np.max(np.abs(ang[:, :2]))))
        v = np.column_stack([r[f"pose.v[{k}]"] for k in (1, 2, 3)])
        a = np.column_stack([r[f"pose.a[{k}]"] for k in (1, 2, 3)])
        h = 0.01
        hermite = h / 2 * (v[1:] + v[:-1]) + h * h / 12 * (a[:-1] - a[1:])
        m["worst_v"] = max(m["worst_v"], float(np.max(np.abs(np.diff(pos, axis=0) - hermite))) / h)
        failed = int(r["mpc.fallbacks"][-1])
        m["fallbacks"] += failed
        m["drives_falling_back"] += failed > 0
        m["solves"] += int(round(r["time"][-1] / 0.01)) + 1
        # One solve per 10 ms step: its count; at the budget, kept at the looser 1e-6 (or
        # converged on the last pass).
        m["at_budget"] += int(np.sum(np.asarray(r["mpc.iterations"])[1:] >= budget))
    print(f"300 fuzzed drives, predictive cueing on Dask: closest approach to a margin {m['closest'] * 1e3:.3f} mm "
          f"(seed {m['closest_seed']}), the net acted in {m['netted']} drives, largest roll or pitch "
          f"{math.degrees(m['tilt']):.4f} deg (tilt.max {math.degrees(m['tilt_max']):.1f}), largest Hermite "
          f"residual of r over a step {m['worst_v']:.2e} m/s, {m['fallbacks']} failed solves of {m['solves']} in "
          f"{m['drives_falling_back']} drives, {m['at_budget']} solves at the iteration budget ({budget})")
    return m


def test_the_commands_keep_every_leg_inside_its_margins_on_fuzzed_drives(fuzzed):
    """Whatever the solves do, no leg of any command on the 300 fuzzed drives leaves
    [lmin + margin, lmax - margin] (the workspace limiter's net)."""
    assert fuzzed["closest"] > -1e-9, fuzzed


def test_the_commands_keep_their_tilt_within_tilt_max_on_fuzzed_drives(fuzzed):
    """No command's roll or pitch on the 300 fuzzed drives passes tilt.max by more than 0.02
    deg. The plans hold the tilt at grid points 1, 3, 7 and 20 only (the first 35 ms ahead),
    and a row may give by the shared slack where the bounds conflict, so a command may pass the
    bound by a hair (10.0055 deg at most against 10, measured 2026-12-03)."""
    assert fuzzed["tilt"] < fuzzed["tilt_max"] + math.radians(0.02), fuzzed


def test_the_fuzzed_drives_figures_are_the_ones_the_docs_quote(fuzzed):
    """docs/cueing.md's figures of the 300 fuzzed drives, in benches/results/cueing.txt (the
    drives are seeded and the FMU's bits the same on every platform)."""
    check_figures("cueing.txt", "predictive cueing, 300 fuzzed drives",
                  f"{fuzzed['fallbacks']} failed solves of {fuzzed['solves']}, {fuzzed['at_budget']} at the iteration "
                  f"budget, the net acted in {fuzzed['netted']} drives, closest approach to a margin "
                  f"{fuzzed['closest'] * 1e3:.3f} mm, largest roll or pitch {math.degrees(fuzzed['tilt']):.4f} deg, "
                  f"largest Hermite residual of r over a step {fuzzed['worst_v']:.1e} m/s")


def test_the_solves_succeed_and_the_command_is_smooth_on_fuzzed_drives(fuzzed):
    """The failed solves are below 1 % of the solves, and the command's velocity and
    acceleration give its position's change over each step by the Hermite rule: the plans'
    jerks are held between solves, so the command is C2 and the rule exact to the step's fifth
    power; a jump (the net pulling back) would show as a residual of m/s."""
    assert fuzzed["fallbacks"] < 0.01 * fuzzed["solves"], fuzzed
    assert fuzzed["worst_v"] < 0.03, fuzzed


def test_the_counters_tell_failed_and_acceptable_solves_apart():
    """`mpc.fallbacks` counts the solves with no iterate within the acceptable level (1e-6),
    `mpc.acceptable` those that ended on one without reaching the tolerance (1e-8). On the
    slalom, one solve per 10 ms step: with 13 iterations, too few for this problem, both
    counters rise, by at most one a step, and (no factorisation breaks down on this drive) only
    on solves that used the whole budget; with the default 30 every solve converges and both
    stay at 0."""
    def counters(budget):
        r = cueing.run(vehicle.MANOEUVRES["slalom"](), h=0.01, integers={**PREDICTIVE, "mpc.maxIterations": budget},
                       record=["mpc.iterations", "mpc.acceptable", "mpc.fallbacks"])
        return tuple(np.asarray(r[n], dtype=np.int64) for n in ("mpc.iterations", "mpc.acceptable", "mpc.fallbacks"))

    iterations, acceptable, fallbacks = counters(13)
    rises = np.diff(acceptable), np.diff(fallbacks)
    solves = len(iterations) - 1
    at_budget = int(np.sum(iterations[1:] == 13))
    print(f"slalom, 13 iterations: {solves} solves, {at_budget} at the budget, {acceptable[-1]} kept at the "
          f"acceptable level, {fallbacks[-1]} failed")
    for rise in rises:
        assert set(np.unique(rise)) <= {0, 1}, "a counter fell or rose by more than one solve in a step"
    assert np.all(rises[0] + rises[1] <= 1), "one solve counted twice"
    assert acceptable[-1] > 0 and fallbacks[-1] > 0, "with too few iterations both kinds of solve occur"
    assert np.all(iterations[1:][(rises[0] + rises[1]) == 1] == 13), "a counted solve stopped before its budget"
    iterations, acceptable, fallbacks = counters(30)
    print(f"slalom, 30 iterations (the default): at most {iterations.max()} per solve")
    assert acceptable[-1] == 0 and fallbacks[-1] == 0 and iterations.max() < 30


def test_a_saved_state_keeps_the_plan_and_the_solvers_counters():
    """Predictive cueing with a tight budget (13 iterations) saved after 5 s of the slalom,
    serialized and restored into another instance: the next second's commands and the
    counters (mpc.iterations, mpc.acceptable, mpc.fallbacks) equal the uninterrupted run's."""
    m = vehicle.MANOEUVRES["slalom"]()
    integers = {**PREDICTIVE, "mpc.maxIterations": 13}
    names = ["mpc.iterations", "mpc.acceptable", "mpc.fallbacks"]

    def steps(c, i0, i1):
        out = []
        for i in range(i0, i1):
            c.set_values(cueing.F + cueing.OMEGA, np.concatenate(vehicle.at(m, i * 0.01)))
            c.step(0.01)
            out.append(np.concatenate([c.values(cueing.POSE), c.slave.getInteger([c.vr[n] for n in names])]))
        return np.array(out)

    a = Component(CUEING_FMU, "a", {}, integers)
    b = Component(CUEING_FMU, "b", {}, integers)
    try:
        before = steps(a, 0, 500)
        assert before[-1, -2] > 0 and before[-1, -1] > 0, "both kinds of counted solve before the save"
        state, saved_at = a.slave.serializeFMUstate(a.slave.getFMUstate()), a.time
        whole = steps(a, 500, 600)
        b.slave.setFMUstate(b.slave.deSerializeFMUstate(state))
        b.time = saved_at
        assert np.array_equal(steps(b, 500, 600), whole)
    finally:
        a.free()
        b.free()


def test_fmi3_equals_fmi2_bit_for_bit_with_predictive_cueing():
    """The FMI 3 cueing FMU gives the FMI 2 one's outputs to the bit on a lane change with
    predictive cueing."""
    from fmpy import extract
    from fmpy.fmi3 import FMU3Slave
    m = vehicle.lane_change(duration=6.0)
    names = cueing.POSE + cueing.FSIM + cueing.OMEGASIM + cueing.PERCEIVED_SIM
    two = cueing.run(m, h=0.01, record=names, integers=PREDICTIVE)
    md = read_model_description(str(FMI3_CUEING))
    var = {v.name: v.valueReference for v in md.modelVariables}
    slave = FMU3Slave(guid=md.guid, unzipDirectory=extract(str(FMI3_CUEING)), modelIdentifier="StewartCueing",
                      instanceName="fmi3")
    slave.instantiate()
    slave.enterInitializationMode()
    slave.setInt32([var["cueing.method"]], [1])
    slave.exitInitializationMode()
    arrays = ["pose.r", "pose.v", "pose.a", "pose.angles", "pose.angleRates", "pose.angleAccelerations", "fsim",
              "omegasim", "perceived.fsim", "perceived.omegasim"]
    rows, time = [], 0.0
    for i in range(len(two["time"])):
        f, w = vehicle.at(m, time)
        slave.setFloat64([var["f"]], list(f))
        slave.setFloat64([var["omega"]], list(w))
        rows.append(np.concatenate([slave.getFloat64([var[a]], 3) for a in arrays]))
        if i < len(two["time"]) - 1:
            slave.doStep(currentCommunicationPoint=time, communicationStepSize=0.01)
            time += 0.01
    slave.terminate()
    slave.freeInstance()
    rows = np.array(rows)
    for j, n in enumerate(names):
        assert np.array_equal(rows[:, j], two[n]), n


def test_a_preview_of_the_drive_is_read_and_used(tmp_path):
    """A preview file of the braking (the recorded drive) changes the plans: the perceived error
    is lower than with the inputs held, and a quarter below the classical washout's (SPEC §12's
    issue asks it of the braking). Within the preview's rows the errors weigh in full, so
    `mpc.trust` changes no bit until the horizon passes the last row. A file without a column,
    with times that do not increase, or that is missing is refused at initialisation with a
    message naming it."""
    m = vehicle.brake()
    path = vehicle.write_csv(m, tmp_path / "brake.csv")
    classical = cueing.measures(cueing.run(m, h=0.01, first_order=True))
    held = cueing.measures(cueing.run(m, h=0.01, first_order=True, integers=PREDICTIVE))
    record = ["perceived.fsim[1]", "pose.angles[2]", "pose.r[1]"]
    runs = [cueing.run(m, h=0.01, first_order=True, integers=PREDICTIVE, record=cueing.RECORDED + record,
                       strings={"preview.file": str(path)}, parameters={"mpc.trust": trust}) for trust in (0.6, 5.0)]
    ahead = cueing.measures(runs[0])
    print(f"braking: perceived error {classical['perceived_error']:.3f} m/s2 classical, {held['perceived_error']:.3f} "
          f"predictive with the inputs held, {ahead['perceived_error']:.3f} with its preview")
    assert ahead["perceived_error"] < held["perceived_error"]
    assert ahead["perceived_error"] < 0.75 * classical["perceived_error"]
    known = runs[0]["time"] <= m["time"][-1] - 2.0       # the default mpc.horizon, 2 s
    for n in record:
        assert np.array_equal(runs[0][n][known], runs[1][n][known]), n
    bad = {"no column": "time,f[1],f[2],f[3],omega[1],omega[2]\n0,0,0,9.81,0,0\n1,0,0,9.81,0,0\n",
           "times": "time,f[1],f[2],f[3],omega[1],omega[2],omega[3]\n0,0,0,9.81,0,0,0\n0,0,0,9.81,0,0,0\n"}
    for why, text in bad.items():
        f = tmp_path / f"{why}.csv"
        f.write_text(text)
        with pytest.raises(Exception):
            Component(CUEING_FMU, "bad", {"preview.file": str(f)}, PREDICTIVE)
    with pytest.raises(Exception):
        Component(CUEING_FMU, "missing", {"preview.file": str(tmp_path / "nowhere.csv")}, PREDICTIVE)


def test_model_exchange_refuses_predictive_cueing_with_a_reason():
    """Model Exchange with cueing.method = 1 ends at initialisation with a message that says
    why and what to use. (Not through simulate_fmu's `logger`: FMPy keeps that callback in a
    process-wide logging proxy, which then points at a freed callback for every later FMU.)"""
    from fmpy import extract, read_model_description
    from fmpy.fmi1 import FMICallException
    from fmpy.fmi2 import FMU2Model

    from stewart_fmu.core import recording_callbacks
    md = read_model_description(str(CUEING_FMU))
    messages = []
    fmu = FMU2Model(guid=md.guid, unzipDirectory=extract(str(CUEING_FMU)), modelIdentifier=md.modelExchange.modelIdentifier,
                    instanceName="refused")
    fmu.instantiate(callbacks=recording_callbacks(messages), loggingOn=True)
    try:
        vr = next(v.valueReference for v in md.modelVariables if v.name == "cueing.method")
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        fmu.setInteger([vr], [1])
        with pytest.raises(FMICallException):
            fmu.exitInitializationMode()
    finally:
        fmu.freeInstance()
    texts = [text for _, _, text in messages]
    assert any("Co-Simulation only" in m for m in texts), texts
