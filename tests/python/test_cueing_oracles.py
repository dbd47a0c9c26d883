"""The StewartCueing FMU against oracles written from SPEC §11 and §12 alone (tests/python/oracles:
`perception`, the otolith and canal filters in closed form and an exact simulator for
piecewise-linear inputs; `washout`, the classical washout with the ideal tilt rate limiter,
integrated by solve_ivp at rtol 1e-10 with the limiter's switches located as events).

The FMU's inputs follow the same piecewise-linear signal the oracles see: in Co-Simulation each
communication step sets the inputs at its start and their chord's slope with
fmi2SetRealInputDerivatives (a step of the input is set at a communication point); in Model
Exchange a Python master (solve_ivp's DOP853 over fmi2SetTime/SetReal/SetContinuousStates/
GetDerivatives, the two event indicators located as roots) sets the interpolated inputs at every
right-hand-side time. All runs use the FMU's default parameters (cueing.method = 0)."""

import functools
import math
from ctypes import c_double
from pathlib import Path

import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Model
from scipy import signal
from scipy.integrate import solve_ivp

from oracles import perception, washout
from stewart_fmu import vehicle
from stewart_fmu.core import CUEING_FMU, Component

FMI3_CUEING = Path(CUEING_FMU).parent / "fmi3" / "StewartCueing.fmu"
F = [f"f[{k}]" for k in (1, 2, 3)]
OMEGA = [f"omega[{k}]" for k in (1, 2, 3)]
INPUTS = F + OMEGA
PERCEIVED = [f"perceived.{n}[{k}]" for n in ("f", "omega") for k in (1, 2, 3)]
PERCEIVED_SIM = [f"perceived.{n}[{k}]" for n in ("fsim", "omegasim") for k in (1, 2, 3)]
SIM = [f"{n}[{k}]" for n in ("fsim", "omegasim") for k in (1, 2, 3)]
POSE = [f"pose.{n}[{k}]" for n in ("r", "v", "a", "angles", "angleRates", "angleAccelerations") for k in (1, 2, 3)]
OMCT_FREQUENCIES = [10 ** ((k - 6) / 5) for k in range(1, 13)]


def gravity():
    return washout.start_values(CUEING_FMU)["g"]


class Table:
    """Inputs linear in time between rows; a time given twice is a jump there. `right(t)` and
    `left(t)`: the limits from the right and from the left (rows: f[1..3], omega[1..3])."""

    def __init__(self, times, values):
        self.times, self.values = np.asarray(times, dtype=float), np.asarray(values, dtype=float)

    def _at(self, t, side):
        n = len(self.times)
        i = int(np.searchsorted(self.times, t, side=side))
        i = min(max(i, 1), n - 1)
        t0, t1 = self.times[i - 1], self.times[i]
        if t1 == t0:
            return self.values[i] if side == "right" else self.values[i - 1]
        x = min(max((t - t0) / (t1 - t0), 0.0), 1.0)
        return self.values[i - 1] + x * (self.values[i] - self.values[i - 1])

    def right(self, t):
        return self._at(t, "right")

    def left(self, t):
        return self._at(t, "left")


def manoeuvre_table(m):
    return Table(m["time"], np.column_stack([m[n] for n in INPUTS]))


def co_simulation(table, h, t_end, record, parameters=None, first_order=True):
    """The FMI 2 Co-Simulation FMU over `table`: at each point t_i = i h the inputs are set to
    the table's right limit there (after a jump), and with `first_order` their chord's slope to
    the left limit at t_i + h; the outputs `record` are read after the inputs are set. Returns
    (t, inputs the FMU saw as oracle samples (times, rows), the recorded rows)."""
    n = int(round(t_end / h))
    cue = Component(CUEING_FMU, "oracle", parameters)
    vrs = [cue.vr[name] for name in INPUTS]
    rows, seen_t, seen = [], [], []
    try:
        for i in range(n + 1):
            t = i * h
            now = table.right(t)
            if i > 0 and not np.array_equal(now, seen[-1]):
                seen_t.append(t)
                seen.append(now)  # a jump at the point: the oracle sees both limits
            elif i == 0:
                seen_t.append(t)
                seen.append(now)
            cue.set_values(INPUTS, now)
            rows.append(cue.get(record))
            if i < n:
                then = table.left((i + 1) * h) if first_order else now
                if first_order:
                    cue.slave.setRealInputDerivatives(vrs, [1] * 6, list((then - now) / h))
                cue.step(h)
                seen_t.append((i + 1) * h)
                seen.append(then)
    finally:
        cue.free()
    return np.arange(n + 1) * h, (np.array(seen_t), np.array(seen)), np.array(rows)


