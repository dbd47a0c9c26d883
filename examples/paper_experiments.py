"""The main job's demonstration: the paper's experiments (Zegzhda, Petrova, Yushkov 2020,
sections 5-7; docs/model.md §6) run through the packaged StewartPlatform FMU with FMPy, in the paper's
non-dimensional units. Writes one CSV per experiment and PNG plots to the output folder.

    python examples/paper_experiments.py [output-folder]   (default: output/)
"""

import csv
import math
import re
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from fmpy import simulate_fmu
from fmpy.fmi1 import FMICallException

from stewart_fmu.cosim import closed_loop
from stewart_fmu import EQUILIBRIUM_FORCE, PLATFORM_FMU, Platform, recording_callbacks, stand_parameters

# The paper's heave programme and its direct problem, written out independently of the FMU's
# code: the tests' oracle (tests/python/oracles/heave.py).
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "python"))
from oracles.heave import heave_forces, heave_programme  # noqa: E402

OUT = Path(sys.argv[1] if len(sys.argv) > 1 else "output")
P = stand_parameters(nondimensional=True)
Z0 = P["r0[3]"]


def write_csv(name, header, rows):
    with open(OUT / name, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(header)
        w.writerows(rows)


def run_forces(force_of_t, t_end, h, derivative_of_t=None):
    """Open loop: forces as a function of time; returns rows (t, heave, roll, pitch) and, if
    the platform left the workspace and the FMU discarded a step, why (else None)."""
    messages = []
    pl = Platform(parameters=P, logger=recording_callbacks(messages))
    rows = [(0.0, 0.0, 0.0, 0.0)]
    stopped = None
    try:
        while pl.time < t_end - 1e-9:
            t = pl.time
            pl.set_forces(force_of_t(t), derivative_of_t(t) if derivative_of_t else None)
            pl.step(min(h, t_end - t))
            a = pl.vector("angles", 3)
            rows.append((pl.time, pl.get("r[3]")[0] - Z0, a[0], a[1]))
    except FMICallException:
        # The platform tumbled: the FMU discarded the step. Its message quotes the leg forces
        # with the FMU's unit N; in this run they are in units of M g.
        found = re.search(r"at t = ([-+0-9.eE]+): (.*?base plane)", messages[-1][2] if messages else "")
        stopped = (f"discarded at t = {float(found.group(1)):.2f}: {found.group(2)}" if found
                   else "discarded: " + (messages[-1][2][:100] if messages else "no message"))
    pl.free()
    return np.array(rows), stopped


def controller_parameters(gain, damping, disturbance=1e-4):
    """StewartController in the paper's units: heave 0.2 sin t (1 - exp(-t/2))^2, the paper's
    perturbation 0.0001 sin 2t (1 - exp(-t/2)) added to every leg."""
    c = {k: v for k, v in P.items() if not k.startswith("r0") and k not in ("stops", "joints")}  # the controller has none of these
    c.update({"G": gain, "D": damping, "heave.centre[3]": Z0, "heave.amplitude": 0.2, "heave.frequency": 1.0,
              "heave.timeConstant": 2.0, "disturbance.amplitude": disturbance, "disturbance.frequency": 2.0,
              "disturbance.timeConstant": 2.0})
    return c


def run_feedback(gain, damping, feedforward=1, h=0.002):
    """The StewartController FMU driving the StewartPlatform FMU (Gauss-Seidel master)."""
    t, rows, errors, status = closed_loop(40.0, h, platform_reals=P, controller_reals=controller_parameters(gain, damping),
                                          controller_integers={"feedforward": feedforward})
    return np.column_stack([t, rows[:, 0] - Z0, errors]) if len(t) else np.zeros((0, 3))


def main():
    OUT.mkdir(parents=True, exist_ok=True)
    summary = []

    # 0. The default SI experiment through simulate_fmu.
    result = simulate_fmu(str(PLATFORM_FMU), output=["r[3]", "angles[1]", "l[1]", "E", "constraintError"])
    write_csv("default_si.csv", result.dtype.names, result.tolist())
    summary.append(f"default SI run, 3 s: max |z - z0| = {np.max(np.abs(result['r[3]'] - result['r[3]'][0])):.1e} m, "
                   f"max constraint error {np.max(result['constraintError']):.1e}")

    # 1. Equilibrium.
    eq, _ = run_forces(lambda t: [EQUILIBRIUM_FORCE] * 6, 25.0, 0.01)
    write_csv("experiment1_equilibrium.csv", ["t", "heave", "roll", "pitch"], eq.tolist())
    dev = np.abs(eq[:, 1]) + np.abs(eq[:, 2]) + np.abs(eq[:, 3])
    summary.append(f"1 equilibrium: pose held to 1e-9 until t = {eq[np.argmax(dev > 1e-9), 0]:.2f}")

    # 2. Parasitic oscillations (paper Fig. 2).
    par, _ = run_forces(lambda t: [EQUILIBRIUM_FORCE + 1e-4 * math.sin(t)] * 6, 8 * math.pi, 0.01,
                     lambda t: [1e-4 * math.cos(t)] * 6)
    write_csv("experiment2_parasitic.csv", ["t", "heave", "roll", "pitch"], par.tolist())
    summary.append(f"2 parasitic oscillations: heave passes 0.01 at t = {par[np.argmax(par[:, 1] > 0.01), 0]:.2f}, "
                   f"0.1 at t = {par[np.argmax(par[:, 1] > 0.1), 0]:.2f}")

    # 3. Heave programme: forces from the direct problem, reproduced by the FMU.
    t_prog = np.arange(0.0, 40.0 + 1e-9, 0.01)
    forces = np.array([heave_forces(t)[0] for t in t_prog])
    heave, heave_stopped = run_forces(lambda t: [heave_forces(t)[0]] * 6, 30.0, 0.001, lambda t: [heave_forces(t)[1]] * 6)
    eta = np.array([heave_programme(t, Z0)[0] - Z0 for t in heave[:, 0]])
    write_csv("experiment3_heave.csv", ["t", "heave_fmu", "heave_programme"], np.column_stack([heave[:, 0], heave[:, 1], eta]).tolist())
    write_csv("experiment3_forces.csv", ["t", "u"], np.column_stack([t_prog, forces]).tolist())
    err8 = np.max(np.abs(heave[heave[:, 0] <= 8, 1] - eta[heave[:, 0] <= 8]))
    summary.append(f"3 heave programme: forces in [{forces.min():.4f}, {forces.max():.4f}], "
                   f"max |eta_FMU - eta| for t <= 8 at step 0.001: {err8:.1e}; open loop, the platform then leaves the programme"
                   + (f" ({heave_stopped})" if heave_stopped else f" (ran to t = {heave[-1, 0]:.2f})"))

    # 4. Perturbed programme (paper Fig. 5).
    def perturbed(t):
        return [heave_forces(t)[0] + 1e-4 * math.sin(2 * t) * (1 - math.exp(-t / 2))] * 6

    def perturbed_rate(t):
        e = math.exp(-t / 2)
        return [heave_forces(t)[1] + 1e-4 * (2 * math.cos(2 * t) * (1 - e) + 0.5 * math.sin(2 * t) * e)] * 6

    pert, _ = run_forces(perturbed, 20.0, 0.005, perturbed_rate)
    eta_p = np.array([heave_programme(t, Z0)[0] - Z0 for t in pert[:, 0]])
    write_csv("experiment4_perturbed.csv", ["t", "heave_fmu", "heave_programme"], np.column_stack([pert[:, 0], pert[:, 1], eta_p]).tolist())
    d4 = pert[:, 1] - eta_p
    summary.append(f"4 perturbed programme: deviation passes 0.01 at t = {pert[np.argmax(d4 > 0.01), 0]:.2f}, "
                   f"min deviation {d4.min():.1e} (never below the programme)")

    # 5. Feedback (paper section 7): the StewartController FMU coupled to the platform FMU,
    # with the paper's perturbation.
    runs = {
        "no feedback": run_feedback(0.0, 0.0),
        "G = 2": run_feedback(2.0, 0.0),
        "G = 2, D = 0.7": run_feedback(2.0, 0.7),
        "G = 1000, D = 16, F^p = 0": run_feedback(1000.0, 16.0, feedforward=0),
    }
    for name, rows in runs.items():
        slug = name.replace(" ", "").replace(",", "_").replace("=", "").replace("^", "")
        write_csv(f"experiment5_{slug}.csv", ["t", "heave", "max_leg_error"], rows.tolist())
        summary.append(f"5 feedback, {name}: ran to t = {rows[-1, 0]:.1f}, max leg-length error {rows[:, 2].max():.2e}")

    # Plots, in the paper's non-dimensional units. Curves that should lie on the programme
    # are drawn over it (the programme wide and pale beneath), each in its own dash.
    T_LABEL = "t (non-dimensional, units of sqrt(R_b/g))"
    Z_LABEL = "heave (z - z0) / R_b"
    programme_style = dict(color="0.6", lw=5, alpha=0.45, zorder=1, label="programme")
    styles = ["-", "--", "-.", ":"]
    fig, ax = plt.subplots(2, 2, figsize=(12, 8))
    ax[0, 0].plot(par[:, 0], par[:, 1])
    ax[0, 0].set(title="Parasitic oscillations, u = 0.2005 + 0.0001 sin t (Fig. 2)", xlabel=T_LABEL, ylabel=Z_LABEL)
    ax[0, 0].set_ylim(-0.05, 1.0)
    ax[0, 1].plot(t_prog, forces)
    ax[0, 1].set(title="Programme leg force, direct problem (paper Fig. 4)", xlabel=T_LABEL,
                 ylabel="leg force u / (M g) (non-dimensional)")
    ax[1, 0].plot(heave[:, 0], eta, **programme_style)
    ax[1, 0].plot(heave[:, 0], heave[:, 1], "C0", ls="--", zorder=3, label="FMU, programme forces")
    ax[1, 0].plot(pert[:, 0], pert[:, 1], "C1", zorder=2, label="FMU, perturbed forces (Fig. 5)")
    if heave_stopped:
        ax[1, 0].plot(heave[-1, 0], max(heave[-1, 1], -0.39), "C0x", ms=9, mew=2, zorder=4,
                      label=f"FMU, programme forces: {heave_stopped.split(':')[0]}")
    ax[1, 0].set(title="Vertical oscillation: direct problem forces applied", xlabel=T_LABEL, ylabel=Z_LABEL,
                 ylim=(-0.4, 1.0))
    ax[1, 0].legend(fontsize=8)
    ax[1, 1].plot(t_prog, [heave_programme(t, Z0)[0] - Z0 for t in t_prog], **programme_style)
    for j, (name, rows) in enumerate(runs.items()):
        ax[1, 1].plot(rows[:, 0], rows[:, 1], f"C{j}", ls=styles[j % len(styles)], lw=1.4, zorder=2 + j, label=name)
    ax[1, 1].set(title="Controller FMU driving the platform FMU (perturbed)", xlabel=T_LABEL, ylabel=Z_LABEL,
                 ylim=(-0.4, 1.0))
    ax[1, 1].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(OUT / "paper_experiments.png", dpi=120)

    fig, ax = plt.subplots(figsize=(7, 4))
    for j, (name, rows) in enumerate(runs.items()):
        ax.semilogy(rows[:, 0], np.maximum(rows[:, 2], 1e-12), f"C{j}", ls=styles[j % len(styles)], label=name)
    ax.set(title="Leg-length tracking error, controller FMU + platform FMU", xlabel=T_LABEL,
           ylabel="max_k |l_k - l_k^p| / R_b")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(OUT / "feedback_tracking_error.png", dpi=120)

    (OUT / "summary.txt").write_text("\n".join(summary) + "\n")
    print("\n".join(summary))
    print(f"wrote CSV files and plots to {OUT.resolve()}")


if __name__ == "__main__":
    main()
