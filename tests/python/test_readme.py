"""The README's five-minute tour runs as written, from a folder outside the repository, with
the repository's environment (tests/python/test_wheel.py runs it again with the installed
wheel), and shows what it says: the equilibrium holds, the closed loop tracks the heave
programme, the pose command through programme 3 is followed, the study's rows come from a Dask
cluster and the leg error is least at the payload the controller expects, the viewer's files
are written. And the README quotes no measured figure that the repository does not record:
each one is in benches/results/setup.txt."""

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import pandas as pd

from stewart_fmu import NEUTRAL_Z, ROOT
from stewart_fmu.sweep import load_results

TOUR = Path(__file__).with_name("readme_tour.py")
README = ROOT / "README.md"


def run_tour(python, work, env=None):
    """The values the tour's Python blocks leave (readme_tour.py), run by `python` in `work`."""
    run = subprocess.run([str(python), str(TOUR), str(README)], cwd=work, capture_output=True, text=True, env=env,
                         timeout=900)
    assert run.returncode == 0, run.stderr[-3000:]
    return json.loads(run.stdout.strip().splitlines()[-1])


def check_tour(kept):
    """What each block of the tour shows."""
    fmpy, loop, cue, viewer = kept
    z = np.array(fmpy["result"]["r[3]"])
    assert np.max(np.abs(z - NEUTRAL_Z)) < 1e-12, "the equilibrium holds"
    roll = np.array(fmpy["tilted"]["angles[1]"])
    # angles0 -> R -> angles at t = 0: the round trip through sin, cos and atan2 to an ulp.
    assert abs(roll[0] - 0.01) < 1e-17 and np.max(np.abs(roll - 0.01)) > 1e-4, "the tilted start moves"
    heave = np.array(loop["rows"])[:, 0]
    assert loop["status"] == "ok" and max(loop["errors"]) < 2e-5, "the legs track the programme within 0.02 mm"
    assert 0.55 < np.ptp(heave) < 0.65, "the default heave programme: amplitude 0.3 m"
    # The braking's tilt coordination: a nose-down pitch near asin(0.6 3.2 / 9.81), followed within 0.1 mrad.
    assert abs(cue["pitch"] - cue["commanded"]) < 1e-4 and cue["pitch"] > 0.15, "the cueing's pitch is followed"
    assert viewer["address"] == "index.html?data=data/tilted.csv&stand=data/tilted.stand.json"


def study_of_the_tour():
    """(the study file's name, its text, the command's arguments) from the README."""
    text = README.read_text()
    toml = re.search(r"Save this as `([^`]+)`:\s*```toml\n(.*?)```", text, re.S)
    command = next(line for block in re.findall(r"```sh\n(.*?)```", text, re.S) for line in block.splitlines()
                   if line.startswith("stewart-sweep ") and toml.group(1) in line)
    return toml.group(1), toml.group(2), command.split("#")[0].split()


def run_study(bin_dir, work, env=None):
    """The tour's study with the `stewart-sweep` in `bin_dir`, as the README writes it."""
    name, text, command = study_of_the_tour()
    (work / name).write_text(text)
    run = subprocess.run([str(bin_dir / command[0]), *command[1:]], cwd=work, capture_output=True, text=True,
                         env=env, timeout=900)
    assert run.returncode == 0, run.stderr[-3000:]
    out = work / command[command.index("--out") + 1]
    rows = load_results(out)
    return rows, out


def check_study(rows, out):
    assert len(rows) == 5 and (rows["status"] == "ok").all()
    assert rows["worker"].str.startswith("tcp://127.0.0.1:").all(), "the runs ran on the local Dask cluster"
    by_mass = rows.set_index("param:platform.M")["max_leg_error"].sort_index()
    # The controller's feedforward assumes the nominal 3000 kg: the error is least there.
    assert by_mass.idxmin() == 3000.0 and by_mass.max() > 2 * by_mass.min()
    assert (out / "summary.txt").exists() and (out / "leg_error.png").exists()
    return by_mass


