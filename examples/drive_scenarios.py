"""The main job's demonstration of the electric drives (docs/model.md §9): holding, a power
loss with dynamic braking against the quasi-static descent and against ideal force actuators,
the heave programme with the controller in voltage mode, and a drive that loses its voltage
under feedback; through the packaged FMUs, SI units, default stand and drives. Writes
drive1_power_loss.csv, drive2_heave.csv, drive3_failure.csv, drive_power_loss.png,
drive_heave.png, drive_failure.png and drive_summary.txt.

    python examples/drive_scenarios.py [output-folder]   (default: output/)
"""

import math
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from stewart_fmu import drives as dr
from stewart_fmu import workspace as ws

from csv_columns import write_columns

# What the runs are compared with: §9's static model, braking and descent written out
# independently of the FMU's code, the tests' oracles (tests/python/oracles/).
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "python"))
from oracles import drives as oracle  # noqa: E402

OUT = Path(sys.argv[1] if len(sys.argv) > 1 else "output")
LEGS = list(dr.LEGS)
P = dr.drive_parameters()
I_HOLD, U_HOLD = oracle.holding(P)
PERIOD = 2 * math.pi / 2.5573423705088842  # the default heave programme's


def write_csv(name, columns):
    write_columns(OUT / name, columns)


def balance(c):
    """E(t) - E(0) - (work.F + work.electric - work.dissipated), J."""
    return c["E"] - c["E"][0] - (c["work.F"] + c["work.electric"] - c["work.dissipated"])


def parameters_line():
    n = oracle.transmission(P)
    return (f"drives (defaults): R = {P['motor.R']} Ohm, L = {P['motor.L'] * 1e3} mH (L/R = "
            f"{P['motor.L'] / P['motor.R'] * 1e3:.1f} ms), k_e = {P['motor.ke']} V.s/rad, k_t = {P['motor.kt']} N.m/A, "
            f"J_m = {P['motor.J']} kg.m2, D = {P['motor.D']} N.m.s/rad, i = {P['gear.ratio']}, p = "
            f"{P['screw.lead'] * 1e3} mm: N = {n:.2f} rad/m, rotor reflected along each leg {P['motor.J'] * n * n:.1f} "
            f"kg; holding the default stand: {I_HOLD:.3f} A and {U_HOLD:.3f} V per leg "
            f"({6 * U_HOLD * I_HOLD:.0f} W in all); braking damping with the windings shorted "
            f"{oracle.braking_damping(P):.4g} N.s/m per leg")


