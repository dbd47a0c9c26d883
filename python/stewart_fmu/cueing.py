"""Motion cueing with the StewartCueing FMU (docs/cueing.md): one run of the washout on a
vehicle's motion, the whole motion system (vehicle -> cueing -> controller -> platform, the
shipped StewartMotionSystem.ssp), and the Objective Motion Cueing Test (ICAO 9625): gain and
phase of the simulator's motion over the vehicle's at twelve frequencies, with Bode plots."""

import math

import numpy as np
from fmpy import read_model_description

from . import vehicle
from .core import CONTROLLER_FMU, CUEING_FMU, LEGS, PLATFORM_FMU, Component, check_times, fmu_file
from .ssp import MOTION_SYSTEM_SSP, bindings, connections, system_description

#: SPEC 12's thresholds of perception (Reid and Nahon 1985): specific force per cabin axis
#: (m/s2) and angular velocity per axis (rad/s; 3.0, 3.6 and 2.6 deg/s).
THRESHOLD_F = (0.17, 0.17, 0.28)
THRESHOLD_OMEGA = tuple(math.radians(d) for d in (3.0, 3.6, 2.6))
#: The perceived cues the cueing FMU outputs (SPEC 12): the vehicle's, then the simulator's.
PERCEIVED = [f"perceived.{n}[{k}]" for n in ("f", "omega") for k in (1, 2, 3)]
PERCEIVED_SIM = [f"perceived.{n}[{k}]" for n in ("fsim", "omegasim") for k in (1, 2, 3)]
AXES = ("x", "y", "z", "roll", "pitch", "yaw")
F = [f"f[{k}]" for k in (1, 2, 3)]
OMEGA = [f"omega[{k}]" for k in (1, 2, 3)]
FSIM = [f"fsim[{k}]" for k in (1, 2, 3)]
OMEGASIM = [f"omegasim[{k}]" for k in (1, 2, 3)]
#: The pose command: the cueing FMU's outputs and the controller's inputs of the same names.
POSE = [f"pose.{name}[{k}]" for name in ("r", "v", "a", "angles", "angleRates", "angleAccelerations")
        for k in (1, 2, 3)]
#: The OMCT's twelve frequencies, rad/s: 10^((k-6)/5), k = 1..12 (0.1 to 15.85).
OMCT_FREQUENCIES = tuple(10 ** ((k - 6) / 5) for k in range(1, 13))
#: The OMCT's tests: name -> (input, output, amplitude of the input sinusoid). The direct
#: tests per axis and the tilt coordination's cross-couplings (surge -> pitch, sway -> roll).
#: Rotations are driven through the angular velocity alone (f held at rest); gains of angular
#: velocity over angular velocity equal those of angle over angle.
OMCT_TESTS = {
    "surge": ("f[1]", "fsim[1]", 0.1),
    "sway": ("f[2]", "fsim[2]", 0.1),
    "heave": ("f[3]", "fsim[3]", 0.1),
    "roll": ("omega[1]", "omegasim[1]", 0.01),
    "pitch": ("omega[2]", "omegasim[2]", 0.01),
    "yaw": ("omega[3]", "omegasim[3]", 0.01),
    "surge -> pitch": ("f[1]", "omegasim[2]", 0.1),
    "sway -> roll": ("f[2]", "omegasim[1]", 0.1),
}
REST = {"f[1]": 0.0, "f[2]": 0.0, "f[3]": vehicle.G, "omega[1]": 0.0, "omega[2]": 0.0, "omega[3]": 0.0}


#: What `run` records by default.
RECORDED = POSE + FSIM + OMEGASIM + PERCEIVED + PERCEIVED_SIM + ["workspace.usage", "workspace.scale"]


