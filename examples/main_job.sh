#!/usr/bin/env bash
# The main job: build and package the FMU, then run the paper's experiments, the workspace
# scenarios (end stops, singular arrangements) and the machine's (heavy legs, joint limits,
# friction, electric drives) through it with FMPy, and the design studies on
# Dask, writing CSV and Parquet data and PNG plots to output/ (or the folder given as the first
# argument).
set -euo pipefail
cd "$(dirname "$0")/.."
OUT="${1:-output}"

if [ ! -x .venv/bin/python ]; then
    python3 -m venv .venv
fi
.venv/bin/python -m pip install --quiet --disable-pip-version-check -r tests/requirements.txt
.venv/bin/python -m pip install --quiet --disable-pip-version-check --no-deps -e python

cargo run --release --bin build-fmu
# The 3-D viewer (three.js, built with vite from the committed lock file).
(cd viewer && npm ci --no-audit --no-fund --loglevel=error && npm run build --silent)
.venv/bin/python examples/paper_experiments.py "$OUT"
.venv/bin/python examples/workspace_scenarios.py "$OUT"
.venv/bin/python examples/machine_scenarios.py "$OUT"
.venv/bin/python examples/drive_scenarios.py "$OUT"
.venv/bin/python examples/linearise.py --output "$OUT"
# Design studies on a local Dask cluster (one worker per core): results.parquet, summary, plots.
for study in stability payload power_loss workspace; do
    .venv/bin/stewart-sweep "studies/$study.toml" --out "$OUT/$study"
done
# The viewer with four results (heave, power loss, actuator failure, start-up).
.venv/bin/python examples/viewer_data.py "$OUT/viewer"
