#!/usr/bin/env bash
# The tests, in two tiers (CONTRIBUTING.md says what each covers):
#
#   bash tests/run_all.sh           the full tier, CI's and the README's command: every test
#   bash tests/run_all.sh --quick   the quick tier: this machine's platform alone, in minutes
#
# The full tier builds and packages the FMUs for every platform (which checks the model
# descriptions and the binaries), runs clippy and the API documentation's links, the Rust tests
# (physics against independent formulations, the FMI boundary through the exported functions,
# fuzzing), then the Python tests that drive the packaged FMUs with FMPy, libcosim, fmi-sim and
# the compiled master, on wine and qemu-user, in a browser, under valgrind and on Dask, on both
# cores (pytest-xdist). A test that skips fails (tests/python/conftest.py).
#
# The quick tier builds the FMUs for this machine's platform alone (STEWART_FMU_TARGETS,
# default x86_64-linux; no cross set-up) and runs the Rust unit tests, the integration tests of
# QUICK_RUST below and the Python tests marked `quick` (tests/python/conftest.py): no wine,
# qemu, browser, valgrind or Dask cluster, no clippy. After it, target/fmu/ holds this
# platform's binaries only; the full tier packages every platform's again (seconds, cached).
#
# Installs what it needs on a fresh Debian machine (tests/setup.sh checks the prerequisites):
# valgrind, libclang (for building fmi-sim) and Chromium (for the viewer's browser test) from
# Debian's packages without their recommends, the cross toolchains for the Windows and aarch64
# binaries and wine and qemu-user that run them (tests/setup_cross.sh), the viewer's Node
# packages with npm ci, fmi-sim from crates.io (into target/tools, once), the Python packages
# from tests/requirements.txt (into .venv). Each step that takes more than a few seconds starts
# with a progress line; steps that run beside others write their output to target/test-logs/.
set -euo pipefail
cd "$(dirname "$0")/.."

QUICK=false
for arg in "$@"; do
    case "$arg" in
        --quick) QUICK=true ;;
        -h | --help) sed -n '2,6p' "$0" | cut -c3-; exit 0 ;;
        *) echo "run_all: unknown argument $arg (usage: bash tests/run_all.sh [--quick])" >&2; exit 2 ;;
    esac
done

# The Rust integration tests of the quick tier (modules of tests/integration.rs): the FMI
# boundary's state machines and checks, the model descriptions, the hot path's allocations and
# the physics' fast checks. The full tier runs every module.
QUICK_RUST=(model_description:: fmi_state_machine:: fmi3_state_machine:: fmi_panic_boundary:: fmi_value_cache::
            no_allocation:: conservation:: tangents:: direct_problem_and_similarity::)

# Prerequisites (checked; on Debian the missing ones installed), .venv, progress lines.
source tests/setup.sh

# `rust_tests [ARGS]`: cargo test --release, ARGS passed on: the mechanics crate's tests on their
# own, since a build that selects stewart-core with the FMU crate gives the FMU crate other
# features (stewart-core's `default`) than its own build, which would then be compiled again.
rust_tests() {
    cargo test --release --workspace --exclude stewart-core "$@"
    cargo test --release -p stewart-core "$@"
}

if $QUICK; then
    require quick
    python_env
    export STEWART_FMU_TARGETS="${STEWART_FMU_TARGETS:-x86_64-linux}"
    build_fmus
    step "the Rust tests of the quick tier: the unit tests, integration modules ${QUICK_RUST[*]}"
    rust_tests --lib --bins
    cargo test --release -p stewart-fmu-tests --test integration -- "${QUICK_RUST[@]}"
    step "the Python tests marked quick, on both cores"
    .venv/bin/python -m pytest tests/python -m quick -n 2 --dist loadfile -rfE
    step "the quick tier passed (the full tier: bash tests/run_all.sh)"
    exit 0
fi

require tests
python_env

# Beside the FMUs' build (each logs to target/test-logs/): the cross toolchains (Debian's
# packages; build_fmus waits for them once the build program is built); fmi-sim, rust-fmi's
# FMI importer, built once into target/tools; the 3-D viewer (Node packages from the committed
# lock file, then the static build); clippy and the API documentation, which wait for target/
# while the FMU for this machine is built there and run while the others are built in
# target/cross/.
if ! cross_ready tests; then
    step "installing the cross toolchains beside the build program (target/test-logs/cross.log)"
    in_background cross cross_toolchains tests
fi
FMI_SIM_VERSION=0.7.0
export FMI_SIM="$PWD/target/tools/bin/fmi-sim"
# (fmi-sim 0.7.0 answers --version with "Error: fmi-sim 0.7.0" and status 1.) Unoptimised
# (--debug): the tests run it for a few hundred steps, whose time is the FMU's; its 200 crates
# then compile in about a third of the time (2.6 against 8.3 minutes of CPU here).
if [[ "$("$FMI_SIM" --version 2>&1 || true)" != *"fmi-sim $FMI_SIM_VERSION"* ]]; then
    step "installing fmi-sim $FMI_SIM_VERSION into target/tools beside the builds below: about 200 crates, 2-4 minutes on 2 cores, once (target/test-logs/fmi-sim.log)"
    in_background fmi-sim cargo install --locked --force --debug "fmi-sim@$FMI_SIM_VERSION" --root target/tools
fi
step "building the 3-D viewer beside the FMUs (npm ci and vite; target/test-logs/viewer.log)"
in_background viewer build_viewer
lints() {
    if cargo clippy --version >/dev/null 2>&1; then
        cargo clippy --release --all-targets -- -D warnings
        # The build without the AVX2 path (`--no-default-features`) compiles and lints clean too.
        cargo clippy --release --lib --no-default-features -- -D warnings
    else
        echo "run_all: clippy is not installed with this toolchain; lint step not run"
    fi
    # The API documentation: every intra-doc link resolves.
    RUSTDOCFLAGS="-D warnings" cargo doc --no-deps -p stewart-core -p stewart_fmu
}
step "clippy (with and without the AVX2 path) and cargo doc beside the FMUs (target/test-logs/lints.log)"
in_background lints lints
build_fmus
finish viewer
step "waiting for clippy and cargo doc (target/test-logs/lints.log)"
finish lints
grep -h "clippy is not installed" target/test-logs/lints.log || true

step "the Rust tests (cargo test --release: builds the tests first, about 3 minutes)"
rust_tests
if [ -n "${BACKGROUND[fmi-sim]:-}" ]; then
    step "waiting for fmi-sim's build (target/test-logs/fmi-sim.log)"
    finish fmi-sim
fi
# Each test once (-v); the numbers the tests print (-rP: passes' output), failures and errors
# (-rfE), the slowest twelve (--durations); on both cores, a file's tests on one of them (their
# module fixtures build once).
step "the Python tests over the packaged FMUs, on both cores (3-8 minutes, with the machine's load)"
.venv/bin/python -m pytest tests/python -v -rfEP -n 2 --dist loadfile --durations=12
step "the full tier passed"
