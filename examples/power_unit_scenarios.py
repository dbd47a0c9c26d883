"""The main job's demonstration of the hydraulic power unit (docs/model.md §10b, `hydraulic.supply
= 1`): the heave programme fed by the pump and the accumulator (scenario 3), a pump stop at the
heave programme's worst moment answered by the accumulator and the controller's safe landing
(scenario 4), and a design study of the accumulator's volume and precharge on a local Dask
cluster (scenario 5); through the packaged FMUs, SI units, default stand, legs and power unit.
Writes hydraulic6_power_unit_heave.csv, hydraulic7_pump_stop_landing.csv, hydraulic_power_unit.png,
hydraulic_landing.png, accumulator_study.csv, accumulator_study.png and
hydraulic_power_unit_summary.txt.

    python examples/power_unit_scenarios.py [output-folder]   (default: output/)
"""

import math
import sys
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from fmpy import read_model_description
from stewart_fmu import hydraulics as hy
from stewart_fmu.core import CONTROLLER_FMU, LEGS, PLATFORM_FMU

from csv_columns import write_columns

OUT = Path(sys.argv[1] if len(sys.argv) > 1 else "output")
PERIOD = 2 * math.pi / 2.5573423705088842  # the default heave programme's, s
LANDING_PRESSURE = 12.0e6  # Pa: the scenarios' landing.pressure (the controller's default is 0, off)
STOP_PHASES = 8  # pump stops tried over one heave cycle
AFTER_STOP = 14.0  # s simulated after the pump stops (the slowest landings in the study take 12)
VOLUMES = [20e-3, 30e-3, 40e-3, 50e-3, 60e-3]  # m3, the study's accumulator.volume
PRECHARGES = [4.5e6, 6e6, 7.5e6, 9e6, 10.5e6, 12e6]  # Pa absolute, the study's accumulator.precharge


def starts(fmu, names):
    start = {v.name: v.start for v in read_model_description(str(fmu)).modelVariables}
    return {n: float(start[n]) for n in names}


UNIT = starts(PLATFORM_FMU, ["pump.maxFlow", "pump.setPressure", "pump.compensatorBand", "relief.pressure",
                             "relief.gain", "accumulator.volume", "accumulator.precharge",
                             "accumulator.polytropic", "supply.volume", "lmin[1]"])
LANDING = starts(CONTROLLER_FMU, ["landing.speed", "landing.floor"])


def balance(c):
    """E(t) - E(0) - (work.pump - work.compression - work.dissipated), J (§10b)."""
    return c["E"] - c["E"][0] - (c["work.pump"] - c["work.compression"] - c["work.dissipated"])


def landing_figures(c, t_stop):
    """What a pump stop's run shows: the lowest supply pressure, the accumulator's least oil, the
    fastest descent, the largest vertical acceleration after the stop, where and how it ended."""
    after = c["time"] >= t_stop
    legs = np.array([c[f"l[{k}]"] for k in LEGS])
    return {
        "lowest_supply": float(c["supply.pressure"][after].min()),
        "least_oil": float(c["accumulator.oilVolume"][after].min()),
        "fastest_descent": float(-c["v[3]"][after].min()),
        "peak_acceleration": float(np.abs(c["der(v[3])"][after]).max()),
        "final_z": float(c["r[3]"][-1]),
        "final_speed": float(abs(c["v[3]"][-1])),
        "shortest_leg": float(legs[:, after].min()),
        "stop_force": float(max(np.abs(c[f"Fstop[{k}]"]).max() for k in LEGS)),
        "pmin": float(c["pmin"][-1]),
        "balance": float(np.abs(balance(c)).max()),
    }


def landed(f):
    """Landed under control: at rest within 2 mm of the floor, no end stop touched."""
    return abs(f["final_z"] - LANDING["landing.floor"]) < 2e-3 and f["final_speed"] < 1e-3 and f["stop_force"] == 0.0


