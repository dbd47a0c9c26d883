"""The main job's demonstration of the hydraulic power unit (docs/model.md §10b, `hydraulic.supply
= 1`): the heave programme fed by the pump and the accumulator (summary line 6), a pump stop at
the heave programme's worst moment answered by the accumulator and the controller's safe landing
(line 7); through the packaged FMUs, SI units, default stand, legs and power unit. The design
study of the accumulator's volume and precharge (line 8) is studies/accumulator.toml,
which `stewart-sweep` runs on a local Dask cluster after this script (examples/main_job.sh):
this script checks that the study's pump stop is the worst moment it finds. Writes
hydraulic6_power_unit_heave.csv, hydraulic7_pump_stop_landing.csv, hydraulic_power_unit.png,
hydraulic_landing.png and hydraulic_power_unit_summary.txt.

    python examples/power_unit_scenarios.py [output-folder]   (default: output/)
"""

import math
import sys
import tomllib
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
STUDY = Path(__file__).resolve().parents[1] / "studies" / "accumulator.toml"  # scenario 8, run by stewart-sweep


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


def check_study(summary, t_stop):
    """The design study (scenario 8) is studies/accumulator.toml, which stewart-sweep runs after
    this script (examples/main_job.sh): its pump stop must be the worst moment found here."""
    spec = tomllib.loads(STUDY.read_text())
    at = float(spec["fixed"]["scenario.pump_stop_at"])
    assert abs(at - t_stop) < 1e-9, (f"{STUDY} stops the pump at {at} s, but the worst of the pump stops is now at "
                                     f"{t_stop} s: set its scenario.pump_stop_at (and stop_time = {t_stop} + "
                                     f"{AFTER_STOP}) to it")
    stop = float(spec["study"]["stop_time"])
    assert abs(stop - (at + AFTER_STOP)) < 1e-9, f"{STUDY}: stop_time = {stop} s, not the pump stop + {AFTER_STOP} s"
    grid = spec["grid"]
    summary.append(
        f"8 design study: {STUDY.relative_to(STUDY.parents[1])} (stewart-sweep on a local Dask cluster, "
        f"{len(grid['platform.accumulator.volume']) * len(grid['platform.accumulator.precharge'])} accumulators, "
        f"the pump stopped at t = {at:.3f} s, the worst moment above): its rows, summary and maps in "
        f"{OUT / spec['study']['name']}/")


def main():
    OUT.mkdir(parents=True, exist_ok=True)
    summary = []
    heave(summary)
    t_stop = landing(summary)
    check_study(summary, t_stop)
    (OUT / "hydraulic_power_unit_summary.txt").write_text("\n".join(summary) + "\n")
    print("\n".join(summary))
    print(f"wrote the power unit's CSV files and plots to {OUT.resolve()}")


if __name__ == "__main__":
    main()
