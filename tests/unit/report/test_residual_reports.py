"""Reports a statistician reads: innovations, labelled open-loop residuals, profiles, periods, units."""

from __future__ import annotations

import numpy as np
import pytest
from matplotlib.figure import Figure

from rczone.calibration import calibrate
from rczone.postfit.profiles import profile_checks
from rczone.report import figures as figs
from rczone.report.fit import fit_report, parameter_rows
from tests.unit.selection.synthetic import TRUE_MODEL, prbs_zone


@pytest.fixture(scope="module")
def zone():
    return prbs_zone(days=1, seed=4)


@pytest.mark.slow  # > 4 s: out of make test (2026-12-02 durations), run by pytest -m slow
def test_ml_report_shows_innovations_profiles_and_units(zone, tmp_path):
    cal = calibrate(TRUE_MODEL, zone, method="ml", n_starts=1)
    prof = {
        k: v.to_dict()
        for k, v in profile_checks(cal.model, cal.data, cal.result, names=["Ci"], n_points=5).items()
    }
    checks = {
        "profiles": prof,
        "at_bound": [],
        "far_from_construction": {},
        "disagreements": [],
        "validation": {},
    }
    rep = fit_report(cal, zone, "zone", TRUE_MODEL, None, checks)
    html = rep.render()
    assert "Innovations: is anything left to explain?" in html and "Ljung-Box Q" in html
    assert {"innovations", "profiles"} <= set(rep.figures)
    assert parameter_rows(cal)[0]["unit"] == "J/K"
    rep.write(tmp_path)
    assert (tmp_path / "profiles.png").stat().st_size > 1000


@pytest.mark.slow  # > 4 s: out of make test (2026-12-02 durations), run by pytest -m slow
def test_ls_report_labels_open_loop_residuals(zone):
    cal = calibrate(TRUE_MODEL, zone, method="ls", n_starts=1)
    html = fit_report(cal, zone, "zone", TRUE_MODEL, None).render()
    row = parameter_rows(cal)[0]  # a family model starts from generic values, not construction data
    assert "generic start" in row and "construction" not in row and "estimate / construction" not in row
    assert "Open-loop residuals (not innovations)" in html and "not expected" in html
    assert "Innovations: is anything" not in html


def _labels(ax) -> list[str]:
    top = next(c for c in ax.child_axes if c is not ax)
    return [t.get_text() for t in top.get_xticklabels()]


def test_period_axes_label_frequencies_by_their_periods():
    ax = Figure().subplots()
    ax.semilogx([1e-6, 1e-2], [0, 1])  # Hz, as the frequency-response figures
    figs.period_axis(ax, per_hour=False)
    labels = _labels(ax)
    assert "1 d" in labels and "1 h" in labels and any(x.endswith("min") for x in labels)
    ax = Figure().subplots()
    ax.plot([0, 6], [0, 1])  # cycles per hour, linear, from zero (the cumulative periodogram)
    ax.set_xlim(0, 6)
    figs.period_axis(ax)
    labels = _labels(ax)
    assert "1 h" in labels and "10 min" in labels and len(labels) == len(set(labels))
    fig = figs.residual_acf(np.arange(1, 13), np.zeros(12), 200, dt_s=600.0)
    assert fig.axes[0].get_xlabel() == "lag (h)"