def heave(summary):
    print("6 the heave programme fed by the power unit ...")
    c, errors, status = hy.power_unit_heave(10.0)
    assert status == "ok", status
    t = c["time"]
    last = t >= t[-1] - PERIOD
    write_columns(OUT / "hydraulic6_power_unit_heave.csv",
                  {"t": t, **{n: c[n] for n in hy.POWER_UNIT + ["Qsupply", "r[3]"]}, "leg_error": errors})
    p = c["supply.pressure"][last]
    summary.append(
        f"6 heave programme with the power unit (hydraulic.supply = 1: pump {UNIT['pump.maxFlow'] * 6e4:.0f} L/min "
        f"compensated at {UNIT['pump.setPressure'] / 1e6:.1f} + {UNIT['pump.compensatorBand'] / 1e6:.1f} MPa, "
        f"accumulator {UNIT['accumulator.volume'] * 1e3:.0f} L precharged to "
        f"{UNIT['accumulator.precharge'] / 1e6:.1f} MPa absolute, relief at {UNIT['relief.pressure'] / 1e6:.1f} MPa), "
        f"10 s at 1 ms: largest leg error {errors.max() * 1e3:.3f} mm; over the last cycle the supply pressure "
        f"{p.min() / 1e6:.3f} .. {p.max() / 1e6:.3f} MPa (ripple {(p.max() - p.min()) / 1e3:.0f} kPa), pump flow "
        f"{c['supply.pumpFlow'][last].min() * 6e4:.0f} .. {c['supply.pumpFlow'][last].max() * 6e4:.0f} L/min, valves "
        f"draw up to {c['Qsupply'][last].max() * 6e4:.0f} L/min, the accumulator's oil "
        f"{c['accumulator.oilVolume'][last].min() * 1e3:.2f} .. {c['accumulator.oilVolume'][last].max() * 1e3:.2f} L, "
        f"relief flow up to {c['supply.reliefFlow'].max() * 6e4:.2f} L/min; lowest chamber pressure (pmin) "
        f"{(c['pmin'][-1] + 101325.0) / 1e6:.3f} MPa absolute; pump work {c['work.pump'][-1] / 1e3:.0f} kJ; "
        f"energy balance residual {np.abs(balance(c)).max():.1e} J of {c['work.dissipated'][-1] / 1e3:.0f} kJ "
        f"dissipated")
    fig, ax = plt.subplots(2, 2, figsize=(14, 8))
    ax[0, 0].plot(t, c["supply.pressure"] / 1e6)
    ax[0, 0].set(title="Supply pressure p_S", xlabel="t, s", ylabel="MPa")
    ax[0, 1].plot(t, c["supply.pumpFlow"] * 6e4, label="pump")
    ax[0, 1].plot(t, c["Qsupply"] * 6e4, label="valves (Qsupply)")
    ax[0, 1].plot(t, c["supply.reliefFlow"] * 6e4, label="relief")
    ax[0, 1].set(title="Flows", xlabel="t, s", ylabel="L/min")
    ax[0, 1].legend(fontsize=8)
    ax[1, 0].plot(t, c["accumulator.oilVolume"] * 1e3)
    ax[1, 0].set(title="Oil in the accumulator", xlabel="t, s", ylabel="L")
    ax[1, 1].plot(t, errors * 1e3)
    ax[1, 1].set(title="Largest leg error max |l - l^p|", xlabel="t, s", ylabel="mm")
    fig.suptitle("Scenario 6: the heave programme fed by the power unit")
    fig.tight_layout()
    fig.savefig(OUT / "hydraulic_power_unit.png", dpi=110)
    plt.close(fig)