def at_points(times, values, t):
    """The rows of `values` (sampled at `times`, jumps given twice) at the points `t`: the last
    sample at each time (after a jump)."""
    index = np.searchsorted(times, t, side="right") - 1
    assert np.allclose(times[index], t, rtol=0, atol=1e-12)
    return values[index]


def perceived_oracle(seen_t, seen):
    """SPEC §12's filters on the inputs as the FMU saw them: perceived f (otoliths from g ez)
    and omega (canals from zero), columns as PERCEIVED."""
    rest = (0.0, 0.0, gravity())
    return np.column_stack([perception.perceive_f(seen_t, seen[:, :3], rest),
                            perception.perceive_omega(seen_t, seen[:, 3:])])


# -- the oracles agree with themselves -----------------------------------------------------------

def test_the_perception_oracle_agrees_with_its_closed_forms_and_scipy():
    """The modal form's step response equals the hand-worked partial fractions and scipy's
    step of N(s)/D(s); its frequency response equals N(j w)/D(j w) and OTO has unit gain at
    rest; the exact simulator equals scipy's lsim (first-order hold) and, for a finely sampled
    sinusoid, the closed-form response within the chord error (w h)^2/8 times ||h||_1."""
    t = np.linspace(0.0, 60.0, 60001)
    for lags, by_hand in ((perception.OTOLITH, perception.otolith_step), (perception.CANAL, perception.canal_step)):
        den = np.poly1d([1.0])
        for tau in lags.taus:
            den = den * np.poly1d([tau, 1.0])
        system = signal.lti(lags.numerator, den.coeffs)
        _, step = signal.step(system, T=t)
        assert np.max(np.abs(lags.step(t) - by_hand(t))) < 1e-12
        assert np.max(np.abs(lags.step(t) - step)) < 1e-9
        w = np.array(OMCT_FREQUENCIES)
        modal = sum(r / (1j * w + a) for r, a in zip(lags.residues, lags.rates))
        assert np.max(np.abs(modal - lags.response(w))) < 1e-12
        u = np.sin(1.7 * t) + 0.3 * np.cos(0.2 * t)
        _, y_lsim, _ = signal.lsim(system, u, t, interp=True)
        assert np.max(np.abs(lags.simulate(t, u) - y_lsim)) < 1e-10
        for omega in (0.1, 15.85):
            y = lags.simulate(t, np.sin(omega * t))
            bound = (omega * (t[1] - t[0])) ** 2 / 8 * perception.l1_norm(lags)
            assert np.max(np.abs(y - lags.sine(t, omega))) < bound
    assert perception.OTOLITH.gain_at_rest() == 1.0
    # The otoliths start at their steady state: a constant input stays where it is.
    y = perception.OTOLITH.simulate(t, np.full_like(t, 9.81), perception.OTOLITH.rest_state(9.81))
    assert np.max(np.abs(y - 9.81)) < 1e-12


def test_the_washout_oracles_kinematics_agree_with_finite_differences():
    """E(beta) is R^T dR/dt for the 1-2-3 angles, E^-1 inverts it, dE/dt is its derivative, and
    the tilt targets' first and second derivatives are those of the targets (central
    differences, at a random state)."""
    rng = np.random.default_rng(1)
    beta, rate = rng.uniform(-0.5, 0.5, 3), rng.uniform(-1, 1, 3)
    eps = 1e-6
    r_dot = (washout.rotation(beta + eps * rate) - washout.rotation(beta - eps * rate)) / (2 * eps)
    skew = washout.rotation(beta).T @ r_dot
    w = np.array([skew[2, 1], skew[0, 2], skew[1, 0]])
    assert np.max(np.abs(washout.euler_matrix(beta) @ rate - w)) < 1e-9
    assert np.max(np.abs(washout.euler_rates(beta, w) - rate)) < 1e-9
    e_dot = (washout.euler_matrix(beta + eps * rate) - washout.euler_matrix(beta - eps * rate)) / (2 * eps)
    assert np.max(np.abs(washout.euler_matrix_rate(beta, rate) - e_dot)) < 1e-9
    wo = washout.Washout(washout.start_values(CUEING_FMU))
    fl, dfl, ddfl = np.array([-1.2, 0.9]), np.array([0.7, -0.4]), np.array([0.3, 0.5])

    def target(s):
        return wo.targets(fl + s * dfl + s * s / 2 * ddfl, dfl + s * ddfl, ddfl, (False, False))

    value, first, second, _ = target(0.0)
    assert np.max(np.abs((target(eps)[0] - target(-eps)[0]) / (2 * eps) - first)) < 1e-8
    assert np.max(np.abs((target(eps)[1] - target(-eps)[1]) / (2 * eps) - second)) < 1e-7


