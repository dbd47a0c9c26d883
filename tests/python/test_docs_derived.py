"""The figures docs/model.md works out by hand from the defaults (the drives' conversions
along a leg, the cylinder's forces, the heave programme's legs, the accumulator's sizing,
the rest on the stops), computed here from the committed model descriptions' start values
with the stand's geometry written out (leg vectors `r + A_k - B_k` at the neutral
orientation, the statics `sum F_k n_k = M g ez`, `sum A_k x F_k n_k = 0`), and recorded in
benches/results/model.txt, which test_readme.py holds the page's quotes to. A default that
moves in the code moves these lines, and the page's figures with them."""

import math

import numpy as np
import pytest

from oracles import heave as oracle_heave
from oracles import hydraulics as oracle
from references import check_figures, short, start_values

pytestmark = pytest.mark.quick

PLATFORM, CONTROLLER = start_values("StewartPlatform"), start_values("StewartController")
STEEL = 7850.0  # kg/m3


def joints(name):
    return np.array([[PLATFORM[f"{name}[{k},{i}]"] for i in (1, 2, 3)] for k in range(1, 7)])


B, A = joints("B"), joints("A")
M, G = PLATFORM["M"], PLATFORM["g"]


def legs(z):
    """The six leg vectors and lengths with the centre of mass at height z, level."""
    vectors = np.array([0.0, 0.0, z]) + A - B
    return vectors, np.linalg.norm(vectors, axis=1)


def holding_forces(z):
    """The legs' axial forces that hold the platform at rest at height z, level."""
    vectors, lengths = legs(z)
    n = vectors / lengths[:, None]
    matrix = np.vstack([n.T, np.cross(A, n).T])
    return np.linalg.solve(matrix, np.array([0.0, 0.0, M * G, 0.0, 0.0, 0.0]))


def heave_programme(t):
    """z, z', z'' of the controller's default heave programme over the times `t`: the §6 law of
    the oracle (`oracles.heave`) with the controller's start values."""
    law = np.vectorize(lambda time: oracle_heave.heave_programme(
        time, CONTROLLER["heave.centre[3]"], CONTROLLER["heave.amplitude"], CONTROLLER["heave.frequency"],
        CONTROLLER["heave.timeConstant"]))
    return law(t)


def heave_legs():
    """Over the heave programme's first 10 s: the centre of mass's height, leg 1's length and
    the vertical share of its direction (symmetric: all six legs alike), z' and z''."""
    t = np.linspace(0.0, 10.0, 100_001)
    z, z_dot, z_ddot = heave_programme(t)
    offset = A[0] - B[0]
    lengths = np.sqrt(offset[0] ** 2 + offset[1] ** 2 + (z + offset[2]) ** 2)
    return z, lengths, (z + offset[2]) / lengths, z_dot, z_ddot


def test_the_stand_and_its_heave_programme():
    # Symmetric: all six legs alike, so leg 1 speaks for each.
    hold = holding_forces(PLATFORM["r0[3]"])
    assert np.ptp(hold) < 1e-9 * hold[0]
    z, lengths, n_z, z_dot, z_ddot = heave_legs()
    speed = np.max(np.abs(n_z * z_dot))
    # Pure heave, massless legs: each leg carries a sixth of M (z'' + g) along its vertical share.
    force = M * (z_ddot + G) / (6 * n_z)
    lmin, lmax = PLATFORM["lmin[1]"], PLATFORM["lmax[1]"]
    assert lmin < lengths.min() < lengths.max() < lmax, "the heave programme stays clear of the stops"
    # At rest on the lower stops: the legs at lmin, pressed in by the holding force over k_s.
    offset = A[0] - B[0]
    low = math.sqrt(lmin**2 - offset[0] ** 2 - offset[1] ** 2) - offset[2]
    rest = holding_forces(low)[0]
    depth = rest / PLATFORM["stops.stiffness"]
    assert 0 < depth < 1e-3
    check_figures("model.txt", "the default stand from its parameters (test_docs_derived.py)",
                  f"each leg holds {hold[0] / (M * G):.4f} M g = {hold[0]:.1f} N at the neutral pose and "
                  f"{rest:.0f} N on the lower stops ({lmin} m), {depth * 1e3:.2f} mm into them; the heave "
                  f"programme (10 s) moves the centre of mass over {z.min():.3f} .. {z.max():.3f} m and the legs "
                  f"over {lengths.min():.2f} .. {lengths.max():.2f} m (stops {lmin}, {lmax}), the fastest at "
                  f"{speed:.2f} m/s, the most loaded with {force.max() / 1e3:.1f} kN")