def power_loss(summary):
    print("1 power loss with dynamic braking ...")
    c, messages, status = dr.power_loss((I_HOLD, U_HOLD), t_loss=0.5, t_end=16.0, h=0.01)
    falling, _, _ = dr.power_loss_forces(t_loss=0.5, t_end=1.5, h=1e-3)
    assert status == "ok", status
    t, z, vz = c["time"], c["r[3]"], c["v[3]"]
    quasi = np.array([oracle.quasi_static_descent_rate(zi, P) for zi in z])
    landing = next(float(m.split()[2].rstrip(":")) for _, _, m in messages if "reached its lower end stop" in m)
    steady = (t > 1.0) & (t < landing - 0.2)
    write_csv("drive1_power_loss.csv", {"t": t, "z": z, "vz": vz, "vz_quasi_static": quasi, "az": c["der(v[3])"],
                                         **{f"I[{k}]": c[f"I[{k}]"] for k in LEGS},
                                         **{f"Fstop[{k}]": c[f"Fstop[{k}]"] for k in LEGS},
                                         "E": c["E"], "work.electric": c["work.electric"],
                                         "work.dissipated": c["work.dissipated"]})
    summary.append(
        f"1 power loss at t = 0.5 s (U = 0, windings shorted): the platform descends at {-vz[steady][0] * 1e3:.2f} .. "
        f"{-vz[steady][-1] * 1e3:.2f} mm/s, within {np.max(np.abs(vz[steady] / quasi[steady] - 1)):.1e} of the "
        f"quasi-static descent rate M g / (6 c n_z^2) computed from the stand's geometry; it reaches its lower stops "
        f"at t = {landing:.3f} s and rests at z = {z[-1]:.9f} m; peak deceleration {np.max(c['der(v[3])']):.2f} m/s2 "
        f"against {np.max(falling['der(v[3])']):.1f} m/s2 with ideal force actuators (forces to 0: the platform "
        f"falls); energy balance residual {np.max(np.abs(balance(c))):.1e} J of {c['work.dissipated'][-1]:.0f} J "
        f"dissipated")
    fig, ax = plt.subplots(1, 3, figsize=(16, 4.2))
    ax[0].plot(t, z, label="electric drives, shorted: braked descent")
    ax[0].plot(falling["time"], falling["r[3]"], "--", label="ideal force actuators, forces to 0: fall")
    ax[0].axvline(landing, color="k", lw=0.6, ls=":", label=f"on the stops, t = {landing:.2f} s")
    ax[0].set(title="Power loss at t = 0.5 s: heave", xlabel="t, s", ylabel="centre of mass z, m")
    ax[0].legend(fontsize=8)
    ax[1].plot(t, -vz * 1e3, label="simulated")
    ax[1].plot(t[steady], -quasi[steady] * 1e3, "k:", label="quasi-static: braking force holds the weight")
    ax[1].set(title="Descent rate -z'", xlabel="t, s", ylabel="mm/s", ylim=(0, 45))
    ax[1].legend(fontsize=8)
    for k in LEGS:
        ax[2].plot(t, c[f"I[{k}]"], lw=0.9, label=f"I[{k}]")
    ax[2].set(title="Armature currents (back EMF drives them after the loss)", xlabel="t, s", ylabel="A")
    ax[2].legend(fontsize=7, ncol=2)
    fig.tight_layout()
    fig.savefig(OUT / "drive_power_loss.png", dpi=110)
    plt.close(fig)


def heave(summary):
    print("2 heave programme with voltage commands ...")
    c, errors, status = dr.heave_closed_loop(I_HOLD, 10.0, record=[f"U[{k}]" for k in LEGS])
    assert status == "ok", status
    t = c["time"]
    i0 = int(np.searchsorted(t, t[-1] - PERIOD))
    supplied = c["work.electric"][-1] - c["work.electric"][i0]
    lost = c["work.dissipated"][-1] - c["work.dissipated"][i0]
    power = sum(c[f"U[{k}]"] * c[f"I[{k}]"] for k in LEGS)
    write_csv("drive2_heave.csv", {"t": t, "z": c["r[3]"], "leg_error": errors,
                                    **{f"U[{k}]": c[f"U[{k}]"] for k in LEGS}, **{f"I[{k}]": c[f"I[{k}]"] for k in LEGS},
                                    "electric_power": power, "work.electric": c["work.electric"]})
    voltages = np.concatenate([c[f"U[{k}]"] for k in LEGS])
    currents = np.concatenate([c[f"I[{k}]"] for k in LEGS])
    summary.append(
        f"2 heave programme, the default controller in voltage mode (drive = 1 in both FMUs), 10 s at 1 ms: largest "
        f"leg error {np.max(errors) * 1e3:.4f} mm; voltages {voltages.min():.1f} .. {voltages.max():.1f} V, currents "
        f"{currents.min():.2f} .. {currents.max():.2f} A; electric power {power.min():.0f} .. {power.max():.0f} W (the "
        f"drives regenerate while the platform descends); per heave period ({PERIOD:.3f} s) {supplied:.0f} J supplied "
        f"and {lost:.0f} J lost")
    fig, ax = plt.subplots(1, 3, figsize=(16, 4.2))
    ax[0].plot(t, errors * 1e3)
    ax[0].set(title="Largest leg error max |l - l^p|", xlabel="t, s", ylabel="mm")
    for k in LEGS:
        ax[1].plot(t, c[f"U[{k}]"], lw=0.9, label=f"U[{k}]")
    ax[1].set(title="Voltage commands (Umax = 300 V)", xlabel="t, s", ylabel="V")
    ax[1].legend(fontsize=7, ncol=2)
    twin = ax[1].twinx()
    twin.plot(t, c["I[1]"], "k:", lw=0.9, label="I[1]")
    twin.set_ylabel("A")
    twin.legend(fontsize=7, loc="lower right")
    ax[2].plot(t, power / 1e3)
    ax[2].set(title="Electric power sum U_k I_k (negative: regeneration)", xlabel="t, s", ylabel="kW")
    fig.tight_layout()
    fig.savefig(OUT / "drive_heave.png", dpi=110)
    plt.close(fig)


