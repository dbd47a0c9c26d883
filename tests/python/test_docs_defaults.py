"""The defaults tables that docs/model.md and docs/cueing.md write by hand (a parameter, its
default in the unit the page chose, why) against the committed model descriptions'
start values: a default changed in the code and not on the page (or the other way round)
fails here. A quoted default must equal the start value rounded to the digits the page gives
(628.3 rad/s for 628.3185...), in the unit the row names (deg, mH, L, L/min, MPa, ms)."""

import math
import re

import pytest

from references import start_values
from stewart_fmu import ROOT

pytestmark = pytest.mark.quick

DESCRIPTIONS = ("StewartPlatform", "StewartController", "StewartCueing")
# What one unit the pages write is in SI (the model descriptions' units).
TO_SI = {"deg": math.pi / 180, "deg/s": math.pi / 180, "mH": 1e-3, "L": 1e-3, "L/min": 1e-3 / 60, "MPa": 1e6,
         "kN": 1e3, "ms": 1e-3}
# A default as the pages write it: a number and, where the cell says it, its unit.
VALUE = re.compile(r"(?<![\w.])(-?\d+(?:\.\d+)?(?:e-?\d+)?)(?:\s+(deg/s|deg|mH|L/min|L|MPa|kN|ms|m/s2|m3/s|rad/s|"
                   r"Pa|m|s)\b)?")


STARTS = {model: start_values(model) for model in DESCRIPTIONS}


def elements(name, models=DESCRIPTIONS):
    """The model descriptions' variables a name of the pages stands for, in order, with the
    start values of each description that has them: `lmin[k]`, `pA0[1..6]`, `hp.f.omega`
    (a vector written without its index) all stand for the elements."""
    base = re.sub(r"\[(?:k|\d\.\.\d)\]$", "", name)
    found = []
    for model in models:
        starts = STARTS[model]
        if base in starts:
            found.append([(model, base, starts[base])])
            continue
        indexed = [(model, n, v) for n, v in starts.items() if re.fullmatch(rf"{re.escape(base)}\[\d+\]", n)]
        if indexed:
            found.append(sorted(indexed, key=lambda e: int(e[1].rsplit("[", 1)[1][:-1])))
    return found


def significant(text):
    """The significant digits a quoted number gives ("628.3": 4, "1.667e-3": 4, "16e6": 2)."""
    mantissa = re.split(r"e", text.lstrip("-"))[0].replace(".", "").lstrip("0")
    return max(1, len(mantissa))


def agrees(quoted, unit, start):
    """The start value, in the quoted unit, rounded to the quoted digits, is the quoted number."""
    value = float(quoted)
    if value == 0.0:
        return start == 0.0
    in_unit = start / TO_SI.get(unit, 1.0)
    rounded = float(f"{in_unit:.{significant(quoted)}g}")
    return math.isclose(rounded, value, rel_tol=1e-12)


def table_rows(page, header):
    """The rows (cells) of each table of `page` whose header starts with `header`."""
    rows, inside = [], False
    for line in (ROOT / "docs" / page).read_text().splitlines():
        if line.startswith(header):
            inside = True
            continue
        if inside and line.startswith("|---"):
            continue
        if inside and line.startswith("|"):
            rows.append([cell.strip() for cell in line.strip("|").split("|")])
        else:
            inside = False
    return rows


def defaults_of(row, unit_column, models):
    """[(a variable of the row, its quoted (number, unit) pairs)]: each name is the first
    `code` of its comma-separated entry (`hydraulic.bore` `D`: `D` is the paper's symbol); a
    cell of as many comma-separated parts as names gives one part to each, else its values
    stand for every name."""
    names = [m.group(1) for entry in row[0].split(",") if (m := re.search(r"`([^`]+)`", entry))]
    names = [n for n in names if elements(n, models)]
    cell = re.sub(r"`[^`]*`", "", row[1]).strip()
    if cell in ("true", "false"):
        return [(n, [("1" if cell == "true" else "0", None)]) for n in names]
    # A "Q (q m3/s)" cell quotes the default twice: the first, in the row's own unit.
    cell = re.sub(r"(\S)\s*\([^)]*\)$", r"\1", cell)
    units = [u.strip() for u in row[unit_column].split(",")] if unit_column is not None else []

    def pairs(text, unit):
        found = [(m.group(1), m.group(2)) for m in VALUE.finditer(text)]
        return [(q, u or unit) for q, u in found]

    parts = [p for p in re.split(r",(?![^(]*\))", cell)]
    if len(names) > 1 and len(parts) == len(names):
        per_name = [pairs(part, units[i] if len(units) == len(names) else (units or [None])[0])
                    for i, part in enumerate(parts)]
    else:
        per_name = [pairs(cell, units[0] if units else None)] * len(names)
    return [(n, p) for n, p in zip(names, per_name) if p]


# (page, the table's header, its unit column if it has one, the FMUs whose parameters it lists:
# the platform's, which the controller shares where it has the same name).
MACHINE = ("StewartPlatform", "StewartController")
CASES = [("model.md", "| parameter | default | unit |", 2, MACHINE),
         ("model.md", "| parameter | default | why |", None, MACHINE),
         ("cueing.md", "| parameter | default | started from |", None, ("StewartCueing",))]


@pytest.mark.parametrize("page,header,unit_column,models", CASES, ids=[f"{p} {h}" for p, h, _, _ in CASES])
def test_the_defaults_tables_hold_the_model_descriptions_start_values(page, header, unit_column, models):
    rows = table_rows(page, header)
    assert len(rows) >= 5, f"docs/{page}: no table starting {header!r}"
    checked, wrong, unread = [], [], []
    for row in rows:
        defaults = defaults_of(row, unit_column, models)
        if not defaults:
            unread.append(row[0])
            continue
        for name, pairs in defaults:
            for description in elements(name, models):
                n = len(description)
                if len(pairs) == n:
                    quoted = pairs  # element by element: (0.5, 0.4, 1.0) m
                elif len(pairs) == 1:
                    quoted = pairs * n
                else:
                    wrong.append(f"{row[0]}: {len(pairs)} defaults for {name}, of {n} elements")
                    continue
                for (model, element, start), (q, unit) in zip(description, quoted):
                    checked.append(element)
                    if not agrees(q, unit, start):
                        wrong.append(f"{element} ({model}): the page says {q} {unit or ''}, the start value is "
                                     f"{start!r}")
    print(f"docs/{page} {header}: {len(checked)} start values checked ({len(set(checked))} variables); rows "
          f"without a numeric default: {unread}")
    assert not wrong, f"docs/{page}: defaults that are not the model descriptions' start values: {wrong}"
    assert len(set(checked)) >= 5


def test_a_changed_default_is_caught():
    """The comparison can fail: a digit off, a unit off, a rounding the page did not make."""
    assert agrees("628.3", None, 2 * math.pi * 100) and not agrees("628.4", None, 2 * math.pi * 100)
    assert agrees("25", "deg", math.radians(25)) and not agrees("25", None, math.radians(25))
    assert agrees("0.4", "mH", 4e-4) and agrees("800", "L/min", 0.8 / 60) and not agrees("0", None, 1e-13)
    assert not agrees("1.667e-3", None, 1.6e-3) and agrees("7.2807e6", None, 7280681.199347934)
