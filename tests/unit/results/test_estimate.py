"""The Estimate record and the one verdict."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
from scipy import stats

from rczone.results import Estimate
from rczone.results.verdict import verdict_of


def test_a_log_scale_interval_is_the_normal_interval_of_the_log_mapped_back() -> None:
    e = Estimate("Cr", 3.0e5, 2.0e4, 1e4, 1e7, 4.5e5, False, "J/K", "capacitance", True)
    lo, hi = stats.norm.interval(0.95, loc=math.log(3.0e5), scale=2.0e4 / 3.0e5)
    assert e.interval() == pytest.approx((math.exp(lo), math.exp(hi)), rel=1e-12)
    assert e.interval()[0] > 0 and e.interval()[1] - 3.0e5 > 3.0e5 - e.interval()[0]  # asymmetric


def test_a_linear_interval_is_symmetric_and_none_without_a_standard_error() -> None:
    e = Estimate("x0_Tw", 22.5, 0.04, -50, 100, math.nan, False, "degC", "state", False)
    assert e.interval(0.1) == pytest.approx(stats.norm.interval(0.9, loc=22.5, scale=0.04), rel=1e-12)
    assert all(math.isnan(v) for v in e._replace(std_error=math.nan).interval())
    assert e.to_dict()["interval_95"] == pytest.approx(list(stats.norm.interval(0.95, loc=22.5, scale=0.04)))
    with pytest.raises(ValueError, match="alpha"):
        e.interval(1.5)


def _fit(**kw):
    est = {"Rw": Estimate("Rw", 0.004, 1e-4, 1e-4, 1.0, 0.008, False, "K/W", "resistance", True)}
    return SimpleNamespace(flags=(), issues=(), parameters=est, **kw)


def _report(**verdicts):
    return SimpleNamespace(parameters={n: SimpleNamespace(verdict=v) for n, v in verdicts.items()})


@pytest.mark.parametrize(
    ("identifiability", "checks", "trustworthy", "suspect"),
    [
        (None, None, True, ()),
        (_report(Rw="identifiable"), None, True, ()),
        (_report(Rw="weak"), None, True, ()),  # a note, not a flag
        (_report(Rw="not identifiable"), None, True, ()),  # a note too: other data decide
        (None, {"profiles": {"Rw": {"flat_low": True, "flat_high": False}}}, False, ("Rw",)),
        (
            None,
            {
                "other_fits": {"B": {}},
                "disagreements": [
                    {
                        "name": "Rw",
                        "data_a": "A",
                        "data_b": "B",
                        "estimate_a": 1.0,
                        "estimate_b": 3.0,
                        "disagree": True,
                    }
                ],
            },
            False,
            ("Rw",),
        ),
    ],
)
def test_the_verdict_counts_every_check(identifiability, checks, trustworthy, suspect) -> None:
    v = verdict_of(_fit(), identifiability, checks)
    assert v.trustworthy is trustworthy and v.suspect == suspect
    assert bool(v.reasons) is not trustworthy
    doubted = identifiability is not None and identifiability.parameters["Rw"].verdict != "identifiable"
    assert bool(v.notes) is doubted and all("Rw" in n for n in v.notes)


def test_the_fit_own_flags_are_part_of_the_verdict() -> None:
    r = _fit()
    r.flags, r.issues = ("Rw is at a bound",), ("at_bound",)
    r.parameters["Rw"] = r.parameters["Rw"]._replace(at_bound=True)
    v = verdict_of(r)
    assert not v.trustworthy and v.reasons == ("Rw is at a bound",) and v.suspect == ("Rw",)
    assert np.array_equal(v.checked, ("fit",))


@pytest.mark.parametrize(
    ("value", "lower", "upper", "at_bound", "log_scale", "side"),
    [
        (1e9, 1e4, 1e9, True, True, "upper"),
        (1e4, 1e4, 1e9, True, True, "lower"),
        # 2e6 lies below the log-space middle sqrt(1e4 * 1e9) = 3.2e6: on the optimizer's (log) scale
        # it is nearer the lower bound, though far below the arithmetic middle too
        (2e6, 1e4, 1e9, True, True, "lower"),
        (1e8, 1e4, 1e9, True, True, "upper"),
        (-19.9, -20.0, 20.0, True, False, "lower"),
        (19.9, -20.0, 20.0, True, False, "upper"),
        (5.0, -20.0, 20.0, False, False, None),
    ],
)
def test_the_bound_an_estimate_sits_at(value, lower, upper, at_bound, log_scale, side):
    e = Estimate("x", value, math.nan, lower, upper, math.nan, at_bound, log_scale=log_scale)
    assert e.bound_side == side
