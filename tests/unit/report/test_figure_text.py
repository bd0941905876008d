"""Every report's figures print what a reader should read: no raw TeX, user names as written.

Each figure is drawn (tick labels are made while drawing), then every visible text artist is read
as matplotlib shows it: a string with an even number of unescaped ``$`` is typeset as mathtext
(the log axes' ``$\\mathdefault{10^{-5}}$`` becomes 10 to the -5), any other string is printed as
written, with ``\\$`` shown as ``$``. The oracle is that rule, from matplotlib's documentation
("Writing mathematical expressions"), written out here rather than asked of matplotlib.
"""

from __future__ import annotations

import re

import numpy as np
import pandas as pd
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.text import Text

from rczone.cli.main import main
from rczone.report import Report
from rczone.report import figures as figs
from rczone.report.html import literal
from tests.unit.selection.synthetic import prbs_zone

HOSTILE = "a$\\frac{$b"


def shown(text: str) -> tuple[str, bool]:
    """What matplotlib draws for ``text``: (the string, typeset as mathtext?)."""
    dollars = len(re.findall(r"(?<!\\)\$", text))
    if dollars and dollars % 2 == 0:
        return text, True
    return text.replace("\\$", "$"), False


def drawn_texts(fig: Figure) -> list[tuple[str, bool]]:
    FigureCanvasAgg(fig).draw()
    texts = [t for t in fig.findobj(Text) if t.get_visible() and t.get_text()]
    return [shown(t.get_text()) if t.get_parse_math() else (t.get_text(), False) for t in texts]


def raw_tex(fig: Figure) -> list[str]:
    """Texts printed with a ``$`` or ``\\mathdefault`` in them (a formula shown as its source)."""
    return [s for s, math in drawn_texts(fig) if not math and ("$" in s or "\\mathdefault" in s)]


def typeset(fig: Figure) -> list[str]:
    return [s for s, math in drawn_texts(fig) if math]


@pytest.fixture
def captured(monkeypatch):
    """Every figure a report embeds, by name."""
    got: dict[str, Figure] = {}
    original = Report.figure

    def keep(self, name, fig, caption=""):
        got[name] = fig
        return original(self, name, fig, caption)

    monkeypatch.setattr(Report, "figure", keep)
    return got


@pytest.mark.slow  # > 4 s: out of make test (2026-12-02 durations), run by pytest -m slow
def test_the_demos_log_axes_are_typeset_not_printed_as_tex():
    from rczone.study.paper import paper_weights_study

    fc, _ = paper_weights_study()
    for fig in (figs.gains(fc), figs.gain_errors(fc), figs.paper_figs_5_6(fc)):
        assert raw_tex(fig) == []
        # the decades are mathtext, and typeset as such
        assert any("10^{-4}" in s for s in typeset(fig))


@pytest.fixture(scope="module")
def zone_csv(tmp_path_factory):
    d = tmp_path_factory.mktemp("figtext")
    prbs_zone(days=1, seed=3).to_csv(d / "zone.csv", index=False)
    return d / "zone.csv"


@pytest.mark.parametrize(
    "args",
    [
        pytest.param(["diagnose", "{csv}", "--model", "Ti+heater"], marks=pytest.mark.slow),
        pytest.param(
            ["fit", "{csv}", "--model", "Ti+heater", "--method", "ml", "--starts", "1", "--no-profiles"],
            marks=pytest.mark.slow,
        ),
        ["predict", "Ti+heater", "{csv}"],
        pytest.param(
            ["select", "{csv}", "--model", "Ti+heater", "--model", "TiTe+heater", "--starts", "1"],
            marks=pytest.mark.slow,
        ),
    ],
    ids=["diagnose", "fit", "predict", "select"],
)
def test_no_report_figure_prints_raw_tex(args, zone_csv, captured, tmp_path, capsys):
    argv = [a.format(csv=zone_csv) for a in args] + ["--report", str(tmp_path / "rep")]
    assert main(argv) == 0, capsys.readouterr()
    assert captured, "the report embedded no figure"
    for name, fig in captured.items():
        assert raw_tex(fig) == [], name


def test_the_profile_figure_log_axis_is_typeset():
    prof = {"Ci": {"values": [1e5, 1e6, 1e7], "rise": [5.0, 0.0, 4.0], "interval": (3e5, 4e6)}}
    fig = figs.profile_curves(prof, {"Ci": 1e6}, {"Ci": "J/K"})
    assert raw_tex(fig) == [] and any("10^{6}" in s for s in typeset(fig))


def test_the_batch_histograms_log_axis_is_typeset():
    from rczone.batch.summary import _histograms

    rng = np.random.default_rng(1)
    df = pd.DataFrame({"status": "ok", "method": "ls", "Ri": 10 ** rng.uniform(-3, -1, 40), "Ri_se": 0.0})
    fig = _histograms(df, ["Ri"])
    assert raw_tex(fig) == [] and typeset(fig)


def test_a_users_dollar_names_are_printed_as_written():
    t = np.linspace(0.0, 7200.0, 13)
    frame = pd.DataFrame({"time": t, HOSTILE: np.sin(t), "$x$": np.cos(t)})
    fig = figs.signals_overview(frame, [(HOSTILE, [HOSTILE, "$x$"])], title=f"zone {HOSTILE}")
    texts = [s for s, math in drawn_texts(fig) if not math]
    assert HOSTILE in texts and "$x$" in texts and f"zone {HOSTILE}" in texts
    fig = figs.fit_overview(t, np.sin(t), np.cos(t), title="$1", label="$T$")
    assert "$T$ (°C)" in [s for s, _ in drawn_texts(fig)]


@pytest.mark.parametrize("name", ["plain", "$", "$$", "a$b$c", "\\$", HOSTILE, "x\\\\$y$"])
def test_literal_is_never_read_as_mathtext_and_shows_the_name(name):
    assert shown(literal(name)) == (name, False)
