#!/usr/bin/env bash
# The wheels of the Python package stewart_fmu, built with maturin from python/pyproject.toml,
# into target/wheels/: Linux x86-64 and aarch64 (manylinux_2_34) and Windows x64 (win_amd64),
# each with the compiled master for its platform, the FMUs with all their binaries and the
# viewer page (python/build_wheels.py says what each carries and how it is built).
#
# On a Debian 12 machine it needs nothing else: like the README's two set-up commands it checks
# the prerequisites and installs what is missing (Debian's packages, the cross toolchains of
# tests/setup_cross.sh), makes .venv (with maturin from tests/requirements.txt), builds the FMUs
# of every platform and the viewer page (seconds when they are built), then the wheels: about
# four minutes the first time on 2 cores (the foreign extensions compile their standard library
# and dependencies), seconds after.
#
#   bash python/build_wheels.sh                              # all three
#   bash python/build_wheels.sh --platforms x86_64-linux     # or some of them
set -euo pipefail
cd "$(dirname "$0")/.."

source tests/setup.sh
require main
python_env
build_fmus
if [ ! -f viewer/dist/index.html ]; then
    build_viewer
fi
step "building the wheels with maturin into target/wheels/ (a line per platform)"
.venv/bin/python python/build_wheels.py "$@"
