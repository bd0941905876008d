"""Progress from inside long work: the search's starts, the sampler's draws, the closed loop's hours.

The estimation, control and emulation code is handed one object (``progress=None`` by default)
and only calls it; a recording object here counts what it is told and compares the count with
what the work did (the local searches in the result, the draws in the posterior, the simulated
hours). Through the CLI, with stderr redirected and the line interval set near zero by the
environment variable, a line with a count appears on stderr, stdout keeps the results only, and
``--quiet`` silences the lines.
"""

from __future__ import annotations

import io
import re

import numpy as np
import pytest

from rczone.cli.main import main
from rczone.cli.progress import INTERVAL_ENV, INTERVAL_S, LineReporter, Steps, interval_s
from rczone.estimation import fit
from rczone.estimation.methods.mcmc import McmcOptions
from tests.unit.estimation.nets import NET2, data2
from tests.unit.selection.synthetic import prbs_zone

LINE = re.compile(r"^\[\d+:\d\d:\d\d\] ")
COUNT = re.compile(r"\((\d+)/(\d+)\)$")


class Recorder:
    """A reporter that keeps what it is told."""

    def __init__(self):
        self.stages: list[str] = []
        self.steps: list[tuple[int, int | None]] = []

    def __call__(self, message: str) -> None:
        self.stages.append(message)

    def advance(self, done: int, total: int | None = None) -> None:
        self.steps.append((done, total))

    def close(self) -> None:
        pass


def test_the_interval_comes_from_the_environment_and_a_bad_value_is_ignored(monkeypatch):
    monkeypatch.setenv(INTERVAL_ENV, "0.25")
    assert interval_s() == 0.25 and LineReporter(io.StringIO()).interval == 0.25
    for bad in ("-1", "soon", "nan", "inf", ""):
        monkeypatch.setenv(INTERVAL_ENV, bad)
        assert interval_s() == INTERVAL_S


def test_steps_number_the_stages_and_pass_the_count_on():
    rec = Recorder()
    steps = Steps(rec, 3, "fitting {name}, candidate {i} of {n}")
    steps("Ti")
    steps.advance(2, 5)
    steps("TiTe")
    assert rec.stages == ["fitting Ti, candidate 1 of 3", "fitting TiTe, candidate 2 of 3"]
    assert rec.steps == [(2, 5)]


@pytest.mark.parametrize("method", ["ml", "ls"])
def test_the_global_search_tells_each_local_search(method):
    rec = Recorder()
    free = ["Cr", "Rw", "sigma_v"] if method == "ml" else ["Cr", "Rw"]
    res = fit(NET2, data2(noise=0.05, rng=np.random.default_rng(3)), free, method=method, progress=rec)
    assert rec.steps, "the search told nothing"
    done = [d for d, _ in rec.steps]
    assert done == sorted(done)
    # told once per local search of the main phase, at most one per search the result holds
    assert max(done) <= len(res.starts) and len(rec.steps) <= len(res.starts)
    assert all(t is not None and d <= t for d, t in rec.steps)


def test_without_progress_the_fit_is_the_same():
    data = data2(noise=0.05, rng=np.random.default_rng(3))
    a = fit(NET2, data, ["Cr", "Rw", "sigma_v"], method="ml", progress=Recorder())
    b = fit(NET2, data, ["Cr", "Rw", "sigma_v"], method="ml")
    assert a.estimates == b.estimates


def test_the_sampler_tells_its_draws_up_to_all_of_them():
    rec = Recorder()
    opts = McmcOptions(draws=20, tune=30, chains=2)
    data = data2(noise=0.05, rng=np.random.default_rng(11))
    fit(
        NET2,
        data,
        ["Cr", "Rw", "sigma_v"],
        method="mcmc",
        fixed={"sigma_w_Ti": 1e-6},
        options=opts,
        progress=rec,
    )
    total = opts.chains * (opts.draws + opts.tune)
    assert {t for _, t in rec.steps} == {total}
    done = [d for d, _ in rec.steps]
    assert done == sorted(done) and done[-1] == total  # every draw, warm-up included, came by


def test_the_closed_loop_tells_each_simulated_hour():
    from rczone.control.closedloop import closed_loop_test
    from rczone.control.virtualplant import WARMUP, VirtualPlant

    rec = Recorder()
    plant = VirtualPlant("summer", days=0.125, seed=1)
    closed_loop_test(plant, "thermostat", progress=rec)
    hours = round((WARMUP + 0.125 * 86400.0) / 3600.0)  # the plant's warm-up is simulated too: 6 h + 3 h
    assert rec.steps == [(k, hours) for k in range(1, hours + 1)]


@pytest.fixture(scope="module")
def csv(tmp_path_factory):
    path = tmp_path_factory.mktemp("inside") / "zone.csv"
    prbs_zone(days=1, seed=8).to_csv(path, index=False)
    return path


def _progress_lines(err: str) -> list[str]:
    return [x for x in err.splitlines() if LINE.match(x)]


@pytest.mark.parametrize("quiet", [False, True], ids=["lines", "quiet"])
def test_a_redirected_fit_counts_its_searches_on_stderr(csv, tmp_path, capsys, monkeypatch, quiet):
    monkeypatch.setenv(INTERVAL_ENV, "0")
    out = tmp_path / "fit.json"
    args = ["fit", str(csv), "--model", "Ti+heater", "--starts", "2", "--json", str(out), "--no-profiles"]
    assert main(args + ["--quiet"] * quiet) in (0, 3)
    captured = capsys.readouterr()
    lines = _progress_lines(captured.err)
    if quiet:
        assert lines == []
    else:
        counted = [COUNT.search(x) for x in lines if "fitting Ti+heater" in x]
        assert any(counted), f"no counted search line in {lines}"
        assert all(int(m.group(1)) <= int(m.group(2)) for m in counted if m)
    assert not _progress_lines(captured.out) and out.exists()  # stdout keeps the results only


@pytest.mark.parametrize("quiet", [False, True], ids=["lines", "quiet"])
def test_a_redirected_control_test_counts_its_hours_on_stderr(tmp_path, capsys, monkeypatch, quiet):
    monkeypatch.setenv(INTERVAL_ENV, "0")
    args = ["control-test", "--controller", "thermostat", "--days", "0.125", "--seed", "1"]
    assert main(args + ["--quiet"] * quiet) == 0
    captured = capsys.readouterr()
    lines = _progress_lines(captured.err)
    if quiet:
        assert lines == []
    else:
        assert any(x.endswith("simulated hours (9/9)") for x in lines), lines  # 6 h warm-up + 3 h
    assert not _progress_lines(captured.out) and "comfort" in captured.out.lower()


@pytest.mark.slow
def test_an_emulation_tells_each_simulated_day(tmp_path, capsys, monkeypatch):
    pytest.importorskip("pyenergyplus")
    monkeypatch.setenv(INTERVAL_ENV, "0")
    args = ["emulate", "--building", "office_small", "--start", "03-01", "--days", "2", "--step", "15"]
    assert main([*args, "-o", str(tmp_path / "run")]) == 0
    captured = capsys.readouterr()
    lines = _progress_lines(captured.err)
    assert any(x.endswith("simulated days (1/2)") for x in lines), lines
    assert any(x.endswith("simulated days (2/2)") for x in lines), lines
    assert not _progress_lines(captured.out) and (tmp_path / "run" / "trend.csv").exists()
