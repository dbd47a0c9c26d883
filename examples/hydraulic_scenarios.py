"""The main job's demonstration of the hydraulic servo legs (docs/model.md §10): the defaults'
figures, holding under control, the heave programme in hydraulic mode, a loss of control
power (the legs lock and creep), a pump failure, a valve stuck open, and the work-precision
figure of the integrators with hydraulics; through the packaged FMUs, SI units, default stand
and legs. Writes hydraulic1_holding.csv .. hydraulic5_stuck_valve.csv, hydraulic_heave.png,
hydraulic_failures.png, hydraulic_air.png (oil with and without entrained air),
hydraulic_work_precision.png and hydraulic_summary.txt.

    python examples/hydraulic_scenarios.py [output-folder]   (default: output/)
"""

import math
import sys
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from stewart_fmu import Platform
from stewart_fmu import hydraulics as hy
from stewart_fmu.core import LEGS

from csv_columns import write_columns

# What the runs are compared with: §10 and the stand written out independently of the FMU's
# code, the tests' oracles (tests/python/oracles/).
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "python"))
from oracles import hydraulics as oracle  # noqa: E402
from oracles.stand import EQUILIBRIUM_FORCE, GRAVITY, MASS, neutral_leg_geometry  # noqa: E402

OUT = Path(sys.argv[1] if len(sys.argv) > 1 else "output")
P = hy.hydraulic_parameters()
AREA_A, AREA_B = oracle.areas(P)
K = oracle.flow_coefficient(P)
PERIOD = 2 * math.pi / 2.5573423705088842  # the default heave programme's
ATMOSPHERE = 101325.0  # Pa: zero absolute is this far below zero gauge (§10b)


def balance(c):
    """E(t) - E(0) - (work.hydraulic - work.compression - work.dissipated), J."""
    return c["E"] - c["E"][0] - (c["work.hydraulic"] - c["work.compression"] - c["work.dissipated"])


def columns(c, names):
    return {"t": c["time"], **{n: c[n] for n in names}}


def defaults_figures():
    """The defaults' figures (docs/model.md §10), from the parameters and the stand's geometry."""
    ps, beta = P["pS"], P["hydraulic.bulkModulus"]
    d, height = neutral_leg_geometry(nondimensional=False)
    l0 = math.hypot(d, height)
    mid = 0.5 * (P["lmin[1]"] + P["lmax[1]"])
    n_z = height / l0
    stiffness = lambda l: beta * (AREA_A ** 2 / oracle.volumes(l, P)[0] + AREA_B ** 2 / oracle.volumes(l, P)[1])  # noqa: E731
    # No load, valve fully open: both lands in series, p_A A_A = p_B A_B.
    speed = K * math.sqrt(ps * AREA_A / (AREA_A ** 3 + AREA_B ** 3))
    heave_mode = math.sqrt(6 * stiffness(l0) * n_z ** 2 / MASS)
    return (f"hydraulic legs (defaults): D/d = {P['hydraulic.bore'] * 1e3:.0f}/{P['hydraulic.rod'] * 1e3:.0f} mm "
            f"(A_A = {AREA_A * 1e4:.2f} cm2, A_B = {AREA_B * 1e4:.2f} cm2), stroke {P['lmax[1]'] - P['lmin[1]']:.2f} m, "
            f"dead volumes {P['hydraulic.deadVolumeA'] * 1e3:.1f}/{P['hydraulic.deadVolumeB'] * 1e3:.1f} L, beta "
            f"{beta / 1e9:.1f} GPa, supply {ps / 1e6:.0f} MPa; valve {P['valve.ratedFlow'] * 6e4:.0f} L/min at "
            f"{P['valve.ratedPressureDrop'] / 1e5:.0f} bar (K = {K:.3e} m3/(s.Pa^0.5)), spool "
            f"{P['valve.omega'] / (2 * math.pi):.0f} Hz, damping {P['valve.damping']}, p_cr {P['valve.pcr'] / 1e5:.1f} "
            f"bar, null leakage {P['valve.leakage']:.1e} m3/(s.Pa) per land, piston {P['hydraulic.internalLeakage']:.1e}."
            f" Figures: largest force {ps * AREA_A / 1e3:.1f} kN extending, {ps * AREA_B / 1e3:.1f} kN retracting "
            f"(the holding force is {EQUILIBRIUM_FORCE * MASS * GRAVITY / 1e3:.2f} kN); largest no-load speed "
            f"{speed:.3f} m/s (valve fully open); oil spring at mid-stroke ({mid:.2f} m) {stiffness(mid) / 1e6:.2f} "
            f"MN/m per leg, at the neutral legs {stiffness(l0) / 1e6:.2f} MN/m: the stand's heave mode on its oil "
            f"{heave_mode:.0f} rad/s ({heave_mode / (2 * math.pi):.1f} Hz); holding pressures "
            f"p_A = {oracle.holding_pressures(P)[0] / 1e6:.3f} MPa, p_B = {oracle.holding_pressures(P)[1] / 1e6:.1f} MPa")