def run(manoeuvre, h=1e-3, parameters=None, record=RECORDED, fmu=CUEING_FMU, first_order=False, integers=None,
        strings=None):
    """The cueing FMU alone on a manoeuvre (`stewart_fmu.vehicle`'s columns: time, f[1..3],
    omega[1..3]; linearly interpolated to the communication points) to the manoeuvre's end,
    the inputs held over each step of `h`, or with `first_order` following their chord to the
    next point (fmi2SetRealInputDerivatives). `integers`: Integer parameters by name (for
    example {"cueing.method": 1}, predictive cueing); `strings`: String parameters
    ({"preview.file": path}). Integer outputs in `record` (`mpc.fallbacks`, `mpc.acceptable`, `mpc.iterations`)
    are read as such. Returns a dict of arrays: `time`, the vehicle's `f[k]`, `omega[k]` as
    set, and `record` at the same instants (the outputs at a communication point see the inputs
    set there)."""
    t_end = float(manoeuvre["time"][-1])
    check_times(t_end, h)
    cue = Component(fmu, "cueing", {**(parameters or {}), **(strings or {})}, integers)
    counters = [n for n in record if n in ("mpc.fallbacks", "mpc.iterations", "mpc.acceptable")]
    reals = [n for n in record if n not in counters]
    counter_vrs = [cue.vr[n] for n in counters]
    inputs = [cue.vr[n] for n in F + OMEGA]
    try:
        rows = []
        steps = int(round(t_end / h))
        now = np.concatenate(vehicle.at(manoeuvre, cue.time))
        for i in range(steps + 1):
            cue.set_values(F + OMEGA, now)
            counted = cue.slave.getInteger(counter_vrs) if counter_vrs else []
            rows.append(np.concatenate([[cue.time], now, cue.get(reals), counted]))
            if i < steps:
                then = np.concatenate(vehicle.at(manoeuvre, cue.time + h))
                if first_order:
                    cue.slave.setRealInputDerivatives(inputs, [1] * 6, list((then - now) / h))
                cue.step(h)
                now = then
    finally:
        cue.free()
    rows = np.array(rows)
    names = ["time"] + F + OMEGA + reals + counters
    return {n: rows[:, j] for j, n in enumerate(names)}


def measures(result):
    """SPEC 12's measures of a run of the cueing FMU (a dict of arrays with the outputs
    `perceived.*` and `workspace.usage`, as `run` and `motion_system` return): for each cabin
    axis the rms of the perceived error (perceived vehicle minus perceived simulator; m/s2 or
    rad/s) and Pearson's correlation of the two perceived signals, and the share of the time
    with a false cue (the simulator's perceived cue beyond its threshold while the vehicle's is
    below its threshold or of the other sign; the vertical force as its deviation from g); and
    in all: `perceived_error`, the rms of the horizontal (x and y) perceived specific-force
    error (m/s2); `correlation`, the mean correlation over the axes on which the vehicle's cue
    is perceived (beyond its threshold at some time); `false_cues`, the share of the time with
    a false cue on some axis; `max_usage`, the largest workspace usage. Returns a dict."""
    g = float(np.median(result["perceived.f[3]"][:1])) if len(result["perceived.f[3]"]) else 9.81
    rest = np.array([0.0, 0.0, g, 0.0, 0.0, 0.0])
    thresholds = np.array(THRESHOLD_F + THRESHOLD_OMEGA)
    vehicle = np.column_stack([result[n] for n in PERCEIVED]) - rest
    simulator = np.column_stack([result[n] for n in PERCEIVED_SIM]) - rest
    error = vehicle - simulator
    out = {}
    felt_axes, false_any = [], np.zeros(len(error), dtype=bool)
    for k, axis in enumerate(AXES):
        v, s = vehicle[:, k], simulator[:, k]
        out[f"rms_{axis}"] = float(np.sqrt(np.mean(error[:, k] ** 2)))
        correlated = np.std(v) > 1e-12 and np.std(s) > 1e-12
        out[f"correlation_{axis}"] = float(np.corrcoef(v, s)[0, 1]) if correlated else float("nan")
        if np.max(np.abs(v)) > thresholds[k]:
            felt_axes.append(out[f"correlation_{axis}"])
        false = (np.abs(s) > thresholds[k]) & ((np.abs(v) < thresholds[k]) | (np.sign(v) != np.sign(s)))
        out[f"false_cues_{axis}"] = float(np.mean(false))
        false_any |= false
    out["perceived_error"] = float(np.sqrt(np.mean(error[:, 0] ** 2 + error[:, 1] ** 2)))
    out["correlation"] = float(np.nanmean(felt_axes)) if felt_axes else float("nan")
    out["false_cues"] = float(np.mean(false_any))
    if "workspace.usage" in result:
        out["max_usage"] = float(np.max(result["workspace.usage"]))
    return out