# -- SPEC §12: the vehicle's perceived cues ------------------------------------------------------

SINE_AMPLITUDES = np.array([1.0, 0.8, 0.6, 0.1, 0.08, 0.06])  # m/s2 (deviation from g ez), rad/s


@pytest.mark.parametrize("omega", OMCT_FREQUENCIES, ids=[f"{w:.3f}rad_per_s" for w in OMCT_FREQUENCIES])
def test_perceived_cues_of_sinusoids_at_the_omct_frequencies(omega):
    """All six inputs sinusoidal at one OMCT frequency (f = g ez + A sin(w t), omega = B sin(w t),
    sampled at communication steps of at most period/200 and 10 ms, chords in between), for a
    period or 8 s, whichever is longer: perceived.f and perceived.omega equal SPEC §12's filters
    on that signal within 1e-6."""
    period = 2 * math.pi / omega
    h = max(s for s in (0.001, 0.002, 0.005, 0.01) if s <= period / 200 or s == 0.001)
    t_end = h * math.ceil(max(8.0, period) / h)
    t = np.arange(int(round(t_end / h)) + 1) * h
    rest = np.array([0.0, 0.0, gravity(), 0.0, 0.0, 0.0])
    table = Table(t, rest + np.outer(np.sin(omega * t), SINE_AMPLITUDES))
    _, (seen_t, seen), fmu = co_simulation(table, h, t_end, PERCEIVED)
    expected = at_points(seen_t, perceived_oracle(seen_t, seen), t)
    error = np.max(np.abs(fmu - expected), axis=0)
    print(f"w = {omega:.4f} rad/s, h = {h * 1e3:g} ms, {t_end:.1f} s: largest |FMU - SPEC 12| "
          f"perceived.f {error[:3].max():.2e} m/s2, perceived.omega {error[3:].max():.2e} rad/s")
    assert error.max() < 1e-6, error


STEP_AT = 1.0
STEP = np.array([1.5, -1.0, 2.0, 0.2, -0.1, 0.3])  # m/s2, rad/s


def step_table(t_end):
    rest = np.array([0.0, 0.0, gravity(), 0.0, 0.0, 0.0])
    return Table([0.0, STEP_AT, STEP_AT, t_end], [rest, rest, rest + STEP, rest + STEP])


def step_expected(t):
    """SPEC §12's closed-form step responses (the otoliths from g ez)."""
    rest = np.array([0.0, 0.0, gravity()])
    f = rest + np.outer(perception.otolith_step(t - STEP_AT), STEP[:3])
    w = np.outer(perception.canal_step(t - STEP_AT), STEP[3:])
    return np.column_stack([f, w])


def test_perceived_cues_of_a_step_in_co_simulation_fmi2():
    """A step of all six inputs at t = 1 s (set at a communication point; h = 1 ms): perceived.f
    and perceived.omega equal the closed-form step responses (and the simulator on the inputs
    as set) within 1e-6."""
    t_end, h = 8.0, 1e-3
    t, (seen_t, seen), fmu = co_simulation(step_table(t_end), h, t_end, PERCEIVED)
    closed = step_expected(t)
    simulated = at_points(seen_t, perceived_oracle(seen_t, seen), t)
    oracle_error = float(np.max(np.abs(simulated - closed)))
    assert oracle_error < 1e-10, oracle_error  # the two oracles: rounding over 8000 steps
    error = np.max(np.abs(fmu - closed), axis=0)
    print(f"step, FMI 2, largest |FMU - closed form|: perceived.f {error[:3].max():.2e} m/s2, "
          f"perceived.omega {error[3:].max():.2e} rad/s (the simulator: {oracle_error:.1e})")
    assert error.max() < 1e-6, error