def holding(summary):
    print("1 holding under control ...")
    c, errors, status = hy.resting(3.0)
    assert status == "ok", status
    write_columns(OUT / "hydraulic1_holding.csv", columns(c, hy.PA + hy.PB + hy.SPOOL + ["Qsupply", "r[3]"]))
    summary.append(
        f"1 holding the neutral pose under control, 3 s: pressures settle from p_A {c['pA[1]'][0] / 1e6:.3f}, p_B "
        f"{c['pB[1]'][0] / 1e6:.3f} MPa to {c['pA[1]'][-1] / 1e6:.3f}, {c['pB[1]'][-1] / 1e6:.3f} MPa (the leakage "
        f"equilibrium, same force); spools at {c['spool[1]'][-1]:.2e} (the offset the leakage needs); supply flow at "
        f"rest {c['Qsupply'][-1] * 6e4:.2f} L/min ({c['Qsupply'][-1] * P['pS'] / 1e3:.2f} kW); largest leg error "
        f"{errors.max() * 1e3:.4f} mm ({status})")


def heave(summary):
    print("2 heave programme in hydraulic mode ...")
    c, errors, status = hy.heave(10.0)
    assert status == "ok", status
    f = hy.cycle_figures(c, PERIOD, P)
    t = c["time"]
    power = np.gradient(c["work.hydraulic"], t)
    write_columns(OUT / "hydraulic2_heave.csv", {**columns(c, hy.PA + hy.PB + hy.SPOOL + ["Qsupply", "r[3]"]),
                                                 "leg_error": errors, "hydraulic_power": power})
    summary.append(
        f"2 heave programme, the default controller in hydraulic mode (drive = 2 in both FMUs: force loop kF = 1.5e-5 "
        f"1/N, leg error through the flow 50 1/s, flow feed-forward), 10 s at 1 ms: largest leg error "
        f"{errors.max() * 1e3:.3f} mm; over the last cycle ({PERIOD:.3f} s) pressures {f['pressure_range'][0] / 1e6:.2f}"
        f" .. {f['pressure_range'][1] / 1e6:.2f} MPa, spools up to {f['largest_opening']:.3f}, peak supply flow "
        f"{f['peak_flow'] * 6e4:.0f} L/min, hydraulic power peak {f['peak_power'] / 1e3:.0f} kW, mean "
        f"{f['mean_power'] / 1e3:.0f} kW (a constant-pressure supply throttled by the valves); energy balance residual "
        f"{np.max(np.abs(balance(c))):.1e} J of {c['work.dissipated'][-1] / 1e3:.0f} kJ dissipated")
    fig, ax = plt.subplots(2, 2, figsize=(14, 8))
    ax[0, 0].plot(t, errors * 1e3)
    ax[0, 0].set(title="Largest leg error max |l - l^p|", xlabel="t, s", ylabel="mm")
    for k in LEGS:
        ax[0, 1].plot(t, c[f"pA[{k}]"] / 1e6, lw=0.8, label=f"pA[{k}]")
    for k in LEGS:
        ax[0, 1].plot(t, c[f"pB[{k}]"] / 1e6, lw=0.8, ls="--", label=f"pB[{k}]")
    ax[0, 1].set(title="Chamber pressures (cap side solid, rod side dashed)", xlabel="t, s", ylabel="MPa")
    ax[0, 1].legend(fontsize=6, ncol=4)
    for k in LEGS:
        ax[1, 0].plot(t, c[f"spool[{k}]"], lw=0.8, label=f"spool[{k}]")
    ax[1, 0].set(title="Spool positions (1 = fully open to extension)", xlabel="t, s", ylabel="1")
    ax[1, 0].legend(fontsize=7, ncol=3)
    ax[1, 1].plot(t, c["Qsupply"] * 6e4, label="supply flow")
    ax[1, 1].set(title="Pump flow and hydraulic power", xlabel="t, s", ylabel="L/min")
    twin = ax[1, 1].twinx()
    twin.plot(t, power / 1e3, "k:", lw=0.9, label="power")
    twin.set_ylabel("kW")
    ax[1, 1].legend(fontsize=8, loc="upper left")
    twin.legend(fontsize=8, loc="upper right")
    fig.tight_layout()
    fig.savefig(OUT / "hydraulic_heave.png", dpi=110)
    plt.close(fig)


