"""The motion cueing FMU (StewartCueing, docs/cueing.md, SPEC §11): the Objective Motion Cueing
Test against the transfer functions of §11's filters computed here, the steady states of a
sustained braking, the workspace limiter on fuzzed manoeuvres on a Dask cluster on loopback,
FMI 3 against FMI 2 bit for bit, Model Exchange against Co-Simulation, FMU states, clear
refusals of bad parameters, and the whole motion system (cueing -> controller -> platform)
with FMPy's driver and with libcosim."""

import math
from pathlib import Path

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu

from stewart_fmu import cueing, vehicle
from stewart_fmu.core import CUEING_FMU, GRAVITY as G, LEGS, Component, stand_parameters
from stewart_fmu.ssp import MOTION_SYSTEM_SSP
from references import check_figures
from test_sweep import cluster, start_cluster  # noqa: F401 - cluster is a fixture
FMI3_CUEING = Path(CUEING_FMU).parent / "fmi3" / "StewartCueing.fmu"


def start_values(fmu=CUEING_FMU):
    return {v.name: float(v.start) for v in read_model_description(str(fmu)).modelVariables
            if v.causality == "parameter" and v.type == "Real"}


def transfer_functions(p, s):
    """§11's filters at the small amplitude where no limit acts, for each OMCT test: the
    simulator's motion over the vehicle's, computed from the equations of SPEC §11 alone. The
    tilt coordination feeds gravity into the translational channel's input (`a_I = R f_s +
    g_vec` with the tilt), so surge and sway see `W_t (1 - W_l) + W_l`."""
    def translation(k):
        w, z, b = p[f"hp.f.omega[{k}]"], p[f"hp.f.damping[{k}]"], p[f"hp.f.break[{k}]"]
        return s ** 3 / ((s * s + 2 * z * w * s + w * w) * (s + b))

    def rotation(k):
        w, z = p[f"hp.w.omega[{k}]"], p[f"hp.w.damping[{k}]"]
        return s * s / (s * s + 2 * z * w * s + w * w)

    wl, zl = p["tilt.omega"], p["tilt.damping"]
    low = wl * wl / (s * s + 2 * zl * wl * s + wl * wl)
    return {
        "surge": p["scale.f[1]"] * (translation(1) * (1 - low) + low),
        "sway": p["scale.f[2]"] * (translation(2) * (1 - low) + low),
        "heave": p["scale.f[3]"] * translation(3),
        "roll": p["scale.omega[1]"] * rotation(1),
        "pitch": p["scale.omega[2]"] * rotation(2),
        "yaw": p["scale.omega[3]"] * rotation(3),
        # A positive pitch puts the nose down: braking (f_x < 0) pitches nose down.
        "surge -> pitch": -s * p["scale.f[1]"] * low / p["g"],
        "sway -> roll": s * p["scale.f[2]"] * low / p["g"],
    }


def test_the_omct_of_the_cueing_fmu_matches_the_filters_of_section_11():
    """Gain within 1 % and phase within 1 degree at every one of the twelve frequencies of
    every test (no limit acts at these amplitudes)."""
    result = cueing.omct()
    p = start_values()
    worst_gain, worst_phase = 0.0, 0.0
    for test, r in result.items():
        assert not r["limited"].any(), f"{test}: the limiter acted"
        expected = transfer_functions(p, 1j * r["frequency"])[test]
        gain_error = np.abs(r["gain"] / np.abs(expected) - 1)
        phase_error = np.abs((r["phase"] - np.degrees(np.angle(expected)) + 180) % 360 - 180)
        for w, ge, pe in zip(r["frequency"], gain_error, phase_error):
            assert ge < 0.01 and pe < 1.0, f"{test} at {w:.3f} rad/s: gain off by {ge:.2%}, phase by {pe:.2f} deg"
        worst_gain, worst_phase = max(worst_gain, gain_error.max()), max(worst_phase, phase_error.max())
    print(f"OMCT, 8 tests x 12 frequencies: largest gain error {worst_gain:.2e}, phase error {worst_phase:.3f} deg")
    check_figures("cueing.txt", "OMCT of the defaults against section 11's transfer functions, 96 points",
                  f"largest relative gain error {worst_gain:.1e}, largest phase error {worst_phase:.2f} deg")


