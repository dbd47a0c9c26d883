"""The StewartController FMU coupled to the StewartPlatform FMU (issue: closed-loop system
co-simulation): the paper's feedback F = F^p + G (l^p - l) (+ D (ldot^p - ldot)) as a
component, in a Python master over two FMU2Slave instances and as an SSP system."""

import math

import numpy as np
import pytest
from fmpy.ssp.simulation import simulate_ssp
from fmpy.validation import validate_fmu

from stewart_fmu.cosim import CONTROLLER_FMU, SYSTEM_SSP, closed_loop
from stewart_fmu import bisect_boundary, stand_parameters
from references import check_figures

P = stand_parameters(nondimensional=True)
Z0 = P["r0[3]"]


def paper_controller(gain, damping, disturbance=1e-4, amplitude=0.2):
    """Controller parameters in the paper's units: the same stand, the heave programme
    0.2 sin t (1 - exp(-t/2))^2 and the perturbation 0.0001 sin 2t (1 - exp(-t/2))."""
    c = {k: v for k, v in P.items() if not k.startswith("r0") and k not in ("stops", "joints")}  # the controller has none of these
    c.update({"G": gain, "D": damping, "heave.centre[3]": Z0, "heave.amplitude": amplitude, "heave.frequency": 1.0,
              "heave.timeConstant": 2.0, "disturbance.amplitude": disturbance, "disturbance.frequency": 2.0,
              "disturbance.timeConstant": 2.0})
    return c


@pytest.mark.quick
def test_controller_fmu_validates():
    assert validate_fmu(str(CONTROLLER_FMU)) == []


@pytest.mark.quick
def test_default_gains_keep_every_leg_within_a_millimetre():
    """SI defaults: the paper's heave scaled to the default stand, 1 ms communication step."""
    t, rows, errors, status = closed_loop(10.0, 1e-3, record=("r[3]",))
    print(f"default controller + platform, 10 s at 1 ms (Gauss-Seidel): max |l - l^p| = {errors.max() * 1e3:.4f} mm, "
          f"heave range {np.ptp(rows[:, 0]):.3f} m")
    assert status == "ok"
    assert errors.max() < 1e-3
    assert 0.55 < np.ptp(rows[:, 0]) < 0.65  # a 0.3 m heave amplitude


def test_gain_table_with_and_without_damping():
    """Max leg-length tracking error over 0 <= t <= 40 (non-dimensional) with the paper's
    perturbation, communication step 0.002: the platform departs without feedback; the error
    falls as G grows above the critical gain (about 1), is growing below it, and damping
    helps. Without damping a large G lets the sampled loop's oscillations grow."""
    h = 0.002
    t0, _, e0, s0 = closed_loop(40.0, h, platform_reals=P, controller_reals=paper_controller(0.0, 0.0))
    table = {}
    for gain in (0.5, 2.0, 10.0, 100.0):
        for damping in (0.0, 0.5 * math.sqrt(gain)):
            t, _, e, s = closed_loop(40.0, h, platform_reals=P, controller_reals=paper_controller(gain, damping))
            table[(gain, damping > 0)] = (e.max(), e, s, damping)
    print(f"no feedback: max error {e0.max():.2e}, {s0[:40]} at t = {t0[-1]:.1f}")
    print("   G |  max error, D = 0 |  D    | max error, D = 0.5 sqrt(G)")
    for gain in (0.5, 2.0, 10.0, 100.0):
        undamped, damped = table[(gain, False)], table[(gain, True)]
        print(f"{gain:5} | {undamped[0]:17.2e} | {damped[3]:5.2f} | {damped[0]:.2e}")
    assert s0 != "ok" or e0.max() > 0.1  # without feedback the platform departs (paper Fig. 5)
    damped = [table[(g, True)][0] for g in (0.5, 2.0, 10.0, 100.0)]
    assert all(a > b for a, b in zip(damped, damped[1:])), "with damping the error falls as G grows"
    assert damped[-1] < 1e-5
    # Without damping: below the critical gain the error grows through the run...
    below = table[(0.5, False)][1]
    quarter = len(below) // 4
    assert below[-quarter:].max() > 10 * below[:quarter].max() and below.max() > 5e-3
    # ... above it the heave is tracked, better for G = 10 than for G = 2.
    assert table[(2.0, False)][0] < 1e-3 and table[(10.0, False)][0] < table[(2.0, False)][0]
    assert all(table[k][2] == "ok" for k in table)
    # The table docs/control.md quotes.
    check_figures("control.txt", "gains, G = 0: no feedback",
                  f"the platform departs: max leg-length error {e0.max():.2e}, "
                  + (f"a step discarded at t = {t0[-1]:.1f}" if s0 != "ok" else "no step discarded by t = 40"))
    for gain in (0.5, 2.0, 10.0, 100.0):
        undamped, damped = table[(gain, False)], table[(gain, True)]
        check_figures("control.txt", f"gains, G = {gain:g}: max leg-length error over 0..40 at step 0.002",
                      f"{undamped[0]:.2e} with D = 0, {damped[0]:.2e} with D = {damped[3]:.2f}")