def motion_system(manoeuvre, h=1e-3, stand=None, cueing=None, controller=None, platform=None,
                  record=("r[1]", "r[2]", "r[3]", "angles[1]", "angles[2]", "angles[3]") + tuple(f"l[{k}]" for k in LEGS),
                  master="fmpy"):
    """The whole motion system of StewartMotionSystem.ssp: the vehicle's motion (a manoeuvre's
    columns, interpolated linearly to the communication points) -> StewartCueing ->
    StewartController (programme 3, the SSP's binding) -> StewartPlatform, connected as the
    SSP's system description says, Gauss-Seidel at the communication step `h`: at each point
    the vehicle's motion goes to the cueing FMU, its pose command and the platform's legs to the
    controller, its forces to the platform, then all three step. `master`: "fmpy" (FMPy's
    instances driven from Python) or "compiled" (`stewart-master`, the same numbers for the
    platform and the controller to the bit). `stand`: start values of the stand's parameters
    (`B`, `A`, `lmin`, `lmax`, ...) given once and set in every component that has them;
    `cueing`, `controller`, `platform`: further start values by name. Returns a dict of arrays:
    `time`, the vehicle's f, omega, the cueing FMU's pose command, fsim, omegasim and
    workspace.scale, the controller's lp, and the platform's `record` (FMPy: the cueing FMU's
    outputs at each point with the vehicle's motion there; compiled: after each step, before
    the next point's motion)."""
    t_end = float(manoeuvre["time"][-1])
    check_times(t_end, h)
    if master not in ("fmpy", "compiled"):
        raise ValueError(f"master = {master!r}: 'fmpy' or 'compiled'")
    ssd = system_description(fmu_file(MOTION_SYSTEM_SSP))
    fmus = {"cueing": CUEING_FMU, "controller": CONTROLLER_FMU, "platform": PLATFORM_FMU}
    start = _start_values(fmus, stand, {"cueing": cueing, "controller": controller, "platform": platform})
    cue_out = POSE + FSIM + OMEGASIM + ["workspace.scale"]
    lp = [f"lp[{k}]" for k in LEGS]
    names = ["time"] + F + OMEGA + cue_out + lp + list(record)
    if master == "compiled":
        return _motion_system_compiled(manoeuvre, t_end, h, start, cue_out, lp, list(record), names)
    bound = bindings(ssd)
    parts = {}
    try:
        for name, fmu in fmus.items():
            reals, integers = {}, {}
            for k, v in bound.get(name, {}).items():
                (integers if isinstance(v, int) else reals)[k] = v
            parts[name] = Component(fmu, name, {**reals, **start[name]}, integers)
        wiring = _wiring(ssd, fmus)
        cue, ctl, pl = parts["cueing"], parts["controller"], parts["platform"]
        rows = []
        steps = int(round(t_end / h))
        for i in range(steps + 1):
            f, w = vehicle.at(manoeuvre, cue.time)
            cue.set_values(F + OMEGA, np.concatenate([f, w]))
            for name in ("controller", "platform"):
                for source, (outputs, connectors) in wiring[name].items():
                    parts[name].set_values(connectors, parts[source].values(outputs))
            rows.append(np.concatenate([[cue.time], f, w, cue.values(cue_out), ctl.values(lp),
                                        pl.values(list(record))]))
            if i < steps:
                for part in parts.values():
                    part.step(h)
    finally:
        for part in parts.values():
            part.free()
    rows = np.array(rows)
    return {n: rows[:, j] for j, n in enumerate(names)}