def failure(summary):
    print("3 a drive loses its voltage under feedback ...")
    c, errors, status = dr.failure(I_HOLD, t_fail=1.0, t_end=6.0)
    forces = ws.actuator_failure(t_fail=1.0, t_end=6.0)
    assert status == "ok", status
    write_csv("drive3_failure.csv", {"t": c["time"], "l[1]": c["l[1]"], "I[1]": c["I[1]"], "roll": c["angles[1]"],
                                      "pitch": c["angles[2]"], "Fstop[1]": c["Fstop[1]"]})
    stop = next((t for t, k, what, _ in forces["events"] if k == 1 and what == "reached"), float("nan"))
    summary.append(
        f"3 leg 1's drive loses its voltage at t = 1 s under feedback (U = 0: shorted): its winding brakes the leg "
        f"(current {c['I[1]'][-1]:.1f} A from the back EMF), which stays off its stop (shortest {np.min(c['l[1]']):.3f} "
        f"m), largest tilt {math.degrees(max(np.max(np.abs(c['angles[1]'])), np.max(np.abs(c['angles[2]'])))):.2f} "
        f"deg; with an ideal force actuator losing its force the leg reaches its lower stop at t = {stop:.3f} s and the "
        f"platform tilts {math.degrees(max(np.max(np.abs(forces['angles[1]'])), np.max(np.abs(forces['angles[2]'])))):.1f}"
        f" deg")
    fig, ax = plt.subplots(1, 2, figsize=(12, 4.2))
    ax[0].plot(c["time"], c["l[1]"], label="electric drive, shorted")
    ax[0].plot(forces["time"], forces["l[1]"], "--", label="ideal force actuator, force 0")
    ax[0].axhline(1.45, color="k", lw=0.6, ls=":", label="lower stop lmin")
    ax[0].set(title="Leg 1 after its actuator fails at t = 1 s", xlabel="t, s", ylabel="l[1], m")
    ax[0].legend(fontsize=8)
    ax[1].plot(c["time"], np.degrees(c["angles[1]"]), label="roll, drive")
    ax[1].plot(c["time"], np.degrees(c["angles[2]"]), label="pitch, drive")
    ax[1].plot(forces["time"], np.degrees(forces["angles[1]"]), "--", label="roll, force actuator")
    ax[1].plot(forces["time"], np.degrees(forces["angles[2]"]), "--", label="pitch, force actuator")
    ax[1].set(title="Platform attitude", xlabel="t, s", ylabel="deg")
    ax[1].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(OUT / "drive_failure.png", dpi=110)
    plt.close(fig)


def main():
    OUT.mkdir(parents=True, exist_ok=True)
    summary = [parameters_line()]
    c, _, status = dr.holding_run((I_HOLD, U_HOLD), 3.0)
    summary.append(f"0 holding at {U_HOLD:.4f} V for 3 s: heave drift {np.max(np.abs(c['r[3]'] - c['r[3]'][0])):.1e} m, "
                   f"currents within {max(np.max(np.abs(c[f'I[{k}]'] - I_HOLD)) for k in LEGS):.1e} A of the static "
                   f"model's ({status})")
    power_loss(summary)
    heave(summary)
    failure(summary)
    (OUT / "drive_summary.txt").write_text("\n".join(summary) + "\n")
    print("\n".join(summary))
    print(f"wrote the drive scenarios' CSV files and plots to {OUT.resolve()}")


if __name__ == "__main__":
    main()
