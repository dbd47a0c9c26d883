"""The linearisation (examples/linearise.py, through the FMU's directional derivatives)
explains the nonlinear model: its unstable heave eigenvalue is the growth rate of a small
heave in a nonlinear run, the paper's feedback stabilises above the critical gain and not
below, and that critical gain is the one the closed-loop simulations find."""

import math

import numpy as np
import pytest

from stewart_fmu.linearise import closed_loop, critical_gain, eigen_table, linearise, max_real_part
from stewart_fmu import EQUILIBRIUM_FORCE, Platform, bisect_boundary, stand_parameters
from oracles.heave import heave_forces
from references import check_figures

P = stand_parameters(nondimensional=True)


@pytest.mark.quick
def test_open_loop_eigenvalues_are_saddle_pairs_and_include_the_heave():
    lin = linearise()
    table = eigen_table(lin["A"])
    print("open-loop eigenvalues (non-dimensional):")
    for value, name in table:
        print(f"  {value.real:+.6f} {value.imag:+.6f}i  {name}")
    values = np.array([v for v, _ in table])
    # Constant forces: a conservative system at a saddle; every degree of freedom unstable.
    assert np.max(np.abs(values.imag)) < 1e-9
    assert np.sum(values.real > 1e-6) == 6 and np.sum(values.real < -1e-6) == 6
    assert lin["equilibrium_residual"] < 1e-12
    heave = [v.real for v, n in table if n == "heave z" and v.real > 0]
    assert len(heave) == 1
    # The fastest mode involves tilt (docs/model.md §6: a lateral + tilt mode, not the heave).
    fastest = table[0][1]
    assert "roll" in fastest or "pitch" in fastest
    check_figures("control.txt", "linearisation, open-loop eigenvalues (non-dimensional)",
                  ", ".join(f"{v.real:+.6f}" for v, _ in table))


def test_heave_eigenvalue_is_the_nonlinear_growth_rate():
    """A 1e-8 heave displacement from the neutral equilibrium, equilibrium forces, tight
    tolerance: z - z0 = a e^{lambda t} + b e^{-lambda t}; the fitted lambda matches the
    linearisation's heave eigenvalue to 1e-3 relative."""
    lin = linearise()
    heave_eigenvalue = max(v.real for v, n in eigen_table(lin["A"]) if n == "heave z")
    dz = 1e-8
    pl = Platform(parameters=dict(P, **{"r0[3]": P["r0[3]"] + dz, "solver.relTol": 1e-12, "solver.absTol": 1e-16}))
    pl.set_forces([EQUILIBRIUM_FORCE] * 6)
    t, z = [], []
    while pl.time < 14.0 - 1e-9:
        pl.step(0.05)
        t.append(pl.time)
        z.append(pl.get("r[3]")[0] - P["r0[3]"])
    pl.free()
    t, z = np.array(t), np.array(z)
    window = (t >= 6.0) & (t <= 14.0)
    # Least squares for a e^{lt} + b e^{-lt} with l scanned finely around the log slope.
    slope = np.polyfit(t[window], np.log(z[window]), 1)[0]
    best = None
    for lam in np.linspace(0.9 * slope, 1.1 * slope, 4001):
        basis = np.column_stack([np.exp(lam * t[window]), np.exp(-lam * t[window])])
        coef, res, *_ = np.linalg.lstsq(basis, z[window], rcond=None)
        err = np.sum((basis @ coef - z[window]) ** 2)
        if best is None or err < best[0]:
            best = (err, lam)
    growth = best[1]
    print(f"heave: eigenvalue {heave_eigenvalue:.6f}, nonlinear growth rate {growth:.6f} "
          f"(relative difference {abs(growth - heave_eigenvalue) / heave_eigenvalue:.1e}); z - z0 at t = 14: {z[-1]:.2e}")
    assert abs(growth - heave_eigenvalue) <= 1e-3 * heave_eigenvalue


@pytest.mark.quick
def test_closed_loop_is_marginally_stable_above_the_critical_gain_and_unstable_below():
    lin = linearise()
    g_c = critical_gain(lin)
    above = [max_real_part(closed_loop(lin, g)) for g in (1.01 * g_c, 1.5 * g_c, 2.0, 5.0, 20.0)]
    below = [max_real_part(closed_loop(lin, g)) for g in (0.0, 0.5 * g_c, 0.99 * g_c)]
    damped = max_real_part(closed_loop(lin, 2.0, 0.5))
    print(f"critical gain G_c = {g_c:.6f}; largest real part above: {max(above):.1e}, below: {min(below):.2e}; "
          f"G = 2 with D = 0.5: {damped:.3f}")
    assert max(above) <= 1e-9
    assert min(below) > 0
    assert damped < -0.01  # damping makes the stable loop asymptotically stable
    check_figures("control.txt", "linearisation, critical gain", f"G_c = {g_c:.6f}")


def test_critical_gain_matches_the_closed_loop_simulation():
    """The closed-loop simulation's critical gain (a seeded tilt grows below it, not above;
    feedback computed every 0.002 time units) within 2% of the linearisation's."""
    lin_gc = critical_gain(linearise())
    seed = 1e-7
    seeded = dict(P, **{"angles0[1]": seed, "angles0[2]": -seed, "r0[1]": seed})
    l0 = heave_forces(0.0)[2]

    def unstable(gain):
        pl = Platform(parameters=seeded)
        late = 0.0
        try:
            while pl.time < 60.0 - 1e-9:
                pl.set_forces(EQUILIBRIUM_FORCE + gain * (l0 - pl.vector("l", 6)))
                pl.step(0.002)
                if pl.time > 45.0:
                    late = max(late, float(np.max(np.abs(pl.vector("angles", 3)))))
        except Exception:
            late = math.inf
        pl.free()
        return late > 100 * seed

    lo, hi = bisect_boundary(unstable, 0.9 * lin_gc, 1.1 * lin_gc, 0.002)
    sim_gc = 0.5 * (lo + hi)
    print(f"critical gain: linearisation {lin_gc:.4f}, closed-loop simulation {sim_gc:.4f} "
          f"(relative difference {abs(sim_gc - lin_gc) / lin_gc:.1e})")
    assert abs(sim_gc - lin_gc) <= 0.02 * lin_gc
    check_figures("control.txt", "linearisation, closed-loop simulation's critical gain",
                  f"{sim_gc:.4f} ({abs(sim_gc - lin_gc) / lin_gc * 100:.1f} % from the linearisation's)")