def landing(summary):
    print(f"7 pump stops at {STOP_PHASES} moments of a heave cycle, the safe landing below "
          f"{LANDING_PRESSURE / 1e6:.0f} MPa ...")
    runs = []
    for i in range(STOP_PHASES):
        t_stop = round(2 * PERIOD + i * PERIOD / STOP_PHASES, 3)
        c, _, status = hy.pump_stop_landing(t_stop, t_stop + AFTER_STOP, LANDING_PRESSURE)
        assert status == "ok", status
        f = landing_figures(c, t_stop)
        print(f"  pump stop at {t_stop:.3f} s: lowest supply {f['lowest_supply'] / 1e6:.2f} MPa, least oil "
              f"{f['least_oil'] * 1e3:.2f} L, landed {landed(f)}")
        runs.append((t_stop, c, f))
    t_stop, c, f = min(runs, key=lambda r: r[2]["lowest_supply"])
    assert all(landed(r[2]) for r in runs), [(r[0], r[2]) for r in runs if not landed(r[2])]
    t = c["time"]
    write_columns(OUT / "hydraulic7_pump_stop_landing.csv",
                  {"t": t, **{n: c[n] for n in hy.POWER_UNIT + ["Qsupply", "r[3]", "v[3]", "der(v[3])"] + hy.L},
                   "energy_balance": balance(c)})
    summary.append(
        f"7 pump stop (pump.speed 0) at each of {STOP_PHASES} moments of a heave cycle, the controller's safe landing "
        f"(landing.pressure {LANDING_PRESSURE / 1e6:.0f} MPa, landing.speed {LANDING['landing.speed']:.2f} m/s, "
        f"landing.floor {LANDING['landing.floor']:.4f} m): every run lands at rest on the floor without touching a "
        f"stop; the worst moment (the lowest supply pressure) is t = {t_stop:.3f} s: supply down to "
        f"{f['lowest_supply'] / 1e6:.2f} MPa, the accumulator's oil down to {f['least_oil'] * 1e3:.2f} L, descent after "
        f"the stop at most {f['fastest_descent']:.3f} m/s, vertical acceleration after the stop at most "
        f"{f['peak_acceleration']:.2f} m/s2, shortest leg {f['shortest_leg']:.4f} m (lmin "
        f"{UNIT['lmin[1]']:.4f} m), at rest at z = {f['final_z']:.4f} m; lowest chamber pressure (pmin) "
        f"{(f['pmin'] + 101325.0) / 1e6:.3f} MPa absolute; energy balance residual {f['balance']:.1e} J "
        f"(pump work {c['work.pump'][-1] / 1e3:.0f} kJ)")
    fig, ax = plt.subplots(2, 2, figsize=(14, 8))
    ax[0, 0].plot(t, c["r[3]"], label="z")
    ax[0, 0].axvline(t_stop, color="k", ls=":", label="pump stops")
    ax[0, 0].axhline(LANDING["landing.floor"], color="grey", ls="--", label="landing.floor")
    ax[0, 0].set(title="Height of the centre of mass", xlabel="t, s", ylabel="m")
    ax[0, 0].legend(fontsize=8)
    ax[0, 1].plot(t, c["supply.pressure"] / 1e6, label="supply pressure")
    ax[0, 1].axhline(LANDING_PRESSURE / 1e6, color="grey", ls="--", label="landing.pressure")
    ax[0, 1].axhline((UNIT["accumulator.precharge"] - 101325.0) / 1e6, color="r", ls=":", label="precharge (gauge)")
    ax[0, 1].set(title="Supply pressure", xlabel="t, s", ylabel="MPa")
    ax[0, 1].legend(fontsize=8)
    ax[1, 0].plot(t, c["accumulator.oilVolume"] * 1e3, label="accumulator oil")
    ax[1, 0].set(title="Oil in the accumulator", xlabel="t, s", ylabel="L")
    ax[1, 1].plot(t, c["v[3]"], label="v_z, m/s")
    ax[1, 1].plot(t, c["der(v[3])"] / 10, label="a_z / 10, m/s2")
    ax[1, 1].set(title="Vertical velocity and acceleration", xlabel="t, s")
    ax[1, 1].legend(fontsize=8)
    fig.suptitle(f"Scenario 7: pump stop at t = {t_stop:.3f} s (the worst of {STOP_PHASES} moments), safe landing")
    fig.tight_layout()
    fig.savefig(OUT / "hydraulic_landing.png", dpi=110)
    plt.close(fig)
    return t_stop


def study_point(volume, precharge, t_stop):
    """One design point: the pump stop at `t_stop` with the accumulator (volume m3, precharge Pa)."""
    c, _, status = hy.pump_stop_landing(t_stop, t_stop + AFTER_STOP, LANDING_PRESSURE,
                                        platform={"accumulator.volume": volume, "accumulator.precharge": precharge})
    f = landing_figures(c, t_stop)
    return {"volume": volume, "precharge": precharge, "status": status, "landed": landed(f), **f}