def failures(summary):
    print("3-5 loss of control power, pump failure, a valve stuck open ...")
    lost, _, s3 = hy.control_power_loss(1.0, 6.0)
    events, events_without_air = [], []
    pump, _, s4 = hy.pump_failure(1.0, 4.0, events=events)
    without_air = {"hydraulic.airFraction": 0.0}
    pump0, _, s40 = hy.pump_failure(1.0, 4.0, events=events_without_air, platform=without_air)
    stuck, stuck_errors, s5 = hy.stuck_valve(1.0, 6.0)
    stuck0, _, s50 = hy.stuck_valve(1.0, 6.0, platform=without_air)
    assert s3 == s4 == s40 == s5 == s50 == "ok", (s3, s4, s40, s5, s50)
    t = lost["time"]
    window = (t >= 3.0) & (t <= 6.0)
    creep = np.polyfit(t[window], lost["l[1]"][window], 1)[0]
    mid = int(np.argmin(np.abs(t - 4.5)))
    quasi = oracle.quasi_static_creep(lost["pA[1]"][mid], lost["pB[1]"][mid], lost["l[1]"][mid], P)
    write_columns(OUT / "hydraulic3_control_power_loss.csv", columns(lost, ["r[3]"] + hy.L + hy.PA + hy.PB + hy.SPOOL))
    summary.append(
        f"3 loss of control power at t = 1 s (every valve command 0): the spools centre ({max(abs(lost[n][-1]) for n in hy.SPOOL):.0e}) "
        f"and the legs lock on their oil; the leakage pulls both chambers towards pS/2, and the legs creep out at "
        f"{creep * 1e3:.4f} mm/s against {quasi * 1e3:.4f} mm/s quasi-static from the leakage flows and the load "
        f"pressures (heave {creep * oracle.heave_rate_of_leg_rate(lost['l[1]'][mid]) * 1e3:.4f} mm/s up)")
    warnings = [m for s, _, m in events if s == 1 and "cavitate" in m]
    warning = next((m for s, _, m in events_without_air if s == 1 and "cavitate" in m), "none")
    after = pump["time"] > 1.0
    write_columns(OUT / "hydraulic4_pump_failure.csv", columns(pump, ["r[3]", "der(v[3])", "pmin", "Qsupply"] + hy.L + hy.PA + hy.PB))
    write_columns(OUT / "hydraulic4_pump_failure_without_air.csv",
                  columns(pump0, ["r[3]", "der(v[3])", "pmin", "Qsupply"] + hy.L + hy.PA + hy.PB))
    summary.append(
        f"4 pump failure at t = 1 s (pS to 0, the controller still commanding): the platform settles through the "
        f"valves onto its lower stops (z {pump['r[3]'][0]:.3f} -> {pump['r[3]'][-1]:.3f} m, legs "
        f"{min(pump[n][-1] for n in hy.L):.4f} m); peak deceleration {np.max(pump['der(v[3])'][after]):.1f} m/s2 at "
        f"the stops; lowest chamber pressure pmin {pump['pmin'][-1] / 1e5:.4f} bar gauge, "
        f"{(pump['pmin'][-1] + ATMOSPHERE) / 1e5:.4f} bar absolute (oil with air, hydraulic.airFraction "
        f"{P['hydraulic.airFraction']}); {len(warnings)} warnings")
    summary.append(
        f"4 the same without air (hydraulic.airFraction = 0, section 10's oil): peak deceleration "
        f"{np.max(pump0['der(v[3])'][pump0['time'] > 1.0]):.1f} m/s2; pmin {pump0['pmin'][-1] / 1e5:.2f} bar gauge, "
        f"{(pump0['pmin'][-1] + ATMOSPHERE) / 1e5:.2f} bar absolute, below zero absolute where no oil can be; the FMU "
        f"warned once: \"{warning[:90]}...\"")
    joint = max(float(np.max(np.linalg.norm(np.array([stuck[f"jointForce[{k},{i}]"] for i in (1, 2, 3)]), axis=0)))
                for k in LEGS)
    others = max(float(np.max(np.abs(stuck[f"l[{k}]"] - stuck[f"l[{k}]"][0]))) for k in LEGS[1:])
    write_columns(OUT / "hydraulic5_stuck_valve.csv", columns(stuck, ["angles[1]", "angles[2]"] + hy.L + hy.PA + hy.PB))
    summary.append(
        f"5 leg 1's valve stuck at +0.2 from t = 1 s under feedback: leg 1 runs out to its upper stop "
        f"({stuck['l[1]'][-1]:.4f} m, p_A {stuck['pA[1]'][-1] / 1e6:.2f} MPa); the other legs move up to "
        f"{others * 1e3:.0f} mm from their start holding the tilted platform (roll "
        f"{math.degrees(stuck['angles[1]'][-1]):.2f} deg, pitch {math.degrees(stuck['angles[2]'][-1]):.2f} deg); "
        f"largest joint force {joint / 1e3:.1f} kN (holding: {EQUILIBRIUM_FORCE * MASS * GRAVITY / 1e3:.1f} kN); "
        f"lowest chamber pressure {stuck['pmin'][-1] / 1e5:.3f} bar gauge (without air {stuck0['pmin'][-1] / 1e5:.3f}: "
        f"no chamber comes near vacuum, the leg runs out at the supply; leg 1 at the end "
        f"{stuck['l[1]'][-1]:.5f} m with air, {stuck0['l[1]'][-1]:.5f} m without)")
    air_figure(pump, pump0, stuck, stuck0)
    fig, ax = plt.subplots(1, 3, figsize=(17, 4.4))
    ax[0].plot(t, (lost["l[1]"] - lost["l[1]"][0]) * 1e3, label="leg 1, simulated")
    ax[0].plot(t[window], (np.polyval(np.polyfit(t[window], lost["l[1]"][window], 1), t[window]) - lost["l[1]"][0]) * 1e3,
               "k:", label=f"fit: {creep * 1e3:.4f} mm/s (quasi-static {quasi * 1e3:.4f})")
    ax[0].set(title="3 Loss of control power at 1 s: locked legs creep", xlabel="t, s", ylabel="l[1] - l[1](0), mm")
    ax[0].legend(fontsize=8)
    ax[1].plot(pump["time"], pump["r[3]"], label="z")
    twin = ax[1].twinx()
    twin.plot(pump["time"], pump["pmin"] / 1e5, "r:", label="pmin")
    twin.axhline(-1.0, color="r", lw=0.5, ls="--")
    twin.set_ylabel("pmin, bar")
    ax[1].set(title="4 Pump failure at 1 s: settling onto the stops", xlabel="t, s", ylabel="centre of mass z, m")
    ax[1].legend(fontsize=8, loc="upper right")
    twin.legend(fontsize=8, loc="lower left")
    for k in LEGS:
        ax[2].plot(stuck["time"], stuck[f"l[{k}]"], lw=0.9, label=f"l[{k}]")
    ax[2].set(title="5 Valve 1 stuck at +0.2 from 1 s", xlabel="t, s", ylabel="leg length, m")
    ax[2].legend(fontsize=7, ncol=2)
    fig.tight_layout()
    fig.savefig(OUT / "hydraulic_failures.png", dpi=110)
    plt.close(fig)


