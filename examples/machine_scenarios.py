"""The main job's demonstration of the machine (docs/model.md §8): heavy legs against massless
ones on the same heave programme, the open-loop ripple resting on its joint limits, and
friction on a small motion; through the packaged FMUs, SI units, default stand. Writes
machine1_heavy_legs.csv, machine2_ripple.csv, machine3_friction.csv, machine_heavy_legs.png,
machine_ripple.png, machine_friction.png and machine_summary.txt.

    python examples/machine_scenarios.py [output-folder]   (default: output/)
"""

import re
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from stewart_fmu import machine as mc
from stewart_fmu.workspace import start_values

from csv_columns import write_columns

OUT = Path(sys.argv[1] if len(sys.argv) > 1 else "output")
LEGS = list(mc.LEGS)


def write_csv(name, columns):
    write_columns(OUT / name, columns)


def cause(message):
    """The fault of a discarded step's message: "at t = ...: platform joint A[k] passed through
    the base plane", or the message's start."""
    found = re.search(r"at t = ([-+0-9.eE]+): (.*?base plane)", message)
    return f"at t = {float(found.group(1)):.4f} s {found.group(2)}" if found else message[:120]


def balance(c):
    """E(t) - E(0) - (work.F - work.dissipated), J."""
    return c["E"] - c["E"][0] - (c["work.F"] - c["work.dissipated"])


def heavy_legs(summary):
    print("1 heavy legs against massless legs, heave programme in the closed loop ...")
    heavy, err_h, st_h = mc.heave_with_legs(mc.HEAVY)
    light, err_l, st_l = mc.heave_with_legs()
    assert st_h == st_l == "ok", (st_h, st_l)
    t = heavy["time"]
    vertical = np.max(np.abs(heavy["jointForce[1,3]"] - light["jointForce[1,3]"]))
    horizontal = np.max(np.hypot(heavy["jointForce[1,1]"] - light["jointForce[1,1]"],
                                 heavy["jointForce[1,2]"] - light["jointForce[1,2]"]))
    write_csv("machine1_heavy_legs.csv", {
        "t": t, "z_heavy": heavy["r[3]"], "z_massless": light["r[3]"],
        **{f"F[{k}]_heavy": heavy[f"F[{k}]"] for k in LEGS}, **{f"F[{k}]_massless": light[f"F[{k}]"] for k in LEGS},
        **{f"jointForce[1,{i}]_heavy": heavy[f"jointForce[1,{i}]"] for i in (1, 2, 3)},
        **{f"jointForce[1,{i}]_massless": light[f"jointForce[1,{i}]"] for i in (1, 2, 3)},
        "leg_error_heavy": err_h, "leg_error_massless": err_l})
    extra = heavy["F[1]"] - light["F[1]"]
    legs = ", ".join(f"{k} {v:g}" for k, v in mc.HEAVY.items())
    summary.append(
        f"1 heavy legs ({legs}) on the heave programme, 10 s closed loop: leg 1's force "
        f"{np.min(heavy['F[1]']):.1f} .. {np.max(heavy['F[1]']):.1f} N against {np.min(light['F[1]']):.1f} .. "
        f"{np.max(light['F[1]']):.1f} N massless ({np.min(extra):+.1f} .. {np.max(extra):+.1f} N); on platform "
        f"joint 1 the vertical force is the same within {vertical:.3f} N (a sixth of the platform's M (z'' + g) in "
        f"this symmetric heave), the horizontal force changes by up to {horizontal:.1f} N (the leg hangs on its "
        f"joints); largest "
        f"leg error {np.max(err_h) * 1e3:.4f} mm heavy, {np.max(err_l) * 1e3:.4f} mm massless; energy balance "
        f"residual {np.max(np.abs(balance(heavy))):.1e} J")
    fig, ax = plt.subplots(1, 3, figsize=(16, 4.2))
    ax[0].plot(t, light["F[1]"] / 1e3, label="massless legs (the paper's)")
    ax[0].plot(t, heavy["F[1]"] / 1e3, label="40 kg cylinders, 15 kg rods")
    ax[0].set(title="Leg 1's actuator force F[1]", xlabel="t, s", ylabel="kN")
    ax[0].legend(fontsize=8)
    for k in LEGS:
        ax[1].plot(t, heavy[f"F[{k}]"] - light[f"F[{k}]"], lw=0.8, label=f"leg {k}")
    ax[1].set(title="What the legs' mass adds: F(heavy) - F(massless), six legs alike", xlabel="t, s", ylabel="N")
    ax[1].legend(fontsize=7, ncol=2)
    for i, axis in enumerate("xyz", start=1):
        ax[2].plot(t, light[f"jointForce[1,{i}]"] / 1e3, lw=1.6, label=f"{axis}, massless")
        ax[2].plot(t, heavy[f"jointForce[1,{i}]"] / 1e3, "k:", lw=0.9, label="heavy legs (dotted)" if i == 3 else None)
    ax[2].set(title="Force on platform joint 1, jointForce[1,:] (inertial frame)", xlabel="t, s", ylabel="kN")
    ax[2].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(OUT / "machine_heavy_legs.png", dpi=110)
    plt.close(fig)


