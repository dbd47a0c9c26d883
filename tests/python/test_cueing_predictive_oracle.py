"""The StewartCueing FMU's predictive cueing (cueing.method = 1) against an oracle written from
SPEC §12 and docs/cueing.md alone (`oracles.predictive`: the docs' optimal control problem,
solved as the linear system of its objective's minimum, every inequality checked inactive).

The FMU (FMI 2 Co-Simulation, default parameters, 1 ms communication steps) and the oracle see
the same inputs: a gentle manoeuvre of `stewart_fmu.vehicle` sampled at the points t_i = i h
and, over each step, following its chord to the next point (fmi2SetRealInputDerivatives), so
that the inputs at a solve time are the same from both sides of it. (A solve due at a
communication point, to a nanosecond of the period, is the next step's first, with the inputs
set for it.) The FMU gets doStep(t_i = i h, h), the points the oracle has: one sub-step of the
simulator perception per 1 ms step (`Predictive.substeps`). The manoeuvres are scaled down
until no inequality of the QP comes near its bound (the oracle raises if one would be active;
the margins are printed), so the QP's solution is the unconstrained minimiser.

Tolerance, from the FMU's solver tolerance: the FMU's interior-point method stops at a relative
tolerance of 1e-8, so its correction du may differ from the exact minimiser by H^-1 r for a
stationarity residual r of up to 1e-8 max|grad| in each component (H, grad: the QP's Hessian
and gradient at du = 0; the solver's own bound is looser, 1e-8 (1 + max|g|) with the slack's
weight 1e4 in g, and it stops well inside it). The test measures what that does to the
outputs: it runs the oracle a second time with such a residual at every solve (each component
at the bound, seeded random signs) and takes, per output group, the largest change over the run
as the tolerance. The vehicle's perceived cues do
not depend on the solves: they are the lags of the inputs, exact on the chords; their tolerance
is 1e-10 (rounding over the run: 1e-13 of g was measured).
"""

import numpy as np
import pytest
from fmpy import read_model_description

from oracles import perception, predictive
from stewart_fmu import vehicle
from stewart_fmu.core import CUEING_FMU, Component

H = 1e-3
F = [f"f[{k}]" for k in (1, 2, 3)]
OMEGA = [f"omega[{k}]" for k in (1, 2, 3)]
INPUTS = F + OMEGA
GROUPS = ["pose.r", "pose.v", "pose.a", "pose.angles", "pose.angleRates", "pose.angleAccelerations", "fsim",
          "omegasim", "perceived.f", "perceived.omega", "perceived.fsim", "perceived.omegasim"]
UNITS = {"pose.r": "m", "pose.v": "m/s", "pose.a": "m/s2", "pose.angles": "rad", "pose.angleRates": "rad/s",
         "pose.angleAccelerations": "rad/s2", "fsim": "m/s2", "omegasim": "rad/s", "perceived.f": "m/s2",
         "perceived.omega": "rad/s", "perceived.fsim": "m/s2", "perceived.omegasim": "rad/s"}
RECORD = [f"{g}[{k}]" for g in GROUPS for k in (1, 2, 3)] + ["workspace.scale"]
#: The groups the solves do not touch, and their tolerance.
VEHICLE_GROUPS, VEHICLE_TOLERANCE = ("perceived.f", "perceived.omega"), 1e-10
#: The gentle manoeuvres: a braking (surge and pitch) and a lane change (sway, roll, yaw) with
#: the default parameters (the guess of mpc.trend going on with the inputs' ramps); a fuzzed
#: motion on all six axes (heave and the head's lever arm included) with the inputs held
#: (mpc.trend = 0: its noise's difference quotients would guess motions that reach the
#: inequalities), and the same with mpc.period = 30 ms (each step's nominal jerk the mean of
#: the last plan's over the step a period later: with the longer period more of each step comes
#: from the next one).
CASES = {
    "brake": (lambda: vehicle.brake(duration=4.0, deceleration=0.2, speed=2.0, start=0.5), {}),
    "lane_change": (lambda: vehicle.lane_change(duration=4.5, speed=10.0, lateral=0.25, peak=0.15, start=0.5), {}),
    "all_axes": (lambda: vehicle.random_manoeuvre(3, duration=4.0, f_limit=0.2, omega_limit=0.02), {"mpc.trend": 0.0}),
    "all_axes_period_30ms": (lambda: vehicle.random_manoeuvre(3, duration=3.0, f_limit=0.2, omega_limit=0.02),
                             {"mpc.period": 0.03, "mpc.trend": 0.0}),
}


def parameters(changes=None):
    """The FMU's Real parameters' start values (its modelDescription.xml), `changes` over them."""
    return {**predictive.start_values(CUEING_FMU), **(changes or {})}


def max_iterations():
    variable = next(v for v in read_model_description(str(CUEING_FMU)).modelVariables
                    if v.name == "mpc.maxIterations")
    return int(variable.start)


