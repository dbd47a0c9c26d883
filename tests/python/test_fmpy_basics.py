"""The packaged FMU as FMPy sees it: validation, simulate_fmu with defaults and with leg
forces from a CSV file, variable communication steps."""

import math

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.util import read_csv, write_csv
from fmpy.validation import validate_fmu

from stewart_fmu import Platform
from oracles.heave import heave_forces, heave_programme
from oracles.stand import EQUILIBRIUM_FORCE, GRAVITY, MASS, NEUTRAL_Z, R_B

pytestmark = pytest.mark.quick


def test_validate_fmu_reports_no_problems(platform_fmu):
    assert validate_fmu(platform_fmu) == []


def test_model_description_declares_the_capabilities(platform_fmu):
    md = read_model_description(platform_fmu)
    cs = md.coSimulation
    assert cs.modelIdentifier == "StewartPlatform"
    assert cs.canHandleVariableCommunicationStepSize and cs.canGetAndSetFMUstate and cs.canSerializeFMUstate
    assert cs.canInterpolateInputs and cs.maxOutputDerivativeOrder >= 1
    units = {v.name: v.unit for v in md.modelVariables}
    assert units["F[1]"] == "N" and units["r[3]"] == "m" and units["angles[1]"] == "rad" and units["E"] == "J"
    assert {v.name: v.displayUnit for v in md.modelVariables}["angles[2]"] == "deg"
    # Pose and leg lengths have no direct feed-through from the forces: they depend on states
    # only (declared for Model Exchange), never on an input; only the joints' forces (the force
    # a leg passes on includes its actuator's) and the actuators' forces do, and the hydraulic
    # supply flow, through the supply pressure pS, and the power unit's supply pressure (pS without
    # it) and pump flow (pump.speed).
    inputs = {v.name for v in md.modelVariables if v.causality == "input"}
    through = {o.variable.name for o in md.outputs if any(d.name in inputs for d in o.dependencies)}
    assert through == ({f"jointForce[{k},{c}]" for k in range(1, 7) for c in range(1, 4)}
                       | {f"actuatorForce[{k}]" for k in range(1, 7)} | {"Qsupply"}
                       | {"supply.pressure", "supply.pumpFlow"}), sorted(through)
    assert any(o.dependencies for o in md.outputs)  # derived outputs list their states


def test_simulate_with_defaults_holds_the_neutral_equilibrium(platform_fmu):
    result = simulate_fmu(platform_fmu, output=["r[3]", "angles[1]", "angles[2]", "l[1]", "E", "constraintError"])
    assert result["time"][-1] == 3.0
    # docs/model.md §3: every leg carries 0.2005 M g in the neutral pose: the platform stays put
    # (round-off seeds the unstable tilt, still below 1e-9 rad after 3 s).
    assert np.max(np.abs(result["r[3]"] - NEUTRAL_Z)) < 1e-9
    assert np.max(np.abs(result["angles[1]"])) < 1e-9
    assert np.max(np.abs(result["l[1]"] - 1.7550860729486566)) < 1e-9
    assert np.ptp(result["E"]) < 1e-9 * result["E"][0]
    assert np.max(result["constraintError"]) < 1e-13


def test_forces_from_a_csv_file_drive_the_heave_programme(platform_fmu, tmp_path):
    """The paper's heave law scaled to SI (a = 0.2 R_b, Omega = sqrt(g/R_b)): forces from the
    direct problem, written to a CSV file, read back and applied by simulate_fmu."""
    omega = math.sqrt(GRAVITY / R_B)
    t = np.linspace(0.0, 3.0, 3001)
    forces = np.array([heave_forces(omega * ti)[0] * MASS * GRAVITY for ti in t])
    rows = [(ti,) + (fi,) * 6 for ti, fi in zip(t, forces)]
    signals = np.array(rows, dtype=[("time", float)] + [(f"F[{k + 1}]", float) for k in range(6)])
    path = tmp_path / "forces.csv"
    write_csv(str(path), signals)
    table = read_csv(str(path))
    result = simulate_fmu(platform_fmu, input=table, output=["r[3]"], output_interval=1e-3)
    assert 0.1 < np.ptp(result["r[3]"]) < 0.7  # the platform really moves
    programme = np.array([heave_programme(omega * ti, NEUTRAL_Z / R_B)[0] * R_B for ti in result["time"]])
    held = np.max(np.abs(result["r[3]"] - programme))

    # simulate_fmu(set_input_derivatives=True) cannot be used: FMPy 0.3.32 allocates room for
    # 9 input derivatives whatever the number of inputs (simulation.py, Input.__init__) and
    # fails for our 6. The same CSV through an FMU2Slave loop with first-order interpolation:
    pl = Platform()
    ts = table["time"]
    f = table["F[1]"]
    interpolated = 0.0
    for i in range(len(ts) - 1):
        h = ts[i + 1] - ts[i]
        pl.set_forces([f[i]] * 6, [(f[i + 1] - f[i]) / h] * 6)
        pl.step(h)
        interpolated = max(interpolated, abs(pl.get("r[3]")[0] - heave_programme(omega * pl.time, NEUTRAL_Z / R_B)[0] * R_B))
    pl.free()
    print(f"heave from CSV forces (SI, 3 s, 1 ms steps): max |z - z_programme| = {held:.2e} m with the forces "
          f"held (simulate_fmu), {interpolated:.2e} m interpolated to first order")
    # Holding the forces over a step is first order in the step, interpolating second order.
    assert held < 1e-3
    assert interpolated < 1e-4
    assert held > 3 * interpolated


def test_variable_communication_steps_give_the_fixed_step_answer(platform_fmu):
    """Constant forces (the ODE does not depend on the step pattern): irregular steps, down
    to 1e-7 s, end on the same states as regular ones, to the integrator's tolerance."""
    forces = [EQUILIBRIUM_FORCE * MASS * GRAVITY * (1.0 + 1e-3 * k) for k in range(6)]
    checkpoints = [0.5, 1.0, 1.5, 2.0]

    def run(steps):
        pl = Platform()
        pl.set_forces(forces)
        out = []
        for target in checkpoints:
            while pl.time < target - 1e-12:
                pl.step(min(next(steps), target - pl.time))
            out.append(np.concatenate([pl.vector("r", 3), pl.vector("angles", 3), pl.vector("l", 6)]))
        pl.free()
        return np.array(out)

    def fixed():
        while True:
            yield 0.01

    def irregular():
        rng = np.random.default_rng(7)
        while True:
            yield float(rng.choice([1e-7, 1e-4, 3.7e-3, 0.011, 0.05, 0.13]))

    a, b = run(fixed()), run(irregular())
    difference = np.max(np.abs(a - b))
    print(f"fixed vs irregular communication steps: max difference {difference:.2e}")
    assert np.ptp(a[:, 2]) > 1e-3  # the platform moves under the unequal forces
    assert difference < 1e-7