def _start_values(fmus, stand, given):
    """Each component's start values: the stand's parameters it has, then its own by name."""
    start = {}
    for name, fmu in fmus.items():
        names = {v.name for v in read_model_description(fmu_file(fmu)).modelVariables}
        start[name] = {**{k: v for k, v in (stand or {}).items() if k in names}, **(given[name] or {})}
    return start


def _wiring(ssd, fmus):
    """Each component's inputs from the SSP's connections, grouped by the component they come
    from: `{target: {source: ([outputs], [connectors])}}`."""
    wiring = {name: {} for name in fmus}
    for source, output, target, connector in connections(ssd):
        outputs, connectors = wiring[target].setdefault(source, ([], []))
        outputs.append(output)
        connectors.append(connector)
    return wiring


def _motion_system_compiled(manoeuvre, t_end, h, start, cue_out, lp, record, names):
    """`motion_system` through the compiled master: the SSP's system, the manoeuvre as an input
    table of the cueing FMU."""
    from . import master as compiled
    system = compiled.from_ssp(fmu_file(MOTION_SYSTEM_SSP))
    try:
        values = {f"{c}.{k}": v for c, given in start.items() for k, v in given.items()}
        table = {"time": manoeuvre["time"], **{n: manoeuvre[n] for n in F + OMEGA}}
        recorded = ([f"cueing.{n}" for n in F + OMEGA + cue_out] + [f"controller.{n}" for n in lp] +
                    [f"platform.{n}" for n in record])
        times, rows, status, message = compiled.run(system, t_end, h, values=values, record=recorded,
                                                    inputs={"cueing": table})
    finally:
        system.close()
    if status != "ok":
        raise RuntimeError(f"the motion system stopped at t = {times[-1] if len(times) else 0}: {status} {message}")
    return {"time": times, **{n: rows[:, j] for j, n in enumerate(names[1:])}}


def _real_parameters(parameters, fmu):
    """The FMU's Real parameters: its start values, `parameters` over them."""
    values = {v.name: float(v.start) for v in read_model_description(fmu_file(fmu)).modelVariables
              if v.causality == "parameter" and v.type == "Real"}
    values.update({k: float(v) for k, v in (parameters or {}).items()})
    return values


def _settling_time(parameters, fmu=CUEING_FMU):
    """Twelve times the slowest time constant of the filters (the FMU's start values, or
    `parameters`), s: what an OMCT run waits before it measures."""
    values = _real_parameters(parameters, fmu)
    poles = [(values["tilt.omega"], values["tilt.damping"])]
    for k in (1, 2, 3):
        poles += [(values[f"hp.f.omega[{k}]"], values[f"hp.f.damping[{k}]"]),
                  (values[f"hp.w.omega[{k}]"], values[f"hp.w.damping[{k}]"])]
    slowest = max(1.0 / values[f"hp.f.break[{k}]"] for k in (1, 2, 3))
    for w, z in poles:
        slow_pole = w * (z - math.sqrt(z * z - 1.0)) if z >= 1.0 else z * w
        slowest = max(slowest, 1.0 / slow_pole)
    return 12.0 * slowest