def ripple(summary):
    print("2 open-loop ripple: resting on the joint limits ...")
    on, events, st_on = mc.ripple_run(10.0, 0.01)
    off, _, st_off = mc.ripple_run(10.0, 0.01, joints=False)
    assert st_on == "ok", st_on
    limits = start_values(["joints.baseMaxAngle", "joints.platformMaxAngle"])
    base_max, platform_max = np.degrees(limits["joints.baseMaxAngle"]), np.degrees(limits["joints.platformMaxAngle"])
    write_csv("machine2_ripple.csv", {"t": on["time"], "z": on["r[3]"], "tilt_deg": np.degrees(mc.tilt(on)),
                                      **{n: on[n] for n in mc.JOINT_ANGLES}, **{f"Fstop[{k}]": on[f"Fstop[{k}]"]
                                                                                 for k in LEGS},
                                      "E": on["E"], "work.F": on["work.F"], "work.dissipated": on["work.dissipated"]})
    reached = [e for e in events if e[3] == "reached"]
    first = "; ".join(f"{j} joint {k} at {t:.3f} s" for t, j, k, _ in reached[:5])
    theta_a = np.degrees(max(on[f"thetaA[{k}]"][-1] for k in LEGS))
    summary.append(
        f"2 ripple 5900.715 (1 + 0.05 sin(2t + k)) N, open loop, 10 s: joints reaching their limits: {first} ... "
        f"({len(reached)} onsets); at 10 s tilt {np.degrees(mc.tilt(on))[-1]:.2f} deg, largest platform joint angle "
        f"{theta_a:.3f} deg (limit {platform_max:g}), base {np.degrees(max(on[f'thetaB[{k}]'][-1] for k in LEGS)):.3f} "
        f"deg (limit {base_max:g}); energy balance residual {np.max(np.abs(balance(on))):.1e} J. Without joint "
        f"limits the run ends at t = {off['time'][-1]:.2f} s: {cause(st_off)}")
    fig, ax = plt.subplots(1, 3, figsize=(16, 4.2))
    ax[0].plot(on["time"], np.degrees(mc.tilt(on)), label="joint limits on (default)")
    ax[0].plot(off["time"], np.degrees(mc.tilt(off)), "--", label="joints = false: discarded at "
               f"{off['time'][-1]:.2f} s")
    ax[0].set(title="Tilt of the platform, acos(R[3,3])", xlabel="t, s", ylabel="deg")
    ax[0].legend(fontsize=8)
    for k in LEGS:
        ax[1].plot(on["time"], np.degrees(on[f"thetaA[{k}]"]), lw=0.9, label=f"thetaA[{k}]")
    ax[1].axhline(platform_max, color="k", ls=":", lw=0.8, label="joints.platformMaxAngle")
    for t, j, k, _ in reached:
        if j == "platform":
            ax[1].plot(t, platform_max, "k|", ms=8)
    ax[1].set(title="Platform joint angles (ticks: limit reached, logEvents)", xlabel="t, s", ylabel="deg")
    ax[1].legend(fontsize=7, ncol=2)
    for k in LEGS:
        ax[2].plot(on["time"], np.degrees(on[f"thetaB[{k}]"]), lw=0.9, label=f"thetaB[{k}]")
    ax[2].axhline(base_max, color="k", ls=":", lw=0.8, label="joints.baseMaxAngle")
    ax[2].set(title="Base joint angles", xlabel="t, s", ylabel="deg")
    ax[2].legend(fontsize=7, ncol=2)
    fig.tight_layout()
    fig.savefig(OUT / "machine_ripple.png", dpi=110)
    plt.close(fig)


def friction(summary):
    print("3 friction on a 5 mm heave in the closed loop ...")
    small = {"heave.amplitude": 0.005}
    dry, err_f, st_f = mc.heave_with_legs(friction=mc.FRICTION, controller_reals=small, t_end=6.0)
    clean, err_c, st_c = mc.heave_with_legs(controller_reals=small, t_end=6.0)
    assert st_f == st_c == "ok", (st_f, st_c)
    t = dry["time"]
    write_csv("machine3_friction.csv", {"t": t, "z_friction": dry["r[3]"], "z_frictionless": clean["r[3]"],
                                        "leg_error_friction": err_f, "leg_error_frictionless": err_c,
                                        "work.dissipated": dry["work.dissipated"]})
    settled = t > 2.0
    params = ", ".join(f"{k} {v:g}" for k, v in mc.FRICTION.items())
    summary.append(
        f"3 friction ({params}) on a 5 mm heave, default closed loop, 6 s: largest leg error after 2 s "
        f"{np.max(err_f[settled]) * 1e3:.3f} mm against {np.max(err_c[settled]) * 1e3:.4f} mm without friction "
        f"(the feedback G = 2e5 N/m needs an error of F_s / G = {mc.FRICTION['friction.static'] / 2e5 * 1e3:.2f} mm "
        f"to overcome it); {dry['work.dissipated'][-1]:.1f} J dissipated; energy balance residual "
        f"{np.max(np.abs(balance(dry))):.1e} J")
    fig, ax = plt.subplots(1, 2, figsize=(12, 4))
    ax[0].plot(t, (clean["r[3]"] - clean["r[3]"][0]) * 1e3, label="no friction")
    ax[0].plot(t, (dry["r[3]"] - dry["r[3]"][0]) * 1e3, label="cylinder friction")
    ax[0].set(title="Heave of a 5 mm programme", xlabel="t, s", ylabel="z - z(0), mm")
    ax[0].legend(fontsize=8)
    ax[1].plot(t, err_c * 1e3, label="no friction")
    ax[1].plot(t, err_f * 1e3, label="cylinder friction")
    ax[1].set(title="Largest leg error max |l - l^p|", xlabel="t, s", ylabel="mm")
    ax[1].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(OUT / "machine_friction.png", dpi=110)
    plt.close(fig)


def main():
    OUT.mkdir(parents=True, exist_ok=True)
    summary = []
    heavy_legs(summary)
    ripple(summary)
    friction(summary)
    (OUT / "machine_summary.txt").write_text("\n".join(summary) + "\n")
    print("\n".join(summary))
    print(f"wrote the machine scenarios' CSV files and plots to {OUT.resolve()}")


if __name__ == "__main__":
    main()
