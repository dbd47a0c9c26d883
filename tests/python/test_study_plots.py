"""The studies' figures say what they show: axes labelled with each quantity's name and unit
from the FMUs' model descriptions (the non-dimensional scale in a non-dimensional study), and
a map's colour scale that shows the bulk of the values when one cell is an outlier (a run at
rest, 1e-15 m), with the cells beyond it marked."""

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import pytest

from stewart_fmu import labels, study_params
from stewart_fmu.sweep import _figure, colour_limits

pytestmark = pytest.mark.quick

VARIABLES = study_params.fmu_variables()


def test_parameters_and_metrics_are_labelled_with_their_names_and_units():
    assert labels.label("platform.M", VARIABLES) == "Mass of the loaded platform (M), kg"
    assert labels.label("controller.sine.amplitude[3]", VARIABLES) == "Amplitude of z (sine.amplitude[3]), m"
    assert labels.label("controller.sine.angleAmplitude[1]", VARIABLES) == \
        "Amplitude of roll (sine.angleAmplitude[1]), rad"
    assert labels.label("controller.G", VARIABLES).endswith("(G), N/m")
    assert labels.label("controller.G", VARIABLES, nondimensional=True).endswith(
        "(G), non-dimensional, units of M g/R_b")
    assert labels.label("step", VARIABLES, nondimensional=True) == \
        "Communication step, non-dimensional, units of sqrt(R_b/g)"
    assert labels.label("peak_deceleration", VARIABLES).endswith(", m/s²")
    assert labels.label("max_leg_error", VARIABLES) == "Largest leg-length error |l - l^p|, m"


def workspace_like():
    """A 6 x 7 map of leg errors about 1e-5 m with one cell of 2e-16 (both amplitudes 0)."""
    rng = np.random.default_rng(1)
    rows = []
    for z in [0.0, 0.1, 0.2, 0.3, 0.4, 0.5]:
        for roll in [0.0, 0.05, 0.1, 0.15, 0.2, 0.25, 0.3]:
            error = 2e-16 if z == roll == 0 else 10 ** rng.uniform(-6, -4.7)
            rows.append({"param:controller.sine.amplitude[3]": z, "param:controller.sine.angleAmplitude[1]": roll,
                         "max_leg_error": error, "stable": True, "status": "ok"})
    return pd.DataFrame(rows)


def test_a_map_labels_its_axes_and_keeps_an_outlier_off_the_colour_scale():
    results = workspace_like()
    spec = {"study": {"name": "workspace", "units": "si"}}
    p = {"kind": "map", "x": "controller.sine.amplitude[3]", "y": "controller.sine.angleAmplitude[1]",
         "value": "max_leg_error", "log": True}
    fig = _figure(plt, spec, results, p, VARIABLES)
    try:
        ax = fig.axes[0]
        image = ax.images[0]
        lo, hi = image.get_clim()
        marks = [t.get_text() for t in ax.texts]
        colourbar = fig.axes[-1]
        print(f"map: colour scale log10 {lo:.2f} .. {hi:.2f} over data {np.log10(results['max_leg_error']).min():.2f} .."
              f" {np.log10(results['max_leg_error']).max():.2f}; marks {marks}; x label {fig.get_supxlabel()!r}")
        # The bulk (1e-6 .. 2e-5) takes the scale (at most 3 interquartile ranges wider); the
        # 2e-16 cell is below it, marked "<".
        bulk = np.log10(results["max_leg_error"][results["max_leg_error"] > 1e-10])
        assert bulk.min() - 2.0 < lo <= bulk.min() and hi == bulk.max()
        assert marks == ["<"]
        assert fig.get_supxlabel() == "Amplitude of z (sine.amplitude[3]), m"
        assert ax.get_ylabel().replace("\n", " ") == "Amplitude of roll (sine.angleAmplitude[1]), rad"
        assert colourbar.get_ylabel().replace("\n", " ") == "log10 of Largest leg-length error |l - l^p|, m"
        assert "beyond the colour scale" in fig._suptitle.get_text().replace("\n", " ")
    finally:
        plt.close(fig)


def test_colour_limits_span_the_data_when_there_is_no_outlier():
    values = np.linspace(-4.9, -2.1, 40)
    assert colour_limits(values) == (values.min(), values.max())
    assert colour_limits([np.nan, 3.0, 3.0]) == (2.5, 3.5)