def air_figure(pump, pump0, stuck, stuck0):
    """Oil with and without entrained air (docs/model.md §10b) through the pump failure and the
    stuck valve: absolute pressures, the platform's height."""
    fig, ax = plt.subplots(1, 3, figsize=(17, 4.4))
    for c, label, style in [(pump, f"with air (airFraction {P['hydraulic.airFraction']})", "-"),
                            (pump0, "without air (section 10)", "--")]:
        lowest = np.min([c[n] for n in hy.PA + hy.PB], axis=0)
        ax[0].plot(c["time"], (lowest + ATMOSPHERE) / 1e5, style, label=label)
        ax[1].plot(c["time"], c["r[3]"], style, label=label)
    ax[0].axhline(0.0, color="r", lw=0.8, ls=":", label="zero absolute")
    ax[0].set(title="Pump failure at 1 s: lowest chamber pressure", xlabel="t, s", ylabel="absolute pressure, bar",
              ylim=(-10, 20))
    ax[0].legend(fontsize=8)
    ax[1].set(title="Pump failure at 1 s: settling onto the stops", xlabel="t, s", ylabel="centre of mass z, m")
    ax[1].legend(fontsize=8)
    for c, label, style in [(stuck, "with air", "-"), (stuck0, "without air", "--")]:
        ax[2].plot(c["time"], (c["pB[1]"] + ATMOSPHERE) / 1e5, style, label=f"p_B[1], {label}")
        ax[2].plot(c["time"], (c["pA[1]"] + ATMOSPHERE) / 1e5, style, label=f"p_A[1], {label}")
    ax[2].set(title="Valve 1 stuck at +0.2 from 1 s: leg 1's chambers", xlabel="t, s", ylabel="absolute pressure, bar")
    ax[2].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(OUT / "hydraulic_air.png", dpi=110)
    plt.close(fig)


