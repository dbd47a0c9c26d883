"""The library unloads cleanly: a sweep worker that calls `fmpy.simulate_fmu` two hundred times
in one process (FMPy unpacks each call into a new folder, loads the binary from there and
unloads it at the end) keeps its memory. Before, the binary was linked with `-z nodelete`, so
every call left its copy mapped (about 0.76 MB each): one call shows that (a deleted file still
mapped), and 100 calls bound any other leak to 5 kB a call. They follow 100 calls that are not
counted: over those the process's RSS still grows by about 1.2 MB (FMPy's and NumPy's first-use
allocations; 2026-12-03), then stays flat to 0.1 MB."""

import re

from fmpy import simulate_fmu

from stewart_fmu import PLATFORM_FMU


def rss_mb():
    status = open("/proc/self/status").read()
    return int(re.search(r"VmRSS:\s+(\d+) kB", status).group(1)) / 1024


def mapped_copies():
    """Mappings of StewartPlatform binaries, and of deleted ones (unpacked folders removed)."""
    maps = open("/proc/self/maps").read().splitlines()
    ours = [m for m in maps if "StewartPlatform.so" in m]
    return len(ours), len([m for m in ours if m.endswith("(deleted)")])


def test_a_hundred_simulate_fmu_calls_keep_the_memory():
    warm_up, calls = 100, 100
    for _ in range(warm_up):  # FMPy's and NumPy's own first-use allocations
        simulate_fmu(str(PLATFORM_FMU), stop_time=0.01, output_interval=0.01, output=["r[3]"])
    before = rss_mb()
    for i in range(calls):
        result = simulate_fmu(str(PLATFORM_FMU), stop_time=0.01, output_interval=0.01, output=["r[3]"])
        assert abs(result["r[3]"][-1] - 1.9589244164161732) < 1e-12
        if i == calls // 2 - 1:
            halfway = rss_mb()
    after = rss_mb()
    copies, deleted = mapped_copies()
    print(f"{calls} simulate_fmu calls: RSS {before:.1f} MB -> {halfway:.1f} MB after {calls // 2} -> {after:.1f} MB "
          f"(growth {after - before:.2f} MB); mappings of the binary left: {copies} ({deleted} of deleted files)")
    assert after - before < 5e-3 * calls  # MB: 5 kB a call
    assert deleted == 0, "an unpacked copy of the binary stayed mapped after FMPy unloaded it"