def test_perceived_cues_of_a_step_in_co_simulation_fmi3():
    """The same step through the FMI 3 FMU, the inputs held over each step (FMI 3 has no input
    derivatives; a step needs none): perceived.f and perceived.omega equal the closed forms
    within 1e-6."""
    from fmpy.fmi3 import FMU3Slave
    md = read_model_description(str(FMI3_CUEING))
    var = {v.name: v.valueReference for v in md.modelVariables}
    slave = FMU3Slave(guid=md.guid, unzipDirectory=extract(str(FMI3_CUEING)), modelIdentifier="StewartCueing",
                      instanceName="oracle3")
    t_end, h = 8.0, 1e-3
    table, n = step_table(t_end), int(round(t_end / 1e-3))
    slave.instantiate()
    try:
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        rows = []
        for i in range(n + 1):
            u = table.right(i * h)
            slave.setFloat64([var["f"]], list(u[:3]))
            slave.setFloat64([var["omega"]], list(u[3:]))
            rows.append(np.concatenate([slave.getFloat64([var["perceived.f"]], 3),
                                        slave.getFloat64([var["perceived.omega"]], 3)]))
            if i < n:
                slave.doStep(currentCommunicationPoint=i * h, communicationStepSize=h)
        slave.terminate()
    finally:
        slave.freeInstance()
    error = np.max(np.abs(np.array(rows) - step_expected(np.arange(n + 1) * h)), axis=0)
    print(f"step, FMI 3, largest |FMU - closed form|: perceived.f {error[:3].max():.2e} m/s2, "
          f"perceived.omega {error[3:].max():.2e} rad/s")
    assert error.max() < 1e-6, error


# -- SPEC §11: the classical washout, and §12 on the simulator's cues ------------------------------

MANOEUVRES = {"brake": vehicle.brake, "lane_change": vehicle.lane_change}
H = 1e-3
WASHOUT_RECORD = POSE + SIM + PERCEIVED_SIM + ["workspace.scale", "workspace.usage"]


class ModelExchange:
    """A Model Exchange master in Python for the cueing FMU: solve_ivp's DOP853 on the FMU's
    derivatives with the inputs of a Table set at every right-hand-side time, restarting at the
    table's rows; the event indicators' sign changes located by solve_ivp, each handled by an
    event iteration just past the root (where the indicator has changed sign). An indicator at
    zero right after an event (the new switch's, which starts there) is left out for 1 us."""

    def __init__(self, fmu=CUEING_FMU, rtol=1e-10, atol=1e-12):
        fmu = str(fmu)
        self.md = read_model_description(fmu)
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.fmu = FMU2Model(guid=self.md.guid, unzipDirectory=extract(fmu),
                             modelIdentifier=self.md.modelExchange.modelIdentifier, instanceName="oracle-me")
        self.nx, self.nz = len(self.md.derivatives), self.md.numberOfEventIndicators
        self.rtol, self.atol = rtol, atol
        self.inputs = [self.vr[n] for n in INPUTS]
        self.event_times = []
        self._x, self._dx, self._z = (c_double * self.nx)(), (c_double * self.nx)(), (c_double * self.nz)()
        self.fmu.instantiate()
        self.fmu.setupExperiment(startTime=0.0)
        self.fmu.enterInitializationMode()
        self.fmu.exitInitializationMode()
        self._event_iteration()

    def _event_iteration(self):
        while self.fmu.newDiscreteStates()[0]:
            pass
        self.fmu.enterContinuousTimeMode()

    def _set(self, t, x, u):
        self.fmu.setTime(t)
        self.fmu.setReal(self.inputs, list(u))
        self._x[:] = list(x)
        self.fmu.setContinuousStates(self._x, self.nx)

    def _indicators(self, t, x, u):
        self._set(t, x, u)
        self.fmu.getEventIndicators(self._z, self.nz)
        return np.array(self._z)

    def states(self):
        self.fmu.getContinuousStates(self._x, self.nx)
        return np.array(self._x)

    def run(self, table, t_out, record):
        """The outputs `record` at the times `t_out` (rows) over the table's time."""
        out = np.full((len(t_out), len(record)), np.nan)
        record_vrs = [self.vr[n] for n in record]
        x, t, quiet = self.states(), 0.0, set()
        for k in range(len(table.times) - 1):
            a, b, u0, u1 = table.times[k], table.times[k + 1], table.values[k], table.values[k + 1]

            def u_of(s):
                return u0 + (s - a) / (b - a) * (u1 - u0)

            def rhs(s, y):
                self._set(s, y, u_of(s))
                self.fmu.getDerivatives(self._dx, self.nx)
                return np.array(self._dx)

            events = []
            for i in range(self.nz):
                def event(s, y, i=i):
                    return self._indicators(s, y, u_of(s))[i]
                event.terminal = True
                events.append(event)
            while t < b:
                end = min(b, t + 1e-6) if quiet else b
                active = [e for i, e in enumerate(events) if i not in quiet]
                sol = solve_ivp(rhs, (t, end), x, method="DOP853", rtol=self.rtol, atol=self.atol,
                                events=active or None, dense_output=True)
                if sol.status < 0:
                    raise RuntimeError(sol.message)
                stop = sol.t[-1]
                for j in np.nonzero((t_out >= t - 1e-12) & (t_out < stop - 1e-12))[0]:
                    self._set(t_out[j], sol.sol(t_out[j]), u_of(t_out[j]))
                    out[j] = self.fmu.getReal(record_vrs)
                x, quiet = sol.y[:, -1], set()
                if sol.status == 1:
                    stop, x = self._past_the_root(sol, t, stop, end, u_of)
                    self._set(stop, x, u_of(stop))
                    self.fmu.enterEventMode()
                    self._event_iteration()
                    self.event_times.append(stop)
                    x = self.states()
                    z = self._indicators(stop, x, u_of(stop))
                    quiet = {i for i in range(self.nz) if abs(z[i]) < 1e-9}
                t = stop
        for j in np.nonzero(np.abs(t_out - t) < 1e-12)[0]:
            self._set(t, x, table.values[-1])
            out[j] = self.fmu.getReal(record_vrs)
        return out

    def _past_the_root(self, sol, t, stop, end, u_of):
        """The first point at or after solve_ivp's root where an indicator has changed sign."""
        before = self._indicators(t, sol.sol(t), u_of(t))
        x, step = sol.y[:, -1], 1e-13
        while True:
            z = self._indicators(stop, x, u_of(stop))
            if np.any(np.sign(z) != np.sign(before)) or step > 1e-8:
                return stop, x
            stop = min(stop + step, end)
            x = sol.sol(stop)
            step *= 4

    def free(self):
        self.fmu.terminate()
        self.fmu.freeInstance()