def test_the_tour_runs_as_written_outside_the_repository(tmp_path):
    env = {k: v for k, v in os.environ.items() if not k.startswith("STEWART_")}
    kept = run_tour(sys.executable, tmp_path, env)
    check_tour(kept)
    rows, out = run_study(Path(sys.executable).parent, tmp_path, env)
    by_mass = check_study(rows, out)
    print(f"README tour: equilibrium z = {kept[0]['result']['r[3]'][-1]!r} m; closed loop: largest leg error "
          f"{max(kept[1]['errors']) * 1e3:.4f} mm; motion cueing: pitch {kept[2]['pitch']:.6f} rad against "
          f"{kept[2]['commanded']:.6f} commanded; study: largest leg error by mass (kg -> mm) "
          f"{ {m: round(e * 1e3, 3) for m, e in by_mass.items()} }")
    assert (tmp_path / "my_viewer" / "data" / "tilted.csv").exists()


def prose(text):
    """The README without code (fenced blocks, `inline code`), link targets and HTML comments."""
    text = re.sub(r"```.*?```", "", text, flags=re.S)
    text = re.sub(r"<!--.*?-->", "", text, flags=re.S)
    text = re.sub(r"`[^`]*`", "", text)
    return re.sub(r"\]\([^)]*\)", "]", text)


# A version, a standard or a citation, not a measurement: "FMI 2.0", "Python 3.11", "7(65), 2020".
VERSION = re.compile(r"(?:FMI|Python|Rust|cargo|Node\.js|npm|Debian|FMPy|fmi-sim|libcosim|three\.js|vite|§|glibc|Ubuntu|RHEL|"
                     r"Windows|macOS|wine)\s*$")
UNITS = r"(?:min|s|h|ms|us|GB|MB|kB|mm|m|N|kg|rad|deg|%|x|cores?)"


def quoted_figures(text):
    """The measured figures the README's prose quotes: numbers with a decimal point, and
    numbers with a unit."""
    found = []
    for m in re.finditer(rf"(?<![\w.])(\d[\d,]*(?:\.\d+)?)(?:(-|\s?){UNITS}\b)?", text):
        number, unit = m.group(1).rstrip(",."), m.group(0)[len(m.group(1)):]
        if VERSION.search(text[max(0, m.start() - 12):m.start()]):
            continue
        if "." in number or unit:
            found.append(number)
    return found


@pytest.mark.quick
def test_the_readme_quotes_only_figures_the_repository_records():
    text = prose(README.read_text())
    # The set-up's figures, and the studies' throughput (benches/sweep_bench.py's output).
    recorded = "\n".join((ROOT / "benches" / "results" / name).read_text() for name in ("setup.txt", "sweep.txt"))
    figures = quoted_figures(text)
    print(f"README: {len(README.read_text())} characters; measured figures quoted {figures}, each in "
          f"benches/results/setup.txt or sweep.txt")
    assert figures, "the README quotes the set-up's times and disk use"
    missing = [f for f in figures if not re.search(rf"(?<![\d.]){re.escape(f)}(?![\d])", recorded)]
    assert not missing, f"figures in the README that benches/results/setup.txt and sweep.txt do not record: {missing}"
    assert quoted_figures("held for 3.5 s at 12 mm, FMI 3.0") == ["3.5", "12"]


def test_the_python_examples_of_the_docs_pages_run(tmp_path):
    """docs/*.md's ```python blocks run as written (the discard recipe, the viewer), from a
    folder outside the repository."""
    ran = []
    cwd = os.getcwd()
    os.chdir(tmp_path)
    try:
        for page in sorted((ROOT / "docs").glob("*.md")):
            for i, block in enumerate(re.findall(r"```python\n(.*?)```", page.read_text(), re.S)):
                namespace = {"__name__": "__main__"}
                exec(compile(block, f"{page.name}, python block {i + 1}", "exec"), namespace)
                ran.append((page.name, namespace))
    finally:
        os.chdir(cwd)
    pages = [name for name, _ in ran]
    print(f"docs: python blocks run: {pages}")
    assert "fmi-behaviour.md" in pages and "viewer.md" in pages
    recipe = next(ns for name, ns in ran if name == "fmi-behaviour.md")
    assert recipe["t"] == 1.5  # the recipe finished the step the FMU refused at first
    assert (tmp_path / "my_viewer" / "data" / "tilted.csv").exists()