def omct(tests=tuple(OMCT_TESTS), frequencies=OMCT_FREQUENCIES, parameters=None, samples=100, periods=3, max_step=0.01,
         amplitude_scale=1.0, progress=None, fmu=CUEING_FMU, integers=None):
    """The Objective Motion Cueing Test of the cueing FMU alone: for each test of OMCT_TESTS
    and each frequency, a sinusoid `A sin(omega t)` on the test's input (the others at rest),
    `samples` communication steps per period but at most `max_step` long (over each step the
    input follows its chord, a first-order hold through fmi2SetRealInputDerivatives; the
    outputs are read with the input set to its value at the point, which the filters pass
    straight through), measured over `periods` whole periods after the filters' transient
    (twelve slowest time constants). `integers`: Integer parameters (for example
    {"cueing.method": 1}, predictive cueing). Returns {test: {"frequency": rad/s, "gain",
    "phase": deg, "limited": whether the limiter acted during the measurement}}; gain and
    phase of the output's fundamental over the input's. `progress(test, frequency)` is called
    before each run, for each test the run measures (tests that drive the same input share it)."""
    settle = _settling_time(parameters, fmu)
    tests = tuple(dict.fromkeys(tests))  # each test once, in the order given
    for test in tests:
        if test not in OMCT_TESTS:
            raise ValueError(f"omct: unknown test {test!r}; the tests are {list(OMCT_TESTS)}")
    # Tests that drive the same input with the same amplitude share their runs (surge and
    # surge -> pitch, sway and sway -> roll): one run reads every output they measure.
    runs = {}
    for test in tests:
        source, output, amplitude = OMCT_TESTS[test]
        runs.setdefault((source, amplitude * amplitude_scale), []).append((test, output))
    measured = {test: {"gain": [], "phase": [], "limited": []} for test in tests}
    for (source, amplitude), outputs in runs.items():
        for w in frequencies:
            if progress:
                for test, _ in outputs:
                    progress(test, w)
            period = 2 * math.pi / w
            per_period = max(samples, int(math.ceil(period / max_step)))
            h = period / per_period
            skip = int(math.ceil(settle / period)) * per_period
            n = skip + periods * per_period
            cue = Component(fmu, "omct", parameters, integers)
            try:
                ys, ts = [], []
                names = list(REST)
                at = names.index(source)
                vr = cue.vr[source]
                values = np.array(list(REST.values()))
                read = [output for _, output in outputs] + ["workspace.scale"]
                for i in range(n):
                    # A first-order hold: the input at the point and its chord to the next.
                    now, then = (amplitude * math.sin(w * j * h) for j in (i, i + 1))
                    values[at] = REST[source] + now
                    cue.set_values(names, values)
                    cue.slave.setRealInputDerivatives([vr], [1], [(then - now) / h])
                    cue.step(h)
                    if i + 1 > skip:
                        # The output at the point sees the input there (the filters pass it
                        # straight through).
                        values[at] = REST[source] + then
                        cue.set_values(names, values)
                        ys.append(cue.values(read))
                        ts.append((i + 1) * h)
            finally:
                cue.free()
            ys, ts = np.array(ys), np.array(ts)
            phasor = np.exp(-1j * w * ts)
            reference = np.sum(amplitude * np.sin(w * ts) * phasor)
            limited = bool(np.min(ys[:, -1]) < 1.0)
            for j, (test, _) in enumerate(outputs):
                ratio = np.sum(ys[:, j] * phasor) / reference
                measured[test]["gain"].append(abs(ratio))
                measured[test]["phase"].append(math.degrees(np.angle(ratio)))
                measured[test]["limited"].append(limited)
    return {test: {"frequency": np.array(frequencies), **{k: np.array(v) for k, v in measured[test].items()}}
            for test in tests}


#: The one fidelity region at hand (docs/cueing.md): Sinacori's and Schroeder's "high
#: fidelity" at 1 rad/s of a direct test, gain 0.8 to 1 with a phase within 20 deg.
HIGH_FIDELITY_AT_1 = {"gain": (0.8, 1.0), "phase": (-20.0, 20.0)}
DIRECT_TESTS = ("surge", "sway", "heave", "roll", "pitch", "yaw")