@pytest.fixture(scope="module")
def runs():
    """Each manoeuvre at the 1 ms points through the washout oracle, the Co-Simulation FMU (the
    inputs following the manoeuvre's chords) and the Model Exchange FMU (the Python master),
    default parameters (cueing.method = 0): {name: {"oracle", "cs", "me": dicts of arrays}}."""
    wo = washout.Washout(washout.start_values(CUEING_FMU))
    result = {}
    for name, make in MANOEUVRES.items():
        m = make()
        t_end = float(m["time"][-1])
        t = np.arange(int(round(t_end / H)) + 1) * H
        oracle = wo.simulate(m["time"], np.column_stack([m[n] for n in F]), np.column_stack([m[n] for n in OMEGA]), t)
        _, _, rows = co_simulation(manoeuvre_table(m), H, t_end, WASHOUT_RECORD)
        cs = {"time": t, **{n: rows[:, j] for j, n in enumerate(WASHOUT_RECORD)}}
        me = ModelExchange()
        try:
            rows = me.run(manoeuvre_table(m), t, WASHOUT_RECORD)
        finally:
            me.free()
        me_run = {"time": t, "event_times": np.array(me.event_times),
                  **{n: rows[:, j] for j, n in enumerate(WASHOUT_RECORD)}}
        result[name] = {"oracle": oracle, "cs": cs, "me": me_run}
    return result


GROUPS = {"pose.r (m)": "pose.r[", "pose.v (m/s)": "pose.v[", "pose.a (m/s2)": "pose.a[",
          "pose.angles (rad)": "pose.angles[", "pose.angleRates (rad/s)": "pose.angleRates[",
          "pose.angleAccelerations (rad/s2)": "pose.angleAccelerations[", "fsim (m/s2)": "fsim[",
          "omegasim (rad/s)": "omegasim["}