def heading_anchor(heading):
    """GitHub's anchor of a Markdown heading."""
    text = re.sub(r"[^\w\- ]", "", heading.strip().lower())
    return text.replace(" ", "-")


@pytest.mark.quick
def test_the_links_between_the_pages_resolve():
    """Every relative link in README.md, ARCHITECTURE.md and docs/*.md names a file of the
    repository, and every #anchor a heading of that file."""
    pages = [ROOT / "README.md", ROOT / "ARCHITECTURE.md", *sorted((ROOT / "docs").glob("*.md"))]
    checked, broken = 0, []
    for page in pages:
        text = re.sub(r"```.*?```", "", page.read_text(), flags=re.S)
        for target in re.findall(r"\]\(([^)\s]+)\)", text):
            if re.match(r"[a-z]+:", target):
                continue  # an address on the web
            path, _, anchor = target.partition("#")
            file = (page.parent / path).resolve() if path else page
            checked += 1
            if not file.exists():
                broken.append(f"{page.name}: {target}: no such file")
            elif anchor:
                anchors = {heading_anchor(h) for h in re.findall(r"^#+ (.*)$", file.read_text(), re.M)}
                if anchor not in anchors:
                    broken.append(f"{page.name}: {target}: no heading with that anchor")
    print(f"links between the pages: {checked} checked")
    assert checked > 30 and not broken, broken


# A measured figure: a number in exponent form, a count with thousands separators, a decimal.
FIGURE = r"(?<![\w.,])(\d+\.\d+e[-+]?\d+|\d{1,3}(?:,\d{3})+|\d+\.\d+)(?![\d])(?! times)"
# A part marked WHOLE: every number it quotes, whole numbers too ("176 rad/s", "197 kg").
WHOLE = "every number"
NUMBER = r"(?<![\w.,])(\d+(?:\.\d+)?e[-+]?\d+|\d{1,3}(?:,\d{3})+|\d+(?:\.\d+)?)(?![\d.])(?! times)"
# The pages of docs/ that quote measurements, and the parts of each that do (None: all of it).
MEASURED_PAGES = {
    "performance.md": None,
    "model.md": [("an independent formulation written from this page alone", "## 8. The machine I"),
                 ("the residual stays below", "### Cost"),
                 ("20 % voltage ripple, 2 s at 1 ms communication steps", "In Model Exchange the host's"),
                 ("the rotor a particle of mass", "(through the FMUs: holding on the static"),
                 ("written from the specification alone, RK4 at 10 us): 3 s with valve commands", "### Cost"),
                 ("| method | largest leg error (m)", "Without the sub-steps RK4 rings"),
                 ("| RK4, 1 ms steps taken whole (no sub-steps) | 2.00e-6", "120 fuzzed runs on a Dask"),
                 ("3 L accumulator (its switch to empty", "## 11. Motion cueing"),
                 ("1. Holding under control: the pressures settle", "### Checks"),
                 ("which holds the\ndefault stand at", "| parameter | default |"),
                 ("the shipped motions stay clear:", "|"), ("the actuator failure's tilt onto the stops", "|"),
                 # Worked out from the defaults (tests/python/test_docs_derived.py) or measured by
                 # a test: every number of these parts, whole numbers too (WHOLE).
                 ("forces are then in units of", "equilibrium)", WHOLE),
                 ("keeps the default heave programme (legs", "|", WHOLE),
                 ("an elastomer cushion of", "|", WHOLE),
                 ("The direct problem gives the leg forces", "4. **Perturbed**"),
                 ("rotor 1.2e-3 and a", "|", WHOLE), ("105 V per 1000 rpm", "|", WHOLE),
                 ("20 mm per turn:", "|", WHOLE),
                 ("start without current;", "|", WHOLE), ("an ISO 63/36 mm cylinder:", "so large because", WHOLE),
                 ("adds a real pole", "it appears when", WHOLE),
                 ("the leg's force answers the valve at", "above the oil", WHOLE),
                 ("= 0 leaves", "The controller also has", WHOLE),
                 ("is both more accurate", "because once the platform"),
                 ("A landing from the top of the", "A higher precharge", WHOLE)],
    "validation.md": None,
    "control.md": None,
    "cueing.md": [("this is why a classical cycle costs", "An earlier form took each leg's first crossing"),
                  ("Between the constrained points a plan may pass", "The remaining 10 % of each stroke"),
                  ("**A failed solve**", "## Defaults: a truck cabin"),
                  ("The tuning was checked", "## Co-Simulation and Model Exchange"),
                  ("from §11 alone: every gain", "![OMCT of the defaults"),
                  ("## Checks", "- Predictive cueing runs in Co-Simulation only")],
    "studies.md": [("Throughput (", "## Tested on a real cluster")],
    "platforms.md": [("With the FMU's maths from the C library", "The Linux x86-64 binary is built"),
                     ("What it costs on x86-64", "## Building the binaries")],
}


