"""The main job's figures that the docs quote, recorded in benches/results/validation.txt: the
paper's experiments, the workspace, machine, drive and hydraulic scenarios (docs/validation.md,
docs/model.md), the motion system's braking (docs/control.md) and the cueing's manoeuvres
(docs/cueing.md), from the summaries the main job wrote into the output folder, without the
wall-clock times some lines carry. tests/python/test_readme.py checks that
every figure those pages quote is in a file of benches/results/; a run that moves a figure shows
in this file's diff.

    python examples/record_figures.py [output-folder]   (default: output/)
"""

import re
import sys
from pathlib import Path

OUT = Path(sys.argv[1] if len(sys.argv) > 1 else "output")
RESULTS = Path(__file__).resolve().parents[1] / "benches" / "results" / "validation.txt"
# (summary file, the script that writes it): every line of each.
SOURCES = [("summary.txt", "examples/paper_experiments.py"),
           ("workspace_summary.txt", "examples/workspace_scenarios.py"),
           ("machine_summary.txt", "examples/machine_scenarios.py"),
           ("drive_summary.txt", "examples/drive_scenarios.py"),
           ("hydraulic_summary.txt", "examples/hydraulic_scenarios.py"),
           ("hydraulic_power_unit_summary.txt", "examples/power_unit_scenarios.py"),
           ("cueing_summary.txt", "examples/cueing_scenarios.py")]

# Summaries with wall-clock times in another form: the pattern that takes them out (the
# hydraulic work-precision line's "..., 4.5 us" after each error, and its heading's words).
WALL_CLOCK = {"cueing_summary.txt": r" \(\d+ s\)",
              "hydraulic_summary.txt": r"; doStep wall time|, \d+(?:\.\d+)? us(?=;|$)"}


def main():
    parts = ["# The main job's figures that docs/validation.md, control.md, cueing.md and model.md quote (bash "
             "examples/main_job.sh writes this file\n# with examples/record_figures.py from the summaries in output/; "
             "wall-clock times left out).\n"]
    for name, script in SOURCES:
        lines = (OUT / name).read_text().splitlines()
        # Wall-clock time (", 15 s in 3.2 s)"; the cueing's " (110 s)"): the machine's, not the model's.
        lines = [re.sub(r" in \d+(?:\.\d+)? s\)", ")", line) for line in lines]
        if name in WALL_CLOCK:
            lines = [re.sub(WALL_CLOCK[name], "", line) for line in lines]
        parts.append(f"## {name} ({script})\n" + "\n".join(lines) + "\n")
    RESULTS.write_text("\n".join(parts))
    print(f"wrote {RESULTS}")


if __name__ == "__main__":
    main()
