"""The main job's demonstration of motion cueing (docs/cueing.md): the truck's manoeuvres as
CSV in the units of SPEC §11, each through the cueing FMU (the vehicle's and the simulator's
specific force side by side); every manoeuvre with both methods, the classical washout and
predictive cueing, judged by what the driver perceives (SPEC §12's measures, the perceived
cues side by side, the workspace used); the braking replayed with its preview; the braking
and the slalom through the whole motion system (StewartMotionSystem.ssp: cueing -> controller
-> platform), the slalom with the predictive method; the harsh manoeuvres in the closed loop
with the default washout and with one that needs the workspace limiter; and the Objective
Motion Cueing Test of both methods as Bode diagrams. Writes manoeuvres/*.csv, cueing_*.csv,
cueing_manoeuvres.png, cueing_perceived.png, cueing_brake.png, cueing_predictive_system.png,
cueing_omct.png, cueing_omct.csv and cueing_summary.txt.

    python examples/cueing_scenarios.py [output-folder]   (default: output/)
"""

import math
import sys
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from stewart_fmu import cueing, vehicle
from stewart_fmu.core import LEGS

from csv_columns import write_columns

OUT = Path(sys.argv[1] if len(sys.argv) > 1 else "output")
#: A washout that would leave the workspace on the harsh manoeuvres (full scale, a slow
#: return, a larger and faster tilt): the limiter's case.
AGGRESSIVE = {**{f"scale.f[{k}]": 1.0 for k in (1, 2, 3)}, **{f"scale.omega[{k}]": 1.0 for k in (1, 2, 3)},
              **{f"hp.f.break[{k}]": 0.15 for k in (1, 2, 3)}, "hp.f.omega[1]": 1.2, "hp.f.omega[2]": 1.2,
              "hp.w.omega[3]": 0.3, "tilt.max": math.radians(20), "tilt.rateLimit": math.radians(10)}
LABELS = {1: "x (forward)", 2: "y (left)", 3: "z (up)"}
PREDICTIVE = {"cueing.method": 1}
#: The manoeuvres judged by perception (SPEC §12's measures), and the axis each is about.
JUDGED = {**{n: m for n, m in vehicle.MANOEUVRES.items()}, "emergency_stop": vehicle.HARSH["emergency_stop"],
          "pothole": vehicle.HARSH["pothole"]}
MAIN_AXIS = {"accelerate": 1, "brake": 1, "emergency_stop": 1, "lane_change": 2, "curve": 2, "slalom": 2,
             "bumps": 3, "pothole": 3}


def cue_error(run):
    """Root mean square of |f - fsim| over the run, m/s2: the cue the driver misses."""
    return float(np.sqrt(np.mean(sum((run[f"fsim[{k}]"] - run[f"f[{k}]"]) ** 2 for k in (1, 2, 3)))))


