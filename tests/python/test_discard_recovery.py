"""What a host sees after a discard, and the recovery recipe of docs/fmi-behaviour.md: a step that only the
limit of internal steps per call stops is refused with the numbers, `fmi2Terminated` false,
and the recipe (restore the state saved before the step, go on in halves) finishes it, with
the same motion as a master that took the shorter steps from the start. A discard the motion
causes says `fmi2Terminated` true and the recipe gives up. FMPy's `simulate_fmu` after a
discard ends the run and repeats the last successful row."""

import re

import numpy as np
import pytest
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave, fmi2Discard, fmi2LastSuccessfulTime, fmi2Terminated

from stewart_fmu import PLATFORM_FMU, ROOT, recording_callbacks

pytestmark = pytest.mark.quick


def readme_recipe():
    """The `step_with_retry` function exactly as docs/fmi-behaviour.md gives it."""
    text = (ROOT / "docs" / "fmi-behaviour.md").read_text()
    block = next(b for b in re.findall(r"```python\n(.*?)```", text, re.S) if "def step_with_retry" in b)
    code = block[: block.index("md = read_model_description")]
    namespace = {}
    exec(compile(code, "docs/fmi-behaviour.md", "exec"), namespace)
    return namespace["step_with_retry"]


def platform(name, messages, forces=None, stops=True):
    md = read_model_description(str(PLATFORM_FMU))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(PLATFORM_FMU)), modelIdentifier="StewartPlatform",
                    instanceName=name)
    fmu.instantiate(callbacks=recording_callbacks(messages))
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.setInteger([vr["solver.method"]], [2])
    fmu.setReal([vr["solver.fixedStep"]], [1e-6])
    # Without stops, the paper's idealised machine: no joint limits either.
    fmu.setBoolean([vr["stops"], vr["joints"]], [stops, stops])
    if forces is not None:
        fmu.setReal([vr[f"F[{k}]"] for k in range(1, 7)], list(forces))
    fmu.exitInitializationMode()
    return fmu, vr


def test_the_recipe_recovers_from_the_step_limit_and_matches_shorter_steps():
    step_with_retry = readme_recipe()
    forces = 5900.715 * (1 + 0.002 * np.arange(6))  # uneven: a real motion, not the equilibrium
    messages = []
    fmu, vr = platform("retry", messages, forces)
    with pytest.raises(FMICallException) as refused:
        fmu.doStep(0.0, 1.5)
    assert refused.value.status == fmi2Discard
    assert not fmu.getBooleanStatus(fmi2Terminated)
    assert fmu.getRealStatus(fmi2LastSuccessfulTime) == 0.0
    text = messages[-1][2]
    print(text)
    assert "needs 1.500e6 steps, more than the limit of 1000000 internal steps per call" in text
    assert "nothing was computed" in text
    fmu.terminate()
    fmu.freeInstance()

    fmu, vr = platform("retry", messages, forces)
    t = step_with_retry(fmu, 0.0, 1.5)
    outputs = [vr[n] for n in ("r[1]", "r[2]", "r[3]", "angles[1]", "angles[2]", "l[1]")]
    recovered = np.array(fmu.getReal(outputs))
    fmu.terminate()
    fmu.freeInstance()

    reference, _ = platform("halves", [], forces)
    reference.doStep(0.0, 0.75)
    reference.doStep(0.75, 0.75)
    expected = np.array(reference.getReal(outputs))
    reference.terminate()
    reference.freeInstance()
    print(f"recipe reached t = {t}; outputs {recovered}; difference to 2 x 0.75 s: "
          f"{np.max(np.abs(recovered - expected)):.1e}")
    assert t == 1.5
    assert np.array_equal(recovered, expected), "the retried steps are exactly the shorter steps"
    assert abs(recovered[2] - 1.9589244164161732) > 1e-6, "the platform moved"


def test_the_recipe_gives_up_when_the_motion_cannot_go_on():
    step_with_retry = readme_recipe()
    messages = []
    fmu, _ = platform("through", messages, forces=[-1.0e5] * 6, stops=False)
    with pytest.raises(FMICallException) as failed:
        step_with_retry(fmu, 0.0, 0.5)
    assert failed.value.status == fmi2Discard
    assert fmu.getBooleanStatus(fmi2Terminated)
    assert any("passed through the base plane" in m for _, _, m in messages)
    fmu.terminate()
    fmu.freeInstance()


def test_simulate_fmu_ends_the_run_at_a_discard_and_repeats_the_last_row():
    result = simulate_fmu(str(PLATFORM_FMU), stop_time=1.0, output_interval=0.05, output=["r[3]"],
                          start_values={"stops": False, "joints": False, **{f"F[{k}]": -1.0e5 for k in range(1, 7)}})
    print(f"simulate_fmu after a discard: rows {[(round(r[0], 3), round(r[1], 6)) for r in result]}")
    assert result["time"][-1] == result["time"][-2] == 0.1
    assert result["r[3]"][-1] == result["r[3]"][-2]
