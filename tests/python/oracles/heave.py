"""The paper's heave programme (5.1) and its direct problem for the symmetric default stand,
non-dimensional, written out independently of the Rust code (the controller FMU's programme 1
and direct problem are the model's own)."""

import math

from .stand import H_C, NEUTRAL_Z, R_B, neutral_leg_geometry


def heave_programme(t, z0, a=0.2, omega=1.0, tc=2.0):
    """The paper's heave law (5.1) z = z0 + a sin(omega t)(1 - exp(-t/tc))^2 with its first
    and second derivatives (written out independently of the Rust code)."""
    e = math.exp(-t / tc)
    g, g1, g2 = (1 - e) ** 2, 2 * (e - e * e) / tc, 2 * (2 * e * e - e) / tc**2
    s, c = math.sin(omega * t), math.cos(omega * t)
    return (z0 + a * s * g, a * (omega * c * g + s * g1), a * (-omega * omega * s * g + 2 * omega * c * g1 + s * g2))


def heave_forces(t, z0=NEUTRAL_Z / R_B):
    """Direct problem for the pure heave of the symmetric default stand (non-dimensional):
    the six leg forces are equal, u = (z'' + g) / (6 n_z), n_z = H / l. Returns (u, du/dt, l, ldot)."""
    d, _ = neutral_leg_geometry()
    joint_offset = H_C / R_B

    def at(tt):
        z, zd, zdd = heave_programme(tt, z0)
        h = z - joint_offset
        l = math.hypot(d, h)
        return (zdd + 1.0) / (6.0 * h / l), l, h * zd / l

    u, l, ldot = at(t)
    eps = 1e-6
    du = (at(t + eps)[0] - at(t - eps)[0]) / (2 * eps)
    return u, du, l, ldot
