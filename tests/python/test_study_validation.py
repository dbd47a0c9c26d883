"""Study files are checked before anything runs (issue 28, items 2, 3, 4 and 6): every bad file
of the red-team run is refused by `stewart-sweep` with exit status 2, a message naming the key
at fault and no traceback, and nothing is written; `--check` prints the plan and runs nothing;
the run count is computed without expanding the runs and refused above `--max-runs`; and a
bad run that reaches `study.execute` without the check (the API) is an error row, never a
crash or a row that looks valid."""

import math
import subprocess
import sys
import time
from pathlib import Path

import pytest

from stewart_fmu import ROOT
from stewart_fmu import study as st

SWEEP = str(Path(sys.executable).parent / "stewart-sweep")

HEAD = """
[study]
name = "tiny"
system = "closed-loop"
units = "nondimensional"
stop_time = 0.05
step = 0.01
"""


def sweep(tmp_path, text, *args, timeout=60):
    """Runs stewart-sweep on a study file with `text`; returns (exit status, stdout + stderr, out)."""
    path = tmp_path / "study.toml"
    path.write_text(text)
    out = tmp_path / "out"
    run = subprocess.run([SWEEP, str(path), "--out", str(out), "--serial", *args], capture_output=True, text=True,
                         timeout=timeout)
    return run.returncode, run.stdout + run.stderr, out


# The red-team run's files (issue 28), each with what the message must name.
REFUSED = {
    "zero step (ZeroDivisionError)": ('[grid]\nstep = [0.0, 0.01]', ["grid.step[0] = 0.0", "greater than 0"]),
    "negative step (rows that looked valid)": ('[grid]\nstep = [-0.01, 0.01]', ["grid.step[0] = -0.01"]),
    "NaN stop time": ('[fixed]\nstop_time = nan', ["fixed.stop_time = nan", "finite"]),
    "com_offset[4] (IndexError)": ('[fixed]\n"platform.com_offset[4]" = 0.01', ["platform.com_offset[4]", "3 components"]),
    "failed leg 7": ('[fixed]\n"scenario.failed_leg" = 7', ['"scenario.failed_leg" = 7', "at most 6"]),
    "mass as text": ('[grid]\n"platform.M" = ["heavy"]', ['grid."platform.M"[0] = \'heavy\'', "a number"]),
    "negative samples": ('[random]\nsamples = -3\n"platform.M" = { uniform = [0.9, 1.1] }',
                         ["random.samples = -3", "at least 1"]),
    "uniform with one bound": ('[random]\nsamples = 3\n"platform.M" = { uniform = [2000.0] }',
                               ['"platform.M".uniform = [2000.0]', "[low, high]"]),
    "[gird]": ('[gird]\n"controller.G" = [1.0, 2.0]', ["unknown section [gird]", "did you mean 'grid'"]),
    "stepp": (None, ["study.stepp", "did you mean 'step'"]),
    "variable typo": ('[grid]\n"controller.GG" = [1.0, 2.0]', ["StewartController has no variable 'GG'",
                                                                "did you mean 'controller.G'"]),
    "map x not varied (KeyError)": ('[grid]\n"controller.G" = [1.0, 2.0]\n[[plot]]\nkind = "map"\nx = "controller.D"\n'
                                    'y = "controller.G"', ["plot 1 (map): x = 'controller.D' is not varied"]),
    "scatter x not varied": ('[grid]\n"controller.G" = [1.0, 2.0]\n[[plot]]\nkind = "scatter"\nx = "platform.M"',
                             ["plot 1 (scatter): x = 'platform.M' is not a varied parameter"]),
    "map facet not varied": ('[grid]\n"controller.G" = [1.0, 2.0]\n"controller.D" = [0.0, 1.0]\n[[plot]]\n'
                             'kind = "map"\nx = "controller.G"\ny = "controller.D"\nfacet = "step"',
                             ["facet = 'step' is not varied"]),
    "plot outside --out": ('[grid]\n"controller.G" = [1.0, 2.0]\n[[plot]]\nkind = "scatter"\nx = "controller.G"\n'
                           'file = "../../x.png"', ["file = '../../x.png'", "inside --out"]),
    "step in a string with a unit": ('[fixed]\nstep = "10 ms"', ["fixed.step = '10 ms'", "a number of time units"]),
    "unquoted dotted name": ('[fixed]\nplatform.M = 1.1', ['quote dotted names, "platform.M"']),
}


