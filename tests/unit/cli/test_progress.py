"""Progress of long work: periodic lines off a terminal (a fake clock), none with --quiet."""

from __future__ import annotations

import io
import re

import pytest

import rczone.cli.progress as progress
from rczone.cli.main import main
from rczone.cli.progress import LineReporter, QuietReporter, TerminalReporter, reporter
from tests.unit.selection.synthetic import prbs_zone

LINE = re.compile(r"^\[\d+:\d\d:\d\d\] ")


class FakeClock:
    def __init__(self):
        self.now = 100.0

    def __call__(self):
        return self.now


def test_lines_come_at_most_every_interval_with_stage_count_and_elapsed_time():
    clock, out = FakeClock(), io.StringIO()
    rep = LineReporter(out, interval=10.0, clock=clock)
    rep("fitting TiTe")  # at once after the start: too soon
    assert out.getvalue() == ""
    clock.now += 9.9
    assert not rep.tick()
    clock.now += 0.1
    assert rep.tick() and out.getvalue() == "[0:00:10] fitting TiTe\n"
    clock.now += 5
    rep.advance(3, 8)
    assert out.getvalue().count("\n") == 1  # 5 s after the last line: nothing
    clock.now += 3600
    rep.advance(4, 8)
    assert out.getvalue().splitlines()[-1] == "[1:00:15] fitting TiTe (4/8)"
    clock.now += 10
    rep("profiling")  # a new stage that is due is written at once, its count reset
    assert out.getvalue().splitlines()[-1] == "[1:00:25] profiling"


def test_a_terminal_gets_a_bar_elsewhere_lines_and_quiet_nothing():
    class Tty(io.StringIO):
        def isatty(self):
            return True

    assert isinstance(reporter(quiet=True), QuietReporter)
    assert isinstance(reporter(stream=io.StringIO(), heartbeat=False), LineReporter)
    with reporter(stream=Tty()) as bar:
        assert isinstance(bar, TerminalReporter)
        bar("stage [x]")  # markup in a name stays literal
        bar.advance(1, 2)


@pytest.fixture(scope="module")
def csv(tmp_path_factory):
    path = tmp_path_factory.mktemp("progress") / "zone.csv"
    prbs_zone(days=1, seed=8).to_csv(path, index=False)
    return path


@pytest.mark.parametrize("quiet", [False, True], ids=["lines", "quiet"])
def test_a_redirected_select_reports_its_candidates_on_stderr(csv, capsys, monkeypatch, quiet):
    monkeypatch.setattr(progress, "INTERVAL_S", 0.0)  # every stage is due: no waiting in a test
    args = ["select", str(csv), "--model", "Ti+heater", "--model", "TiTe+heater", "--starts", "1"]
    assert main(args + ["--quiet"] * quiet) == 0
    captured = capsys.readouterr()
    lines = [x for x in captured.err.splitlines() if LINE.match(x)]
    if quiet:
        assert lines == []
    else:
        assert any("candidate 1 of 2" in x for x in lines) and any("candidate 2 of 2" in x for x in lines)
    assert not any(LINE.match(x) for x in captured.out.splitlines())  # stdout keeps the results only
