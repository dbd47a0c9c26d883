"""How much better than the classical washout a cueing can be on brakings whose end it does not
know: an estimate of the room left for predictive cueing with its inputs held (issue 46 asks
for 25 % lower perceived error on the main job's braking; the held inputs give 3 %).

Four brakings at 3 m/s2 (`stewart_fmu.vehicle.brake`) from 10, 15, 20 and 25 m/s are the same
drive until the shortest one's stop begins. A cueing that does not know the future (the
predictive method with its inputs held, the classical washout) must command the same motion
in all four until then. The script finds the motion that minimises the largest ratio, over the
four, of the rms perceived surge error (SPEC §12's otolith model) to the classical washout's
(the packaged FMU with its defaults), with:

- the stand at rest until the braking begins (a drive that does not brake is the same drive
  until then, and only a stand at rest cues it without error);
- the pitch within `tilt.max` (10 deg) and its rate within `tilt.rateLimit` (3 deg/s) plus the
  vehicle's own pitch rate, as the predictive method's constraints are;
- the head's surge and the pitch within the convex hull of the (surge, pitch) pairs the
  default stand reaches with every leg inside `[lmin + margin, lmax - margin]`, sampled (heave
  2 cm, sway 0.1 m, roll and yaw 5 and 10 deg, pitch 0.5 deg) and each widened by the surge
  grid's step;
- the cabin's surge cue to first order in the pitch, `a - g theta` (its heave's part and the
  pitch's second order dropped), no leg-speed limit, a 20 ms grid.

The simplifications are not all relaxations, so the figure is an estimate, not a proof: no
cueing of the stand that does not know the stop does much better than it on all four.

    .venv/bin/pip install cvxpy==1.9.3     # not in tests/requirements.txt: a study, not a test
    .venv/bin/python benches/cueing_braking_bound.py     # after the main job (target/fmu)

Prints a table and writes it to benches/results/cueing_braking_bound.txt (a minute or two).
"""

import sys
from pathlib import Path

import numpy as np
import scipy.signal as sg
from fmpy import read_model_description
from scipy.spatial import ConvexHull

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "python"))
from stewart_fmu import cueing, vehicle  # noqa: E402
from stewart_fmu.core import CUEING_FMU, PLATFORM_FMU, default_stand  # noqa: E402

OUT = ROOT / "benches" / "results" / "cueing_braking_bound.txt"
SPEEDS = (10.0, 15.0, 20.0, 25.0)
DECELERATION = 3.0
DT = 0.02
SURGE_STEP = 0.01
# SPEC §12's otolith: (tau_oa s + 1) / ((tau_oL s + 1)(tau_oS s + 1)).
OTOLITH = ([10.0, 1.0], np.polymul([5.0, 1.0], [0.016, 1.0]))


def starts(fmu):
    return {v.name: v.start for v in read_model_description(str(fmu)).modelVariables if v.start is not None}


def rotation(roll, pitch, yaw):
    """R = Rx(roll) Ry(pitch) Rz(yaw), the cueing FMU's 1-2-3 attitude (docs/cueing.md)."""
    cr, sr, cp, sp, cy, sy = np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch), np.cos(yaw), np.sin(yaw)
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return rx @ ry @ rz


def reachable_hull(tilt_max):
    """The convex hull of the (head surge, pitch) pairs of the default stand with every leg
    inside its margins and the pitch within `tilt_max`; heave, sway, roll and yaw free (sampled),
    each pair widened by the surge grid's step (the hull of samples lies inside the set's)."""
    stand, p, c = default_stand(), starts(PLATFORM_FMU), starts(CUEING_FMU)
    b, a = np.array(stand["B"]), np.array(stand["A"])
    lo = np.array([float(p[f"lmin[{k}]"]) for k in range(1, 7)]) + float(c["margin"])
    hi = np.array([float(p[f"lmax[{k}]"]) for k in range(1, 7)]) - float(c["margin"])
    head = np.array([float(c[f"head[{i}]"]) for i in (1, 2, 3)])
    neutral = np.array([float(c[f"neutral[{i}]"]) for i in (1, 2, 3)])
    xs = np.arange(-1.0, 1.0 + 1e-9, SURGE_STEP)
    others = [(y, z, roll, yaw) for y in np.arange(-0.2, 0.201, 0.1) for z in np.arange(-0.5, 0.5, 0.02)
              for roll in np.radians([-10.0, -5.0, 0.0, 5.0, 10.0]) for yaw in np.radians([-10.0, 0.0, 10.0])]
    points = []
    for theta in np.radians(np.arange(-30.0, 30.01, 0.5)):
        if abs(theta) > tilt_max + 1e-12:
            continue
        reach = np.zeros(len(xs), dtype=bool)
        for y, z, roll, yaw in others:
            rot = rotation(roll, theta, yaw)
            # The cabin turns about the head: the centre of mass for each surge x.
            r = (neutral + head - rot @ head + np.array([0.0, y, z]))[None, :] + np.outer(xs, [1.0, 0.0, 0.0])
            legs = np.linalg.norm(r[:, None, :] + (rot @ a.T).T[None, :, :] - b[None, :, :], axis=2)
            reach |= np.all((legs >= lo) & (legs <= hi), axis=1)
        for x in xs[reach]:
            points += [(x - SURGE_STEP, theta), (x + SURGE_STEP, theta)]
    return ConvexHull(np.array(points)), np.array(points)