def manoeuvres(lines):
    """Writes every manoeuvre as CSV, runs each default one through the cueing FMU alone and
    plots the vehicle's against the simulator's specific force."""
    folder = OUT / "manoeuvres"
    folder.mkdir(parents=True, exist_ok=True)
    made = {name: make() for name, make in {**vehicle.MANOEUVRES, **vehicle.HARSH}.items()}
    for name, m in made.items():
        vehicle.write_csv(m, folder / f"{name}.csv")
    lines.append(f"manoeuvres: {len(made)} files in {folder}/ (time s, f[1..3] m/s2, omega[1..3] rad/s)")
    fig, axes = plt.subplots(len(vehicle.MANOEUVRES), 2, figsize=(11, 11), sharex="row")
    for i, name in enumerate(vehicle.MANOEUVRES):
        run = cueing.run(vehicle.read_csv(folder / f"{name}.csv"), h=0.01)
        for j, (inp, out, unit, axes_) in enumerate(((cueing.F, cueing.FSIM, "m/s2", (1, 2, 3)),
                                                     (cueing.OMEGA, cueing.OMEGASIM, "rad/s", (1, 2, 3)))):
            ax = axes[i, j]
            for k in axes_:
                rest = vehicle.G if (j == 0 and k == 3) else 0.0
                vehicle_line, = ax.plot(run["time"], run[inp[k - 1]] - rest, lw=1.2, label=f"vehicle {LABELS[k]}")
                ax.plot(run["time"], run[out[k - 1]] - rest, "--", lw=1.0, color=vehicle_line.get_color(),
                        label=f"simulator {LABELS[k]}")
            ax.set_ylabel(f"{name}\n{'f - g ez' if j == 0 else 'omega'} ({unit})", fontsize=8)
            ax.grid(lw=0.3)
        lines.append(f"  {name:12s}: rms |f - fsim| {cue_error(run):.3f} m/s2, largest |f - g ez| "
                     f"{max(np.max(np.abs(run[f'f[{k}]'] - (vehicle.G if k == 3 else 0))) for k in (1, 2, 3)):.2f} m/s2, "
                     f"workspace usage up to {np.max(run['workspace.usage']):.3f}")
    axes[0, 0].legend(fontsize=6, ncol=2)
    axes[0, 1].legend(fontsize=6, ncol=2)
    axes[-1, 0].set_xlabel("time (s)")
    axes[-1, 1].set_xlabel("time (s)")
    fig.suptitle("The truck's manoeuvres through StewartCueing (default washout): vehicle solid, simulator dashed",
                 fontsize=10)
    fig.tight_layout()
    fig.savefig(OUT / "cueing_manoeuvres.png", dpi=100)
    plt.close(fig)


def braking_through_the_system(lines):
    """The braking through StewartMotionSystem.ssp (FMPy driving the three FMUs at 1 ms)."""
    started = time.perf_counter()
    run = cueing.motion_system(vehicle.read_csv(OUT / "manoeuvres" / "brake.csv"))
    seconds = time.perf_counter() - started
    write_columns(OUT / "cueing_brake.csv", run)
    legs = np.array([run[f"l[{k}]"] for k in LEGS])
    error = np.max(np.abs(legs - np.array([run[f"lp[{k}]"] for k in LEGS])))
    lines.append(f"braking through StewartMotionSystem.ssp (cueing -> controller -> platform, FMPy, 1 ms, "
                 f"{run['time'][-1]:.0f} s in {seconds:.1f} s): largest leg error {error * 1e3:.2f} mm, legs "
                 f"{legs.min():.4f}..{legs.max():.4f} m, pitch up to {math.degrees(run['angles[2]'].max()):.2f} deg, "
                 f"rms |f - fsim| {cue_error(run):.3f} m/s2")
    fig, axes = plt.subplots(3, 1, figsize=(8, 8), sharex=True)
    t = run["time"]
    axes[0].plot(t, run["f[1]"], label="vehicle f_x")
    axes[0].plot(t, run["fsim[1]"], "--", label="simulator f_x (commanded)")
    axes[0].set_ylabel("specific force x (m/s2)")
    axes[0].legend(fontsize=8)
    axes[1].plot(t, np.degrees(run["pose.angles[2]"]), label="commanded pitch")
    axes[1].plot(t, np.degrees(run["angles[2]"]), "--", label="platform pitch")
    axes[1].plot(t, 1e3 * (run["pose.r[1]"] - run["pose.r[1]"][0]) / 10, label="commanded x (cm)")
    axes[1].set_ylabel("deg, cm")
    axes[1].legend(fontsize=8)
    for k in LEGS:
        axes[2].plot(t, run[f"l[{k}]"], lw=0.9, label=f"leg {k}")
    axes[2].set_ylabel("leg length (m)")
    axes[2].set_xlabel("time (s)")
    axes[2].legend(fontsize=7, ncol=3)
    for ax in axes:
        ax.grid(lw=0.3)
    fig.suptitle("Braking 3 m/s2 from 15 m/s through the motion system: tilt coordination and washout", fontsize=10)
    fig.tight_layout()
    fig.savefig(OUT / "cueing_brake.png", dpi=100)
    plt.close(fig)


