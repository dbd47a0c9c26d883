import pytest

from stewart_fmu import PLATFORM_FMU


@pytest.fixture(scope="session")
def platform_fmu():
    if not PLATFORM_FMU.exists():
        pytest.fail(f"{PLATFORM_FMU} is missing: run `cargo run --release --bin build-fmu` first")
    return str(PLATFORM_FMU)
