#!/usr/bin/env bash
# Builds the wheel of the Python package stewart_fmu that carries the FMUs (FMI 2 and 3), the
# SSP systems, the built viewer page and the compiled co-simulation master (the extension module
# stewart_fmu._master, built for Python 3.11+'s stable ABI), so that it works wherever it is installed:
#   target/wheels/stewart_fmu-<version>-py3-none-linux_x86_64.whl
# (linux_x86_64: the compiled master inside is a Linux x86-64 extension; the FMUs carry every
# platform's binary). Needs the FMUs and the
# viewer built first (`bash examples/main_job.sh` does both; or `cargo run --release --bin
# build-fmu` and `npm ci && npm run build` in viewer/). The build runs in a copy of python/
# under target/wheel/, so nothing is written into the repository's source folders.
#
#   bash python/build_wheel.sh            # with .venv/bin/python, or $PYTHON
set -euo pipefail
cd "$(dirname "$0")/.."
PYTHON="${PYTHON:-.venv/bin/python}"
STAGE=target/wheel/stage
DATA="$STAGE/stewart_fmu/data"

FMUS=(target/fmu/StewartPlatform.fmu target/fmu/StewartController.fmu target/fmu/StewartCueing.fmu
      target/fmu/StewartSystem.ssp target/fmu/StewartSystemDrives.ssp target/fmu/StewartSystemHydraulic.ssp
      target/fmu/StewartMotionSystem.ssp
      target/fmu/fmi3/StewartPlatform.fmu target/fmu/fmi3/StewartController.fmu target/fmu/fmi3/StewartCueing.fmu)
MASTER=target/release/libstewart_master_py.so
for f in "${FMUS[@]}" viewer/dist/index.html "$MASTER"; do
    if [ ! -f "$f" ]; then
        echo "build_wheel: $f is missing: build the FMUs (cargo run --release --bin build-fmu) and the viewer" \
             "(npm ci && npm run build in viewer/) and the master (cargo build --release -p stewart-master-py) first;" \
             "bash examples/main_job.sh does all three" >&2
        exit 2
    fi
done

rm -rf target/wheel
mkdir -p "$DATA/fmu/fmi3" target/wheels
cp python/pyproject.toml "$STAGE/"
cp -r python/stewart_fmu "$STAGE/"
find "$STAGE" -name __pycache__ -prune -exec rm -rf {} +
for f in "${FMUS[@]}"; do cp "$f" "$DATA/fmu/${f#target/fmu/}"; done
cp -r viewer/dist "$DATA/viewer"
cp "$MASTER" "$STAGE/stewart_fmu/_master.abi3.so"
# The platform tag says where the FMUs run; setuptools builds in the copy.
printf '[bdist_wheel]\nplat_name = linux_x86_64\n' > "$STAGE/setup.cfg"

echo "build_wheel: building the wheel (pip fetches setuptools into an isolated build environment the first time)"
"$PYTHON" -m pip wheel --quiet --disable-pip-version-check --no-deps --wheel-dir target/wheels "$STAGE"
ls -l target/wheels/stewart_fmu-*.whl