def test_large_gain_tracks_even_without_programme_forces():
    """The paper: with a large enough G the programme is followed even with F^p = 0. The
    leg-length error is the static sag that makes the feedback carry the load, about 0.26/G
    (the programme force is 0.15..0.26): it falls like 1/G."""
    errors = {}
    for gain in (100.0, 1000.0):
        _, _, e, s = closed_loop(40.0, 0.002, platform_reals=P, controller_reals=paper_controller(gain, 0.5 * math.sqrt(gain), 0.0),
                                 controller_integers={"feedforward": 0})
        assert s == "ok"
        errors[gain] = e.max()
    print(f"F^p = 0: max error {errors[100.0]:.2e} at G = 100, {errors[1000.0]:.2e} at G = 1000; "
          f"G x error = {100 * errors[100.0]:.3f}, {1000 * errors[1000.0]:.3f}")
    for gain, error in errors.items():
        assert error < 0.3 / gain
    assert 8.0 < errors[100.0] / errors[1000.0] < 12.0


def test_communication_step_limits_stability():
    """For G = 10, D = 0.5 sqrt(10) (non-dimensional), the largest communication step that
    keeps the coupled loop stable, found by bisection; twice that step is unstable."""
    gain, damping = 10.0, 0.5 * math.sqrt(10.0)

    def stable(h):
        _, _, e, s = closed_loop(20.0, h, platform_reals=P, controller_reals=paper_controller(gain, damping, 0.0))
        return s == "ok" and e.max() < 0.01

    lo, hi = bisect_boundary(stable, 0.05, 1.0, 0.005)
    print(f"G = {gain}, D = {damping:.2f}: largest stable communication step {lo:.3f} (unstable at {hi:.3f}); "
          f"as a fraction of the closed loop's period: {lo * math.sqrt(6 * gain * 0.69) / (2 * math.pi):.2f}")
    assert 0.1 < lo < 0.5
    assert not stable(2 * lo)
    check_figures("control.txt", f"gains, G = {gain:g}, D = {damping:.2f}: largest stable communication step",
                  f"{lo:.2f} ({lo * math.sqrt(6 * gain * 0.69) / (2 * math.pi):.2f} of the closed loop's period), "
                  f"unstable at {2 * lo:.2f}")


def test_critical_gain_through_the_controller_fmu():
    """The closed loop around the neutral pose (programme amplitude 0) with a seeded tilt:
    below the critical gain the lateral+tilt mode grows, above it stays bounded."""
    seed = 1e-7
    seeded = dict(P, **{"angles0[1]": seed, "angles0[2]": -seed, "r0[1]": seed})

    def unstable(gain):
        t, rows, e, s = closed_loop(100.0, 0.01, platform_reals=seeded,
                                    controller_reals=paper_controller(gain, 0.0, 0.0, amplitude=0.0),
                                    record=("r[1]", "angles[1]", "angles[2]"))
        return s != "ok" or np.max(np.abs(rows[t > 80.0])) > 100 * seed

    lo, hi = bisect_boundary(unstable, 0.5, 2.0, 0.005)
    print(f"critical gain through the controller FMU (communication step 0.01): G_c = {0.5 * (lo + hi):.3f}")
    assert 0.9 < 0.5 * (lo + hi) < 1.1


@pytest.mark.quick
def test_ssp_run_and_python_master_agree():
    """FMPy's simulate_ssp on target/fmu/StewartSystem.ssp (SI defaults, 1 ms) and the Python
    master in its "jacobi" mode (FMPy's SSP algorithm) give the same trajectory."""
    result = simulate_ssp(str(SYSTEM_SSP), stop_time=2.0, step_size=1e-3)
    t, rows, errors, status = closed_loop(2.0, 1e-3, scheme="jacobi", record=("r[3]", "l[1]", "angles[1]"))
    n = len(t)
    ssp = np.column_stack([result["platform.r[3]"][:n], result["platform.l[1]"][:n], result["platform.angles[1]"][:n]])
    difference = np.max(np.abs(ssp - rows))
    gauss_seidel = closed_loop(2.0, 1e-3, record=("r[3]",))
    print(f"SSP vs Python master (Jacobi), 2 s at 1 ms: max difference {difference:.1e}; leg error "
          f"{errors.max() * 1e3:.3f} mm (Jacobi, connections start at 0), "
          f"{gauss_seidel[2].max() * 1e3:.4f} mm (Gauss-Seidel)")
    assert status == "ok" and n == 2000
    assert difference == 0.0
    assert errors.max() < 1e-3
