"""The defaults tables that docs/model.md and docs/cueing.md write by hand (a parameter, its
default in the unit the page chose, why) against the committed model descriptions'
start values: a default changed in the code and not on the page (or the other way round)
fails here, and so does a row that names no variable or whose default this test cannot read.
A quoted default must equal the start value in the unit the row names (deg, mH, L, L/min, MPa,
ms); only a quote of four or more significant digits may be the start value rounded (628.3
rad/s for 628.3185...)."""

import math
import re

import pytest

from references import start_values
from stewart_fmu import ROOT

pytestmark = pytest.mark.quick

DESCRIPTIONS = ("StewartPlatform", "StewartController", "StewartCueing")
STARTS = {model: start_values(model) for model in DESCRIPTIONS}
# What one unit the pages write is in SI (the model descriptions' units).
TO_SI = {"deg": math.pi / 180, "deg/s": math.pi / 180, "mH": 1e-3, "L": 1e-3, "L/min": 1e-3 / 60, "MPa": 1e6,
         "kN": 1e3, "ms": 1e-3}
UNIT = r"deg/s|deg|mH|L/min|L|MPa|kN|ms|m/s2|m3/s|rad/s|Pa|m|s"
# A default as the pages write it: a number and, where the cell says it right after it, its unit.
VALUE = re.compile(rf"(?<![\w.])(-?\d+(?:\.\d+)?(?:e-?\d+)?)(?:\s+({UNIT})\b)?")
# Defaults the pages write as a relation to another value: the words, and the value a variable
# so described must have.
PLATFORM = STARTS["StewartPlatform"]
RELATIONS = {
    # joints.r0, joints.angles0: the joints are assembled in the neutral pose.
    "neutral pose": lambda element: PLATFORM[element.removeprefix("joints.")],
    # The cueing's stand: one set of stand values describes all three FMUs.
    "the platform's": lambda element: PLATFORM[element],
    # relief.gain: `Q_max` per MPa.
    "per MPa": lambda element: PLATFORM["pump.maxFlow"] / 1e6,
}


def variables(name, model):
    """The model description's variables a name of the pages stands for, in order: `lmin[k]`,
    `pA0[1..6]`, `hp.f.omega` (a vector written without its index), `B` (a matrix) all stand
    for the elements."""
    starts = STARTS[model]
    base = re.sub(r"\[(?:k|\d\.\.\d)\]$", "", name)
    if base in starts:
        return [base]
    indexed = [n for n in starts if re.fullmatch(rf"{re.escape(base)}\[\d+(?:,\d+)?\]", n)]
    return sorted(indexed, key=lambda n: tuple(int(i) for i in n.rsplit("[", 1)[1][:-1].split(",")))


def significant(text):
    """The significant digits a quoted number gives ("628.3": 4, "1.667e-3": 4, "16e6": 2)."""
    mantissa = re.split(r"e", text.lstrip("-"))[0].replace(".", "").lstrip("0")
    return max(1, len(mantissa))


def agrees(quoted, unit, start):
    """The start value, in the quoted unit, is the quoted number (to the round-off of the unit's
    conversion); a quote of four or more significant digits may be it rounded to those digits."""
    value, in_unit = float(quoted), start / TO_SI.get(unit, 1.0)
    if math.isclose(in_unit, value, rel_tol=1e-12, abs_tol=0.0):
        return True
    digits = significant(quoted)
    return digits >= 4 and math.isclose(float(f"{in_unit:.{digits}g}"), value, rel_tol=1e-12)


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


def quoted(text, unit):
    """The (number, unit) pairs of a part of a cell: a number's own unit, else the unit written
    after the last number ("2.5, 2.5, 4 rad/s", "(0.5, 0.4, 1.0) m"), else the row's."""
    found = [(m.group(1), m.group(2)) for m in VALUE.finditer(text)]
    trailing = re.search(rf"(?:\d|\))\s*({UNIT})\s*$", text)
    after = trailing.group(1) if trailing else unit
    return [(q, u or after) for q, u in found]


