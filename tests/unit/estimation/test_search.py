"""The global search: finds the better of two basins, merges identical optima, says when it is unsure."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rczone.errors import ParameterError
from rczone.estimation import make_spec
from rczone.estimation.optimize import StartOutcome
from rczone.estimation.search import global_search, latin_hypercube, merge_optima

from .nets import NET1


def _spec():
    # R in [1e-4, 1] around 0.01, Cr in [1e3, 1e9] around 1e6 (log space, 4 and 6 decades)
    return make_spec(NET1, ["Cr", "R"], start={"R": 0.3}, bounds={"R": (1e-4, 1.0), "Cr": (1e3, 1e9)})


def two_basins(eta: np.ndarray) -> float:
    """A narrow deep basin at R = 1e-3 and a wide shallow one at R = 0.3 (where the start is)."""
    r, c = eta[1], eta[0] - math.log(1e6)
    deep = (r - math.log(1e-3)) ** 2 / 0.05 + 0.01 * c**2
    shallow = 0.5 * (r - math.log(0.3)) ** 2 + 0.01 * c**2 + 3.0
    return float(min(deep, shallow))


def test_a_local_search_from_the_start_stays_in_the_worse_basin_the_global_one_does_not() -> None:
    spec = _spec()
    local, s1 = global_search(two_basins, spec, "ml", np.random.default_rng(0), n_starts=1)
    assert s1.strategy == "local" and s1.n_sampled == 0
    assert local[0].end[1] == pytest.approx(0.3, rel=1e-3)  # the shallow basin, cost 3
    # confirmed by a second method that cannot leave the basin either: honest about the method, not magic
    assert s1.confirmed_by == "powell" and s1.converged
    outs, s = global_search(two_basins, spec, "ml", np.random.default_rng(0))
    best = min(outs, key=lambda o: o.cost)
    assert best.end[1] == pytest.approx(1e-3, rel=1e-3) and best.cost == pytest.approx(0.0, abs=1e-8)
    assert s.converged and s.n_best >= 2 and "reached from" in s.reason
    assert s.optima[0].cost < s.optima[-1].cost  # the shallow basin is reported as a worse optimum
    assert any(o.theta[1] == pytest.approx(0.3, rel=1e-3) for o in s.optima)


def test_fixed_number_of_starts_runs_exactly_that_many() -> None:
    outs, s = global_search(two_basins, _spec(), "ml", np.random.default_rng(1), n_starts=5)
    assert len(outs) in (5, 6) and s.n_local == len(outs)  # + a confirmation if the best was found once
    np.testing.assert_allclose(outs[0].start, _spec().start)  # the model's own start is always tried
    with pytest.raises(ParameterError, match="positive integer"):
        global_search(two_basins, _spec(), "ml", np.random.default_rng(1), n_starts=0)


def test_a_best_optimum_found_once_and_beaten_by_the_second_method_is_not_converged() -> None:
    calls = {"n": 0}

    def fickle(eta: np.ndarray) -> float:
        # Nelder-Mead sees a plateau it stops on; Powell's line searches find the slope beyond it
        calls["n"] += 1
        r = eta[1] - math.log(0.01)
        return float(min(abs(r), 0.5) ** 2 + (eta[0] - math.log(1e6)) ** 2 + (1e-3 * r if r > 0.5 else 0.0))

    _, s = global_search(fickle, _spec(), "ml", np.random.default_rng(3), n_starts=1)
    assert s.n_local == 2  # the local search and the second method
    if s.confirmed_by is None:
        assert not s.converged and "not settled" in s.reason
    else:
        assert s.converged


def test_merge_uses_a_cost_tolerance_and_keeps_the_order() -> None:
    def out(cost: float, r: float) -> StartOutcome:
        return StartOutcome(np.zeros(2), np.array([1e6, r]), cost, True, 10, "")

    optima, tol = merge_optima(
        [out(5.0, 0.1), out(1.0, 0.01), out(1.0 + 1e-3, 0.011), out(math.nan, 1.0)], "ml"
    )
    assert tol == pytest.approx(0.01 + 1e-9)
    assert [o.count for o in optima] == [2, 1] and optima[0].starts == (1, 2)
    optima, _ = merge_optima([out(100.0, 0.1), out(100.0001, 0.1), out(101.0, 0.2)], "ls")
    assert [o.count for o in optima] == [2, 1]  # least squares: relative tolerance 1e-5
    optima, _ = merge_optima([out(1e-20, 0.1), out(1e-18, 0.1)], "ls", scale=1e4)
    assert [o.count for o in optima] == [2]  # a perfect fit: tolerance relative to the data's variation


def test_latin_hypercube_has_one_point_per_stratum() -> None:
    u = latin_hypercube(16, 3, np.random.default_rng(2))
    assert u.shape == (16, 3) and np.all((u >= 0) & (u < 1))
    for j in range(3):
        assert sorted(np.floor(u[:, j] * 16).astype(int)) == list(range(16))


def test_a_gradient_search_is_confirmed_by_a_restart_near_its_optimum_not_a_direct_search() -> None:
    from rczone.estimation.search import DISPLACEMENT, displaced

    spec = _spec()
    outs, s = global_search(two_basins, spec, "ml", np.random.default_rng(0), optimizer="lbfgs", n_starts=1)
    assert s.confirmed_by == "lbfgs" and s.converged and "restart of lbfgs near it" in s.reason
    assert len(outs) == 2 and outs[1].end[1] == pytest.approx(outs[0].end[1], rel=1e-4)  # came back
    # the restart starts DISPLACEMENT of the box away in every parameter, inside the box
    theta = np.array([1e6, 0.9])  # R near its upper bound 1: the step goes the other way
    moved = spec.to_eta(displaced(spec, theta, np.random.default_rng(2))) - spec.to_eta(theta)
    np.testing.assert_allclose(np.abs(moved), DISPLACEMENT * (spec.eta_upper - spec.eta_lower), rtol=1e-9)
    assert moved[1] < 0
    outs, s = global_search(two_basins, spec, "ml", np.random.default_rng(0), optimizer="lbfgs")
    assert min(o.cost for o in outs) == pytest.approx(0.0, abs=1e-8) and s.converged  # the deep basin


def test_an_adaptive_gradient_search_stops_when_its_start_and_a_restart_near_it_agree() -> None:
    """Early agreement: one basin, the model's start converges, the restart DISPLACEMENT away comes back;
    two agreeing starts end the search before any sampled start (every sampled point costs more)."""
    from rczone.estimation.search import DISPLACEMENT

    spec = _spec()

    def one_basin(eta: np.ndarray) -> float:
        return float((eta[1] - math.log(0.02)) ** 2 + 0.01 * (eta[0] - math.log(1e6)) ** 2)

    outs, s = global_search(one_basin, spec, "ml", np.random.default_rng(0), optimizer="lbfgs")
    assert s.n_local == len(outs) == 2 and s.n_best == 2 and s.converged
    assert s.reason == "the best optimum was reached from 2 of 2 starts"
    np.testing.assert_allclose(outs[0].start, spec.start)
    moved = np.abs(spec.to_eta(outs[1].start) - spec.to_eta(outs[0].end))
    np.testing.assert_allclose(moved, DISPLACEMENT * (spec.eta_upper - spec.eta_lower), rtol=1e-6)
    np.testing.assert_allclose(outs[1].end, [1e6, 0.02], rtol=1e-4)  # the minimum, known by construction


def test_two_converged_ends_that_agree_to_rounding_are_not_polished(monkeypatch) -> None:
    """``ends_agree``: two searches that converged by their own test and end within COST_TIE (relative)
    of each other need no polish; one converged end, or ends further apart, do."""
    from rczone.estimation import search
    from rczone.estimation.search import COST_TIE, Optimum, ends_agree

    def out(cost: float, converged: bool = True) -> StartOutcome:
        return StartOutcome(np.ones(2), np.ones(2), cost, converged, 10, "")

    c = -1234.5
    tie = COST_TIE * abs(c)
    best = Optimum(c, np.ones(2), (0, 1))
    assert ends_agree([out(c), out(c + 0.5 * tie)], best)
    assert not ends_agree([out(c), out(c + 3.0 * tie)], best)
    assert not ends_agree([out(c), out(c, converged=False)], best)
    assert not ends_agree([out(c)], Optimum(c, np.ones(2), (0,)))

    # the early agreement on one basin: the polish is not run (it would fail here)
    def polish(*args, **kwargs):
        raise AssertionError("polished two ends that agree")

    monkeypatch.setattr(search, "_polish", polish)
    spec = _spec()

    def one_basin(eta: np.ndarray) -> float:
        return float((eta[1] - math.log(0.02)) ** 2 + 0.01 * (eta[0] - math.log(1e6)) ** 2)

    outs, s = global_search(one_basin, spec, "ml", np.random.default_rng(0), optimizer="lbfgs")
    assert s.converged and s.n_best == 2 and ends_agree(outs, s.optima[0])
