"""The machine (docs/model.md §8: legs as bodies, joint limits, cylinder friction) through the
packaged FMUs: the paper's machine is still computed to the bit; open-loop forces that tip the
platform over leave it resting on its joint limits in every host; heavy legs in the closed
loop."""

import csv
import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu

from stewart_fmu import CONTROLLER_FMU, PLATFORM_FMU, ROOT, Platform
from stewart_fmu.cosim import closed_loop
from stewart_fmu.machine import HEAVY, joint_events, ripple

sys.path.insert(0, str(Path(__file__).parent))
import rigid_legs  # noqa: E402
from test_importers import fmi_sim_binary  # noqa: E402



@pytest.mark.quick
def test_the_papers_machine_gives_the_previous_releases_numbers_to_the_bit():
    """Massless legs, no friction: heave in closed loop, a power loss onto the stops, a tumble
    through singular arrangements, a tip-over; against the bits the release before the machine
    wrote (tests/data/rigid_legs_db183c0_libm.json), with the joint limits off, and on where no
    joint reaches its limit."""
    reference = json.loads((ROOT / "tests" / "data" / "rigid_legs_db183c0_libm.json").read_text())
    for joints in (False, True):
        motions = rigid_legs.motions(str(PLATFORM_FMU), str(CONTROLLER_FMU), joints)
        for name, rows in reference["motions"].items():
            got = rigid_legs.bits(motions[name])
            assert len(got) == len(rows), name
            different = [(i, reference["record"][j]) for i, (a, b) in enumerate(zip(rows, got))
                         for j, (x, y) in enumerate(zip(a, b)) if x != y]
            print(f"joints {joints}, {name}: {len(rows)} samples of {len(rows[0])} outputs, {len(different)} bits differ")
            assert not different, f"{name}: {different[:5]}"


def tilt_degrees(rows, names):
    """The body axis e3's angle from the vertical, degrees: acos(R[3,3])."""
    return math.degrees(math.acos(min(1.0, rows[names.index("R[3,3]")])))


def test_tipping_forces_leave_the_platform_on_its_joint_limits_in_every_host(tmp_path):
    """The 5 % per-leg ripple runs 10 s without a discard in FMPy, libcosim and fmi-sim, the
    platform resting tilted on its platform joints' limits; FMPy's logEvents names which
    joints reached their limits and when. Without joint limits it tips over and the step is
    discarded (the paper's machine)."""
    from libcosimpy.CosimEnums import CosimVariableType
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimManipulator import CosimManipulator
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave

    h, steps = 0.01, 1000
    record = ["r[3]", "R[3,3]"] + [f"thetaA[{k}]" for k in range(1, 7)] + [f"thetaB[{k}]" for k in range(1, 7)]
    finals = {}
    # FMPy, with the log.
    events = []
    pl = Platform(events=events)
    for i in range(steps):
        pl.set_forces(ripple(i * h))
        pl.step(h)
    finals["FMPy"] = pl.get(*record)
    pl.free()
    joints = [(t, j, k) for t, j, k, what in joint_events(events) if what == "reached"]
    # libcosim: the forces through an override manipulator, step by step.
    vr = {v.name: v.valueReference for v in read_model_description(str(PLATFORM_FMU)).modelVariables}
    execution = CosimExecution.from_step_size(step_size=int(h * 1e9))
    index = execution.add_local_slave(local_slave=CosimLocalSlave(fmu_path=str(PLATFORM_FMU), instance_name="p"))
    manipulator = CosimManipulator.create_override()
    execution.add_manipulator(manipulator=manipulator)
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer=observer)
    forces = [vr[f"F[{k}]"] for k in range(1, 7)]
    for i in range(steps):
        assert manipulator.slave_real_values(index, forces, ripple(i * h))
        assert execution.step()
    finals["libcosim"] = observer.last_real_values(slave_index=index, variable_references=[vr[n] for n in record])
    # fmi-sim: the forces from a CSV file.
    inputs = tmp_path / "ripple.csv"
    with open(inputs, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["time"] + [f"F[{k}]" for k in range(1, 7)])
        for i in range(steps + 1):
            w.writerow([repr(i * h)] + [repr(x) for x in ripple(i * h)])
    out = tmp_path / "out.csv"
    run = subprocess.run([fmi_sim_binary(), "--model", str(PLATFORM_FMU), "-i", str(inputs), "-o", str(out),
                          "co-simulation", "--step", str(h), "-f", str(steps * h)], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr[-2000:]
    with open(out) as f:
        rows = list(csv.DictReader(f))
    assert abs(float(rows[-1]["time"]) - steps * h) < 1e-9, rows[-1]["time"]
    finals["fmi-sim"] = [float(rows[-1][n]) for n in record]
    for host, values in finals.items():
        theta_a = max(values[2:8])
        print(f"{host}: t = 10 s, z = {values[0]:.4f} m, tilt {tilt_degrees(values, record):.2f} deg, "
              f"largest platform joint angle {math.degrees(theta_a):.3f} deg, base {math.degrees(max(values[8:])):.3f} deg")
        assert 15.0 < tilt_degrees(values, record) < 45.0, host
        assert 35.0 <= math.degrees(theta_a) < 37.0, host  # on the default 35-degree limit
    print("joints reaching their limits (FMPy's logEvents):", ", ".join(f"{j} {k} at {t:.3f} s" for t, j, k in joints[:8]),
          f"... ({len(joints)} in all)")
    assert joints and joints[0][0] < 1.5 and any(j == "platform" for _, j, _ in joints)
    # The paper's machine: the same forces tip it over.
    result = simulate_fmu(str(PLATFORM_FMU), start_values={"joints": False}, stop_time=10.0, output_interval=h,
                          output=["r[3]"], input=np.array(
                              [(i * h, *ripple(i * h)) for i in range(steps + 1)],
                              dtype=[("time", float)] + [(f"F[{k}]", float) for k in range(1, 7)]))
    print(f"without joint limits the run ends at t = {result['time'][-1]:.3f} s")
    assert result["time"][-1] < 2.0


@pytest.mark.quick
def test_heavy_legs_in_the_closed_loop_follow_the_programme_to_a_millimetre():
    """Legs of 40 kg cylinders and 15 kg rods in platform and controller (whose programme
    forces then carry the legs' weight and inertia): the default closed loop holds the heave
    programme to 1e-3 m. The drives push harder by the legs' weight and inertia; the joints,
    which carry the platform along the same motion, see the same forces."""
    record = ["F[1]", "jointForce[1,3]"]
    t, rows, errors, status = closed_loop(10.0, 1e-3, platform_reals=HEAVY, controller_reals=HEAVY, record=record)
    t0, rows0, errors0, status0 = closed_loop(10.0, 1e-3, record=record)
    assert status == "ok" and status0 == "ok", (status, status0)
    worst, worst0 = float(np.max(errors)), float(np.max(errors0))
    extra = rows[:, 0] - rows0[:, 0]
    joint = float(np.max(np.abs(rows[:, 1] - rows0[:, 1])))
    print(f"largest leg error over 10 s: {worst * 1e3:.4f} mm with heavy legs, {worst0 * 1e3:.4f} mm massless; leg 1's "
          f"force {np.min(extra):.1f} .. {np.max(extra):.1f} N larger; its joint's vertical force within {joint:.2f} N")
    assert worst < 1e-3
    assert np.min(extra) > 100.0
    assert joint < 0.01 * np.max(np.abs(rows0[:, 1]))