def harsh(lines):
    """The harsh manoeuvres in the closed loop: legs inside the strokes, what the limiter cut."""
    rows = {"manoeuvre": [], "washout": [], "shortest leg m": [], "longest leg m": [], "least scale": [],
            "rms |f - fsim| m/s2": []}
    lines.append("harsh manoeuvres in the closed loop (lmin 1.45 m, lmax 2.15 m, margin 0.03 m):")
    for name, make in vehicle.HARSH.items():
        for label, params in (("default", None), ("aggressive", AGGRESSIVE)):
            run = cueing.motion_system(make(), cueing=params)
            legs = np.array([run[f"l[{k}]"] for k in LEGS])
            for key, value in zip(rows, (name, label, legs.min(), legs.max(), run["workspace.scale"].min(),
                                         cue_error(run))):
                rows[key].append(value)
            lines.append(f"  {name:16s} {label:10s}: legs {legs.min():.4f}..{legs.max():.4f} m, least scale "
                         f"{run['workspace.scale'].min():.3f}, rms |f - fsim| {cue_error(run):.3f} m/s2")
    write_columns(OUT / "cueing_harsh.csv", rows)


def perceived(lines):
    """Every judged manoeuvre through the cueing FMU alone at 1 ms with both methods: SPEC §12's
    measures in a table, the perceived specific force of the manoeuvre's axis (vehicle,
    classical, predictive) and the workspace usage over time side by side."""
    rows = {"manoeuvre": [], "method": [], "perceived error x,y m/s2": [], "rms z m/s2": [], "correlation": [],
            "false cues": [], "max usage": [], "fallbacks": [], "solves": []}
    fig, axes = plt.subplots(len(JUDGED), 2, figsize=(11, 2.0 * len(JUDGED)), sharex="row",
                             gridspec_kw={"width_ratios": [2.2, 1]})
    lines.append("perception (SPEC 12) over every manoeuvre, cueing FMU alone, 1 ms: perceived error x,y (rms, m/s2), "
                 "mean correlation, false cues (share of the time), largest workspace usage")
    started = time.perf_counter()
    improvements = {}
    for i, (name, make) in enumerate(JUDGED.items()):
        m = make()
        runs = {"classical": cueing.run(m), "predictive": cueing.run(m, integers=PREDICTIVE,
                                                                     record=cueing.RECORDED + ["mpc.fallbacks"])}
        k = MAIN_AXIS[name]
        rest = vehicle.G if k == 3 else 0.0
        ax = axes[i, 0]
        t = runs["classical"]["time"]
        ax.plot(t, runs["classical"][f"perceived.f[{k}]"] - rest, color="k", lw=1.4, label="vehicle")
        measures = {}
        for method, run in runs.items():
            measures[method] = cueing.measures(run)
            ax.plot(t, run[f"perceived.fsim[{k}]"] - rest, lw=1.0, label=method)
            axes[i, 1].plot(t, run["workspace.usage"], lw=1.0, label=method)
            fallbacks = int(run["mpc.fallbacks"][-1]) if "mpc.fallbacks" in run else 0
            for key, value in zip(rows, (name, method, measures[method]["perceived_error"], measures[method]["rms_z"],
                                         measures[method]["correlation"], measures[method]["false_cues"],
                                         measures[method]["max_usage"], fallbacks,
                                         int(round(t[-1] / 0.01)) if method == "predictive" else 0)):
                rows[key].append(value)
        ax.set_ylabel(f"{name}\nperceived f {'xyz'[k - 1]} (m/s2)", fontsize=8)
        axes[i, 1].set_ylabel("workspace usage", fontsize=8)
        for a in axes[i]:
            a.grid(lw=0.3)
        c, p = measures["classical"], measures["predictive"]
        gain = 1 - p["perceived_error"] / c["perceived_error"] if c["perceived_error"] > 1e-9 else float("nan")
        improvements[name] = gain
        lines.append(f"  {name:15s} classical {c['perceived_error']:.3f} m/s2 (z {c['rms_z']:.3f}), correlation "
                     f"{c['correlation']:.2f}, false cues {c['false_cues']:.3f}, usage {c['max_usage']:.2f} | predictive "
                     f"{p['perceived_error']:.3f} m/s2 (z {p['rms_z']:.3f}), correlation {p['correlation']:.2f}, false "
                     f"cues {p['false_cues']:.3f}, usage {p['max_usage']:.2f}, fallbacks {rows['fallbacks'][-1]} | "
                     f"{'lower by ' + format(100 * gain, '.0f') + ' %' if gain == gain else 'no horizontal cue'}")
    mean = {method: float(np.nanmean([c for c, mm in zip(rows["correlation"], rows["method"]) if mm == method]))
            for method in ("classical", "predictive")}
    lines.append(f"  mean correlation over the manoeuvres: classical {mean['classical']:.2f}, predictive "
                 f"{mean['predictive']:.2f} ({time.perf_counter() - started:.0f} s)")
    write_columns(OUT / "cueing_measures.csv", rows)
    axes[0, 0].legend(fontsize=7, ncol=3)
    axes[0, 1].legend(fontsize=7)
    axes[-1, 0].set_xlabel("time (s)")
    axes[-1, 1].set_xlabel("time (s)")
    fig.suptitle("What the driver perceives (SPEC 12): the vehicle, the classical washout and predictive cueing; "
                 "right, the workspace used (1: a leg at its margin)", fontsize=9)
    fig.tight_layout()
    fig.savefig(OUT / "cueing_perceived.png", dpi=100)
    plt.close(fig)


