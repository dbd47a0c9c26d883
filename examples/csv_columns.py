"""The examples' CSV writer: named columns of equal length, one row per index."""

import csv

import numpy as np


def write_columns(path, columns):
    """Writes `columns` (name -> sequence) to `path`, the names as the header row."""
    names = list(columns)
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(names)
        w.writerows(zip(*[np.asarray(columns[n]) for n in names]))