def test_a_sustained_braking_becomes_a_sustained_pitch_and_the_translation_washes_out():
    """2 m/s2 of braking held for 60 s: the cabin pitches nose down to asin(K_f 2 / g) no
    faster than tilt.rateLimit; the head returns to neutral, so the centre of mass sits where
    the rotation about the head puts it."""
    p = start_values()
    t = np.arange(6001) * 0.01
    f_x = -2.0 * vehicle.smooth_step(t, 1.0, 0.5)
    manoeuvre = {"time": t, "f[1]": f_x, "f[2]": 0 * t, "f[3]": G + 0 * t, "omega[1]": 0 * t, "omega[2]": 0 * t,
                 "omega[3]": 0 * t}
    r = cueing.run(manoeuvre, h=0.01, record=cueing.POSE + ["washout.r[1]", "washout.r[3]"])
    pitch = r["pose.angles[2]"]
    target = math.asin(p["scale.f[1]"] * 2.0 / G)
    assert abs(pitch[-1] - target) < 1e-6, (pitch[-1], target)
    assert np.max(np.abs(r["pose.angleRates[2]"])) <= p["tilt.rateLimit"] * (1 + 1e-12)
    # The rate limit acts: the pitch needs target / rate limit seconds at least.
    reached = t[np.argmax(pitch > 0.99 * target)]
    assert reached - 1.0 > 0.99 * target / p["tilt.rateLimit"]
    assert abs(r["washout.r[1]"][-1]) < 1e-4 and abs(r["washout.r[3]"][-1]) < 1e-4
    head = np.array([p["head[1]"], p["head[2]"], p["head[3]"]])
    c, s_ = math.cos(pitch[-1]), math.sin(pitch[-1])
    rot_head = np.array([[c, 0, s_], [0, 1, 0], [-s_, 0, c]]) @ head
    neutral = np.array([p["neutral[1]"], p["neutral[2]"], p["neutral[3]"]])
    r_end = np.array([r[f"pose.r[{k}]"][-1] for k in (1, 2, 3)])
    assert np.max(np.abs(r_end - (neutral + head - rot_head))) < 1e-4
    print(f"sustained braking: pitch {math.degrees(pitch[-1]):.3f} deg (target {math.degrees(target):.3f}), "
          f"reached 99 % after {reached - 1.0:.2f} s, head displacement {r['washout.r[1]'][-1]:.2e} m")
    check_figures("cueing.txt", "sustained braking of 2 m/s2 for 60 s",
                  f"pitch {math.degrees(pitch[-1]):.2f} deg, asin(K_f 2 / g) = {math.degrees(target):.2f} deg")


def leg_lengths(r, angles, stand):
    """l_k = |r + R A_k - B_k| for the 1-2-3 angles, computed here (rows: instants)."""
    a, b, c = angles[:, 0], angles[:, 1], angles[:, 2]
    ca, sa, cb, sb, cc, sc = np.cos(a), np.sin(a), np.cos(b), np.sin(b), np.cos(c), np.sin(c)
    rot = np.array([[cb * cc, -cb * sc, sb],
                    [ca * sc + sa * sb * cc, ca * cc - sa * sb * sc, -sa * cb],
                    [sa * sc - ca * sb * cc, sa * cc + ca * sb * sc, ca * cb]]).transpose(2, 0, 1)
    out = []
    for k in LEGS:
        A = np.array([stand[f"A[{k},{i}]"] for i in (1, 2, 3)])
        B = np.array([stand[f"B[{k},{i}]"] for i in (1, 2, 3)])
        out.append(np.linalg.norm(r + rot @ A - B, axis=1))
    return np.array(out).T


AGGRESSIVE = {**{f"scale.f[{k}]": 1.0 for k in (1, 2, 3)}, **{f"scale.omega[{k}]": 1.0 for k in (1, 2, 3)},
              **{f"hp.f.break[{k}]": 0.15 for k in (1, 2, 3)}, "hp.f.omega[1]": 1.2, "hp.f.omega[2]": 1.2,
              "hp.w.omega[3]": 0.3, "tilt.max": math.radians(20), "tilt.rateLimit": math.radians(10)}


