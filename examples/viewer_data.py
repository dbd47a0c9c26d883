"""The main job's 3-D viewer: writes the built page and eight results into output/viewer/ (or the
folder given), listed in its dataset menu, and prints how to serve it.

- the default controller driving the heave programme (SI, 10 s at 1 ms);
- power loss: the legs lose their force at 0.5 s and the platform drops onto its stops;
- actuator failure: leg 1's force falls to 0 at 1 s under feedback;
- start-up: the controller lifts the platform from its parked pose on the stops (programme 4);
- heavy legs (40 kg cylinders, 15 kg rods) on the heave programme;
- the open-loop 5 % ripple per leg tips the platform onto its joint limits (red joints);
- hydraulic servo legs on the heave programme: the cylinders coloured by their load pressure,
  the pressures and spools plotted;
- motion cueing: the truck's braking through the whole motion system (cueing -> controller ->
  platform), the vehicle's and the simulator's specific force and angular velocity plotted.
"""

import sys
from pathlib import Path

import numpy as np

from stewart_fmu import Platform, cueing, vehicle
from stewart_fmu.cosim import closed_loop
from stewart_fmu.machine import HEAVY, ripple_run
from stewart_fmu.viewer import HYDRAULIC_VIEW_OUTPUTS, VIEW_OUTPUTS, stand, view

OUT = Path(sys.argv[1] if len(sys.argv) > 1 else "output/viewer")
RECORD = VIEW_OUTPUTS


def as_columns(times, rows, record=RECORD):
    columns = {"time": np.asarray(times)}
    rows = np.asarray(rows)
    for j, name in enumerate(record):
        columns[name] = rows[:, j]
    return columns


def loop(name, title, record=RECORD, **kwargs):
    t, rows, _, status = closed_loop(record=tuple(record), **kwargs)
    url = view(as_columns(t, rows, record), stand(kwargs.get("platform_reals")), OUT, name, title)
    print(f"viewer: {title}: {len(t)} rows ({status}) -> {url}")


def power_loss():
    pl = Platform(name="power-loss")
    u0 = pl.get("F[1]")[0]
    times, rows = [0.0], [pl.get(*RECORD)]
    for i in range(3000):
        pl.set_forces([u0 if pl.time < 0.5 else 0.0] * 6)
        pl.step(1e-3)
        times.append(pl.time)
        rows.append(pl.get(*RECORD))
    pl.free()
    url = view(as_columns(times, rows), stand(), OUT, "power_loss", "power loss at 0.5 s (SI)")
    print(f"viewer: power loss: {len(times)} rows -> {url}")


def main():
    loop("heave", "default controller, heave programme (SI)", t_end=10.0, h=1e-3)
    power_loss()
    loop("actuator_failure", "leg 1 fails at 1 s under feedback (SI)", t_end=5.0, h=1e-3,
         force_hook=lambda t, f: np.where(np.arange(6) == 0, 0.0, f) if t >= 1.0 else f)
    parked = {"r0[3]": 1.5717790024}
    loop("start_up", "start-up from the parked pose (programme 4, SI)", t_end=6.0, h=1e-3, platform_reals=parked,
         controller_integers={"programme": 4})
    loop("heavy_legs", "heavy legs (40 kg cylinders, 15 kg rods), heave programme (SI)", t_end=10.0, h=1e-3,
         platform_reals=HEAVY, controller_reals=HEAVY)
    loop("hydraulic_heave", "hydraulic servo legs fed by the power unit, heave programme: cylinders coloured by load "
         "pressure, the supply pressure and the accumulator's oil plotted (SI)",
         record=RECORD + HYDRAULIC_VIEW_OUTPUTS, t_end=10.0, h=1e-3, platform_reals={"drive": 2, "hydraulic.supply": 1},
         controller_integers={"drive": 2})
    braking = cueing.motion_system(vehicle.brake(), record=tuple(RECORD))
    # Every tenth row (100 per second) keeps the file small.
    url = view({n: c[::10] for n, c in braking.items()}, stand(), OUT, "cueing_braking",
               "motion cueing: a truck brakes 3 m/s2 to a stop; vehicle and simulator cues (SI)")
    print(f"viewer: cueing braking: {len(braking['time'][::10])} rows -> {url}")
    columns, events, status = ripple_run(10.0, 0.01)
    url = view(columns, stand(), OUT, "ripple_joint_limits", "open-loop 5 % ripple per leg: resting on the joint limits (SI)")
    print(f"viewer: ripple: {len(columns['time'])} rows ({status}, {len(events)} joint-limit events) -> {url}")
    print(f"viewer: serve it with  .venv/bin/python -m http.server --directory {OUT} 8000  and open "
          f"http://127.0.0.1:8000/")


if __name__ == "__main__":
    main()
