"""The checks after a fit are made when first read, once, and equal the checks made at once (issue 34, item 7)."""

from __future__ import annotations

import pytest

import rczone
from rczone import datasets
from rczone.estimation.settings import FitSettings
from rczone.workflow import check_fit, fit_and_check
from rczone.workflow import checks as checks_module


@pytest.fixture(scope="module")
def night():
    return datasets.load("C")


@pytest.fixture
def counted(monkeypatch):
    """The number of times the post-fit checks ran."""
    calls = []
    made = checks_module.PostFitChecks.__call__

    def counting(self, cal):
        calls.append(cal)
        return made(self, cal)

    monkeypatch.setattr(checks_module.PostFitChecks, "__call__", counting)
    return calls


def test_a_fit_makes_no_check_until_a_result_that_needs_one_is_read(night, counted) -> None:
    cal = rczone.fit("first-order", night, n_starts=1)
    assert counted == []
    # the estimates and what they need cost nothing more
    assert cal.params.index.tolist() == list(cal.result.names)
    assert cal.model.theta and cal.open_loop.rmse_K > 0
    assert cal.model.provenance["flags"] == list(cal.result.flags)  # the fit's own, until the verdict
    assert counted == []
    verdict = cal.verdict
    assert len(counted) == 1
    assert cal.checks["profiles"] and cal.identifiability is not None
    cal.summary()
    cal.to_dict()
    assert len(counted) == 1
    assert cal.model.provenance["trustworthy"] == verdict.trustworthy
    assert cal.model.provenance["flags"] == list(verdict.reasons)


def test_the_checks_made_later_equal_the_checks_made_at_once(night, counted) -> None:
    lazy = rczone.fit("first-order", night, n_starts=1)
    settings = FitSettings(n_starts=1, checks=False)
    eager = check_fit(
        fit_and_check(rczone.load_model("first-order"), night, settings, label="C"), night, settings
    )
    assert len(counted) == 1  # the eager one
    assert lazy.checks == eager.checks
    assert lazy.verdict.to_dict() == eager.verdict.to_dict()
    assert lazy.identifiability.to_dict() == eager.identifiability.to_dict()
    assert len(counted) == 2


def test_without_checks_nothing_is_pending(night, counted) -> None:
    cal = rczone.fit("first-order", night, n_starts=1, checks=False)
    assert cal.pending is None and cal.checks is None and cal.identifiability is None
    assert cal.verdict is not None and counted == []
