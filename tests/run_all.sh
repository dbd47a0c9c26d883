#!/usr/bin/env bash
# All tests: build and package the FMUs (which checks the model descriptions and the binary),
# clippy, the Rust tests (physics, integrators, the FMI boundary through the exported
# functions, fuzzing), then the Python tests that drive the packaged FMUs with FMPy,
# libcosim and fmi-sim, and the valgrind leak check.
#
# Installs what it needs on a fresh Debian machine: valgrind, libclang (for building fmi-sim)
# and Chromium (for the viewer's browser test) from Debian's packages, the viewer's Node
# packages with npm ci, fmi-sim from crates.io (into target/tools), the Python
# packages from tests/requirements.txt (into .venv).
set -euo pipefail
cd "$(dirname "$0")/.."

SUDO=""
if [ "$(id -u)" -ne 0 ] && command -v sudo >/dev/null; then SUDO="sudo"; fi
need_apt=()
command -v valgrind >/dev/null || need_apt+=(valgrind)
command -v gcc >/dev/null || need_apt+=(gcc)
ls /usr/lib/llvm-*/lib/libclang.so* >/dev/null 2>&1 || need_apt+=(libclang-dev)
command -v chromium >/dev/null || need_apt+=(chromium)
command -v npm >/dev/null || need_apt+=(nodejs npm)
if [ ${#need_apt[@]} -gt 0 ]; then
    echo "run_all: installing ${need_apt[*]} from Debian's packages"
    $SUDO apt-get update -qq
    $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${need_apt[@]}"
fi

if [ ! -x .venv/bin/python ]; then
    python3 -m venv .venv
fi
.venv/bin/python -m pip install --quiet --disable-pip-version-check -r tests/requirements.txt
.venv/bin/python -m pip install --quiet --disable-pip-version-check --no-deps -e python

export FMI_SIM="$PWD/target/tools/bin/fmi-sim"
if [ ! -x "$FMI_SIM" ]; then
    echo "run_all: installing fmi-sim 0.7.0 (rust-fmi's FMI importer) into target/tools"
    cargo install --quiet --locked fmi-sim@0.7.0 --root target/tools
fi

cargo run --release --bin build-fmu
# The 3-D viewer: Node packages from the committed lock file, then the static build.
(cd viewer && npm ci --no-audit --no-fund --loglevel=error && npm run build --silent)
if cargo clippy --version >/dev/null 2>&1; then
    cargo clippy --release --all-targets -- -D warnings
    # The build without the AVX2 path (`--no-default-features`) compiles and lints clean too.
    cargo clippy --release --lib --no-default-features -- -D warnings
else
    echo "run_all: clippy is not installed with this toolchain; lint step not run"
fi
cargo test --release
.venv/bin/python -m pytest tests/python -v -rA