def bode_plot(result, path, title="Objective Motion Cueing Test: StewartCueing, default parameters", reference=None,
              others=None, label="FMU", fidelity=False):
    """Bode diagrams (gain and phase against frequency) of an `omct` result, four tests a row
    (gain above phase, the phase unwrapped); `reference`: another result drawn dashed (the
    filters' transfer functions); `others`: {label: result} drawn beside it (another method);
    `fidelity`: the high-fidelity region at 1 rad/s drawn on the direct tests
    (HIGH_FIDELITY_AT_1)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    tests = list(result)
    columns = min(4, len(tests))
    rows = -(-len(tests) // columns)
    fig, axes = plt.subplots(2 * rows, columns, figsize=(3.2 * columns, 2.9 * rows * 2 / 1.3), squeeze=False)

    def draw(gain_ax, phase_ax, r, style, label):
        phase = np.degrees(np.unwrap(np.radians(r["phase"])))
        gain_ax.loglog(r["frequency"], r["gain"], style, ms=3, lw=0.9, label=label)
        phase_ax.semilogx(r["frequency"], phase, style, ms=3, lw=0.9)

    for j, test in enumerate(tests):
        gain_ax, phase_ax = axes[2 * (j // columns), j % columns], axes[2 * (j // columns) + 1, j % columns]
        draw(gain_ax, phase_ax, result[test], "o-", label)
        for other_label, other in (others or {}).items():
            if test in other:
                draw(gain_ax, phase_ax, other[test], "s-", other_label)
        if fidelity and test in DIRECT_TESTS:
            g0, g1 = HIGH_FIDELITY_AT_1["gain"]
            p0, p1 = HIGH_FIDELITY_AT_1["phase"]
            gain_ax.plot([1.0, 1.0], [g0, g1], color="tab:green", lw=5, alpha=0.4, solid_capstyle="butt",
                         label="high fidelity at 1 rad/s")
            phase_ax.plot([1.0, 1.0], [p0, p1], color="tab:green", lw=5, alpha=0.4, solid_capstyle="butt")
        if reference and test in reference:
            draw(gain_ax, phase_ax, reference[test], "k--", "filters (SPEC 11)")
        gain_ax.set_title(test, fontsize=9)
        phase_ax.set_xlabel("frequency (rad/s)", fontsize=8)
        gain_ax.set_ylabel("gain", fontsize=8)
        phase_ax.set_ylabel("phase (deg)", fontsize=8)
        for ax in (gain_ax, phase_ax):
            ax.grid(True, which="both", lw=0.3)
            ax.tick_params(labelsize=7)
    for j in range(len(tests), rows * columns):
        axes[2 * (j // columns), j % columns].axis("off")
        axes[2 * (j // columns) + 1, j % columns].axis("off")
    axes[0, 0].legend(fontsize=7)
    fig.suptitle(title + " (gain: simulator over vehicle; cross-couplings in rad/s per m/s2)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def filter_responses(frequencies=OMCT_FREQUENCIES, parameters=None, fmu=CUEING_FMU):
    """The OMCT of §11's linear filters at small amplitude, from the FMU's start values (or
    `parameters`): {test: {"frequency", "gain", "phase"}}, what `omct` measures where no limit
    acts (the dashed reference of `bode_plot`). The tilt coordination feeds gravity into the
    translational channel, so surge and sway see `K (W_t (1 - W_l) + W_l)`."""
    p = _real_parameters(parameters, fmu)
    s = 1j * np.asarray(frequencies, dtype=float)

    def high_pass(prefix, k, third):
        w, z = p[f"{prefix}.omega[{k}]"], p[f"{prefix}.damping[{k}]"]
        quadratic = s * s + 2 * z * w * s + w * w
        return s ** 3 / (quadratic * (s + p[f"hp.f.break[{k}]"])) if third else s * s / quadratic

    low = p["tilt.omega"] ** 2 / (s * s + 2 * p["tilt.damping"] * p["tilt.omega"] * s + p["tilt.omega"] ** 2)
    h = {
        "surge": p["scale.f[1]"] * (high_pass("hp.f", 1, True) * (1 - low) + low),
        "sway": p["scale.f[2]"] * (high_pass("hp.f", 2, True) * (1 - low) + low),
        "heave": p["scale.f[3]"] * high_pass("hp.f", 3, True),
        "roll": p["scale.omega[1]"] * high_pass("hp.w", 1, False),
        "pitch": p["scale.omega[2]"] * high_pass("hp.w", 2, False),
        "yaw": p["scale.omega[3]"] * high_pass("hp.w", 3, False),
        "surge -> pitch": -s * p["scale.f[1]"] * low / p["g"],
        "sway -> roll": s * p["scale.f[2]"] * low / p["g"],
    }
    return {test: {"frequency": np.asarray(frequencies, dtype=float), "gain": np.abs(x),
                   "phase": np.degrees(np.angle(x))} for test, x in h.items()}