def test_the_limiter_keeps_every_leg_inside_its_margins_on_fuzzed_manoeuvres(cluster):  # noqa: F811
    """300 random manoeuvres (sums of steps and sinusoids within +-8 m/s2 and +-0.5 rad/s), half
    with the default washout and half with one that would leave the workspace, run on a Dask
    cluster on loopback: every leg of every commanded pose, computed here from pose.r and
    pose.angles, stays inside [lmin + margin, lmax - margin]; the limiter acts in most of the
    aggressive runs; the command's velocity and acceleration (the inputs following their chords)
    give its position's change over each step by the Hermite rule."""
    from distributed import Client
    address, _ = cluster
    stand = stand_parameters(nondimensional=False)
    p = start_values()
    lower = np.array([p[f"lmin[{k}]"] + p["margin"] for k in LEGS])
    upper = np.array([p[f"lmax[{k}]"] - p["margin"] for k in LEGS])
    record = cueing.POSE + ["workspace.scale"]
    runs = [(seed, AGGRESSIVE if seed % 2 else None) for seed in range(300)]
    with Client(address, timeout=60) as client:
        futures = client.map(lambda run: cueing.run(vehicle.random_manoeuvre(run[0]), h=0.01, parameters=run[1],
                                                    record=record, first_order=True), runs, pure=False)
        results = client.gather(futures)
    closest, limited, worst_v = np.inf, 0, 0.0
    for (seed, params), r in zip(runs, results):
        pos = np.column_stack([r[f"pose.r[{k}]"] for k in (1, 2, 3)])
        ang = np.column_stack([r[f"pose.angles[{k}]"] for k in (1, 2, 3)])
        l = leg_lengths(pos, ang, stand)
        gap = min(np.min(l - lower), np.min(upper - l))
        assert gap > -1e-9, f"seed {seed}: a leg leaves its margin by {-gap:.3e} m"
        closest = min(closest, gap)
        limited += params is not None and bool(np.min(r["workspace.scale"]) < 0.999)
        # The position's change over each step against the cubic Hermite rule on the velocity
        # and acceleration at its ends (exact to the step's fifth power of a smooth motion).
        v = np.column_stack([r[f"pose.v[{k}]"] for k in (1, 2, 3)])
        a = np.column_stack([r[f"pose.a[{k}]"] for k in (1, 2, 3)])
        h = 0.01
        hermite = h / 2 * (v[1:] + v[:-1]) + h * h / 12 * (a[:-1] - a[1:])
        worst_v = max(worst_v, float(np.percentile(np.abs(np.diff(pos, axis=0) - hermite), 99.9)) / h)
    assert limited > 100, f"the limiter acted in only {limited} of the 150 aggressive runs"
    # SPEC 11's ideal tilt limiter jumps the tilt rate where a slewing angle catches its target
    # (by up to tilt.rateLimit plus the target's rate), so the centre's velocity jumps by that
    # times the head's lever: in both halves the rule's error over such a step is about half
    # the jump, up to 0.11 m/s on these drives (benches/results/cueing.txt). A jump of the
    # workspace limiter (the first-crossing limiter of an earlier version jumped by up to 1 m/s,
    # an error of 0.5 m/s) would stand above it.
    assert worst_v < 0.25, worst_v
    figures = (f"closest approach to a margin {closest * 1e3:.3f} mm, the limiter acted in {limited} of 150 "
               f"aggressive runs, 99.9th percentile of the Hermite residual of r over a step at most {worst_v:.2f} m/s")
    print(f"300 fuzzed manoeuvres on Dask: {figures}")
    check_figures("cueing.txt", "the classical limiter, 300 fuzzed manoeuvres", figures)


def test_fmi3_equals_fmi2_bit_for_bit():
    """The FMI 3 cueing FMU gives the FMI 2 one's outputs to the bit on a lane change."""
    from fmpy import extract
    from fmpy.fmi3 import FMU3Slave
    m = vehicle.lane_change(duration=6.0)
    names = cueing.POSE + cueing.FSIM + cueing.OMEGASIM
    two = cueing.run(m, h=0.01, record=names)
    md = read_model_description(str(FMI3_CUEING))
    var = {v.name: v.valueReference for v in md.modelVariables}
    slave = FMU3Slave(guid=md.guid, unzipDirectory=extract(str(FMI3_CUEING)), modelIdentifier="StewartCueing",
                      instanceName="fmi3")
    slave.instantiate()
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    arrays = ["pose.r", "pose.v", "pose.a", "pose.angles", "pose.angleRates", "pose.angleAccelerations", "fsim",
              "omegasim"]
    rows, time = [], 0.0
    for i in range(len(two["time"])):
        f, w = vehicle.at(m, time)
        slave.setFloat64([var["f"]], list(f))
        slave.setFloat64([var["omega"]], list(w))
        rows.append(np.concatenate([slave.getFloat64([var[a]], 3) for a in arrays]))
        if i < len(two["time"]) - 1:
            # The communication points summed, as the FMI 2 driver counts them.
            slave.doStep(currentCommunicationPoint=time, communicationStepSize=0.01)
            time += 0.01
    slave.terminate()
    slave.freeInstance()
    rows = np.array(rows)
    for j, n in enumerate(names):
        assert np.array_equal(rows[:, j], two[n]), n


