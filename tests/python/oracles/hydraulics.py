"""The hydraulic servo legs of docs/model.md §10 (each leg a differential cylinder fed by a
servo valve) written out from the document, independently of the FMU's code: the areas, the
valve's flow coefficient, the chambers' volumes, the default stand's holding pressures, the
leakage at a centred spool and the creep of a locked leg. `p`: the parameters by FMI name with
`lmin[1]`, `lmax[1]` (`stewart_fmu.hydraulics.hydraulic_parameters()`, the FMU's start values)."""

import math

from .stand import EQUILIBRIUM_FORCE, GRAVITY, MASS, neutral_leg_geometry

ATMOSPHERE = 101325.0  # Pa: absolute = gauge + this; zero absolute is this far below zero gauge (§10b)


def areas(p):
    """`(A_A, A_B)`, m²."""
    d, rod = p["hydraulic.bore"], p["hydraulic.rod"]
    return math.pi * d * d / 4.0, math.pi * (d * d - rod * rod) / 4.0


def flow_coefficient(p):
    """`K = Q_N / sqrt(dp_N / 2)`."""
    return p["valve.ratedFlow"] / math.sqrt(p["valve.ratedPressureDrop"] / 2.0)


def volumes(l, p):
    """`(V_A, V_B)`, m³, of a leg of length `l`."""
    area_a, area_b = areas(p)
    x = l - p["lmin[1]"]
    return p["hydraulic.deadVolumeA"] + area_a * x, p["hydraulic.deadVolumeB"] + area_b * (p["lmax[1]"] - p["lmin[1]"] - x)


def holding_pressures(p):
    """The default stand's holding pressures at its neutral pose: `p_B = p_S / 2`, and the cap
    side pushing `0.2005 M g` (docs/model.md §3) with it."""
    area_a, area_b = areas(p)
    pb = p["pS"] / 2.0
    return (EQUILIBRIUM_FORCE * MASS * GRAVITY + pb * area_b) / area_a, pb


def leakage_flows(pa, pb, p, supply=None):
    """The leakage into each chamber at a centred spool (§10: each land's null leakage to
    supply and to tank, the piston's internal leakage): `(Q_A, Q_B)`, m³/s."""
    ps = p["pS"] if supply is None else supply
    pt, cv, ci = p["hydraulic.tankPressure"], p["valve.leakage"], p["hydraulic.internalLeakage"]
    internal = ci * (pa - pb)
    return cv * (ps - pa) - cv * (pa - pt) - internal, cv * (ps - pb) - cv * (pb - pt) + internal


def quasi_static_creep(pa, pb, l, p, supply=None):
    """The leg rate (m/s) at which a locked leg (spool centred) creeps on its leakage while it
    keeps carrying its load: the force `p_A A_A - p_B A_B` constant, so `A_A p_A' = A_B p_B'`
    with `p_A' = beta/V_A (Q_A - A_A v)`, `p_B' = beta/V_B (Q_B + A_B v)`:
    `v = (A_A Q_A / V_A - A_B Q_B / V_B) / (A_A^2 / V_A + A_B^2 / V_B)`."""
    area_a, area_b = areas(p)
    va, vb = volumes(l, p)
    qa, qb = leakage_flows(pa, pb, p, supply)
    return (area_a * qa / va - area_b * qb / vb) / (area_a * area_a / va + area_b * area_b / vb)


def heave_rate_of_leg_rate(l):
    """`z'` per unit leg rate in pure heave at leg length `l`: the legs' vertical direction
    cosine is `n_z = H / l`, `l' = n_z z'`."""
    d, _ = neutral_leg_geometry(nondimensional=False)
    height = math.sqrt(max(l * l - d * d, 0.0))
    return l / height
