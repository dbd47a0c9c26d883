import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))
# The linearisation command (examples/linearise.py) is also a library for the tests.
sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "examples"))

from stewart import PLATFORM_FMU  # noqa: E402


@pytest.fixture(scope="session")
def platform_fmu():
    if not PLATFORM_FMU.exists():
        pytest.fail(f"{PLATFORM_FMU} is missing: run `cargo run --release --bin build-fmu` first")
    return str(PLATFORM_FMU)