def test_model_exchange_follows_co_simulation():
    """A braking in a curve held from the start: FMPy's CVODE on the Model Exchange interface
    and the Co-Simulation's RK4 agree on the pose command after 10 s."""
    start = {"f[1]": -2.0, "f[2]": 1.5, "omega[3]": 0.1}
    names = ["pose.r[1]", "pose.r[2]", "pose.angles[1]", "pose.angles[2]", "pose.angles[3]", "fsim[1]"]
    me = simulate_fmu(str(CUEING_FMU), fmi_type="ModelExchange", stop_time=10.0, start_values=start,
                      relative_tolerance=1e-10, output_interval=0.01, output=names)
    cs = simulate_fmu(str(CUEING_FMU), fmi_type="CoSimulation", stop_time=10.0, start_values=start,
                      output_interval=0.01, output=names)
    for n in names:
        assert abs(me[n][-1] - cs[n][-1]) < 1e-6, (n, me[n][-1], cs[n][-1])


def test_an_fmu_state_continues_bit_for_bit():
    """Saved after 3 s of a lane change with the inputs' derivatives set, serialized, restored
    into another instance: the rest of the run equals the uninterrupted one."""
    m = vehicle.lane_change(duration=6.0)

    def steps(c, i0, i1):
        out = []
        for i in range(i0, i1):
            f, w = vehicle.at(m, i * 0.01)
            c.set_values(cueing.F + cueing.OMEGA, np.concatenate([f, w]))
            # The inputs follow their chords: the derivatives set before a save are state too.
            then = np.concatenate(vehicle.at(m, (i + 1) * 0.01))
            c.slave.setRealInputDerivatives([c.vr[n] for n in cueing.F + cueing.OMEGA], [1] * 6,
                                            list((then - np.concatenate([f, w])) / 0.01))
            if i == i1 - 1 and i1 == 300:
                break  # the save comes between the derivatives' set and the step
            c.step(0.01)
            out.append(c.values(cueing.POSE))
        return np.array(out)

    a = Component(CUEING_FMU, "a")
    b = Component(CUEING_FMU, "b")
    try:
        steps(a, 0, 300)  # ends with step 299's inputs and derivatives set, not yet stepped
        state, saved_at = a.slave.serializeFMUstate(a.slave.getFMUstate()), a.time
        a.step(0.01)
        whole = np.vstack([a.values(cueing.POSE), steps(a, 300, 600)])
        b.slave.setFMUstate(b.slave.deSerializeFMUstate(state))
        b.time = saved_at
        b.step(0.01)
        assert np.array_equal(np.vstack([b.values(cueing.POSE), steps(b, 300, 600)]), whole)
    finally:
        a.free()
        b.free()


@pytest.mark.parametrize("values, words", [
    ({"margin": 0.4}, "margin"),
    ({"neutral[3]": 2.5}, "neutral"),
    ({"tilt.max": 2.0}, "tilt.max"),
    ({"hp.f.break[2]": 0.0}, "hp.f.break[2]"),
])
def test_bad_parameters_are_refused_naming_them(values, words):
    from fmpy.fmi1 import FMICallException
    messages = []
    with pytest.raises(FMICallException):
        Component(CUEING_FMU, "bad", values, events=messages)
    assert any(words in text for _, _, text in messages), messages