def fmu_run(m, changes=None):
    """The FMU over the manoeuvre `m` to its end: the inputs at t_i = i h (linear
    interpolation of the table) and their chord's slope to the next point, doStep from t_i;
    the outputs RECORD and the Integers mpc.iterations, mpc.fallbacks at every point (after
    the inputs are set)."""
    t_end = float(m["time"][-1])
    n = int(round(t_end / H))
    t = np.arange(n + 1) * H
    u = np.column_stack([np.interp(t, m["time"], m[name]) for name in INPUTS])
    cue = Component(CUEING_FMU, "predictive-oracle", changes, {"cueing.method": 1})
    vrs = [cue.vr[name] for name in INPUTS]
    integers = [cue.vr["mpc.iterations"], cue.vr["mpc.fallbacks"]]
    rows, counts = [], []
    try:
        for i in range(n + 1):
            cue.set_values(INPUTS, u[i])
            rows.append(cue.get(RECORD))
            counts.append(cue.slave.getInteger(integers))
            if i < n:
                cue.slave.setRealInputDerivatives(vrs, [1] * 6, list((u[i + 1] - u[i]) / H))
                # The points as the oracle has them, i h (not a sum of steps).
                cue.slave.doStep(currentCommunicationPoint=t[i], communicationStepSize=H)
    finally:
        cue.free()
    rows, counts = np.array(rows), np.array(counts)
    out = {"time": t, "inputs": u, "mpc.iterations": counts[:, 0], "mpc.fallbacks": counts[:, 1]}
    out.update({name: rows[:, j] for j, name in enumerate(RECORD)})
    return out


def group_difference(a, b, group):
    return max(float(np.max(np.abs(a[f"{group}[{k}]"] - b[f"{group}[{k}]"]))) for k in (1, 2, 3))


def stationarity_residual(seed):
    """A perturbation of each solve: du + H^-1 r, every component of r 1e-8 max|grad| with a
    random sign (the solver's bound per component)."""
    rng = np.random.default_rng(seed)

    def perturb(_, info):
        r = rng.choice([-1.0, 1.0], predictive.N_UNKNOWNS) * 1e-8 * np.max(np.abs(info["gradient"]))
        return info["du"] + np.linalg.solve(info["hessian"], r).reshape(info["du"].shape)
    return perturb


@pytest.fixture(scope="module")
def runs():
    """Per manoeuvre: the FMU's run, the oracle's, the oracle's with the solver's residual."""
    result = {}
    for seed, (name, (make, changes)) in enumerate(CASES.items()):
        oracle = predictive.Predictive(parameters(changes))
        fmu = fmu_run(make(), changes)
        exact = oracle.simulate(fmu["time"], fmu["inputs"])
        perturbed = oracle.simulate(fmu["time"], fmu["inputs"], perturb=stationarity_residual(seed), fine=1)
        result[name] = {"fmu": fmu, "oracle": exact, "perturbed": perturbed}
    return result


# -- the oracle against itself ----------------------------------------------------------------

def test_the_oracles_pieces_agree_with_closed_forms_and_differences():
    """The grid sums to the horizon with h_j = h_0 1.1^j; each block's unit-jerk sensitivity
    equals the closed form of a jerk held over the block's steps (position ((T-a)^3 - (T-b)^3)/6,
    rate ((T-a)^2 - (T-b)^2)/2, acceleration b - a at T >= b); the cues' and the legs' Jacobians
    equal central differences; the lags' exact step equals the perception oracle's modal
    simulator on a linear input (otolith and canal)."""
    p = parameters()
    oracle = predictive.Predictive(p)
    assert abs(oracle.tau[-1] - p["mpc.horizon"]) < 1e-14
    assert np.allclose(oracle.h[1:] / oracle.h[:-1], 1.1, rtol=1e-14, atol=0)
    print(f"grid: h_0 = {oracle.h[0] * 1e3:.2f} ms, h_19 = {oracle.h[-1] * 1e3:.2f} ms")
    starts = np.concatenate([[0], np.cumsum(predictive.BLOCKS)])
    for b in range(predictive.N_BLOCKS):
        a_, b_ = oracle.tau[starts[b]], oracle.tau[starts[b + 1]]
        for j in range(predictive.STEPS + 1):
            T = oracle.tau[j]
            lo, hi = max(T - a_, 0.0), max(T - b_, 0.0)
            expected = [(lo ** 3 - hi ** 3) / 6, (lo ** 2 - hi ** 2) / 2, lo - hi]
            assert np.allclose(oracle.sens[j, :, b], expected, rtol=1e-12, atol=1e-15), (b, j)
    rng = np.random.default_rng(7)
    x = rng.uniform(-0.3, 0.3, (predictive.N_CHANNELS, 3))
    y, jac = oracle.cues(x, jacobian=True)
    length, grad, speed = oracle.legs(x[None])
    eps = 1e-6
    for c in range(predictive.N_CHANNELS):
        for d in range(3):
            up, down = x.copy(), x.copy()
            up[c, d] += eps
            down[c, d] -= eps
            assert np.allclose((oracle.cues(up)[0] - oracle.cues(down)[0]) / (2 * eps), jac[0, :, c, d], atol=1e-8)
            if d == 0:
                dl = (oracle.legs(up[None])[0] - oracle.legs(down[None])[0]) / (2 * eps)
                assert np.allclose(dl[0], grad[0, :, c], atol=1e-8)
    # The legs' speed J (P', beta') is the length's time derivative along the motion.
    moved = x.copy()
    moved[:, 0] += eps * x[:, 1]
    back = x.copy()
    back[:, 0] -= eps * x[:, 1]
    assert np.allclose((oracle.legs(moved[None])[0] - oracle.legs(back[None])[0]) / (2 * eps), speed, atol=1e-8)
    t = np.linspace(0.0, 3.0, 301)
    for lags, cue in ((perception.OTOLITH, 0), (perception.CANAL, 3)):
        u = np.sin(2.3 * t) + 0.4 * t
        state = np.zeros(len(predictive.LAG_TAU))
        out = [0.0]
        for k in range(len(t) - 1):
            e, a, b = predictive.lag_coefficients(t[k + 1] - t[k])
            y0, y1 = np.zeros(6), np.zeros(6)
            y0[cue], y1[cue] = u[k], u[k + 1]
            state = e * state + a * y0[predictive.LAG_CUE] + b * y1[predictive.LAG_CUE]
            out.append((predictive.LAG_SUM @ state)[cue])
        assert np.max(np.abs(np.array(out) - lags.simulate(t, u))) < 1e-12