def preview_replay(lines):
    """The braking replayed with its preview (preview.file: the recorded drive) against held
    inputs, the predictive method, and against the classical washout."""
    path = (OUT / "manoeuvres" / "brake.csv").resolve()
    m = vehicle.read_csv(path)
    classical = cueing.measures(cueing.run(m))
    held = cueing.measures(cueing.run(m, integers=PREDICTIVE))
    previewed = cueing.measures(cueing.run(m, integers=PREDICTIVE, strings={"preview.file": str(path)}))
    lower = 100.0 * (1.0 - previewed["perceived_error"] / classical["perceived_error"])
    lines.append(f"braking replayed with its preview (preview.file, predictive): perceived error x,y "
                 f"{previewed['perceived_error']:.3f} m/s2 ({lower:.0f} % below the classical washout's "
                 f"{classical['perceived_error']:.3f}) against {held['perceived_error']:.3f} with the inputs held, "
                 f"correlation {previewed['correlation']:.2f} against {held['correlation']:.2f} and "
                 f"{classical['correlation']:.2f}")


def predictive_motion_system(lines):
    """The slalom through StewartMotionSystem.ssp with predictive cueing: the legs within
    their strokes, the platform following."""
    started = time.perf_counter()
    run = cueing.motion_system(vehicle.slalom(), cueing=PREDICTIVE)
    seconds = time.perf_counter() - started
    write_columns(OUT / "cueing_predictive_system.csv", run)
    legs = np.array([run[f"l[{k}]"] for k in LEGS])
    error = np.max(np.abs(legs - np.array([run[f"lp[{k}]"] for k in LEGS])))
    lines.append(f"slalom through StewartMotionSystem.ssp with predictive cueing (FMPy, 1 ms, {run['time'][-1]:.0f} s in "
                 f"{seconds:.1f} s): legs {legs.min():.4f}..{legs.max():.4f} m (strokes 1.45..2.15 m, margins 0.03 m), "
                 f"largest leg error {error * 1e3:.2f} mm")
    fig, axes = plt.subplots(3, 1, figsize=(8, 8), sharex=True)
    t = run["time"]
    axes[0].plot(t, run["f[2]"], label="vehicle f_y")
    axes[0].plot(t, run["fsim[2]"], "--", label="simulator f_y (commanded)")
    axes[0].set_ylabel("specific force y (m/s2)")
    axes[0].legend(fontsize=8)
    axes[1].plot(t, np.degrees(run["pose.angles[1]"]), label="commanded roll")
    axes[1].plot(t, np.degrees(run["angles[1]"]), "--", label="platform roll")
    axes[1].plot(t, 100 * (run["pose.r[2]"] - run["pose.r[2]"][0]), label="commanded y (cm)")
    axes[1].set_ylabel("deg, cm")
    axes[1].legend(fontsize=8)
    for k in LEGS:
        axes[2].plot(t, run[f"l[{k}]"], lw=0.9, label=f"leg {k}")
    for bound in (1.45, 1.48, 2.12, 2.15):
        axes[2].axhline(bound, color="grey", lw=0.6, ls=":" if bound in (1.48, 2.12) else "-")
    axes[2].set_ylabel("leg length (m)")
    axes[2].set_xlabel("time (s)")
    axes[2].legend(fontsize=7, ncol=3)
    for ax in axes:
        ax.grid(lw=0.3)
    fig.suptitle("0.4 Hz slalom of 2.5 m/s2 through the motion system, predictive cueing (dotted: the margins)",
                 fontsize=10)
    fig.tight_layout()
    fig.savefig(OUT / "cueing_predictive_system.png", dpi=100)
    plt.close(fig)