def test_the_motion_system_follows_the_command_and_harsh_manoeuvres_stay_inside_the_strokes():
    """StewartMotionSystem.ssp's chain at 1 ms with FMPy: the platform's legs follow the
    controller's programme lengths within 6 mm on the lane change and 3 mm on the braking (its
    centre of mass the command within twice that); on the harsh manoeuvres (a 6 m/s2 emergency stop, a 0.5 g lane change, a
    pothole), with the default washout and with one that needs the limiter, every leg stays
    inside [lmin, lmax]."""
    p = start_values()
    lines = []
    # The controller's error on these commands (docs/control.md quotes the braking's).
    # SPEC 11's ideal tilt limiter steps the commanded tilt rate where a slewing angle catches
    # its target; the controller follows such a step over its bandwidth (the lane change's
    # error was 1.3 mm with the smooth 20 1/s catch-up of an earlier version).
    for name, make, bound in (("lane change", vehicle.lane_change, 6e-3), ("braking", vehicle.brake, 3e-3)):
        r = cueing.motion_system(make())
        lp = np.array([r[f"lp[{k}]"] for k in LEGS])
        l = np.array([r[f"l[{k}]"] for k in LEGS])
        leg_error = np.max(np.abs(lp - l))
        r_error = max(np.max(np.abs(r[f"r[{k}]"] - r[f"pose.r[{k}]"])) for k in (1, 2, 3))
        # The centre of mass sits a metre below the head: the pitch's following error shows there.
        assert leg_error < bound and r_error < 2 * bound, (name, leg_error, r_error)
        lines.append(f"{name}: leg error {leg_error * 1e3:.2f} mm, centre of mass {r_error * 1e3:.2f} mm")
    check_figures("cueing.txt", "StewartMotionSystem.ssp with FMPy at 1 ms", "; ".join(lines))
    lmin = np.array([p[f"lmin[{k}]"] for k in LEGS])[:, None]
    lmax = np.array([p[f"lmax[{k}]"] for k in LEGS])[:, None]
    for name, make in vehicle.HARSH.items():
        for label, params in (("default", None), ("aggressive", AGGRESSIVE)):
            run = cueing.motion_system(make(), cueing=params)
            legs = np.array([run[f"l[{k}]"] for k in LEGS])
            assert (legs > lmin).all() and (legs < lmax).all(), (name, label, legs.min(), legs.max())
            cost = np.sqrt(np.mean(sum((run[f"fsim[{k}]"] - run[f"f[{k}]"]) ** 2 for k in (1, 2, 3))))
            lines.append(f"{name} ({label}): legs {legs.min():.4f}..{legs.max():.4f} m, scale down to "
                         f"{run['workspace.scale'].min():.3f}, rms |f - fsim| {cost:.2f} m/s2")
    print("\n".join(lines))


def test_libcosim_runs_the_motion_system():
    """libcosim loads StewartMotionSystem.ssp (its binding sets programme = 3), the vehicle's
    motion set through an override manipulator each step: the platform follows the braking's
    command (libcosim's exchange delays the legs by a step) within 3 mm per leg."""
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimManipulator import CosimManipulator
    from libcosimpy.CosimObserver import CosimObserver
    from stewart_fmu.core import CONTROLLER_FMU, PLATFORM_FMU

    log_output_level(CosimLogLevel.WARNING)
    vr = {name: {v.name: v.valueReference for v in read_model_description(str(f)).modelVariables}
          for name, f in (("cueing", CUEING_FMU), ("controller", CONTROLLER_FMU), ("platform", PLATFORM_FMU))}
    execution = CosimExecution.from_ssp_file(ssp_path=str(MOTION_SYSTEM_SSP), step_size=1_000_000)
    index = {(s.name.decode() if isinstance(s.name, bytes) else s.name): s.index for s in execution.slave_infos()}
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer=observer)
    manipulator = CosimManipulator.create_override()
    execution.add_manipulator(manipulator=manipulator)
    m = vehicle.brake(duration=8.0)
    inputs = [vr["cueing"][n] for n in cueing.F + cueing.OMEGA]
    worst, pitch = 0.0, 0.0
    for i in range(8000):
        f, w = vehicle.at(m, i * 1e-3)
        manipulator.slave_real_values(index["cueing"], inputs, list(np.concatenate([f, w])))
        assert execution.step()
        l = observer.last_real_values(slave_index=index["platform"],
                                      variable_references=[vr["platform"][f"l[{k}]"] for k in LEGS])
        lp = observer.last_real_values(slave_index=index["controller"],
                                       variable_references=[vr["controller"][f"lp[{k}]"] for k in LEGS])
        worst = max(worst, float(np.max(np.abs(np.array(l) - np.array(lp)))))
        pitch = observer.last_real_values(slave_index=index["platform"],
                                          variable_references=[vr["platform"]["angles[2]"]])[0]
    print(f"libcosim, StewartMotionSystem.ssp, 8 s of braking at 1 ms: largest leg error {worst * 1e3:.2f} mm, "
          f"pitch {math.degrees(pitch):.2f} deg")
    assert worst < 3e-3
    assert pitch > math.radians(3.0)
    check_figures("cueing.txt", "libcosim, StewartMotionSystem.ssp, 8 s of braking at 1 ms",
                  f"largest leg error {worst * 1e3:.2f} mm, pitch {math.degrees(pitch):.2f} deg")


