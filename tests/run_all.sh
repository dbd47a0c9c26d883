#!/usr/bin/env bash
# All tests: build and package the FMUs (which checks the model descriptions and the binary),
# clippy, the Rust tests (physics, integrators, the FMI boundary through the exported
# functions, fuzzing), then the Python tests that drive the packaged FMUs with FMPy,
# libcosim and fmi-sim, and the valgrind leak check.
#
# Installs what it needs on a fresh Debian machine (tests/setup.sh checks the prerequisites):
# valgrind, libclang (for building fmi-sim) and Chromium (for the viewer's browser test) from
# Debian's packages without their recommends, the cross toolchains for the Windows and aarch64
# binaries and wine and qemu-user that run them (tests/setup_cross.sh), the viewer's Node packages with npm ci, fmi-sim
# from crates.io (into target/tools), the Python packages from tests/requirements.txt (into
# .venv). Each step that takes more than a few seconds starts with a progress line.
set -euo pipefail
cd "$(dirname "$0")/.."

# Prerequisites (checked; on Debian the missing ones installed), .venv, progress lines.
source tests/setup.sh
require tests
python_env

export FMI_SIM="$PWD/target/tools/bin/fmi-sim"
if [ ! -x "$FMI_SIM" ]; then
    # cargo prints a line per crate compiled: the progress of this long step.
    step "installing fmi-sim 0.7.0 (rust-fmi's FMI importer) into target/tools: compiling about 200 crates, 5-10 minutes on 2 cores, once"
    cargo install --locked fmi-sim@0.7.0 --root target/tools
fi

build_fmus
# The 3-D viewer: Node packages from the committed lock file, then the static build.
build_viewer
if cargo clippy --version >/dev/null 2>&1; then
    step "clippy (the Rust lints; about a minute the first time)"
    cargo clippy --release --all-targets -- -D warnings
    # The build without the AVX2 path (`--no-default-features`) compiles and lints clean too.
    cargo clippy --release --lib --no-default-features -- -D warnings
else
    echo "run_all: clippy is not installed with this toolchain; lint step not run"
fi
step "the API documentation (cargo doc: every intra-doc link resolves)"
RUSTDOCFLAGS="-D warnings" cargo doc --no-deps -p stewart-core -p stewart_fmu
step "the Rust tests (cargo test --release: builds the tests first, about 3 minutes)"
cargo test --release
# Each test once (-v); the numbers the tests print (-rP: passes' output), failures and errors (-rfE).
step "the Python tests over the packaged FMUs (4-15 minutes on 2 cores, with the machine's load)"
.venv/bin/python -m pytest tests/python -v -rfEP