@pytest.mark.quick
@pytest.mark.parametrize("page", sorted(MEASURED_PAGES))
def test_the_docs_quote_only_figures_the_benches_record(page):
    """The measured figures of docs/performance.md, validation.md and control.md, and of the
    measured parts of docs/studies.md, platforms.md, cueing.md and model.md (instruction counts
    with thousands separators, decimals, numbers in exponent form), are each in a file of
    benches/results/ (its counts are written there without the separators); a ratio ("7.3
    times") is read from the figures beside it. Each measured part quotes at least one figure."""
    text = prose((ROOT / "docs" / page).read_text())
    whole = []
    if MEASURED_PAGES[page]:
        parts = []
        for start, end, *every in MEASURED_PAGES[page]:
            # Each part from its start to the first end after it.
            at = text.find(start)
            until = text.find(end, at + 1) if at >= 0 else -1
            assert at >= 0 and until >= 0, f"docs/{page}: the bounds of a measured part moved: {start!r} .. {end!r}"
            parts.append(text[at:until])
            assert re.search(FIGURE if not every else NUMBER, parts[-1]), \
                f"docs/{page}: the measured part from {start!r} quotes no figure"
            if every:
                whole += [m.group(1) for m in re.finditer(NUMBER, parts[-1]) if not re.fullmatch(FIGURE, m.group(1))]
        text = "\n".join(parts)
    recorded = "\n".join(p.read_text() for p in sorted((ROOT / "benches" / "results").glob("*.txt")))
    figures = [m.group(1) for m in re.finditer(FIGURE, text)] + whole

    def recorded_as(figure):
        # Counts are written without separators, exponents with two digits (1.3e-08).
        forms = (figure, figure.replace(",", ""), re.sub(r"e([-+]?)(\d)$", r"e\g<1>0\2", figure))
        return any(re.search(rf"(?<![\d.]){re.escape(f)}(?![\d])", recorded) for f in forms)

    missing = [f for f in figures if not recorded_as(f)]
    print(f"docs/{page} quotes {len(figures)} measured figures, each in benches/results/: {figures}")
    assert len(figures) >= 3
    assert not missing, f"figures of docs/{page} that no file of benches/results/ records: {missing}"


@pytest.mark.quick
def test_the_tables_the_rust_tests_print_stand_in_the_docs_as_printed():
    """docs/model.md's work-precision tables (tests/hydraulics.rs prints them into
    benches/results/model.txt): every row, whole numbers too, as the test printed it."""
    recorded = (ROOT / "benches" / "results" / "model.txt").read_text()
    page = (ROOT / "docs" / "model.md").read_text()
    tables = re.findall(r"^\| method \| largest leg error \(m\).*?\n((?:\|.*\n)+)", page, re.M)
    rows = [line.replace("`", "") for table in tables for line in table.splitlines() if not line.startswith("|---")]
    print(f"docs/model.md: {len(rows)} rows of the work-precision tables, each in benches/results/model.txt")
    assert len(rows) == 10
    missing = [row for row in rows if row not in recorded]
    assert not missing, f"rows of docs/model.md that tests/hydraulics.rs did not print: {missing}"
