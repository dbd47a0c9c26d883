#!/usr/bin/env bash
# The main job: build and package the FMUs (Linux x86-64 and aarch64, Windows x64), then run the paper's experiments, the workspace
# scenarios (end stops, singular arrangements) and the machine's (heavy legs, joint limits,
# friction, electric drives, hydraulic legs) and motion cueing through it with FMPy, and the design studies on
# Dask, writing CSV and Parquet data and PNG plots to output/ (or the folder given as the first
# argument).
set -euo pipefail
cd "$(dirname "$0")/.."
OUT="${1:-output}"

# Prerequisites (checked; on Debian the missing ones installed), .venv, progress lines.
source tests/setup.sh
require main
python_env

build_fmus
# The 3-D viewer (three.js, built with vite from the committed lock file).
build_viewer
step "the paper's experiments (non-dimensional units)"
.venv/bin/python examples/paper_experiments.py "$OUT"
step "the workspace scenarios: end stops, singular arrangements"
.venv/bin/python examples/workspace_scenarios.py "$OUT"
step "the machine scenarios: heavy legs, joint limits, friction"
.venv/bin/python examples/machine_scenarios.py "$OUT"
step "the drive scenarios: holding, dynamic braking, voltage commands, a failed drive"
.venv/bin/python examples/drive_scenarios.py "$OUT"
step "the hydraulic scenarios: holding, heave, loss of control power, pump failure, a stuck valve"
.venv/bin/python examples/hydraulic_scenarios.py "$OUT"
step "the power unit: the heave on pump and accumulator, pump stops with the safe landing (under a minute)"
.venv/bin/python examples/power_unit_scenarios.py "$OUT"
step "motion cueing: the truck's manoeuvres, the motion system, the harsh manoeuvres, the OMCT (about three minutes)"
.venv/bin/python examples/cueing_scenarios.py "$OUT"
step "the linearisation about the neutral pose"
.venv/bin/python examples/linearise.py --output "$OUT"
# Design studies on a local Dask cluster (one worker per core) with the compiled co-simulation
# master (stewart-sweep's default): results.parquet, summary, plots.
# accumulator: the power unit's design study (scenario 8 of examples/power_unit_scenarios.py).
for study in stability payload power_loss workspace washout accumulator; do
    step "design study $study on a local Dask cluster (seconds to half a minute; a progress bar)"
    .venv/bin/stewart-sweep "studies/$study.toml" --out "$OUT/$study"
done
step "the payload Monte Carlo: 10,000 runs of 1,500 closed-loop steps on a local Dask cluster (under a minute on 2 cores; a progress bar)"
.venv/bin/stewart-sweep studies/payload_monte_carlo.toml --out "$OUT/payload_monte_carlo"
# The viewer with eight results (heave, power loss, actuator failure, start-up, heavy legs, hydraulic legs, motion cueing, the ripple on its joint limits).
step "the viewer's results"
.venv/bin/python examples/viewer_data.py "$OUT/viewer"
# What each file in the output folder is.
.venv/bin/python examples/output_index.py "$OUT"
# The figures the docs quote (docs/validation.md, docs/control.md), into benches/results/.
.venv/bin/python examples/record_figures.py "$OUT"
step "done: results in $OUT/ (what each file is: $OUT/README.md)"
