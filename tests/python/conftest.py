"""What every Python test shares: the packaged platform FMU, and the tiers (CONTRIBUTING.md).

The quick tier (`bash tests/run_all.sh --quick`) runs the tests marked `quick` (`pytest -m
quick`): a module's `pytestmark = pytest.mark.quick`, or a test's `@pytest.mark.quick`. They run
on this machine's platform alone, without wine, qemu-user, a browser, valgrind or a Dask
cluster, in seconds each. The full tier (`bash tests/run_all.sh`, CI's command) runs every test.
In either, a test that skips fails: a skipped test is never counted as passing.
"""

import pytest

from stewart_fmu import PLATFORM_FMU


def pytest_configure(config):
    config.addinivalue_line(
        "markers", "quick: in the quick tier (tests/run_all.sh --quick): the host platform only, no wine, "
                   "qemu-user, browser, valgrind or Dask cluster, seconds each")


@pytest.hookimpl(wrapper=True)
def pytest_runtest_makereport(item, call):
    report = yield
    if report.skipped and not hasattr(report, "wasxfail"):
        reason = report.longrepr[-1] if isinstance(report.longrepr, tuple) else report.longrepr
        report.outcome = "failed"
        report.longrepr = f"{item.nodeid} skipped ({reason}): a skipped test fails here, it is never counted as passing"
    return report


@pytest.fixture(scope="session")
def platform_fmu():
    if not PLATFORM_FMU.exists():
        pytest.fail(f"{PLATFORM_FMU} is missing: run `cargo run --release --bin build-fmu` first")
    return str(PLATFORM_FMU)
