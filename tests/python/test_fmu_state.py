"""FMU state round trips (the FMI analogue of rapier's snapshot test): get, step, set back,
step again reproduces bit for bit; serialized bytes continue bit for bit in a fresh process;
a state can be restored after fmi2Terminate and after fmi2Reset."""

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from stewart_fmu import EQUILIBRIUM_FORCE, Platform, stand_parameters

pytestmark = pytest.mark.quick

P = stand_parameters(nondimensional=True)
OUTPUTS = [f"r[{i}]" for i in (1, 2, 3)] + [f"R[{a},{b}]" for a in (1, 2, 3) for b in (1, 2, 3)] + \
          [f"l[{k}]" for k in range(1, 7)] + [f"ldot[{k}]" for k in range(1, 7)] + ["E", "constraintError"]


def drive(pl, until, h=0.01):
    """Sinusoidal leg forces with first-order interpolation; returns the outputs after each step."""
    rows = []
    while pl.time < until - 1e-9:
        t = pl.time
        f = [EQUILIBRIUM_FORCE + 1e-3 * math.sin(1.3 * t + k) for k in range(6)]
        df = [1.3e-3 * math.cos(1.3 * t + k) for k in range(6)]
        pl.set_forces(f, df)
        pl.step(h)
        rows.append(pl.get(*OUTPUTS))
    return np.array(rows)


def test_get_step_set_step_is_bit_exact():
    pl = Platform(parameters=P)
    drive(pl, 1.0)
    state = pl.slave.getFMUstate()
    t_saved = pl.time
    first = drive(pl, 3.0)
    pl.slave.setFMUstate(state)
    pl.time = t_saved
    second = drive(pl, 3.0)
    pl.slave.freeFMUstate(state)
    pl.free()
    assert first.shape == second.shape == (200, len(OUTPUTS))
    assert np.array_equal(first, second)  # bit for bit, not to a tolerance
    assert np.ptp(first[:, 2]) > 1e-6  # the platform moves


def test_state_restored_after_terminate_and_after_reset():
    pl = Platform(parameters=P)
    drive(pl, 1.0)
    state = pl.slave.getFMUstate()
    t_saved = pl.time
    reference = drive(pl, 2.0)
    pl.slave.terminate()
    pl.slave.setFMUstate(state)  # legal in the terminated state; brings back stepComplete
    pl.time = t_saved
    after_terminate = drive(pl, 2.0)
    pl.slave.reset()
    pl.slave.setFMUstate(state)
    pl.time = t_saved
    after_reset = drive(pl, 2.0)
    pl.slave.freeFMUstate(state)
    pl.free()
    assert np.array_equal(reference, after_terminate)
    assert np.array_equal(reference, after_reset)


CONTINUE_SCRIPT = r"""
import json, sys
sys.path.insert(0, {tests!r})
import numpy as np
from stewart_fmu import Platform, stand_parameters
from test_fmu_state import drive

pl = Platform(parameters=stand_parameters(nondimensional=True), name="fresh")
state = pl.slave.deSerializeFMUstate(open({path!r}, "rb").read())
pl.slave.setFMUstate(state)
pl.slave.freeFMUstate(state)
pl.time = {t}
rows = drive(pl, 3.0)
pl.free()
print(json.dumps([[x.hex() for x in row] for row in rows.tolist()]))
"""


def test_serialized_state_continues_bit_exactly_in_a_fresh_process(tmp_path):
    pl = Platform(parameters=P)
    drive(pl, 1.0)
    state = pl.slave.getFMUstate()
    data = bytes(pl.slave.serializeFMUstate(state))
    pl.slave.freeFMUstate(state)
    t_saved = pl.time
    here = drive(pl, 3.0)
    pl.free()
    path = tmp_path / "state.bin"
    path.write_bytes(data)
    script = CONTINUE_SCRIPT.format(tests=str(Path(__file__).parent), path=str(path), t=t_saved)
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, check=True)
    there = np.array([[float.fromhex(x) for x in row] for row in json.loads(out.stdout.strip().splitlines()[-1])])
    print(f"serialized state: {len(data)} bytes; continued in a fresh process for {len(there)} steps")
    assert np.array_equal(here, there)


def test_corrupted_or_foreign_state_bytes_are_refused():
    pl = Platform(parameters=P)
    drive(pl, 0.5)
    state = pl.slave.getFMUstate()
    data = bytearray(pl.slave.serializeFMUstate(state))
    pl.slave.freeFMUstate(state)
    before = pl.get(*OUTPUTS)
    refused = 0
    flipped = bytearray(data)
    flipped[200] ^= 0x01  # one bit inside the payload
    for corrupt in (data[:-1], data[: len(data) // 2], bytes(len(data)), flipped, b"garbage",
                    bytes(data[:-8]) + bytes(8)):
        try:
            s = pl.slave.deSerializeFMUstate(bytes(corrupt))
            pl.slave.freeFMUstate(s)
        except Exception:
            refused += 1
    assert refused == 6
    assert pl.get(*OUTPUTS) == before  # nothing changed
    pl.free()
