"""Output to a file or a pipe is never wrapped: a number or a word stays whole on its line.

rich wraps at 80 columns when it cannot ask a terminal its width; ``rczone fit C > out`` split
``4.499e+05`` and header words across lines. A wrapped table shows itself by continuation rows
whose first cell is blank; an unwrapped one has none.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys

import pytest

from rczone.cli.console import UNWRAPPED_WIDTH, console, unwrapped
from rczone.cli.main import main
from tests.unit.selection.synthetic import prbs_zone


def continuation_rows(text: str) -> list[str]:
    """Table rows whose first cell is blank (a cell wrapped onto a second line)."""
    rows = [line for line in text.splitlines() if line.startswith("│")]
    return [r for r in rows if not r.split("│")[1].strip()]


@pytest.mark.slow  # > 4 s: out of make test (2026-12-02 durations), run by pytest -m slow
def test_a_piped_table_keeps_each_row_on_one_line():
    env = {k: v for k, v in os.environ.items() if k != "COLUMNS"}
    proc = subprocess.run(
        [sys.executable, "-m", "rczone.cli", "models"], capture_output=True, text=True, env=env, timeout=300
    )
    assert proc.returncode == 0, proc.stderr
    assert continuation_rows(proc.stdout) == []
    assert "MRC(13, 8, 32) full-scale model of office 241" in proc.stdout  # a long cell, whole
    assert max(len(x) for x in proc.stdout.splitlines()) > 80


def test_a_redirected_fit_prints_whole_numbers(tmp_path, capsys, monkeypatch):
    monkeypatch.delenv("COLUMNS", raising=False)
    path = tmp_path / "zone.csv"
    prbs_zone(days=1, seed=9).to_csv(path, index=False)
    assert main(["fit", str(path), "--model", "TiTe+heater", "--method", "ls", "--starts", "1"]) in (0, 3)
    out = capsys.readouterr().out
    assert continuation_rows(out) == []
    (ci,) = [r for r in out.splitlines() if r.startswith("│") and r.split("│")[1].strip() == "Ci"]
    assert re.search(r"\d\.\d+e\+0\d", ci)  # the capacity, e.g. 2.001e+06, whole on its row
    # a built-in family model's values before the fit are generic starts, not construction data
    (head,) = [line for line in out.splitlines() if "parameter" in line and "estimate" in line]
    assert "generic start" in head and "construction" not in head


@pytest.mark.parametrize("stderr", [False, True])
def test_a_console_off_a_terminal_is_unwrapped(stderr, monkeypatch):
    monkeypatch.delenv("COLUMNS", raising=False)
    assert console(stderr=stderr).width == UNWRAPPED_WIDTH  # pytest's streams are no terminal
    monkeypatch.setenv("COLUMNS", "100")  # a width asked for is kept
    assert console(stderr=stderr).width == 100

    class Terminal:
        is_terminal, width = True, 93

    term = Terminal()
    assert unwrapped(term).width == 93  # type: ignore[arg-type]
