"""The main job's demonstration of the whole workspace (end stops, singular leg arrangements):
the scenarios of tests/python/workspace.py through the packaged FMUs, SI units, default
stand. Writes one CSV per scenario, workspace_scenarios.png (heave and end-stop forces of
scenarios 1-4), workspace_energy_and_singularities.png and workspace_summary.txt.

    python examples/workspace_scenarios.py [output-folder]   (default: output/)
"""

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from stewart_fmu import workspace as ws

from csv_columns import write_columns

OUT = Path(sys.argv[1] if len(sys.argv) > 1 else "output")
LEGS = list(ws.LEGS)


def write_csv(name, columns):
    write_columns(OUT / name, columns)


def stop_columns(d):
    return {f"Fstop[{k}]": d[f"Fstop[{k}]"] for k in LEGS}


def events_text(events, limit=8):
    text = "; ".join(f"t = {t:.4f} s leg {k} {what} its {stop} stop" for t, k, what, stop in events[:limit])
    return text + (f" ... ({len(events)} events)" if len(events) > limit else "")


def joints_text(data, during=slice(None)):
    base, platform = ws.largest_joint_angles(data, during)
    return f"joint angles up to {base:.1f} deg (base), {platform:.1f} deg (platform)"


def main():
    OUT.mkdir(parents=True, exist_ok=True)
    summary = []
    lmin, lmax, stiffness, damping = ws.stop_defaults()
    summary.append(f"end stops: stroke {lmin} .. {lmax} m, stiffness {stiffness:g} N/m, damping {damping:g} N.s/m")

    print("1 power loss ...")
    loss = ws.power_loss()
    z_static, _ = ws.static_rest_height(stiffness, lmin)
    balance = loss["E"] - loss["E"][0] - (loss["work.F"] - loss["work.dissipated"])
    write_csv("workspace1_power_loss.csv", {"t": loss["time"], "z": loss["r[3]"], "vz": loss["v[3]"],
                                             "az": loss["der(v[3])"], "E": loss["E"], "work.F": loss["work.F"],
                                             "work.dissipated": loss["work.dissipated"], **stop_columns(loss)})
    summary.append(f"1 power loss at 0.5 s: {events_text(loss['events'], 6)}; peak deceleration "
                   f"{np.max(loss['der(v[3])']):.1f} m/s2; rest z = {loss['r[3]'][-1]:.9f} m (static solution "
                   f"{z_static:.9f} m); energy balance residual {np.max(np.abs(balance)):.1e} J; {joints_text(loss)}")

    print("2 elastic stops ...")
    elastic = ws.elastic_bounces(6.0, 1e-12)
    drift = (elastic["E"] - elastic["E"][0]) / elastic["E"][0]
    write_csv("workspace2_elastic.csv", {"t": elastic["time"], "z": elastic["r[3]"], "E": elastic["E"],
                                          "roll": elastic["angles[1]"]})
    bounces = len([e for e in elastic["events"] if e[1] == 1 and e[2] == "reached"])
    summary.append(f"2 elastic stops: {bounces} bounces in 6 s, max relative energy drift {np.max(np.abs(drift)):.1e}")

    print("3 start-up ...")
    lift = 3.0  # s: the start-up programme's lift, then the heave programme
    start = ws.start_up(duration=lift)
    write_csv("workspace3_start_up.csv", {"t": start["time"], "z": start["r[3]"], "leg_error": start["error"],
                                           **stop_columns(start)})
    heave_error = np.max(start["error"][start["time"] > 4]) * 1e3
    summary.append(f"3 start-up from rest on the lower stops (z = {start['z_rest']:.6f} m): {events_text(start['events'])};"
                   f" max leg error during the heave programme {heave_error:.4f} mm; "
                   f"the lift (to {lift:g} s) {joints_text(start, start['time'] <= lift)}, the heave programme after "
                   f"it {joints_text(start, start['time'] > lift)}")

    print("4 actuator failure ...")
    failure = ws.actuator_failure()
    write_csv("workspace4_actuator_failure.csv", {"t": failure["time"], "z": failure["r[3]"],
                                                   "roll": failure["angles[1]"], "pitch": failure["angles[2]"],
                                                   **{f"l[{k}]": failure[f"l[{k}]"] for k in LEGS},
                                                   **stop_columns(failure)})
    summary.append(f"4 actuator failure (leg 1 at t = 1 s, under feedback): {events_text(failure['events'])}; "
                   f"final roll {failure['angles[1]'][-1]:.3f} rad, pitch {failure['angles[2]'][-1]:.3f} rad; "
                   f"{joints_text(failure)}")

    print("5 tumble ...")
    tumble = ws.tumble()
    write_csv("workspace5_tumble.csv", {"t": tumble["time"], "x": tumble["r[1]"], "y": tumble["r[2]"],
                                         "z": tumble["r[3]"], "kappa": tumble["kappa"]})
    summary.append(f"5 tumble without end stops: singular arrangements passed at t = "
                   f"{[round(t, 4) for t in tumble['singular']]} s, no discard")

    print("6 power loss through Model Exchange ...")
    me, me_events = ws.power_loss_model_exchange()
    write_csv("workspace6_power_loss_model_exchange.csv", {"t": me["time"], "z": me["r[3]"],
                                                           **{f"Fstop[{k}]": me[f"Fstop[{k}]"] for k in LEGS}})
    summary.append(f"6 power loss, FMPy Model Exchange with CVODE: rest z = {me['r[3]'][-1]:.9f} m; contacts located "
                   f"by the event indicators: {events_text(me_events, 3)}")

    # Heave and stop forces of scenarios 1-4.
    fig, ax = plt.subplots(2, 4, figsize=(17, 7), sharex="col")
    panels = [("1 power loss at t = 0.5 s", loss), ("3 start-up from the stops", start),
              ("4 leg 1 fails at t = 1 s (feedback)", failure)]
    ax[0, 0].plot(loss["time"], loss["r[3]"], label="FMU (Co-Simulation)")
    ax[0, 0].plot(me["time"], me["r[3]"], "--", label="FMPy Model Exchange, CVODE")
    ax[0, 0].axhline(z_static, color="k", lw=0.6, ls=":", label="static rest on the stops")
    ax[0, 0].legend(fontsize=8)
    ax[0, 1].plot(elastic["time"], elastic["r[3]"])
    ax[0, 2].plot(start["time"], start["r[3]"])
    ax[0, 3].plot(failure["time"], failure["r[3]"], label="heave z")
    twin = ax[0, 3].twinx()
    twin.plot(failure["time"], np.degrees(failure["angles[1]"]), "C1", lw=0.8, label="roll")
    twin.plot(failure["time"], np.degrees(failure["angles[2]"]), "C2", lw=0.8, label="pitch")
    twin.set_ylabel("deg")
    twin.legend(fontsize=8, loc="lower right")
    for col, (title, d) in zip([0, 2, 3], panels):
        ax[0, col].set_title(title)
        for k in LEGS:
            ax[1, col].plot(d["time"], np.asarray(d[f"Fstop[{k}]"]) / 1e3, label=f"leg {k}")
    ax[0, 1].set_title("2 elastic stops: bounces")
    ax[1, 1].plot(elastic["time"], np.abs(drift) + 1e-18)
    ax[1, 1].set(yscale="log", ylabel="|E - E(0)| / E(0)")
    for col in range(4):
        ax[0, col].set_ylabel("centre of mass z, m")
        ax[1, col].set_xlabel("t, s")
        if col != 1:
            ax[1, col].set_ylabel("end-stop force Fstop, kN")
    ax[1, 0].legend(fontsize=7, ncol=2)
    fig.tight_layout()
    fig.savefig(OUT / "workspace_scenarios.png", dpi=110)

    fig, ax = plt.subplots(1, 2, figsize=(12, 4))
    ax[0].plot(loss["time"], balance * 1e3)
    ax[0].set(title="Power loss: E(t) - E(0) - (work.F - work.dissipated)", xlabel="t, s", ylabel="mJ")
    ax[1].semilogy(tumble["time"], tumble["kappa"])
    for t in tumble["singular"]:
        ax[1].axvline(t, color="r", lw=0.6, ls=":")
    ax[1].set(title="Tumble, no end stops: kappa (red lines: singular arrangements passed)",
              xlabel="t, s", ylabel="kappa")
    ax[1].title.set_fontsize(10)
    fig.tight_layout()
    fig.savefig(OUT / "workspace_energy_and_singularities.png", dpi=110)

    (OUT / "workspace_summary.txt").write_text("\n".join(summary) + "\n")
    print("\n".join(summary))
    print(f"wrote the workspace scenarios' CSV files and plots to {OUT.resolve()}")


if __name__ == "__main__":
    main()
