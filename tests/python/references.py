"""Committed reference files that tests compare with what they compute now: the viewer's default
stand (from the platform FMU's model description) and the figures the docs quote, in
benches/results/ (docs/validation.md's in validation.txt, docs/control.md's in control.txt, one
line a figure set, each written by the test that computes it).

A test whose figures moved fails and says how to write them again:
`STEWART_UPDATE_REFERENCES=1 .venv/bin/python -m pytest TEST` rewrites its part of the file
instead; then review the diff, bring the page that quotes the figures up to date, and commit
both with the change that moved them (tests/python/test_readme.py checks that every figure a
page quotes is in benches/results/)."""

import fcntl
import os
import xml.etree.ElementTree as ET
from pathlib import Path

from stewart_fmu import ROOT

UPDATE = os.environ.get("STEWART_UPDATE_REFERENCES") == "1"
RESULTS = ROOT / "benches" / "results"


def _current_test():
    return os.environ.get("PYTEST_CURRENT_TEST", "TEST").rsplit(" ", 1)[0]


def _mismatch(path, committed, text):
    test = _current_test()
    return AssertionError(
        f"{path.relative_to(ROOT)} holds\n  {committed}\nbut the code computes now\n  {text}\nIf the change is meant, "
        f"write it again with STEWART_UPDATE_REFERENCES=1 .venv/bin/python -m pytest {test}, bring the page that "
        f"quotes it up to date, and commit both")


def check_reference(path: Path, text: str):
    """The file `path` holds `text` (STEWART_UPDATE_REFERENCES=1: written). Called from the
    test that computes it."""
    if UPDATE:
        path.write_text(text)
        return
    committed = path.read_text() if path.exists() else "(missing)"
    if committed != text:
        raise _mismatch(path, committed, text)


def check_figures(name: str, key: str, text: str):
    """The line `key: text` of benches/results/NAME (the figures one test computes, in the
    form the page quotes them); with STEWART_UPDATE_REFERENCES=1 that line is written (other
    tests' lines stay; a lock keeps two writers apart). Called from the test that computes them."""
    path = RESULTS / name
    line = f"{key}: {text}"
    if UPDATE:
        with open(path, "a+") as f:
            fcntl.flock(f, fcntl.LOCK_EX)
            f.seek(0)
            lines = [x for x in f.read().splitlines() if x and not x.startswith(f"{key}: ")]
            head = [x for x in lines if x.startswith("#")]
            body = sorted(x for x in lines if not x.startswith("#"))
            f.seek(0)
            f.truncate()
            f.write("\n".join(head + sorted(body + [line])) + "\n")
        return
    committed = next((x for x in path.read_text().splitlines() if x.startswith(f"{key}: ")), "(no such line)") \
        if path.exists() else "(missing)"
    if committed != line:
        raise _mismatch(path, committed, line)


def short(x: float, digits: int = 2) -> str:
    """A figure in the exponent form the pages write: 2.2e3, 1.4e-1 (`digits` significant)."""
    mantissa, exponent = f"{x:.{digits - 1}e}".split("e")
    return f"{mantissa}e{int(exponent)}"


def start_values(model: str) -> dict:
    """{name: start value} of a committed FMI 2 model description (modelDescription/MODEL.xml:
    its Real, Integer and Boolean variables; a Boolean as 1.0 or 0.0)."""
    root = ET.parse(ROOT / "modelDescription" / f"{model}.xml").getroot()
    values = {}
    for variable in root.iter("ScalarVariable"):
        for kind in variable:
            if kind.tag in ("Real", "Integer", "Boolean") and "start" in kind.attrib:
                text = kind.attrib["start"]
                values[variable.attrib["name"]] = float(text == "true") if kind.tag == "Boolean" else float(text)
    return values
