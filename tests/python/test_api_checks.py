"""The Python API refuses wrong input with a ValueError naming it (issue 28, items 3 and 7),
before anything runs: `cosim.closed_loop` with a step or end time that is not positive and
finite or an unknown scheme (it returned 'ok' with no rows, or the scheme's name as its
status), unknown names in `platform_reals` and the like (ignored), `Platform().set_forces`
with other than six forces (padded with zeros), and names `Platform` does not have."""

import math

import numpy as np
import pytest

from stewart_fmu import Platform
from stewart_fmu.cosim import closed_loop
from stewart_fmu.workspace import power_loss, start_values

pytestmark = pytest.mark.quick


@pytest.mark.parametrize("args, kwargs, expected", [
    ((0.05, -0.01), {}, "h = -0.01"),
    ((0.05, 0.0), {}, "h = 0.0"),
    ((0.05, math.nan), {}, "h = nan"),
    ((-1.0, 0.01), {}, "t_end = -1.0"),
    ((math.inf, 0.01), {}, "t_end = inf"),
    ((0.05, 0.2), {}, "h = 0.2 is longer than t_end = 0.05"),
    ((0.05, 0.01), {"scheme": "bogus"}, "scheme = 'bogus'"),
    ((0.05, 0.01), {"platform_reals": {"stopz": False}}, "platform_reals: StewartPlatform has no variable 'stopz'; "
                                                          "did you mean 'stops'?"),
    ((0.05, 0.01), {"controller_reals": {"GG": 1.0}}, "controller_reals: StewartController has no variable 'GG'"),
    ((0.05, 0.01), {"controller_integers": {"programme": 2.5}}, "controller_integers: programme = 2.5"),
    ((0.05, 0.01), {"record": ("r[3]", "r[4]")}, "record: StewartPlatform has no variable 'r[4]'"),
])
def test_closed_loop_refuses_wrong_arguments_before_anything_runs(args, kwargs, expected):
    with pytest.raises(ValueError) as refused:
        result = closed_loop(*args, **kwargs)
        print(f"accepted: status {result[3]!r}, {len(result[0])} rows")
    print(f"closed_loop{args} {kwargs}: {refused.value}")
    assert expected in str(refused.value)


def test_a_force_hook_that_returns_the_wrong_number_of_forces_is_refused():
    with pytest.raises(ValueError, match=r"force_hook's forces: 6 values \(F\[1\] \.\. F\[6\]\) are expected, got 5"):
        closed_loop(0.05, 0.01, force_hook=lambda t, forces: forces[:5])


def test_closed_loop_still_runs_right_arguments():
    t, rows, errors, status = closed_loop(0.05, 0.01, scheme="jacobi", platform_reals={"stops": True},
                                          controller_integers={"programme": 1})
    assert status == "ok" and len(t) == 5 and rows.shape == (5, 1)


@pytest.mark.parametrize("forces, expected", [
    ([1.0, 2.0], "forces: 6 values (F[1] .. F[6]) are expected, got 2"),
    ([1.0] * 7, "got 7"),
    (np.ones((2, 3)), "shape (2, 3)"),
    ([1.0, 2.0, 3.0, 4.0, 5.0, math.nan], "F[6] = nan is not a finite number"),
    (["a"] * 6, "6 numbers (F[1] .. F[6]) are expected"),
])
def test_set_forces_refuses_anything_but_six_finite_forces(forces, expected):
    platform = Platform()
    try:
        before = platform.vector("F", 6)
        with pytest.raises(ValueError) as refused:
            platform.set_forces(forces)
        assert expected in str(refused.value)
        np.testing.assert_array_equal(platform.vector("F", 6), before)  # nothing was set
        with pytest.raises(ValueError, match=r"rates: 6 values"):
            platform.set_forces([1.0] * 6, rates=[0.0])
    finally:
        platform.free()


def test_platform_refuses_names_it_does_not_have():
    with pytest.raises(ValueError, match=r"parameters: StewartPlatform has no variable 'Mass'"):
        Platform(parameters={"Mass": 3000.0})
    with pytest.raises(ValueError, match=r"integers: StewartPlatform has no variable 'solver.methd'; "
                                         r"did you mean 'solver.method'\?"):
        Platform(integers={"solver.methd": 2})
    with pytest.raises(ValueError, match=r"parameters: stops = 'no': true or false is expected"):
        Platform(parameters={"stops": "no"})
    platform = Platform()
    try:
        with pytest.raises(ValueError, match=r"get: StewartPlatform has no variable 'r\[4\]'; did you mean 'r\[3\]'"):
            platform.get("r[4]")
        with pytest.raises(ValueError, match=r"set: StewartPlatform has no variable 'MM'"):
            platform.set({"MM": 1.0})
        with pytest.raises(ValueError, match=r"step: h = -0.01"):
            platform.step(-0.01)
        assert platform.time == 0.0
    finally:
        platform.free()


def test_workspace_scenarios_refuse_bad_steps_and_names():
    with pytest.raises(ValueError, match=r"h = -0.001"):
        power_loss(h=-1e-3)
    with pytest.raises(ValueError, match=r"start_values: StewartPlatform has no variable 'lmin\[7\]'"):
        start_values(["lmin[7]"])
