"""The rigid-leg regression: four motions of the paper's machine (massless legs, no friction)
through a platform FMU, sampled every 0.1 s, as exact bits. `tests/data/rigid_legs_db183c0_libm.json`
holds them as the release before the machine (legs as bodies, joint limits, friction) computed
them (commit db183c0, whose FMUs wrote it with this file's `main`), with its elementary
functions taken from the libm crate as the FMU's are since they give every platform the same
bits (`tests/data/rigid_legs_db183c0_libm.patch`: db183c0's calls of `sin`, `exp`, `pow`, ...
replaced one for one, nalgebra's `libm-force`); test_machine.py checks that the FMU still
computes them to the bit, with the joint limits off and, where no joint reaches its limit, on.

To write the file again: `git worktree add /tmp/old db183c0 && cd /tmp/old && git apply
.../tests/data/rigid_legs_db183c0_libm.patch && cargo run --release --bin build-fmu`, then

    .venv/bin/python tests/python/rigid_legs.py /tmp/old/target/fmu/StewartPlatform.fmu \
        /tmp/old/target/fmu/StewartController.fmu tests/data/rigid_legs_db183c0_libm.json
"""

import json
import math
import sys

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

RECORD = (["r[1]", "r[2]", "r[3]", "E", "work.F", "work.dissipated"]
          + [f"R[{a},{b}]" for a in range(1, 4) for b in range(1, 4)]
          + [f"l[{k}]" for k in range(1, 7)] + [f"ldot[{k}]" for k in range(1, 7)] + [f"Fstop[{k}]" for k in range(1, 7)])
EQUILIBRIUM = 0.2005 * 3000.0 * 9.81
SAMPLE = 0.1


class Slave:
    def __init__(self, path, name, reals=None, booleans=None):
        md = read_model_description(path)
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self.fmu = FMU2Slave(guid=md.guid, unzipDirectory=extract(path), modelIdentifier=md.coSimulation.modelIdentifier,
                             instanceName=name)
        self.fmu.instantiate()
        self.fmu.setupExperiment(startTime=0.0)
        self.fmu.enterInitializationMode()
        for n, x in (booleans or {}).items():
            if n in self.vr:  # the old release has no `joints`
                self.fmu.setBoolean([self.vr[n]], [x])
        for n, x in (reals or {}).items():
            self.fmu.setReal([self.vr[n]], [x])
        self.fmu.exitInitializationMode()

    def get(self, names):
        return self.fmu.getReal([self.vr[n] for n in names])

    def set(self, names, values):
        self.fmu.setReal([self.vr[n] for n in names], list(values))

    def free(self):
        self.fmu.terminate()
        self.fmu.freeInstance()


F = [f"F[{k}]" for k in range(1, 7)]
L = [f"l[{k}]" for k in range(1, 7)]
LDOT = [f"ldot[{k}]" for k in range(1, 7)]


def open_loop(platform_fmu, forces, t_end, h, booleans):
    p = Slave(platform_fmu, "rigid", booleans=booleans)
    rows, n, every = [p.get(RECORD)], int(round(t_end / h)), int(round(SAMPLE / h))
    for i in range(n):
        p.set(F, forces(i * h))
        p.fmu.doStep(currentCommunicationPoint=i * h, communicationStepSize=h)
        if (i + 1) % every == 0:
            rows.append(p.get(RECORD))
    p.free()
    return rows


def heave(platform_fmu, controller_fmu, joints=True, t_end=3.0, h=1e-3):
    """The closed loop (Gauss-Seidel) on the controller's default heave programme."""
    p = Slave(platform_fmu, "rigid", booleans={"joints": joints})
    c = Slave(controller_fmu, "controller")
    rows, n, every = [p.get(RECORD)], int(round(t_end / h)), int(round(SAMPLE / h))
    for i in range(n):
        c.set(L + LDOT, p.get(L) + p.get(LDOT))
        p.set(F, c.get(F))
        p.fmu.doStep(currentCommunicationPoint=i * h, communicationStepSize=h)
        c.fmu.doStep(currentCommunicationPoint=i * h, communicationStepSize=h)
        if (i + 1) % every == 0:
            rows.append(p.get(RECORD))
    p.free()
    c.free()
    return rows


def motions(platform_fmu, controller_fmu, joints):
    """The four motions; `joints` is the joint limits' switch where they may stay on (no
    joint reaches its limit); the ripple tips the platform, so it runs without them."""
    return {
        "heave": heave(platform_fmu, controller_fmu, joints),
        "power loss": open_loop(platform_fmu, lambda t: [EQUILIBRIUM if t < 0.5 - 1e-12 else 0.0] * 6, 2.0, 1e-3,
                                {"joints": joints}),
        "tumble": open_loop(platform_fmu,
                            lambda t: [EQUILIBRIUM * (1.05 + 0.5 * math.sin(2.0 * t + 1.1 * k)) for k in range(6)],
                            2.0, 1e-2, {"stops": False, "joints": False}),
        "ripple": open_loop(platform_fmu,
                            lambda t: [EQUILIBRIUM * (1.0 + 0.05 * math.sin(2.0 * t + k)) for k in range(1, 7)],
                            1.6, 1e-3, {"joints": False}),
    }


def bits(rows):
    return [[float(x).hex() for x in row] for row in rows]


def main():
    platform_fmu, controller_fmu, out = sys.argv[1:4]
    data = {name: bits(rows) for name, rows in motions(platform_fmu, controller_fmu, joints=False).items()}
    with open(out, "w") as f:
        json.dump({"record": RECORD, "sample": SAMPLE, "motions": data}, f, indent=0)


if __name__ == "__main__":
    main()
