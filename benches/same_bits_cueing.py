"""Two builds of the cueing FMU, output by output and bit by bit: every Real output both
declare, with both methods, through FMPy (stewart_fmu.cueing.run): the manoeuvres of
stewart_fmu.vehicle.MANOEUVRES at the defaults and (classical) at unit scaling, and three fuzzed
drives at unit scaling, where the workspace limiter acts (workspace.scale down to about 0.44).
The classical washout at 1 ms steps, predictive cueing at 10 ms. How a change that should not
touch the cueing's numbers is checked (the limiter's speed-ups of 3ea53c8 and 1ae55ac: 0
differing values); about half a minute.

    .venv/bin/python benches/same_bits_cueing.py OLD/StewartCueing.fmu NEW/StewartCueing.fmu
"""
import sys

import numpy as np
from fmpy import read_model_description

from stewart_fmu import cueing, vehicle

UNIT_SCALING = {**{f"scale.f[{k}]": 1.0 for k in (1, 2, 3)}, **{f"scale.omega[{k}]": 1.0 for k in (1, 2, 3)}}


def cases(method):
    """(name, manoeuvre, Real parameters) of one method."""
    for name, make in vehicle.MANOEUVRES.items():
        yield name, make(), None
        if method == 0:
            yield name + ", unit scaling", make(), UNIT_SCALING
    for seed in range(3):
        yield f"fuzzed {seed}, unit scaling", vehicle.random_manoeuvre(seed), UNIT_SCALING


def main(old, new):
    names = {v.name for v in read_model_description(old).modelVariables}
    outputs = [v.name for v in read_model_description(new).modelVariables
               if v.type == "Real" and v.causality == "output" and v.name in names]
    total = 0
    for method, h in ((0, 1e-3), (1, 1e-2)):
        for name, manoeuvre, parameters in cases(method):
            a, b = (cueing.run(manoeuvre, h=h, parameters=parameters, record=outputs, fmu=fmu,
                               integers={"cueing.method": method}) for fmu in (old, new))
            differing = sum(int(np.sum(a[n].view(np.int64) != b[n].view(np.int64))) for n in outputs)
            total += differing
            print(f"method {method}, {name:26s} {len(a['time']):6d} rows x {len(outputs)} outputs: {differing} differing "
                  f"values (workspace.scale down to {np.min(a['workspace.scale']):.3f})", flush=True)
    print(f"differing values in all: {total}")
    return total


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    sys.exit(1 if main(sys.argv[1], sys.argv[2]) else 0)