#: Tolerances of the washout's comparison. The oracle's own error is at the rounding level: its
#: DOP853 steps end at the input's 10 ms rows, where the error of an 8th-order step on time
#: constants of 0.25 s and more is below 1e-13 (rtol 1e-7 and 1e-13 give the braking's outputs
#: to 1e-14), and brentq locates the switches to rounding. A fixed-step RK4 at 1 ms on these time
#: scales (w h <= 0.004) errs by about (w h)^4/120, relative, under 1e-11; the Model Exchange
#: master is the oracle's integrator on the FMU's derivatives. 1e-8 (1e-7 for the angular
#: accelerations) leaves room for another integrator and the switch times' location, and
#: stands five orders below what an approximate limiter costs (1e-3 rad in tilt, 0.1 rad/s in
#: omegasim).
WASHOUT_TOLERANCE = {group: 1e-8 for group in GROUPS}
WASHOUT_TOLERANCE["pose.angleAccelerations (rad/s2)"] = 1e-7


def compare(name, fmu, oracle, what):
    """The largest differences of the pose command, fsim and omegasim by group (printed with
    the oracle's switches); the workspace limiter must not have acted."""
    assert np.all(fmu["workspace.scale"] == 1.0), f"{name}: the workspace limiter acted"
    worst = {group: max(float(np.max(np.abs(fmu[n] - oracle[n]))) for n in POSE + SIM if n.startswith(prefix))
             for group, prefix in GROUPS.items()}
    switches = ", ".join(f"{s[2]} {s[1]} at {s[0]:.4f} s" for s in oracle["switches"])
    print(f"{name}, {what}, largest |FMU - oracle|: " + ", ".join(f"{g} {v:.1e}" for g, v in worst.items())
          + f"; workspace usage <= {np.max(fmu['workspace.usage']):.3f}; the oracle's switches: {switches}")
    return worst


def limiter_switch_times(oracle, clips=False):
    """The distinct times at which the oracle's tilt limiter switches (and with `clips`, where
    the targets' clips start or stop acting)."""
    return np.unique([s[0] for s in oracle["switches"] if clips or not s[2].startswith("clip")])


@pytest.mark.parametrize("name", list(MANOEUVRES))
def test_the_classical_washout_follows_the_oracle_in_co_simulation(name, runs):
    """The braking (the pitch slews, its target is clipped at tilt.max, it slews back) and the
    lane change (the roll slews up, down, up) at 1 ms, the inputs following their chords: the
    pose command, fsim and omegasim equal the oracle's within WASHOUT_TOLERANCE, the workspace
    limiter idle (workspace.scale = 1 throughout)."""
    oracle = runs[name]["oracle"]
    assert len(limiter_switch_times(oracle)) >= 3, "the tilt rate limit hardly acted"
    worst = compare(name, runs[name]["cs"], oracle, "Co-Simulation at 1 ms")
    for group, value in worst.items():
        assert value < WASHOUT_TOLERANCE[group], (group, value)


@pytest.mark.parametrize("name", list(MANOEUVRES))
def test_the_classical_washout_follows_the_oracle_in_model_exchange(name, runs):
    """The same manoeuvres through the Model Exchange interface (a Python master on solve_ivp's
    DOP853 at rtol 1e-10, the inputs interpolated at every right-hand-side time): the pose
    command, fsim and omegasim equal the oracle's within WASHOUT_TOLERANCE; the FMU's four event
    indicators (the limiter's modes, the targets' clips) fire once at each of the oracle's
    switches of the tilt limiter and of the clips, within 1e-9 s."""
    oracle, me = runs[name]["oracle"], runs[name]["me"]
    worst = compare(name, me, oracle, f"Model Exchange (DOP853, rtol 1e-10), {len(me['event_times'])} events")
    switches = limiter_switch_times(oracle, clips=True)
    assert len(me["event_times"]) == len(switches), (me["event_times"], switches)
    offset = float(np.max(np.abs(me["event_times"] - switches)))
    print(f"{name}: the events at {', '.join(f'{x:.6f}' for x in me['event_times'])} s, "
          f"largest offset from the oracle's switches {offset:.1e} s")
    assert offset < 1e-9, offset
    for group, value in worst.items():
        assert value < WASHOUT_TOLERANCE[group], (group, value)


