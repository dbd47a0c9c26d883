"""The cueing FMU where cueing runs, a simulator's real-time computer (docs/cueing.md "Real
time"): a plain C host (benches/c/cueing_host.c) drives the packaged FMU at 1 kHz through the
slalom; in 10^4 cycles after the first 2,000 the FMU makes no allocation (an LD_PRELOAD
counter of the C library's allocating functions, benches/c/cueing_alloc.c) and no system call
(strace between two marker calls of the host), with either method. Times and instruction
counts belong to benches/cueing_bench.py, not to a test."""

import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "benches"))
import cueing_bench  # noqa: E402


@pytest.fixture(scope="module")
def host(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("cueing_host")
    program, shim = cueing_bench.build(tmp)
    return tmp, program, shim, cueing_bench.unpack(tmp), cueing_bench.drives(tmp, only=["slalom"])["slalom"]


@pytest.mark.parametrize("method", [0, 1], ids=["classical", "predictive"])
def test_no_allocation_and_no_system_call_in_the_steps(host, method):
    tmp, program, shim, unpacked, drive = host
    allocated, calls, cycles = cueing_bench.quiet(program, shim, unpacked, drive, method, tmp)
    print(f"method {method}: {allocated} allocations and {calls} system calls in {cycles} cycles")
    assert calls >= 0, "strace saw no marker: the count did not run"
    assert (allocated, calls) == (0, 0)
