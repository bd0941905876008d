"""Generators of the second hostile campaign (issue 25): big integers, mathtext, daylight-saving
edges, pipes and devices, Unicode forms of names. Fast: a few dozen examples each.

The only outcomes are a result or one :class:`~rczone.errors.RczoneError` line.
"""

from __future__ import annotations

import os
import tempfile
import unicodedata
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rczone.data import read_column_map
from rczone.errors import RczoneError
from rczone.files.text import nfkc, read_toml

FAST = settings(max_examples=25, deadline=None, suppress_health_check=list(HealthCheck), database=None)


def one_line_or_result(call) -> None:
    try:
        call()
    except RczoneError as exc:
        assert "\n" not in str(exc), str(exc)


big_integers = st.one_of(st.integers(2**63, 10**600), st.integers(-(10**600), -(2**63) - 1))


@FAST
@given(
    big_integers,
    st.sampled_from(["air_density = {}", "[resample]\nstep = {}", "[resample]\nstep = 300\nmax_gap = {}"]),
)
def test_big_integers_in_a_column_map(n, where):
    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / "map.toml"
        text = where.format(n)
        p.write_text(
            ('[columns]\nTi = "Ti"\n' + text)
            if not where.startswith("air")
            else (text + '\n[columns]\nTi = "Ti"\n')
        )
        with pytest.raises(RczoneError, match=r"beyond 64 bits|not valid TOML"):
            read_column_map(p)


mathtext = st.lists(st.sampled_from([*"$\\{}^_ab", "\\frac", "\\sqrt", "$$"]), min_size=1, max_size=12).map(
    "".join
)


@pytest.mark.slow  # > 4 s: out of make test (2026-12-02 durations), run by pytest -m slow
@FAST
@given(mathtext)
def test_mathtext_in_figure_texts(s):
    import io

    from matplotlib.figure import Figure

    from rczone.report.html import literal

    fig = Figure(figsize=(2, 2))
    ax = fig.subplots()
    ax.set_title(literal(s))  # a user's text is drawn escaped, never parsed as mathtext
    ax.plot([0, 1], [0, 1], label=literal(s))
    ax.legend()
    ax.set_xticks([0, 1], [literal(s), literal(s)])
    fig.tight_layout()
    fig.savefig(io.BytesIO(), format="png")


# New York's changes in 2014: 2 a.m. on March 9 (skipped), 1 a.m. on November 2 (repeated)
dst_edges = st.builds(
    lambda day, minute: f"2014-{day} {1 + (day == '03-09'):02d}:{minute:02d}",
    st.sampled_from(["03-09", "11-02"]),
    st.integers(0, 59),
)


@FAST
@given(dst_edges, st.sampled_from(["start", "end"]))
def test_dst_edges_in_start_and_end(stamp, key):
    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / "map.toml"
        p.write_text(f'[time]\ntimezone = "America/New_York"\n{key} = "{stamp}"\n[columns]\nTi = "Ti"\n')
        one_line_or_result(lambda: read_column_map(p))


@pytest.mark.skipif(os.name == "nt", reason="pipes and devices as on POSIX")
@FAST
@given(st.sampled_from(["fifo", "/dev/zero", "/dev/null", "/dev/urandom", "loop", "folder"]))
def test_pipes_devices_and_loops_are_one_line(kind):
    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / "x.toml"
        if kind == "fifo":
            os.mkfifo(p)
        elif kind == "loop":
            p.symlink_to(p.name)
        elif kind == "folder":
            p.mkdir()
        else:
            p = Path(kind)
        with pytest.raises(RczoneError):
            read_toml(p, "column map")


names = st.lists(
    st.sampled_from(["\u00b5", "\u03bc", "\u2126", "\u03a9", "\ufb01", "fi", "\u00c5", "A\u030a", "R", "_"]),
    min_size=1,
    max_size=6,
).map("".join)


@FAST
@given(names)
def test_names_have_one_unicode_form(name):
    assert nfkc(name) == unicodedata.normalize("NFKC", name)
    assert nfkc({name: [name]}) == {nfkc(name): [nfkc(name)]}
    assert nfkc(nfkc(name)) == nfkc(name)