# -- the FMU against the oracle -----------------------------------------------------------------

@pytest.mark.parametrize("name", list(CASES))
def test_predictive_cueing_follows_the_oracle(name, runs):
    """Every solve of the oracle has all its inequality rows strictly inside their bounds (else
    it raises), no solve of the FMU fails (mpc.fallbacks = 0, mpc.iterations within
    mpc.maxIterations) and its workspace net stays idle (workspace.scale = 1); the pose command,
    fsim, omegasim and the simulator's perceived cues equal the oracle's within the change a
    1e-8 stationarity residual per solve makes (see the module's docstring), the vehicle's
    perceived cues within 1e-10."""
    fmu, oracle, perturbed = runs[name]["fmu"], runs[name]["oracle"], runs[name]["perturbed"]
    margins = ", ".join(f"{kind} {value:.2f}" for kind, value in oracle["margins"].items())
    iterations = fmu["mpc.iterations"][1:]
    print(f"{name}: {len(oracle['solves'])} solves; smallest margins of the QP's rows (slack units: cm, "
          f"5 cm/s, deg/s, deg): {margins}; FMU iterations {iterations.min()}-{iterations.max()}")
    assert np.all(fmu["mpc.fallbacks"] == 0), "a solve of the FMU failed"
    # Below the budget: converged to 1e-8 (a solve kept at the looser 1e-6 reports the budget).
    assert np.all((iterations >= 1) & (iterations < max_iterations()))
    assert np.all(fmu["workspace.scale"] == 1.0), "the workspace net acted"
    assert all(value > 0 for value in oracle["margins"].values())
    failures = []
    for group in GROUPS:
        measured = group_difference(fmu, oracle, group)
        if group in VEHICLE_GROUPS:
            tolerance = VEHICLE_TOLERANCE
        else:
            tolerance = group_difference(perturbed, oracle, group)
        largest = max(float(np.max(np.abs(fmu[f"{group}[{k}]"]))) for k in (1, 2, 3))
        print(f"   {group:25s} |FMU - oracle| <= {measured:.1e} {UNITS[group]} (tolerance {tolerance:.1e}; "
              f"largest |value| {largest:.3g})")
        if not measured < tolerance:
            failures.append((group, measured, tolerance))
    assert not failures, failures


@pytest.mark.parametrize("name", list(CASES))
def test_the_simulators_perception_takes_its_cues_linearly_over_each_sub_step(name, runs):
    """The simulator's lags follow the docs' rule (fsim and omegasim linear between the ends of
    each sub-step of at most solver.maxStep), not the lags' exact integral: the FMU's
    perceived.fsim and perceived.omegasim are within 1 % of the difference the exact integral
    (the oracle's `fine` lags, 8 sub-steps of the exact motion) would make, which is what makes
    the comparison above able to tell the two apart."""
    fmu, oracle = runs[name]["fmu"], runs[name]["oracle"]
    for group in ("perceived.fsim", "perceived.omegasim"):
        measured = group_difference(fmu, oracle, group)
        exact = max(float(np.max(np.abs(oracle[f"{group}.fine[{k}]"] - oracle[f"{group}[{k}]"])))
                    for k in (1, 2, 3))
        print(f"{name}: {group}: |FMU - oracle| {measured:.1e}, |exact integral - chords| {exact:.1e}")
        assert measured < 0.01 * exact, (group, measured, exact)