def defaults_of(row, unit_column):
    """(the row's names, [(name, its quoted (number, unit) pairs, or the words of a relation)]):
    each name is the first
    `code` of its comma-separated entry (`hydraulic.bore` `D`: `D` is the paper's symbol); a
    cell of as many comma-separated parts as names gives one part to each, else its values
    stand for every name. A cell "Q (q m3/s)" quotes the default twice, both checked."""
    names = [m.group(1) for entry in row[0].split(",") if (m := re.search(r"`([^`]+)`", entry))]
    cell = re.sub(r"`[^`]*`", "", row[1]).strip()
    if cell in ("true", "false"):
        return names, [(n, [("1" if cell == "true" else "0", None)]) for n in names]
    units = [u.strip() for u in row[unit_column].split(",")] if unit_column is not None else []
    parts = re.split(r",(?![^(]*\))", cell)
    if len(names) > 1 and len(parts) == len(names):
        unit_of = (lambda i: units[i]) if len(units) == len(names) else (lambda i: units[0] if units else None)
    else:
        parts, unit_of = [cell] * len(names), (lambda i: units[0] if units else None)
    defaults = []
    for i, (name, part) in enumerate(zip(names, parts)):
        again = re.fullmatch(r"(.*\S)\s*\(([^)]*)\)", part.strip())
        relation = next((words for words in RELATIONS if words in part), None)
        if relation:
            defaults.append((name, relation))
        elif again and VALUE.search(again.group(1)):
            defaults += [(name, quoted(again.group(1), unit_of(i))), (name, quoted(again.group(2), None))]
        else:
            defaults.append((name, quoted(part, unit_of(i))))
    return names, [(n, p) for n, p in defaults if p]


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
    checked, wrong = [], []
    for row in rows:
        names, defaults = defaults_of(row, unit_column)
        unknown = [n for n in names if not any(variables(n, m) for m in models)]
        if unknown or not names:
            wrong.append(f"{row[0]}: names no variable of {models} ({unknown})")
            continue
        if not defaults:
            wrong.append(f"{row[0]}: no default this test can read in {row[1]!r}")
        for name, pairs in defaults:
            for model in models:
                elements = variables(name, model)
                if not elements:
                    continue
                if isinstance(pairs, str):
                    for element in elements:
                        checked.append(element)
                        if STARTS[model][element] != RELATIONS[pairs](element):
                            wrong.append(f"{element} ({model}): the page says {pairs!r}, {RELATIONS[pairs](element)!r};"
                                         f" the start value is {STARTS[model][element]!r}")
                    continue
                if len(pairs) == 1:
                    pairs = pairs * len(elements)
                if len(pairs) != len(elements):
                    wrong.append(f"{row[0]}: {len(pairs)} defaults for {name}, of {len(elements)} elements")
                    continue
                for element, (q, unit) in zip(elements, pairs):
                    checked.append(element)
                    start = STARTS[model][element]
                    if not agrees(q, unit, start):
                        wrong.append(f"{element} ({model}): the page says {q} {unit or ''}, the start value is "
                                     f"{start!r}")
    print(f"docs/{page} {header}: {len(checked)} start values checked ({len(set(checked))} variables)")
    assert not wrong, f"docs/{page}: defaults that are not the model descriptions' start values: {wrong}"
    assert len(set(checked)) >= 5


def test_a_changed_default_is_caught():
    """The comparison can fail: a digit off, a unit off, a rounding the page did not make, a
    default of one or two digits that moved within their rounding."""
    assert agrees("628.3", None, 2 * math.pi * 100) and not agrees("628.4", None, 2 * math.pi * 100)
    assert agrees("25", "deg", math.radians(25)) and not agrees("25", None, math.radians(25))
    assert agrees("0.4", "mH", 4e-4) and agrees("800", "L/min", 0.8 / 60) and not agrees("0", None, 1e-13)
    assert not agrees("1.667e-3", None, 1.6e-3) and agrees("7.2807e6", None, 7280681.199347934)
    assert not agrees("1e7", None, 1.4e7) and not agrees("0.4", "mH", 0.44e-3) and not agrees("0.7", None, 0.74)
    assert quoted("2.5, 2.5, 4 rad/s", None) == [("2.5", "rad/s"), ("2.5", "rad/s"), ("4", "rad/s")]
    assert quoted("(0.5, 0.4, 1.0) deg", None) == [("0.5", "deg"), ("0.4", "deg"), ("1.0", "deg")]
    assert defaults_of(["`x.y`, `x.z`", "16 MPa, 0.5 MPa"], None)[1] == [("x.y", [("16", "MPa")]),
                                                                           ("x.z", [("0.5", "MPa")])]