def main():
    import cvxpy as cp

    c = starts(CUEING_FMU)
    g = float(c.get("g", 9.81))
    tilt_max, rate = float(c["tilt.max"]), float(c["tilt.rateLimit"])
    hull, points = reachable_hull(tilt_max)
    ad, bd, cd, dd = sg.cont2discrete(sg.tf2ss(*OTOLITH), DT, method="zoh")[:4]
    s = cp.Variable()
    constraints, runs = [], {}
    for speed in SPEEDS:
        m = vehicle.brake(speed=speed, duration=max(20.0, 12.0 + speed / DECELERATION), deceleration=DECELERATION)
        classical = cueing.measures(cueing.run(m))["perceived_error"]
        t = np.arange(0.0, float(m["time"][-1]) + 1e-9, DT)
        n = len(t)
        f = np.interp(t, m["time"], m["f[1]"])
        # The predictive method's tilt rate limit: tilt.rateLimit plus the vehicle's own rate.
        pitch_rate = np.abs(np.interp(t, m["time"], m["omega[2]"]))
        x_lag, felt = np.zeros(2), np.zeros(n)
        for k in range(n):
            felt[k] = (cd @ x_lag)[0] + dd[0, 0] * f[k]
            x_lag = ad @ x_lag + bd[:, 0] * f[k]
        acc, theta, vel, pos, lag = cp.Variable(n), cp.Variable(n), cp.Variable(n), cp.Variable(n), cp.Variable((n, 2))
        # The cabin's surge cue: fsim = R^T (A + g ez) with R = Rx Ry Rz, to first order in the
        # pitch: a nose-down pitch (theta > 0) gives a braking cue.
        fsim = acc - g * theta
        rest = t < 1.0
        constraints += [e[0] * pos + e[1] * theta + e[2] <= 0 for e in hull.equations]
        constraints += [theta[rest] == 0, pos[rest] == 0, acc[rest] == 0, vel[0] == 0, lag[0] == 0,
                        cp.abs(cp.diff(theta)) <= (rate + pitch_rate[:-1]) * DT, vel[1:] == vel[:-1] + acc[:-1] * DT,
                        pos[1:] == pos[:-1] + vel[:-1] * DT + acc[:-1] * DT * DT / 2,
                        lag[1:].T == ad @ lag[:-1].T + bd @ cp.reshape(fsim[:-1], (1, n - 1), order="C")]
        felt_sim = (cd @ lag.T)[0] + dd[0, 0] * fsim
        constraints.append(cp.norm(felt - felt_sim) / np.sqrt(n) <= s * classical)
        stop = 1.0 + 0.75 + speed / DECELERATION
        runs[speed] = dict(t=t, acc=acc, theta=theta, stop=stop, felt=felt, felt_sim=felt_sim, classical=classical)
    # Non-anticipativity: the same decisions while the drives are the same (until the shorter
    # braking's ramp out begins, half a second before its stop).
    for short, long in zip(SPEEDS, SPEEDS[1:]):
        a, b = runs[short], runs[long]
        k = int(np.sum(a["t"] < a["stop"] - 0.5))
        constraints += [a["acc"][:k] == b["acc"][:k], a["theta"][:k + 1] == b["theta"][:k + 1]]
    problem = cp.Problem(cp.Minimize(s), constraints)
    problem.solve(solver="CLARABEL", max_iter=500)
    lines = [
        "How much better than the classical washout a cueing can be on brakings whose stop it does not know",
        "(benches/cueing_braking_bound.py: an estimate, its simplifications in the script's docstring)",
        f"3 m/s2 brakings, the same motion until the shorter one's stop begins; pitch within {np.degrees(tilt_max):.0f} deg "
        f"at {np.degrees(rate):.0f} deg/s plus the vehicle's; surge and pitch within the hull of {len(points)} pairs; "
        f"{DT * 1e3:.0f} ms grid; CVXPY {cp.__version__} with Clarabel: {problem.status}",
        "",
        f"{'from (m/s)':>10} {'classical (m/s2)':>17} {'bound (m/s2)':>13} {'ratio':>6}",
    ]
    for speed, r in runs.items():
        rms = float(np.sqrt(np.mean((r["felt"] - r["felt_sim"].value) ** 2)))
        lines.append(f"{speed:>10.0f} {r['classical']:>17.3f} {rms:>13.3f} {rms / r['classical']:>6.3f}")
    lines += ["", f"largest ratio at best: {s.value:.3f} ({100 * (1 - s.value):.0f} % lower error on all four; "
              f"the issue asks 25 %)"]
    text = "\n".join(lines) + "\n"
    print(text, end="")
    OUT.write_text(text)


if __name__ == "__main__":
    main()