def objective_motion_cueing_test(lines):
    started = time.perf_counter()
    result = cueing.omct()
    seconds = time.perf_counter() - started
    started = time.perf_counter()
    predictive = cueing.omct(integers=PREDICTIVE)
    predictive_seconds = time.perf_counter() - started
    reference = cueing.filter_responses()
    cueing.bode_plot(result, OUT / "cueing_omct.png", reference=reference, label="classical",
                     others={"predictive": predictive}, fidelity=True,
                     title="Objective Motion Cueing Test: StewartCueing, both methods, default parameters")
    columns = {"frequency rad/s": result["surge"]["frequency"]}
    worst = 0.0
    for test, r in result.items():
        columns[f"{test} gain"] = r["gain"]
        columns[f"{test} phase deg"] = r["phase"]
        columns[f"{test} predictive gain"] = predictive[test]["gain"]
        columns[f"{test} predictive phase deg"] = predictive[test]["phase"]
        worst = max(worst, float(np.max(np.abs(r["gain"] / reference[test]["gain"] - 1))))
    write_columns(OUT / "cueing_omct.csv", columns)
    at1 = {test: (float(np.interp(0.0, np.log10(r["frequency"]), r["gain"])),
                  float(np.interp(0.0, np.log10(r["frequency"]), r["phase"]))) for test, r in result.items()}
    lines.append(f"OMCT of the defaults ({len(result)} tests x 12 frequencies in {seconds:.0f} s): largest gain "
                 f"difference from the filters' transfer functions {worst:.1e}; at 1 rad/s: " +
                 ", ".join(f"{t} {g:.3f} / {p:.0f} deg" for t, (g, p) in at1.items()))
    at1 = {test: (float(np.interp(0.0, np.log10(r["frequency"]), r["gain"])),
                  float(np.interp(0.0, np.log10(r["frequency"]), r["phase"]))) for test, r in predictive.items()}
    lines.append(f"OMCT of predictive cueing ({predictive_seconds:.0f} s): at 1 rad/s " +
                 ", ".join(f"{t} {g:.3f} / {p:.0f} deg" for t, (g, p) in at1.items()))


def main():
    OUT.mkdir(parents=True, exist_ok=True)
    lines = []
    manoeuvres(lines)
    perceived(lines)
    preview_replay(lines)
    braking_through_the_system(lines)
    predictive_motion_system(lines)
    harsh(lines)
    objective_motion_cueing_test(lines)
    text = "\n".join(lines) + "\n"
    (OUT / "cueing_summary.txt").write_text(text)
    print(text, end="")


if __name__ == "__main__":
    main()
