"""diagnose's verdicts agree with what least-squares fits actually do on many virtual nights.

For each regime (summer and winter closed-loop, autumn forced response) and each free parameter
(Cr, Rw of the paper's reduced model), seeded nights are diagnosed as a user would (the operating
point chosen by diagnose) and then fitted by LS, with the paper's free set and with rczone's default
(which also estimates the wall's initial temperature). With the paper's fit, a parameter the nights
call identifiable must be recovered and one no night calls identifiable must not be (criteria in
:mod:`tests.acceptance.survey`). With the default fit, what diagnose calls identifiable is recovered
and summer's closed-loop failure of Rw remains; on other closed-loop cases diagnose can be
conservative (see ``docs/identifiability.md``). The truth is independent of
rczone's fitting code: the virtual building's true construction, aggregated the paper's way
(steady state) and, for the structural allowance, the exact layered-wall admittance at the test's
periods (:mod:`tests.acceptance.truth`).
"""

from __future__ import annotations

import numpy as np
import pytest

from tests.acceptance.survey import FITS, FREE, REGIMES, STRUCTURAL_FACTOR, night_outcome, summarize
from tests.acceptance.truth import hour_scale_wall_resistance, steady_state_equivalent

pytestmark = pytest.mark.slow  # > 4 s: out of make test (2026-12-02 durations), run by pytest -m slow

FAST_SEEDS = range(100, 108)
SLOW_SEEDS = range(200, 230)


def _summaries(seeds, fits=tuple(FITS)) -> dict[tuple[str, str, str], object]:
    """``(fit, regime, parameter)`` -> summary."""
    truth = steady_state_equivalent()
    out = {}
    for regime in REGIMES:
        outcomes = [night_outcome(regime, s, fits) for s in seeds]
        for fit in fits:
            for name in FREE:
                out[fit, regime, name] = summarize(outcomes, name, truth[name], fit)
    return out


@pytest.fixture(scope="module")
def fast():
    return _summaries(FAST_SEEDS, ("reduced",))  # the default fit: the slow test (time)


def _check_agreement(summaries) -> None:
    for (fit, regime, name), s in summaries.items():
        assert s.consensus != "mixed", f"{regime} {name}: verdicts differ between nights {s.verdicts}"
        if s.consensus == "identifiable":  # never false confidence, whichever fit
            assert s.recovered, f"{regime} {name} called identifiable but not recovered by the {fit} fit: {s}"
        elif fit == "reduced":
            assert not s.recovered, f"{regime} {name} called not identifiable but recovered: {s}"
    # the expected verdicts themselves (the paper's lesson)
    for name in FREE:
        assert summaries["reduced", "autumn forced", name].consensus == "identifiable"
        for regime in ("summer closed-loop", "winter closed-loop"):
            assert summaries["reduced", regime, name].consensus == "not identifiable"
    if ("default", "summer closed-loop", "Rw") in summaries:
        # the paper's failure mode survives rczone's default fit: summer Rw far below the truth.
        # Beyond that the default fit (which estimates the wall's initial state) often lands within
        # the structural allowance on closed-loop nights diagnose calls not identifiable: diagnose
        # is conservative there (docs/identifiability.md); not asserted, it depends on the search
        assert not summaries["default", "summer closed-loop", "Rw"].recovered


def test_verdicts_agree_with_fits(fast):
    _check_agreement(fast)


@pytest.mark.slow
def test_verdicts_agree_with_fits_many_nights():
    _check_agreement(_summaries(SLOW_SEEDS))


def test_forced_scatter_is_explained_by_the_model_error_allowance(fast):
    """On forced nights the estimates scatter more than the statistical standard error predicts.

    The scatter (std of ln theta over nights) exceeds diagnose's statistical expected standard error
    several-fold -- the errors come from model error that changes with each night's schedule and
    weather, not from sensor noise -- but diagnose's total predicted uncertainty (statistical plus
    worst-case model-error bias, at the quick fit diagnose runs on these nights) bounds it and is at
    most 2.5 times too pessimistic (docs/identifiability.md: 0.5-0.6 on the fast and slow nights).
    """
    for name in FREE:
        s = fast["reduced", "autumn forced", name]
        assert s.scatter_ln > 2 * s.se_rms, f"{name}: scatter {s.scatter_ln:.3f} vs se {s.se_rms:.3f}"
        assert s.u_rms / 2.5 <= s.scatter_ln <= s.u_rms, (
            f"{name}: scatter {s.scatter_ln:.3f} vs u {s.u_rms:.3f}"
        )


def test_forced_estimates_match_the_hour_scale_truth(fast):
    """The forced-night Rw is the wall's effective resistance at the test's periods (1-4 h).

    The reference comes from the exact admittance of the true layered walls, not from any fit.
    Tolerance: 10 % beyond the 1-4 h range (the schedule's blocks last 1-2.5 h, a cycle 3-7 h).
    """
    rw = fast["reduced", "autumn forced", "Rw"].gmean
    lo, hi = hour_scale_wall_resistance(3600.0), hour_scale_wall_resistance(4 * 3600.0)
    assert 0.9 * lo <= rw <= 1.1 * hi, f"Rw {rw:.4g} outside the hour-scale band [{lo:.4g}, {hi:.4g}]"


def test_closed_loop_fits_are_far_off_or_scattered(fast):
    """What 'not recovered' looks like: the fits fail in one of the ways the paper describes."""
    for regime in ("summer closed-loop", "winter closed-loop"):
        for name in FREE:
            s = fast["reduced", regime, name]
            off = abs(np.log(s.ratio_to_truth)) > np.log(STRUCTURAL_FACTOR)
            scattered = s.scatter_ln > np.log(2.0) or s.n_at_bound > 0
            assert off or scattered, f"{regime} {name}: {s}"
    # the paper's failure mode: closed-loop Rw far below the truth on every summer night, or (the
    # global search finds these too) at a bound of the search box: grossly wrong either way
    truth = steady_state_equivalent()["Rw"]
    assert fast["reduced", "summer closed-loop", "Rw"].max_inside < truth / 2


def test_structural_allowance_reference_is_consistent():
    """The hour-scale Rw tends to the steady-state aggregate at long periods, and is well below it at 1 h."""
    ss = steady_state_equivalent()["Rw"]
    assert hour_scale_wall_resistance(7 * 86400.0) == pytest.approx(ss, rel=0.05)
    assert hour_scale_wall_resistance(3600.0) < 0.6 * ss
    periods = [3600.0 * h for h in (1, 2, 4, 12, 48)]
    assert np.all(np.diff([hour_scale_wall_resistance(p) for p in periods]) > 0)