def short(x):
    """An error in the exponent form the docs quote (5.25e3, 4.35e-1): three digits."""
    mantissa, exponent = f"{x:.2e}".split("e")
    return f"{mantissa}e{int(exponent)}"


def work_precision(summary):
    """The pump failure with the valves fully open (the stiff regime: open lands with little
    drop) through the FMU's Co-Simulation at 1 ms communication steps: each method's error
    against the adaptive method at relTol 1e-12, and the wall time of its doStep calls alone
    (one run each on this machine, the ctypes call included: noisy; the stable measure is the
    evaluations per step in tests/hydraulics.rs and benches/results/hydraulics.txt)."""
    print("work-precision with hydraulics ...")
    start = {"drive": 2, **{f"valve[{k}]": 1.0 for k in LEGS}, "pS": 0.0}

    def run(settings):
        pl = Platform(parameters={**start, **settings}, name="work-precision")
        pressures, seconds = [], 0.0
        for _ in range(1000):
            t0 = time.perf_counter()
            pl.slave.doStep(currentCommunicationPoint=pl.time, communicationStepSize=1e-3)
            seconds += time.perf_counter() - t0
            pl.time += 1e-3
            pressures.append(pl.get("pA[1]", "pB[1]"))
        pl.free()
        return np.array(pressures), seconds / 1000 * 1e6

    reference, _ = run({"solver.relTol": 1e-12})
    rows = []
    for name, settings in ([(f"RK4 fixedStep {h * 1e3:g} ms", {"solver.method": 2, "solver.fixedStep": h})
                            for h in (1e-3, 5e-4, 2.5e-4, 1.25e-4)]
                           + [(f"adaptive relTol {tol:g}", {"solver.relTol": tol}) for tol in (1e-4, 1e-6, 1e-8, 1e-10)]):
        pressures, micros = run(settings)
        rows.append((name, float(np.max(np.abs(pressures - reference))), micros))
    lines = ["| method | largest pressure error (Pa) | doStep wall time (us per 1 ms step) |", "|---|---|---|"]
    lines += [f"| {n} | {short(e)} | {s:.1f} |" for n, e, s in rows]
    (OUT / "hydraulic_work_precision.md").write_text(
        "Pump failure with the valves fully open (pS = 0 from the start), 1 s at 1 ms communication steps; error of "
        "pA[1], pB[1] against the adaptive method at relTol 1e-12; wall time of the doStep calls alone, one run each "
        "on this machine (the ctypes call included).\n\n" + "\n".join(lines) + "\n")
    fig, ax = plt.subplots(figsize=(7, 4.6))
    for marker, prefix in (("o-", "RK4"), ("s-", "adaptive")):
        sel = [r for r in rows if r[0].startswith(prefix)]
        ax.loglog([r[2] for r in sel], [max(r[1], 1e-6) for r in sel], marker, label=prefix)
        for n, e, s in sel:
            ax.annotate(n.split(" ", 1)[1], (s, max(e, 1e-6)), fontsize=7)
    ax.set(title="Work-precision with hydraulics (stiff regime: pump failure, valves open)",
           xlabel="doStep wall time per 1 ms step, us (one run)", ylabel="largest pressure error, Pa")
    ax.legend()
    fig.tight_layout()
    fig.savefig(OUT / "hydraulic_work_precision.png", dpi=110)
    plt.close(fig)
    summary.append("work-precision (pump failure, valves fully open, 1 s at 1 ms, error of p_A[1], p_B[1] against "
                   "relTol 1e-12; doStep wall time): "
                   + "; ".join(f"{n}: {short(e)} Pa, {s:.1f} us" for n, e, s in rows))


def main():
    OUT.mkdir(parents=True, exist_ok=True)
    summary = [defaults_figures()]
    holding(summary)
    heave(summary)
    failures(summary)
    work_precision(summary)
    (OUT / "hydraulic_summary.txt").write_text("\n".join(summary) + "\n")
    print("\n".join(summary))
    print(f"wrote the hydraulic scenarios' CSV files and plots to {OUT.resolve()}")


if __name__ == "__main__":
    main()
