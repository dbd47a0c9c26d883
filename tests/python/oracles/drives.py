"""The electric drive of docs/model.md §9 (a DC motor turning a ball screw in each leg) written
out from the document, independently of the FMU's code: the transmission, the static model,
the holding current and voltage of the default stand, the braking with shorted windings and
the quasi-static descent it allows. `p`: the drive's parameters by FMI name
(`stewart_fmu.drives.drive_parameters()`, the FMU's start values)."""

import math

from .stand import EQUILIBRIUM_FORCE, GRAVITY, H_C, MASS, neutral_leg_geometry


def transmission(p):
    """N = 2 pi i / p, rad/m."""
    return 2.0 * math.pi * p["gear.ratio"] / p["screw.lead"]


def static_drive(force, l_dot, p):
    """The drive's static model (docs/model.md §9): current I = u / (N k_t) and voltage
    U = R I + k_e N l' for the axial force u at the leg rate l'."""
    n = transmission(p)
    current = force / (n * p["motor.kt"])
    return current, current * p["motor.R"] + p["motor.ke"] * n * l_dot


def holding(p):
    """The holding current and voltage of the default stand at its neutral pose: each leg
    carries 0.2005 M g (docs/model.md §3)."""
    return static_drive(EQUILIBRIUM_FORCE * MASS * GRAVITY, 0.0, p)


def braking_damping(p):
    """With the windings shorted (U = 0) and the current settled, a leg moving at l' feels the
    force -c l', c = N^2 (k_t k_e / R + D), N.s/m."""
    n = transmission(p)
    return n * n * (p["motor.kt"] * p["motor.ke"] / p["motor.R"] + p["motor.D"])


def quasi_static_descent_rate(z, p):
    """The heave rate z' (m/s, negative) at which the default stand, in pure heave at centre-of-
    mass height z, sinks with its six drives braking: each leg's braking force c l' balances the
    leg force u = M g / (6 n_z) that holds the weight (n_z = H / l the leg's vertical direction
    cosine, H = z - h_c the joint plane's height, l = sqrt(d^2 + H^2)); with l' = n_z z',
    z' = -M g / (6 c n_z^2)."""
    d, _ = neutral_leg_geometry(nondimensional=False)
    height = z - H_C
    n_z = height / math.hypot(d, height)
    return -MASS * GRAVITY / (6.0 * braking_damping(p) * n_z * n_z)