def study(summary, t_stop):
    from dask.distributed import Client, LocalCluster, as_completed

    points = [(v, p) for v in VOLUMES for p in PRECHARGES]
    print(f"8 design study: {len(points)} accumulators (volume x precharge) on a local Dask cluster, pump stop at "
          f"{t_stop:.3f} s ...")
    started = time.perf_counter()
    with LocalCluster(n_workers=2, threads_per_worker=1, host="127.0.0.1", dashboard_address=None,
                      processes=True) as cluster, Client(cluster) as client:
        futures = [client.submit(study_point, v, p, t_stop, pure=False) for v, p in points]
        rows = []
        for done, future in enumerate(as_completed(futures), 1):
            rows.append(future.result())
            print(f"  {done}/{len(points)} done ({time.perf_counter() - started:.0f} s)", flush=True)
    rows.sort(key=lambda r: (r["volume"], r["precharge"]))
    keys = ["volume", "precharge", "landed", "lowest_supply", "least_oil", "peak_acceleration", "fastest_descent",
            "final_z", "shortest_leg", "stop_force", "balance"]
    write_columns(OUT / "accumulator_study.csv", {k: np.array([float(r[k]) for r in rows]) for k in keys})
    grid = {k: np.array([[next(r[k] for r in rows if r["volume"] == v and r["precharge"] == p) for p in PRECHARGES]
                         for v in VOLUMES], dtype=float) for k in ("lowest_supply", "peak_acceleration", "landed")}
    fig, ax = plt.subplots(1, 2, figsize=(14, 5.5))
    for a, key, scale, unit, title in ((ax[0], "lowest_supply", 1e-6, "MPa", "lowest supply pressure"),
                                       (ax[1], "peak_acceleration", 1.0, "m/s2", "peak vertical acceleration")):
        image = a.imshow(grid[key] * scale, origin="lower", aspect="auto", cmap="viridis")
        fig.colorbar(image, ax=a, label=unit)
        for i in range(len(VOLUMES)):
            for j in range(len(PRECHARGES)):
                mark = "" if grid["landed"][i, j] else "\n(not landed)"
                a.text(j, i, f"{grid[key][i, j] * scale:.2f}{mark}", ha="center", va="center", fontsize=7,
                       color="w")
        a.set_xticks(range(len(PRECHARGES)), [f"{p / 1e6:.1f}" for p in PRECHARGES])
        a.set_yticks(range(len(VOLUMES)), [f"{v * 1e3:.0f}" for v in VOLUMES])
        a.set(xlabel="accumulator.precharge, MPa absolute", ylabel="accumulator.volume, L", title=title)
    fig.suptitle(f"Scenario 8: the accumulator against a pump stop at the heave's worst moment (t = {t_stop:.3f} s), "
                 f"safe landing below {LANDING_PRESSURE / 1e6:.0f} MPa")
    fig.tight_layout()
    fig.savefig(OUT / "accumulator_study.png", dpi=110)
    plt.close(fig)
    landed_count = sum(bool(r["landed"]) for r in rows)
    default = next(r for r in rows if r["volume"] == UNIT["accumulator.volume"]
                   and r["precharge"] == UNIT["accumulator.precharge"])
    smallest = min((r for r in rows if r["landed"]), key=lambda r: r["volume"], default=None)
    summary.append(
        f"8 design study on a local Dask cluster (2 workers on 127.0.0.1), {len(rows)} accumulators: volume "
        f"{VOLUMES[0] * 1e3:.0f} .. {VOLUMES[-1] * 1e3:.0f} L x precharge {PRECHARGES[0] / 1e6:.1f} .. "
        f"{PRECHARGES[-1] / 1e6:.1f} MPa absolute, the pump stopped at t = {t_stop:.3f} s; {landed_count} land at rest "
        f"on the floor without a stop; the default ({default['volume'] * 1e3:.0f} L, "
        f"{default['precharge'] / 1e6:.1f} MPa) keeps the supply above {default['lowest_supply'] / 1e6:.2f} MPa with "
        f"{default['least_oil'] * 1e3:.2f} L of oil left"
        + (f"; the smallest that lands: {smallest['volume'] * 1e3:.0f} L at {smallest['precharge'] / 1e6:.1f} MPa "
           f"(lowest supply {smallest['lowest_supply'] / 1e6:.2f} MPa)" if smallest else ""))
    print(f"the design study took {time.perf_counter() - started:.0f} s")


def main():
    OUT.mkdir(parents=True, exist_ok=True)
    summary = []
    heave(summary)
    t_stop = landing(summary)
    study(summary, t_stop)
    (OUT / "hydraulic_power_unit_summary.txt").write_text("\n".join(summary) + "\n")
    print("\n".join(summary))
    print(f"wrote the power unit's CSV files and plots to {OUT.resolve()}")


if __name__ == "__main__":
    main()