@pytest.mark.parametrize("case", sorted(REFUSED))
def test_the_red_team_study_files_are_refused_before_anything_runs(case, tmp_path):
    addition, expected = REFUSED[case]
    text = HEAD.replace("step = 0.01", "step = 0.01\nstepp = 0.5") if addition is None else HEAD + addition + "\n"
    status, output, out = sweep(tmp_path, text)
    print(f"{case}: exit {status}: {output.strip()[:300]}")
    assert status == 2, output
    assert "Traceback" not in output
    assert output.startswith("stewart-sweep: ")
    for part in expected:
        assert part in output
    assert not (out / "results.parquet").exists(), "a refused study must not run"


def test_every_problem_of_a_file_is_named_at_once(tmp_path):
    status, output, _ = sweep(tmp_path, HEAD + '[grid]\n"controller.GG" = [1.0]\nstep = [0.0]\n[gird]\n')
    assert status == 2
    assert "3 problems" in output and "controller.GG" in output and "grid.step[0]" in output and "[gird]" in output


def test_check_prints_the_plan_with_the_run_count_and_runs_nothing(tmp_path):
    out = tmp_path / "out"
    run = subprocess.run([SWEEP, str(ROOT / "studies" / "stability.toml"), "--check"], capture_output=True, text=True,
                         timeout=60)
    print(run.stdout)
    assert run.returncode == 0, run.stderr
    assert "runs: 4 controller.D x 3 controller.G x 11 step = 132" in run.stdout
    assert "map of max_leg_error over step x controller.D, a panel per controller.G -> stability_map.png" in run.stdout
    assert "nothing was run" in run.stdout
    assert not out.exists()


def test_a_ten_million_run_grid_is_refused_at_once_and_counted_without_expanding(tmp_path):
    values = "[" + ", ".join(f"{1.0 + i}" for i in range(10)) + "]"
    names = ["controller.G", "controller.D", "platform.M", "platform.g", "platform.J[1]", "platform.J[2]",
             "platform.J[3]"]
    text = HEAD + "[grid]\n" + "".join(f'"{n}" = {values}\n' for n in names)
    started = time.monotonic()
    status, output, out = sweep(tmp_path, text, timeout=30)
    refused_in = time.monotonic() - started
    print(f"10^7 runs: exit {status} in {refused_in:.1f} s: {output.strip()}")
    assert status == 2 and "1.000e+07 runs" in output and "--max-runs 1.000e+05" in output
    assert "Traceback" not in output and not (out / "results.parquet").exists()
    assert refused_in < 20
    path = tmp_path / "study.toml"
    started = time.monotonic()
    run = subprocess.run([SWEEP, str(path), "--check", "--max-runs", "20000000"], capture_output=True, text=True,
                         timeout=30)
    assert run.returncode == 0, run.stderr
    assert "= 10000000 (--max-runs 20000000)" in run.stdout
    assert time.monotonic() - started < 20


# ----- a run that reaches execute() without the check is a row -----------------------------------

SPEC = {"study": {"name": "api", "system": "closed-loop", "units": "nondimensional", "stop_time": 0.05, "step": 0.01}}


@pytest.mark.parametrize("run, expected", [
    ({"step": 0.0}, "step = 0.0"),
    ({"step": -0.01}, "step = -0.01"),
    ({"stop_time": math.nan}, "stop_time = nan"),
    ({"platform.com_offset[4]": 0.01}, "platform.com_offset[4]"),
    ({"scenario.failed_leg": 7}, "scenario.failed_leg = 7"),
    ({"platform.M": ["heavy"]}, "platform.M = ['heavy']"),
    ({"controller.GG": 1.0}, "did you mean 'controller.G'"),
    ({"step": 0.3}, "gives no step"),
])
def test_a_bad_run_given_to_execute_is_an_error_row_with_its_message(run, expected):
    spec = {k: dict(v) for k, v in SPEC.items()}
    row = st.execute(spec, run, st.fmus_for(spec))
    print(f"{run}: {row['status']}: {row['message']}")
    assert row["status"] == "error" and row["stable"] is False
    assert expected in row["message"]


def test_a_run_after_a_failed_one_is_unaffected():
    spec = {k: dict(v) for k, v in SPEC.items()}
    fmus = st.fmus_for(spec)
    heave = {"controller.heave.centre[3]": 1.3059496109441155, "controller.heave.amplitude": 0.2,
             "controller.G": 10.0, "controller.D": 1.58}
    good = st.execute(spec, heave, fmus)
    assert st.execute(spec, dict(heave, **{"platform.M": -1.0}), fmus)["status"] == "error"
    assert st.execute(spec, dict(heave, **{"platform.M": "x"}), fmus)["status"] == "error"
    again = st.execute(spec, heave, fmus)
    assert good["status"] == again["status"] == "ok"
    assert good["final_z"] == again["final_z"] and good["max_leg_error"] == again["max_leg_error"]
