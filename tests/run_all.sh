#!/usr/bin/env bash
# All tests: build and package the FMUs (which checks the model descriptions and the binary),
# the Rust tests (physics, integrators, FMI boundary), then the Python tests that drive the
# packaged FMUs with FMPy.
set -euo pipefail
cd "$(dirname "$0")/.."

if [ ! -x .venv/bin/python ]; then
    python3 -m venv .venv
fi
.venv/bin/python -m pip install --quiet --disable-pip-version-check -r tests/requirements.txt

cargo run --release --bin build-fmu
cargo test --release
.venv/bin/python -m pytest tests/python -v -rA