def test_the_compiled_master_runs_the_motion_system_with_fmpys_numbers(tmp_path):
    """StewartMotionSystem.ssp through the compiled master, the manoeuvre an input table of the
    cueing FMU: the platform's motion and the pose command equal FMPy's to the bit; the
    command line `stewart-master run ... --input cueing=brake.csv` gives the same legs."""
    import subprocess
    import sys
    m = vehicle.lane_change(duration=4.0)
    py = cueing.motion_system(m)
    cm = cueing.motion_system(m, master="compiled")
    # The compiled master records after each step; FMPy's driver also at the start.
    for name in [f"l[{k}]" for k in LEGS] + ["r[1]", "r[2]", "r[3]", "angles[1]", "angles[2]", "angles[3]",
                                             "pose.r[1]", "pose.r[2]", "pose.angles[1]", "pose.angles[3]"]:
        assert np.array_equal(py[name][1:], cm[name]), name
    brake = vehicle.write_csv(vehicle.brake(duration=3.0), tmp_path / "brake.csv")
    out = tmp_path / "legs.csv"
    stewart_master = Path(sys.executable).parent / "stewart-master"
    done = subprocess.run([str(stewart_master), "run", str(MOTION_SYSTEM_SSP), "--stop-time", "3", "--step", "0.001",
                           "--input", f"cueing={brake}", "--record", "platform.l[1]", "--record", "platform.angles[2]",
                           "--out", str(out)], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    table = np.genfromtxt(out, delimiter=",", names=True)
    again = cueing.motion_system(vehicle.read_csv(brake), master="compiled", record=("l[1]", "angles[2]"))
    assert np.array_equal(table[table.dtype.names[1]], again["l[1]"])
    assert table[table.dtype.names[2]][-1] > 0.01, "the braking pitches the cabin nose down"
    for component, table_text, words in (("controller", "time,pose.r[1]\n0,1.9\n1,2.0\n", "driven by a connection"),
                                         ("controller", "time,lp[1]\n0,1.7\n", "not a Real input"),
                                         ("cueing", "time,f[1]\n1,0.0\n0,0.5\n", "times must increase")):
        bad_table = tmp_path / "bad.csv"
        bad_table.write_text(table_text)
        bad = subprocess.run([str(stewart_master), "run", str(MOTION_SYSTEM_SSP), "--stop-time", "1", "--step",
                              "0.001", "--input", f"{component}={bad_table}"], capture_output=True, text=True, timeout=60)
        assert bad.returncode == 2 and words in bad.stderr, bad.stderr


def test_stewart_sweep_studies_the_washout(tmp_path, cluster):  # noqa: F811
    """A system = 'cueing' study on a Dask cluster on loopback: the rows carry the cue error and
    the workspace usage, a larger scale uses more workspace (the braking's usage grows with
    K_f), and the schema refuses what does not fit a cueing study, naming it."""
    import subprocess
    import sys
    import pandas as pd
    address, _ = cluster
    sweep = Path(sys.executable).parent / "stewart-sweep"
    study = tmp_path / "scale.toml"
    study.write_text('[study]\nsystem = "cueing"\nmanoeuvre = "brake"\nstop_time = 12.0\nstep = 0.01\n'
                     '[grid]\n"cueing.scale.f[1]" = [0.3, 0.6, 0.9]\n')
    done = subprocess.run([str(sweep), str(study), "--out", str(tmp_path / "out"), "--scheduler", address],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    rows = pd.read_parquet(tmp_path / "out" / "results.parquet").sort_values("param:cueing.scale.f[1]")
    assert (rows["status"] == "ok").all() and rows["worker"].str.startswith("tcp://127.0.0.1:").all()
    assert rows["max_usage"].is_monotonic_increasing and rows["max_usage"].iloc[0] > 0.2
    assert (rows["cue_error"] > 0).all() and (rows["least_scale"] <= 1).all()
    print("washout study:", rows[["param:cueing.scale.f[1]", "cue_error", "max_usage", "max_tilt"]].to_dict("list"))
    bad = tmp_path / "bad.toml"
    bad.write_text('[study]\nsystem = "cueing"\nmanoeuvre = "brakes"\nstop_time = 5.0\nstep = 0.01\n'
                   '[grid]\n"platform.M" = [3000.0]\n"cueing.f[1]" = [1.0]\n')
    refused = subprocess.run([str(sweep), str(bad), "--check"], capture_output=True, text=True, timeout=120)
    assert refused.returncode == 2
    for words in ("did you mean 'brake'", "runs cueing only", "the study's manoeuvre drives"):
        assert words in refused.stderr, (words, refused.stderr)