def test_the_drives_along_a_leg():
    n = 2 * math.pi * PLATFORM["gear.ratio"] / PLATFORM["screw.lead"]  # rad of the motor per m of the leg
    ke, kt = PLATFORM["motor.ke"], PLATFORM["motor.kt"]
    hold = holding_forces(PLATFORM["r0[3]"])[0]
    _, _, n_z, z_dot, _ = heave_legs()
    speed = np.max(np.abs(n_z * z_dot))
    rpm = 60 / (2 * math.pi)
    # A solid steel screw of 32 mm and 1 m: the rest of motor.J is the rotor's.
    screw = STEEL * math.pi * 0.016**2 * 1.0 * 0.016**2 / 2
    assert 0 < screw < PLATFORM["motor.J"]
    check_figures("model.txt", "the drives along a leg from their parameters (test_docs_derived.py)",
                  f"N = {n:.2f} rad/m; motor.J N^2 = {PLATFORM['motor.J'] * n * n:.0f} kg and motor.D N^2 = "
                  f"{PLATFORM['motor.D'] * n * n:.0f} N.s/m along each leg (a 32 mm x 1 m steel screw "
                  f"{screw * 1e3:.1f}e-3 kg.m2, the rotor {(PLATFORM['motor.J'] - screw) * 1e3:.1f}e-3); "
                  f"{ke * 1000 / rpm:.0f} V per 1000 rpm, 300 V at {300 / ke * rpm:,.0f} rpm; the heave programme's "
                  f"fastest leg ({speed:.2f} m/s) turns the motor at {speed * n * rpm:,.0f} rpm; holding current "
                  f"{hold / (n * kt):.2f} A ({hold / (M * G):.4f} M g per leg)")


def test_the_cylinder_and_the_accumulator():
    # The areas, the valve's coefficient and the chambers as the §10 oracle writes them.
    cap, annulus = oracle.areas(PLATFORM)
    supply = PLATFORM["pS"]
    # The landing from the top of the heave to the controller's landing.floor fills the rod sides.
    top = CONTROLLER["heave.centre[3]"] + CONTROLLER["heave.amplitude"]
    floor = CONTROLLER["landing.floor"]
    l_top, l_floor = legs(top)[1][0], legs(floor)[1][0]
    landing = 6 * annulus * (l_top - l_floor)
    # The accumulator's gas between absolute pressures: V0 ((P0/P2)^(1/n) - (P0/P1)^(1/n)).
    v0, p0, n = (PLATFORM[f"accumulator.{x}"] for x in ("volume", "precharge", "polytropic"))
    trigger = 12e6 + oracle.ATMOSPHERE  # examples/power_unit_scenarios.py's landing.pressure, absolute
    lowest = p0 / 0.9  # the precharge is 90 % of the lowest pressure the landing works down to
    charged = PLATFORM["pump.setPressure"] + PLATFORM["pump.compensatorBand"] + oracle.ATMOSPHERE

    def delivered(high, low):
        return v0 * ((p0 / low) ** (1 / n) - (p0 / high) ** (1 / n))

    below, above = delivered(trigger, lowest), delivered(charged, trigger)
    assert below > landing, "the accumulator holds the landing below the trigger"
    # The chambers at mid-stroke and with the leg at lmin.
    beta, k = PLATFORM["hydraulic.bulkModulus"], oracle.flow_coefficient(PLATFORM)
    lmin, lmax = PLATFORM["lmin[1]"], PLATFORM["lmax[1]"]
    (v_a, v_b), at_lmin = oracle.volumes((lmin + lmax) / 2, PLATFORM), oracle.volumes(lmin, PLATFORM)
    # An open land near p_cr: the real pole beta K / (V sqrt(p_cr)), fastest in the smaller
    # chamber; the force's answer to the valve, beta K sqrt(p_S/2) (A_A/V_A + A_B/V_B), and the
    # force loop's crossover kF times it.
    poles = [beta * k / (min(v) * math.sqrt(PLATFORM["valve.pcr"])) for v in ((v_a, v_b), at_lmin)]
    gain = beta * k * math.sqrt(supply / 2) * (cap / v_a + annulus / v_b)
    crossover = CONTROLLER["hydraulic.forceGain"] * gain
    assert poles[1] > poles[0] and 0 < crossover < PLATFORM["valve.omega"]
    check_figures("model.txt", "the cylinder and the accumulator from their parameters (test_docs_derived.py)",
                  f"{supply * cap / 1e3:.1f} kN extending, {supply * annulus / 1e3:.1f} kN retracting at "
                  f"{supply / 1e6:.0f} MPa; the landing from the heave's top ({top:.2f} m, legs {l_top:.3f} m) to "
                  f"landing.floor ({floor:.3f} m, legs {l_floor:.3f} m) fills the rod sides with "
                  f"{landing * 1e3:.1f} L; {v0 * 1e3:.0f} L precharged to {p0 / 1e6:.0f} MPa hold {below * 1e3:.1f} L "
                  f"between {trigger / 1e6:.1f} and {lowest / 1e6:.1f} MPa absolute and {above * 1e3:.1f} L from "
                  f"{charged / 1e6:.1f} MPa down to the trigger; an open land's pole {short(poles[0])} /s at "
                  f"mid-stroke (the rod side), {short(poles[1])} /s at lmin (the cap side); the force's answer to "
                  f"the valve {short(gain)} N/s per unit opening at mid-stroke, the force loop's crossover "
                  f"{crossover:.0f} rad/s")