def with_jumps(t, x, jumps):
    """The samples `x` at the points `t` with a jump inserted at each time in `jumps` that falls
    inside a step: its left value extrapolated from the two points before, its right value
    from the two after (the rows at the same time: left, then right)."""
    times, values = list(t), list(x)
    h = t[1] - t[0]
    for ts in jumps:
        i = int(np.floor(ts / h + 1e-9))
        if min(ts - t[i], t[min(i + 1, len(t) - 1)] - ts) < 1e-12 or i < 1 or i + 2 >= len(t):
            continue
        times += [ts, ts]
        values += [x[i] + (x[i] - x[i - 1]) * (ts - t[i]) / h, x[i + 1] + (x[i + 2] - x[i + 1]) * (ts - t[i + 1]) / h]
    order = np.argsort(times, kind="stable")
    return np.array(times)[order], np.array(values)[order]


@functools.lru_cache(maxsize=1)
def l1_norms():
    """||h||_1 of OTO (three columns) and SCC (three)."""
    return np.array([perception.l1_norm(perception.OTOLITH)] * 3 + [perception.l1_norm(perception.CANAL)] * 3)


def simulator_cues_check(t, run, jumps, kinks):
    """SPEC §12's filters on the FMU's own fsim and omegasim (the 1 ms samples, linear between,
    with `jumps` inserted: the switches of the tilt limiter and its clips, where omegasim jumps
    or fsim and omegasim have a kink) against its perceived.fsim and perceived.omegasim:
    (largest error per column, bound per column). The bound: inside a step the FMU's signal is
    smooth, not the chord; the chord's error is at most h^2/8 max|x''| and an extrapolated
    jump's h^2 max|x''|, so the filters' outputs differ by at most ||h||_1 (2.96 for OTO, 2.08
    for SCC) times 1.125 h^2 max|x''|. x'' is estimated from the second differences away from
    the jumps and from the input's breakpoints `kinks` (at a point, where the slope of fsim and
    omegasim jumps with the input's, the chords have no error to bound); twice that for the
    estimate, plus 1e-9 for the FMU's own integration (measured 1e-12 on the vehicle's cues)."""
    sim = np.column_stack([run[n] for n in SIM])
    got = np.column_stack([run[n] for n in PERCEIVED_SIM])
    times, values = with_jumps(t, sim, jumps)
    rest = (0.0, 0.0, gravity())
    expected = at_points(times, np.column_stack([perception.perceive_f(times, values[:, :3], rest),
                                                 perception.perceive_omega(times, values[:, 3:])]), t)
    second = np.abs(sim[2:] - 2 * sim[1:-1] + sim[:-2])
    near = np.zeros(len(t) - 2, dtype=bool)
    for ts in jumps:
        near |= np.abs(t[1:-1] - ts) < 2.5 * (t[1] - t[0])
    kinks = np.asarray(kinks)
    after = np.clip(np.searchsorted(kinks, t[1:-1]), 1, len(kinks) - 1)
    near |= np.minimum(np.abs(t[1:-1] - kinks[after - 1]), np.abs(t[1:-1] - kinks[after])) < 1e-9
    bound = 2 * l1_norms() * 1.125 * np.max(second[~near], axis=0) + 1e-9
    return np.max(np.abs(got - expected), axis=0), bound



@pytest.mark.parametrize("interface, cue", [
    ("cs", "fsim"),
    ("cs", "omegasim"),
    ("me", "fsim"),
    ("me", "omegasim"),
])
@pytest.mark.parametrize("name", list(MANOEUVRES))
def test_perceived_simulator_cues_are_spec_12s_filters_on_fsim_and_omegasim(name, interface, cue, runs):
    """perceived.fsim (perceived.omegasim) equal SPEC §12's otolith (canal) filters fed with the
    FMU's own fsim (omegasim) series within the bound of `simulator_cues_check`, also right
    after each switch of the tilt limiter, where omegasim jumps by the change of the tilt rate
    (up to 2 tilt.rateLimit): Co-Simulation ends a sub-step of the perception at each switch
    (an earlier build that did not was off by 3.8e-3 rad/s after a braking's switch)."""
    run = runs[name][interface]
    columns = slice(0, 3) if cue == "fsim" else slice(3, 6)
    error, bound = simulator_cues_check(run["time"], run, limiter_switch_times(runs[name]["oracle"], clips=True),
                                        MANOEUVRES[name]()["time"])
    unit = "m/s2" if cue == "fsim" else "rad/s"
    print(f"{name}, {interface}: largest |perceived.{cue} - SPEC 12 on the FMU's {cue}| "
          f"{error[columns].max():.2e} {unit} (bound {bound[columns].max():.1e})")
    assert np.all(error[columns] < bound[columns]), (error[columns], bound[columns])
