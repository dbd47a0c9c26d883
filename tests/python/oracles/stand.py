"""The default stand of docs/model.md §3, the truck-cabin stand, written out from the document:
base joints on a 1.5 m circle, platform joints on a 1.0 m circle 0.5 m below the centre of
mass, at the azimuths below; M = 3000 kg, J = (1500, 1500, 2200) kg m², g = 9.81 m/s²; the
neutral pose's centre of mass at the height where each leg carries 0.2005 M g. The package
reads the stand from the FMU's model description (`stewart_fmu.default_stand`);
tests/python/test_stand.py holds the two equal.
"""

import math

R_B, R_P, H_C = 1.5, 1.0, 0.5
BASE_AZIMUTHS = [-10, 10, 110, 130, 230, 250]
PLATFORM_AZIMUTHS = [-50, 50, 70, 170, 190, 290]
MASS, INERTIA, GRAVITY = 3000.0, (1500.0, 1500.0, 2200.0), 9.81
NEUTRAL_Z = 1.9589244164161732
EQUILIBRIUM_FORCE = 0.2005  # units of M g


def stand_parameters(nondimensional=True):
    """FMI parameter values of the default stand, in the paper's units (R_b, M, M g,
    sqrt(R_b/g)) or in SI (without the end stops' and joint limits' switches)."""
    length = R_B if nondimensional else 1.0
    mass = MASS if nondimensional else 1.0
    p = {"M": MASS / mass, "g": 1.0 if nondimensional else GRAVITY, "r0[1]": 0.0, "r0[2]": 0.0,
         "r0[3]": NEUTRAL_Z / length}
    for a, j in enumerate(INERTIA):
        p[f"J[{a + 1}]"] = j / (mass * length * length)
    for k in range(6):
        pb, pp = math.radians(BASE_AZIMUTHS[k]), math.radians(PLATFORM_AZIMUTHS[k])
        for i, x in enumerate((R_B * math.cos(pb), R_B * math.sin(pb), 0.0)):
            p[f"B[{k + 1},{i + 1}]"] = x / length
        for i, x in enumerate((R_P * math.cos(pp), R_P * math.sin(pp), -H_C)):
            p[f"A[{k + 1},{i + 1}]"] = x / length
    return p


def neutral_leg_geometry(nondimensional=True):
    """Horizontal leg projection d and platform joint plane height H0 of the neutral pose."""
    length = R_B if nondimensional else 1.0
    pb, pp = math.radians(BASE_AZIMUTHS[0]), math.radians(PLATFORM_AZIMUTHS[0])
    dx = R_P * math.cos(pp) - R_B * math.cos(pb)
    dy = R_P * math.sin(pp) - R_B * math.sin(pb)
    return math.hypot(dx, dy) / length, (NEUTRAL_Z - H_C) / length
